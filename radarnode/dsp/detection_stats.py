"""Exact statistics of the detection test: the non-coherent sum of N channels under CA- and OS-CFAR.

The signal chain tests, in every range–Doppler cell, the power summed over the
N virtual channels, X = Σ_c |x_c|². Per channel the noise is complex Gaussian
with the same variance σ² in every cell, but a window makes neighbouring cells
correlated: windowed white noise is white noise convolved with the window's
spectrum, so the complex correlation between cells ``lag`` bins apart is the
normalised DFT of w² (DFT-even Hann: 1, −2/3, +1/6, 0, …). Range and Doppler
windows act separably, so the correlation of two cells is ρ_d(Δd)·ρ_r(Δr).

Under noise alone, with σ² = 1:

* the cell under test is X ~ Gamma(N, 1) (independent of its training cells
  when the guard cells cover the window's correlation length);
* the sum of the training cells is Z = Σ_j λ_j E_j, E_j ~ Gamma(N, 1), λ_j the
  eigenvalues of the training cells' correlation matrix (all 1 without a
  window, then Z ~ Gamma(N·N_T, 1)).

CA-CFAR declares a detection when X > α·Z/N_T, so

    Pfa(α) = E_Z[ P(X > a Z) ],  a = α/N_T,
           = M(a) · Σ_{k<N} ν_k,   M(a) = Π_j (1 + aλ_j)^(−N),
    ν_0 = 1,  ν_{k+1} = N/(k+1) · Σ_{i=0}^{k} S_{i+1} ν_{k−i},  S_m = Σ_j (aλ_j/(1 + aλ_j))^m,

which follows from P(X > t) = e^{−t} Σ_{k<N} t^k/k! and the derivatives of
the moment-generating function of Z (every term is positive, so the sum is
stable at any Pfa). For λ_j = 1 it reduces to the closed form
Pfa = P(B > a/(1 + a)), B ~ Beta(N, N·N_T), which the tests use as the
independent reference. The threshold factor is found by a root search on
log Pfa. OS-CFAR has no closed form with correlated training cells: its
false-alarm probability is E[Q_N(α·Y_(k))] (Q_N the Gamma(N) survival
function, Y_(k) the k-th smallest training cell) averaged over simulated
training rings drawn with the exact correlation (a fixed seed: the threshold
is deterministic). Conditioning on Y_(k) makes this average smooth, so a few
thousand rings give it to a few per cent even at 1e-6.

Detection probability (the target's complex amplitude is the same in every
channel up to the array phase, total windowed energy E over σ²):

* Swerling 0: 2X ~ χ'²(2N, 2E) (non-central), Pd = E_Z[P(X > aZ)];
* Swerling 1 (Rayleigh amplitude, frame to frame): X = (1 + E)·Exp(1) +
  Gamma(N − 1), whose survival function is closed:
  P(X > t) = Q_{N−1}(t) + e^{−t/μ} b^{−(N−1)} P_{N−1}(b t), μ = 1 + E, b = 1 − 1/μ.

All functions are pure; arrays broadcast; nothing loops over cells.

References
----------
Richards, *Fundamentals of Radar Signal Processing*, 2nd ed., sec. 6.2–6.5
(non-coherent integration, Swerling models, CA- and OS-CFAR).
Rohling, "Radar CFAR thresholding in clutter and multiple target situations",
IEEE Trans. AES-19 (1983).
"""

from __future__ import annotations

import functools
import math

import numpy as np

from radarnode.errors import ConfigError

#: simulated training rings behind an OS-CFAR threshold (fixed seed)
OS_RINGS = 4000
#: quantiles of the training sum over which a detection probability is averaged
Z_QUANTILES = 48


def noise_correlation(window: np.ndarray) -> np.ndarray:
    """Complex correlation of windowed white noise between DFT bins ``lag`` apart.

    Parameters
    ----------
    window : array, shape (n,)
        The window applied before the FFT.

    Returns
    -------
    complex array, shape (n,): ρ[lag], ρ[0] = 1, circular in the lag.
    """
    w2 = np.asarray(window, dtype=np.float64) ** 2
    if w2.ndim != 1 or w2.size == 0 or not np.all(np.isfinite(w2)) or w2.sum() <= 0:
        raise ConfigError(f"window: value of shape {np.shape(window)} is not allowed; expected a finite, non-zero "
                          "1-D window")
    rho = np.fft.fft(w2) / w2.sum()
    rho[np.abs(rho) < 1e-12] = 0.0
    return rho


