"""Seed 001 as array-level signal models: two incoherent corner radars, per-radar beam scanning and Capon, the
two-circle intersection and LC-ACM (the two-channel auto-compensator over both radars), batched over trials.

Geometry (seed 001, fig. 1, eq. 4–5): the radars' phase centres are at ``C1 = (−b/2, 0)`` and ``C2 = (+b/2, 0)``
on the bumper, ``b`` the baseline (1.46 m); ``y`` points forward, the targets lie at ``y > 0``. An azimuth is
measured from ``+y`` towards ``+x`` (towards radar 2): ``azimuth = atan2(x, y)``. This is the paper's frame, not
the sensor frame of DESIGN.md (there azimuth is positive to the left); the Monte Carlo compares angles, so only
the consistency matters. Radar ``k`` is turned by ``yaw_k`` (seed 001: each turned 45°; outwards here — the
paper gives no direction, corner radars look outwards — radar 1 by −45°, radar 2 by +45°); a point at azimuth
``ψ_k`` seen from ``C_k`` is at the local angle ``θ_k = ψ_k − yaw_k``, ``u_k = sin θ_k``.

Array (seed 001, eq. 1): ``N`` isotropic elements at ``d`` wavelengths, phase centre in the middle of the
aperture: ``a_p(u) = exp(j·2π·d·(p − (N+1)/2)·u)``, ``p = 1 … N`` (the printed eq. 1 has a bracket misplaced;
the text says the phase centre is the aperture's centre). With the centred phase ``a(−θ) = a(θ)*``.

Axis order: snapshots ``y[trial, element, snapshot]`` (T, N, K) — seed 001 uses one snapshot (K = 1) per radar;
ranges ``r[trial]``; estimates ``[trial, source]`` with the strongest peak first.

LC-ACM (eq. 3, 6–10), with the choices where the paper is silent (README, "Seed 001"):

1. *Transform (eq. 3)*: ``z_k = diag(a(−θ_k))·y_k`` moves the pair's "centre of mass" to broadside of radar
   ``k``. The paper takes ``θ_k`` from the radar's scan; it also writes the final answer as ``φ + θ̂`` with
   ``φ`` the direction of the two-circle point — the two agree only if the transform is centred on that same
   point. ``centre="circle"`` (default) centres each radar on the local angle of the two-circle point, so
   ``φ`` and ``θ̂`` share their zero; ``centre="scan"`` is the literal reading (centre on each radar's
   beam-scan peak, then add ``φ``).
2. *Data* ``Z = [z_1, z_2]`` (N × 2K), spatially smoothed (sub-arrays of ``Q = round(0.7·N)``, 8 for N = 12): every
   sub-array of every radar's every snapshot is one sample, ``S = 2·(N − Q + 1)·K`` samples of length Q. No
   sample ever mixes the two radars, so no coherence between them is needed.
3. *Auto-compensator (eq. 7–9)*: for a look direction ``u`` (in the transformed, sine domain) the main channel
   is the sub-array beam ``x0 = a_Q(u)ᴴ z / Q``; the paper does not say what feeds the two auxiliary channels.
   Here they are the two adjacent orthogonal beams ``x1,2 = a_Q(u ∓ 1/(Q·d))ᴴ z / Q``: each has a null at
   ``u``, so a source in the look direction passes undistorted while the compensator cancels the rest — the
   minimum output power over (c1, c2) is then Capon's spectrum restricted to the three beams, "a practical
   implementation of Capon's method with a two-channel auto-compensator". The weights are the Wiener
   solution; eq. 9 as printed repeats ``⟨x0 x2*⟩`` in its first term, a typo (it must be ``⟨x0 x1*⟩⟨x1 x2*⟩``,
   the 2 × 2 normal equations whose first row eq. 8 solves); :func:`acm_weights` uses the corrected form.
4. *Peaks (eq. 6)*: local maxima of ``⟨|y(u)|²⟩`` over ``|u| < 1/(Q·d)`` (the span between the auxiliary beams),
   within ``floor_db`` of the strongest, count as targets.
5. *Angle (eq. 10)*: ``θ = φ + θ̂``. An offset ``Δ`` in azimuth appears in radar ``k``'s sine domain as
   ``cos θ_k·Δ``; ``offset="angle"`` (default) converts the peak ``u'`` back as ``Δ = arcsin(u') / c̄``,
   ``c̄ = ½(cos θ_1 + cos θ_2)`` at the centres; ``offset="sine"`` adds ``arcsin(u')`` as eq. 10 is printed,
   which shrinks every offset — and its noise — by ``c̄`` (≈ 0.65 at the 45° mounts).

Never NaN: the two-circle point is clipped to ``y ≥ 0`` when noisy ranges do not intersect (flagged), spectra
are clipped away from zero before any logarithm, the 2 × 2 determinant away from zero, and every estimate that
is not a peak is flagged ``False`` with a finite angle.

References
----------
Artyukhin, Flaksman, Rubtsov, "Investigation of efficiency of DoA algorithm ... distributed system of
incoherent radars", Radiotekhnika i Elektronika 2024 (seed 001), eq. 1–14, Table 2.
Widrow & Stearns, Adaptive Signal Processing, 1985 (the auto-compensator, Wiener weights).
Shan, Wax & Kailath 1985 (spatial smoothing).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from radarnode.dsp.subspace import default_subarray
from radarnode.errors import ConfigError

#: seed 001: the radars 1.46 m apart on the bumper, each turned 45° (outwards)
SEED001_BASELINE_M = 1.46
SEED001_YAW_DEG = 45.0
#: one rule for every spectrum: a peak within 10 dB of the strongest is a target (a uniform aperture's first
#: sidelobe is −13.3 dB). radarnode.dsp.subspace allows Capon 20 dB; with one snapshot and Q = 8 that counts
#: noise ripples: at 15 dB Capon found exactly one of one target in 28 % of trials at 20 dB, 82 % at 10 dB
FLOOR_DB_SCAN = 10.0
FLOOR_DB_CAPON = 10.0
FLOOR_DB_ACM = 10.0
#: coarse grid points over the visible region u ∈ [−1, 1) (d = ½: one period) for the full-array scans
SCAN_GRID = 1024
CAPON_GRID = 512
#: coarse grid points across the compensator's window |u'| < 1/(Q·d)
ACM_GRID = 129
#: fine points on each side of a coarse peak; the refinement spans ± one coarse step
REFINE_HALF = 4
_TINY = 1e-300


@dataclass(frozen=True)
class PairGeometry:
    """Two radars on a baseline, each turned outwards (seed 001).

    baseline_m : distance between the phase centres, m (> 0).
    yaw_rad : (radar 1, radar 2) boresight azimuths, rad, in (−π/2, π/2).
    """

    baseline_m: float = SEED001_BASELINE_M
    yaw_rad: tuple[float, float] = (-math.radians(SEED001_YAW_DEG), math.radians(SEED001_YAW_DEG))

    def __post_init__(self) -> None:
        if not (isinstance(self.baseline_m, (int, float)) and math.isfinite(self.baseline_m) and self.baseline_m > 0):
            raise ConfigError(f"lcacm baseline_m: value {self.baseline_m!r} is not allowed; expected a finite "
                              "distance > 0 m")
        if (len(self.yaw_rad) != 2 or not all(isinstance(v, (int, float)) and math.isfinite(v)
                                              and abs(v) < math.pi / 2 for v in self.yaw_rad)):
            raise ConfigError(f"lcacm yaw_rad: value {self.yaw_rad!r} is not allowed; expected two finite "
                              "angles in (−π/2, π/2) rad")

    @property
    def positions_m(self) -> np.ndarray:
        """(2,) x of the phase centres, m (y = 0)."""
        return np.array([-0.5 * self.baseline_m, 0.5 * self.baseline_m])


# ---------------------------------------------------------------------------------------------------------
# geometry

def polar_to_xy(range_m: np.ndarray, azimuth_rad: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points at ``range_m`` and ``azimuth_rad`` from the origin (mid-baseline): ``(x_m, y_m)``, broadcast."""
    r = np.asarray(range_m, dtype=float)
    a = np.asarray(azimuth_rad, dtype=float)
    return r * np.sin(a), r * np.cos(a)


