"""Straight lines in point sets by the Hough transform, vectorised over the points.

Lines in normal form ρ = x·cosθ + y·sinθ, θ in [−90°, 90°), ρ signed. Every
point votes, with an optional weight (e.g. its detection power), for one ρ
cell in every θ column; the votes of all points are accumulated with one
``numpy.bincount`` over the flattened (θ, ρ) index. Peaks are found with
non-maximum suppression so that two parallel boundaries a lane apart stay
two lines.

Reference: seed 002 (road boundaries from stationary radar returns by the
Hough transform); Duda and Hart, "Use of the Hough transformation to detect
lines and curves in pictures", 1972.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radarnode.errors import ConfigError


@dataclass(frozen=True)
class Line:
    """ρ = x·cosθ + y·sinθ; ``votes`` is the accumulated (weighted) vote."""

    theta_rad: float
    rho_m: float
    votes: float

    def distance_m(self, x: np.ndarray, y: np.ndarray) -> np.ndarray:
        """Signed distance of points to the line."""
        return x * np.cos(self.theta_rad) + y * np.sin(self.theta_rad) - self.rho_m


@dataclass(frozen=True)
class HoughGrid:
    """The (θ, ρ) cells of the accumulator."""

    theta_rad: np.ndarray   # shape (n_theta,)
    rho_m: np.ndarray       # shape (n_rho,), cell centres

    @classmethod
    def make(cls, rho_max_m: float, rho_step_m: float = 0.25, theta_step_deg: float = 0.5,
             theta_min_deg: float = -90.0, theta_max_deg: float = 90.0) -> HoughGrid:
        if not rho_max_m > 0 or not rho_step_m > 0 or not theta_step_deg > 0:
            raise ConfigError(f"hough grid: rho_max_m={rho_max_m!r}, rho_step_m={rho_step_m!r}, "
                              f"theta_step_deg={theta_step_deg!r} are not allowed; expected positive numbers")
        if not -90.0 <= theta_min_deg < theta_max_deg <= 90.0:
            raise ConfigError(f"hough grid: theta range [{theta_min_deg}, {theta_max_deg}) is not allowed; "
                              "expected -90 <= min < max <= 90 degrees")
        theta = np.radians(np.arange(theta_min_deg, theta_max_deg, theta_step_deg))
        n_rho = int(np.ceil(rho_max_m / rho_step_m))
        rho = (np.arange(-n_rho, n_rho + 1)) * rho_step_m
        return cls(theta, rho)


#: up to this many candidate cells, :func:`strongest_lines` tests each against its own window; more (a plateau), by a
#: maximum filter over the box that holds them (the same peaks either way)
FEW_CANDIDATES = 16


class Scratch:
    """Two work arrays that :func:`accumulate` reuses from call to call instead of allocating them: the (point, θ)
    cells as float64 and as intp. A caller that accumulates many point sets (the road-boundary search, some 800
    points × 120 θ a call) keeps one; each array is then about 0.8 MB, beyond malloc's mmap threshold, so that a
    fresh pair a call was page-faulted in anew every call (about half the call's time on a 2-core machine)."""

    def __init__(self, share_result: bool = False) -> None:
        self._cell = np.empty(0)
        self._idx = np.empty(0, dtype=np.intp)
        self._votes = np.empty(0)
        self._grid: HoughGrid | None = None         # the grid whose tables are held (grid_tables)
        self._tables: tuple[np.ndarray, np.ndarray] = (np.empty((3, 0)), np.empty(0))
        #: :func:`accumulate` returns the accumulator in this scratch's memory (valid until its next call with it)
        #: instead of a copy: for a caller that reads each accumulator before the next (the road-boundary search:
        #: a new 270 kB array a call, written page by page, was most of the search's time)
        self.share_result = share_result

    def grid_tables(self, grid: HoughGrid) -> tuple[np.ndarray, np.ndarray]:
        """:func:`accumulate`'s tables of a grid, made once while the scratch serves that grid: the (3, n_theta)
        coefficients [cosθ/Δρ, sinθ/Δρ, 1.5 − ρ₀/Δρ] and each θ row's first cell, (n_theta,)."""
        if self._grid is not grid:
            n_t, n_r = grid.theta_rad.size, grid.rho_m.size
            step = grid.rho_m[1] - grid.rho_m[0]
            coef = np.empty((3, n_t))
            coef[0], coef[1], coef[2] = (np.cos(grid.theta_rad) / step, np.sin(grid.theta_rad) / step,
                                         1.5 - grid.rho_m[0] / step)
            self._grid, self._tables = grid, (coef, np.arange(n_t) * (n_r + 2.0))
        return self._tables

    def arrays(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """(n,) float64 and intp views of the work arrays, grown (to 1.5× what is asked) when too small."""
        if self._cell.size < n:
            self._cell = np.empty(n + n // 2)
            self._idx = np.empty(n + n // 2, dtype=np.intp)
        return self._cell[:n], self._idx[:n]

    def votes(self, n: int) -> np.ndarray:
        """(n,) float64 zeros: the accumulator's memory, the same from call to call (zeroed each time)."""
        if self._votes.size != n:
            self._votes = np.zeros(n)
        else:
            self._votes.fill(0.0)
        return self._votes


def accumulate(x: np.ndarray, y: np.ndarray, grid: HoughGrid, weights: np.ndarray | None = None,
               scratch: Scratch | None = None) -> np.ndarray:
    """The Hough accumulator, shape (n_theta, n_rho); points beyond the ρ range vote nowhere. ``scratch``: work
    arrays to reuse (:class:`Scratch`; the result is the same with or without; with ``Scratch(share_result=True)``
    it is held in the scratch's memory, valid until the next call with the same scratch)."""
    x = np.asarray(x, dtype=np.float64)
    y = np.asarray(y, dtype=np.float64)
    if x.shape != y.shape or x.ndim != 1:
        raise ConfigError(f"hough points: shapes {x.shape} and {y.shape} are not allowed; expected two (n,) arrays")
    n_t, n_r = grid.theta_rad.size, grid.rho_m.size
    # a NaN or infinite point votes nowhere
    finite = np.isfinite(x) & np.isfinite(y)
    w = None if weights is None else np.broadcast_to(np.asarray(weights, dtype=np.float64), x.shape)
    if not finite.all():
        x, y = x[finite], y[finite]
        w = None if w is None else w[finite]
    if x.size == 0:
        return np.zeros((n_t, n_r))
    # the cell of every (point, θ) in one matrix product: [x, y, 1] @ [cosθ/Δρ, sinθ/Δρ, 1.5 − ρ₀/Δρ] is the
    # ρ cell counted from 1, plus ½, so that truncation rounds it (a point exactly half a cell between two votes
    # for the upper one); each θ row has a cell before and after the grid (0 and n_rho + 1) that collect the votes
    # falling outside it, so that a clip replaces the masking
    pts = np.empty((x.size, 3))
    pts[:, 0], pts[:, 1], pts[:, 2] = x, y, 1.0
    scratch = scratch or Scratch()
    coef, rows = scratch.grid_tables(grid)
    flat, idx = scratch.arrays(x.size * n_t)
    cell = flat.reshape(x.size, n_t)
    np.matmul(pts, coef, out=cell)                                       # (n, n_theta)
    np.clip(cell, 0.0, n_r + 1.0, out=cell)
    np.add(cell, rows, out=cell)                                         # each θ row's own cells
    np.copyto(idx, flat, casting="unsafe")                               # truncation: every value is ≥ 0
    if w is None:
        # one vote each, added into the scratch's zeroed accumulator (exact: integer sums): the road-boundary search
        # took 0.2 ms a call here to write bincount's new 270 kB result and its conversion to float page by page
        votes = scratch.votes(n_t * (n_r + 2))
        np.add.at(votes, idx, 1.0)
        if not scratch.share_result:
            votes = votes.copy()
    else:
        votes = np.bincount(idx, weights=np.broadcast_to(w[:, None], (x.size, n_t)).ravel(),
                            minlength=n_t * (n_r + 2))
    return votes.reshape(n_t, n_r + 2)[:, 1:-1]


def strongest_lines(acc: np.ndarray, grid: HoughGrid, max_lines: int = 2, min_votes: float = 3.0,
                    suppress_rho_m: float = 1.0, suppress_theta_deg: float = 5.0, min_fraction: float = 0.0
                    ) -> list[Line]:
    """Up to ``max_lines`` accumulator peaks with at least ``min_votes``, strongest first.

    A peak is a cell that no cell within ±``suppress_rho_m`` and ±``suppress_theta_deg`` exceeds; a peak
    taken suppresses that neighbourhood so that one line is not reported twice. With ``min_fraction`` > 0
    only peaks with at least that fraction of the strongest's votes are returned (the same peaks as without it,
    less the weaker ones; the search then looks only at the cells around the strong ones).
    """
    top = acc.max() if acc.size else 0.0
    if acc.size == 0 or top < min_votes:
        return []
    step_r = grid.rho_m[1] - grid.rho_m[0]
    step_t = np.degrees(grid.theta_rad[1] - grid.theta_rad[0]) if grid.theta_rad.size > 1 else 1.0
    half = (max(int(round(suppress_theta_deg / step_t)), 0), max(int(round(suppress_rho_m / step_r)), 0))
    cand = acc >= max(min_votes, min_fraction * top)
    at = np.flatnonzero(cand)             # (row-major)
    if not at.size:                       # (a NaN cell: no strongest line to measure the others by)
        return []
    # a peak is a candidate no cell of whose window exceeds it. A few candidates (a road-boundary search has one to
    # three of 34,000 cells) are each tested against their own window, cut by the accumulator's edge (what the
    # filter's extended edge gives: it repeats cells already in the window); the twenty small passes of the filter
    # were most of the search. More of them (a plateau): the maximum filter over the box that holds the candidates
    # and the cells that can exceed them (half a window beyond); cells further from every candidate are never
    # tested. Where the box is cut by the accumulator's edge the filter extends the edge, as over the whole
    # accumulator; elsewhere its extension reaches only cells more than half a window from every candidate. The
    # same peaks, in the same (row-major) order, either way
    n_r, n_c = acc.shape
    if at.size <= FEW_CANDIDATES:
        ti, ri = np.divmod(at, n_c)
        peak = [acc[max(t - half[0], 0):t + half[0] + 1, max(r - half[1], 0):r + half[1] + 1].max() <= acc[t, r]
                for t, r in zip(ti.tolist(), ri.tolist())]
        ti, ri = ti[peak], ri[peak]
    else:
        cols = at % n_c
        r0, r1 = max(int(at[0]) // n_c - half[0], 0), min(int(at[-1]) // n_c + half[0] + 1, n_r)
        c0, c1 = max(int(cols.min()) - half[1], 0), min(int(cols.max()) + half[1] + 1, n_c)
        box = acc[r0:r1, c0:c1]
        ti, ri = np.nonzero((box >= max_filter(box, half)) & cand[r0:r1, c0:c1])
        ti += r0
        ri += c0
    order = np.argsort(-acc[ti, ri], kind="stable")
    ti, ri = ti[order], ri[order]
    theta, rho, votes = grid.theta_rad[ti], grid.rho_m[ri], acc[ti, ri]
    # strongest first; a peak near one already taken (±suppress_theta_deg and ±suppress_rho_m) is the same line:
    # each line taken strikes its neighbourhood off the candidates at once (a plateau holds a thousand of them)
    free = np.ones(ti.size, dtype=bool)
    lines: list[Line] = []
    while len(lines) < max_lines:
        left = np.flatnonzero(free)
        if not left.size:
            break
        k = left[0]
        lines.append(Line(float(theta[k]), float(rho[k]), float(votes[k])))
        free &= ~((np.abs(np.degrees(theta - lines[-1].theta_rad)) <= suppress_theta_deg)
                  & (np.abs(rho - lines[-1].rho_m) <= suppress_rho_m))
    return lines


def max_filter(a: np.ndarray, half: tuple[int, int]) -> np.ndarray:
    """The maximum over the (2·half[0] + 1) × (2·half[1] + 1) window around each cell of a 2-D array, edges
    extended (what ``scipy.ndimage.maximum_filter(a, size, mode="nearest")`` gives), by doubling windows along
    each axis: a few numpy passes instead of one per window cell."""
    if half == (0, 0):
        return a.copy()
    out = _running_max(_pad_edge(a, half[0], axis=0), 2 * half[0] + 1, axis=0)
    return _running_max(_pad_edge(out, half[1], axis=1), 2 * half[1] + 1, axis=1)


def _pad_edge(a: np.ndarray, h: int, axis: int) -> np.ndarray:
    """``numpy.pad(a, h, mode="edge")`` along one axis of a 2-D array (without its generic wrapper)."""
    if h == 0:
        return a
    if axis == 1:
        return _pad_edge(a.T, h, 0).T
    out = np.empty((a.shape[0] + 2 * h, a.shape[1]), dtype=a.dtype)
    out[h:h + a.shape[0]] = a
    out[:h] = a[0]
    out[h + a.shape[0]:] = a[-1]
    return out


def _running_max(a: np.ndarray, width: int, axis: int) -> np.ndarray:
    """m[i] = max(a[i : i + width]) along ``axis`` (the result is ``width − 1`` shorter there)."""
    n = a.shape[axis] - width + 1

    def cut(x, start, length):
        return x[start:start + length] if axis == 0 else x[:, start:start + length]

    span, m = 1, a                        # m[i] = max(a[i : i + span])
    while 2 * span <= width:
        m = np.maximum(cut(m, 0, m.shape[axis] - span), cut(m, span, m.shape[axis] - span))
        span *= 2
    if span == width:
        return cut(m, 0, n)
    # the window is two overlapping spans: [i, i + span) and [i + width − span, i + width)
    return np.maximum(cut(m, 0, n), cut(m, width - span, n))


def refine(line: Line, x: np.ndarray, y: np.ndarray, band_m: float = 1.0) -> tuple[Line, np.ndarray]:
    """Total-least-squares fit on the points within ``band_m`` of a Hough line; returns (line, inlier mask)."""
    inliers = np.abs(line.distance_m(x, y)) <= band_m
    if inliers.sum() < 2:
        return line, inliers
    px, py = x[inliers], y[inliers]
    mx, my = px.mean(), py.mean()
    cov = np.cov(np.stack([px - mx, py - my]))
    evals, evecs = np.linalg.eigh(cov)
    nx, ny = evecs[:, 0]                        # normal: eigenvector of the smallest eigenvalue
    theta = np.arctan2(ny, nx)
    if theta >= np.pi / 2:                      # keep θ in [−90°, 90°)
        theta -= np.pi
    elif theta < -np.pi / 2:
        theta += np.pi
    rho = mx * np.cos(theta) + my * np.sin(theta)
    return Line(float(theta), float(rho), float(inliers.sum())), inliers
