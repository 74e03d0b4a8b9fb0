"""Road boundaries from stationary radar returns by the Hough transform (seed 002).

Every cycle the stationary detections (ego-motion compensated radial speed
below ``STATIONARY_MPS``) are added to an accumulator of the last ``cycles``
cycles, kept in an odometry frame that the ego's speed and yaw rate move;
the accumulated points are brought into the current sensor frame and
straightened by the ego's predicted path (curvature yaw rate / speed, so a
boundary of a bend that the ego follows becomes a straight line); the Hough
transform (``radarnode.dsp.hough``) finds the strongest near-longitudinal
line on each side of the path, and a quadratic fit on the line's inliers,
with the path curvature added back, gives offset, heading and curvature:
y(x) = c0 + c1·x + c2·x², curvature ≈ 2·c2.

Seed 002's gap rule: the valid stretch is cut into ``sections`` (M) cross-
sections; a boundary with more than ``max_missing`` (k) sections without a
point is unavailable and its side's search restarts (the accumulated points
of that side are dropped).

Once a boundary is found it is followed, as production road-boundary
estimators do: its curve, kept in the odometry frame, is moved into the new
sensor frame, the points within ``band_m`` of it are its inliers and the fit
is redone on them. The Hough search runs again when the boundary is lost and
every ``reacquire_cycles`` cycles (a nearer line, a new guardrail), so the
accumulator is built a few times a second instead of twice a cycle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radarnode.dsp.hough import HoughGrid, accumulate, strongest_lines

STATIONARY_MPS = 1.0
#: samples of a followed boundary's curve (odometry frame)
CURVE_SAMPLES = 12
#: at most this many re-fits of a followed boundary's line to its inliers
FOLLOW_PASSES = 2
_CURVE_STEPS = np.arange(CURVE_SAMPLES, dtype=np.float64)


def _linspace(start: float, stop: float) -> np.ndarray:
    """``numpy.linspace(start, stop, CURVE_SAMPLES)``, the same numbers without its generic wrapper."""
    delta = stop - start
    step = delta / (CURVE_SAMPLES - 1)
    y = _CURVE_STEPS / (CURVE_SAMPLES - 1) * delta if step == 0 else _CURVE_STEPS * step
    y += start
    y[-1] = stop
    return y


def polyfit(x: np.ndarray, y: np.ndarray, deg: int) -> np.ndarray:
    """Least-squares polynomial coefficients, lowest power first (deg 1 or 2): the normal equations in a centred,
    scaled variable (well conditioned at 200 m), a fraction of numpy.polynomial's cost for a few hundred points."""
    # (the means as sum / n: what ndarray.mean computes, without its Python-level wrapper: this runs ~8 times a cycle)
    xm = float(np.add.reduce(x)) / x.size
    t = x - xm
    xs = max(float(np.maximum.reduce(np.abs(t))), 1e-9)
    t /= xs
    if deg == 1:            # closed form: slope = cov/var
        ym = float(np.add.reduce(y)) / y.size
        slope = float(np.dot(t, y - ym)) / max(float(np.dot(t, t)), 1e-300) / xs
        return np.array([ym - slope * xm, slope])
    powers = np.empty((t.size, 3))                                  # numpy.vander(t, 3, increasing=True)
    powers[:, 0] = 1.0
    powers[:, 1] = t
    np.multiply(t, t, out=powers[:, 2])
    c = np.linalg.solve(powers.T @ powers, powers.T @ y)
    # back to x: Σ c_k·((x − xm)/xs)^k
    a = c[2] / (xs * xs)
    return np.array([c[0] - c[1] * xm / xs + a * xm * xm, c[1] / xs - 2.0 * a * xm, a])


@dataclass(frozen=True)
class Boundary:
    """One road boundary in the sensor frame: y(x) = offset + tan(heading)·x + curvature·x²/2."""

    valid: bool
    offset_m: float = 0.0
    heading_rad: float = 0.0
    curvature_1pm: float = 0.0
    range_start_m: float = 0.0
    range_end_m: float = 0.0
    confidence: float = 0.0        # fraction of cross-sections with a point, 0..1

    def y_at(self, x_m: np.ndarray) -> np.ndarray:
        return self.offset_m + math.tan(self.heading_rad) * x_m + 0.5 * self.curvature_1pm * x_m * x_m


UNAVAILABLE = Boundary(False)


