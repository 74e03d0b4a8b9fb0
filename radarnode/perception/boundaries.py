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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radarnode.dsp.hough import HoughGrid, accumulate, strongest_lines

STATIONARY_MPS = 1.0


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
                 band_m: float = 1.0, max_offset_m: float = 30.0) -> None:
        self.cycles = cycles
        self.sections = sections
        self.max_missing = max_missing
        self.section_m = section_m
        self.band_m = band_m
        self.grid = HoughGrid.make(rho_max_m=max_offset_m + 5.0, rho_step_m=0.25, theta_step_deg=0.5,
                                   theta_min_deg=-90.0, theta_max_deg=90.0)
        # only near-longitudinal lines are road boundaries: |θ| ≥ 60° (within 30° of the x axis)
        self._longitudinal = np.abs(np.degrees(self.grid.theta_rad)) >= 60.0
        self._points: list[np.ndarray] = []          # per cycle: (n, 2) in the odometry frame
        self._pose = np.zeros(3)                     # odometry: x, y, heading of the sensor
        self.left = UNAVAILABLE
        self.right = UNAVAILABLE

    def _to_odometry(self, x, y):
        c, s = math.cos(self._pose[2]), math.sin(self._pose[2])
        return np.stack([self._pose[0] + c * x - s * y, self._pose[1] + s * x + c * y], axis=1)

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
        self.left = self._side(px, py, +1, kappa)
        self.right = self._side(px, py, -1, kappa)
        if not self.left.valid and not self.right.valid and len(self._points) >= self.cycles:
            self._points = self._points[-1:]         # restart the search (seed 002)
        return self.left, self.right

    def _side(self, px: np.ndarray, py: np.ndarray, sign: int, kappa: float) -> Boundary:
        side = sign * py > 0.5
        x, y = px[side], py[side]
        if x.size < 4:
            return UNAVAILABLE
        acc = accumulate(x, y, self.grid)
        acc[~self._longitudinal] = 0.0
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
        xi, yi = x[inliers], y[inliers]
        if xi.size < 4:
            return UNAVAILABLE
        # seed 002: M cross-sections along x, at most k of them without a boundary point
        start = max(0.0, float(xi.min()))
        edges = start + self.section_m * np.arange(self.sections + 1)
        counts = np.histogram(xi, bins=edges)[0]
        present = counts > 0
        reach = int(np.max(np.flatnonzero(present))) + 1 if present.any() else 0
        missing = int((~present[:reach]).sum()) + max(0, self.sections - reach - self.max_missing)
        if missing > self.max_missing or reach < 2:
            return UNAVAILABLE
        span = float(xi.max() - xi.min())
        deg = 2 if span > 40.0 and xi.size >= 8 else 1
        coef = np.polyfit(xi, yi, deg)
        c2 = coef[0] if deg == 2 else 0.0
        c1, c0 = coef[-2], coef[-1]
        return Boundary(True, float(c0), float(math.atan(c1)), float(2.0 * c2 + kappa), start, float(xi.max()),
                        float(present[:reach].mean() * reach / self.sections))
