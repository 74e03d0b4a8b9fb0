"""Super-resolution direction of arrival over a uniform linear array, as pure array functions.

Array model: ``N`` elements at spacing ``d`` wavelengths; a plane wave from azimuth θ
(broadside 0) has element phase ``+2π·d·k·u``, ``u = sin θ``, ``k = 0 … N-1`` — the same
convention as :mod:`radarnode.dsp.doa`. Every estimator returns **sin θ** (dimensionless,
ascending); degrees only at the edges (:attr:`SubspaceEstimate.azimuth_deg`).

Axis order: snapshots ``X`` have shape ``(..., N, K)`` — elements, then snapshots (``K`` may
be 1); covariances have shape ``(..., N, N)``. The covariance helpers broadcast over leading
batch axes; the estimators take one covariance ``(N, N)`` each.

Pipeline of :func:`estimate`: validate → scale to unit peak magnitude when the peak lies outside
1e±100 (angles are scale invariant; this keeps 1e±300 inputs finite) → sample covariance → optional spatial smoothing
(sub-arrays of length ``Q``, default ``round(0.7·N)`` as seed 001) → optional forward–backward
averaging → source count (given, or MDL) → estimator.

Never NaN, never a linear-algebra exception: every estimator works from the eigenvectors of a
Hermitian matrix (LAPACK ``?heevr``, numpy's ``eigh`` as its fallback) or the eigenvalues of a
general one (``?geev``, ``np.roots`` as the fallback) or ``pinv``, clips eigenvalues and
spectra away from zero, and :func:`estimate` turns any remaining ``LinAlgError`` into an
explicit "not resolved" result with finite angles. The steps of the pipeline are fused where
that saves calls (cost: the section on steering below), always the same matrices.

References
----------
Schmidt, "Multiple emitter location and signal parameter estimation", IEEE TAP 1986 (MUSIC).
Huarng & Yeh, "A unitary transformation method for angle-of-arrival estimation", IEEE TSP 1991;
seed 004 (U-MUSIC). Barabell 1983 (root-MUSIC). Roy & Kailath 1989 (ESPRIT, TLS).
Shan, Wax & Kailath 1985 (spatial smoothing). Wax & Kailath 1985 (MDL/AIC).
Stoica & Nehorai, "Performance study of conditional and unconditional DOA estimation", IEEE
TASSP 1990 (stochastic CRB, :func:`crb_sin`).
"""

from __future__ import annotations

import cmath
import functools
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.linalg import blas as _blas
from scipy.linalg import lapack as _lapack

from radarnode.errors import ConfigError

#: spectrum peaks more than this far below the strongest are not counted as sources (dB); a uniform
#: aperture's first sidelobe is −13.3 dB, so beam scanning needs less than that
DEFAULT_FLOOR_DB = {"bartlett": 10.0, "capon": 20.0, "music": 20.0, "unitary_music": 20.0}
#: a MUSIC peak whose null spectrum ‖Enᴴa‖² is below this fraction of ‖a‖² = N counts whatever its height
#: relative to the strongest (a steering vector in a random M-dim subspace has ≈ 1 − M/N there)
MUSIC_ACCEPT = 0.5
#: dtypes compared by identity on the fast paths (numpy's built-in descriptors are singletons)
_COMPLEX128 = np.dtype(np.complex128)
_FLOAT64 = np.dtype(np.float64)
_BOOL = np.dtype(bool)
#: coarse grid points per unit of sin θ per element (≥ 256 points over [-1, 1])
GRID_PER_ELEMENT = 16
#: fine-grid points on each side of a coarse peak in the local refinement
REFINE_HALF = 4


def _takes_in_order(fn: object, head: str) -> bool:
    """Whether scipy's f2py wrapper ``fn`` documents its signature as beginning with ``head`` (the first line of its
    docstring, spaces removed)."""
    doc = getattr(fn, "__doc__", None) or ""
    return doc.split("\n", 1)[0].replace(" ", "").startswith(head)


#: f2py parses keyword arguments at a cost (≈ 0.3–0.5 µs a call measured alone, about twice that within an
#: estimate), so this module's BLAS/LAPACK calls pass them by position — the values the keywords had, or the
#: wrappers' documented defaults — when the installed scipy documents that order, and by name otherwise
_POSITIONAL = all(_takes_in_order(getattr(module, name, None), head) for module, name, head in (
    (_blas, "zgemm", "c=zgemm(alpha,a,b,[beta,c,trans_a,trans_b,overwrite_c]"),
    (_lapack, "zheevr", "w,z,m,isuppz,info=zheevr(a,[compute_v,range,lower,vl,vu,il,iu,"),
    (_lapack, "dsyevr", "w,z,m,isuppz,info=dsyevr(a,[compute_v,range,lower,vl,vu,il,iu,"),
    (_lapack, "zheev", "w,v,info=zheev(a,[compute_v,lower,"),
    (_lapack, "dsyev", "w,v,info=dsyev(a,[compute_v,lower,"),
    (_lapack, "dgeev", "wr,wi,vl,vr,info=dgeev(a,[compute_vl,compute_vr,lwork,overwrite_a]"),
))


# ---------------------------------------------------------------------------------------------
# covariance preprocessing (broadcast over leading axes)

def sample_covariance(x: np.ndarray) -> np.ndarray:
    """Sample covariance ``X·Xᴴ / K``: snapshots ``(..., N, K)`` → ``(..., N, N)`` complex."""
    x = np.asarray(x)
    return (x @ np.conj(np.swapaxes(x, -1, -2))) / x.shape[-1]


def forward_backward(r: np.ndarray) -> np.ndarray:
    """Forward–backward average ``(R + J·R*·J) / 2``: ``(..., N, N)`` → ``(..., N, N)``.

    ``J`` is the exchange matrix; for a centro-symmetric array this doubles the snapshots and
    decorrelates two coherent sources unless their phase difference is unlucky.
    """
    r = np.asarray(r)
    return 0.5 * (r + np.conj(r[..., ::-1, ::-1]))


def default_subarray(n_elements: int) -> int:
    """Sub-array length ``Q = round(0.7·N)`` (seed 001: N = 12 → Q = 8), at least 2."""
    return max(2, min(n_elements, int(round(0.7 * n_elements))))


@functools.lru_cache(maxsize=64)
def _smoothing_index(n: int, q: int) -> tuple[np.ndarray, np.ndarray]:
    start = np.arange(n - q + 1)[:, None]
    idx = start + np.arange(q)[None, :]                          # (L, Q)
    return idx[:, :, None], idx[:, None, :]