class RoadBoundaryEstimator:
    """Left and right road boundaries, updated once per radar cycle.

    Parameters
    ----------
    cycles : int
        How many cycles of stationary detections are accumulated.
    sections, max_missing : int
        Seed 002's M cross-sections and k allowed gaps.
    section_m : float
        Length of one cross-section along x.
    band_m : float
        Half-width of the band around a Hough line whose points are its inliers.
    """

    def __init__(self, cycles: int = 10, sections: int = 10, max_missing: int = 3, section_m: float = 8.0,
                 band_m: float = 1.0, max_offset_m: float = 30.0, reacquire_cycles: int = 14) -> None:
        self.cycles = cycles
        self.sections = sections
        self.max_missing = max_missing
        self.section_m = section_m
        self.band_m = band_m
        self.reacquire_cycles = reacquire_cycles
        # only near-longitudinal lines are road boundaries: normals within 30° of the y axis, θ in [60°, 120°)
        # (one continuous range through 90°, where the full [−90°, 90°) grid would split them at its ends)
        full = HoughGrid.make(rho_max_m=max_offset_m + 5.0, rho_step_m=0.25, theta_step_deg=0.5)
        self.grid = HoughGrid(np.radians(np.arange(60.0, 120.0, 0.5)), full.rho_m)
        self._points: list[np.ndarray] = []          # per cycle: (n, 2) in the odometry frame
        self._pose = np.zeros(3)                     # odometry: x, y, heading of the sensor
        self._curves: dict[int, np.ndarray | None] = {+1: None, -1: None}   # followed boundaries, odometry frame
        self._cycle = 0
        self.left = UNAVAILABLE
        self.right = UNAVAILABLE

    def _to_odometry(self, x, y):
        c, s = math.cos(self._pose[2]), math.sin(self._pose[2])
        out = np.empty((np.size(x), 2))
        out[:, 0] = self._pose[0] + c * x - s * y
        out[:, 1] = self._pose[1] + s * x + c * y
        return out

    def _to_sensor(self, pts):
        c, s = math.cos(self._pose[2]), math.sin(self._pose[2])
        dx, dy = pts[:, 0] - self._pose[0], pts[:, 1] - self._pose[1]
        return c * dx + s * dy, -s * dx + c * dy

    def update(self, x_m: np.ndarray, y_m: np.ndarray, range_rate_mps: np.ndarray, dt_s: float,
               sensor_velocity: tuple[float, float], yaw_rate_rps: float) -> tuple[Boundary, Boundary]:
        """Add one cycle's detections (sensor frame; radial speed negative when closing) and re-estimate.

        ``sensor_velocity`` is the sensor's velocity over ground in its own axes, as known from the ego-
        motion input; ``dt_s`` is the time since the previous call.
        """
        # move the odometry pose by the ego motion since the last cycle
        vx, vy = sensor_velocity
        c, s = math.cos(self._pose[2]), math.sin(self._pose[2])
        self._pose += np.array([(c * vx - s * vy) * dt_s, (s * vx + c * vy) * dt_s, yaw_rate_rps * dt_s])
        r = np.maximum(np.hypot(x_m, y_m), 1e-6)
        ground = range_rate_mps + (vx * x_m + vy * y_m) / r
        still = np.abs(ground) < STATIONARY_MPS
        self._points.append(self._to_odometry(x_m[still], y_m[still]))
        self._points = self._points[-self.cycles:]
        px, py = self._to_sensor(np.concatenate(self._points)) if self._points else (np.zeros(0), np.zeros(0))
        ahead = px > 0.0
        px, py = px[ahead], py[ahead]
        speed = math.hypot(vx, vy)
        kappa = yaw_rate_rps / speed if speed > 1.0 else 0.0
        py = py - 0.5 * kappa * px * px          # straighten along the predicted path
        self._cycle += 1
        search = self._cycle % self.reacquire_cycles == 0
        self.left = self._estimate(px, py, +1, kappa, search)
        self.right = self._estimate(px, py, -1, kappa, search)
        if not self.left.valid and not self.right.valid and len(self._points) >= self.cycles:
            self._points = self._points[-1:]         # restart the search (seed 002)
        return self.left, self.right

    def _estimate(self, px: np.ndarray, py: np.ndarray, sign: int, kappa: float, search: bool) -> Boundary:
        """Follow this side's boundary if there is one, else (and when ``search``) look for it by Hough."""
        side = sign * py > 0.5
        x, y = px[side], py[side]
        b = UNAVAILABLE
        if self._curves[sign] is not None and not search:
            b = self._follow(x, y, self._curves[sign], kappa)
        if not b.valid:
            b = self._side(x, y, kappa)
        self._curves[sign] = self._curve(b, kappa) if b.valid else None
        return b

    def _curve(self, b: Boundary, kappa: float) -> np.ndarray:
        """Samples of a boundary (sensor frame, as reported) in the odometry frame, shape (CURVE_SAMPLES, 2)."""
        x = _linspace(b.range_start_m, b.range_end_m)
        return self._to_odometry(x, b.y_at(x))

    def _follow(self, x: np.ndarray, y: np.ndarray, curve: np.ndarray, kappa: float) -> Boundary:
        """The boundary near last cycle's: its curve moved into this frame and straightened, its inliers fitted."""
        cx, cy = self._to_sensor(curve)
        cy = cy - 0.5 * kappa * cx * cx
        if x.size < 4 or np.maximum.reduce(cx) - np.minimum.reduce(cx) <= 0.0:
            return UNAVAILABLE
        # the line is re-fitted to the points within band_m of it until the inliers settle (a few passes):
        # starting from the prediction, the gate centres itself on the points instead of on last cycle's error
        c0, c1 = polyfit(cx, cy, 1)
        inliers = np.abs(y - (c0 + c1 * x)) <= self.band_m
        for _ in range(FOLLOW_PASSES):
            if np.count_nonzero(inliers) < 4:
                return UNAVAILABLE
            c0, c1 = polyfit(x[inliers], y[inliers], 1)
            again = np.abs(y - (c0 + c1 * x)) <= self.band_m
            if not (again ^ inliers).any():
                break
            inliers = again
        return self._fit(x[inliers], y[inliers], kappa)

    def _side(self, x: np.ndarray, y: np.ndarray, kappa: float) -> Boundary:
        """The nearest strong near-longitudinal Hough line among a side's points (straightened frame), fitted."""
        if x.size < 4:
            return UNAVAILABLE
        acc = accumulate(x, y, self.grid)
        lines = strongest_lines(acc, self.grid, max_lines=3, min_votes=4.0)
        if not lines:
            return UNAVAILABLE
        # the boundary is the nearest strong line on this side (a line of parked cars further out is not)
        sin_t = np.array([math.sin(ln.theta_rad) for ln in lines])
        offsets = np.array([ln.rho_m for ln in lines]) / np.where(np.abs(sin_t) > 1e-6, sin_t, 1e-6)
        votes = np.array([ln.votes for ln in lines])
        strong = votes >= 0.5 * votes.max()
        best = lines[int(np.argmin(np.where(strong, np.abs(offsets), np.inf)))]
        inliers = np.abs(best.distance_m(x, y)) <= self.band_m
        return self._fit(x[inliers], y[inliers], kappa)

    def _fit(self, xi: np.ndarray, yi: np.ndarray, kappa: float) -> Boundary:
        """Seed 002's gap rule on a boundary's inliers, then y = c0 + c1·x (+ c2·x²) with the path curvature
        added back."""
        if xi.size < 4:
            return UNAVAILABLE
        # seed 002: M cross-sections along x, at most k of them without a boundary point
        x_min, x_max = float(np.minimum.reduce(xi)), float(np.maximum.reduce(xi))
        start = max(0.0, x_min)
        cell = np.floor((xi - start) / self.section_m).astype(np.int64)
        present = (np.bincount(cell[cell < self.sections], minlength=self.sections) > 0).tolist()   # M sections
        reach = max((k + 1 for k, p in enumerate(present) if p), default=0)
        seen = sum(present[:reach])
        missing = (reach - seen) + max(0, self.sections - reach - self.max_missing)
        if missing > self.max_missing or reach < 2:
            return UNAVAILABLE
        span = x_max - x_min
        deg = 2 if span > 40.0 and xi.size >= 8 else 1
        c = polyfit(xi, yi, deg)
        c0, c1 = c[0], c[1]
        c2 = c[2] if deg == 2 else 0.0
        return Boundary(True, float(c0), float(math.atan(c1)), float(2.0 * c2 + kappa), start, x_max,
                        seen / reach * reach / self.sections)
