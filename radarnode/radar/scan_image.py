"""The radar image of a mechanically scanning radar (seed 002's 39 GHz MAI radar, preset ``scanning_ka``).

A 256 × 512 azimuth–range image: range cells of 0.48 m (resolution 0.75 m,
Hann), azimuth cells of 0.36° under a 1° beam (Gaussian two-way pattern).
Objects are seed 002's *multi-point model*: scatterers on a grid over the
footprint with an amplitude distribution that is flat in the middle and
tapers towards the edges, A(x)·A(y); each frame draws new scattering phases
(the car moves), so the image fluctuates from frame to frame as seed 002's
measured images do. Complex unit-variance noise per cell.

    I[r, a] = Σ_k a_k e^{jφ_k} h((r − R_k)/ΔR) b(θ_a − θ_k) + n[r, a]

one matrix product over the scatterers.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radarnode.radar.detection_model import hann_straddle

RANGE_CELL_M = 0.48
AZIMUTH_CELL_DEG = 0.36
RANGE_RESOLUTION_M = 0.75
BEAMWIDTH_DEG = 1.0


@dataclass(frozen=True)
class Footprint:
    """Scatterers of one object: positions (range m, azimuth deg) and amplitude weights, shape (k,)."""

    range_m: np.ndarray
    azimuth_deg: np.ndarray
    weight: np.ndarray


def multipoint_vehicle(range_m: float, azimuth_deg: float, length_m: float, width_m: float,
                       spacing_m: float = 0.2, flat: float = 0.6) -> Footprint:
    """A vehicle seen from behind: a grid over its footprint, raised-cosine taper outside the flat ``flat`` part."""
    xs = np.arange(0.0, length_m + 1e-9, spacing_m)
    ys = np.arange(-width_m / 2, width_m / 2 + 1e-9, spacing_m)
    x, y = (g.ravel() for g in np.meshgrid(xs, ys, indexing="ij"))

    def taper(u, half):
        edge = np.clip((np.abs(u) - flat * half) / ((1 - flat) * half + 1e-12), 0.0, 1.0)
        return 0.5 + 0.5 * np.cos(np.pi * edge)

    w = taper(x - length_m / 2, length_m / 2) * taper(y, width_m / 2)
    return Footprint(range_m + x, azimuth_deg + np.degrees(y / range_m), w / np.sqrt(np.sum(w * w)))


def scan_image(fp: Footprint, snr_db: float, rng: np.random.Generator, range_axis_m: np.ndarray,
               azimuth_axis_deg: np.ndarray, noise: bool = True) -> np.ndarray:
    """Amplitude image, shape (range, azimuth); ``snr_db`` is the object's total power over the noise per cell."""
    amp = fp.weight * 10.0 ** (snr_db / 20.0) * np.exp(2j * np.pi * rng.random(fp.weight.size))
    h = hann_straddle((range_axis_m[:, None] - fp.range_m[None, :]) / RANGE_RESOLUTION_M)   # sidelobes too
    b = np.exp(-4.0 * math.log(2.0) * ((azimuth_axis_deg[None, :] - fp.azimuth_deg[:, None]) / BEAMWIDTH_DEG) ** 2)
    img = (h * amp[None, :]) @ b
    if noise:
        img = img + (rng.standard_normal(img.shape) + 1j * rng.standard_normal(img.shape)) / math.sqrt(2.0)
    return np.abs(img)
