"""``radarnode image SCENARIO -o out.png``: the range–Doppler map and range–azimuth image of one frame.

Renders the scenario at the signal level at ``--time`` and draws what the
DSP chain sees (seed 000, figures 3–4): the range–Doppler map (power summed
over the virtual channels) and the range–azimuth image, both shown with the
R⁴ spreading loss taken out (beamformed over the
channels, strongest Doppler bin per cell), with the detections marked.
Needs matplotlib (``pip install 'radarnode[image]'``).
"""

from __future__ import annotations

import dataclasses
import sys

import numpy as np
import scipy.fft

from radarnode.cli.common import add_scenario_argument, scenario_from_args
from radarnode.dsp.spectra import noncoherent_power, range_doppler
from radarnode.errors import ConfigError
from radarnode.radar.models import SignalModel
from radarnode.radar.object_model import RuntimeConfig
from radarnode.scene.world import Scene


def add_subparser(sub) -> None:
    p = sub.add_parser("image", help="draw the range-Doppler and range-azimuth images of one frame",
                       description=__doc__)
    add_scenario_argument(p)
    p.add_argument("-o", "--output", required=True, help="PNG file to write")
    p.add_argument("--time", type=float, default=0.0, help="scenario time of the frame, s (default 0)")
    p.set_defaults(func=cmd)


def range_azimuth(rd: np.ndarray, preset, n_angle: int = 128) -> tuple[np.ndarray, np.ndarray]:
    """Beamformed power (angle, range), max over Doppler, and the sin(azimuth) grid.

    The TDM slot phase is removed for every Doppler bin, and a Hann taper over
    the channels keeps the sidelobes of strong targets out of the picture.
    """
    c, m, _ = rd.shape
    speed = (np.arange(m) - m // 2) * preset.speed_resolution_mps
    fd = 2.0 * speed / preset.wavelength_m
    tx_of = np.repeat(np.arange(preset.num_tx), preset.num_rx)
    comp = np.exp(-2j * np.pi * fd[None, :] * tx_of[:, None] * preset.chirp_period_s)   # (channel, doppler)
    taper = np.hanning(c + 2)[1:-1][:, None, None]
    x = rd * comp[:, :, None] * taper
    spec = scipy.fft.fftshift(scipy.fft.fft(x, n=n_angle, axis=0), axes=0)   # (angle, doppler, range)
    power = (spec.real ** 2 + spec.imag ** 2).max(axis=1)
    u = scipy.fft.fftshift(scipy.fft.fftfreq(n_angle)) / preset.element_spacing_wl
    return power, u


def cmd(args) -> int:
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise ConfigError("radarnode image needs matplotlib: pip install 'radarnode[image]'") from None
    scenario = scenario_from_args(args)
    if not 0.0 <= args.time <= scenario.duration_s:
        raise ConfigError(f"option --time: value {args.time} is not allowed; expected a time in "
                          f"[0, {scenario.duration_s}] s")
    scenario = dataclasses.replace(scenario, signal=dataclasses.replace(scenario.signal, decimate=False))
    preset = scenario.radar.model
    model = SignalModel(Scene(scenario), preset, np.random.default_rng(scenario.seed), scenario.signal,
                        keep_cube=True)
    model.step(args.time, RuntimeConfig(max_distance_m=preset.max_range_m))
    cube, det = model.info.cube, model.info.detections
    rd = range_doppler(cube)
    rdp = 10 * np.log10(noncoherent_power(rd) + 1e-12)
    rap, u = range_azimuth(rd, preset)
    rap = 10 * np.log10(rap + 1e-12)
    n_r = rd.shape[2]
    ranges = np.arange(n_r) * preset.range_resolution_m
    # display with the R⁴ spreading loss taken out (as a sensitivity-time control would), so far and near
    # targets share one colour scale
    stc = 40.0 * np.log10(np.maximum(ranges, 2.0))
    rdp = rdp + stc[None, :]
    rap = rap + stc[None, :]
    speeds = (np.arange(rd.shape[1]) - rd.shape[1] // 2) * preset.speed_resolution_mps
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 5.5))
    vmax = rdp.max()
    a1.imshow(rdp.T, origin="lower", aspect="auto", cmap="viridis", vmin=vmax - 50, vmax=vmax,
              extent=[speeds[0], speeds[-1], 0, ranges[-1]])
    a1.scatter(det.range_rate_mps, det.range_m, s=30, facecolors="none", edgecolors="r", label="detections")
    a1.set_xlabel("range rate, m/s")
    a1.set_ylabel("range, m")
    a1.set_title(f"range–Doppler map, {scenario.name} t={args.time:.2f} s")
    a1.legend(loc="upper right")
    valid = np.abs(u) <= 1
    az = np.degrees(np.arcsin(u[valid]))
    rr, aa = np.meshgrid(ranges, np.radians(az))
    vmax = rap.max()
    a2.pcolormesh(rr * np.sin(aa), rr * np.cos(aa), rap[valid], cmap="viridis", vmin=vmax - 45, vmax=vmax,
                  shading="gouraud")
    a2.scatter(det.y_m, det.x_m, s=30, facecolors="none", edgecolors="r")
    a2.set_aspect("equal")
    a2.set_xlabel("lateral, m (left of the radar on the left)")
    a2.set_ylabel("longitudinal, m")
    a2.invert_xaxis()
    a2.set_title("range–azimuth image (bird's eye)")
    fig.tight_layout()
    try:
        fig.savefig(args.output, dpi=90)
    except (OSError, ValueError) as exc:
        raise ConfigError(f"option --output: cannot write {args.output!r}: {exc}") from None
    print(f"wrote {args.output}: {len(det)} detections, {len(model.info.scatterers)} scatterers, "
          f"cube {cube.shape[0]}x{cube.shape[1]}x{cube.shape[2]}", file=sys.stderr)
    return 0
