"""Fidelity level 3: the FMCW beat signal of a TDM MIMO radar (seed 000 eq. 1–2), exact at every speed.

Signal model
------------
Scatterer k has range R, a constant radial speed v over the frame (positive
opening) and azimuth θ. Transmitter t of N_tx fires chirp m at
τ = (m·N_tx + t)·T_c (T_c = ``chirp_period_s``, chirps back to back). A chirp
sweeps B in T_c (slope S = B/T_c) and is sampled n_full =
:func:`num_range_samples` times (sample period T_s = T_c/n_full, fast time
t_f = n·T_s; with real sampling the model keeps the N/2 complex samples that
carry the same range axis). The beat phase of virtual channel c = (t, r),
chirp m, ADC sample n is, in cycles,

    φ = (2/λ)(R + vτ) + (2/λ)·v·t_f + (2S/c)(R + vτ)·t_f + (2S/c)·v·t_f² + (d/λ)(t·N_rx + r)·sinθ
        carrier, Doppler   coupling    beat, range migration   in-chirp     virtual ULA

(λ = c/``carrier_hz``, the sweep's start). Since (2S/c)·T_s = 1/(ΔR·n_full),
the beat term is (R + vτ)/ΔR · n/n_full cycles: the FFT's range-bin mapping
R/ΔR. In slow time s = τ/T_r = m + t/N_tx (T_r = N_tx·T_c):

    φ = 2R/λ + a·s + b·n + g·s·n + q·n² + array phase,
    a = 2vT_r/λ,  b = R/(ΔR·n_full) + 2vT_c/(λ·n_full),  g = vT_r/(ΔR·n_full),  q = vT_c/(ΔR·n_full²).

Every term is kept for every scatterer; there is no speed threshold and no
grouping by speed. The cross term g·s·n (range migration: the beat frequency
drifts from chirp to chirp; equally, the Doppler frequency drifts along fast
time, so the Doppler estimate is that of the sweep's mean frequency) is what
keeps the cube from being one matrix product. Amplitudes come from the radar
equation (the integrated SNR ρ of :func:`radarnode.radar.equation.snr_db`,
element pattern included, spread over n_full·M·C samples) or from a stated
per-sample, per-channel SNR; a uniform random scattering phase is drawn from
``rng`` first; thermal noise has unit variance per sample.

Two ways to the same spectrum
-----------------------------
:func:`synthesize` builds the raw cube ``[channel, chirp, sample]``. At a fixed
ADC sample n every scatterer is one complex exponential in slow time, of
frequency a + g·n: the cube's column n is one product (chirp × scatterer)·
(scatterer × channel) with a Vandermonde matrix shared by the transmitters,
and that matrix follows from the previous sample's by one elementwise product
(see :func:`_time_domain`). Exact to ~1e-13 of the peak (complex128), at a
cost independent of the speeds.

:func:`synthesize_rd` builds the Hann-windowed range–Doppler spectrum the DSP
chain would compute from that cube, over only the cells each scatterer's
response reaches. Centred on the frame (σ = s − s_c, ν = n − n_c), the
migration term is exp(2πi·g·σ·ν) = Σ_p (2πi·g)^p σ^p ν^p / p!, so the
response is a short sum of separable terms: the Doppler DFT of w_d·σ^p times
the range DFT of w_r·ν^p·exp(2πi·q·n²), restricted to a patch around the
scatterer's bins and obtained from tabulated patches of the windowed moments
(no exponential per sample). The series is summed until its remainder is
small enough; the patch is a cross (long along each axis, where the DFT-even
Hann kernel's 1/x³ tail lies, narrow across, where the response is a product
of two tails) large enough that what it leaves out is small enough, "small
enough" being an energy budget per scatterer: the stricter of ``floor_db`` below its own peak and
``noise_margin_db`` below the noise of one cell. An error of energy ε²σ² adds
at most ε² to the noise of any cell; how far it moves an estimate depends on
the estimator: the chain's patch fit sums every channel, where the error
repeats, and whitens the windows' correlated noise, which weighs it up, so the
default margin, 30 dB, is set by measurement (``RD_NOISE_MARGIN_DB``: the range
rate within 0.93 of its Cramér–Rao bound of the exact cube's, the range within
0.96, at ρ = 20–80 dB, where 20 dB left up to 2.45). The noise is drawn directly in that domain: windowed white
noise is white noise convolved with the window's spectrum, for the Hann
window the kernel [−1/4, 1/2, −1/4] on each axis (adjacent-bin correlation
−2/3, +1/6 at two bins).

Optional (time domain only), each off unless asked for: two-ray ground
multipath (seed 003), LO phase noise with its range correlation, IQ
imbalance, per-channel gain/phase mismatch and ADC quantisation (seed 004).

Speed: on a shared two-core machine OpenBLAS's idle worker threads spin after
every threaded product and take the core the noise thread needs; run with
``OPENBLAS_NUM_THREADS=1`` (or threadpoolctl) — measured in
``benchmarks/signal_speed.py``. Accuracy: ``tests/test_synthesis.py``.
"""

from __future__ import annotations

import functools
import math
import threading

import numpy as np
import scipy.fft
import scipy.sparse
from scipy.special import gammaln

from radarnode.dsp.spectra import window
from radarnode.errors import ConfigError
from radarnode.radar import equation
from radarnode.radar.options import Impairments, check_snr_db
from radarnode.radar.presets import SPEED_OF_LIGHT_MPS, RadarPreset
from radarnode.radar.scatterers import Scatterers

#: What ``synthesize_rd`` may leave out of each scatterer's response, as energy over the whole map: at most
#: this far below its own (ideal, on-bin, per channel) peak ...
RD_PEAK_FLOOR_DB = 40.0
#: ... and at most this far below the noise of one range–Doppler cell of one channel. Measured (a point target, no
#: noise, the chain on this synthesis against the exact time-domain cube; tests/test_synthesis.py): with 30 dB the
#: range rate differs by at most 0.93 of its CRB and the range by at most 0.96 of its CRB (mimo12 at 50 m, −70…50
#: m/s in 4 m/s steps, ρ 20–80 dB, 217 cases: 6 over 0.51 in range rate, the worst at −18 m/s and 50 dB; srr_corner
#: and ars408_like at 37 m, 138 cases: up to 0.82 and 0.96; an independent tester's grid), against up to 2.45 with
#: 20 dB, the margin before (a per-cell bound of ε·σ per estimate leaves out that the error repeats in every channel
#: and that the patch fit whitens the windows' correlated noise, which weighs it up); 35 dB: at most 0.19 on the
#: tester's worst cases. Cost against 20 dB, mimo12 highway frame: 30 dB +1.1–2.9 ms, 35 dB +2.2–6.1 ms (0–70 m/s),
#: which complex128 at 70 m/s (35–39 ms with the migration fit) cannot afford within its 45 ms with margin to spare
RD_NOISE_MARGIN_DB = 30.0

