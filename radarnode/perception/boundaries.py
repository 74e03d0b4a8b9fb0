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
#: the sides in the order of the (2, n) masks: left (+1, y > 0) and right (−1)
SIDES = (+1, -1)
_NO_CURVE = np.zeros((CURVE_SAMPLES, 2))
_LINES = np.zeros(2, dtype=bool)                 # masked_fit's deg2 for two straight lines
_CURVE_ROWS = np.kron(np.eye(2, dtype=bool), np.ones(CURVE_SAMPLES, dtype=bool))   # two curves' samples, in a row


def _linspace(start: float, stop: float) -> np.ndarray:
    """``numpy.linspace(start, stop, CURVE_SAMPLES)``, the same numbers without its generic wrapper."""
    delta = stop - start
    step = delta / (CURVE_SAMPLES - 1)
    y = _CURVE_STEPS / (CURVE_SAMPLES - 1) * delta if step == 0 else _CURVE_STEPS * step
    y += start
    y[-1] = stop
    return y


#: the fits' variable u = (x − FIT_CENTRE_M) / FIT_SCALE_M: within about ±1.5 over the radar's range, so that the
#: normal equations of a quadratic stay well conditioned at 200 m
FIT_CENTRE_M, FIT_SCALE_M = 100.0, 100.0