def spatial_smoothing(r: np.ndarray, q: int) -> np.ndarray:
    """Forward spatial smoothing: mean of the ``L = N - Q + 1`` overlapping ``Q × Q`` diagonal blocks.

    Parameters
    ----------
    r : (..., N, N) complex covariance.
    q : sub-array length, ``2 ≤ q ≤ N``.

    Returns
    -------
    (..., Q, Q) complex covariance; decorrelates up to ``L`` coherent sources (2L with FB).
    """
    r = np.asarray(r)
    n = r.shape[-1]
    _check_subarray(q, n)
    if q == n:
        return r
    rows, cols = _smoothing_index(n, int(q))
    return r[..., rows, cols].mean(axis=-3)


def _check_subarray(q: object, n: int) -> None:
    if not (isinstance(q, (int, np.integer)) and 2 <= q <= n):
        raise ConfigError(f"subspace subarray: value {q!r} is not allowed; expected an integer 2 … {n} (N)")


@functools.lru_cache(maxsize=64)
def _stack_index(n: int, q: int, k: int, fb: bool) -> np.ndarray:
    """Flat index of ``Zᵀ`` (:func:`_covariance`) into ``x.ravel()`` (N·K), followed for FB by its conjugate: (L·K, Q)
    or (2·L·K, Q), row-major, so that ``Z`` is its transpose in column-major order, as BLAS takes it (no copy);
    column (l, k) of Z's forward part is sub-array l's snapshot k, ``x[l + i, k]`` in row i, of the backward part
    ``x*[l + Q − 1 − i, k]``."""
    i = np.arange(q)[:, None, None]
    lk = (np.arange(n - q + 1)[None, :, None], np.arange(k)[None, None, :])
    idx = ((lk[0] + i) * k + lk[1]).reshape(q, -1)
    if fb:
        idx = np.concatenate((idx, (n * k + (lk[0] + q - 1 - i) * k + lk[1]).reshape(q, -1)), axis=1)
    idx = np.ascontiguousarray(idx.T)
    idx.setflags(write=False)
    return idx


def _covariance(x: np.ndarray, q: int, fb: bool) -> np.ndarray:
    """:func:`sample_covariance`, :func:`spatial_smoothing` (``q``) and optionally :func:`forward_backward` of
    one set of snapshots ``x`` (N, K), as one product: ``Z·Zᴴ / (columns of Z)`` with ``Z`` the L = N − Q + 1
    sub-arrays' snapshots side by side (Q, L·K), followed for FB by their reversed conjugates (Q, 2·L·K).
    The same matrix as the three steps (the sums in another order): (Q, Q) complex."""
    n, k = x.shape
    if q == n and not fb:
        z = x
    else:
        flat = x.reshape(-1)
        z = (np.concatenate((flat, np.conj(flat))) if fb else flat).take(_stack_index(n, q, k, fb)).T
    return _gram(z, 1.0 / z.shape[1])


def _gram(a: np.ndarray, scale: float = 1.0) -> np.ndarray:
    """``scale · a·aᴴ`` (complex) in one BLAS call (no conjugate copy, no separate scaling); column-major."""
    if _POSITIONAL:                                    # beta = 0, c = None (none given), trans_a = 0: the defaults
        return _blas.zgemm(scale, a, a, 0.0, None, 0, 2)
    return _blas.zgemm(scale, a, a, trans_b=2)


# ---------------------------------------------------------------------------------------------
# source-number estimation

def _eigvals_desc(r: np.ndarray) -> np.ndarray:
    """Eigenvalues of the Hermitian part of ``r``, descending, clipped to ≥ 1e-300 (N,) float64."""
    r = 0.5 * (r + np.conj(r.T))
    lam = np.linalg.eigvalsh(r)[::-1]
    return np.maximum(lam, max(float(lam[0]), 0.0) * 1e-15 + 1e-300)


def _info_criteria(lam: np.ndarray, n_snapshots: float) -> tuple[np.ndarray, np.ndarray]:
    """Log-likelihood term and free-parameter count for k = 0 … N-1 sources (Wax & Kailath 1985)."""
    n = lam.size
    k = np.arange(n)
    log_lam = np.log(lam)
    # tail sums over the N-k smallest eigenvalues, for every k at once
    tail_log = np.cumsum(log_lam[::-1])[::-1]
    tail_sum = np.cumsum(lam[::-1])[::-1]
    m = n - k
    log_ratio = tail_log / m - np.log(tail_sum / m)               # log(geometric / arithmetic) ≤ 0
    loglik = -n_snapshots * m * np.minimum(log_ratio, 0.0)
    return loglik, k * (2 * n - k)


def mdl(lam: np.ndarray, n_snapshots: float) -> int:
    """Number of sources by the minimum description length: ``lam`` (N,) eigenvalues, descending.

    ``n_snapshots``: effective independent snapshots (K; about K·L·2 after smoothing and FB).
    Returns 0 … N-1.
    """
    loglik, p = _info_criteria(np.asarray(lam, dtype=float), float(n_snapshots))
    return int(np.argmin(loglik + 0.5 * p * math.log(max(n_snapshots, 2.0))))


def aic(lam: np.ndarray, n_snapshots: float) -> int:
    """Number of sources by Akaike's criterion (tends to overestimate at high K): 0 … N-1."""
    loglik, p = _info_criteria(np.asarray(lam, dtype=float), float(n_snapshots))
    return int(np.argmin(2.0 * loglik + 2.0 * p))


