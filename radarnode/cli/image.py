"""``radarnode image SCENARIO -o out.png``: the radar image of a frame, in four views.

Renders the scenario at the signal level up to ``--time`` and draws what the
DSP chain sees (seed 000, figures 3–4; seed 002, figure 10): the
range–Doppler map, the range–azimuth image in polar form (azimuth × range),
the bird's-eye Cartesian image and seed 002's direct-perspective view (near
edge widened by ``--k``), with detections, objects (boxes of their estimated
size), their tracks and the road boundaries overlaid. Images are shown with
the R⁴ spreading loss taken out. ``--animate out.gif`` renders the whole
scenario instead. Needs matplotlib (``pip install 'radarnode[image]'``).
"""

from __future__ import annotations

import math
import sys
from collections import defaultdict, deque
from pathlib import Path

import numpy as np
import scipy.fft

from radarnode.cli import options
from radarnode.cli.common import add_scenario_argument, atomic_path, require_matplotlib, scenario_from_args
from radarnode.wire.logfiles import check_stem
from radarnode.dsp.spectra import noncoherent_power, range_doppler
from radarnode.errors import FileError, UsageError
from radarnode.perception.boundaries import RoadBoundaryEstimator
from radarnode.perception.views import direct_perspective
from radarnode.radar.setup import radar_config, with_signal
from radarnode.radar.levels import check_level
from radarnode.radar.models import SignalModel
from radarnode.radar.object_model import RuntimeConfig
from radarnode.scene.world import Scene

TRAIL_CYCLES = 15
LATERAL_VIEW_M = 30.0     # the road and its surroundings, not the whole ±60° fan
COLOUR_LABEL = "power, dB re. peak (R⁴ removed)"


def add_subparser(sub) -> None:
    p = sub.add_parser("image", help="draw the radar image of a frame (four views) or animate a scenario",
                       description=__doc__)
    add_scenario_argument(p)
    p.add_argument("-o", "--output", required=True, help="PNG file to write (or GIF with --animate)")
    p.add_argument("--time", type=options.number(lo=0.0, hi=86_400.0), default=None,
                   help="scenario time of the frame, s (default 0; at most the scenario's duration; not with "
                        "--animate)")
    p.add_argument("--k", type=options.number(lo=1.0, hi=10.0), default=2.5,
                   help="direct-perspective widening of the near edge, 1..10 (1.7, 2.5)")
    p.add_argument("--animate", action="store_true", help="render every --every-th cycle of the scenario as a GIF")
    p.add_argument("--every", type=options.POSITIVE_COUNT, default=None,
                   help="cycles between animation frames, with --animate (default 5)")
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
    spec = scipy.fft.fftshift(scipy.fft.fft(rd * comp[:, :, None] * taper, n=n_angle, axis=0), axes=0)
    power = (spec.real ** 2 + spec.imag ** 2).max(axis=1)          # (angle, range)
    u = scipy.fft.fftshift(scipy.fft.fftfreq(n_angle)) / preset.element_spacing_wl
    return power, u


