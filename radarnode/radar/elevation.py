"""What a radar without an elevation measurement sees of a reflector above the road (issue 10).

A reflector at height h_t above the road, at horizontal distance R from a radar at height h_r, is reached by
two rays: the direct one, at elevation φ_d = atan((h_t − h_r)/R), and the one reflected by the road, which
leaves the antenna at φ_r = −atan((h_t + h_r)/R) (towards the reflector's image below the road). The one-way
field relative to a free-space target on boresight is

    F = g(φ_d) + Γ · g(φ_r) · (R_d/R_r) · exp(−j·2π·(R_r − R_d)/λ)

with g the elevation beam's voltage pattern (g(0) = 1) and Γ the road's reflection coefficient; the two-way
power factor is |F|⁴ (Richards, *Fundamentals of Radar Signal Processing*, sec. 2.7; seed 003's two-ray model).
Two things follow for an overhead structure — a bridge, a sign gantry — as the ego approaches it:

* **lobing**: far away g ≈ 1 and |F|⁴ swings between (1 − |Γ|)⁴ and (1 + |Γ|)⁴ (−21 … +9 dB for Γ = −0.7)
  with nulls where the path difference R_r − R_d ≈ 2·h_r·h_t/R is a whole number of wavelengths:
  R_n = 2·h_r·h_t/(n·λ) — for a radar at 0.5 m and a deck edge at 5 m, every 12 m around 120 m and every
  3 m around 60 m. A car's reflection centres spread over its height (bumper to roof) and their lobes
  average out (ground actors keep the free-space model: their in-situ RCS holds the ground's average share);
* **the elevation beam**: closer in, φ_d grows beyond the beam (±7° at −3 dB for ``ars408_like``: (5 − 0.5) m
  leaves it at about 37 m) and the return fades by 12·(φ/θ₃)² dB each way, down to the antenna's elevation
  sidelobes (:data:`SIDELOBE_DB`).

The elevation beam is modelled as a Gaussian main lobe of full −3 dB width ``preset.elevation_beamwidth_deg``
(one way) on a sidelobe floor; Γ is the road's specular reflection coefficient at grazing incidence
(:data:`GROUND_REFLECTION`, as the signal level's ``multipath`` impairment takes it). The reflector's height is
that of its lower edge: a deck's fascia or a sign panel seen from below at a few degrees reflects from its
edge, not its face (a face 1.5 m tall returns specularly only within λ/1.5 m ≈ 0.15° of its normal).
"""

from __future__ import annotations

import math

import numpy as np

from radarnode.radar.presets import RadarPreset

#: the road's reflection coefficient at grazing incidence (asphalt, 77 GHz: −0.6 … −0.9 below 10°)
GROUND_REFLECTION = -0.7
#: one-way level of the elevation beam's sidelobes relative to its peak, dB (a tapered series-fed patch column)
SIDELOBE_DB = -25.0
_GAUSS_DB = 10.0 * math.log10(2.0) * 4.0          # 12.04: a Gaussian beam is −3 dB at half its −3 dB width


def pattern_db(preset: RadarPreset, elevation_rad: np.ndarray) -> np.ndarray:
    """One-way power gain of the elevation beam at ``elevation_rad``, dB re. boresight (≤ 0): the Gaussian main
    lobe on the sidelobe floor, which falls off with the element pattern towards ±90° (as in azimuth,
    :func:`radarnode.radar.equation.pattern_db`: a patch sees nothing straight above it)."""
    theta3 = math.radians(preset.elevation_beamwidth_deg)
    el = np.asarray(elevation_rad, dtype=np.float64)
    floor = SIDELOBE_DB + preset.element_pattern_exponent * 10.0 * np.log10(np.maximum(np.cos(el), 1e-6))
    return np.maximum(-_GAUSS_DB * (el / theta3) ** 2, floor)


def propagation_db(preset: RadarPreset, ground_range_m: np.ndarray, target_height_m: np.ndarray,
                   radar_height_m: float, reflection: float = GROUND_REFLECTION) -> np.ndarray:
    """Two-way power factor 40·log10|F| of a point reflector at ``target_height_m`` above the road, dB re. a
    free-space reflector on boresight (see the module docstring). Arrays of any shape, broadcast together.

    Parameters
    ----------
    ground_range_m : array
        Horizontal distance from the radar, m (values below 0.1 m count as 0.1 m).
    target_height_m : array
        Height of the reflector above the road, m.
    radar_height_m : float
        Height of the radar above the road, m.
    reflection : float
        The road's reflection coefficient Γ (−1 … 1; 0: free space with the elevation beam only).
    """
    r = np.maximum(np.asarray(ground_range_m, dtype=np.float64), 0.1)
    ht = np.asarray(target_height_m, dtype=np.float64)
    hr = float(radar_height_m)
    up, down = ht - hr, ht + hr
    direct = np.hypot(r, up)
    reflected = np.hypot(r, down)
    g_d = 10.0 ** (pattern_db(preset, np.arctan2(up, r)) / 20.0)
    g_r = 10.0 ** (pattern_db(preset, -np.arctan2(down, r)) / 20.0)
    phase = 2.0 * np.pi * np.mod((reflected - direct) / preset.wavelength_m, 1.0)
    f = g_d + reflection * g_r * (direct / reflected) * np.exp(-1j * phase)
    return 40.0 * np.log10(np.maximum(np.abs(f), 1e-6))


def null_ranges_m(preset: RadarPreset, target_height_m: float, radar_height_m: float, r_min_m: float,
                  r_max_m: float) -> np.ndarray:
    """Horizontal distances of the two-ray nulls (Γ < 0) between ``r_min_m`` and ``r_max_m``, far to near:
    R_n = 2·h_r·h_t/(n·λ) (flat-earth small-angle form; the exact nulls are within a few cm of these)."""
    k = 2.0 * radar_height_m * target_height_m / preset.wavelength_m
    n = np.arange(max(1, math.ceil(k / r_max_m)), math.floor(k / r_min_m) + 1)
    return k / n


__all__ = ["GROUND_REFLECTION", "SIDELOBE_DB", "null_ranges_m", "pattern_db", "propagation_db"]