def eigen_threshold(lam: np.ndarray, n_snapshots: float, noise_power: float | None = None,
                    margin: float = 1.5) -> int:
    """Number of eigenvalues above ``margin · σ² · (1 + √(N/K))²`` (Marchenko–Pastur upper edge).

    ``noise_power`` σ² in the covariance's units; ``None`` estimates it as the mean of the
    smaller half of the eigenvalues (assumes fewer than N/2 sources). Returns 0 … N-1.
    """
    lam = np.asarray(lam, dtype=float)
    n = lam.size
    if noise_power is None:
        noise_power = float(np.mean(lam[n // 2:]))
    edge = margin * noise_power * (1.0 + math.sqrt(n / max(float(n_snapshots), 1.0))) ** 2
    return int(min(np.count_nonzero(lam > edge), n - 1))


SOURCE_COUNTERS: dict[str, Callable[..., int]] = {"mdl": mdl, "aic": aic, "threshold": eigen_threshold}


# ---------------------------------------------------------------------------------------------
# steering, eigenvectors, grid search and refinement
#
# Cost (issue 11 item 7): at N = 12 an estimate is a few dozen tiny numpy/LAPACK calls, each costing
# ~1 µs of call overhead whatever its arithmetic. So everything that depends only on (N, d, grid) is
# tabulated once (lru_cache), the search works on real tables and a real coefficient vector, and the
# eigenvectors come straight from LAPACK (?heevr for the needed ones only; ?heev up to N = 8), about half
# the cost of numpy's eigh with its checks.

def steering(n: int, u: np.ndarray, d: float = 0.5) -> np.ndarray:
    """Steering vectors ``exp(j·2π·d·k·u)``: ``u`` shape ``S`` → ``(N, *S)`` complex."""
    u = np.asarray(u, dtype=float)
    k = np.arange(n).reshape((n,) + (1,) * u.ndim)
    return np.exp(2j * np.pi * d * k * u)


def _periodic(d: float) -> bool:
    # the steering vector repeats every 1/d in u; at d = ½ the visible region [-1, 1) is one period
    return abs(2.0 * d - 1.0) < 1e-12


def _eigvecs(h: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """Eigenvectors of the ``lo``-th … ``hi``-th smallest eigenvalues (1-based, inclusive) of a Hermitian
    (complex) or symmetric (real) ``h`` (N, N), read from its upper triangle: (N, hi − lo + 1), ascending.

    LAPACK's ``?heevr``/``?syevr`` computes only the wanted vectors; up to N = 8 the plain QR ``?heev``/``?syev``
    of all of them is cheaper. Should LAPACK report a failure (never seen), numpy's ``eigh`` of the Hermitian part
    is the fallback; its ``LinAlgError`` is what :func:`estimate` turns into "not resolved".
    """
    complex_ = h.dtype.kind == "c"
    if h.shape[0] <= 8:
        fn = _lapack.zheev if complex_ else _lapack.dsyev
        _, v, info = fn(h, 1, 0) if _POSITIONAL else fn(h, lower=0)
        if info == 0:
            return v[:, lo - 1:hi]
    else:
        fn = _lapack.zheevr if complex_ else _lapack.dsyevr
        # vl = 0, vu = 1: the defaults (unused for range "I")
        _, v, found, _, info = fn(h, 1, "I", 0, 0.0, 1.0, lo, hi) if _POSITIONAL else fn(h, range="I", il=lo, iu=hi)
        if info == 0 and found == hi - lo + 1:
            return v
    _, v = np.linalg.eigh(0.5 * (h + np.conj(h.T)))
    return v[:, lo - 1:hi]


def _signal_subspace(r: np.ndarray, n_sources: int) -> np.ndarray:
    """Eigenvectors of the ``n_sources`` largest eigenvalues of ``r`` (N, N): (N, n_sources)."""
    n = r.shape[0]
    return _eigvecs(r, n - n_sources + 1, n)


# a(u)ᴴ S a(u) = Σ_m s_m e^{j·2π·d·m·u}, s_m = Σ_{l−k=m} S_kl the sums of S's diagonals (s_{−m} = s_m*), is
# the real trigonometric polynomial  s_0 + Σ_{m≥1} 2·Re s_m·cos(2π·d·m·u) − 2·Im s_m·sin(2π·d·m·u):
# a real row (2N − 1) per u, tabulated on the grids, times one real vector per covariance.

@functools.lru_cache(maxsize=32)
def _diag_sum_matrix(n: int, sign: float = 1.0) -> np.ndarray:
    """(2N − 1, 2N²) float64: ``S.view(float)`` (row-major, re/im interleaved) → ``[s_0, Re s_1 … s_{N−1},
    Im s_1 … s_{N−1}]`` of the Hermitian part of S (both triangles averaged)."""
    k, l = np.divmod(np.arange(n * n), n)
    m = l - k                                                   # diagonal of entry (k, l)
    a = np.abs(m)
    out = np.zeros((2 * n - 1, n * n, 2))
    out[a, np.arange(n * n), 0] = np.where(a > 0, 0.5, 1.0)      # Re s_|m|: both triangles averaged
    off = a > 0
    out[n - 1 + a[off], np.flatnonzero(off), 1] = 0.5 * np.sign(m[off])   # Im s_m = ½(Im S_kl − Im S_lk)
    out = sign * out.reshape(2 * n - 1, 2 * n * n)
    out.setflags(write=False)
    return out


def _diag_sums(s: np.ndarray, sign: float = 1.0) -> np.ndarray:
    """Real diagonal-sum vector (2N − 1,) of an (N, N) Hermitian matrix (see :func:`_diag_sum_matrix`), times
    ``sign``."""
    v = s.ravel()                                       # row-major (a copy of zgemm's column-major output)
    if v.dtype is not _COMPLEX128:
        v = v.astype(np.complex128)
    return _diag_sum_matrix(s.shape[0], sign) @ v.view(np.float64)


def _null_sums(es: np.ndarray) -> np.ndarray:
    """Diagonal-sum vector of the noise projector ``I − Es·Esᴴ`` from the signal subspace ``es`` (N, M)."""
    n = es.shape[0]
    c = _diag_sums(_gram(es), -1.0)
    c[0] += n
    return c


@functools.lru_cache(maxsize=32)
def _null_sum_matrix_columns(n: int) -> np.ndarray:
    """(2N − 1, 2N²) float64: :func:`_null_sums`' map (``−_diag_sum_matrix(n)``) for the *column-major* float view
    of a Hermitian S. That view is Sᵀ = S* read row-major, whose diagonal sums are the conjugates: the Im rows change
    sign."""
    out = _diag_sum_matrix(n) * np.concatenate((-np.ones(n), np.ones(n - 1)))[:, None]
    out.setflags(write=False)
    return out


def _null_sums_columns(es: np.ndarray) -> np.ndarray:
    """:func:`_null_sums` for root-MUSIC: zgemm's Es·Esᴴ read where it lies, column-major, not from a row-major
    copy. The same sums but for rounding (they are added in another order); one call and one copy fewer."""
    n = es.shape[0]
    c = _null_sum_matrix_columns(n).dot(_gram(es).ravel("F").view(np.float64))
    c[0] += n
    return c


def _trig_rows(n: int, u: np.ndarray, d: float) -> np.ndarray:
    """Rows ``[1, 2·cos(2π·d·m·u), −2·sin(2π·d·m·u)]`` (m = 1 … N−1): ``u`` shape S → (*S, 2N − 1) float64,
    so that ``rows @ _diag_sums(S)`` is ``a(u)ᴴ S a(u)``."""
    u = np.asarray(u, dtype=float)
    phase = (2.0 * np.pi * d) * np.multiply.outer(u, np.arange(1, n))
    return np.concatenate((np.ones(u.shape + (1,)), 2.0 * np.cos(phase), -2.0 * np.sin(phase)), axis=-1)


@dataclass(frozen=True)
class _Grid:
    u: np.ndarray           # (G,) coarse grid of sin θ
    coarse: np.ndarray      # (G, 2N − 1) trigonometric rows at u; at d = ½ (G + 2,): u[-1], u, u[0] (circular)
    fine: np.ndarray        # (G, F, 2N − 1) rows at u[g] + offs[f], offs: F points over ± one coarse step
    first: np.ndarray       # (G,) u[g] + offs[0]
    fine_step: float        # offs[1] − offs[0]
    centre: np.ndarray      # (F,) int: argmin over the fine points → centre of the three for the parabola


@functools.lru_cache(maxsize=16)               # (G, F, 2N − 1) floats each: 0.4 MB at N = 12
def _grid(n: int, d: float, n_grid: int) -> _Grid:
    if _periodic(d):
        u = -1.0 + 2.0 * np.arange(n_grid) / n_grid                 # [-1, 1): +1 is -1
        coarse = _trig_rows(n, u[np.arange(-1, n_grid + 1) % n_grid], d)
    else:
        u = np.linspace(-1.0, 1.0, n_grid)
        coarse = _trig_rows(n, u, d)
    step = float(u[1] - u[0])
    offs = np.linspace(-step, step, 2 * REFINE_HALF + 1)
    f = offs.size
    grid = _Grid(u, coarse, _trig_rows(n, u[:, None] + offs, d), u + offs[0], float(offs[1] - offs[0]),
                 np.minimum(np.maximum(np.arange(f), 1), f - 2))
    for a in (grid.u, grid.coarse, grid.fine, grid.first, grid.centre):
        a.setflags(write=False)
    return grid


def _n_grid(n: int, n_grid: int | None) -> int:
    return max(256, GRID_PER_ELEMENT * n) if n_grid is None else int(n_grid)


def _wrap(u: np.ndarray, d: float) -> np.ndarray:
    if _periodic(d):
        return (u + 1.0) % 2.0 - 1.0
    return np.minimum(np.maximum(u, -1.0), 1.0)


def _search(cost: Callable[[np.ndarray], np.ndarray], n: int, d: float, n_sources: int,
            n_grid: int | None, floor_db: float, maximise: bool,
            accept_below: float = -np.inf) -> tuple[np.ndarray, np.ndarray]:
    """Grid search, then a fine local grid with a parabola through the three best points.

    ``cost(T)`` maps trigonometric rows ``T`` (…, 2N − 1) (:func:`_trig_rows`) to the cost (…) to be
    minimised. ``maximise``: the cost is −P (beam scanning, spectrum P); otherwise it is the positive
    denominator of the pseudo-spectrum 1/cost (Capon, MUSIC). Peaks more than ``floor_db`` below
    the strongest are dropped unless their cost is below ``accept_below`` (MUSIC: half the steering
    vector's energy outside the signal subspace — pseudo-spectrum peak heights span decades and say
    little about source power). Returns ``(u (n,), resolved (n,))``.
    """
    grid = _grid(n, d, _n_grid(n, n_grid))
    # local minima of the cost; at d = ½ the grid is circular (the table has both neighbours' rows)
    if _periodic(d):
        ext = cost(grid.coarse)
        c = ext[1:-1]
    else:
        c = cost(grid.coarse)
        ext = np.concatenate(([np.inf], c, [np.inf]))
    best = np.minimum.reduce(c)
    if maximise and not best < 0:                      # zero data: a flat, empty spectrum
        return np.zeros(n_sources), np.zeros(n_sources, dtype=bool)
    limit = max(best * _FLOOR[floor_db, maximise], accept_below)
    peaks = ((c < ext[:-2]) & (c <= ext[2:]) & (c <= limit)).nonzero()[0]
    if peaks.size == 0:
        return np.zeros(n_sources), np.zeros(n_sources, dtype=bool)
    if peaks.size > n_sources:
        peaks = peaks[c[peaks].argsort()[:n_sources]]
    # local refinement: 2·REFINE_HALF+1 points over ± one coarse step, parabola through the best three
    cf = cost(grid.fine[peaks])                               # (P, F)
    f = cf.shape[1]
    i = grid.centre[cf.argmin(axis=1)]                         # argmin, kept off the ends
    three = cf.take((np.arange(0, cf.size, f) + i)[:, None] + _THREE)          # (P, 3)
    num, den = (three @ _PARABOLA).T                          # ½(c₀ − c₂), c₀ − 2c₁ + c₂
    shift = np.divide(num, den, out=np.zeros(num.size), where=den > 0)      # 0 where den ≤ 0
    shift = np.minimum(np.maximum(shift, -1.0), 1.0)
    u = _wrap(grid.first[peaks] + (i + shift) * grid.fine_step, d)
    return _pad(u, n_sources)


_THREE = np.array([-1, 0, 1])
_PARABOLA = np.array([[0.5, 1.0], [0.0, -2.0], [-0.5, 1.0]])


class _FloorFactors(dict):
    """(floor_db, maximise) → factor on the best cost below which a grid minimum counts as a peak."""

    def __missing__(self, key):
        floor_db, maximise = key
        value = 10.0 ** (-floor_db / 10.0) if maximise else 10.0 ** (floor_db / 10.0)
        self[key] = value
        return value


_FLOOR = _FloorFactors()


def _pad(u: np.ndarray, n_sources: int) -> tuple[np.ndarray, np.ndarray]:
    """Sort the estimates ``u`` (all resolved; sorted in place); fill up to ``n_sources`` with copies of the first
    (strongest), flagged unresolved."""
    if u.size >= n_sources:
        u.sort()
        ok = np.empty(u.size, dtype=bool)
        ok.fill(True)
        return u, ok
    fill = u[0] if u.size else 0.0
    ok = np.arange(n_sources) < u.size
    u = np.concatenate((u, np.full(n_sources - u.size, fill)))
    order = np.argsort(u)
    return u[order], ok[order]


def _hermitian_eigh(r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eigen-decomposition of the Hermitian part of ``r``, eigenvalues ascending."""
    return np.linalg.eigh(0.5 * (r + np.conj(r.T)))


# ---------------------------------------------------------------------------------------------
# estimators: covariance (N, N) → (sin θ (n,), resolved (n,) bool)

def bartlett(r: np.ndarray, n_sources: int, d: float = 0.5, n_grid: int | None = None,
             floor_db: float = DEFAULT_FLOOR_DB["bartlett"]) -> tuple[np.ndarray, np.ndarray]:
    """Bartlett (conventional, FFT-equivalent) beam scan ``P(u) = aᴴ R a``; peaks of P.

    For ``K = 1`` without smoothing this is ``|FFT|²`` of the snapshot. Resolution ≈ 2/(N·d) in u.
    """
    s = _diag_sums(r)

    def cost(rows):
        return -(rows @ s)

    return _search(cost, r.shape[0], d, n_sources, n_grid, floor_db, maximise=True)


def capon(r: np.ndarray, n_sources: int, d: float = 0.5, loading: float = 1e-3,
          n_grid: int | None = None,
          floor_db: float = DEFAULT_FLOOR_DB["capon"]) -> tuple[np.ndarray, np.ndarray]:
    """Capon/MVDR ``P(u) = 1 / (aᴴ (R + δI)⁻¹ a)`` with diagonal loading ``δ = loading · tr(R)/N``.

    The inverse is taken through ``eigh`` with eigenvalues clipped at ``1e-12 · λ_max``, so a
    rank-deficient ``R`` (one snapshot, zero loading) stays finite.
    """
    n = r.shape[0]
    delta = loading * max(float(np.real(np.trace(r))), 0.0) / n
    w, v = _hermitian_eigh(r)
    w = w + delta
    w = np.maximum(w, max(float(w[-1]), 0.0) * 1e-12 + 1e-300)
    vs = v / np.sqrt(w)[None, :]                             # R⁻¹ = vs·vsᴴ
    s = _diag_sums(_gram(vs))

    def cost(rows):
        return np.maximum(rows @ s, 1e-300)

    return _search(cost, n, d, n_sources, n_grid, floor_db, maximise=False)


def _music_search(es: np.ndarray, n: int, d: float, n_sources: int, n_grid: int | None,
                  floor_db: float) -> tuple[np.ndarray, np.ndarray]:
    """Peaks of ``1 / ‖Enᴴ a‖²``, the null spectrum ``‖Enᴴ a‖² = N − ‖Esᴴ a‖²`` (‖a‖² = N) from the thin
    signal subspace ``es`` (N, M) in the steering vectors' basis."""
    c = _null_sums(es)

    def cost(rows):
        return np.maximum(rows @ c, 1e-300)

    return _search(cost, n, d, n_sources, n_grid, floor_db, maximise=False, accept_below=MUSIC_ACCEPT * n)


def music(r: np.ndarray, n_sources: int, d: float = 0.5, n_grid: int | None = None,
          floor_db: float = DEFAULT_FLOOR_DB["music"]) -> tuple[np.ndarray, np.ndarray]:
    """MUSIC: peaks of ``1 / ‖Enᴴ a(u)‖²``, coarse grid then local refinement (:func:`_search`)."""
    n = r.shape[0]
    return _music_search(_signal_subspace(r, n_sources), n, d, n_sources, n_grid, floor_db)


@functools.lru_cache(maxsize=64)
def unitary_matrix(n: int) -> np.ndarray:
    """Sparse unitary ``Q_N`` (Huarng & Yeh 1991; seed 004), ``(N, N)`` complex, for odd and even N.

    ``N = 2m``:   ``Q = [[I, jI], [J, −jJ]] / √2``;
    ``N = 2m+1``: ``Q = [[I, 0, jI], [0ᵀ, √2, 0ᵀ], [J, 0, −jJ]] / √2``.
    ``Qᴴ a_c(u)`` is real for a steering vector centred on the array's middle, and
    ``Qᴴ R Q`` is real for a centro-Hermitian (forward–backward averaged) ``R``.
    """
    m = n // 2
    eye = np.eye(m)
    ex = eye[::-1]
    q = np.zeros((n, n), dtype=complex)
    q[:m, :m] = eye
    q[:m, n - m:] = 1j * eye
    q[n - m:, :m] = ex
    q[n - m:, n - m:] = -1j * ex
    if n % 2:
        q[m, m] = math.sqrt(2.0)
    q /= math.sqrt(2.0)
    q.setflags(write=False)
    return q


def _unitary_steering(n: int, u: np.ndarray, d: float) -> np.ndarray:
    """Real steering ``Qᴴ a_c(u)``: ``u`` shape S → ``(N, *S)`` float64 (phase centre mid-array)."""
    u = np.asarray(u, dtype=float)
    k = (np.arange(n) - 0.5 * (n - 1)).reshape((n,) + (1,) * u.ndim)
    phase = 2.0 * np.pi * d * k * u
    m = n // 2
    # Qᴴ a_c = [√2·cos φ_k (k < m), 1 (middle, odd N), √2·sin φ_k (k < m)]
    out = np.empty((n,) + u.shape)
    out[:m] = math.sqrt(2.0) * np.cos(phase[:m])
    out[n - m:] = math.sqrt(2.0) * np.sin(phase[:m])
    if n % 2:
        out[m] = 1.0
    return out


def unitary_music(r: np.ndarray, n_sources: int, d: float = 0.5, n_grid: int | None = None,
                  floor_db: float = DEFAULT_FLOOR_DB["unitary_music"]) -> tuple[np.ndarray, np.ndarray]:
    """Unitary MUSIC (seed 004): real covariance ``Re(Qᴴ R Q) = Qᴴ R_fb Q``, real eigh.

    Equivalent to complex MUSIC on the forward–backward averaged ``R`` (same subspace, same
    null spectrum), at real instead of complex arithmetic. The null spectrum
    ``N − ‖Esᵀ Qᴴ a_c(u)‖²`` is that of the subspace ``Q·Es`` in the steering vectors' own basis
    (the centring phase cancels), so the search is the one of :func:`music`.
    """
    n = r.shape[0]
    q = unitary_matrix(n)
    c = np.real(np.conj(q.T) @ r @ q)
    es = _signal_subspace(c, n_sources)                        # (N, M) real
    return _music_search(q @ es, n, d, n_sources, n_grid, floor_db)


# root-MUSIC. P(z) = Σ_i coef_i zⁱ (degree D = 2N − 2) has coef_{D−i} = coef_i*: its roots come in pairs
# z, 1/z*. No polynomial map identifies z with 1/z* (z ↦ 1/z* is anti-holomorphic), so there is no exact
# degree-(N−1) problem short of a spectral factorisation, itself a root problem. But the pairing makes P
# real on the unit circle, and the Cayley map z = w·(t − j)/(t + j) (|w| = 1) takes the circle to the real
# axis: Q(t) = w^{−(N−1)}·(t + j)^D·P(z)/(…) is a *real* polynomial of degree D, pairs z, 1/z* become
# conjugates t, t*, |z| ≤ 1 ⟺ Im t ≥ 0. Its companion matrix goes to LAPACK's real dgeev, a third of the
# complex zgeev that np.roots runs (degree 22: about 55 µs against 180 µs). The point w = −e^{jα} sent to
# t = ∞ is put where |P| is largest on a coarse probe of the circle, far from the roots near the circle.

#: probe points per element for the Cayley map's point at infinity
_CAYLEY_PROBES = 4


@functools.lru_cache(maxsize=16)
def _cayley_tables(n: int) -> tuple[np.ndarray, tuple[np.ndarray, ...], tuple[complex, ...], np.ndarray]:
    """For a noise projector's diagonal-sum vector ``c`` (2N − 1,) (:func:`_diag_sums`):

    * ``probe`` (G, 2N − 1): ``probe @ c`` is P's modulus |z^{−(N−1)}·P(z)| at ``z_g = e^{j2πg/G}``;
    * ``real`` G × (D + 1, 2N − 1): ``real[g] @ c`` the coefficients (ascending powers of t) of the real
      polynomial whose roots t map to P's roots by ``z = z_g·(t − j)/(t + j)`` (a tuple of views of one array:
      one is picked per call, and a tuple is cheaper to index than an array);
    * ``w`` G × complex: ``z_g`` (a tuple of Python complex numbers, likewise);
    * ``companion`` (D, D) Fortran-ordered template: ones on the sub-diagonal.
    """
    deg = 2 * n - 2
    n_probe = _CAYLEY_PROBES * n
    omega = 2.0 * np.pi * np.arange(n_probe) / n_probe
    probe = _trig_rows(n, omega, 1.0 / (2.0 * np.pi))
    # coef (D + 1,) complex = to_coef @ c: coef_{N−1±m} = Re c_m ± j·Im c_m
    m = np.arange(1, n)
    to_coef = np.zeros((deg + 1, 2 * n - 1), dtype=complex)
    to_coef[n - 1, 0] = 1.0
    to_coef[n - 1 + m, m] = 1.0
    to_coef[n - 1 + m, n - 1 + m] = 1j
    to_coef[n - 1 - m, m] = 1.0
    to_coef[n - 1 - m, n - 1 + m] = -1j
    # cayley[k, i]: coefficient of tᵏ in (1 + jt)ⁱ (1 − jt)^(D−i) (exact binomials; a one-off table)
    cayley = np.zeros((deg + 1, deg + 1), dtype=complex)
    for i in range(deg + 1):
        plus = np.array([math.comb(i, a) * 1j ** a for a in range(i + 1)])
        minus = np.array([math.comb(deg - i, b) * (-1j) ** b for b in range(deg - i + 1)])
        cayley[:, i] = np.convolve(plus, minus)
    # with z = e^{jα}(1 + jt)/(1 − jt), α = ω_g − π:  Q(t) = e^{−j(N−1)α}(1 − jt)^D P(z) = Σ_i coef_i e^{j(i−N+1)α}
    # (1 + jt)ⁱ (1 − jt)^(D−i), real for real t: (1 + t²)^(N−1) times P's modulus on the circle
    alpha = omega - np.pi
    rot = np.exp(1j * np.multiply.outer(alpha, np.arange(deg + 1) - (n - 1)))          # (G, D + 1)
    real = np.real(np.einsum("ki,gi,ic->gkc", cayley, rot, to_coef))
    companion = np.zeros((deg, deg), order="F")
    companion[np.arange(1, deg), np.arange(deg - 1)] = 1.0
    for a in (probe, real, companion):
        a.setflags(write=False)
    return probe, tuple(real), tuple(complex(v) for v in np.exp(1j * omega)), companion


def _root_music_coef(c: np.ndarray, n: int) -> np.ndarray:
    """P's coefficients (ascending powers) from the noise projector's diagonal-sum vector ``c``: (2N − 1,) complex."""
    m = np.arange(1, n)
    half = c[m] + 1j * c[n - 1 + m]
    return np.concatenate((np.conj(half[::-1]), c[:1] + 0j, half))


def _polynomial_roots(c: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray, complex | None]:
    """All roots of the root-MUSIC polynomial P(z) from the noise projector's diagonal sums ``c``, as the roots
    ``t = tr + j·ti`` of the real Cayley polynomial: returns ``(tr, ti, w)``, ``z = w·(t − j)/(t + j)``. Should
    LAPACK fail (never seen), ``w`` is None and ``tr`` holds P's roots z from ``np.roots`` (the reference)."""
    probe, real, w, template = _cayley_tables(n)
    g = int(probe.dot(c).argmax())
    q = real[g].dot(c)                                          # ascending powers of t; |q[-1]| = max |P|
    comp = template.copy(order="F")
    np.divide(q[-2::-1], -q[-1], out=comp[0])
    if _POSITIONAL:                                             # lwork = 4·D: the default
        tr, ti, _, _, info = _lapack.dgeev(comp, 0, 0, 4 * comp.shape[0], 1)
    else:
        tr, ti, _, _, info = _lapack.dgeev(comp, compute_vl=0, compute_vr=0, overwrite_a=1)
    if info == 0:
        return tr, ti, w[g]
    return np.roots(_root_music_coef(c, n)[::-1]), None, None


def root_music(r: np.ndarray, n_sources: int, d: float = 0.5) -> tuple[np.ndarray, np.ndarray]:
    """Root-MUSIC: roots of ``Σ_m c_m z^m``, ``c_m`` = sum of the m-th diagonal of ``En Enᴴ``.

    Keeps the ``n_sources`` roots inside (or on) the unit circle closest to it;
    ``u = arg z / (2π d)``. ``resolved`` is False for a root that repeats another's angle.
    The roots are those of a real polynomial of the same degree (Cayley map, :func:`_cayley_tables`).
    """
    n = r.shape[0]
    es = _signal_subspace(r, n_sources)
    c = _null_sums_columns(es)                                  # En Enᴴ = I − Es Esᴴ
    tr, ti, w = _polynomial_roots(c, n)
    if w is None:                                               # np.roots' z
        roots = tr[np.isfinite(tr)]
        inside = roots[np.abs(roots) <= 1.0]
    else:
        found = _nearest_inside(tr, ti, w, d, n_sources)
        if found is not None:
            return found
        t = tr + 1j * ti                                        # P's roots at ∞ (t = −j) are not roots
        with np.errstate(divide="ignore", invalid="ignore"):
            roots = w * (t - 1j) / (t + 1j)
        roots = roots[np.isfinite(roots)]
        inside = roots[np.abs(roots) <= 1.0]
    if roots.size == 0:
        return np.zeros(n_sources), np.zeros(n_sources, dtype=bool)
    cand = inside if inside.size >= n_sources else roots
    z = cand[np.abs(1.0 - np.abs(cand)).argsort()[:n_sources]]
    return _roots_to_u(z, d, n_sources)


def _nearest_inside(tr: np.ndarray, ti: np.ndarray, w: complex, d: float,
                    n_sources: int) -> tuple[np.ndarray, np.ndarray] | None:
    """The ``n_sources`` roots ``z = w·(t − j)/(t + j)`` inside (or on) the unit circle closest to it, from the
    Cayley roots ``t = tr + j·ti`` (:func:`_polynomial_roots`), as :func:`_roots_to_u`'s ``(u, resolved)``; None
    when fewer than ``n_sources`` lie inside.

    Inside is ``Im t > 0``, where ``1 − |z|² = 4·Im t / |t + j|²``: the closest are the smallest
    ``Im t / |t + j|²``. The few (n_sources) chosen are turned into angles on Python floats and complex numbers:
    a dozen roots are too few for numpy's per-call cost to pay (issue 11 item 7).
    """
    trl = tr.tolist()
    til = ti.tolist()
    cand = [(b / (a * a + (b + 1.0) * (b + 1.0)), a, b) for a, b in zip(trl, til) if b > 0.0]
    if 2 * len(cand) < len(trl):
        # real t: |z| = 1. P ≥ 0 on the circle, so a root there is double, split by rounding into two real
        # t or a conjugate pair; keep one of each two (in order), as np.roots' radial split keeps one inside
        cand += [(0.0, a, 0.0) for a in sorted([a for a, b in zip(trl, til) if b == 0.0])[::2]]
    if len(cand) < n_sources:
        return None
    cand.sort()
    scale = 2.0 * math.pi * d
    periodic = _periodic(d)
    u = []
    for _, a, b in cand[:n_sources]:
        t = complex(a, b)
        v = cmath.phase(w * ((t - 1j) / (t + 1j))) / scale           # arg z
        u.append((v + 1.0) % 2.0 - 1.0 if periodic else min(max(v, -1.0), 1.0))
    u.sort()
    ok = [True] * n_sources
    for i in range(1, n_sources):
        ok[i] = u[i] - u[i - 1] >= 1e-9                         # a repeated angle is not resolved
    return np.array(u), np.array(ok)


def _roots_to_u(z: np.ndarray, d: float, n_sources: int) -> tuple[np.ndarray, np.ndarray]:
    u = _wrap(np.arctan2(z.imag, z.real) / (2.0 * np.pi * d), d)          # arg z
    u, ok = _pad(u, n_sources)
    if u.size > 1:
        ok[1:] &= u[1:] - u[:-1] >= 1e-9                        # a repeated angle is not resolved
    return u, ok


def esprit(r: np.ndarray, n_sources: int, d: float = 0.5, tls: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """ESPRIT on the shift between elements 0…N−2 and 1…N−1: total (``tls``) or ordinary least squares.

    TLS: ``Ψ = −V₁₂ V₂₂⁻¹`` from the right singular vectors ``[V₁₂; V₂₂]`` of ``[Es₁ Es₂]`` for its M
    smallest singular values — taken as the eigenvectors of the 2M × 2M Gram matrix for its M smallest
    eigenvalues (Ψ does not depend on the basis of that subspace); ``V₂₂⁺`` when V₂₂ is near singular.
    LS: ``Ψ = Es₁⁺ Es₂``. ``u = arg eig(Ψ) / (2π d)``. Pseudo-inverses (SVD) keep a rank-deficient
    subspace finite.
    """
    n = r.shape[0]
    m = n_sources
    es = _signal_subspace(r, m)
    e1, e2 = es[:-1], es[1:]
    if tls:
        e12 = np.concatenate((e1, e2), axis=1)
        v = _eigvecs(_blas.zgemm(1.0, e12, e12, trans_a=2), 1, m)         # (2M, M): Gram matrix
        v12, v22 = v[:m], v[m:]
        try:
            inv = np.linalg.inv(v22)
        except np.linalg.LinAlgError:
            inv = None
        # |V₂₂⁻¹| < 1e13 bounds σ_min(V₂₂) (σ_max ≤ 1) far above pinv's cut-off, where pinv is the inverse
        if inv is None or not np.abs(inv).max() < 1e13:
            inv = np.linalg.pinv(v22)
        psi = -v12 @ inv
    else:
        psi = np.linalg.pinv(e1) @ e2
    z, _, _, info = _lapack.zgeev(psi, compute_vl=0, compute_vr=0)
    if info != 0:
        z = np.linalg.eigvals(psi)
    return _roots_to_u(z, d, n_sources)


#: name → estimator(covariance (N, N), n_sources, d=…, **options) → (sin θ (n,), resolved (n,))
ESTIMATORS: dict[str, Callable[..., tuple[np.ndarray, np.ndarray]]] = {
    "bartlett": bartlett,
    "capon": capon,
    "music": music,
    "unitary_music": unitary_music,
    "root_music": root_music,
    "esprit": esprit,
}


# ---------------------------------------------------------------------------------------------
# entry point

@dataclass(frozen=True)
class SubspaceEstimate:
    """One estimate.

    sin_theta : (n,) float64, ascending, always finite.
    resolved : (n,) bool; False marks an entry the estimator could not separate (its angle is a
        copy of a resolved one, or 0 when nothing was found).
    n_sources : sources used (given, or from the source counter; 0 → empty arrays).
    method : estimator name.
    """

    sin_theta: np.ndarray
    resolved: np.ndarray
    n_sources: int
    method: str

    @property
    def all_resolved(self) -> bool:
        return bool(np.all(self.resolved)) and self.n_sources > 0

    @property
    def azimuth_deg(self) -> np.ndarray:
        """(n,) azimuth in degrees, broadside 0."""
        return np.degrees(np.arcsin(np.clip(self.sin_theta, -1.0, 1.0)))


def _check_snapshots(x: object) -> np.ndarray:
    if type(x) is np.ndarray and x.dtype is _COMPLEX128 and x.ndim == 2 and x.shape[0] >= 2 and x.shape[1] >= 1:
        return x                                        # the common case, as the checks below would return it
    try:
        x = np.asarray(x)
    except Exception as exc:  # ragged lists and the like
        raise ConfigError(f"subspace X: value of type {type(x).__name__} is not allowed; "
                          f"expected an array of shape (N, K)") from exc
    if x.ndim == 1:
        x = x[:, None]
    if x.ndim != 2 or x.shape[0] < 2 or x.shape[1] < 1:
        raise ConfigError(f"subspace X: shape {x.shape} is not allowed; expected (N, K) with N >= 2 "
                          f"elements and K >= 1 snapshots (or (N,) for one snapshot)")
    if x.dtype.kind not in "biufcm":                    # bool or np.number (timedelta64 is one)
        raise ConfigError(f"subspace X: dtype {x.dtype} is not allowed; expected a real or complex number array")
    return x.astype(np.complex128, copy=False)


def estimate(method: str, x: np.ndarray, n_sources: int | None = None, d: float = 0.5, *,
             fb: bool = False, subarray: int | bool | None = None, counter: str = "mdl",
             **options) -> SubspaceEstimate:
    """Estimate sin θ of ``n_sources`` plane waves from snapshots ``x``.

    Parameters
    ----------
    method : a key of :data:`ESTIMATORS`.
    x : (N, K) complex snapshots (elements × snapshots) or (N,) for one snapshot; finite.
    n_sources : sources to estimate; ``None`` counts them with ``counter`` (may give 0).
    d : element spacing in wavelengths, > 0.
    fb : forward–backward averaging.
    subarray : spatial-smoothing sub-array length Q; ``True`` → ``round(0.7·N)``; ``None``/``False`` → off.
    counter : ``"mdl"``, ``"aic"`` or ``"threshold"`` (used when ``n_sources`` is None).
    **options : passed to the estimator (``loading``, ``n_grid``, ``floor_db``, ``tls``).

    Returns
    -------
    SubspaceEstimate with finite angles; unresolved entries are flagged, never NaN.

    Raises
    ------
    ConfigError : unknown method or counter, bad shape, non-finite samples, bad d, subarray or
        n_sources (subspace methods need ``1 ≤ n_sources ≤ Q − 1``).
    """
    try:
        fn = ESTIMATORS[method]
    except (KeyError, TypeError):
        raise ConfigError(f"subspace method: value {method!r} is not allowed; expected one of "
                          f"{', '.join(sorted(ESTIMATORS))}") from None
    if counter not in SOURCE_COUNTERS:
        raise ConfigError(f"subspace counter: value {counter!r} is not allowed; expected one of "
                          f"{', '.join(sorted(SOURCE_COUNTERS))}")
    if not (isinstance(d, (int, float, np.floating)) and math.isfinite(d) and d > 0):
        raise ConfigError(f"subspace d: value {d!r} is not allowed; expected a finite spacing > 0 wavelengths")
    x = _check_snapshots(x)
    n, k = x.shape
    given = not (subarray is True or subarray is None or subarray is False)
    if given:
        q = subarray                                    # checked below (after X's own checks)
    else:
        q = default_subarray(n) if subarray is True else n      # both in 2 … N
    # the energy Σ|x|² (one BLAS call) bounds the peak: peak² ≤ Σ|x|² ≤ N·K·peak². Within these bounds (with a
    # margin of √10 for rounding) x is finite, not zero and its peak inside 1e±100, so the common case needs
    # neither the peak nor the scaling; otherwise the peak decides as it always did
    energy = np.vdot(x, x).real                        # NaN or inf anywhere makes this non-finite
    if 1e-199 * n * k < energy < 1e199:
        peak = 1.0
    else:
        peak = float(np.maximum.reduce(np.abs(x), axis=None))   # NaN or inf anywhere makes this non-finite
        if not math.isfinite(peak):
            raise ConfigError("subspace X: a non-finite value (NaN or inf) is not allowed; expected finite samples")
        if peak > 0 and not 1e-100 < peak < 1e100:    # angles are scale invariant; keep x·xᴴ in range
            x = x / peak
    if given:
        _check_subarray(q, n)
    r = _covariance(x, int(q), bool(fb))
    m_max = q - 1
    if n_sources is None:
        lam = _eigvals_desc(r)
        k_eff = k * (n - q + 1) * (2 if fb else 1)
        n_used = min(SOURCE_COUNTERS[counter](lam, k_eff), m_max)
    else:
        if not (isinstance(n_sources, (int, np.integer)) and not isinstance(n_sources, bool)
                and 1 <= n_sources <= m_max):
            raise ConfigError(f"subspace n_sources: value {n_sources!r} is not allowed; expected an "
                              f"integer 1 … {m_max} (sub-array length {q} − 1) or None")
        n_used = int(n_sources)
    if n_used == 0 or peak == 0:
        return SubspaceEstimate(np.zeros(n_used), np.zeros(n_used, dtype=bool), n_used, method)
    try:
        u, ok = fn(r, n_used, d, **options)
    except (np.linalg.LinAlgError, FloatingPointError):
        # the safety net the stability tests check is never needed; kept so the contract holds
        u, ok = np.zeros(n_used), np.zeros(n_used, dtype=bool)
    if type(u) is not np.ndarray or u.dtype is not _FLOAT64:
        u = np.asarray(u, dtype=float)
    if type(ok) is not np.ndarray or ok.dtype is not _BOOL:
        ok = np.asarray(ok, dtype=bool)
    if not math.isfinite(u.dot(u)):                    # a NaN or inf (or |u| > 1e154: then nothing changes)
        finite = np.isfinite(u)
        ok = ok & finite
        u = np.where(finite, u, 0.0)
    return SubspaceEstimate(u, ok, n_used, method)


# ---------------------------------------------------------------------------------------------
# bound

def crb_sin(u: np.ndarray, n_elements: int, n_snapshots: int, snr_db: float | np.ndarray,
            d: float = 0.5, source_cov: np.ndarray | None = None) -> np.ndarray:
    """Stochastic (unconditional) Cramér–Rao bound on sin θ (Stoica & Nehorai 1990, eq. 4.1 / B.7).

    ``CRB(u) = σ²/(2K) · {Re[(Dᴴ P⊥_A D) ⊙ (P Aᴴ R⁻¹ A P)ᵀ]}⁻¹`` with ``D = ∂a/∂u``, noise σ² = 1.

    Parameters
    ----------
    u : (M,) sin θ of the sources.
    n_elements, n_snapshots : N and K.
    snr_db : per-element, per-snapshot SNR of each source (scalar or (M,)); ignored if ``source_cov``.
    d : spacing in wavelengths.
    source_cov : optional (M, M) source covariance P in units of σ² (for correlated sources).

    Returns
    -------
    (M,) variance bound on each sin θ (dimensionless²).
    """
    u = np.atleast_1d(np.asarray(u, dtype=float))
    m = u.size
    a = steering(n_elements, u, d)                                   # (N, M)
    k = np.arange(n_elements)[:, None]
    dd = 2j * np.pi * d * k * a
    if source_cov is None:
        p = np.diag(np.broadcast_to(10.0 ** (np.asarray(snr_db, dtype=float) / 10.0), (m,))).astype(complex)
    else:
        p = np.asarray(source_cov, dtype=complex)
    r = a @ p @ np.conj(a.T) + np.eye(n_elements)
    proj = np.eye(n_elements) - a @ np.linalg.pinv(a)
    h = np.conj(dd.T) @ proj @ dd
    g = p @ np.conj(a.T) @ np.linalg.solve(r, a) @ p
    fim = np.real(h * g.T)
    return np.diag(np.linalg.inv(fim)) / (2.0 * n_snapshots)