def seen_from(x_m: np.ndarray, y_m: np.ndarray, geometry: PairGeometry) -> tuple[np.ndarray, np.ndarray]:
    """Range and local angle of points from each radar: ``(range_m, theta_rad)``, each shape ``(2, *x.shape)``."""
    x = np.asarray(x_m, dtype=float)
    y = np.asarray(y_m, dtype=float)
    cx = geometry.positions_m.reshape((2,) + (1,) * x.ndim)
    yaw = np.asarray(geometry.yaw_rad).reshape((2,) + (1,) * x.ndim)
    dx = x[None] - cx
    return np.hypot(dx, y[None]), np.arctan2(dx, y[None]) - yaw


def two_circle_intersection(r1_m: np.ndarray, r2_m: np.ndarray,
                            baseline_m: float = SEED001_BASELINE_M) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The point at range ``r1_m`` from ``(−b/2, 0)`` and ``r2_m`` from ``(+b/2, 0)``, in ``y ≥ 0`` (seed 001 eq. 4–5).

    ``x = (r1² − r2²) / (2b)``, ``y = √(r1² − (x + b/2)²)``. Arrays broadcast.

    Returns
    -------
    x_m, y_m : the point, m; where the circles do not meet (noisy ranges with ``|r1 − r2| > b`` or
        ``r1 + r2 < b``) ``y`` is clipped to 0 — the closest point of the baseline's line — never NaN.
    ok : bool, False where the circles do not meet.
    """
    r1 = np.asarray(r1_m, dtype=float)
    r2 = np.asarray(r2_m, dtype=float)
    b = float(baseline_m)
    x = (r1 * r1 - r2 * r2) / (2.0 * b)
    y2 = r1 * r1 - (x + 0.5 * b) ** 2
    ok = y2 >= 0.0
    return x, np.sqrt(np.maximum(y2, 0.0)), ok


# ---------------------------------------------------------------------------------------------------------
# array model

def steering(n: int, u: np.ndarray, d: float = 0.5) -> np.ndarray:
    """Centred steering vectors (eq. 1) ``exp(j·2π·d·(p − (N+1)/2)·u)``.

    ``u`` (G,) → (N, G); ``u`` (T, M) → (T, N, M): the element axis sits before the last axis of ``u``.
    """
    u = np.asarray(u, dtype=float)
    p = np.arange(n) - 0.5 * (n - 1)
    return np.exp(2j * np.pi * d * p[:, None] * u[..., None, :])


def snapshots(rng: np.random.Generator, theta_rad: np.ndarray, snr_db: float | np.ndarray, n: int,
              d: float = 0.5, k: int = 1) -> np.ndarray:
    """One radar's snapshots (seed 001 eq. 2): ``y = Σ_m a(θ_m) s_m + ξ``, batched over trials.

    Targets ``s_m ~ CN(0, ρ_m)`` independent over trials, targets and snapshots (seed 001: "a complex Gaussian
    process"), noise ``ξ ~ CN(0, I)``, so ``snr_db`` is the mean per-element, per-snapshot SNR ``ρ``.

    Parameters
    ----------
    theta_rad : (T, J) local angles of the J targets in each trial.
    snr_db : scalar or (J,).

    Returns
    -------
    (T, N, K) complex128.
    """
    theta = np.atleast_2d(np.asarray(theta_rad, dtype=float))
    t, j = theta.shape
    amp = np.broadcast_to(10.0 ** (np.asarray(snr_db, dtype=float) / 20.0), (j,))
    a = steering(n, np.sin(theta), d)                                           # (T, N, J)
    s = (rng.standard_normal((t, j, k)) + 1j * rng.standard_normal((t, j, k))) * (amp[None, :, None] / math.sqrt(2.0))
    w = (rng.standard_normal((t, n, k)) + 1j * rng.standard_normal((t, n, k))) / math.sqrt(2.0)
    return a @ s + w


def derotate(y: np.ndarray, u_centre: np.ndarray, d: float = 0.5) -> np.ndarray:
    """Eq. 3: ``z = diag(a(−θ))·y`` — the direction ``u_centre = sin θ`` moved to broadside.

    ``y`` (T, N, K), ``u_centre`` (T,) → (T, N, K).
    """
    n = y.shape[-2]
    g = steering(n, -np.asarray(u_centre, dtype=float)[:, None], d)           # (T, N, 1)
    return g * y


def subarray_samples(y: np.ndarray, q: int) -> np.ndarray:
    """Forward spatial smoothing as samples: (T, N, K) → (T, (N − Q + 1)·K, Q), sub-array by sub-array."""
    t, n, k = y.shape
    if not (isinstance(q, (int, np.integer)) and 2 <= q <= n):
        raise ConfigError(f"lcacm subarray: value {q!r} is not allowed; expected an integer 2 … {n} (N)")
    idx = np.arange(n - q + 1)[:, None] + np.arange(q)[None, :]                 # (L, Q)
    sub = y[:, idx, :]                                                          # (T, L, Q, K)
    return np.moveaxis(sub, 3, 2).reshape(t, (n - q + 1) * k, q)


# ---------------------------------------------------------------------------------------------------------
# batched peak search

_GRID_STEERING: dict = {}


def _conj_steering(n: int, u: np.ndarray, d: float, grid: np.ndarray | None, shift: float = 0.0) -> np.ndarray:
    """``conj(a(u + shift))``: (N, G) for the coarse ``grid`` itself (computed once per grid, cached), else (T, N, M)
    for per-trial points. A uniform grid is known by its size and end points (not by ``id``, which a new array may
    reuse once the old one is gone)."""
    if grid is not None and u is grid:
        key = (n, float(d), grid.size, float(grid[0]), float(grid[-1]), float(shift))
        a = _GRID_STEERING.get(key)
        if a is None:
            a = np.ascontiguousarray(np.conj(steering(n, grid + shift, d)))
            a.setflags(write=False)
            _GRID_STEERING[key] = a
        return a
    return np.conj(steering(n, np.asarray(u, dtype=float) + shift, d))

@functools.lru_cache(maxsize=16)
def _uniform_grid(n_grid: int, lo: float, hi: float, circular: bool) -> np.ndarray:
    g = lo + (hi - lo) * np.arange(n_grid) / n_grid if circular else np.linspace(lo, hi, n_grid)
    g.setflags(write=False)
    return g


def _search(power, grid: np.ndarray, n_max: int, floor_db: float, circular: bool,
            lo: float, hi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Up to ``n_max`` peaks of ``power`` per trial, strongest first, refined on a fine grid and a parabola.

    ``power(u)``: ``u`` (G,) shared → (T, G); ``u`` (T, M) per trial → (T, M); non-negative. Peaks are strict
    local maxima (circular on a periodic grid; the window's end points are never peaks) within ``floor_db``
    of the trial's strongest. Returns ``u (T, n_max)``, ``power (T, n_max)``, ``ok (T, n_max)``; an entry that
    is not a peak repeats the strongest (or 0) with ``ok`` False.
    """
    p = power(grid)                                                             # (T, G)
    t, g = p.shape
    if circular:
        left, right = np.roll(p, 1, axis=1), np.roll(p, -1, axis=1)
    else:
        edge = np.full((t, 1), np.inf)
        left = np.concatenate((edge, p[:, :-1]), axis=1)
        right = np.concatenate((p[:, 1:], edge), axis=1)
    best = p.max(axis=1, keepdims=True)
    peak = (p > left) & (p >= right) & (p >= best * 10.0 ** (-floor_db / 10.0)) & (p > 0.0)
    score = np.where(peak, p, -1.0)
    idx = np.argsort(-score, axis=1, kind="stable")[:, :n_max]                  # (T, n_max)
    ok = np.take_along_axis(score, idx, axis=1) > 0.0
    # refinement: 2·REFINE_HALF + 1 points over ± one coarse step, parabola through the best three (log power)
    step = float(grid[1] - grid[0])
    offs = np.linspace(-step, step, 2 * REFINE_HALF + 1)
    uf = grid[idx][..., None] + offs                                            # (T, n_max, F)
    pf = power(uf.reshape(t, -1)).reshape(uf.shape)
    lf = np.log(np.maximum(pf, _TINY))
    i = np.minimum(np.maximum(lf.argmax(axis=2), 1), offs.size - 2)
    l0, l1, l2 = (np.take_along_axis(lf, (i + s)[..., None], axis=2)[..., 0] for s in (-1, 0, 1))
    den = l0 - 2.0 * l1 + l2
    conc = den < 0.0
    shift = np.minimum(np.maximum(0.5 * (l0 - l2) / np.where(conc, den, -1.0), -1.0), 1.0) * conc
    u = np.take_along_axis(uf, i[..., None], axis=2)[..., 0] + shift * (offs[1] - offs[0])
    u = (u - lo) % (hi - lo) + lo if circular else np.minimum(np.maximum(u, lo), hi)
    pw = np.take_along_axis(pf, i[..., None], axis=2)[..., 0]
    # entries that are not peaks: a copy of the strongest, flagged
    u = np.where(ok, u, u[:, :1] * ok[:, :1])
    pw = np.where(ok, pw, 0.0)
    return u, pw, ok


def _check(y: np.ndarray, name: str = "y") -> np.ndarray:
    y = np.asarray(y)
    if y.ndim != 3 or y.shape[1] < 2 or y.shape[2] < 1 or y.shape[0] < 1:
        raise ConfigError(f"lcacm {name}: shape {y.shape} is not allowed; expected (T, N, K) with T >= 1 trials, "
                          "N >= 2 elements, K >= 1 snapshots")
    if not np.all(np.isfinite(y)):
        raise ConfigError(f"lcacm {name}: a non-finite value (NaN or inf) is not allowed; expected finite samples")
    return y.astype(np.complex128, copy=False)


def _unit_scale(y: np.ndarray) -> np.ndarray:
    """Each trial scaled to unit peak magnitude (angles are scale invariant; keeps |y|² in range)."""
    peak = np.abs(y).max(axis=(1, 2), keepdims=True)
    return y / np.where(peak > 0.0, peak, 1.0)


# ---------------------------------------------------------------------------------------------------------
# single-radar estimators

def beam_scan(y: np.ndarray, n_max: int = 1, d: float = 0.5, floor_db: float = FLOOR_DB_SCAN,
              n_grid: int = SCAN_GRID) -> tuple[np.ndarray, np.ndarray]:
    """Beam scanning (seed 001's BS, Bartlett) on one radar: peaks of ``P(u) = Σ_k |a(u)ᴴ y_k|²``.

    ``y`` (T, N, K) → ``u (T, n_max)`` sin of the local angle, strongest first, and ``ok (T, n_max)``;
    ``ok.sum(axis=1)`` is the number of targets found.
    """
    y = _unit_scale(_check(y))
    n = y.shape[1]
    grid = _uniform_grid(n_grid, -1.0, 1.0, abs(2 * d - 1) < 1e-12)

    yt = np.ascontiguousarray(np.swapaxes(y, 1, 2))                             # (T, K, N)

    def power(u):
        b = yt @ _conj_steering(n, u, d, grid)                                  # (T, K, G): a(u)ᴴ y_k
        return np.einsum("tkg,tkg->tg", b, np.conj(b)).real

    u, _, ok = _search(power, grid, n_max, floor_db, abs(2 * d - 1) < 1e-12, -1.0, 1.0)
    return u, ok


def capon_scan(y: np.ndarray, n_max: int = 1, d: float = 0.5, q: int | None = None, loading: float = 1e-3,
               floor_db: float = FLOOR_DB_CAPON, n_grid: int = CAPON_GRID) -> tuple[np.ndarray, np.ndarray]:
    """Capon on one radar with spatial smoothing (seed 001: sub-arrays of Q ≈ 0.7·N for one snapshot).

    ``P(u) = 1 / (a_Q(u)ᴴ (R + δI)⁻¹ a_Q(u))``, ``R`` the smoothed Q × Q covariance, ``δ = loading·tr(R)/Q``;
    the inverse through ``eigh`` with eigenvalues clipped at ``1e-12·λ_max``. ``y`` (T, N, K) → ``u``, ``ok``
    (T, n_max) as :func:`beam_scan`.
    """
    y = _unit_scale(_check(y))
    t, n, _ = y.shape
    q = default_subarray(n) if q is None else q
    x = subarray_samples(y, q)                                                  # (T, S, Q)
    r = np.swapaxes(x, 1, 2) @ np.conj(x) / x.shape[1]                          # (T, Q, Q) = mean x xᴴ
    r = 0.5 * (r + np.conj(np.swapaxes(r, 1, 2)))
    w, v = np.linalg.eigh(r)
    w = w + loading * np.maximum(np.real(np.trace(r, axis1=1, axis2=2)), 0.0)[:, None] / q
    w = np.maximum(w, np.maximum(w[:, -1:], 0.0) * 1e-12 + _TINY)
    vsh = np.conj(np.swapaxes(v / np.sqrt(w)[:, None, :], 1, 2))               # R⁻¹ = vs·vsᴴ
    periodic = abs(2 * d - 1) < 1e-12
    grid = _uniform_grid(n_grid, -1.0, 1.0, periodic)

    def power(u):
        c = vsh @ np.conj(_conj_steering(q, u, d, grid))                        # (T, Q, G)
        return 1.0 / np.maximum(np.einsum("tqg,tqg->tg", c, np.conj(c)).real, _TINY)

    u, _, ok = _search(power, grid, n_max, floor_db, periodic, -1.0, 1.0)
    return u, ok


# ---------------------------------------------------------------------------------------------------------
# the two-channel auto-compensator

def acm_weights(m00: np.ndarray, m11: np.ndarray, m22: np.ndarray, m01: np.ndarray, m02: np.ndarray,
                m21: np.ndarray, loading: float = 1e-9) -> tuple[np.ndarray, np.ndarray]:
    """Weights of the two-channel auto-compensator (seed 001 eq. 8–9, Wiener solution; eq. 9 corrected).

    Moments over the samples: ``m11 = ⟨|x1|²⟩``, ``m22 = ⟨|x2|²⟩``, ``m01 = ⟨x0 x1*⟩``, ``m02 = ⟨x0 x2*⟩``,
    ``m21 = ⟨x2 x1*⟩`` (``m00`` unused, kept for the signature's symmetry). Minimising ``⟨|x0 + c1 x1 + c2 x2|²⟩``::

        c1 = (⟨x0x2*⟩⟨x2x1*⟩ − ⟨x0x1*⟩⟨|x2|²⟩) / (⟨|x1|²⟩⟨|x2|²⟩ − |⟨x2x1*⟩|²)     (eq. 8)
        c2 = (⟨x0x1*⟩⟨x1x2*⟩ − ⟨x0x2*⟩⟨|x1|²⟩) / (⟨|x1|²⟩⟨|x2|²⟩ − |⟨x1x2*⟩|²)     (eq. 9, corrected)

    ``⟨|x1|²⟩`` and ``⟨|x2|²⟩`` get a diagonal loading of ``loading`` times their mean: when both auxiliary
    channels see one and the same interferer and no noise, the determinant is 0 and eq. 8–9 are 0/0; the loaded
    solution is then the minimum-norm one, which still cancels it (``loading=0`` gives eq. 8–9 exactly). The
    determinant is clipped at a tiny positive value, so zero data gives zero weights, never NaN. Arrays broadcast.
    """
    delta = loading * 0.5 * (m11 + m22)
    m11, m22 = m11 + delta, m22 + delta
    det = np.maximum(m11 * m22 - np.abs(m21) ** 2, _TINY)
    c1 = (m02 * m21 - m01 * m22) / det
    c2 = (m01 * np.conj(m21) - m02 * m11) / det
    return c1, c2


def acm_spectrum(samples: np.ndarray, u: np.ndarray, d: float = 0.5, grid: np.ndarray | None = None) -> np.ndarray:
    """Output power ``⟨|y(u)|²⟩`` of the compensator (eq. 7) looking at ``u`` (transformed sine domain).

    ``samples`` (T, S, Q); ``u`` (G,) or (T, M) (``grid``: ``u`` is this coarse grid, whose steering is
    cached). Main channel ``x0 = a_Q(u)ᴴz/Q``, auxiliaries the orthogonal beams at ``u ∓ 1/(Q·d)`` (module
    docstring, choice 3). Returns (T, G) or (T, M), ≥ 0.
    """
    q = samples.shape[-1]
    delta = 1.0 / (q * d)
    u = np.asarray(u, dtype=float)
    # x_i (T, S, G) = samples @ conj(a_Q(u_i)) / Q
    x0, x1, x2 = (samples @ _conj_steering(q, u, d, grid, s) / q for s in (0.0, -delta, delta))

    def mean(a, b):
        return np.einsum("tsg,tsg->tg", a, np.conj(b)) / samples.shape[1]

    m11, m22 = mean(x1, x1).real, mean(x2, x2).real
    c1, c2 = acm_weights(None, m11, m22, mean(x0, x1), mean(x0, x2), mean(x2, x1))
    out = x0 + c1[:, None, :] * x1 + c2[:, None, :] * x2                     # eq. 7, y for every sample
    return np.einsum("tsg,tsg->tg", out, np.conj(out)).real / samples.shape[1]


@dataclass(frozen=True)
class LcacmEstimate:
    """LC-ACM result for a batch of trials (seed 001 eq. 10).

    azimuth_rad : (T, n_max) azimuths from the origin (mid-baseline), strongest compensator peak first.
    ok : (T, n_max) bool; ``ok.sum(axis=1)`` targets found; not-found entries repeat a found one.
    centre_azimuth_rad : (T,) φ, the direction of the two-circle point.
    circles_meet : (T,) bool, False where the measured ranges did not intersect (y clipped to 0).
    """

    azimuth_rad: np.ndarray
    ok: np.ndarray
    centre_azimuth_rad: np.ndarray
    circles_meet: np.ndarray

    @property
    def count(self) -> np.ndarray:
        return self.ok.sum(axis=1)


def lcacm(y1: np.ndarray, y2: np.ndarray, r1_m: np.ndarray, r2_m: np.ndarray,
          geometry: PairGeometry = PairGeometry(), *, n_max: int = 2, d: float = 0.5, q: int | None = None,
          centre: str = "circle", offset: str = "angle", floor_db: float = FLOOR_DB_ACM,
          n_grid: int = ACM_GRID) -> LcacmEstimate:
    """LC-ACM over two incoherent radars (seed 001 §1): scan, transform, combine, compensate, shift by φ.

    Parameters
    ----------
    y1, y2 : (T, N, K) snapshots of radar 1 and radar 2 (the same range–Doppler cell).
    r1_m, r2_m : (T,) ranges of that cell measured by each radar, m.
    geometry : baseline and mounts.
    n_max : most targets reported per trial.
    q : sub-array length (default ``round(0.7·N)``).
    centre : ``"circle"`` or ``"scan"`` — what eq. 3 centres each radar on (module docstring, choice 1).
    offset : ``"angle"`` or ``"sine"`` — how a compensator peak becomes an azimuth offset (choice 5).

    Returns
    -------
    LcacmEstimate with finite angles.
    """
    if centre not in ("circle", "scan"):
        raise ConfigError(f"lcacm centre: value {centre!r} is not allowed; expected one of circle, scan")
    if offset not in ("angle", "sine"):
        raise ConfigError(f"lcacm offset: value {offset!r} is not allowed; expected one of angle, sine")
    y1, y2 = _unit_scale(_check(y1, "y1")), _unit_scale(_check(y2, "y2"))
    if y1.shape != y2.shape:
        raise ConfigError(f"lcacm y2: shape {y2.shape} is not allowed; expected the shape of y1, {y1.shape}")
    n = y1.shape[1]
    q = default_subarray(n) if q is None else q
    r1 = np.broadcast_to(np.asarray(r1_m, dtype=float), (y1.shape[0],))
    r2 = np.broadcast_to(np.asarray(r2_m, dtype=float), (y1.shape[0],))
    if not (np.all(np.isfinite(r1)) and np.all(np.isfinite(r2)) and np.all(r1 > 0) and np.all(r2 > 0)):
        raise ConfigError("lcacm r1_m, r2_m: a non-finite or non-positive range is not allowed; expected ranges "
                          "> 0 m")
    x, yy, meet = two_circle_intersection(r1, r2, geometry.baseline_m)
    phi = np.arctan2(x, yy)
    _, theta_c = seen_from(x, yy, geometry)                                     # (2, T) local angles of the point
    if centre == "scan":
        u_c = np.stack([beam_scan(y, 1, d)[0][:, 0] for y in (y1, y2)])
        theta_c = np.arcsin(np.clip(u_c, -1.0, 1.0))
    else:
        u_c = np.sin(theta_c)
    z = [derotate(y, u_c[i], d) for i, y in enumerate((y1, y2))]
    samples = np.concatenate([subarray_samples(zi, q) for zi in z], axis=1)   # (T, 2·L·K, Q)
    half = 1.0 / (q * d)
    grid = _uniform_grid(n_grid, -half, half, False)
    u, _, ok = _search(lambda uu: acm_spectrum(samples, uu, d, grid), grid, n_max, floor_db, False, -half, half)
    off = np.arcsin(np.clip(u, -1.0, 1.0))
    if offset == "angle":
        off = off / np.maximum(0.5 * (np.cos(theta_c[0]) + np.cos(theta_c[1])), 1e-3)[:, None]
    return LcacmEstimate(phi[:, None] + off, ok, phi, meet)


__all__ = ["PairGeometry", "LcacmEstimate", "polar_to_xy", "seen_from", "two_circle_intersection", "steering",
           "snapshots", "derotate", "subarray_samples", "beam_scan", "capon_scan",
           "acm_weights", "acm_spectrum", "lcacm", "SEED001_BASELINE_M", "SEED001_YAW_DEG"]
