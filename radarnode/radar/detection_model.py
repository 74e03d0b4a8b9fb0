"""Fidelity level 2: the analytic detection model (no time-domain signal).

Each scatterer lands in its range–Doppler–angle resolution cell (Doppler
aliased as the radar would alias it); scatterers sharing a cell merge as a coherent sum with their
random scattering phases; the window's main-lobe straddle loss is applied for
the scatterer's offset from the bin centre; the result is detected against a
CA-CFAR threshold with the Swerling 1 closed form
Pd = (1 + T/(1 + SNR))^(−N), T = Pfa^(−1/N) − 1 (Richards eq. 6.87); the
estimate carries noise at the Cramér–Rao bound; Poisson false alarms come at
the CFAR's rate. Range sidelobes of strong cells are off by default: in the
signal chain the main lobe sits in the sidelobe cell's CA-CFAR ring and raises
its threshold ~19 dB above the −31.5 dB sidelobe, so they are not detected
(measured: 0.05 false alarms per frame at the signal level against 5 per frame
with sidelobes modelled, ``benchmarks/fidelity.py``); ``sidelobes=True`` adds them.
"""

from __future__ import annotations

import math

import numpy as np

from radarnode.perception.types import Detections
from radarnode.radar import equation
from radarnode.radar.presets import RadarPreset
from radarnode.radar.scatterers import Scatterers
from radarnode.radar.signal_model import num_range_samples

HANN_PROCESSING_LOSS_DB = 2 * 1.76      # range and Doppler Hann windows
HANN_SIDELOBE_DB = -31.5                 # first sidelobe, ±2.5 bins
N_TRAIN = 248                            # CA-CFAR training cells of the default DSP chain


def hann_straddle(delta: np.ndarray) -> np.ndarray:
    """Amplitude of a Hann-windowed tone at ``delta`` bins from the bin centre, relative to on-bin.

    W(δ) ∝ sinc(δ) / (1 − δ²) (the Hann kernel), exact for |δ| ≤ 0.5.
    """
    d = np.asarray(delta, dtype=np.float64)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = np.sinc(d) / (1.0 - d * d)
    return np.where(np.abs(np.abs(d) - 1.0) < 1e-9, 0.5, w)