class Renderer:
    """Runs the signal level cycle by cycle and draws the four views of any cycle."""

    def __init__(self, scenario, k: float) -> None:
        self.scenario = with_signal(scenario, decimate=False)
        self.preset = radar_config(self.scenario).preset
        self.scene = Scene(self.scenario)
        # the signal level's options and cube checked with the file and the field's line (its cube's refusal named
        # neither: a tester's finding)
        check_level("signal", radar_config(self.scenario).signal, self.scenario)
        self.model = SignalModel(self.scene, self.preset, np.random.default_rng(self.scenario.seed),
                                 radar_config(self.scenario).signal, keep_cube=True)
        self.boundaries = RoadBoundaryEstimator()
        self.tracks: dict[int, deque] = defaultdict(lambda: deque(maxlen=TRAIL_CYCLES))
        self.k = k
        self.cfg = RuntimeConfig(max_distance_m=self.preset.max_range_m)
        self.t_prev: float | None = None

    def step(self, t_s: float):
        frame, view = self.model.step(t_s, self.cfg)
        self.view = view                   # the ground truth, drawn beside what the radar reports
        det = self.model.info.detections
        yaw = self.scene.ego_state(t_s).yaw_rate_rps
        dt = 0.0 if self.t_prev is None else t_s - self.t_prev
        self.t_prev = t_s
        left, right = self.boundaries.update(det.x_m, det.y_m, det.range_rate_mps, dt,
                                             (view.sensor_vx_mps, view.sensor_vy_mps), yaw)
        present = {int(i) for i in frame.objects.id}
        for gone in [i for i in self.tracks if i not in present]:
            del self.tracks[gone]          # an ID that comes back later belongs to a new object
        for k in range(len(frame.objects)):
            self.tracks[int(frame.objects.id[k])].append((frame.objects.dist_long_m[k], frame.objects.dist_lat_m[k]))
        return frame, (left, right)

    def draw(self, fig, t_s: float, frame, boundaries) -> None:
        p = self.preset
        cube, det = self.model.info.cube, self.model.info.detections
        rd = range_doppler(cube)
        n_r = rd.shape[2]
        ranges = np.arange(n_r) * p.range_resolution_m
        stc = 40.0 * np.log10(np.maximum(ranges, 2.0))      # R⁴ taken out for display
        rdp = 10 * np.log10(noncoherent_power(rd) + 1e-12) + stc[None, :]
        rap, u = range_azimuth(rd, p)
        rap = 10 * np.log10(rap + 1e-12) + stc[None, :]
        valid = np.abs(u) <= 1
        az = np.arcsin(u[valid])
        img = rap[valid]
        speeds = (np.arange(rd.shape[1]) - rd.shape[1] // 2) * p.speed_resolution_mps
        fig.clf()
        a1, a2, a3, a4 = fig.subplots(1, 4)
        vmax = rdp.max()
        # colour in dB relative to the strongest cell of the view, R⁴ spreading taken out (so a target's colour
        # says its RCS, not its range)
        im = a1.imshow(rdp.T - vmax, origin="lower", aspect="auto", cmap="viridis", vmin=-50, vmax=0,
                       extent=[speeds[0], speeds[-1], 0, ranges[-1]])
        fig.colorbar(im, ax=a1, label=COLOUR_LABEL, fraction=0.05, pad=0.02)
        # the map's Doppler axis is the measured one, which wraps at ±N/2 bins; a detection's range rate is the
        # resolved (unaliased) one: drawn where the map shows its cell, folded into the axis (-28 m/s → +10 m/s)
        span = rd.shape[1] * p.speed_resolution_mps
        aliased = (np.asarray(det.range_rate_mps) - speeds[0]) % span + speeds[0]
        a1.scatter(aliased, det.range_m, s=20, facecolors="none", edgecolors="r", label="detections")
        a1.legend(loc="upper right", fontsize=7)
        top = min(ranges[-1], p.max_range_m)
        a1.set(xlabel="range rate, m/s (negative closing; as measured, aliased)", ylabel="range, m",
               title="range–Doppler", ylim=(0, top))
        vmax = img.max()
        # the maps as pictures inside a vector file (.svg, .pdf): drawn as vectors, cell by cell, one frame's svg took
        # 435 MB (an independent tester's finding); in a .png the same pixels either way
        pm = a2.pcolormesh(np.degrees(az), ranges, img.T - vmax, cmap="viridis", vmin=-45, vmax=0, shading="auto",
                           rasterized=True)
        fig.colorbar(pm, ax=a2, label=COLOUR_LABEL, fraction=0.05, pad=0.02)
        a2.scatter(np.degrees(det.azimuth_rad), det.range_m, s=20, facecolors="none", edgecolors="r",
                   label="detections")
        a2.legend(loc="upper right", fontsize=7)
        a2.set(xlabel="azimuth, ° (left positive)", ylabel="range, m", title="range–azimuth (polar form)",
               ylim=(0, top))
        a2.invert_xaxis()
        rr, aa = np.meshgrid(ranges, az)
        lat, lon = rr * np.sin(aa), rr * np.cos(aa)
        for ax, persp in ((a3, False), (a4, True)):
            x_img, y_img = (direct_perspective(lat, lon, self.k, top) if persp else (lat, lon))
            pm = ax.pcolormesh(x_img, y_img, img - vmax, cmap="viridis", vmin=-45, vmax=0, shading="gouraud",
                               rasterized=True)
            fig.colorbar(pm, ax=ax, label=COLOUR_LABEL, fraction=0.05, pad=0.02)
            self._overlay(ax, det, frame, boundaries, top, persp)
            ax.set(xlabel="lateral, m (left on the left)", ylabel="longitudinal, m",
                   title=(f"direct perspective, k={self.k}" if persp else "bird's eye (Cartesian)"))
            half = LATERAL_VIEW_M * (self.k if persp else 1.0)
            ax.set_xlim(half, -half)           # left of the radar on the left
            ax.set_ylim(0, top)
            if not persp:
                ax.set_aspect("equal", adjustable="box")    # to scale: a metre is a metre both ways
        fig.suptitle(f"{self.scenario.name}, t = {t_s:.2f} s, {len(det)} detections, {len(frame.objects)} objects")

    def _overlay(self, ax, det, frame, boundaries, range_max, persp: bool) -> None:
        def tf(lat, lon):
            return direct_perspective(lat, lon, self.k, range_max) if persp else (np.asarray(lat), np.asarray(lon))

        ax.scatter(*tf(det.y_m, det.x_m), s=12, facecolors="none", edgecolors="r", linewidths=0.8, label="detections")
        ol = frame.objects
        first = {"objects": True, "tracks": True, "road boundary": True, "ground truth": True}

        def label(name):          # one legend entry per kind of overlay
            shown, first[name] = first[name], False
            return name if shown else "_nolegend_"

        for k in range(len(ol)):
            x0, y0 = ol.dist_long_m[k], ol.dist_lat_m[k]
            L, W = max(ol.length_m[k], 0.5), max(ol.width_m[k], 0.5)
            bx = np.array([x0, x0 + L, x0 + L, x0, x0])
            by = np.array([y0 - W / 2, y0 - W / 2, y0 + W / 2, y0 + W / 2, y0 - W / 2])
            ax.plot(*tf(by, bx), color="w", linewidth=1.0, label=label("objects"))
            trail = np.array(self.tracks.get(int(ol.id[k]), []))
            # trails of road users only (not of the point-like guardrail posts the tracker also follows)
            if (len(trail) > 1 and ol.dyn_prop[k] in (0, 2, 6) and 1 <= ol.obj_class[k] <= 5
                    and np.max(np.hypot(*np.diff(trail, axis=0).T)) < 4.0):   # no re-associated jumps
                ax.plot(*tf(trail[:, 1], trail[:, 0]), color="orange", linewidth=0.8, label=label("tracks"))
        # the ground truth: every actor's outline (centre, heading, length, width), guardrails left out
        v, sc = self.view, self.scene
        corners = np.array([[0.5, 0.5], [0.5, -0.5], [-0.5, -0.5], [-0.5, 0.5], [0.5, 0.5]])
        for i in np.flatnonzero(~sc.is_guardrail):
            c, s_ = math.cos(v.orientation_rad[i]), math.sin(v.orientation_rad[i])
            lx, ly = corners[:, 0] * sc.length_m[i], corners[:, 1] * sc.width_m[i]
            gx, gy = v.centre_x_m[i] + c * lx - s_ * ly, v.centre_y_m[i] + s_ * lx + c * ly
            if 0.0 <= v.centre_x_m[i] <= range_max:
                ax.plot(*tf(gy, gx), color="m", linewidth=1.0, linestyle="--", label=label("ground truth"))
        xs = np.linspace(0.0, range_max, 60)
        for b in boundaries:
            if b.valid:
                xb = xs[(xs >= b.range_start_m) & (xs <= b.range_end_m)]
                ax.plot(*tf(b.y_at(xb), xb), color="c", linewidth=1.5, label=label("road boundary"))
        ax.legend(loc="upper right", fontsize=7, facecolor="0.3", labelcolor="w", framealpha=0.7)


def _check_output(path: str, animate: bool, plt) -> None:
    """The output's suffix must name a format the writer has, before the (slow) rendering starts."""
    suffix = Path(path).suffix.lower().lstrip(".")
    if animate:
        allowed = ["gif"]
    else:
        allowed = sorted(plt.figure().canvas.get_supported_filetypes())
        plt.close("all")
    check_stem(path, "--output", ["." + a for a in allowed])
    if suffix not in allowed:
        raise UsageError(f"option --output: value {path!r} is not allowed; expected a file name ending in "
                         + " ".join("." + a for a in allowed) + (" (with --animate)" if animate else ""))


def cmd(args) -> int:
    # an option the chosen mode does not use would be ignored: refused, naming both
    if args.every is not None and not args.animate:
        raise UsageError(f"option --every: value {args.every} is not allowed without --animate; expected --animate "
                         "with it (or no --every)")
    if args.time is not None and args.animate:
        raise UsageError(f"option --time: value {args.time:g} is not allowed with --animate (it renders every "
                         "cycle); expected --time without --animate, or no --time")
    if args.fidelity not in (None, "signal"):
        # the image is always the signal level's cube and chain (an independent tester drew the same PNG with
        # --fidelity object)
        raise UsageError(f"option --fidelity: value {args.fidelity!r} is not allowed with image (it draws the signal "
                         "level's range–Doppler cube and detections); expected --fidelity signal, or no --fidelity")
    args.every = 5 if args.every is None else args.every
    args.time = 0.0 if args.time is None else args.time
    plt = require_matplotlib("radarnode image")
    _check_output(args.output, args.animate, plt)
    scenario = scenario_from_args(args)
    if not 0.0 <= args.time <= scenario.duration_s:
        raise UsageError(f"option --time: value {args.time} is not allowed; expected a time in "
                         f"[0, {scenario.duration_s}] s (the scenario's duration)")
    period = scenario.period_s
    fig = plt.figure(figsize=(22, 6))
    try:
        with atomic_path(args.output, "--output") as tmp:         # an output that cannot be written fails first
            r = Renderer(scenario, args.k)
            try:
                if args.animate:
                    from matplotlib.animation import PillowWriter
                    writer = PillowWriter(fps=max(1, round(1.0 / (period * args.every))))
                    with writer.saving(fig, tmp, dpi=60):
                        n = 0
                        for k in range(scenario.num_cycles):
                            frame, bnd = r.step(k * period)
                            if k % args.every == 0:
                                r.draw(fig, k * period, frame, bnd)
                                writer.grab_frame()
                                n += 1
                else:
                    last = int(math.floor(args.time / period + 1e-9))
                    for k in range(last):
                        r.step(k * period)
                    frame, bnd = r.step(args.time)
                    r.draw(fig, args.time, frame, bnd)
                    fig.tight_layout()
                    fig.savefig(tmp, dpi=80)
            except OSError as exc:
                raise FileError(f"option --output: cannot write {args.output!r}: {exc.strerror or exc}") from None
    finally:
        plt.close(fig)
    if args.animate:
        print(f"wrote {args.output}: {n} frames", file=sys.stderr)
        return 0
    info = r.model.info
    cube = info.cube
    print(f"wrote {args.output}: {len(info.detections)} detections, {len(frame.objects)} objects, "
          f"{len(info.scatterers)} scatterers, cube {cube.shape[0]}x{cube.shape[1]}x{cube.shape[2]}", file=sys.stderr)
    return 0
