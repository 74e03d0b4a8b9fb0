"""Two-dimensional CFAR detectors over a range–Doppler power map.

Each detector estimates the noise level in a ring of training cells around
every cell (guard cells excluded) and compares the cell against a threshold
set for a false-alarm probability. Doppler wraps around (it is circular);
range does not: near the first and last range bins the CA ring is one-sided
and its threshold factor is set for the cells it still holds (mirroring the
map would put a target near the edge into its own training cells); OS-CFAR
mirrors, since its order statistic ignores those few cells.

The threshold factors are those of the statistic actually tested: the map is
the non-coherent sum of ``n_channels`` channels (each cell Gamma(N) under
noise), and the windows make neighbouring cells correlated, which the
training sum feels (:mod:`radarnode.dsp.detection_stats` derives both
exactly). With ``n_channels=1`` and no correlation they reduce to the
single-cell formulas (Richards eq. 6.84 for CA; Rohling 1983 for OS).

``CFAR_KINDS`` is the registry: name -> class.

References
----------
Richards, *Fundamentals of Radar Signal Processing*, 2nd ed., sec. 6.5.
Rohling, IEEE Trans. AES-19 (1983).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from radarnode.dsp import detection_stats as stats
from radarnode.errors import ConfigError


def _ring(guard: tuple[int, int], train: tuple[int, int]) -> np.ndarray:
    gd, gr = guard
    td, tr = train
    fd, fr = gd + td, gr + tr
    ring = np.ones((2 * fd + 1, 2 * fr + 1), dtype=bool)
    ring[fd - gd:fd + gd + 1, fr - gr:fr + gr + 1] = False
    return ring


def ring_problem(guard: tuple[int, int], train: tuple[int, int], correlation: tuple[np.ndarray, np.ndarray]
                 ) -> tuple[str, str, tuple[int, int], str] | None:
    """What a CFAR ring of ``guard`` and ``train`` cells (Doppler, range) cannot do with the noise ``correlation``
    (ρ_d, ρ_r) between cells, as (``guard`` or ``train``, the axis, the value, what is allowed), or None: fewer than
    4 training cells, or guard cells that do not cover the correlation length (the training cells would share
    the tested cell's noise)."""
    n_train = int(_ring(guard, train).sum())
    if n_train < 4:
        return "train", "both", tuple(train), f"a ring of at least 4 training cells (this one has {n_train})"
    for axis, rho, g in (("doppler", correlation[0], guard[0]), ("range", correlation[1], guard[1])):
        length = stats.correlation_length(np.asarray(rho))
        if length > g:
            return "guard", axis, tuple(guard), (f"at least {length} guard cells in {axis}: the window correlates "
                                                 f"{axis} bins up to {length} apart")
    return None


@dataclass(frozen=True)
class CfarResult:
    """Detection mask and the noise estimate, both shaped like the power map (doppler, range)."""

    mask: np.ndarray
    noise: np.ndarray
    threshold: np.ndarray


class Cfar:
    """Base class: guard and training cells per axis (doppler, range), and a false-alarm probability.

    Parameters
    ----------
    pfa : float
        False-alarm probability per cell, in (0, 0.5).
    guard, train : (int, int)
        Guard and training cells on each side, (doppler, range).
    n_channels : int
        Channels summed non-coherently into the map (each noise cell is Gamma(N, σ²)).
    correlation : (complex array, complex array), optional
        Noise correlation between bins of the (doppler, range) axes, as
        :func:`radarnode.dsp.detection_stats.noise_correlation` gives it for the
        windows; ``None`` for independent cells. The guard cells must cover its
        length so the cell under test is independent of its training cells.
    """

    name = ""

    def __init__(self, pfa: float = 1e-6, guard: tuple[int, int] = (2, 2), train: tuple[int, int] = (4, 8),
                 n_channels: int = 1, correlation: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        if not (isinstance(pfa, (int, float)) and 0.0 < pfa < 0.5):
            raise ConfigError(f"cfar pfa: value {pfa!r} is not allowed; expected a number in (0, 0.5)")
        for name, pair in (("guard", guard), ("train", train)):
            if len(pair) != 2 or any((not isinstance(v, (int, np.integer))) or v < 0 for v in pair):
                raise ConfigError(f"cfar {name}: value {pair!r} is not allowed; expected two integers >= 0")
        if not isinstance(n_channels, (int, np.integer)) or not 1 <= n_channels <= 4096:
            raise ConfigError(f"cfar n_channels: value {n_channels!r} is not allowed; expected an integer in 1..4096")
        self.pfa = pfa
        self.guard = tuple(int(v) for v in guard)
        self.train = tuple(int(v) for v in train)
        self.n_channels = int(n_channels)
        self.footprint = _ring(self.guard, self.train)
        self.n_train = int(self.footprint.sum())
        if correlation is None:
            span = 2 * max(self.guard[0] + self.train[0], self.guard[1] + self.train[1]) + 3
            delta = np.zeros(span, dtype=np.complex128)
            delta[0] = 1.0
            correlation = (delta, delta)
        self.rho_d, self.rho_r = (np.asarray(c, dtype=np.complex128) for c in correlation)
        problem = ring_problem(self.guard, self.train, (self.rho_d, self.rho_r))
        if problem is not None:
            what, _, value, allowed = problem
            raise ConfigError(f"cfar {what}: value {value!r} is not allowed; expected {allowed}")

    def __call__(self, power: np.ndarray) -> CfarResult:
        if power.ndim != 2:
            raise ConfigError(f"cfar power: shape {power.shape} is not allowed; expected (doppler, range)")
        noise, alpha = self.noise(np.asarray(power, dtype=np.float64))
        threshold = alpha * noise
        return CfarResult(power > threshold, noise, threshold)

    def noise(self, power: np.ndarray) -> tuple[np.ndarray, np.ndarray | float]:  # pragma: no cover - abstract
        """Noise estimate per cell and the threshold factor (per cell where the ring is cut by an edge)."""
        raise NotImplementedError

    def detect(self, power: np.ndarray) -> np.ndarray:
        """The detection mask alone: ``self(power).mask``, bit for bit (a detector may get it more cheaply)."""
        return self(power).mask

    def offsets(self, left: int | None = None, right: int | None = None) -> np.ndarray:
        """(doppler, range) offsets of the full training ring, shape (n_train, 2), or of the ring the range edges cut
        (:func:`radarnode.dsp.detection_stats.ring_offsets`)."""
        return stats.ring_offsets(self.guard, self.train, left, right)


class CellAveragingCfar(Cfar):
    """CA-CFAR: the mean of the training cells times α, α exact for the tested statistic (module docstring)."""

    name = "ca"

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.eigenvalues = self.cut_eigenvalues(None, None)
        self.alpha = self.alpha_for_cut(None, None)                                 # on the mean of the whole ring

    def _eigenvalues(self, offsets: np.ndarray) -> np.ndarray:
        return stats.ring_eigenvalues(offsets, self.rho_d, self.rho_r)

    def cut_eigenvalues(self, left: int | None, right: int | None) -> np.ndarray:
        """The training-ring eigenvalues of the ring :meth:`alpha_for_cut` cuts (``None``: none lost), computed once per
        process for each CFAR configuration and cut, as α is (a 248-cell ring's eigvalsh, about 5 ms, had been
        computed twice: for the eigenvalues and again for α); read-only. A subclass with eigenvalues of its own
        (:meth:`_eigenvalues`) computes its own each time."""
        if type(self)._eigenvalues is not CellAveragingCfar._eigenvalues:
            return self._eigenvalues(self.offsets(left, right))
        return _cut_eigenvalues(self.guard, self.train, self.rho_d.tobytes(), self.rho_r.tobytes(), left, right)

    def alpha_for_cut(self, left: int | None, right: int | None) -> float:
        """α of a ring that loses the range columns beyond ``left`` bins to the left and ``right`` to the right
        (``None``: none lost). Each is a root of the exact false-alarm probability (about 10 ms): computed once per
        process for each CFAR configuration and cut, whichever detector asks (a subclass with eigenvalues of its own,
        :meth:`_eigenvalues`, computes its own each time)."""
        if type(self)._eigenvalues is not CellAveragingCfar._eigenvalues:
            return stats.ca_alpha(self.pfa, self.n_channels, self._eigenvalues(self.offsets(left, right)))
        return _ca_alpha_for_cut(self.pfa, self.n_channels, self.guard, self.train, self.rho_d.tobytes(),
                                 self.rho_r.tobytes(), left, right)

    def _ring_sum(self, x: np.ndarray) -> np.ndarray:
        # ring sum = box sum over guard+training − box sum over the guard: two separable O(n) box filters;
        # zeros beyond the range edges, wrap-around in Doppler
        (gd, gr), (td, tr) = self.guard, self.train
        outer = (2 * (gd + td) + 1, 2 * (gr + tr) + 1)
        inner = (2 * gd + 1, 2 * gr + 1)
        mode = ("wrap", "constant")
        import scipy.ndimage  # imported when first needed: a faster start
        box_o = scipy.ndimage.uniform_filter(x, size=outer, mode=mode, cval=0.0) * (outer[0] * outer[1])
        box_i = scipy.ndimage.uniform_filter(x, size=inner, mode=mode, cval=0.0) * (inner[0] * inner[1])
        return np.maximum(box_o - box_i, 0.0)

    def noise(self, power: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        n_r = power.shape[1]
        key = power.shape
        if getattr(self, "_count_key", None) != key:   # cells and α of each (edge-cut) ring, once per map shape
            reach = self.guard[1] + self.train[1]
            self._count = np.maximum(np.rint(self._ring_sum(np.ones(power.shape))), 1.0)
            cols = np.arange(n_r)
            left, right = np.minimum(cols, reach), np.minimum(n_r - 1 - cols, reach)
            cuts = {(int(a), int(b)) for a, b in zip(left, right)}       # at most 2·reach + 1 ring shapes
            table = {cut: self.alpha_for_cut(*cut) for cut in cuts}
            per_col = np.array([table[(int(a), int(b))] for a, b in zip(left, right)])
            self._alpha = np.broadcast_to(per_col[None, :], power.shape)
            self._count_key = key
        return self._ring_sum(power) / self._count, self._alpha


class OrderedStatisticCfar(Cfar):
    """OS-CFAR: the k-th smallest training cell (k = 3N/4 by default); robust next to other targets."""

    name = "os"

    def __init__(self, *args, rank_fraction: float = 0.75, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        if not 0.0 < rank_fraction <= 1.0:
            raise ConfigError(f"cfar rank_fraction: value {rank_fraction!r} is not allowed; expected (0, 1]")
        self.k = max(1, int(round(rank_fraction * self.n_train)))
        ranked = stats.os_rank_samples(self.n_channels, self.offsets(), self.rho_d, self.rho_r, self.k)
        self.alpha = stats.os_alpha(self.pfa, self.n_channels, ranked)

    def noise(self, power: np.ndarray) -> tuple[np.ndarray, float]:
        # mirrored at the range edges: the order statistic ignores the few strong cells a mirrored target adds
        pad = self.guard[1] + self.train[1]
        padded = np.pad(power, ((0, 0), (pad, pad)), mode="symmetric")
        import scipy.ndimage  # imported when first needed: a faster start
        ranked = scipy.ndimage.rank_filter(padded, self.k - 1, footprint=self.footprint, mode="wrap")
        return ranked[:, pad:padded.shape[1] - pad], self.alpha

    def detect(self, power: np.ndarray) -> np.ndarray:
        """``self(power).mask`` bit for bit, the order statistic taken only where two bounds cannot settle a cell.

        Both bound the k-th smallest of a ring of N cells from below, so a cell not above α times the bound is
        not above α times the order statistic. By counts: where fewer than k ring cells lie below a level c, the
        k-th smallest is at least c (levels an octave apart, from 1/8 to 16 times the map's median; the counts are exact
        integer box sums). By sums: it is at least (S − (N − k)·M)/k, S the ring's sum and M its largest cell (the
        k smallest sum to at least S less the N − k largest, and to at most k times the k-th); S by direct sums,
        whose error of a few hundred ulps of the box's largest cell the bound gives away. The order statistic of
        the cells left comes from a partition of their rings: the values the rank filter selects, so the same
        comparisons. On maps of noise and targets well under one cell in a hundred is left (the rank filter over
        a 128 × 256 map took about 150–270 ms here)."""
        power = np.asarray(power, dtype=np.float64)
        if power.ndim != 2:
            raise ConfigError(f"cfar power: shape {power.shape} is not allowed; expected (doppler, range)")
        import scipy.ndimage  # imported when first needed: a faster start
        (gd, gr), (td, tr) = self.guard, self.train
        fd, pad = gd + td, gr + tr
        m, n = power.shape
        padded = np.pad(power, ((0, 0), (pad, pad)), mode="symmetric")
        inner = slice(pad, padded.shape[1] - pad)
        outer = (2 * fd + 1, 2 * pad + 1)
        k_n, k = self.n_train, self.k

        def box(shape: tuple[int, int]) -> np.ndarray:
            out = scipy.ndimage.correlate1d(padded, np.ones(shape[1]), axis=1, mode="wrap")
            return scipy.ndimage.correlate1d(out, np.ones(shape[0]), axis=0, mode="wrap")[:, inner]

        ring_sum = box(outer) - box((2 * gd + 1, 2 * gr + 1))
        top = scipy.ndimage.maximum_filter(padded, size=outer, mode="wrap")[:, inner]
        bound = (ring_sum - (k_n - k) * top - 1e-12 * outer[0] * outer[1] * top) / k
        median = float(np.median(power))
        if median > 0.0:
            wrapped = np.pad(padded, ((fd, fd), (0, 0)), mode="wrap")      # Doppler wraps: the boxes never do
            for c in median * 2.0 ** np.arange(-3.0, 5.0):
                below = np.zeros((wrapped.shape[0] + 1, wrapped.shape[1] + 1), dtype=np.int32)
                np.cumsum(np.cumsum(wrapped < c, axis=0, dtype=np.int32), axis=1, out=below[1:, 1:])
                count = (below[outer[0]:outer[0] + m, outer[1]:outer[1] + n] - below[:m, outer[1]:outer[1] + n]
                         - below[outer[0]:outer[0] + m, :n] + below[:m, :n])
                a0, a1 = fd - gd, pad - gr                              # the guard box within the outer one
                b0, b1 = a0 + 2 * gd + 1, a1 + 2 * gr + 1
                count -= (below[b0:b0 + m, b1:b1 + n] - below[a0:a0 + m, b1:b1 + n]
                          - below[b0:b0 + m, a1:a1 + n] + below[a0:a0 + m, a1:a1 + n])
                np.maximum(bound, np.where(count < k, c, -np.inf), out=bound)
        mask = np.zeros(power.shape, dtype=bool)
        cand_d, cand_r = np.nonzero(power > self.alpha * bound)
        if cand_d.size:
            off = self.offsets()                                   # (N, 2): doppler, range
            for lo in range(0, cand_d.size, 4096):                 # (chunks of 4096 × N values)
                d, r = cand_d[lo:lo + 4096], cand_r[lo:lo + 4096]
                rows = np.mod(d[:, None] + off[None, :, 0], m)
                vals = padded[rows, r[:, None] + pad + off[None, :, 1]]
                kth = np.partition(vals, k - 1, axis=1)[:, k - 1]
                mask[d, r] = power[d, r] > self.alpha * kth
        return mask


CFAR_KINDS: dict[str, type[Cfar]] = {"ca": CellAveragingCfar, "os": OrderedStatisticCfar}


@functools.lru_cache(maxsize=1024)
def _ca_alpha_for_cut(pfa: float, n_channels: int, guard: tuple[int, int], train: tuple[int, int], rho_d: bytes,
                      rho_r: bytes, left: int | None, right: int | None) -> float:
    """:meth:`CellAveragingCfar.alpha_for_cut` of a CFAR with these settings (correlations: complex128 bytes)."""
    return stats.ca_alpha(pfa, n_channels, _cut_eigenvalues(guard, train, rho_d, rho_r, left, right))


@functools.lru_cache(maxsize=1024)
def _cut_eigenvalues(guard: tuple[int, int], train: tuple[int, int], rho_d: bytes, rho_r: bytes, left: int | None,
                     right: int | None) -> np.ndarray:
    """:meth:`CellAveragingCfar.cut_eigenvalues` of a CFAR with these settings (correlations: complex128 bytes),
    read-only (one array shared by every caller)."""
    correlations = (np.frombuffer(rho, dtype=np.complex128) for rho in (rho_d, rho_r))
    eig = stats.ring_eigenvalues(stats.ring_offsets(guard, train, left, right), *correlations)
    eig.flags.writeable = False
    return eig


def make_cfar(kind: str, **kwargs) -> Cfar:
    if kind not in CFAR_KINDS:
        raise ConfigError(f"cfar kind: value {kind!r} is not allowed; expected one of {', '.join(CFAR_KINDS)}")
    return CFAR_KINDS[kind](**kwargs)