def detect(preset: RadarPreset, scat: Scatterers, rng: np.random.Generator, *, pfa: float | None = None,
           power_reduction_db: float = 0.0, snr_db: float | None = None, sidelobes: bool = False) -> Detections:
    """Detections of one frame, computed from the scatterers analytically."""
    p = preset
    pfa = p.pfa if pfa is None else pfa
    n_r = num_range_samples(p)
    m = p.num_chirps
    k = len(scat)
    r, v, az = scat.range_m, scat.range_rate_mps, scat.azimuth_rad
    if snr_db is not None:
        rho = np.full(k, 10.0 ** ((snr_db + 10 * math.log10(n_r * m * p.num_virtual)) / 10.0))
    else:
        rho = 10.0 ** (equation.snr_db(p, r, scat.rcs_dbsm, power_reduction_db) / 10.0)
    # continuous bin positions; range beyond the unambiguous range and speed beyond ±v_max alias
    rb = np.mod(r / p.range_resolution_m, n_r)
    vb = np.mod(v / p.speed_resolution_mps + m / 2, m) - m / 2
    ri, vi = np.rint(rb).astype(np.int64) % n_r, np.rint(vb).astype(np.int64)
    # the beamformer separates what the range–Doppler cell does not: the cell includes the angle bin
    ai = np.rint(np.sin(az) / p.angular_resolution_rad).astype(np.int64)
    n_a = int(np.ceil(2.0 / p.angular_resolution_rad)) + 3
    cell = (ri * m + (vi % m)) * n_a + (ai + n_a // 2)
    # coherent sum within a cell with random scattering phases
    amp = np.sqrt(rho) * hann_straddle(rb - np.rint(rb)) * hann_straddle(vb - np.rint(vb))
    phase = np.exp(2j * np.pi * rng.random(k))
    uniq, inv = np.unique(cell, return_inverse=True)
    field = np.zeros(uniq.size, dtype=np.complex128)
    np.add.at(field, inv, amp * phase)
    power = np.abs(field) ** 2 * 10.0 ** (-HANN_PROCESSING_LOSS_DB / 10.0)
    weight = np.zeros(uniq.size)
    np.add.at(weight, inv, amp ** 2)
    wsafe = np.maximum(weight, 1e-300)

    def mean(x):
        acc = np.zeros(uniq.size)
        np.add.at(acc, inv, amp ** 2 * x)
        return acc / wsafe

    c_r, c_v, c_sin = mean(rb), mean(vb), mean(np.sin(az))
    tag = np.full(uniq.size, -1, dtype=np.int64)
    first = np.full(uniq.size, -2, dtype=np.int64)
    np.maximum.at(first, inv, scat.actor_index)
    last = np.full(uniq.size, 1 << 40, dtype=np.int64)
    np.minimum.at(last, inv, scat.actor_index)
    tag = np.where(first == last, first, -1)
    # CA-CFAR with Swerling 1 targets
    t = pfa ** (-1.0 / N_TRAIN) - 1.0
    pd = (1.0 + t / (1.0 + power)) ** (-N_TRAIN)
    hit = rng.random(uniq.size) < pd
    snr_cell = 10.0 * np.log10(np.maximum(power[hit], 1e-30))
    sig = snr_cell
    # estimation noise at the Cramér–Rao bound of the cell's SNR
    sr = equation.crb_range_m(p, sig) / p.range_resolution_m
    sv = equation.crb_speed_mps(p, sig) / p.speed_resolution_mps
    saz = equation.crb_azimuth_rad(p, sig, np.arcsin(np.clip(c_sin[hit], -1, 1)))
    nz = rng.standard_normal((3, int(hit.sum())))
    est_r = (c_r[hit] + sr * nz[0]) * p.range_resolution_m
    est_v = (c_v[hit] + sv * nz[1]) * p.speed_resolution_mps
    est_az = np.arcsin(np.clip(c_sin[hit], -1, 1)) + saz * nz[2]
    det = Detections(est_r, est_v, est_az, snr_cell + HANN_PROCESSING_LOSS_DB - equation.snr_db(
        p, np.maximum(est_r, 0.01), 0.0, power_reduction_db), snr_cell, tag[hit])
    parts = [det]
    if sidelobes:
        threshold_db = 10.0 * math.log10(t * N_TRAIN)       # α = N·T over the mean noise
        strong = snr_cell + HANN_SIDELOBE_DB > threshold_db + 3.0
        if strong.any():
            s = det.take(strong)
            for shift in (-2.5, 2.5):
                parts.append(Detections(s.range_m + shift * p.range_resolution_m, s.range_rate_mps, s.azimuth_rad,
                                        s.rcs_dbsm + HANN_SIDELOBE_DB, s.snr_db + HANN_SIDELOBE_DB,
                                        np.full(len(s), -1, dtype=np.int64)))
    n_fa = int(rng.poisson(pfa * n_r * m))
    if n_fa:
        fr = rng.uniform(0, n_r, n_fa) * p.range_resolution_m
        fv = rng.uniform(-m / 2, m / 2, n_fa) * p.speed_resolution_mps
        faz = np.arcsin(rng.uniform(-1, 1, n_fa))
        fs = 10.0 * np.log10(t * N_TRAIN) + rng.exponential(0.5, n_fa)     # just above the threshold
        parts.append(Detections(fr, fv, faz, fs + HANN_PROCESSING_LOSS_DB - equation.snr_db(p, np.maximum(fr, 0.01),
                                                                                           0.0), fs,
                                np.full(n_fa, -1, dtype=np.int64)))
    out = Detections(*(np.concatenate([getattr(q, f) for q in parts]) for f in
                       ("range_m", "range_rate_mps", "azimuth_rad", "rcs_dbsm", "snr_db", "actor_index")))
    keep = out.range_m >= 0
    return out.take(keep)
