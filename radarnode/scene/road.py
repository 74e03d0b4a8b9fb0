"""The road's reference line: straight, arc and clothoid segments, as OpenDRIVE's plan view describes a road.

The reference line is the centre of the ego lane. Along it, the curvature κ(s) is piecewise linear in the
station s (metres from the ego's start): constant on a straight (0) or an arc, linear from
``curvature_start_1pm`` to ``curvature_end_1pm`` on a clothoid (Euler spiral). Before the first segment the
line continues with the first segment's starting curvature, after the last with the last one's end curvature
(a road given as one constant curvature is one arc in both directions). The heading is the integral of κ and
the position the integral of (cos θ, sin θ):

    θ(s) = θ_i + κ_i·u + c_i·u²/2,   x + j·y = x_i + j·y_i + ∫₀ᵘ exp(j·θ(t)) dt,   u = s − s_i

with (x_i, y_i, θ_i, κ_i, c_i) the pose, curvature and curvature rate at the start of the table interval i that
holds s. The table is built once: the segment boundaries plus a point every :data:`TABLE_STEP_M` inside each
segment. Within an interval the integral is exact for a constant curvature (the chord of an arc) and a
5-point Gauss–Legendre quadrature otherwise (over ≤ 2 m of a clothoid the phase is a quadratic of at most
0.1 rad: the quadrature's error is below 1e-12 m). Every query is a ``searchsorted`` and a handful of numpy
operations over all its points, whatever their shape.

Road coordinates (s, d) — d to the left of the reference line — map to the world by

    x = X(s) − d·sin θ(s),   y = Y(s) + d·cos θ(s).

The world frame has its origin at the reference line's station 0, x along the road's initial direction.
"""

from __future__ import annotations

import numpy as np

TABLE_STEP_M = 2.0                 # the longest table interval inside a clothoid
_GL_X, _GL_W = np.polynomial.legendre.leggauss(5)


class RoadGeometry:
    """Station → pose of the reference line, built once from segments.

    Parameters
    ----------
    segments : sequence of (length_m, curvature_start_1pm, curvature_end_1pm)
        In order from station 0; a straight is (L, 0, 0), an arc (L, κ, κ), a clothoid (L, κ0, κ1).
    curvature_1pm : float
        With no segments: one arc of this curvature everywhere (0: a straight road).
    """

    def __init__(self, segments=(), curvature_1pm: float = 0.0) -> None:
        segs = [(float(length), float(k0), float(k1)) for length, k0, k1 in segments]
        self.straight = all(k0 == 0.0 and k1 == 0.0 for _, k0, k1 in segs) and (bool(segs) or curvature_1pm == 0.0)
        if not segs:
            segs = [(0.0, float(curvature_1pm), float(curvature_1pm))]
        # table intervals: each inside one segment, at most TABLE_STEP_M long where the curvature changes
        starts, kappa, rate = [], [], []
        s0 = 0.0
        for length, k0, k1 in segs:
            if length <= 0.0:
                continue
            c = (k1 - k0) / length
            n = max(1, int(np.ceil(length / TABLE_STEP_M))) if c != 0.0 else 1
            u = np.arange(n) * (length / n)
            starts.append(s0 + u)
            kappa.append(k0 + c * u)
            rate.append(np.full(n, c))
            s0 += length
        self.length_m = s0
        k_first, k_last = segs[0][1], segs[-1][2]
        # interval 0 lies before station 0 and the last beyond the end: arcs of the end curvatures
        inner_s = np.concatenate(starts) if starts else np.zeros(0)
        self._s = np.concatenate([[-np.inf], inner_s, [s0]])
        self._k = np.concatenate([[k_first], np.concatenate(kappa) if kappa else [], [k_last]])
        self._c = np.concatenate([[0.0], np.concatenate(rate) if rate else [], [0.0]])
        self._start = np.where(np.isfinite(self._s), self._s, 0.0)   # the interval before station 0 is anchored there
        # poses at the interval starts, integrated interval by interval (once)
        m = inner_s.size
        th = np.zeros(m + 2)
        z = np.zeros(m + 2, dtype=np.complex128)
        if m:
            lengths = np.diff(self._s[1:])                              # intervals 1 … m
            k_in, c_in = self._k[1:-1], self._c[1:-1]
            th[2:] = np.cumsum(k_in * lengths + 0.5 * c_in * lengths ** 2)
            z[2:] = np.cumsum(_increment(th[1:-1], k_in, c_in, lengths))
        self._x, self._y, self._th = z.real.copy(), z.imag.copy(), th

    def _locate(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        i = np.searchsorted(self._s, s, side="right") - 1
        i = np.clip(i, 0, self._s.size - 1)
        return i, s - self._start[i]

    def curvature(self, s) -> np.ndarray:
        """κ at station ``s`` (1/m, left positive); any shape."""
        s = np.asarray(s, dtype=np.float64)
        i, u = self._locate(s)
        return self._k[i] + self._c[i] * u

    def heading(self, s) -> np.ndarray:
        """Heading of the reference line at ``s`` (rad, world frame)."""
        s = np.asarray(s, dtype=np.float64)
        i, u = self._locate(s)
        return self._th[i] + self._k[i] * u + 0.5 * self._c[i] * u * u

    def pose(self, s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World position and heading of the reference line at stations ``s`` (any shape)."""
        s = np.asarray(s, dtype=np.float64)
        if self.straight:
            return s.copy(), np.zeros(s.shape), np.zeros(s.shape)
        i, u = self._locate(s)
        k, c, th = self._k[i], self._c[i], self._th[i]
        z = _increment(th, k, c, u)
        return self._x[i] + z.real, self._y[i] + z.imag, th + k * u + 0.5 * c * u * u

    def to_world(self, s, d) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World position and road heading at road coordinates (s, d)."""
        x, y, th = self.pose(s)
        d = np.asarray(d, dtype=np.float64)
        if self.straight:
            return x, y + d, th
        return x - d * np.sin(th), y + d * np.cos(th), th

    def lane_length(self, s0, s1, d) -> np.ndarray:
        """Length of the line at lateral offset ``d`` from station ``s0`` to ``s1``: ∫(1 − κ·d) ds."""
        s0, s1 = np.asarray(s0, dtype=np.float64), np.asarray(s1, dtype=np.float64)
        if self.straight:
            return s1 - s0
        return (s1 - s0) - np.asarray(d, dtype=np.float64) * (self.heading(s1) - self.heading(s0))


def _increment(th0: np.ndarray, k: np.ndarray, c: np.ndarray, u: np.ndarray) -> np.ndarray:
    """∫₀ᵘ exp(j(θ0 + k·t + c·t²/2)) dt: exact for c = 0 (an arc's chord), 5-point Gauss–Legendre otherwise."""
    th0, k, c, u = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64) for a in (th0, k, c, u)))
    half = 0.5 * k * u
    arc = u * np.sinc(half / np.pi) * np.exp(1j * (th0 + half))
    if not np.any(c):
        return arc
    t = 0.5 * u[..., None] * (1.0 + _GL_X)
    gl = 0.5 * u * np.sum(_GL_W * np.exp(1j * (th0[..., None] + k[..., None] * t + 0.5 * c[..., None] * t * t)),
                          axis=-1)
    return np.where(c != 0.0, gl, arc)


__all__ = ["RoadGeometry", "TABLE_STEP_M"]
