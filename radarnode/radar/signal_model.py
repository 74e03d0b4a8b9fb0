"""Fidelity level 3: the raw FMCW beat signal of a TDM MIMO radar (seed 000 eq. 1–2).

For scatterer k at range R, radial speed v and azimuth θ, virtual channel
c = (tx t, rx r), chirp m and ADC sample n, the complex (IQ) beat signal is

    s[c, m, n] = a_k · exp(j2π [ (R + v·τ_m,t)/ΔR · n/N          (beat frequency 2SR/c)
                                 + 2v/λ · τ_m,t                  (Doppler, TDM slot included)
                                 + d/λ · (t·N_rx + r) · sinθ ])  (virtual ULA phase)

with τ_m,t = m·N_tx·T_c + t·T_c the start of chirp m of transmitter t. The
terms separate in (c, m, n) except for range migration (R changing within the
frame), so the cube is one matrix product over the scatterers,
``(A ⊙ D)[c·m, k] @ S[k, n]``; scatterers whose motion over the frame exceeds
half a range bin get the migration term, grouped by speed.
Amplitudes come from the radar equation (per-cell SNR spread over N·M·C
samples) or from a stated per-sample, per-channel SNR; the thermal noise has
unit variance per sample.

Optional, each off unless asked for: two-ray ground multipath (seed 003),
phase noise, IQ imbalance, per-channel gain/phase mismatch and ADC
quantisation (seed 004).

complex128 by default; complex64 halves memory and roughly quarters the
matrix-product time. Its cost in accuracy is measured in the benchmark
(``benchmarks/fidelity.py``) and bounded in ``tests/test_signal.py``.
"""

from __future__ import annotations

import threading

import numpy as np

from radarnode.errors import ConfigError
from radarnode.radar import equation
from radarnode.radar.presets import RadarPreset
from radarnode.radar.options import Impairments
from radarnode.radar.scatterers import Scatterers

MIGRATION_SPEED_STEP_MPS = 0.05   # phase error of the grouping ≤ 2π·0.025·T_frame/ΔR (< 0.01 rad for mimo12)


def num_range_samples(preset: RadarPreset) -> int:
    """IQ samples per chirp in the model: N with complex sampling, N/2 for real sampling (same range axis)."""
    return preset.num_samples if preset.complex_sampling else preset.num_samples // 2


def decimation_for(preset: RadarPreset, max_range_m: float) -> int:
    """Largest power-of-two decimation of the samples that still covers ``max_range_m``.

    Sampling the same chirp at a lower rate keeps the swept bandwidth, so the
    range resolution is unchanged; only the unambiguous range shrinks — the
    radar's decimation filter does exactly this when the far range is not needed.
    """
    n = num_range_samples(preset)
    factor = 1
    while n // (factor * 2) >= 16 and preset.range_resolution_m * n / (factor * 2) >= 1.15 * max_range_m:
        factor *= 2
    return factor