def correlation_length(rho: np.ndarray) -> int:
    """The largest lag (≤ n/2) at which the correlation is not zero."""
    n = rho.size
    lags = np.flatnonzero(np.abs(rho[: n // 2 + 1]) > 1e-9)
    return int(lags.max()) if lags.size else 0


#: the largest |integrated SNR| (dB) the statistic's readings take: beyond it 10^(ρ/10) leaves float64's range on the
#: way (a reading at 1e308 dB came out NaN with overflow warnings: an independent tester's finding)
RHO_DB_LIMIT = 300.0


def _check_range(where: str, name: str, value, lo: float, hi: float, what: str) -> None:
    """A ValueError naming ``name`` where ``value`` holds a NaN or a value outside [lo, hi]."""
    a = np.asarray(value, dtype=np.float64)
    bad = ~((a >= lo) & (a <= hi))                 # (NaN fails both)
    if np.any(bad):
        first = float(np.ravel(a[bad] if a.ndim else a)[0])
        raise ValueError(f"{where}: {name} holds {int(np.count_nonzero(bad))} value(s) outside [{lo:g}, {hi:g}] "
                         f"(first {first!r}); expected {what} in [{lo:g}, {hi:g}]")


def ring_correlation(offsets: np.ndarray, rho_d: np.ndarray, rho_r: np.ndarray) -> np.ndarray:
    """Correlation matrix of a set of cells given as (doppler, range) offsets, shape (n, 2) -> (n, n)."""
    dd = offsets[:, None, 0] - offsets[None, :, 0]
    dr = offsets[:, None, 1] - offsets[None, :, 1]
    return rho_d[dd % rho_d.size] * rho_r[dr % rho_r.size]


def ring_eigenvalues(offsets: np.ndarray, rho_d: np.ndarray, rho_r: np.ndarray) -> np.ndarray:
    """Eigenvalues λ_j of the training cells' correlation (Hermitian, so real and ≥ 0)."""
    lam = np.linalg.eigvalsh(ring_correlation(offsets, rho_d, rho_r))
    return np.clip(lam, 0.0, None)


#: :func:`ca_log_pfa` scales its ν down once one exceeds this (a step multiplies them by at most N·N_T: far below
#: the 1e108 left to overflow)
_RESCALE_ABOVE = 1e200


def ca_log_pfa(alpha: float, n_channels: int, eig: np.ndarray) -> float:
    """log Pfa of CA-CFAR with threshold α·mean(training) (see the module docstring)."""
    eig = np.asarray(eig, dtype=np.float64)
    a = alpha / eig.size
    q = a * eig / (1.0 + a * eig)
    s = np.sum(q[None, :] ** np.arange(1, n_channels)[:, None], axis=1)  # S_1 … S_{N−1}
    nu = np.zeros(n_channels)
    nu[0] = 1.0
    # the ν_k grow like the Poisson weights of a mean near N·a·Σλ (past 1e308 from N ≈ 450 on a 248-cell ring: α
    # came out infinite, the radar blind, an independent tester's finding); the recurrence is linear and homogeneous
    # in ν, so every ν computed so far is scaled down together and the scale kept as a logarithm
    log_scale = 0.0
    for k in range(n_channels - 1):           # N terms of a recurrence, not a loop over cells
        nu[k + 1] = n_channels / (k + 1) * np.dot(s[: k + 1], nu[k::-1])
        if nu[k + 1] > _RESCALE_ABOVE:
            top = nu[: k + 2].max()
            nu[: k + 2] /= top
            log_scale += math.log(top)
    return float(-n_channels * np.sum(np.log1p(a * eig)) + log_scale + np.log(np.sum(nu)))


def ca_alpha(pfa: float, n_channels: int, eig: np.ndarray) -> float:
    """Threshold factor α (on the mean of the training cells) that gives ``pfa`` exactly."""
    _check_pfa(pfa)
    target = math.log(pfa)
    f = lambda alpha: ca_log_pfa(alpha, n_channels, eig) - target   # noqa: E731 - decreasing in α
    return _root_decreasing(f, 0.0)


def gamma_sf(n_channels: int, t: np.ndarray) -> np.ndarray:
    """P(X > t) for X ~ Gamma(N, 1): the noise-only cell."""
    import scipy.special  # imported when first needed: a faster start (cached tables need none)
    return scipy.special.gammaincc(n_channels, t)


def os_rank_samples(n_channels: int, offsets: np.ndarray, rho_d: np.ndarray, rho_r: np.ndarray, rank: int,
                    draws: int = OS_RINGS, seed: int = 0) -> np.ndarray:
    """The ``rank``-th smallest training cell (1-based) of ``draws`` simulated noise-only rings.

    Each ring's cells are the sum over channels of |x|², x complex Gaussian with
    the cells' exact correlation (through the Cholesky-free square root
    U·√Λ of the correlation matrix). Returns shape (draws,).
    """
    corr = ring_correlation(offsets, rho_d, rho_r)
    lam, u = np.linalg.eigh(corr)
    root = u * np.sqrt(np.clip(lam, 0.0, None))[None, :]              # corr = root @ root^H
    rng = np.random.default_rng(seed)
    n = offsets.shape[0]
    power = np.zeros((n, draws))
    for _ in range(n_channels):               # N channels, each one matrix product over all rings
        y = (rng.standard_normal((n, draws)) + 1j * rng.standard_normal((n, draws))) * math.sqrt(0.5)
        x = root @ y
        power += x.real ** 2 + x.imag ** 2
    return np.partition(power, rank - 1, axis=0)[rank - 1]


def os_log_pfa(alpha: float, n_channels: int, ranked: np.ndarray) -> float:
    """log Pfa of OS-CFAR (threshold α·Y_(k)) from the simulated order statistics ``ranked``."""
    import scipy.special  # imported when first needed: a faster start (cached tables need none)
    return float(scipy.special.logsumexp(_log_gamma_sf(n_channels, alpha * ranked)) - math.log(ranked.size))


def os_alpha(pfa: float, n_channels: int, ranked: np.ndarray) -> float:
    """Threshold factor α (on the k-th smallest training cell) that gives ``pfa``."""
    _check_pfa(pfa)
    target = math.log(pfa)
    f = lambda alpha: os_log_pfa(alpha, n_channels, ranked) - target   # noqa: E731
    return _root_decreasing(f, 1e-9)


def _root_decreasing(f, lo: float) -> float:
    """The root of a decreasing function above ``lo`` (f(lo) > 0), by doubling, then regula falsi with the Illinois
    rule (the end that stayed put twice has its value halved) within the bracket, to 1e-13 relative; a step that does
    not halve the bracket is followed by a bisection. About 10 evaluations where bisection took 46 (scipy.optimize's
    import alone costs more than either)."""
    hi = 1.0
    f_hi = f(hi)
    while f_hi > 0:
        lo, hi = hi, hi * 2.0
        f_hi = f(hi)
    f_lo = f(lo)
    side = 0
    while hi - lo > 1e-13 * hi:
        width = hi - lo
        x = hi - f_hi * width / (f_hi - f_lo) if f_lo > f_hi else 0.5 * (lo + hi)
        if not lo < x < hi:
            x = 0.5 * (lo + hi)
        fx = f(x)
        if fx > 0:
            lo, f_lo = x, fx
            if side == -1:
                f_hi *= 0.5
            side = -1
        elif fx < 0:
            hi, f_hi = x, fx
            if side == 1:
                f_lo *= 0.5
            side = 1
        else:
            return x
        if hi - lo > 0.5 * width:               # a slow step: bisect once
            mid = 0.5 * (lo + hi)
            fm = f(mid)
            if fm > 0:
                lo, f_lo = mid, fm
            elif fm < 0:
                hi, f_hi = mid, fm
            else:
                return mid
            side = 0
    return 0.5 * (lo + hi)


def _log_gamma_sf(n: int, t: np.ndarray) -> np.ndarray:
    """log Q_N(t), accurate far in the tail (where gammaincc underflows): log Γ(N, t) − log Γ(N)."""
    import scipy.special  # imported when first needed: a faster start (cached tables need none)
    t = np.asarray(t, dtype=np.float64)
    q = scipy.special.gammaincc(n, t)
    with np.errstate(divide="ignore"):
        out = np.log(q)
    tail = q < 1e-250
    if tail.any():
        # Γ(N, t) = e^{−t} t^{N−1} Σ_{k<N} (N−1)!/(N−1−k)! t^{−k} for integer N
        tt = t[tail]
        k = np.arange(n)
        terms = scipy.special.gammaln(n) - scipy.special.gammaln(n - k)[None, :] - k[None, :] * np.log(tt)[:, None]
        out[tail] = -tt + (n - 1) * np.log(tt) + scipy.special.logsumexp(terms, axis=1) - scipy.special.gammaln(n)
    return out


def _check_pfa(pfa: float) -> None:
    if not (isinstance(pfa, (int, float)) and 0.0 < pfa < 0.5):
        raise ConfigError(f"pfa: value {pfa!r} is not allowed; expected a number in (0, 0.5)")


# --- detection probability ---------------------------------------------------------------------------------


def training_sum_quantiles(n_channels: int, eig: np.ndarray, count: int = Z_QUANTILES) -> np.ndarray:
    """Equally likely values of the training sum Z (mid-quantiles of a Gamma law with Z's mean and variance).

    Z is a positive sum of N·N_T weighted exponentials: a Gamma law with its
    first two moments is accurate to far better than what a detection
    probability needs (Pd depends on Z only through the small CFAR loss).
    """
    import scipy.special  # imported when first needed: a faster start (cached tables need none)
    eig = np.asarray(eig, dtype=np.float64)
    mean = n_channels * eig.sum()
    var = n_channels * np.sum(eig ** 2)
    shape, scale = mean * mean / var, var / mean
    u = (np.arange(count) + 0.5) / count
    return scale * scipy.special.gammaincinv(shape, u)                  # the Gamma law's quantiles


def sf_swerling0(t: np.ndarray, energy: np.ndarray, n_channels: int) -> np.ndarray:
    """P(X > t) for a steady target of total energy ``energy`` (over σ²) in N channels."""
    import scipy.stats  # imported when first needed: a faster start
    return scipy.stats.ncx2.sf(2.0 * np.asarray(t), 2 * n_channels, 2.0 * np.asarray(energy))


def sf_swerling1(t: np.ndarray, energy: np.ndarray, n_channels: int) -> np.ndarray:
    """P(X > t) for a Rayleigh-fluctuating target of mean total energy ``energy`` in N channels."""
    import scipy.special  # imported when first needed: a faster start (cached tables need none)
    t = np.asarray(t, dtype=np.float64)
    e = np.maximum(np.asarray(energy, dtype=np.float64), 1e-12)
    mu = 1.0 + e
    if n_channels == 1:
        return np.exp(-t / mu)
    b = e / mu
    nm1 = n_channels - 1
    # e^{−t/μ} b^{−(N−1)} P_{N−1}(b t), in logs so a weak target (b → 0) stays finite
    with np.errstate(divide="ignore"):
        log_p = np.log(scipy.special.gammainc(nm1, b * t))
    tail = np.exp(np.minimum(-t / mu - nm1 * np.log(b) + log_p, 0.0))
    return np.minimum(scipy.special.gammaincc(nm1, t) + tail, 1.0)


#: Acklam's rational approximation of the standard normal quantile (relative error below 1.2e-9): numerator and
#: denominator of the central region (|p − ½| ≤ ½ − P_LOW) and of the tails
_ACKLAM_A = (-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02, 1.383577518672690e+02,
             -3.066479806614716e+01, 2.506628277459239e+00)
_ACKLAM_B = (-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02, 6.680131188771972e+01,
             -1.328068155288572e+01, 1.0)
_ACKLAM_C = (-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00, -2.549732539343734e+00,
             4.374664141464968e+00, 2.938163982698783e+00)
_ACKLAM_D = (7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00, 3.754408661907416e+00, 1.0)
_ACKLAM_P_LOW = 0.02425


def normal_isf(s: np.ndarray) -> np.ndarray:
    """z with P(N(0, 1) > z) = ``s``, for s in (0, 1) (clipped to [1e-300, 1 − 1e-16]): Acklam's rational
    approximation, relative error below 1.2e-9, in numpy alone (scipy.special takes 0.2 s to import, more than the
    object level's set-up; the tests check it against ``scipy.special.ndtri``)."""
    p = np.clip(np.asarray(s, dtype=np.float64), 1e-300, 1.0 - 1e-16)
    low = np.minimum(p, 1.0 - p)                     # the nearer tail's probability: z = ∓Φ⁻¹(low)
    q = np.sqrt(-2.0 * np.log(np.maximum(low, 1e-300)))
    tail = np.polyval(_ACKLAM_C, q) / np.polyval(_ACKLAM_D, q)          # Φ⁻¹(low), low < P_LOW
    c = 0.5 - p                                      # Φ⁻¹(1 − p) = −Φ⁻¹(p) in the centre
    r = c * c
    centre = np.polyval(_ACKLAM_A, r) * c / np.polyval(_ACKLAM_B, r)
    return np.where(low < _ACKLAM_P_LOW, np.where(p < 0.5, -tail, tail), centre)


def statistic_isf(s: np.ndarray, energy: np.ndarray, n_channels: int) -> np.ndarray:
    """The value x that the test's statistic X (over σ², summed over N channels) of a steady return of windowed
    energy ``energy`` exceeds with probability ``s``: 2X ~ χ'²(2N, 2E) (non-central). Patnaik's central
    approximation c·χ²(ν) (the same mean and variance, c = (k + 2λ)/(k + λ), ν = (k + λ)²/(k + 2λ), k = 2N, λ = 2E)
    with the Wilson–Hilferty cube for the χ² quantile. Against the exact quantile (``scipy.stats.ncx2``), for
    E = 3 … 1e5 and s = 1e-4 … 0.9 wherever x − N exceeds E/2 (where a detected return lies), x − N within 0.55 dB
    at N = 1, 0.4 dB at N = 2, 0.12 dB at N = 12, 0.04 dB at N = 48 and 0.015 dB at N = 192
    (tests/test_detection_stats.py); it is worse in the far tail of a weak return (0.8 dB at N = 1, E = 1–3,
    s = 1e-6). Arrays broadcast."""
    k = 2.0 * n_channels
    lam = 2.0 * np.asarray(energy, dtype=np.float64)
    c = (k + 2.0 * lam) / (k + lam)
    nu = (k + lam) ** 2 / (k + 2.0 * lam)
    h = 2.0 / (9.0 * nu)
    cube = np.maximum(1.0 - h + normal_isf(s) * np.sqrt(h), 0.0)
    return 0.5 * c * nu * cube ** 3


def normal_cdf(z: np.ndarray) -> np.ndarray:
    """P(N(0, 1) ≤ z): Abramowitz–Stegun 7.1.26 for erfc (absolute error below 1.5e-7), z clipped at ±5 (Q(5) =
    2.9e-7); numpy alone, as :func:`normal_isf`."""
    z = np.asarray(z, dtype=np.float64)
    x = np.minimum(np.abs(z), 5.0) / math.sqrt(2.0)
    t = 1.0 / (1.0 + 0.3275911 * x)
    erfc = t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429)))) \
        * np.exp(-x * x)
    return np.where(z >= 0.0, 1.0 - 0.5 * erfc, 0.5 * erfc)