def powers(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The columns whose masked sums are every moment a fit of y on x up to a quadratic needs: (n, 8) =
    1, u, u², u³, u⁴, y, u·y, u²·y with u = (x − FIT_CENTRE_M)/FIT_SCALE_M."""
    out = np.empty((x.size, 8))
    out[:, 0] = 1.0
    u = out[:, 1]
    np.subtract(x, FIT_CENTRE_M, out=u)
    u /= FIT_SCALE_M
    np.multiply(u, u, out=out[:, 2])
    np.multiply(out[:, 2], u, out=out[:, 3])
    np.multiply(out[:, 2], out[:, 2], out=out[:, 4])
    out[:, 5] = y
    np.multiply(u, y, out=out[:, 6])
    np.multiply(out[:, 2], y, out=out[:, 7])
    return out


def masked_fit(pw: np.ndarray, mask: np.ndarray, deg2: np.ndarray) -> np.ndarray:
    """Least-squares y = c0 + c1·x (+ c2·x²) of the points ``mask`` selects, one fit per row of ``mask``.

    pw: the points' :func:`powers` (n, 8); mask: (S, n) bool, each row with at least 2 points (3 for a
    quadratic); deg2: (S,) bool, a quadratic for the rows where it is set. Returns (S, 3), lowest power first
    (c2 = 0 for a line). Every row's moments are one matrix product (S, n) @ (n, 8); the 2×2 or 3×3 normal
    equations in u are solved in Python numbers: the fits of both road sides cost one numpy call. Accurate to
    about 1e-9 relative for a line over any stretch and for a quadratic over tens of metres (the estimator fits a
    quadratic only over more than 40 m: over 10 m at 200 m it would lose digits to the moments' cancellation).
    """
    mom = (mask.astype(np.float64) @ pw).tolist()
    out = np.zeros((len(mom), 3))
    for k, (n, s1, s2, s3, s4, sy, suy, su2y) in enumerate(mom):
        if n < 2.0:                 # a row with no fit to make (its caller does not use it)
            continue
        if deg2[k]:         # Cramer's rule on [[n, s1, s2], [s1, s2, s3], [s2, s3, s4]]·c = [sy, suy, su2y]
            m11, m12, m22 = s2 * s4 - s3 * s3, s1 * s4 - s2 * s3, s1 * s3 - s2 * s2
            det = n * m11 - s1 * m12 + s2 * m22
            c0 = (sy * m11 - s1 * (suy * s4 - s3 * su2y) + s2 * (suy * s3 - s2 * su2y)) / det
            c1 = (n * (suy * s4 - s3 * su2y) - sy * m12 + s2 * (s1 * su2y - suy * s2)) / det
            c2 = (n * (s2 * su2y - s3 * suy) - s1 * (s1 * su2y - s2 * suy) + sy * m22) / det
        else:
            det = n * s2 - s1 * s1
            c1 = (n * suy - s1 * sy) / det if det > 1e-300 else 0.0
            c0, c2 = (sy - s1 * c1) / n, 0.0
        # back to x: c0 + c1·u + c2·u², u = (x − C)/S
        c, sc = FIT_CENTRE_M, FIT_SCALE_M
        q = c2 / (sc * sc)
        out[k] = (c0 - c1 * c / sc + q * c * c, c1 / sc - 2.0 * q * c, q)
    return out


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
        px, py = self._to_sensor(np.concatenate(self._points))
        ahead = px > 0.0
        px, py = px[ahead], py[ahead]
        speed = math.hypot(vx, vy)
        kappa = yaw_rate_rps / speed if speed > 1.0 else 0.0
        py -= 0.5 * kappa * px * px          # straighten along the predicted path
        self._cycle += 1
        sides = np.stack([py > 0.5, py < -0.5])                 # (2, n): left, right
        found = [UNAVAILABLE, UNAVAILABLE]
        if self._cycle % self.reacquire_cycles:                  # the full search runs every reacquire_cycles
            found = self._follow(px, py, sides, kappa)
        for k, sign in enumerate(SIDES):
            if not found[k].valid:
                found[k] = self._side(px[sides[k]], py[sides[k]], kappa)
            self._curves[sign] = self._curve(found[k]) if found[k].valid else None
        self.left, self.right = found
        if not self.left.valid and not self.right.valid and len(self._points) >= self.cycles:
            self._points = self._points[-1:]         # restart the search (seed 002)
        return self.left, self.right

    def _curve(self, b: Boundary) -> np.ndarray:
        """Samples of a boundary (sensor frame, as reported) in the odometry frame, shape (CURVE_SAMPLES, 2)."""
        x = _linspace(b.range_start_m, b.range_end_m)
        return self._to_odometry(x, b.y_at(x))

    def _follow(self, px: np.ndarray, py: np.ndarray, sides: np.ndarray, kappa: float) -> list[Boundary]:
        """Both sides' boundaries near last cycle's: each curve moved into this frame and straightened, its
        inliers fitted (UNAVAILABLE for a side that had none or lost it). The two sides in one pass each."""
        curves = [self._curves[sign] for sign in SIDES]
        follow = np.array([cv is not None for cv in curves])
        if not follow.any():
            return [UNAVAILABLE, UNAVAILABLE]
        cx, cy = self._to_sensor(np.concatenate([cv if cv is not None else _NO_CURVE for cv in curves]))
        cx, cy = cx.reshape(2, CURVE_SAMPLES), cy.reshape(2, CURVE_SAMPLES)
        cy -= 0.5 * kappa * cx * cx
        follow &= (np.add.reduce(sides, axis=1) >= 4) & (np.ptp(cx, axis=1) > 0.0)
        # the line is re-fitted to the points within band_m of it until the inliers settle (a few passes):
        # starting from the prediction, the gate centres itself on the points instead of on last cycle's error.
        # A side whose inliers settled keeps them in the passes left (the fit of a settled set is the same line)
        line = masked_fit(powers(cx.ravel(), cy.ravel()), _CURVE_ROWS, _LINES)
        pw = powers(px, py)                              # the points' moments, for every fit of this cycle
        inliers = sides & (np.abs(py - (line[:, :1] + line[:, 1:2] * px)) <= self.band_m)
        for _ in range(FOLLOW_PASSES):
            follow &= np.add.reduce(inliers, axis=1) >= 4
            if not follow.any():
                return [UNAVAILABLE, UNAVAILABLE]
            inliers &= follow[:, None]
            line = masked_fit(pw, inliers, _LINES)
            again = sides & follow[:, None] & (np.abs(py - (line[:, :1] + line[:, 1:2] * px)) <= self.band_m)
            if not (again ^ inliers).any():
                break
            inliers = again
        return self._fit(px, py, inliers, follow, kappa, pw)

    def _side(self, x: np.ndarray, y: np.ndarray, kappa: float) -> Boundary:
        """The nearest strong near-longitudinal Hough line among a side's points (straightened frame), fitted."""
        if x.size < 4:
            return UNAVAILABLE
        acc = accumulate(x, y, self.grid)
        # (a line with less than half the strongest's votes is never taken: only the strong ones are searched for)
        lines = strongest_lines(acc, self.grid, max_lines=3, min_votes=4.0, min_fraction=0.5)
        if not lines:
            return UNAVAILABLE
        # the boundary is the nearest strong line on this side (a line of parked cars further out is not)
        sin_t = np.array([math.sin(ln.theta_rad) for ln in lines])
        offsets = np.array([ln.rho_m for ln in lines]) / np.where(np.abs(sin_t) > 1e-6, sin_t, 1e-6)
        votes = np.array([ln.votes for ln in lines])
        strong = votes >= 0.5 * votes.max()
        best = lines[int(np.argmin(np.where(strong, np.abs(offsets), np.inf)))]
        inliers = np.abs(best.distance_m(x, y)) <= self.band_m
        return self._fit(x, y, inliers[None, :], np.ones(1, dtype=bool), kappa)[0]

    def _fit(self, x: np.ndarray, y: np.ndarray, inliers: np.ndarray, use: np.ndarray, kappa: float,
             pw: np.ndarray | None = None) -> list[Boundary]:
        """Seed 002's gap rule on each row's inliers (``inliers`` (S, n), rows where ``use``), then
        y = c0 + c1·x (+ c2·x²) with the path curvature added back; one Boundary per row (``pw``: the points'
        :func:`powers`, if known)."""
        count = np.add.reduce(inliers, axis=1)
        use = use & (count >= 4)
        if not use.any():
            return [UNAVAILABLE] * inliers.shape[0]
        x_min = np.minimum.reduce(np.where(inliers, x, np.inf), axis=1)
        x_max = np.maximum.reduce(np.where(inliers, x, -np.inf), axis=1)
        start = np.maximum(np.where(use, x_min, 0.0), 0.0)
        # seed 002: M cross-sections along x, at most k of them without a boundary point
        cell = np.floor((x - start[:, None]) / self.section_m)
        take = inliers & (cell < self.sections)
        cell += (np.arange(inliers.shape[0]) * self.sections)[:, None]        # each row's own sections
        present = np.bincount(cell[take].astype(np.intp), minlength=inliers.shape[0] * self.sections)
        present = (present.reshape(-1, self.sections) > 0).tolist()
        span = x_max - x_min
        deg2 = (span > 40.0) & (count >= 8)
        ok, seen = [], []
        for k, p in enumerate(present):
            reach = max((j + 1 for j, q in enumerate(p) if q), default=0)
            seen.append(sum(p[:reach]))
            missing = (reach - seen[k]) + max(0, self.sections - reach - self.max_missing)
            ok.append(bool(use[k]) and missing <= self.max_missing and reach >= 2)
        if not any(ok):
            return [UNAVAILABLE] * inliers.shape[0]
        ok = np.array(ok)
        coef = masked_fit(powers(x, y) if pw is None else pw, inliers, deg2 & ok)
        out = []
        for k in range(len(present)):
            if not ok[k]:
                out.append(UNAVAILABLE)
                continue
            c0, c1, c2 = coef[k].tolist()
            out.append(Boundary(True, c0, math.atan(c1), 2.0 * c2 + kappa, float(start[k]), float(x_max[k]),
                                seen[k] / self.sections))
        return out