def synthesize(preset: RadarPreset, scat: Scatterers, rng: np.random.Generator, *, snr_db: float | None = None,
               power_reduction_db: float = 0.0, dtype=np.complex128, impairments: Impairments | None = None,
               decimation: int = 1, noise: bool = True) -> np.ndarray:
    """The beat-signal cube of one frame.

    Parameters
    ----------
    preset : RadarPreset
    scat : Scatterers
    rng : numpy.random.Generator
    snr_db : float, optional
        Per-sample, per-channel SNR of every scatterer (seed 000 states −5 dB);
        by default the radar equation gives each scatterer its own.
    dtype : complex128 or complex64
    decimation : int
        Keep every ``decimation``-th ADC sample (see :func:`decimation_for`).

    Returns
    -------
    cube : complex array, shape (channel, chirp, sample) = (num_tx·num_rx, num_chirps, N/decimation)
    """
    if dtype not in (np.complex128, np.complex64):
        raise ConfigError(f"dtype: value {dtype!r} is not allowed; expected numpy.complex128 or numpy.complex64")
    if decimation < 1 or num_range_samples(preset) % decimation:
        raise ConfigError(f"decimation: value {decimation!r} is not allowed; expected a divisor of "
                          f"{num_range_samples(preset)}")
    imp = impairments or Impairments()
    n_full = num_range_samples(preset)
    n = n_full // decimation
    m, c = preset.num_chirps, preset.num_virtual
    k = len(scat)

    r = scat.range_m
    v = scat.range_rate_mps
    sin_t = np.sin(scat.azimuth_rad)
    if snr_db is not None:
        amp = np.full(k, 10.0 ** (snr_db / 20.0))
    else:
        rho = 10.0 ** (equation.snr_db(preset, r, scat.rcs_dbsm, power_reduction_db) / 10.0)
        amp = np.sqrt(rho / (n_full * m * c))
    amp = amp.astype(np.complex128) * np.exp(2j * np.pi * rng.random(k))    # random scattering phase
    if imp.multipath:
        amp = amp * _two_ray(preset, r, scat.z_m, imp)

    # Thermal noise is drawn on a second thread while this one builds the signal: numpy's generator and the
    # BLAS product both release the GIL, so on two cores the draw costs almost nothing. Nothing else uses
    # ``rng`` until the thread has finished, so the numbers drawn are the same as on one thread.
    # The samples are float32 whatever the cube's dtype: they are random to begin with, so 24 bits of
    # mantissa cost nothing measurable, and drawing them takes half the time.
    noise_buf = np.empty((c, m, n, 2), dtype=np.float32) if noise else None
    drawer = threading.Thread(target=rng.standard_normal, kwargs={"out": noise_buf, "dtype": np.float32}) \
        if noise else None
    if drawer is not None:
        drawer.start()

    tc = preset.chirp_period_s
    t_slot = np.arange(preset.num_tx) * tc                                  # (tx,)
    t_chirp = np.arange(m) * preset.frame_chirp_period_s                    # (m,)
    fd = 2.0 * v / preset.wavelength_m                                      # Doppler, Hz (positive: opening)
    element = (np.arange(preset.num_tx)[:, None] * preset.num_rx + np.arange(preset.num_rx)[None, :]).ravel()
    tx_of = np.repeat(np.arange(preset.num_tx), preset.num_rx)
    # A[c, k]: array phase and TDM slot Doppler; D[m, k]: chirp Doppler; S[k, n]: beat frequency
    a_mat = amp[None, :] * np.exp(2j * np.pi * (preset.element_spacing_wl * element[:, None] * sin_t[None, :]
                                                 + fd[None, :] * t_slot[tx_of][:, None]))
    d_mat = np.exp(2j * np.pi * fd[None, :] * t_chirp[:, None])
    samples = np.arange(n) * decimation
    beat = r / preset.range_resolution_m / n_full                          # cycles per (undecimated) sample
    s_mat = np.exp(2j * np.pi * beat[:, None] * samples[None, :])

    # Range migration: the range moves by v·(frame time). It is modelled where it exceeds half a range bin
    # (below that the peak moves by less than the interpolation error). Migrating scatterers are grouped by
    # speed in steps of MIGRATION_SPEED_STEP_MPS: one group shares the coupling term exp(j2π·v·t_m·n/(ΔR·N)),
    # so it costs one small matrix product and one elementwise product.
    migrating = np.abs(v) * m * preset.frame_chirp_period_s > 0.5 * preset.range_resolution_m
    still = ~migrating
    cube = np.empty((c * m, n), dtype=dtype)
    if still.any():
        left = (a_mat[:, None, still] * d_mat[None, :, still]).reshape(c * m, -1).astype(dtype, copy=False)
        np.matmul(left, s_mat[still].astype(dtype, copy=False), out=cube)
    else:
        cube[:] = 0
    if migrating.any():
        group = np.rint(v / MIGRATION_SPEED_STEP_MPS).astype(np.int64)
        cube3 = cube.reshape(c, m, n)
        for g in np.unique(group[migrating]):      # a loop over speed groups, not over scatterers
            sel = migrating & (group == g)
            left = (a_mat[:, None, sel] * d_mat[None, :, sel]).reshape(c * m, -1).astype(dtype, copy=False)
            part = (left @ s_mat[sel].astype(dtype, copy=False)).reshape(c, m, n)
            drift = g * MIGRATION_SPEED_STEP_MPS * t_chirp / preset.range_resolution_m / n_full
            cube3 += part * np.exp(2j * np.pi * drift[:, None] * samples[None, :]).astype(dtype, copy=False)[None]
    cube = cube.reshape(c, m, n)
    if drawer is not None:
        drawer.join()

    if imp.phase_noise_deg > 0:
        walk = np.cumsum(rng.normal(0.0, np.radians(imp.phase_noise_deg), m))
        cube *= np.exp(1j * walk).astype(dtype, copy=False)[None, :, None]
    if imp.channel_gain_sigma_db > 0 or imp.channel_phase_sigma_deg > 0:
        g = 10.0 ** (rng.normal(0.0, imp.channel_gain_sigma_db, c) / 20.0)
        ph = np.radians(rng.normal(0.0, imp.channel_phase_sigma_deg, c))
        cube *= (g * np.exp(1j * ph)).astype(dtype, copy=False)[:, None, None]
    if noise:
        noise_buf *= np.float32(np.sqrt(0.5))
        cube += noise_buf.view(np.complex64)[..., 0]
    if imp.iq_gain_db != 0 or imp.iq_phase_deg != 0:
        g = 10.0 ** (imp.iq_gain_db / 20.0)
        phi = np.radians(imp.iq_phase_deg)
        mu = (1.0 + g * np.exp(-1j * phi)) / 2.0
        nu = (1.0 - g * np.exp(1j * phi)) / 2.0
        cube = (mu * cube + nu * np.conj(cube)).astype(dtype, copy=False)
    if imp.adc_bits > 0:
        cube = _quantise(cube, imp.adc_bits, imp.adc_headroom_db)
    return cube


def _two_ray(preset: RadarPreset, r: np.ndarray, z: np.ndarray, imp: Impairments) -> np.ndarray:
    """Two-way two-ray propagation factor F² = (1 + Γ·(R_d/R_r)·e^{−jk(R_r − R_d)})² (Richards, sec. 2.7)."""
    ht = imp.target_height_m + z
    hr = imp.radar_height_m
    ground = np.sqrt(np.maximum(r ** 2 - (ht - hr) ** 2, 1e-6))
    direct = np.sqrt(ground ** 2 + (ht - hr) ** 2)
    reflected = np.sqrt(ground ** 2 + (ht + hr) ** 2)
    f = 1.0 + imp.ground_reflection * (direct / reflected) * np.exp(-2j * np.pi * (reflected - direct)
                                                                     / preset.wavelength_m)
    return f * f


def _quantise(cube: np.ndarray, bits: int, headroom_db: float) -> np.ndarray:
    """Uniform ADC on I and Q: full scale ``headroom_db`` above the largest sample; clipping at full scale."""
    real = cube.real.dtype
    peak = max(float(np.max(np.abs(cube.real))), float(np.max(np.abs(cube.imag))), np.finfo(real).tiny)
    full = peak * 10.0 ** (headroom_db / 20.0)
    step = 2.0 * full / (2 ** bits)
    levels = 2 ** (bits - 1)
    i = np.clip(np.round(cube.real / step), -levels, levels - 1) * step
    q = np.clip(np.round(cube.imag / step), -levels, levels - 1) * step
    return (i + 1j * q).astype(cube.dtype)