def detection_probability(energy: np.ndarray, alpha: float, n_channels: int, eig: np.ndarray,
                          swerling: int = 1) -> np.ndarray:
    """Pd of CA-CFAR for targets of total windowed energy ``energy`` (over σ², linear), any shape."""
    if swerling not in (0, 1):
        raise ConfigError(f"swerling: value {swerling!r} is not allowed; expected 0 or 1")
    eig = np.asarray(eig, dtype=np.float64)
    z = training_sum_quantiles(n_channels, eig)
    t = (alpha / eig.size) * z                                        # (Q,)
    e = np.asarray(energy, dtype=np.float64)
    sf = sf_swerling0 if swerling == 0 else sf_swerling1
    return sf(t.reshape((-1,) + (1,) * e.ndim), e[None], n_channels).mean(axis=0)


@functools.lru_cache(maxsize=32)
def _cached_ring(guard: tuple[int, int], train: tuple[int, int]) -> np.ndarray:
    gd, gr = guard
    td, tr = train
    d, r = np.mgrid[-(gd + td):gd + td + 1, -(gr + tr):gr + tr + 1]
    ring = (np.abs(d) > gd) | (np.abs(r) > gr)
    return np.stack([d[ring], r[ring]], axis=1)


def ring_offsets(guard: tuple[int, int], train: tuple[int, int], left: int | None = None,
                 right: int | None = None) -> np.ndarray:
    """(doppler, range) offsets of the training cells of a rectangular ring, shape (n_train, 2); with ``left`` and
    ``right``, of the ring that loses the range columns beyond ``left`` bins to the left and ``right`` to the right
    (the map's first or last range bins cut it)."""
    off = _cached_ring(tuple(guard), tuple(train))
    return off if left is None else off[(off[:, 1] >= -left) & (off[:, 1] <= right)]


# --- the statistic of one processing chain -----------------------------------------------------------------


def window_snr_gain(window: np.ndarray) -> float:
    """Coherent SNR gain of a window against none, (Σw)² / (N·Σw²) (Hann: 2/3, −1.76 dB)."""
    w = np.asarray(window, dtype=np.float64)
    return float(w.sum() ** 2 / (w.size * np.sum(w * w)))