_MAX_TAYLOR_TERMS = 96                 # RD synthesis: series terms at most (float64 limits it to ~12 bins)
_TD_CHUNK_ELEMENTS = 1 << 18           # time domain: (chirp, scatterer) elements per pass over the scatterers ...
_TD_W_ELEMENTS = 1 << 22               # ... and (sample, scatterer, channel) elements
_TD_WRITE_SAMPLES = 16                 # time domain: samples per copy into the cube
_ANCHOR_SAMPLES = 128                  # time domain: exact exponential every this many samples
_RD_CHUNK_ELEMENTS = 1 << 20           # patch elements per batch of scatterers in the RD synthesis
_PATCH_SERIES = 24                     # RD synthesis: terms of the in-patch frequency series
_RD_SPARSE_ENTRIES = 1 << 20          # RD synthesis: sparse entries held before they are added to the maps
_RD_MIN_TIER = 8                       # RD synthesis: fewer scatterers than this join the next patch size


def num_range_samples(preset: RadarPreset) -> int:
    """IQ samples per chirp in the model: N with complex sampling, N/2 for real sampling (same range axis)."""
    return preset.num_range_bins


#: the largest share of this machine's memory one frame's cube may take at the signal level (the chain keeps the
#: cube, its spectrum and their channel sums at once: several cubes' worth in all)
CUBE_MEMORY_SHARE = 0.125


def check_cube_memory(preset: RadarPreset, dtype, field: str = "radar.overrides") -> None:
    """Refuse a preset whose signal-level cube (channels × chirps × samples of ``dtype``) would take more than
    :data:`CUBE_MEMORY_SHARE` of this machine's memory: it failed with numpy's MemoryError and a 60-line traceback
    (12 × 8192 × 8192 complex128 samples, 12 GiB), or took the machine's memory. Where the size is not known
    (no sysconf), nothing is refused."""
    import os
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return
    n = preset.num_virtual * preset.num_chirps * num_range_samples(preset)
    need = n * np.dtype(dtype).itemsize
    if total > 0 and need > CUBE_MEMORY_SHARE * total:
        raise ConfigError(f"{field}: a signal-level frame of {preset.num_virtual} channels × {preset.num_chirps} "
                          f"chirps × {num_range_samples(preset)} samples ({np.dtype(dtype).name}) needs "
                          f"{need / 2**30:.1f} GiB, more than {CUBE_MEMORY_SHARE:.3g} of this machine's "
                          f"{total / 2**30:.1f} GiB; expected fewer chirps or samples (num_chirps, num_samples), "
                          "complex64, or a cheaper fidelity (--fidelity detection)")


def decimation_for(preset: RadarPreset, max_range_m: float) -> int:
    """Largest power-of-two decimation of the samples that still covers ``max_range_m``.

    Sampling the same chirp at a lower rate keeps the swept bandwidth, so the
    range resolution is unchanged; only the unambiguous range shrinks — the
    radar's decimation filter does exactly this when the far range is not needed
    (and passes 1/decimation of the noise: :func:`synthesize` scales it, so the
    integrated SNR is the same).
    """
    n = num_range_samples(preset)
    factor = 1
    while n // (factor * 2) >= 16 and preset.range_resolution_m * n / (factor * 2) >= 1.15 * max_range_m:
        factor *= 2
    return factor


# ----------------------------------------------------------------------------------------------------------
# per-scatterer terms, shared by both paths


class _Terms:
    """Per-scatterer amplitude and phase coefficients of the beat signal; every array has shape (K,).

    ``amp`` is complex (scattering phase, carrier phase 2R/λ and multipath included);
    ``a``, ``b``, ``g``, ``q`` are the coefficients of s, n, s·n and n² in the phase, in cycles
    (see the module docstring); ``sin_t`` is sinθ; ``delay_s`` the round-trip delay 2R/c.
    """

    __slots__ = ("amp", "a", "b", "g", "q", "sin_t", "delay_s")

    def __init__(self, amp, a, b, g, q, sin_t, delay_s) -> None:
        self.amp, self.a, self.b, self.g, self.q, self.sin_t, self.delay_s = amp, a, b, g, q, sin_t, delay_s

    def __len__(self) -> int:
        return int(self.amp.shape[0])

    def take(self, index) -> _Terms:
        return _Terms(*(getattr(self, f)[index] for f in self.__slots__))


def _check_common(scat: Scatterers, snr_db: float | None, power_reduction_db: float, dtype) -> None:
    if dtype not in (np.complex128, np.complex64):
        raise ConfigError(f"dtype: value {dtype!r} is not allowed; expected numpy.complex128 or numpy.complex64")
    check_snr_db(snr_db)
    if not (isinstance(power_reduction_db, (int, float, np.floating, np.integer))
            and math.isfinite(float(power_reduction_db))):
        raise ConfigError(f"power_reduction_db: value {power_reduction_db!r} is not allowed; "
                          "expected a finite number (dB)")
    scat.require_finite()


def _terms(preset: RadarPreset, scat: Scatterers, rng: np.random.Generator, snr_db: float | None,
           power_reduction_db: float, imp: Impairments) -> _Terms:
    """Amplitudes and phase coefficients; draws the K random scattering phases from ``rng`` (first)."""
    n_full = num_range_samples(preset)
    m, c = preset.num_chirps, preset.num_virtual
    k = len(scat)
    r = scat.range_m
    v = scat.range_rate_mps
    az = scat.azimuth_rad
    if snr_db is not None:
        amp = np.full(k, 10.0 ** (float(snr_db) / 20.0))
    else:
        rho = 10.0 ** (equation.snr_db(preset, r, scat.rcs_dbsm, power_reduction_db, azimuth_rad=az) / 10.0)
        amp = np.sqrt(rho / (n_full * m * c))
    amp = amp.astype(np.complex128) * np.exp(2j * np.pi * rng.random(k))    # random scattering phase
    if imp.multipath:
        amp = amp * _two_ray(preset, r, scat.z_m, imp)
    # 2R/λ is ~6·10⁴ cycles at 100 m: in float64 its fraction would carry ~1e-11 cycles of rounding, so it is
    # formed in extended precision (the only term that large)
    lam = preset.wavelength_m
    carrier = np.asarray(np.mod(2 * r.astype(np.longdouble) / np.longdouble(lam), 1), dtype=np.float64)
    amp = amp * np.exp(2j * np.pi * carrier)
    dr = preset.range_resolution_m
    tc, tr = preset.chirp_period_s, preset.frame_chirp_period_s
    a = 2.0 * v * tr / lam
    b = r / (dr * n_full) + 2.0 * v * tc / (lam * n_full)
    g = v * tr / (dr * n_full)
    q = v * tc / (dr * n_full * n_full)
    return _Terms(amp, a, b, g, q, np.sin(az), 2.0 * r / SPEED_OF_LIGHT_MPS)


def _cycles(x: np.ndarray) -> np.ndarray:
    """exp(2πi·x) for x in cycles, reduced to [0, 1) first so large phases keep their accuracy."""
    return np.exp(2j * np.pi * np.mod(x, 1.0))


