"""Radar equation (with the element pattern and the anti-alias filter) and Cramér–Rao bounds, vectorised.

All functions take numpy arrays (any shape, broadcast together) and return
arrays of the broadcast shape; none loops in Python.

References
----------
Richards, *Fundamentals of Radar Signal Processing*, 2nd ed.: eq. 2.17 (radar
equation with coherent dwell). The detection probability is the signal chain's
(:mod:`radarnode.dsp.detection_stats`).
DESIGN.md section 8: Cramér–Rao bounds for range, radial speed and azimuth.
"""

from __future__ import annotations

import numpy as np

from radarnode.radar.presets import BOLTZMANN_J_PER_K, REFERENCE_TEMPERATURE_K, RadarPreset


#: stop-band rejection of a real-sampling receiver's anti-alias filter, dB
ANTI_ALIAS_REJECTION_DB = 80.0


def snr_db(preset: RadarPreset, range_m: np.ndarray, rcs_dbsm: np.ndarray,
           power_reduction_db: float = 0.0, azimuth_rad: np.ndarray | None = None) -> np.ndarray:
    """The integrated SNR ρ of a target: the one SNR definition of radarnode.

    ρ = Pt·Gt·Gr·λ²·σ·T / ((4π)³·R⁴·k·T0·F·L), with T the coherent dwell (all
    chirps of the frame) and ``num_virtual`` channels: the SNR of the ideal
    matched filter over every sample, chirp and channel, no window, target on
    the bin centres. The detection statistic sees ρ less the window and
    straddle losses (:class:`radarnode.dsp.detection_stats.DetectionStatistic`);
    the Cramér–Rao bounds below take ρ itself.

    Parameters
    ----------
    range_m : array
        Range, m; values below 1 cm are treated as 1 cm to keep R⁴ finite.
    rcs_dbsm : array
        Radar cross section, dBsm.
    power_reduction_db : float
        Transmit attenuation (ARS 408 ``RadarPower``: 0, 3, 6 or 9 dB).
    azimuth_rad : array, optional
        Azimuth: the element pattern's two-way gain (:func:`pattern_db`) is applied; ``None``: boresight.

    Returns
    -------
    array of float64, dB.
    """
    r = np.maximum(np.asarray(range_m, dtype=np.float64), 0.01)
    const_db = (
        preset.tx_power_dbm - 30.0 - power_reduction_db
        + 2.0 * preset.antenna_gain_dbi
        + 20.0 * np.log10(preset.wavelength_m)
        + 10.0 * np.log10(preset.integration_time_s * preset.num_virtual)
        - 30.0 * np.log10(4.0 * np.pi)
        - 10.0 * np.log10(BOLTZMANN_J_PER_K * REFERENCE_TEMPERATURE_K)
        - preset.noise_figure_db - preset.system_loss_db
    )
    out = const_db + np.asarray(rcs_dbsm, dtype=np.float64) - 40.0 * np.log10(r)
    if not preset.complex_sampling:
        # a real-sampling receiver's anti-alias filter: beat frequencies past Nyquist would fold back to a
        # wrong (possibly very short) range; the filter suppresses them instead
        out = out - np.where(r > preset.unambiguous_range_m, ANTI_ALIAS_REJECTION_DB, 0.0)
    if azimuth_rad is not None:
        out = out + pattern_db(preset, azimuth_rad)
    return out


def pattern_db(preset: RadarPreset, azimuth_rad: np.ndarray) -> np.ndarray:
    """Two-way element-pattern gain, dB: 2q·10·log10(cos θ); −120 dB at and beyond ±90° (behind the antenna)."""
    c = np.cos(np.asarray(azimuth_rad, dtype=np.float64))
    return 2.0 * preset.element_pattern_exponent * 10.0 * np.log10(np.maximum(c, 1e-6))