def straddle_gain(window: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """Power of a windowed tone ``delta`` bins off the bin centre, relative to on-bin (any shape of delta):
    |:func:`window_response`|²."""
    return np.abs(window_response(window, delta)) ** 2


def window_response(window: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """Complex amplitude, in a bin, of a windowed tone ``delta`` bins above that bin, relative to on-bin:
    Σ_n w_n·e^{iθn} / Σ_n w_n, θ = 2π·δ/N (any shape of delta; a DFT bin k of the tone at k + δ).

    Computed with n = B·a + b (B ≈ √N): Σ_a e^{iθBa} · Σ_b w_{Ba+b}·e^{iθb}, so that a δ costs about 2√N complex
    exponentials instead of N (a statistic's two 2001-point straddle tables of a 256-sample window: 17 → 2.4 ms
    each); within 3e-15 of the direct sum, relative."""
    w = np.asarray(window, dtype=np.float64)
    d = np.asarray(delta, dtype=np.float64)
    n = w.size
    b = max(1, math.isqrt(n))
    a = -(-n // b)
    padded = np.zeros(a * b)
    padded[:n] = w
    theta = (2.0 * np.pi / n) * d.reshape(-1)
    inner = np.exp(1j * np.multiply.outer(theta, np.arange(b))) @ padded.reshape(a, b).T       # (δ, a)
    resp = np.einsum("da,da->d", inner, np.exp(1j * np.multiply.outer(theta, b * np.arange(a))))
    return (resp / w.sum()).reshape(d.shape)


#: the cells about a return's nearest one that :meth:`DetectionStatistic.draw_block` tests, per axis (bins)
_BLOCK_STEPS = np.array([-1.0, 0.0, 1.0])
#: :meth:`DetectionStatistic.block_signal`'s response table: its reach (bins) and points a bin
WIDE_REACH, WIDE_PER_BIN = 3.5, 2000


class DetectionStatistic:
    """The detection test of one chain: N channels summed non-coherently, two windows, one CFAR.

    It converts the integrated SNR ρ (the matched-filter SNR of all samples,
    chirps and channels, no window: ``radarnode.radar.equation.snr_db``) into
    the windowed energy E the test sees, gives the exact Pd of that test, and
    draws the test's outcome without a signal (the detection level), so every
    fidelity level detects with the same law.

    Parameters
    ----------
    cfar : Cfar
        The CFAR the chain applies (its n_channels, α and training-ring eigenvalues are used).
    range_window, doppler_window : arrays
        The windows applied before the range and Doppler FFTs.
    """

    #: straddle offsets (bins) over which a target's unknown position within its cell is averaged
    STRADDLE_POINTS = 9

    def __init__(self, cfar, range_window: np.ndarray, doppler_window: np.ndarray) -> None:
        self.cfar = cfar
        self.n_channels = cfar.n_channels
        self.range_window = np.asarray(range_window, dtype=np.float64)
        self.doppler_window = np.asarray(doppler_window, dtype=np.float64)
        self.window_gain = window_snr_gain(self.range_window) * window_snr_gain(self.doppler_window)
        eig = getattr(cfar, "eigenvalues", None)
        self.eigenvalues = eig if eig is not None else np.ones(cfar.n_train)
        # the threshold on the training sum: α·Z/N_T (OS-CFAR: the CA factor with the same Pfa stands in for Pd)
        self.alpha_ca = cfar.alpha if cfar.name == "ca" else ca_alpha(cfar.pfa, self.n_channels, self.eigenvalues)
        self._pd_tables: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._second_tables: dict[float, tuple[np.ndarray, np.ndarray]] = {}     # pd_second_look, per gain
        # straddle gains tabulated once (|δ| ≤ ½, step 1/2000: interpolation error < 1e-6)
        self._delta = np.linspace(-0.5, 0.5, 2001)
        self._straddle_r = straddle_gain(self.range_window, self._delta)
        self._straddle_d = straddle_gain(self.doppler_window, self._delta)

    def energy(self, rho: np.ndarray, delta_range: np.ndarray = 0.0, delta_doppler: np.ndarray = 0.0) -> np.ndarray:
        """Windowed energy E over σ² (summed over channels) of targets of integrated SNR ρ (linear); the offsets
        from the bin centres (|δ| ≤ ½) in range and Doppler bins."""
        return (np.asarray(rho, dtype=np.float64) * self.window_gain
                * np.interp(delta_range, self._delta, self._straddle_r)
                * np.interp(delta_doppler, self._delta, self._straddle_d))

    def pd(self, energy: np.ndarray, swerling: int = 1) -> np.ndarray:
        """Exact Pd of the test for windowed energy ``energy`` (linear, any shape)."""
        return detection_probability(energy, self.alpha_ca, self.n_channels, self.eigenvalues, swerling)

    def pd_of_snr(self, rho_db: np.ndarray, swerling: int = 1) -> np.ndarray:
        """Pd of targets of integrated SNR ``rho_db`` at a position uniform within their cell (straddle averaged).

        Tabulated once per Swerling case on a 0.05 dB grid and interpolated, so it
        costs one ``np.interp`` per call (the object level calls it every cycle).
        """
        if swerling not in self._pd_tables:
            # Pd of the windowed energy on a fine dB grid (one function of one variable), then its average
            # over the straddle gains of a uniform position, by interpolation in dB
            e_grid = np.arange(-40.0, 70.0001, 0.02)
            pd_e = self.pd(10.0 ** (e_grid / 10.0), swerling)
            u = (np.arange(self.STRADDLE_POINTS) + 0.5) / self.STRADDLE_POINTS - 0.5
            g = (straddle_gain(self.range_window, u)[:, None] * straddle_gain(self.doppler_window, u)[None, :]).ravel()
            offset = 10.0 * np.log10(self.window_gain * g)                 # dB from ρ to E
            grid = np.arange(-30.0, 60.0001, 0.05)
            table = np.interp(grid[:, None] + offset[None, :], e_grid, pd_e).mean(axis=1)
            self._pd_tables[swerling] = (grid, table)
            self._table_built()
        grid, table = self._pd_tables[swerling]
        return np.interp(np.asarray(rho_db, dtype=np.float64), grid, table)

    def snr_of_pd(self, pd: np.ndarray, swerling: int = 1) -> np.ndarray:
        """The integrated SNR (dB) at which :meth:`pd_of_snr` reaches ``pd``: its table inverted by interpolation
        (where the table is flat, at the false-alarm floor or at 1, the first SNR of the flat part)."""
        self.pd_of_snr(0.0, swerling)
        grid, table = self._pd_tables[swerling]
        inverse = self.__dict__.setdefault("_pd_inverse", {})
        if swerling not in inverse or inverse[swerling][0] is not table:     # (made once a table)
            rising = np.maximum.accumulate(table)
            keep = np.concatenate([[True], np.diff(rising) > 0.0])
            inverse[swerling] = (table, rising[keep], grid[keep])
        _, xp, fp = inverse[swerling]
        pd = np.asarray(pd, dtype=np.float64)
        _check_range("DetectionStatistic.snr_of_pd", "pd", pd, 0.0, 1.0, "probabilities")
        return np.interp(pd, xp, fp)

    #: equal-probability points of the exponential law (the midpoints of 48 quantile bins) over which a Swerling 1
    #: target's two looks in one cycle are averaged (:meth:`pd_second_look`)
    _EXP_POINTS = -np.log1p(-(np.arange(48) + 0.5) / 48)

    def pd_second_look(self, rho_db: np.ndarray, gain_db: float, swerling: np.ndarray | int) -> np.ndarray:
        """P(a second look detects | the first did): the second look (another chirp sequence of the same cycle, a
        staggered ramp) at ``rho_db`` + ``gain_db`` with its own noise and, for a Swerling 1 target, the same
        fluctuation (one per cycle). Swerling 0: the second look's Pd. Swerling 1:
        E[Pd₀(ρ₁x)·Pd₀(ρ₂x)] / E[Pd₀(ρ₁x)] over x ~ Exp(1) (48 equal-probability points), tabulated once per gain
        on a 0.1-dB grid over −10 … 50 dB (1.4 ms) and interpolated (one ``np.interp`` a call). ``swerling``
        broadcasts with ``rho_db``."""
        rho = np.asarray(rho_db, dtype=np.float64)
        if not (np.ndim(gain_db) == 0 and np.asarray(gain_db).dtype.kind in "iuf" and math.isfinite(gain_db)):
            # (a NaN gain's table, kept by the cache, made its file unreadable: an independent tester's finding)
            raise ValueError(f"DetectionStatistic.pd_second_look: gain_db {gain_db!r} is not allowed; expected a "
                             "finite number of dB")
        fluct = np.broadcast_to(np.asarray(swerling) == 1, rho.shape)
        if not fluct.any():
            return self.pd_of_snr(rho + gain_db, 0)
        key = round(float(gain_db), 9)
        if key not in self._second_tables:
            # (−10 … 50 dB: below, both looks' Pd are the false-alarm floor's; above, 1 — clamped there)
            grid = np.arange(-10.0, 50.0001, 0.1)
            r = grid[:, None] + 10.0 * np.log10(self._EXP_POINTS)[None, :]
            first = self.pd_of_snr(r, 0)
            both = (first * self.pd_of_snr(r + gain_db, 0)).mean(axis=1)
            marginal = first.mean(axis=1)
            self._second_tables[key] = (grid, np.where(marginal > 0.0, both / np.maximum(marginal, 1e-300), 0.0))
            self._table_built()
        grid, table = self._second_tables[key]
        fluctuating = np.interp(rho, grid, table)
        if fluct.all():                 # (the steady Pd only where a look does not fluctuate)
            return np.asarray(fluctuating)
        return np.where(fluct, fluctuating, self.pd_of_snr(rho + gain_db, 0))

    #: the fluctuation factors (power over its mean, Exp(1) a priori) and the SNR step of the table of
    #: :meth:`fluctuation_given_detection` (built from the Swerling 0 Pd table: 901 × 400, a row when first read)
    _G_GRID = np.geomspace(1e-4, 60.0, 400)
    _POSTERIOR_STEP_DB = 0.1
    _POSTERIOR_RHO_DB = np.arange(-30.0, 60.0001, _POSTERIOR_STEP_DB)

    def fluctuation_given_detection(self, rho_db: np.ndarray, w: np.ndarray) -> np.ndarray:
        """The power factor g of a Swerling 1 return the test detected at mean integrated SNR ``rho_db``: the
        ``w``-quantile (w uniform in (0, 1)) of its posterior p(g | detected) ∝ Pd₀(ρ·g)·e^{−g} (Pd₀ the steady
        return's straddle-averaged Pd, :meth:`pd_of_snr`; a priori g ~ Exp(1)). Near the threshold a detected return
        is one that faded up (g's posterior median 3.3 at Pd 0.1 on mimo12, 0.69 a priori); well above it the
        posterior is the prior. Tabulated on ρ every 0.1 dB (nearest row) and 400 log-spaced g from 1e-4 to 60,
        inverted by linear interpolation of its CDF. Arrays broadcast."""
        rho_db, w = np.broadcast_arrays(np.asarray(rho_db, dtype=np.float64), np.asarray(w, dtype=np.float64))
        if not np.all(np.isfinite(rho_db)):
            raise ValueError("DetectionStatistic.fluctuation_given_detection: rho_db must be finite (a NaN or an "
                             "infinity given); expected dB values")
        _check_range("DetectionStatistic.fluctuation_given_detection", "w", w, 0.0, 1.0, "uniforms")
        n_g = self._G_GRID.size
        i = np.clip(np.rint((rho_db - self._POSTERIOR_RHO_DB[0]) / self._POSTERIOR_STEP_DB), 0,
                    self._POSTERIOR_RHO_DB.size - 1).astype(np.intp)
        rows, cdf, flat = self._posterior_rows(i)
        p = np.searchsorted(rows, i)                               # each element's row among those built
        w = np.clip(w, 1e-12, 1.0 - 1e-12)
        j = np.searchsorted(flat, w + 2.0 * i) - p * n_g           # the first grid point whose CDF reaches w
        j = np.clip(j, 0, n_g - 1)
        hi = cdf[p, j]
        lo = np.where(j > 0, cdf[p, np.maximum(j - 1, 0)], 0.0)
        g_lo = np.where(j > 0, self._G_GRID[np.maximum(j - 1, 0)], 0.0)
        frac = (w - lo) / np.maximum(hi - lo, 1e-300)
        return g_lo + np.clip(frac, 0.0, 1.0) * (self._G_GRID[j] - g_lo)

    def _posterior_rows(self, i: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The rows of :meth:`fluctuation_given_detection`'s table built so far, with those of the row indices ``i``
        (into ``_POSTERIOR_RHO_DB``) built now: (their indices, increasing; their CDFs over ``_G_GRID``; the CDFs
        flattened with row index k offset by 2k, so that one ``searchsorted`` inverts every element). A row is built
        when first asked for: a run reads a few hundred of the 901 (166 in a 300-s log of ``highway_cut_in``), and
        the whole table (2.9 MB a array, written five times) cost a new model's first cycle some 15 ms, most of it
        the pages' first touch. Each row is the same numbers whenever it is built (every operation is per row)."""
        built = self.__dict__.get("_posterior")
        # the distinct rows, increasing (np.unique's check for a masked array imports numpy.ma: some 9 ms of a run)
        need = np.flatnonzero(np.bincount(i.ravel(), minlength=1))
        if built is not None:
            need = need[~np.isin(need, built[0], assume_unique=True)]
        if need.size:
            g = self._G_GRID
            dens = self.pd_of_snr(self._POSTERIOR_RHO_DB[need][:, None] + 10.0 * np.log10(g)[None, :], 0) \
                * np.exp(-g)[None, :]
            # the CDF over g by the trapezoid rule, from 0 (below g[0] the density is about dens[:, 0])
            mass = np.concatenate([dens[:, :1] * g[0], 0.5 * (dens[:, 1:] + dens[:, :-1]) * np.diff(g)], axis=1)
            cdf = np.cumsum(mass, axis=1)
            cdf /= cdf[:, -1:]
            rows = need
            if built is not None:
                rows = np.concatenate([built[0], need])
                order = np.argsort(rows, kind="stable")
                rows, cdf = rows[order], np.concatenate([built[1], cdf])[order]
            self._posterior = built = (rows, cdf, (cdf + 2.0 * rows[:, None]).ravel())
        return built

    def reading(self, rho_db: np.ndarray, v: np.ndarray, w: np.ndarray, fluctuating: np.ndarray,
                loss_db: np.ndarray | float = 0.0) -> np.ndarray:
        """The integrated SNR the chain reads of a return the test detected, over its mean ρ (linear): the measured
        energy (the statistic less the noise's mean N, as the chain's estimate) divided by the window's and the mean
        straddle's loss, as the chain divides its own out. Drawn jointly with the detection: ``v`` uniform in
        (0, 1) — the uniform u that decided it, over its Pd (u < Pd, so u/Pd is uniform) — and ``w`` a second
        uniform. A Swerling 1 return's fluctuation is :meth:`fluctuation_given_detection` at ``w``; its statistic
        given that fluctuation is the quantile v·Pd₀(ρ·g) of the steady law (:func:`statistic_isf`), the upper
        part of it that passed the test. So a return near the threshold reads high, as the chain reads the ones it
        detects (a reading drawn apart from the detection read −9.5 dBsm where the other levels read −4.5/−5.0 at
        Pd ≈ 0.3). The measured energy floored at 1e-30, as the detection level floors its own (a floor at −13 dB
        piled 4 % of a Swerling 1 target's readings at 40 dB on it, where the chain reads fades down to −22 dB: an
        independent tester's finding). ``loss_db`` (≥ 0): the SNR by which other targets in the training ring
        lowered the Pd that decided the detection (the masking, as an equivalent loss: :meth:`snr_of_pd` of the Pd
        without and with it): the return passed the raised threshold, so its fluctuation's posterior and the part
        of its statistic that passed are those at ρ less the loss, while its energy stays ρ's (drawn at ρ, a
        fluctuating point among four others 8 m apart on ``ars408_like``, its Pd masked by 0.7–1, read
        −5.2 / −1.6 / +1.4 dB where the detection level read −4.1 / −0.9 / +1.7). Arrays broadcast."""
        rho_db = np.asarray(rho_db, dtype=np.float64)
        loss_db = np.asarray(loss_db, dtype=np.float64)
        _check_range("DetectionStatistic.reading", "rho_db", rho_db, -RHO_DB_LIMIT, RHO_DB_LIMIT, "dB values")
        if not np.all(np.isfinite(loss_db)):
            bad = loss_db[~np.isfinite(loss_db)] if loss_db.ndim else loss_db
            raise ValueError(f"DetectionStatistic.reading: loss_db holds {np.size(bad)} value(s) that are not "
                             f"finite (first {float(np.ravel(bad)[0])!r}); expected finite dB values")
        v = np.asarray(v, dtype=np.float64)
        _check_range("DetectionStatistic.reading", "v", v, 0.0, 1.0, "the uniform that decided the detection over its Pd")
        _check_range("DetectionStatistic.reading", "w", w, 0.0, 1.0, "uniforms")
        fluctuating = np.asarray(fluctuating)
        if fluctuating.dtype.kind not in "bi":
            raise ValueError(f"DetectionStatistic.reading: fluctuating of dtype {fluctuating.dtype} is not allowed; "
                             "expected booleans (a NaN would count as True)")
        cond_db = rho_db - np.maximum(loss_db, 0.0)
        fluct = np.broadcast_to(fluctuating.astype(bool), rho_db.shape)
        g = np.ones(rho_db.shape)
        if fluct.any():
            g = np.where(fluct, self.fluctuation_given_detection(cond_db, w), 1.0)
        g_db = 10.0 * np.log10(np.maximum(g, 1e-300))
        s = np.clip(np.asarray(v, dtype=np.float64) * self.pd_of_snr(cond_db + g_db, 0), 1e-300, 1.0)
        loss = self.window_gain * self.straddle_mean
        mean = 10.0 ** (rho_db / 10.0) * loss
        x = statistic_isf(s, mean * g, self.n_channels)
        return np.maximum(x - self.n_channels, 1e-30) / mean

    @functools.cached_property
    def straddle_mean(self) -> float:
        """The straddle gain of a position uniform within its cell, averaged as :meth:`pd_of_snr` averages Pd."""
        u = (np.arange(self.STRADDLE_POINTS) + 0.5) / self.STRADDLE_POINTS - 0.5
        return float(np.mean(straddle_gain(self.range_window, u)[:, None] * straddle_gain(self.doppler_window, u)[None, :]))

    def draw(self, energy: np.ndarray, rng: np.random.Generator, interference: np.ndarray | float = 0.0,
             range_bins: np.ndarray | None = None, n_range: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """One draw of the test for steady targets of windowed energy ``energy``, shape (n,).

        The cell's statistic is X = |√E + n₀|² + Gamma(N − 1) (the signal's
        direction plus the N − 1 orthogonal noise dimensions), the threshold
        α·(Z + I)/N_T with Z the training sum (a Gamma law with Z's exact mean and
        variance) and I the other targets' energy in the training cells
        (:meth:`ring_interference`; CA-CFAR only: an order statistic ignores a few
        strong cells). A fluctuating (Swerling 1) target is a steady one whose
        energy was drawn from an exponential law first.

        With ``range_bins`` (the cells' range bins, shape (n,)) and ``n_range`` (the map's), a CA-CFAR ring
        that the map's first or last range bins cut is the chain's: only its cells inside the map, with their
        own α, training-sum law and count (:meth:`ring_cut`), as :class:`radarnode.dsp.cfar.CellAveragingCfar`
        tests the cells within ``guard + train`` range bins of an edge.

        Returns (detected, statistic), the statistic in units of σ² (the cell's
        power over the per-channel noise).
        """
        e = np.asarray(energy, dtype=np.float64)
        n = e.size
        z0 = (rng.standard_normal(n) + 1j * rng.standard_normal(n)) * math.sqrt(0.5)
        x = np.abs(np.sqrt(e) + z0) ** 2
        if self.n_channels > 1:
            x = x + rng.gamma(self.n_channels - 1, 1.0, n)
        return x > self._threshold(rng, n, interference, range_bins, n_range), x

    def _threshold(self, rng: np.random.Generator, n: int, interference, range_bins, n_range) -> np.ndarray:
        """One draw of the CFAR threshold α·(Z + I)/N_T for ``n`` tested cells (:meth:`draw`'s: the training sum Z
        a Gamma law with its exact mean and variance, the cut ring near the map's first or last range bins, the other
        targets' energy I in the ring for CA-CFAR)."""
        if range_bins is not None and self.cfar.name == "ca":
            alpha, mean, var, count = self.ring_cut(range_bins, n_range)
        else:
            eig = self.eigenvalues
            alpha, count = self.alpha_ca, eig.size
            mean, var = self.n_channels * eig.sum(), self.n_channels * np.sum(eig ** 2)
        z = rng.gamma(mean * mean / var, var / mean, n)
        if self.cfar.name == "ca":
            z = z + interference
        return alpha * z / count

    def draw_block(self, energy: np.ndarray, delta_range: np.ndarray, delta_doppler: np.ndarray,
                   rng: np.random.Generator, interference: np.ndarray | float = 0.0,
                   range_bins: np.ndarray | None = None, n_range: int | None = None,
                   signal: np.ndarray | None = None, signal_rows: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`draw` as the chain tests a return, which spreads over its nearest cell and the neighbours around it:
        the 3 × 3 cells about the nearest one, each with its share of the return and the windows' correlated noise;
        detected where the strongest of the nine passes the threshold (the chain reports a local maximum of its map
        above the CFAR's threshold, so a return half a bin off has two cells to be seen in, half a bin off in both
        axes four, and its side lobes a few more chances at low SNR).

        ``energy``: the windowed energy in the nearest cell (with its straddle, as :meth:`energy` gives it) of
        returns ``delta_range``, ``delta_doppler`` bins from that cell's centre (|δ| ≤ ½; clipped there), shape
        (n,). The nine cells share one threshold (their CA-CFAR rings differ by a column or a row). Returns
        (detected, statistic of the strongest cell), as :meth:`draw`.

        Measured against the chain at a fixed position in the cell (``benchmarks/calibration.py --only cells``): within
        0.04 of its Pd at every offset, where :meth:`draw` (the nearest cell alone) is up to 0.22 below. The detection
        level tests its range–Doppler cells with it.

        ``signal`` (k, N, 9), complex, with ``signal_rows`` (k,): the noise-free map of those rows' nine cells channel
        by channel (:meth:`block_signal`: several returns, each at its own offset and angle), in place of the one
        return that ``energy`` and the offsets describe; the noise is drawn as for every row (the same random stream
        whichever rows have one).
        """
        e = np.asarray(energy, dtype=np.float64)
        n = e.size
        if (signal is None) != (signal_rows is None) or (
                signal is not None and (np.shape(signal) != (len(signal_rows), self.n_channels, 9)
                                        or (len(signal_rows) and not 0 <= np.min(signal_rows) <= np.max(signal_rows) < n))):
            raise ConfigError(f"signal: shape {np.shape(signal)} with signal_rows of shape {np.shape(signal_rows)} is not "
                              f"allowed; expected both or neither, signal (k, {self.n_channels}, 9) for k rows in "
                              f"[0, {n})")
        dr = np.clip(np.asarray(delta_range, dtype=np.float64), -0.5, 0.5)
        dd = np.clip(np.asarray(delta_doppler, dtype=np.float64), -0.5, 0.5)
        grid, resp_r, resp_d, chol = self._block_tables()
        near = np.interp(dr, self._delta, self._straddle_r) * np.interp(dd, self._delta, self._straddle_d)
        amp = np.sqrt(e / np.maximum(near, 1e-300))                      # on-bin amplitude

        def response(table, x):
            return np.interp(x, grid, table.real) + 1j * np.interp(x, grid, table.imag)
        a_r = response(resp_r, dr[:, None] - _BLOCK_STEPS[None, :])        # (n, 3): cells −1, 0, +1
        a_d = response(resp_d, dd[:, None] - _BLOCK_STEPS[None, :])
        sig = amp[:, None] * (a_r[:, :, None] * a_d[:, None, :]).reshape(n, 9)
        # white noise in the channels, correlated between the nine cells by the windows; the return lies in one
        # direction of the channel space (the same for its nine cells), the other N − 1 directions are noise only
        z = (rng.standard_normal((n, self.n_channels, 9)) + 1j * rng.standard_normal((n, self.n_channels, 9))) \
            * math.sqrt(0.5)
        noise = z @ chol.T
        x = np.abs(sig + noise[:, 0, :]) ** 2
        if self.n_channels > 1:
            rest = noise[:, 1:, :]
            x += np.einsum("tci,tci->ti", rest.real, rest.real)
            x += np.einsum("tci,tci->ti", rest.imag, rest.imag)
        if signal is not None and len(signal_rows):
            # white in the channels: any basis of them holds the same noise, here the channels' own
            total = signal + noise[signal_rows]
            x[signal_rows] = np.einsum("tci,tci->ti", total.real, total.real) \
                + np.einsum("tci,tci->ti", total.imag, total.imag)
        best = x.max(axis=1)
        return best > self._threshold(rng, n, interference, range_bins, n_range), best

    def block_signal(self, z: np.ndarray, delta_range: np.ndarray, delta_doppler: np.ndarray, u: np.ndarray,
                     group: np.ndarray, groups: int) -> np.ndarray:
        """The noise-free map, channel by channel, of each group's returns in the 3 × 3 cells about the group's cell,
        as :meth:`draw_block`'s ``signal`` takes it: shape (groups, N, 9), cell q = 3·(range step) + (Doppler step).

        Return j (shape (n,) each): on-bin windowed amplitude and phase ``z`` (|z|² the energy :meth:`energy` gives on
        the bin), ``delta_range`` and ``delta_doppler`` bins from its group's cell (within ±2.5: its response in the
        cells one bin further is tabulated to ±:data:`WIDE_REACH`, zero beyond), ``u`` = d·sinθ (channel k at phase
        e^{2πi·u·k}), ``group`` its group in [0, groups). Σ_j z_j·W_r(δr_j − s)·W_d(δd_j − t)·e^{2πi·u_j·k}/√N:
        one return's nine cells are :meth:`draw_block`'s own (its energy over the N channels is |z|²·|W|²), two
        returns add in each channel at their own angle, so their cells fade and surge as the chain's do."""
        table = self._wide_table()
        n_ch = self.n_channels
        g = np.asarray(group, dtype=np.int64)
        if g.size and not 0 <= g.min() <= g.max() < groups:
            raise ConfigError(f"group: values {g.min()} … {g.max()} are not allowed; expected groups in [0, {groups})")
        order = np.argsort(g, kind="stable")
        g = g[order]
        # both axes' responses at the three steps, one linear interpolation in the uniform table (rows: range, Doppler)
        x = np.stack([np.asarray(delta_range, dtype=np.float64)[order],
                      np.asarray(delta_doppler, dtype=np.float64)[order]])[:, :, None] - _BLOCK_STEPS
        pos = (x + WIDE_REACH) * WIDE_PER_BIN
        i = np.clip(np.floor(pos), 0, table.shape[1] - 2).astype(np.intp)
        frac = pos - i
        row = np.arange(2)[:, None, None]
        a = table[row, i] * (1.0 - frac) + table[row, i + 1] * frac
        a[(pos < 0.0) | (pos > table.shape[1] - 1)] = 0.0               # zero beyond the table
        cells = (a[0][:, :, None] * a[1][:, None, :]).reshape(g.size, 9) * np.asarray(z)[order, None]
        steer = np.exp(2j * np.pi * np.multiply.outer(np.asarray(u, dtype=np.float64)[order], np.arange(n_ch))) \
            / math.sqrt(n_ch)
        out = np.zeros((groups, n_ch, 9), dtype=np.complex128)
        if g.size:
            starts = np.flatnonzero(np.r_[True, g[1:] != g[:-1]])
            out[g[starts]] = np.add.reduceat(steer[:, :, None] * cells[:, None, :], starts, axis=0)
        return out

    def _wide_table(self) -> np.ndarray:
        """:meth:`block_signal`'s table, (2, ·) complex: the range and Doppler windows' responses (as
        :meth:`_block_tables`', the convention of the noise correlation) over |δ| ≤ :data:`WIDE_REACH` bins,
        :data:`WIDE_PER_BIN` points a bin (linear interpolation within 4e-7 of the peak)."""
        table = self.__dict__.get("_wide")
        if table is None:
            grid = np.linspace(-WIDE_REACH, WIDE_REACH, int(2 * WIDE_REACH * WIDE_PER_BIN) + 1)
            table = self.__dict__["_wide"] = np.stack([window_response(self.range_window, grid),
                                                       window_response(self.doppler_window, grid)])
        return table

    def _block_tables(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`draw_block`'s tables, made on its first call: the windows' complex responses over |δ| ≤ 1.5 bins
        (step 1/2000) and the Cholesky factor of the nine cells' noise correlation (the Kronecker product of the two
        axes': E[n_a·conj(n_b)] = ρ[a − b], :func:`noise_correlation`)."""
        tables = self.__dict__.get("_block")
        if tables is None:
            grid = np.linspace(-1.5, 1.5, 6001)
            resp_r, resp_d = window_response(self.range_window, grid), window_response(self.doppler_window, grid)

            def axis(window):
                rho = noise_correlation(window)
                steps = _BLOCK_STEPS.astype(np.int64)
                return rho[(steps[:, None] - steps[None, :]) % rho.size]
            chol = np.linalg.cholesky(np.kron(axis(self.range_window), axis(self.doppler_window)))
            tables = self.__dict__["_block"] = (grid, resp_r, resp_d, chol)
        return tables

    def ring_cut(self, range_bins: np.ndarray, n_range: int) -> tuple[np.ndarray, ...]:
        """Per cell at ``range_bins`` (ints, shape (n,)) of a map of ``n_range`` range bins, the CA-CFAR ring the
        chain tests it with: (α, mean and variance of the training sum over σ², number of training cells), each
        shape (n,). Within ``guard + train`` bins of the first or last range bin the ring loses the columns beyond
        the map (:meth:`radarnode.dsp.cfar.CellAveragingCfar.alpha_for_cut`); elsewhere it is the full ring.
        Tabulated once per cut (at most 2·(guard + train) + 1 of them)."""
        r = np.asarray(range_bins, dtype=np.int64)
        reach = self.cfar.guard[1] + self.cfar.train[1]
        left, right = np.clip(r, 0, reach), np.clip(n_range - 1 - r, 0, reach)
        cuts = self.__dict__.setdefault("_cuts", {})
        key = left * (reach + 1) + right
        out = np.empty((4, r.size))
        built = False
        for k in np.flatnonzero(np.bincount(key, minlength=1)).tolist():     # the distinct cuts (not np.unique: numpy.ma)
            if k not in cuts:
                a, b = divmod(k, reach + 1)
                eig = self.cfar.cut_eigenvalues(a, b)
                cuts[k] = (self.cfar.alpha_for_cut(a, b), self.n_channels * eig.sum(),
                           self.n_channels * np.sum(eig ** 2), float(eig.size))
                built = True
            out[:, key == k] = np.array(cuts[k])[:, None]
        if built:
            self._table_built()
        return out[0], out[1], out[2], out[3]

    def cell_pairs(self, cell_d: np.ndarray, cell_r: np.ndarray, pos_d: np.ndarray, pos_r: np.ndarray,
                   shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
        """(cell index, target index) of the cells and targets within the ring tables' reach of each other in both
        axes, ±(guard + train + BOX_REACH) bins (a k-d tree on the circular map, the axes scaled to that reach):
        what :meth:`ring_interference` sums over."""
        (gd, gr), (td, tr) = self.cfar.guard, self.cfar.train
        m, n = shape
        cell_d, cell_r = np.asarray(cell_d, dtype=np.float64), np.asarray(cell_r, dtype=np.float64)
        pos_d, pos_r = np.mod(np.asarray(pos_d, dtype=np.float64), m), np.mod(np.asarray(pos_r, dtype=np.float64), n)
        if cell_d.size == 0 or pos_d.size == 0:
            return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
        import scipy.spatial  # imported when first needed: a faster start
        reach = np.array([gd + td + self.BOX_REACH, gr + tr + self.BOX_REACH], dtype=np.float64)
        box = np.array([m, n], dtype=np.float64) / reach
        cells = scipy.spatial.cKDTree(np.mod(np.stack([cell_d, cell_r], axis=1) / reach, box), boxsize=box)
        targets = scipy.spatial.cKDTree(np.stack([pos_d, pos_r], axis=1) / reach % box, boxsize=box)
        pairs = cells.sparse_distance_matrix(targets, 1.0, p=np.inf, output_type="ndarray")
        return pairs["i"].astype(np.intp), pairs["j"].astype(np.intp)

    def ring_interference(self, cell_d: np.ndarray, cell_r: np.ndarray, pos_d: np.ndarray, pos_r: np.ndarray,
                          energy: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
        """Signal energy (over σ², summed over channels) that targets put into each test cell's training ring.

        A target of on-bin windowed energy E at (pos_d, pos_r) bins puts E·K_d(b − pos_d)·K_r(a − pos_r) into
        the cell (b, a), K the window's power response relative to its peak (main lobe and sidelobes). The
        ring of a cell is the box ±(guard + train) less the box ±guard, so its sum is a difference of two
        separable box sums, tabulated once per window. This is what masks a weak target beside a strong one
        (or beside a row of guardrail posts on the stationary Doppler line) in the CA-CFAR of the signal chain.

        Parameters
        ----------
        cell_d, cell_r : int arrays, shape (C,)
            The test cells (Doppler, range bins).
        pos_d, pos_r, energy : arrays, shape (T,)
            The targets' positions (bins, any real value) and on-bin windowed energies.
        shape : (doppler bins, range bins) of the map; both axes are taken as circular.

        Returns
        -------
        array, shape (C,)
        """
        (gd, gr), (td, tr) = self.cfar.guard, self.cfar.train
        m, n = shape
        cell_d, cell_r = np.asarray(cell_d, dtype=np.float64), np.asarray(cell_r, dtype=np.float64)
        pos_d, pos_r = np.mod(np.asarray(pos_d, dtype=np.float64), m), np.mod(np.asarray(pos_r, dtype=np.float64), n)
        energy = np.asarray(energy, dtype=np.float64)
        out = np.zeros(cell_d.size)
        if cell_d.size == 0 or pos_d.size == 0:
            return out
        i, j = self.cell_pairs(cell_d, cell_r, pos_d, pos_r, shape)
        if i.size == 0:
            return out
        dd = np.mod(pos_d[j] - cell_d[i] + m / 2.0, m) - m / 2.0
        dr = np.mod(pos_r[j] - cell_r[i] + n / 2.0, n) - n / 2.0
        return np.bincount(i, weights=self.ring_kernel(dd, dr, cell_r[i], n) * energy[j], minlength=cell_d.size)

    def ring_kernel(self, delta_d: np.ndarray, delta_r: np.ndarray, cell_r: np.ndarray | None = None,
                    n_range: int | None = None) -> np.ndarray:
        """The share of a target's on-bin energy in the training ring of a cell ``delta`` bins from it (any
        shape): the box ±(guard + train) less the box ±guard, each a product of two tabulated sums. With the
        cells' range bins ``cell_r`` (integers, the shape of ``delta_r``) and the map's ``n_range``, a ring that
        the first or last range bins cut holds only its cells inside the map, as the chain's CA-CFAR has it
        (:meth:`ring_cut`); elsewhere the result is the same."""
        d_outer, d_inner = self._ring_boxes("d", delta_d)
        r_outer, r_inner = self._ring_boxes("r", delta_r)
        if cell_r is not None:
            g, t = self._guard_train("r")
            cell_r = np.broadcast_to(np.asarray(cell_r, dtype=np.float64), np.shape(r_outer))
            edge = (cell_r < g + t) | (cell_r > n_range - 1 - (g + t))
            if np.any(edge):
                r_outer, r_inner = r_outer.copy(), r_inner.copy()
                dr, a = np.broadcast_to(delta_r, edge.shape)[edge], cell_r[edge]
                r_outer[edge] = self._cut_box(g + t, dr, a, n_range)
                r_inner[edge] = self._cut_box(g, dr, a, n_range)
        return d_outer * r_outer - d_inner * r_inner

    def _cut_box(self, half: int, delta: np.ndarray, cell: np.ndarray, n_range: int) -> np.ndarray:
        """Σ K_r(a − δ) over the range offsets a in [−half, half] whose bins cell + a lie in [0, n_range): the
        box sum of a ring's range axis where an edge of the map cuts it, from the cumulative table
        C(x) = Σ_{j≥0} K_r(x − j) as C(hi − δ) − C(lo − 1 − δ)."""
        lo = np.maximum(-half, -cell)
        hi = np.minimum(half, n_range - 1 - cell)
        grid, table, total = self._cumulative_range()
        c_hi = np.interp(hi - delta, grid, table, left=0.0, right=total)
        c_lo = np.interp(lo - 1.0 - delta, grid, table, left=0.0, right=total)
        return np.where(hi >= lo, c_hi - c_lo, 0.0)

    def _cumulative_range(self) -> tuple[np.ndarray, np.ndarray, float]:
        """The grid (1/32 bin), the table of C(x) = Σ_{j≥0} K_r(x − j) on it, and C's limit far above it (the
        sum of K_r over every bin, N·Σw²/(Σw)² by Parseval); C is below 1e-7 of that limit under the grid."""
        tables = self.__dict__.setdefault("_ring_tables_cut", {})
        if "r" not in tables:
            g, t = self._guard_train("r")
            top = 2 * (g + t) + self.BOX_REACH + 2               # |hi − δ|, |lo − 1 − δ| never beyond this
            low = top + self.BOX_REACH                           # K_r(x − j) below the grid is negligible
            x = np.arange(-low * 32, top * 32 + 1) / 32.0
            k = straddle_gain(self.range_window, x)
            # C at x sums K at x, x − 1, x − 2, …: a cumulative sum along each residue of the grid modulo one bin
            c = np.empty_like(k)
            for res in range(32):
                c[res::32] = np.cumsum(k[res::32])
            w = self.range_window
            total = float(w.size * np.sum(w * w) / w.sum() ** 2)
            keep = x >= -top
            tables["r"] = (x[keep], c[keep], total)
        return tables["r"]

    def _guard_train(self, axis: str) -> tuple[int, int]:
        """The CFAR's guard and training cells along one axis ("d": Doppler, "r": range)."""
        k = 0 if axis == "d" else 1
        return self.cfar.guard[k], self.cfar.train[k]

    def _ring_boxes(self, axis: str, delta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The outer (±(guard + train)) and inner (±guard) box sums of one axis at ``delta``: :meth:`_box_sum`'s
        two tables on the outer one's grid (1/32 bin; the inner one zero beyond its own), each with its slope from
        one grid point to the next, read by index (linear interpolation). One index serves both boxes, without the
        binary search of a general interpolation on every pair of the ring sum (the detection level's costliest
        step). NaN in, NaN out."""
        tables = self.__dict__.setdefault("_ring_tables", {})
        if axis not in tables:
            g, t = self._guard_train(axis)
            grid = np.arange(-(g + t + self.BOX_REACH), g + t + self.BOX_REACH + 1e-9, 1.0 / 32.0)
            cols = []
            for half in (g + t, g):
                value = np.zeros(grid.size + 1)                    # one zero after the grid: "outside"
                value[:grid.size] = self._box_sum(axis, half, grid)
                slope = np.zeros(grid.size + 1)
                slope[:grid.size - 1] = np.diff(value[:grid.size])
                cols += [value, slope]
            tables[axis] = (float(grid[0]), grid.size, cols)
            self._table_built()
        x0, size, (v_out, s_out, v_in, s_in) = tables[axis]
        pos = (np.asarray(delta, dtype=np.float64) - x0) * 32.0
        outside = ~((pos >= 0.0) & (pos <= size - 1))           # beyond the tables (±inf, NaN): the zero entry
        cell = np.where(outside, size, np.floor(np.where(outside, 0.0, pos)))
        frac = np.where(outside, 0.0, pos - cell)
        i = cell.astype(np.intp)
        outer = np.take(v_out, i) + frac * np.take(s_out, i)
        inner = np.take(v_in, i) + frac * np.take(s_in, i)
        if np.any(outside):
            bad = np.isnan(pos)
            outer, inner = np.where(bad, np.nan, outer), np.where(bad, np.nan, inner)
        return outer, inner

    #: grids of :meth:`masking_factor`'s table: ρ in dB, interference over the noise's mean training sum (log10)
    MASK_RHO_DB = np.arange(-10.0, 80.001, 1.0)
    MASK_LOG_I = np.arange(-2.0, 7.001, 0.25)

    def _mask_table(self, swerling: int) -> np.ndarray:
        """:meth:`masking_factor`'s table over MASK_RHO_DB × MASK_LOG_I (built once per Swerling case)."""
        tables = self.__dict__.setdefault("_mask_tables", {})
        if swerling not in tables:
            mean_z = self.n_channels * self.eigenvalues.sum()
            rho, log_i = np.meshgrid(self.MASK_RHO_DB, self.MASK_LOG_I, indexing="ij")
            with_i = self.pd_interfered(rho, 10.0 ** log_i * mean_z, swerling)
            without = self.pd_interfered(self.MASK_RHO_DB, np.zeros(self.MASK_RHO_DB.size), swerling)
            tables[swerling] = np.clip(with_i / np.maximum(without, 1e-300)[:, None], 0.0, 1.0)
            self._table_built()
        return tables[swerling]

    def masking_factor(self, rho_db: np.ndarray, interference: np.ndarray, swerling: int = 1) -> np.ndarray:
        """Pd with ``interference`` in the training ring over Pd without (:meth:`pd_interfered`), from a table
        over ρ (1 dB) and log I (a quarter decade), interpolated bilinearly; 1 below 1 % of the noise's sum.
        ``rho_db`` and ``interference`` broadcast: a column of SNRs (K, 1) against rows of interference (K, X)
        reads the SNR's share of the table once a row (the same values as each repeated)."""
        mean_z = self.n_channels * self.eigenvalues.sum()
        rel = np.asarray(interference, dtype=np.float64) / mean_z
        if np.any(np.isnan(rel)):      # (a NaN compares false everywhere below: it had read as unmasked)
            raise ValueError("DetectionStatistic.masking_factor: interference holds a NaN; expected energies ≥ 0")
        if not np.any(rel >= 0.01):                  # nothing in any ring: the table is not even built
            return np.ones(np.broadcast(np.asarray(rho_db), rel).shape)
        table = self._mask_table(swerling)
        rho_db = np.asarray(rho_db, dtype=np.float64)
        # above the table's top SNR the noise counts for nothing beside the target and (where it masks at all) the
        # interference: the factor depends on their ratio alone, so both are taken down together to the top row
        # (clipping the SNR alone read a car 8 m ahead, at 88 dB, as masked by a neighbour its own strength)
        over = np.maximum(rho_db - self.MASK_RHO_DB[-1], 0.0)
        x = np.clip(rho_db - over, self.MASK_RHO_DB[0], self.MASK_RHO_DB[-1])
        y = np.clip(np.log10(np.maximum(rel, 1e-300)) - over / 10.0, self.MASK_LOG_I[0], self.MASK_LOG_I[-1])
        fx = (x - self.MASK_RHO_DB[0]) / (self.MASK_RHO_DB[1] - self.MASK_RHO_DB[0])
        fy = (y - self.MASK_LOG_I[0]) / (self.MASK_LOG_I[1] - self.MASK_LOG_I[0])
        i0 = np.minimum(np.floor(fx).astype(np.int64), table.shape[0] - 2)
        j0 = np.minimum(np.floor(fy).astype(np.int64), table.shape[1] - 2)
        ax, ay = fx - i0, fy - j0
        # the four corners by flat index into the table (one take each, not a 2-D fancy index), summed in place in
        # the order of (1 − a_x)(1 − a_y)·f₀₀ + a_x(1 − a_y)·f₁₀ + (1 − a_x)a_y·f₀₁ + a_x·a_y·f₁₁
        flat, row = table.ravel(), table.shape[1]
        at = i0 * row + j0
        bx, by = 1 - ax, 1 - ay
        f = bx * by
        f *= flat.take(at)
        for wx, wy, shift in ((ax, by, row), (bx, ay, 1), (ax, ay, row + 1)):
            term = wx * wy
            term *= flat.take(at + shift)
            f += term
        return np.where(rel < 0.01, 1.0, f)

    def pd_interfered(self, rho_db: np.ndarray, interference: np.ndarray, swerling: int = 1) -> np.ndarray:
        """Pd of targets of integrated SNR ``rho_db`` whose training ring holds ``interference`` (same shape; over
        σ², summed over channels): :meth:`pd_of_snr` with the threshold α·(Z + I)/N_T, the position within the
        cell averaged over 3 × 3 straddle points. CA-CFAR only (an order statistic ignores a few strong cells)."""
        rho_db = np.asarray(rho_db, dtype=np.float64)
        interference = np.asarray(interference, dtype=np.float64)
        if self.cfar.name != "ca":
            return self.pd_of_snr(rho_db, swerling)
        u = (np.arange(3) + 0.5) / 3 - 0.5
        g = (straddle_gain(self.range_window, u)[:, None] * straddle_gain(self.doppler_window, u)[None, :]).ravel()
        e = (10.0 ** (rho_db / 10.0) * self.window_gain)[..., None, None] * g                     # (..., 1, 9)
        eig = self.eigenvalues
        z = training_sum_quantiles(self.n_channels, eig)                                          # (Q,)
        t = (self.alpha_ca / eig.size) * (z[:, None] + interference.reshape(-1)[None, :])        # (Q, K)
        t = t.T.reshape(interference.shape + (z.size, 1))                                         # (..., Q, 1)
        sf = sf_swerling0 if swerling == 0 else sf_swerling1
        return sf(t, e, self.n_channels).mean(axis=(-2, -1))

    #: the box sums are tabulated to this many bins beyond the box (Hann sidelobes there are below −75 dB)
    BOX_REACH = 16

    def _box_sum(self, axis: str, half: int, delta: np.ndarray) -> np.ndarray:
        """Σ_{a=−half}^{half} K(a − δ), K the window's power response relative to on-bin; 0 far outside."""
        key = (axis, half)
        tables = self.__dict__.setdefault("_box_tables", {})
        if key not in tables:
            w = self.doppler_window if axis == "d" else self.range_window
            span = half + self.BOX_REACH
            grid = np.arange(-span, span + 1e-9, 1.0 / 32.0)
            a = np.arange(-half, half + 1)
            reach = 2 * half + self.BOX_REACH                       # |a − δ| never exceeds this
            k = straddle_gain(w, np.arange(-reach, reach + 1e-9, 1.0 / 32.0))
            idx = np.rint((a[None, :] - grid[:, None] + reach) * 32.0).astype(np.int64)
            tables[key] = (grid, k[idx].sum(axis=1))
        grid, table = tables[key]
        return np.interp(delta, grid, table, left=0.0, right=0.0)

    #: reach of :meth:`response`'s table, bins: the main lobe (±2 for Hann) and the first sidelobes
    RESPONSE_REACH = 4.0
    #: grid points of :meth:`response`'s table per bin
    RESPONSE_PER_BIN = 64

    def response(self, axis: str, delta: np.ndarray) -> np.ndarray:
        """The amplitude of a windowed tone δ bins from a cell, relative to on-bin, along one axis ("d": Doppler,
        "r": range), with its sign and without the linear phase e^{−iπδ(L−1)/L} that every tone at δ carries (so
        two tones' cross-term in a cell is the product of their two values): real, its square the power response
        K(δ). Tabulated within ±:data:`RESPONSE_REACH` with :data:`RESPONSE_PER_BIN` points a bin (interpolation
        error below 1e-4 of the peak), 0 beyond; a NaN δ gives NaN."""
        tables = self.__dict__.setdefault("_response_tables", {})
        if axis not in tables:
            w = self.doppler_window if axis == "d" else self.range_window
            grid = self._response_grid()
            n = np.arange(w.size)
            resp = (np.exp(2j * np.pi * np.outer(grid, n - (w.size - 1) / 2.0) / w.size) @ w).real / w.sum()
            tables[axis] = self._response_table(grid, resp)
            self._table_built()           # (a disk cache keeps it: 2–7 ms an axis at every start)
        grid, table, slope = tables[axis]
        delta = np.asarray(delta, dtype=np.float64)
        if delta.size < 512:            # a few hundred values: np.interp's one call is cheaper than the passes below
            return np.interp(delta, grid, table, left=0.0, right=0.0)
        inside = (delta >= -self.RESPONSE_REACH) & (delta <= self.RESPONSE_REACH)
        pos = (delta + self.RESPONSE_REACH) * self.RESPONSE_PER_BIN      # grid cells from the start
        if inside.all():                # (no NaN either): the same values without the passes that mask
            cell = pos.astype(np.intp)
            return table[cell] + slope[cell] * (pos - cell)
        lost = np.isnan(pos)            # a NaN δ stays NaN, as np.interp keeps it
        pos = np.where(inside, pos, 0.0)
        cell = pos.astype(np.intp)
        out = np.where(inside, table[cell] + slope[cell] * (pos - cell), 0.0)
        if lost.any():
            out[lost] = np.nan
        return out

    def _response_grid(self) -> np.ndarray:
        """The offsets (bins) of :meth:`response`'s table."""
        return np.arange(-self.RESPONSE_REACH, self.RESPONSE_REACH + 1e-9, 1.0 / self.RESPONSE_PER_BIN)

    @staticmethod
    def _response_table(grid: np.ndarray, resp: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`response`'s table of ``resp`` on ``grid``, with each point's slope to the next: the grid is uniform,
        a lookup by index, not np.interp's search (the lobe test looks up thousands of pairs a frame: 7–10× faster
        there); the last point's slope 0, so that it needs no cell after it."""
        return grid, resp, np.append(np.diff(resp), 0.0)

    # --- the tables, for a cache outside this module ----------------------------------------------------------

    #: the version of the tables' layout: a cache keyed on :meth:`table_key` holds tables of this layout
    TABLE_LAYOUT = 1

    def table_key(self) -> bytes:
        """Everything the tables are computed from: the CFAR's kind, threshold factor and training eigenvalues,
        the channel count, both windows and the tables' grids (bytes; a cache adds the code's own version)."""
        parts = [self.cfar.name.encode(), repr((self.TABLE_LAYOUT, self.n_channels, float(self.alpha_ca),
                                                tuple(self.cfar.guard), tuple(self.cfar.train),
                                                self.STRADDLE_POINTS, self.BOX_REACH)).encode()]
        for a in (self.eigenvalues, self.range_window, self.doppler_window, self.MASK_RHO_DB, self.MASK_LOG_I):
            parts.append(np.ascontiguousarray(a, dtype=np.float64).tobytes())
        return b"|".join(parts)

    #: called with no argument after a table was built (a cache's way to keep it; None: nobody listens)
    on_table_built = None

    def _table_built(self) -> None:
        if self.on_table_built is not None:
            self.on_table_built()

    def export_tables(self) -> dict[str, np.ndarray]:
        """The tables built so far, as named arrays."""
        out = {}
        for swerling, (grid, table) in self._pd_tables.items():
            out[f"pd{swerling}_grid"], out[f"pd{swerling}"] = grid, table
        for swerling, table in self.__dict__.get("_mask_tables", {}).items():
            out[f"mask{swerling}"] = table
        for axis, (_, _, cols) in self.__dict__.get("_ring_tables", {}).items():
            out[f"ring_{axis}"] = np.stack(cols)
        for gain, (grid, table) in self._second_tables.items():      # pd_second_look's, one a gain
            out[f"second_{gain!r}_grid"], out[f"second_{gain!r}"] = grid, table
        for axis, (_, table, _) in self.__dict__.get("_response_tables", {}).items():
            out[f"response_{axis}"] = table
        cuts = self.__dict__.get("_cuts", {})
        if cuts:            # the rings the range edges cut: (key, α, mean, variance, count) a row
            out["ring_cuts"] = np.array([(float(k), *v) for k, v in sorted(cuts.items())], dtype=np.float64)
        return out

    def import_tables(self, arrays: dict[str, np.ndarray]) -> None:
        """Take tables that :meth:`export_tables` gave (for this :meth:`table_key`); raises ValueError, leaving
        this statistic as it was, where a name, shape or value is not what this statistic builds."""
        pd, mask, ring, cut, second, response = {}, {}, {}, {}, {}, {}
        for name, a in arrays.items():
            a = np.asarray(a)
            if a.dtype != np.float64 or not np.all(np.isfinite(a)):
                raise ValueError(f"table {name}: dtype {a.dtype} or a non-finite value; expected finite float64")
            if name in ("pd0", "pd1") and f"{name}_grid" in arrays:
                grid = np.asarray(arrays[f"{name}_grid"], dtype=np.float64)
                if a.ndim != 1 or grid.shape != a.shape or a.size < 2:
                    raise ValueError(f"table {name}: shape {a.shape} against its grid's {grid.shape}")
                if not (np.all(np.diff(grid) > 0) and np.all((a >= 0.0) & (a <= 1.0))):
                    raise ValueError(f"table {name}: a grid not increasing or a probability outside [0, 1]")
                pd[int(name[2])] = (grid, a)
            elif name.startswith("second_") and f"{name}_grid" in arrays:
                try:
                    gain = float(name[len("second_"):])
                except ValueError:
                    raise ValueError(f"table {name}: not a gain in its name") from None
                grid = np.asarray(arrays[f"{name}_grid"], dtype=np.float64)
                if a.ndim != 1 or grid.shape != a.shape or a.size < 2 or not math.isfinite(gain) \
                        or not np.all(np.diff(grid) > 0) or not np.all((a >= 0.0) & (a <= 1.0)):
                    raise ValueError(f"table {name}: shape {a.shape}, grid or a probability not allowed")
                second[round(gain, 9)] = (grid, a)
            elif name in ("mask0", "mask1"):
                if a.shape != (self.MASK_RHO_DB.size, self.MASK_LOG_I.size) or not np.all((a >= 0.0) & (a <= 1.0)):
                    raise ValueError(f"table {name}: shape {a.shape} or a factor outside [0, 1]; expected "
                                     f"{(self.MASK_RHO_DB.size, self.MASK_LOG_I.size)}")
                mask[int(name[4])] = a
            elif name in ("ring_d", "ring_r"):
                axis = name[-1]
                g, t = self._guard_train(axis)
                size = 64 * (g + t + self.BOX_REACH) + 1
                if a.shape != (4, size + 1):
                    raise ValueError(f"table {name}: shape {a.shape}; expected {(4, size + 1)}")
                ring[axis] = (-float(g + t + self.BOX_REACH), size, list(a))
            elif name == "ring_cuts":
                reach = self.cfar.guard[1] + self.cfar.train[1]
                if a.ndim != 2 or a.shape[1] != 5 or np.any(a[:, 0] != np.rint(a[:, 0])) \
                        or np.any((a[:, 0] < 0) | (a[:, 0] >= (reach + 1) ** 2)) or np.any(a[:, 1:] <= 0.0):
                    raise ValueError(f"table {name}: shape {a.shape} or a cut or value not allowed; expected (k, 5) "
                                     f"with cut keys in 0..{(reach + 1) ** 2 - 1} and positive values")
                cut = {int(row[0]): tuple(float(v) for v in row[1:]) for row in a}
            elif name in ("response_d", "response_r"):
                grid = self._response_grid()
                if a.shape != grid.shape or not np.all(np.abs(a) <= 1.0 + 1e-9):
                    raise ValueError(f"table {name}: shape {a.shape} or an amplitude beyond 1; expected {grid.shape}")
                response[name[-1]] = self._response_table(grid, a)
            elif not name.endswith("_grid"):
                raise ValueError(f"table {name}: not a table this statistic builds")
        self._pd_tables.update(pd)
        self._second_tables.update(second)
        self.__dict__.setdefault("_mask_tables", {}).update(mask)
        self.__dict__.setdefault("_ring_tables", {}).update(ring)
        self.__dict__.setdefault("_cuts", {}).update(cut)
        self.__dict__.setdefault("_response_tables", {}).update(response)

    def threshold_mean(self) -> float:
        """The mean threshold in units of σ²: α·E[Z]/N_T."""
        return float(self.alpha_ca * self.n_channels * self.eigenvalues.sum() / self.eigenvalues.size)

    def noise_floor(self, power: np.ndarray) -> float:
        """Per-channel noise σ² of a power map, unbiased: its median over the median of Gamma(N, 1)."""
        import scipy.special  # imported when first needed: a faster start (cached tables need none)
        med = float(np.median(power))
        return max(med / float(scipy.special.gammaincinv(self.n_channels, 0.5)), np.finfo(np.float64).tiny)