def _ramp(count: int, lin: np.ndarray, start: np.ndarray | float = 0.0, quad: np.ndarray | float = 0.0,
          stride: float = 1.0, seg: int = 16) -> np.ndarray:
    """exp(2πi(start + lin·x + quad·x²)) at x = j·stride, j < ``count``, for K rows: shape (K, count), complex128.

    A complex exponential costs ~50 ns here (numpy's float64 sin/cos are not
    vectorised), a complex multiply ~2 ns. So the phase is evaluated exactly
    only at the start of each segment of ``seg`` points (value and local step)
    and for the in-segment quadratic term; inside a segment the ramp is the
    start times powers of the step, accumulated by ``cumprod`` (≤ seg
    roundings, ~2e-15).
    """
    lin = np.atleast_1d(np.asarray(lin, dtype=np.float64))
    k = lin.size
    start = np.broadcast_to(np.asarray(start, dtype=np.float64), (k,))
    quad = np.broadcast_to(np.asarray(quad, dtype=np.float64), (k,))
    seg = max(1, min(seg, count))
    nseg = -(-count // seg)
    x0 = np.arange(nseg) * (seg * stride)                                   # segment starts
    head = _cycles(start[:, None] + lin[:, None] * x0 + quad[:, None] * x0 ** 2)          # (K, nseg)
    step = _cycles((lin[:, None] + 2.0 * quad[:, None] * x0) * stride)                   # (K, nseg)
    out = np.empty((k, nseg, seg), dtype=np.complex128)
    out[:, :, 0] = head
    out[:, :, 1:] = step[:, :, None]
    np.cumprod(out, axis=2, out=out)
    if np.any(quad != 0):
        out *= _cycles(quad[:, None] * (np.arange(seg) * stride) ** 2)[:, None, :]
    return out.reshape(k, nseg * seg)[:, :count]


# ----------------------------------------------------------------------------------------------------------
# time domain


def synthesize(preset: RadarPreset, scat: Scatterers, rng: np.random.Generator, *, snr_db: float | None = None,
               power_reduction_db: float = 0.0, dtype=np.complex128, impairments: Impairments | None = None,
               decimation: int = 1, noise: bool = True) -> np.ndarray:
    """The beat-signal cube of one frame (every term of the module docstring, for every scatterer).

    Parameters
    ----------
    preset : RadarPreset
    scat : Scatterers
        Every float field must be finite.
    rng : numpy.random.Generator
        Draws, in this order: the scattering phases (K), the LO phase steps
        (N_tx·M, only with phase noise), the thermal noise (on a helper thread),
        the channel mismatch (only when asked for).
    snr_db : float, optional
        Per-sample, per-channel SNR of every scatterer, dB (seed 000 states −5 dB);
        by default the radar equation gives each scatterer its own.
    power_reduction_db : float
        Transmit attenuation, dB (radar-equation amplitudes only).
    dtype : complex128 or complex64
    impairments : Impairments, optional
        Phase noise is the LO's phase φ(t) over the whole frame: a random walk
        with rms step ``phase_noise_deg`` from one transmitted chirp to the next
        (N_tx·M steps), linear within each chirp (the parameter says nothing of
        noise faster than the chirp rate, so none is invented). An echo delayed
        by τ = 2R/c is mixed with the same LO, so only φ(t) − φ(t − τ) = φ'·τ
        remains — exact for this φ where t − τ lies in the same chirp, i.e. all
        but the first τ/T_s samples, where the Hann window is below 0.06 on
        mimo12 at 112 m. It is a phase per chirp and scatterer, white across
        chirps with rms step·τ/T_c: the skirt it raises grows as R² and
        vanishes for near targets.
    decimation : int
        Keep every ``decimation``-th ADC sample (see :func:`decimation_for`), as the radar's decimation filter
        passes them: with 1/decimation of the noise, so that every return integrates to the same SNR.
    noise : bool
        Add the thermal noise (unit variance per complex sample of the full rate; 1/decimation decimated).

    Returns
    -------
    cube : complex array, shape (channel, chirp, sample) = (num_tx·num_rx, num_chirps, n_full/decimation)

    Raises
    ------
    ConfigError
        Bad dtype or decimation; a NaN or infinite scatterer field, ``snr_db`` or ``power_reduction_db``.
    """
    _check_common(scat, snr_db, power_reduction_db, dtype)
    if not isinstance(decimation, (int, np.integer)) or decimation < 1 or num_range_samples(preset) % decimation:
        raise ConfigError(f"decimation: value {decimation!r} is not allowed; expected a divisor of "
                          f"{num_range_samples(preset)}")
    imp = impairments or Impairments()
    n = num_range_samples(preset) // decimation
    m, c = preset.num_chirps, preset.num_virtual

    tm = _terms(preset, scat, rng, snr_db, power_reduction_db, imp)
    lo_steps = None
    if imp.phase_noise_deg > 0:
        # one step per transmitted chirp: the LO runs through every transmitter's slot
        lo_steps = rng.normal(0.0, np.radians(imp.phase_noise_deg), preset.num_tx * m)

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
    try:
        cube = _time_domain(preset, tm, dtype, decimation, lo_steps)
    finally:
        if drawer is not None:
            drawer.join()

    if imp.channel_gain_sigma_db > 0 or imp.channel_phase_sigma_deg > 0:
        g = 10.0 ** (rng.normal(0.0, imp.channel_gain_sigma_db, c) / 20.0)
        ph = np.radians(rng.normal(0.0, imp.channel_phase_sigma_deg, c))
        cube *= (g * np.exp(1j * ph)).astype(dtype, copy=False)[:, None, None]
    if noise:
        # a decimated cube is what the radar's decimation filter passes: its band, 1/decimation of the samples', holds
        # 1/decimation of the noise, so that the return integrates to the same SNR over the fewer samples (unscaled,
        # the time domain read a 10-dBsm point 20 m ahead as −2 dBsm, 10·log10(16) low, and lost as much
        # sensitivity: an independent tester's finding)
        noise_buf *= np.float32(np.sqrt(0.5 / decimation))
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


def _time_domain(preset: RadarPreset, tm: _Terms, dtype, decimation: int, lo_steps: np.ndarray | None
                 ) -> np.ndarray:
    """The noise-free cube, shape (channel, chirp, sample), exact for every scatterer.

    For a fixed ADC sample n, every scatterer is one complex exponential in
    slow time: its phase (a + g·n)·s + b·n + q·n² is linear in s = m + t/N_tx,
    with frequency f_k(n) = a_k + g_k·n cycles per chirp — range migration only
    makes that frequency depend on n. So sample by sample the cube is one
    product, cube[c, :, n] = V_n[chirp, k] @ W_n[k, c], with the Vandermonde
    matrix V_n[m, k] = exp(2πi·f_k(n)·m), shared by every transmitter, and
    W_n[k, (t, r)] = A[k, c]·exp(2πi(b·n + q·n² + f_k(n)·t/N_tx)). From one
    sample to the next V_n is multiplied by G[m, k] = exp(2πi·g_k·decimation·m)
    (a recurrence on a matrix that stays in cache; it is re-anchored from a
    complex128 copy every ``_ANCHOR_SAMPLES`` samples, every 16 in complex64).
    The cost is the old single product's plus one complex multiply per
    (sample, chirp, scatterer), whatever the speeds. With phase noise the
    chirp's residual LO phase multiplies V_n per transmitter.

    Measured on the mimo12 highway frame (~320 scatterers): ~2× the old
    single product without migration, the same at every speed. Splitting the
    samples over two Python threads was slower (OpenBLAS already threads these
    products), and so was splitting the products into smaller ones.
    """
    n_tx, n_rx, m = preset.num_tx, preset.num_rx, preset.num_chirps
    c = n_tx * n_rx
    n = num_range_samples(preset) // decimation
    k_all = len(tm)
    cube = np.zeros((c, m, n), dtype=dtype)
    if k_all == 0:
        return cube
    anchor = _ANCHOR_SAMPLES if dtype == np.complex128 else 16
    kc = min(k_all, max(1, min(_TD_CHUNK_ELEMENTS // m, _TD_W_ELEMENTS // (n * c))))
    for k0 in range(0, k_all, kc):                                          # chunks of scatterers: memory
        part = tm.take(slice(k0, k0 + kc))
        k = len(part)
        # W[n, k, t, r] = exp(2πi(b·n + q·n²))·z^t·A[k, t, r], z = exp(2πi·f_k(n)/N_tx) the slot's share
        arr = (part.amp[:, None] * _ramp(c, preset.element_spacing_wl * part.sin_t)).reshape(k, n_tx, n_rx)
        lead = _ramp(n, part.b, quad=part.q, stride=float(decimation)).T                   # (n, k)
        z = _ramp(n, part.g / n_tx, start=part.a / n_tx, stride=float(decimation)).T       # (n, k)
        slots = np.empty((n, k, n_tx), dtype=np.complex128)
        slots[:, :, 0] = lead
        for t in range(1, n_tx):                                             # a loop over the transmitters
            np.multiply(slots[:, :, t - 1], z, out=slots[:, :, t])
        w_all = slots.astype(dtype, copy=False)[:, :, :, None] * arr.astype(dtype)[None]  # (n, k, tx, rx)
        g_step = part.g * decimation                                         # frequency step per output sample
        grow = np.ascontiguousarray(_ramp(m, g_step).T).astype(dtype, copy=False)     # G, (m, k)
        jump = np.ascontiguousarray(_ramp(m, anchor * g_step).T)                        # G^anchor, complex128
        resid = None
        if lo_steps is not None:
            # residual LO phase of transmitted chirp j = m·N_tx + t for scatterer k: φ'·τ = step_j·τ_k/T_c
            resid = np.exp(-1j * lo_steps.reshape(m, n_tx)[:, :, None]
                           * (part.delay_s / preset.chirp_period_s)[None, None, :]).astype(dtype)  # (m, tx, k)

        shadow = np.ascontiguousarray(_ramp(m, part.a).T)                   # V_0, (m, k), complex128
        vand = shadow
        # products land in a small (sample, chirp, channel) buffer, copied into the cube every
        # _TD_WRITE_SAMPLES samples: the cube's sample axis is contiguous, one sample alone is a strided write
        buf = np.empty((_TD_WRITE_SAMPLES, m, c), dtype=dtype)
        for j in range(n):                                                   # a loop over the N samples
            if j % anchor == 0:
                if j:
                    shadow *= jump
                vand = shadow.astype(dtype, copy=True)
            else:
                vand *= grow
            row = buf[j % _TD_WRITE_SAMPLES]
            if resid is None:
                np.matmul(vand, w_all[j].reshape(k, c), out=row)
            else:
                for t in range(n_tx):
                    np.matmul(vand * resid[:, t, :], w_all[j, :, t], out=row[:, t * n_rx:(t + 1) * n_rx])
            if j % _TD_WRITE_SAMPLES == _TD_WRITE_SAMPLES - 1 or j == n - 1:
                j0 = j - j % _TD_WRITE_SAMPLES
                dst = cube[:, :, j0: j + 1]
                src = buf[: j + 1 - j0].transpose(2, 1, 0)
                if k0 == 0:
                    dst[...] = src
                else:
                    dst += src
    return cube


# ----------------------------------------------------------------------------------------------------------
# range–Doppler domain


def synthesize_rd(preset: RadarPreset, scat: Scatterers, rng: np.random.Generator, *, snr_db: float | None = None,
                  power_reduction_db: float = 0.0, dtype=np.complex128, range_window: str = "hann",
                  doppler_window: str = "hann", impairments: Impairments | None = None,
                  noise: bool = True, floor_db: float = RD_PEAK_FLOOR_DB,
                  noise_margin_db: float = RD_NOISE_MARGIN_DB) -> np.ndarray:
    """The windowed range–Doppler spectrum of one frame, synthesised without the time-domain cube.

    Equal in distribution to ``range_doppler(synthesize(...), range_window=..., doppler_window=...)`` with
    the same arguments. Without noise, equal to it up to what each scatterer may leave out, an energy
    over the whole map (per channel) of at most ε²·|a|²·(Σw_d·Σw_r)², ε the stricter of ``floor_db``
    below its ideal peak |a|·Σw_d·Σw_r and ``noise_margin_db`` below the noise rms of one cell,
    √(Σw_d²·Σw_r²) (default ``RD_NOISE_MARGIN_DB``, 30 dB: the chain's estimates within 0.93–0.96 of their
    Cramér–Rao bound of the exact cube's, measured; see there).

    Parameters
    ----------
    preset, scat, rng, snr_db, power_reduction_db, dtype, noise
        As for :func:`synthesize`; ``rng`` draws the scattering phases (K) first, then the noise
        (one float64 and one float32 uniform a cell, on a helper thread).
    range_window, doppler_window : str
        Only ``"hann"``: its spectrum and its noise kernel are what this synthesis knows.
    impairments : Impairments, optional
        Must ask for nothing: impairments act on the raw samples, which this path never forms.
    floor_db, noise_margin_db : float
        The truncation budget above, dB (default ``RD_PEAK_FLOOR_DB``, ``RD_NOISE_MARGIN_DB``).

    Returns
    -------
    rd : complex array, shape (channel, doppler, range) = (num_tx·num_rx, num_chirps, n_full)
        Doppler fftshifted (bin M/2 is zero speed), all n_full range bins: the convention of
        :func:`radarnode.dsp.spectra.range_doppler` (Doppler window times (−1)^m, then the FFT).

    Raises
    ------
    ConfigError
        A window other than Hann, impairments, an odd number of chirps, a range migration of more than
        ~12 bins in one frame (float64 cannot sum its series), bad dtype or budget, non-finite input.
    """
    for name, value in (("range_window", range_window), ("doppler_window", doppler_window)):
        if value != "hann":
            raise ConfigError(f"{name}: value {value!r} is not allowed; expected 'hann' "
                              "(for other windows use synthesize and range_doppler)")
    if impairments is not None and impairments.any:
        raise ConfigError(f"impairments: value {impairments!r} is not allowed; expected none "
                          "(impairments act on the raw samples: use synthesize)")
    if preset.num_chirps % 2:
        raise ConfigError(f"num_chirps: value {preset.num_chirps} is not allowed; expected an even number")
    for name, value in (("floor_db", floor_db), ("noise_margin_db", noise_margin_db)):
        if not (isinstance(value, (int, float, np.floating, np.integer)) and 0.0 <= float(value) <= 200.0):
            raise ConfigError(f"{name}: value {value!r} is not allowed; expected a number in [0, 200] (dB)")
    _check_common(scat, snr_db, power_reduction_db, dtype)
    n, m, c = num_range_samples(preset), preset.num_chirps, preset.num_virtual
    tm = _terms(preset, scat, rng, snr_db, power_reduction_db, Impairments())

    job = _RdNoise(rng, c, m, n, dtype) if noise else None                # draws on a helper thread
    try:
        sig = _rd_signal(preset, tm, dtype, floor_db, noise_margin_db)      # (channel, cell)
    finally:
        rd = job.result() if job is not None else np.zeros((c, m, n), dtype=dtype)
    if sig is not None:
        rd += sig.reshape(c, m, n)
    return rd


class _RdNoise:
    """Windowed thermal noise in the range–Doppler domain, shape (channel, doppler, range), filled by two threads.

    The DFT of unit-variance white noise is white with variance N·M per cell;
    the window multiplies in time, so it convolves (circularly) in frequency
    with the window's DFT over its length — for the DFT-even Hann window the
    kernel [−1/4, 1/2, −1/4] on each axis. The Doppler shift of the map is a
    circular shift, which white noise does not notice.

    The white cells are z = √E·e^{2πiφ}: E = −ln(1 − u) ~ Exp(1) from a float64
    uniform u (tail exact to e^−36) and φ a float32 uniform — exactly CN(0, 1),
    and 3× faster here than ``standard_normal`` (numpy's float32 sin/cos are
    vectorised, its ziggurat is not). A helper thread draws every uniform
    first (so the numbers depend only on the generator's state), then shapes
    channel after channel; the calling thread joins in once its own work is
    done (:meth:`help`). Each channel is a pure function of its uniforms, so
    who shapes it does not change the result.
    """

    def __init__(self, rng: np.random.Generator, c: int, m: int, n: int, dtype) -> None:
        self.rng, self.shape, self.dtype = rng, (c, m, n), dtype
        self.out: np.ndarray | None = None
        self.error: BaseException | None = None
        self.drawn = threading.Event()
        self.lock = threading.Lock()
        self.next_channel = 0
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    def _run(self) -> None:
        try:
            c, m, n = self.shape
            self.energy = self.rng.random(c * m * n).reshape(c, m, n)
            self.phase = self.rng.random(c * m * n, dtype=np.float32).reshape(c, m, n)
            self.out = np.empty(self.shape, dtype=self.dtype)
        except BaseException as exc:                                         # re-raised in the caller's thread
            self.error = exc
        finally:
            self.drawn.set()
        if self.error is None:
            self._shape_channels()

    def help(self) -> None:
        """Shape channels on the calling thread until none is left."""
        self.drawn.wait()
        if self.error is None:
            self._shape_channels()

    def result(self) -> np.ndarray:
        self.help()
        self.thread.join()
        if self.error is not None:
            raise self.error
        return self.out

    def _shape_channels(self) -> None:
        c, m, n = self.shape
        scale = -(0.25 * 0.25) * n * m            # variance N·M, and the kernel's two factors 1/2
        while True:
            with self.lock:
                ch = self.next_channel
                self.next_channel += 1
            if ch >= c:
                return
            try:
                energy, phase = self.energy[ch], self.phase[ch]
                x = np.empty((m, n), dtype=np.complex64)
                phase *= np.float32(2.0 * np.pi)
                np.cos(phase, out=x.real)
                np.sin(phase, out=x.imag)
                # 1 − u lies in (0, 1] exactly in float64; rounded to float32 it keeps its relative precision
                # down to 2^−53, so −ln(1 − u) keeps the exponential tail (the phase buffer is free again)
                np.subtract(1.0, energy, out=phase, casting="same_kind")
                np.log(phase, out=phase)
                phase *= np.float32(scale)
                np.sqrt(phase, out=phase)
                x *= phase
                y = np.empty_like(x)
                _hann_pass(x, y, axis=1)
                _hann_pass(y, self.out[ch], axis=0)
            except BaseException as exc:
                self.error = exc
                return


def _hann_pass(x: np.ndarray, y: np.ndarray, axis: int) -> None:
    """y = x − (x[j−1] + x[j+1])/2 along ``axis``, circularly: the Hann kernel over 1/2."""
    def sl(a, b):
        idx = [slice(None)] * x.ndim
        idx[axis] = slice(a, b)
        return tuple(idx)
    np.add(x[sl(None, -2)], x[sl(2, None)], out=y[sl(1, -1)])
    np.add(x[sl(-1, None)], x[sl(1, 2)], out=y[sl(None, 1)])
    np.add(x[sl(-2, -1)], x[sl(None, 1)], out=y[sl(-1, None)])
    y *= -0.5
    y += x


@functools.lru_cache(maxsize=32)
def _hann_tail_energy(length: int, oversample: int = 32) -> np.ndarray:
    """S(x) = Σ_{j ≥ 0} env(x + j)², env(x) = sup_{|u| ≥ x} |W(u)|/W(0), on the grid x = i/oversample.

    W(u) = Σ_n w[n]·exp(2πi·u·n/L) is the DFT-even Hann window's response u
    bins from the tone; S is an upper bound on the energy (relative to the
    peak's) of the bins at x, x + 1, x + 2, ... from the tone on one side.
    """
    w = window("hann", length)
    spec = np.abs(np.fft.fft(w, length * oversample))[: length * oversample // 2 + 1] / w.sum()
    env2 = np.maximum.accumulate(spec[::-1])[::-1] ** 2
    size = env2.size
    # one bin apart is `oversample` grid points apart: a reverse cumulative sum within each residue class
    pad = (-size) % oversample
    grid = np.concatenate([env2, np.zeros(pad)]).reshape(-1, oversample)
    s = np.cumsum(grid[::-1], axis=0)[::-1].reshape(-1)[:size]
    s.setflags(write=False)
    return s


def _half_width(length: int, tol: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """Smallest half-width K (bins) whose left-out energy is below ``tol``² of the peak's on this axis.

    The tone lies within 1/2 + ``shift`` bins of the patch's centre bin, so the
    bins left out start K + 1/2 − shift bins away on one side and
    K + 1/2 + shift on the other: energy ≤ S(K + 1/2 − shift) + S(K + 1/2 + shift).
    S is non-increasing, so K lies between the K with S(K + 1/2 − shift) ≤ tol²
    and the K with 2·S(K + 1/2 − shift) ≤ tol²; both are found by bisection and
    the few candidates between them checked. A result ≥ L/2 means the whole axis.
    """
    os_ = 32
    s = _hann_tail_energy(length, os_)
    neg = -s                                                                  # non-decreasing
    x_lo = np.searchsorted(neg, -tol ** 2, side="left") / os_                 # first x with S(x) ≤ tol²
    x_hi = np.searchsorted(neg, -0.5 * tol ** 2, side="left") / os_           # first x with 2·S(x) ≤ tol²
    k_lo = np.maximum(np.ceil(x_lo - 0.5 + shift), 1.0)
    k_hi = np.maximum(np.ceil(x_hi - 0.5 + shift), k_lo)
    span = int(min(np.max(k_hi - k_lo), length)) + 1
    k = k_lo[:, None] + np.arange(span)[None, :]                              # candidates, (K, span)
    near = np.clip(np.ceil((k + 0.5 - shift[:, None]) * os_), 0, s.size - 1).astype(np.int64)
    far = np.clip(np.ceil((k + 0.5 + shift[:, None]) * os_), 0, s.size - 1).astype(np.int64)
    ok = (s[near] + s[far] <= tol[:, None] ** 2) | (k >= k_hi[:, None])
    return np.minimum(k[np.arange(k.shape[0]), np.argmax(ok, axis=1)], float(length))


@functools.lru_cache(maxsize=8)
def _taylor_moments(m: int, n: int, n_tx: int, terms: int) -> tuple[np.ndarray, np.ndarray]:
    """log of √(L·Σ w²·|x̂|^2p)/Σ w on each axis, p < ``terms``: by Parseval, the energy of a term's DFT.

    x̂ is the centred, normalised time (σ̂ on the Doppler axis, including the
    largest transmitter-slot offset; ν̂ on the range axis).
    """
    wd, wr = window("hann", m), window("hann", n)
    mu = np.abs(np.arange(m) - m / 2.0) / m + (n_tx - 1) / (2.0 * n_tx * m)
    nu = np.abs(np.arange(n) - n / 2.0) / n
    p = np.arange(terms)[:, None]
    with np.errstate(divide="ignore"):
        md = 0.5 * np.log(m * (wd ** 2 * mu ** (2 * p)).sum(axis=1)) - np.log(wd.sum())
        mr = 0.5 * np.log(n * (wr ** 2 * nu ** (2 * p)).sum(axis=1)) - np.log(wr.sum())
    return md, mr


def _taylor_terms(phi: np.ndarray, tol: np.ndarray, m: int, n: int, n_tx: int) -> np.ndarray:
    """Terms P of Σ_p (2πiΦ)^p/p!·σ̂^p·ν̂^p after which the remainder's energy is ≤ ``tol``² of the peak's."""
    md, mr = _taylor_moments(m, n, n_tx, _MAX_TAYLOR_TERMS)
    p = np.arange(_MAX_TAYLOR_TERMS)
    with np.errstate(divide="ignore"):
        log_z = np.log(2.0 * np.pi * np.abs(phi))
    log_term = np.where(p[None, :] > 0, p[None, :] * np.maximum(log_z, -1e300)[:, None], 0.0) \
        - gammaln(p + 1.0)[None, :] + (md + mr)[None, :]
    rem = np.cumsum(np.exp(log_term)[:, ::-1], axis=1)[:, ::-1]             # bound on the remainder from p on
    ok = rem <= tol[:, None]
    terms = np.where(ok.any(axis=1), np.argmax(ok, axis=1), _MAX_TAYLOR_TERMS + 1)
    # the terms grow to ~e^(1.6·Φ) before they fall: summing them loses that times the float64 epsilon,
    # which must stay below the budget too (it does up to a migration of ~12 bins)
    rounding = np.exp(log_term.max(axis=1)) * _MAX_TAYLOR_TERMS * np.finfo(np.float64).eps
    terms = np.where(rounding <= tol, terms, _MAX_TAYLOR_TERMS + 1)
    return np.maximum(terms, 1)


def _windowed_moments(length: int, terms: int) -> np.ndarray:
    """w[x]·x̂^p, x̂ = (x − L/2)/L, for p < ``terms``: shape (terms, L) (the DFT-even Hann window)."""
    rel = (np.arange(length) - length / 2.0) / length
    return window("hann", length)[None, :] * rel[None, :] ** np.arange(terms)[:, None]


@functools.lru_cache(maxsize=256)
def _moment_spectra(length: int, terms: int, offsets: tuple[int, ...]) -> np.ndarray:
    """Hankel stack Q[l, p, i] = Σ_x w[x]·x̂^(p+l)·exp(−2πi·offsets[i]·x/L), l < _PATCH_SERIES: the patch of
    the windowed moment p of a tone, term l of its frequency series; shape (_PATCH_SERIES,
    terms·len(offsets)), read-only (a few kB: cached per patch shape)."""
    x = np.arange(length)
    dft = np.exp(-2j * np.pi * np.mod(np.outer(x, np.asarray(offsets)), length) / length)   # (L, count)
    q = _windowed_moments(length, terms + _PATCH_SERIES) @ dft                              # (p + l, count)
    h = np.stack([q[l: l + terms].reshape(-1) for l in range(_PATCH_SERIES)])
    h.setflags(write=False)
    return h


def _frequency_series(lin: np.ndarray, quad: np.ndarray | None = None) -> np.ndarray:
    """Coefficients c[k, l] of exp(2πi(lin·x̂ + quad·x̂²)) = Σ_l c_l·x̂^l for |x̂| ≤ 1/2, l < _PATCH_SERIES.

    With |lin| ≤ ~1/2 (a tone within half a bin of the patch centre) the terms
    fall as (π/2)^l/l!: 24 terms leave < 1e-16.
    """
    l = np.arange(1, _PATCH_SERIES)
    c = np.ones((lin.size, _PATCH_SERIES), dtype=np.complex128)
    c[:, 1:] = np.cumprod((2j * np.pi * lin)[:, None] / l[None, :], axis=1)
    if quad is not None and np.any(quad != 0):
        # times Σ_j (2πi·quad)^j/j!·x̂^(2j): a short convolution, the in-chirp term is tiny
        b = np.ones((quad.size, _PATCH_SERIES // 2), dtype=np.complex128)
        b[:, 1:] = np.cumprod((2j * np.pi * quad)[:, None] / np.arange(1, _PATCH_SERIES // 2)[None, :], axis=1)
        out = c.copy()
        for j in range(1, _PATCH_SERIES // 2):                                 # a loop over the series' terms
            out[:, 2 * j:] += b[:, j, None] * c[:, : _PATCH_SERIES - 2 * j]
        c = out
    return c


def _span(length: int, half: int) -> tuple[int, ...]:
    """Offsets −half … half of a patch on an axis of ``length`` bins (the whole axis if that is wider)."""
    if 2 * half + 1 >= length:
        return tuple(range(-(length // 2), length - length // 2))
    return tuple(range(-half, half + 1))


def _rectangles(m: int, n: int, long_half: int, short_half: int
                ) -> list[tuple[tuple[int, ...], tuple[int, ...]]]:
    """The patch as (Doppler offsets, range offsets) rectangles: a cross of arms ±long_half long and
    ±short_half wide, or one square when the arms are as wide as they are long."""
    long_d, long_r = _span(m, long_half), _span(n, long_half)
    if short_half >= long_half:
        return [(long_d, long_r)]
    short_d, short_r = _span(m, short_half), _span(n, short_half)
    outer_r = tuple(o for o in long_r if abs(o) > short_half)
    rects = [(long_d, short_r)]                                              # along Doppler, through the centre
    if outer_r:
        rects.append((short_d, outer_r))                                     # along range, without the centre
    return rects


_LADDER = np.array([2, 3, 4, 5, 6, 8, 10, 12, 16, 20, 24, 32, 40, 48, 64, 96, 128, 192, 256, 384, 512,
                    1 << 10, 1 << 11, 1 << 12, 1 << 13, 1 << 14, 1 << 15, 1 << 16])


def _rd_signal(preset: RadarPreset, tm: _Terms, dtype, floor_db: float = RD_PEAK_FLOOR_DB,
               noise_margin_db: float = RD_NOISE_MARGIN_DB) -> np.ndarray | None:
    """The noise-free windowed range–Doppler spectrum of every scatterer, shape (channel, doppler·range cell).

    Per scatterer: Doppler patch D[j, i_d] = Σ_m w_d[m]·μ̂^j·e^{2πi e_d m/M}·e^{−2πi i_d m/M} and range
    patch R[p, i_r] = Σ_n w_r[n]·ν̂^p·e^{2πi(e_r n/N + q n²)}·e^{−2πi i_r n/N} around the nearest bins
    (p_k, q_k) of the frame-centre frequencies (e_d, e_r their fractional parts); the response of
    transmitter t is Σ_j D[j]⊗G_t[j], G_t[j] = Σ_p (2πiΦ)^p/p!·C(p, j)·ε_t^(p−j)·R[p] (σ̂ = μ̂ + ε_t, ε_t
    the slot's offset, Φ = g·M·N the migration over the frame, bins). The patch is a cross: the response
    is (nearly) separable, so away from both axes it is the product of two tails and falls much faster
    than along them. Patches go into one sparse (cell × scatterer) matrix per transmitter, multiplied by
    each channel's phases; patches that cover most of the map are added densely by a matrix product.
    ``None`` when there is no scatterer.
    """
    n, m = num_range_samples(preset), preset.num_chirps
    n_tx, n_rx = preset.num_tx, preset.num_rx
    cells = m * n
    keep = np.flatnonzero(np.abs(tm.amp) > 0)
    if keep.size == 0:
        return None
    tm = tm.take(keep)
    out = np.zeros((n_tx * n_rx, cells), dtype=dtype)

    # frame-centred expansion: s = s_c + σ, n = n_c + ν (the windows are symmetric about M/2 and N/2)
    n_c, s_c = n / 2.0, m / 2.0 + (n_tx - 1) / (2.0 * n_tx)
    alpha = tm.a + tm.g * n_c                                               # cycles per chirp, at ν = 0
    beta = tm.b + tm.g * s_c                                                # cycles per sample, at σ = 0
    phi = tm.g * m * n                                                      # migration over the frame, bins
    xd = m * np.mod(alpha + 0.5, 1.0)                                       # + 1/2: the (−1)^m fftshift
    xr = n * np.mod(beta, 1.0)
    pd = np.floor(xd + 0.5)
    pr = np.floor(xr + 0.5)

    # What each scatterer may leave out, as energy over the map relative to its ideal peak's squared (ε²):
    # the stricter of floor_db and noise_margin_db below one cell's noise (RD_NOISE_MARGIN_DB: what that does
    # to the chain's estimates is measured, not bounded by ε times their standard deviation). In norm,
    # the series' remainder gets ε/4 (counted twice: it is also cut by the patch) and the patch's edges
    # ε/2: with S(K) the energy of one axis' kernel beyond ±K (worst position, shifted by the migration)
    # and 1.5 = Σ|W|²/W(0)² its total (Parseval), the two arms' ends get 1.5·S(K_long) each, ε²/6
    # together, and the four corners S_d(K_short)·S_r(K_short) ≤ ε²/12.
    wd, wr = window("hann", m), window("hann", n)
    peak = np.abs(tm.amp) * wd.sum() * wr.sum()
    noise_rms = math.sqrt(float((wd * wd).sum() * (wr * wr).sum()))
    tol = np.minimum(10.0 ** (-floor_db / 20.0), 10.0 ** (-noise_margin_db / 20.0) * noise_rms / peak)
    drift_d = np.abs(phi) / 2.0
    drift_r = drift_d + 2.0 * np.abs(tm.q) * n * n
    end = tol / math.sqrt(18.0)
    corner = np.sqrt(tol / math.sqrt(12.0))
    long_half = np.maximum(_half_width(m, end, drift_d), _half_width(n, end, drift_r))
    short_half = np.maximum(_half_width(m, corner, drift_d), _half_width(n, corner, drift_r))
    terms = _taylor_terms(phi, tol / 4.0, m, n, n_tx)
    if np.any(terms > _MAX_TAYLOR_TERMS):
        k = int(np.argmax(terms))
        snr_peak_db = 20.0 * math.log10(max(float(peak[k]) / noise_rms, 1e-300))
        if abs(phi[k]) <= 12.0:
            # the migration is within reach: the scatterer's return towers so far over the noise that the series
            # would need more terms to keep its error below it (a return some 200 dB over the noise)
            raise ConfigError(f"scatterer {k}: peak-to-noise value {snr_peak_db:.0f} dB with a range migration of "
                              f"{phi[k]:.2f} bins is not allowed for synthesize_rd (its series would need "
                              f"{int(terms[k])} terms, at most {_MAX_TAYLOR_TERMS}); expected a return at most about "
                              "200 dB over the noise (check its rcs_dbsm; or use synthesize)")
        raise ConfigError(f"range migration: value {phi[k]:.1f} bins in one frame is not allowed for "
                          "synthesize_rd; expected at most ~12 (use synthesize)")
    ladder = _LADDER.size - 1
    tier_long = _LADDER[np.minimum(np.searchsorted(_LADDER, long_half), ladder)]
    tier_short = np.minimum(_LADDER[np.minimum(np.searchsorted(_LADDER, short_half), ladder)], tier_long)

    # channel phases (K, tx, rx): amplitude, the centring constant, the slot's share of the Doppler phase,
    # the virtual array
    chan_phase = ((tm.amp * _cycles(-tm.g * s_c * n_c))[:, None, None]
                  * _ramp(n_tx, alpha / n_tx)[:, :, None]
                  * _ramp(n_tx * n_rx, preset.element_spacing_wl * tm.sin_t).reshape(-1, n_tx, n_rx)
                  ).astype(dtype)
    eps = (np.arange(n_tx) / n_tx - (n_tx - 1) / (2.0 * n_tx)) / m                    # slot offsets of σ̂

    # Tiers of equal patch shape, each done in a few batched products; a tier of fewer than _RD_MIN_TIER
    # scatterers joins the next larger one (a larger patch is exact too, and each tier has a fixed cost)
    key = tier_long.astype(np.int64) * (1 << 20) + tier_short.astype(np.int64)
    shapes = np.unique(key)
    for small, large in zip(shapes[:-1], shapes[1:]):
        if np.count_nonzero(key == small) < _RD_MIN_TIER:
            key[key == small] = max(large, (small >> 20 << 20) + (large & 0xFFFFF))
    plan = []
    for shape in np.unique(key):                                            # a loop over a few patch shapes
        idx = np.flatnonzero(key == shape)
        h_long, h_short = int(shape >> 20), int(shape & 0xFFFFF)
        rects = _rectangles(m, n, h_long, h_short)
        dense = sum(len(a) * len(b) for a, b in rects) * 4 >= cells
        if dense:                                                           # the whole map, in grid order
            rects = [(tuple(range(m)), tuple(range(n)))]
        plan.append((idx, rects, dense))

    # Patches collect in one (cell × scatterer) sparse matrix per transmitter (same pattern, the transmitter's
    # values), flushed into the maps whenever _RD_SPARSE_ENTRIES entries have collected: bounded memory
    total = sum(pl[0].size * sum(len(a) * len(b) for a, b in pl[1]) for pl in plan if not pl[2])
    budget = min(total, _RD_SPARSE_ENTRIES)
    data = np.empty((n_tx, budget), dtype=dtype)
    rows = np.empty(budget, dtype=np.int32)
    held: list[tuple[np.ndarray, int]] = []                                 # (scatterers, entries each)
    at = 0

    def flush() -> None:
        nonlocal at
        if not at:
            return
        cols = np.concatenate([sel for sel, _ in held])
        counts = np.concatenate([np.full(sel.size, size) for sel, size in held])
        indptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
        mat = scipy.sparse.csc_array((data[0, :at], rows[:at], indptr), shape=(cells, cols.size))
        for t in range(n_tx):
            mat.data = data[t, :at]                                         # same pattern, this transmitter's values
            # every receiver's channel in one pass over the entries (each cell's sum in the same order as one
            # vector a channel: the same values)
            out[t * n_rx:(t + 1) * n_rx] += (mat @ chan_phase[cols, t, :]).T
        held.clear()
        at = 0

    # Doppler: e^{2πi e_d m/M} = e^{iπ e_d}·e^{2πi e_d μ̂}; range: e^{2πi(e_r n/N + q n²)} = e^{2πi(e_r/2 + qN²/4)}
    # ·e^{2πi((e_r + qN²)ν̂ + qN²ν̂²)}; the second factors as power series in μ̂, ν̂, so every patch is a small
    # product with the tabulated patches of the windowed moments (no exponential per sample)
    e_d, e_r = xd - pd, xr - pr
    qn2 = tm.q * n * n
    series_d = _frequency_series(e_d) * np.exp(1j * np.pi * e_d)[:, None]
    series_r = _frequency_series(e_r + qn2, qn2) * _cycles(e_r / 2.0 + qn2 / 4.0)[:, None]
    for idx, rects, dense in plan:
        area = sum(len(a) * len(b) for a, b in rects)
        step = max(1, _RD_CHUNK_ELEMENTS // (n_tx * area))
        for i0 in range(0, idx.size, step):                                 # chunks bound the memory
            sel = idx[i0: i0 + step]
            k = sel.size
            p_terms = int(terms[sel].max())
            coef = _series_coefficients(phi[sel], eps, p_terms)              # (tx, k, j, p)
            if not dense:
                size = k * area
                if at + size > budget:
                    flush()
                # column by column: each scatterer's cells of every rectangle together, each rectangle written in
                # its columns' place (no concatenated copy)
                block, block_rows = data[:, at: at + size].reshape(n_tx, k, area), rows[at: at + size].reshape(k, area)
                col = 0
            for off_d, off_r in rects:                                       # one or two rectangles
                nd, nr = len(off_d), len(off_r)
                if dense:                                                    # every bin, counted from 0: FFTs
                    dop = scipy.fft.fft(_ramp(m, xd[sel] / m)[:, None, :] * _windowed_moments(m, p_terms)[None],
                                        axis=2)
                    rng_ = scipy.fft.fft(_ramp(n, xr[sel] / n, quad=tm.q[sel])[:, None, :]
                                         * _windowed_moments(n, p_terms)[None], axis=2)
                else:
                    # one small product per scatterer (batched): a single large one would wake OpenBLAS's
                    # threads, which then spin against the noise thread
                    dop = (series_d[sel, None, :] @ _moment_spectra(m, p_terms, off_d)).reshape(k, p_terms, nd)
                    rng_ = (series_r[sel, None, :] @ _moment_spectra(n, p_terms, off_r)).reshape(k, p_terms, nr)
                # (tx, k, i_d, i_r): G_t = coef_t @ R, then D^T @ G_t; batched over (tx, k), small products
                resp = np.swapaxes(dop, 1, 2)[None] @ (coef @ rng_[None])
                if dense:
                    for t in range(n_tx):
                        out[t * n_rx:(t + 1) * n_rx] += chan_phase[sel, t].T @ resp[t].reshape(k, cells).astype(dtype)
                    continue
                block[:, :, col: col + nd * nr] = resp.reshape(n_tx, k, nd * nr)
                block_rows[:, col: col + nd * nr] = (
                    (((pd[sel, None].astype(np.int32) + np.asarray(off_d, dtype=np.int32)) % m)[:, :, None] * n
                     + ((pr[sel, None].astype(np.int32) + np.asarray(off_r, dtype=np.int32)) % n)[:, None, :]
                     ).reshape(k, nd * nr))
                col += nd * nr
            if dense:
                continue
            held.append((sel, area))
            at += size
    flush()
    return out


def _series_coefficients(phi: np.ndarray, eps: np.ndarray, terms: int) -> np.ndarray:
    """coef[t, k, j, p] = (2πiΦ_k)^p/p!·C(p, j)·ε_t^(p−j) for j ≤ p, else 0: shape (tx, K, terms, terms).

    Σ_p (2πiΦ)^p/p!·(μ̂ + ε_t)^p·ν̂^p regrouped by the power j of μ̂, so the
    Doppler patches are computed once for all transmitters.
    """
    p = np.arange(terms)
    z = 2j * np.pi * phi
    c_p = np.ones((phi.size, terms), dtype=np.complex128)
    if terms > 1:
        c_p[:, 1:] = np.cumprod(z[:, None] / p[None, 1:], axis=1)          # z^p/p! without overflow
    return c_p[None, :, None, :] * _binomial_mix(terms, np.asarray(eps, dtype=np.float64).tobytes())[:, None]


@functools.lru_cache(maxsize=64)
def _binomial_mix(terms: int, eps_bytes: bytes) -> np.ndarray:
    """C(p, j)·ε_t^(p−j) for j ≤ p, else 0: shape (tx, terms, terms), read only (the slot offsets ``eps_bytes``,
    float64, and the terms are those of a preset: made once, not per batch of scatterers)."""
    eps = np.frombuffer(eps_bytes, dtype=np.float64)
    p = np.arange(terms)
    log_fact = gammaln(p + 1.0)
    jj, pp = np.meshgrid(p, p, indexing="ij")                                 # (j, p)
    upper = jj <= pp
    gap = np.maximum(pp - jj, 0)
    binom = np.where(upper, np.exp(log_fact[pp] - log_fact[jj] - log_fact[gap]), 0.0)
    mix = binom[None] * np.where(upper[None], eps[:, None, None] ** gap[None], 0.0)      # (t, j, p)
    mix.setflags(write=False)
    return mix


# ----------------------------------------------------------------------------------------------------------
# impairments


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