def pattern_moved_db(preset: RadarPreset, seen_rad: np.ndarray, read_rad: np.ndarray, where: np.ndarray) -> np.ndarray:
    """What an RCS gains where the element pattern is divided out at the angle ``read_rad`` the radar measured instead
    of at ``seen_rad``, where its power came from: :func:`pattern_db` at the one less at the other where ``where``,
    else 0 (dB). A grating lobe's or a draw near endfire's angle (``radarnode.radar.ambiguity.measured_azimuth``)."""
    return np.where(where, pattern_db(preset, seen_rad) - pattern_db(preset, read_rad), 0.0)


def pattern_gain(preset: RadarPreset, azimuth_rad: np.ndarray, where: np.ndarray | None = None) -> np.ndarray:
    """:func:`pattern_db` as a power ratio, cos(θ)^2q (cos θ floored at 1e-6, as there), without the logarithm and
    the exponential: the same gain to rounding, a few times cheaper where it weights every outline point of a
    body (:mod:`radarnode.radar.object_model`). ``where`` (bool, the shape of ``azimuth_rad``): the gain only there,
    1 elsewhere (a cosine saved a point its caller drops)."""
    az = np.asarray(azimuth_rad, dtype=np.float64)
    if where is None:
        c = np.cos(az)
    else:
        c = np.ones(az.shape)
        np.cos(az, out=c, where=where)
    c = np.maximum(c, 1e-6)
    e = 2.0 * preset.element_pattern_exponent
    return c * c if e == 2.0 else c ** e


def crb_range_m(preset: RadarPreset, snr_db_: np.ndarray) -> np.ndarray:
    """σ_R ≥ ΔR·√6 / (2π·√ρ), ρ the per-cell SNR (linear)."""
    return _crb_range(preset, _ratio(snr_db_))


def crb_speed_mps(preset: RadarPreset, snr_db_: np.ndarray) -> np.ndarray:
    """σ_v ≥ Δv·√6 / (2π·√ρ)."""
    return _crb_speed(preset, _ratio(snr_db_))


def crb_azimuth_rad(preset: RadarPreset, snr_db_: np.ndarray, azimuth_rad: np.ndarray) -> np.ndarray:
    """σ_θ ≥ λ/(2π·d·cosθ) · √(6 / (ρ_e·K·(K²−1))), ρ_e = ρ/K the per-element SNR.

    cosθ is bounded below by cos 85° so the bound stays finite at the edge of
    any field of view.
    """
    return _crb_azimuth(preset, _ratio(snr_db_), azimuth_rad)


def crbs(preset: RadarPreset, snr_db_: np.ndarray, azimuth_rad: np.ndarray
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(:func:`crb_range_m`, :func:`crb_speed_mps`, :func:`crb_azimuth_rad`) at once: the same values, ρ computed
    once (the object level's guardrail posts: thousands a block)."""
    rho = _ratio(snr_db_)
    return _crb_range(preset, rho), _crb_speed(preset, rho), _crb_azimuth(preset, rho, azimuth_rad)


def _ratio(snr_db_: np.ndarray) -> np.ndarray:
    """ρ, linear, from dB."""
    return 10.0 ** (np.asarray(snr_db_, dtype=np.float64) / 10.0)


def _crb_range(preset: RadarPreset, rho: np.ndarray) -> np.ndarray:
    return preset.range_resolution_m * np.sqrt(6.0) / (2.0 * np.pi * np.sqrt(rho))


def _crb_speed(preset: RadarPreset, rho: np.ndarray) -> np.ndarray:
    return preset.speed_resolution_mps * np.sqrt(6.0) / (2.0 * np.pi * np.sqrt(rho))


def _crb_azimuth(preset: RadarPreset, rho: np.ndarray, azimuth_rad: np.ndarray) -> np.ndarray:
    k = preset.num_virtual
    rho_e = rho / k
    cos_t = np.maximum(np.cos(np.asarray(azimuth_rad, dtype=np.float64)), np.cos(np.radians(85.0)))
    if k < 2:
        # A single channel measures azimuth by beam scanning: the bound is the beamwidth over √(2ρ).
        return preset.angular_resolution_rad / np.sqrt(2.0 * rho_e) / cos_t
    return (1.0 / (2.0 * np.pi * preset.element_spacing_wl * cos_t)) * np.sqrt(6.0 / (rho_e * k * (k * k - 1)))
