"""Two-dimensional CFAR detectors over a range–Doppler power map.

Each detector estimates the noise level in a ring of training cells around
every cell (guard cells excluded) and compares the cell against a threshold
set for a false-alarm probability. Doppler wraps around (it is circular);
range does not: near the first and last range bins the CA ring is one-sided
and its threshold factor is set for the cells it still holds (mirroring the
map would put a target near the edge into its own training cells); OS-CFAR
mirrors, since its order statistic ignores those few cells.

``CFAR_KINDS`` is the registry: name -> class.

References
----------
Richards, *Fundamentals of Radar Signal Processing*, 2nd ed., sec. 6.5:
cell-averaging (eq. 6.84: α = N(Pfa^(−1/N) − 1)) and ordered-statistic CFAR
(Pfa = Π_{i=0}^{k−1} (N−i)/(N−i+α), Rohling 1983).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.ndimage
import scipy.optimize

from radarnode.errors import ConfigError


def _ring(guard: tuple[int, int], train: tuple[int, int]) -> np.ndarray:
    gd, gr = guard
    td, tr = train
    fd, fr = gd + td, gr + tr
    ring = np.ones((2 * fd + 1, 2 * fr + 1), dtype=bool)
    ring[fd - gd:fd + gd + 1, fr - gr:fr + gr + 1] = False
    return ring


@dataclass(frozen=True)
class CfarResult:
    """Detection mask and the noise estimate, both shaped like the power map (doppler, range)."""

    mask: np.ndarray
    noise: np.ndarray
    threshold: np.ndarray


class Cfar:
    """Base class: guard and training cells per axis (doppler, range), and a false-alarm probability."""

    name = ""

    def __init__(self, pfa: float = 1e-6, guard: tuple[int, int] = (2, 2), train: tuple[int, int] = (4, 8)) -> None:
        if not 0.0 < pfa < 0.5:
            raise ConfigError(f"cfar pfa: value {pfa!r} is not allowed; expected a number in (0, 0.5)")
        for name, pair in (("guard", guard), ("train", train)):
            if len(pair) != 2 or any((not isinstance(v, (int, np.integer))) or v < 0 for v in pair):
                raise ConfigError(f"cfar {name}: value {pair!r} is not allowed; expected two integers >= 0")
        self.pfa = pfa
        self.guard = tuple(int(v) for v in guard)
        self.train = tuple(int(v) for v in train)
        self.footprint = _ring(self.guard, self.train)
        self.n_train = int(self.footprint.sum())
        if self.n_train < 4:
            raise ConfigError(f"cfar train: value {train!r} gives {self.n_train} training cells; expected >= 4")

    def __call__(self, power: np.ndarray) -> CfarResult:
        if power.ndim != 2:
            raise ConfigError(f"cfar power: shape {power.shape} is not allowed; expected (doppler, range)")
        noise, alpha = self.noise(np.asarray(power, dtype=np.float64))
        threshold = alpha * noise
        return CfarResult(power > threshold, noise, threshold)

    def noise(self, power: np.ndarray) -> tuple[np.ndarray, np.ndarray | float]:  # pragma: no cover - abstract
        """Noise estimate per cell and the threshold factor (per cell where the ring is cut by an edge)."""
        raise NotImplementedError


class CellAveragingCfar(Cfar):
    """CA-CFAR: the mean of the training cells, threshold α = N(Pfa^(−1/N) − 1)."""

    name = "ca"

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        n = self.n_train
        self.alpha = n * (self.pfa ** (-1.0 / n) - 1.0)   # applied to the mean of the training cells

    def _ring_sum(self, x: np.ndarray) -> np.ndarray:
        # ring sum = box sum over guard+training − box sum over the guard: two separable O(n) box filters;
        # zeros beyond the range edges, wrap-around in Doppler
        (gd, gr), (td, tr) = self.guard, self.train
        outer = (2 * (gd + td) + 1, 2 * (gr + tr) + 1)
        inner = (2 * gd + 1, 2 * gr + 1)
        mode = ("wrap", "constant")
        box_o = scipy.ndimage.uniform_filter(x, size=outer, mode=mode, cval=0.0) * (outer[0] * outer[1])
        box_i = scipy.ndimage.uniform_filter(x, size=inner, mode=mode, cval=0.0) * (inner[0] * inner[1])
        return np.maximum(box_o - box_i, 0.0)

    def noise(self, power: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        shape = power.shape[1]
        key = (power.shape[0], shape)
        if getattr(self, "_count_key", None) != key:   # cells in each (edge-cut) ring, once per map shape
            count = np.rint(self._ring_sum(np.ones(power.shape)))
            self._count = np.maximum(count, 1.0)
            self._alpha = self._count * (self.pfa ** (-1.0 / self._count) - 1.0)
            self._count_key = key
        return self._ring_sum(power) / self._count, self._alpha


class OrderedStatisticCfar(Cfar):
    """OS-CFAR: the k-th smallest training cell (k = 3N/4 by default); robust next to other targets."""

    name = "os"

    def __init__(self, *args, rank_fraction: float = 0.75, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        if not 0.0 < rank_fraction <= 1.0:
            raise ConfigError(f"cfar rank_fraction: value {rank_fraction!r} is not allowed; expected (0, 1]")
        n = self.n_train
        self.k = max(1, int(round(rank_fraction * n)))
        i = np.arange(self.k)

        def log_pfa(alpha: float) -> float:
            return float(np.sum(np.log(n - i) - np.log(n - i + alpha))) - np.log(self.pfa)

        self.alpha = scipy.optimize.brentq(log_pfa, 1e-9, 1e9)

    def noise(self, power: np.ndarray) -> tuple[np.ndarray, float]:
        # mirrored at the range edges: the order statistic ignores the few strong cells a mirrored target adds
        pad = self.guard[1] + self.train[1]
        padded = np.pad(power, ((0, 0), (pad, pad)), mode="symmetric")
        ranked = scipy.ndimage.rank_filter(padded, self.k - 1, footprint=self.footprint, mode="wrap")
        return ranked[:, pad:padded.shape[1] - pad], self.alpha


CFAR_KINDS: dict[str, type[Cfar]] = {"ca": CellAveragingCfar, "os": OrderedStatisticCfar}


def make_cfar(kind: str, **kwargs) -> Cfar:
    if kind not in CFAR_KINDS:
        raise ConfigError(f"cfar kind: value {kind!r} is not allowed; expected one of {', '.join(CFAR_KINDS)}")
    return CFAR_KINDS[kind](**kwargs)
