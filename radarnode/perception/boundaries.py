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

from radarnode.dsp.hough import HoughGrid, Scratch, accumulate, strongest_lines

STATIONARY_MPS = 1.0
#: a followed boundary is predicted by the least-squares line through this many points evenly spaced over its
#: reported stretch (``numpy.linspace``'s), moved into the new frame and straightened: computed from the sums below
CURVE_SAMPLES = 12
#: at most this many re-fits of a followed boundary's line to its inliers
FOLLOW_PASSES = 2
_LINES = np.zeros(2, dtype=bool)                 # solve's deg2 for two straight lines
#: Σ jᵏ over the samples' centred indices j = i − (CURVE_SAMPLES − 1)/2, k = 0, 2, 4, 6 (the odd sums are 0); exact
_J_SUMS = [float(sum((i - (CURVE_SAMPLES - 1) / 2) ** k for i in range(CURVE_SAMPLES)))
           for k in (0, 2, 4, 6)]


#: the fits' variable u = (x − FIT_CENTRE_M) / FIT_SCALE_M: within about ±1.5 over the radar's range, so that the
#: normal equations of a quadratic stay well conditioned at 200 m
FIT_CENTRE_M, FIT_SCALE_M = 100.0, 100.0


def powers(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The rows whose masked sums are every moment a fit of y on x up to a quadratic needs: (8, n) =
    1, u, y, u², u³, u⁴, u·y, u²·y with u = (x − FIT_CENTRE_M)/FIT_SCALE_M (a row each, so that every product is
    one pass over contiguous memory; the first three rows are also what a line's residual y − a − b·u needs)."""
    out = np.empty((8, x.size))
    out[0] = 1.0
    u = out[1]
    np.subtract(x, FIT_CENTRE_M, out=u)
    u /= FIT_SCALE_M
    out[2] = y
    u2 = out[3]
    np.multiply(u, u, out=u2)
    np.multiply(u2, u, out=out[4])
    np.multiply(u2, u2, out=out[5])
    np.multiply(u, y, out=out[6])
    np.multiply(u2, y, out=out[7])
    return out


def masked_fit(pw: np.ndarray, mask: np.ndarray, deg2: np.ndarray) -> np.ndarray:
    """Least-squares y = c0 + c1·x (+ c2·x²) of the points ``mask`` selects, one fit per row of ``mask``.

    pw: the points' :func:`powers` (8, n); mask: (S, n) bool, each row with at least 2 points (3 for a
    quadratic); deg2: (S,) bool, a quadratic for the rows where it is set. Returns (S, 3), lowest power first
    (c2 = 0 for a line). Every row's moments are one matrix product (S, n) @ (n, 8) (:func:`moments`, with the powers' rows as
    columns); the 2×2 or
    3×3 normal equations in u are solved in Python numbers (:func:`solve`): the fits of both road sides cost one
    numpy call. Accurate to about 1e-9 relative for a line over any stretch and for a quadratic over tens of
    metres (the estimator fits a quadratic only over more than 40 m: over 10 m at 200 m it would lose digits to
    the moments' cancellation).
    """
    return solve(moments(pw, mask), deg2)


def moments(pw: np.ndarray, mask: np.ndarray) -> list[list[float]]:
    """The sums of :func:`powers`' columns over the points each row of ``mask`` (S, n) selects: S lists of 8."""
    return (mask.astype(np.float64) @ pw.T).tolist()


def solve(mom: list[list[float]], deg2) -> np.ndarray:
    """:func:`masked_fit` from the rows' :func:`moments`."""
    return np.array(solve_x(mom, deg2)).reshape(len(mom), 3)


def solve_x(mom: list[list[float]], deg2) -> list[tuple[float, float, float]]:
    """:func:`solve` in Python numbers: (c0, c1, c2) a row."""
    c, sc = FIT_CENTRE_M, FIT_SCALE_M
    out = []
    for c0, c1, c2 in solve_u(mom, deg2):   # back to x: c0 + c1·u + c2·u², u = (x − C)/S
        q = c2 / (sc * sc)
        out.append((c0 - c1 * c / sc + q * c * c, c1 / sc - 2.0 * q * c, q))
    return out


def solve_u(mom: list[list[float]], deg2) -> list[tuple[float, float, float]]:
    """The fits of :func:`solve` in u = (x − FIT_CENTRE_M)/FIT_SCALE_M: y = c0 + c1·u + c2·u², a tuple a row (zeros
    for a row of fewer than 2 points)."""
    out = []
    for k, (n, s1, sy, s2, s3, s4, suy, su2y) in enumerate(mom):
        if n < 2.0:                 # a row with no fit to make (its caller does not use it)
            out.append((0.0, 0.0, 0.0))
        elif deg2[k]:         # Cramer's rule on [[n, s1, s2], [s1, s2, s3], [s2, s3, s4]]·c = [sy, suy, su2y]
            m11, m12, m22 = s2 * s4 - s3 * s3, s1 * s4 - s2 * s3, s1 * s3 - s2 * s2
            det = n * m11 - s1 * m12 + s2 * m22
            out.append(((sy * m11 - s1 * (suy * s4 - s3 * su2y) + s2 * (suy * s3 - s2 * su2y)) / det,
                        (n * (suy * s4 - s3 * su2y) - sy * m12 + s2 * (s1 * su2y - suy * s2)) / det,
                        (n * (s2 * su2y - s3 * suy) - s1 * (s1 * su2y - s2 * suy) + sy * m22) / det))
        else:
            det = n * s2 - s1 * s1
            c1 = (n * suy - s1 * sy) / det if det > 1e-300 else 0.0
            out.append(((sy - s1 * c1) / n, c1, 0.0))
    return out


def predicted_line(curve: tuple, ox: float, oy: float, c: float, s: float, kappa: float
                   ) -> tuple[float, float] | None:
    """The least-squares line y = a + b·u (u = (x − FIT_CENTRE_M)/FIT_SCALE_M) through a followed boundary's
    CURVE_SAMPLES samples moved into the sensor frame at odometry pose (ox, oy, heading cos c, sin s) and straightened
    by the path curvature ``kappa`` (y − κ·x²/2); None for a curve of no length.

    ``curve`` as :meth:`RoadBoundaryEstimator._keep_curves` keeps it: (ox0, oy0, c0, s0) the pose it was found at,
    its samples x = m + step·j (j centred) and y = o + t·d + h·d², d = x − m. The move is rigid, so in this frame
    x = a0 + a1·d + a2·d² and the straightened y a quartic in d; the line's sums are those polynomials' moments over
    the samples (the d-sums of odd powers vanish), in closed form: the samples' own least-squares line to rounding,
    for a few dozen operations instead of passes over the samples.
    """
    ox0, oy0, c0, s0, m, step, o, t, h = curve
    ca, sa = c * c0 + s * s0, s * c0 - c * s0              # the rotation from the old frame into this one
    dx, dy = ox0 - ox, oy0 - oy
    e, f = c * dx + s * dy, c * dy - s * dx                 # the old origin in this frame
    a0, a1, a2 = ca * m + sa * o + e, ca + sa * t, sa * h   # x = a0 + a1·d + a2·d²
    b0, b1, b2 = ca * o - sa * m + f, ca * t - sa, ca * h   # y before straightening
    k2 = 0.5 * kappa                                        # straightened y = Σ g_i dⁱ
    g0, g1, g2 = b0 - k2 * a0 * a0, b1 - 2.0 * k2 * a0 * a1, b2 - k2 * (a1 * a1 + 2.0 * a0 * a2)
    g3, g4 = -2.0 * k2 * a1 * a2, -k2 * a2 * a2
    n, j2, j4, j6 = _J_SUMS
    q = step * step
    d2, d4, d6 = j2 * q, j4 * q * q, j6 * q * q * q         # Σ d², Σ d⁴, Σ d⁶
    v4, v6 = d4 - d2 * d2 / n, d6 - d2 * d4 / n             # Σ (d² − d̄²)·d², ·d⁴
    sxx = a1 * a1 * d2 + a2 * a2 * v4                       # Σ (x − x̄)²: x − x̄ = a1·d + a2·(d² − d̄²)
    if not sxx > 0.0:
        return None
    sxy = a1 * (g1 * d2 + g3 * d4) + a2 * (g2 * v4 + g4 * v6)
    mx, my = a0 + a2 * d2 / n, g0 + (g2 * d2 + g4 * d4) / n
    slope = sxy / sxx                     # the line in u: y = (a + b·C) + b·S·u
    return my - slope * mx + slope * FIT_CENTRE_M, slope * FIT_SCALE_M


def _to_odometry(x: np.ndarray, y: np.ndarray, ox, oy, c, s) -> np.ndarray:
    """Sensor-frame points (1-D) into the odometry frame of a sensor at (ox, oy) with heading cos c, sin s:
    x = ox + c·x − s·y, y = oy + s·x + c·y, in that order; shape (2, n), the rows x and y. The pose is numbers (one
    cycle's, :meth:`RoadBoundaryEstimator.update`: an outer product a column) or float64 arrays like x (each point's
    cycle's, :meth:`RoadBoundaryEstimator.update_many`): the same numbers either way."""
    if np.ndim(c) == 0:
        out = np.multiply.outer((c, s), x)
        out += np.array([[ox], [oy]])
        out += np.multiply.outer((-s, c), y)
        return out
    out = np.empty((2, x.size))
    np.multiply(c, x, out=out[0])
    out[0] += ox
    out[0] += np.negative(s) * y
    np.multiply(s, x, out=out[1])
    out[1] += oy
    out[1] += c * y
    return out


def _to_sensor(dx: np.ndarray, dy: np.ndarray, c: float, s: float) -> np.ndarray:
    """Odometry-frame offsets from the sensor into its frame: x = c·dx + s·dy, y = −s·dx + c·dy; shape
    (2, *dx.shape)."""
    out = np.multiply.outer((c, -s), dx)
    out += np.multiply.outer((s, c), dy)
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

    @classmethod
    def found(cls, offset_m: float, heading_rad: float, curvature_1pm: float, range_start_m: float,
              range_end_m: float, confidence: float) -> Boundary:
        """A valid boundary, as ``Boundary(True, …)`` makes it, without the frozen dataclass's ``__init__`` (which
        sets each field through ``object.__setattr__``: the estimator makes two a cycle)."""
        out = object.__new__(cls)
        out.__dict__.update(valid=True, offset_m=offset_m, heading_rad=heading_rad, curvature_1pm=curvature_1pm,
                            range_start_m=range_start_m, range_end_m=range_end_m, confidence=confidence)
        return out


UNAVAILABLE = Boundary(False)


def _next_pose(pose: tuple, dt_s: float, sensor_velocity: tuple[float, float], yaw_rate_rps: float
               ) -> tuple[tuple, tuple[float, float, float, float]]:
    """The odometry pose (x, y, heading) moved by the ego motion over ``dt_s``, and the new pose's x, y and its
    heading's cos, sin."""
    vx, vy = sensor_velocity
    ox, oy, h = pose
    c, s = math.cos(h), math.sin(h)
    ox, oy, h = ox + (c * vx - s * vy) * dt_s, oy + (s * vx + c * vy) * dt_s, h + yaw_rate_rps * dt_s
    return (ox, oy, h), (ox, oy, math.cos(h), math.sin(h))


def _plain(x) -> bool:
    """A number whose arithmetic with float64 arrays and Python floats :meth:`RoadBoundaryEstimator.update_many`'s
    float64 table reproduces: a Python int or float, a numpy integer, float32 or float64."""
    return type(x) is float or (isinstance(x, (int, float, np.integer, np.float32, np.float64))
                                and not isinstance(x, (bool, np.bool_)))


def _plain_motion(dt_s, sensor_velocity, yaw_rate_rps) -> bool:
    """A cycle's motion of :func:`_plain` numbers, the velocity a pair of them (a tuple, list or array)."""
    v = sensor_velocity if type(sensor_velocity) is tuple else list(np.ravel(np.asarray(sensor_velocity, dtype=object)))
    return len(v) == 2 and _plain(dt_s) and _plain(yaw_rate_rps) and _plain(v[0]) and _plain(v[1])


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
        self._scratch = Scratch(share_result=True)   # the Hough search's work arrays and accumulator, reused
        self._points: list[np.ndarray] = []          # per cycle: (2, n), the rows x and y in the odometry frame
        self._pose = (0.0, 0.0, 0.0)                 # odometry: x, y, heading of the sensor
        # the followed boundaries' samples in the odometry frame (per side: the lists x and y, or None), and which
        # are followed
        self._curves: list[tuple | None] = [None, None]
        self._followed = [False, False]
        self._cycle = 0
        self.left = UNAVAILABLE
        self.right = UNAVAILABLE

    def update(self, x_m: np.ndarray, y_m: np.ndarray, range_rate_mps: np.ndarray, dt_s: float,
               sensor_velocity: tuple[float, float], yaw_rate_rps: float, range_m: np.ndarray | None = None
               ) -> tuple[Boundary, Boundary]:
        """Add one cycle's detections (sensor frame; radial speed negative when closing) and re-estimate.

        ``sensor_velocity`` is the sensor's velocity over ground in its own axes, as known from the ego-
        motion input; ``dt_s`` is the time since the previous call. ``range_m``: the detections' ranges at least
        1e-6 m, ``np.maximum(np.hypot(x_m, y_m), 1e-6)``, where the caller has them (else computed here).
        """
        ox, oy, c, s = self._advance(dt_s, sensor_velocity, yaw_rate_rps)
        vx, vy = sensor_velocity
        r = np.maximum(np.hypot(x_m, y_m), 1e-6) if range_m is None else range_m
        ground = range_rate_mps + (vx * x_m + vy * y_m) / r
        still = np.abs(ground) < STATIONARY_MPS
        return self._estimate(_to_odometry(x_m[still], y_m[still], ox, oy, c, s), ox, oy, c, s, sensor_velocity,
                              yaw_rate_rps)

    def update_many(self, x_m: np.ndarray, y_m: np.ndarray, range_rate_mps: np.ndarray, range_m: np.ndarray,
                    counts: list[int], motion: list[tuple[float, tuple[float, float], float]]
                    ) -> list[tuple[Boundary, Boundary]]:
        """:meth:`update` of several cycles in order: their detections one after the other (``counts`` a cycle;
        ``range_m`` as :meth:`update` takes it, required here) and each cycle's (dt_s, sensor_velocity, yaw_rate_rps).
        The same estimates, element by element the same numbers: only the cycles' stationary detections are found and
        moved into the odometry frame in one pass over all of them (the poses depend on the inputs alone), the
        rest cycle by cycle (the road-boundary process answers 32 cycles at a time, :mod:`radarnode.wire.pipeline`:
        some twenty numpy calls a cycle fewer). Detections other than float64 arrays, or motion other than plain
        numbers (int, float, float32, float64), are taken cycle by cycle with :meth:`update`: its arithmetic follows
        their dtype, which one table of float64 would not (an independent tester's float32 detections within float32's
        rounding of the stationary threshold). Nothing is changed when the inputs do not fit together."""
        columns = (x_m, y_m, range_rate_mps, range_m)
        if len(counts) != len(motion) or sum(counts) != x_m.size or any(np.shape(a) != (x_m.size,) for a in columns):
            raise ValueError(f"update_many: {len(counts)} counts summing to {sum(counts)} and {len(motion)} motions "
                             f"for detections of shapes {[np.shape(a) for a in columns]}; expected a count and a "
                             "motion a cycle, the counts summing to the detections, four columns of that length")
        if not (all(isinstance(a, np.ndarray) and a.dtype == np.float64 for a in columns)
                and all(_plain_motion(*m) for m in motion)):
            ends = np.cumsum(counts).tolist()
            return [self.update(x_m[b - c:b], y_m[b - c:b], range_rate_mps[b - c:b], dt_s, v, yaw, range_m[b - c:b])
                    for c, b, (dt_s, v, yaw) in zip(counts, ends, motion)]
        poses, frames = [], []      # per cycle: its pose as :meth:`_advance` returns it, and as self._pose holds it
        pose = self._pose
        for dt_s, v, yaw in motion:
            pose, now = _next_pose(pose, dt_s, v, yaw)
            poses.append(now)
            frames.append(pose)
        n = len(poses)
        table = np.array([(*p, *v) for p, (_, v, _) in zip(poses, motion)], dtype=np.float64).reshape(n, 6)
        row = np.repeat(np.arange(n), counts)
        # element by element :meth:`update`'s expressions, with each detection's cycle's numbers
        ground = range_rate_mps + (table[row, 4] * x_m + table[row, 5] * y_m) / range_m
        still = np.abs(ground) < STATIONARY_MPS
        k = row[still]
        points = _to_odometry(x_m[still], y_m[still], table[k, 0], table[k, 1], table[k, 2], table[k, 3])
        ends = np.cumsum(np.bincount(k, minlength=n)).tolist()
        out, start = [], 0
        for j, ((ox, oy, cj, sj), (_, v, yaw)) in enumerate(zip(poses, motion)):
            self._pose = frames[j]          # (what the cycle's estimate reads of it)
            out.append(self._estimate(points[:, start:ends[j]], ox, oy, cj, sj, v, yaw))
            start = ends[j]
        return out

    def _advance(self, dt_s: float, sensor_velocity: tuple[float, float], yaw_rate_rps: float
                 ) -> tuple[float, float, float, float]:
        """Move the odometry pose by the ego motion over ``dt_s``: the new pose's x, y and its heading's cos, sin."""
        self._pose, now = _next_pose(self._pose, dt_s, sensor_velocity, yaw_rate_rps)
        return now

    def _estimate(self, points: np.ndarray, ox: float, oy: float, c: float, s: float,
                  sensor_velocity: tuple[float, float], yaw_rate_rps: float) -> tuple[Boundary, Boundary]:
        """One cycle's estimate from its stationary detections in the odometry frame, ``points`` (2, n), the
        sensor's pose (at ox, oy, heading cos c, sin s: :meth:`_advance`'s) and motion."""
        vx, vy = sensor_velocity
        self._points.append(points)
        del self._points[:-self.cycles]
        d = np.concatenate(self._points, axis=1) - np.array([[ox], [oy]])    # every point into the sensor frame
        p = _to_sensor(d[0], d[1], c, s)
        p = p.compress(p[0] > 0.0, axis=1)                    # ahead
        px, py = p[0], p[1]
        speed = math.hypot(vx, vy)
        kappa = yaw_rate_rps / speed if speed > 1.0 else 0.0
        if kappa:
            py -= 0.5 * kappa * px * px          # straighten along the predicted path
        self._cycle += 1
        sides = np.empty((2, px.size), dtype=bool)            # (2, n): left, right
        np.greater(py, 0.5, out=sides[0])
        np.less(py, -0.5, out=sides[1])
        found = [UNAVAILABLE, UNAVAILABLE]
        if self._cycle % self.reacquire_cycles and (self._followed[0] or self._followed[1]):
            found = self._follow(px, py, sides, kappa, c, s)  # the full search runs every reacquire_cycles
        for k in range(2):
            if not found[k].valid:
                found[k] = self._side(px[sides[k]], py[sides[k]], kappa)
        self._keep_curves(found, c, s)
        self.left, self.right = found
        if not self.left.valid and not self.right.valid and len(self._points) >= self.cycles:
            del self._points[:-1]         # restart the search (seed 002)
        return self.left, self.right

    def _keep_curves(self, found: list[Boundary], c: float, s: float) -> None:
        """The boundaries found (sensor frame, as reported), to follow them: per side the pose of this frame in the
        odometry frame and the curve about the middle m of its stretch, y = o + t·d + h·d² with x = m + d, and the
        spacing of its CURVE_SAMPLES samples (:func:`predicted_line` moves them)."""
        self._followed = [b.valid for b in found]
        ox, oy = self._pose[0], self._pose[1]
        curves = []
        for b in found:
            if not b.valid:
                curves.append(None)
                continue
            t, h = math.tan(b.heading_rad), 0.5 * b.curvature_1pm
            m = 0.5 * (b.range_start_m + b.range_end_m)
            curves.append((ox, oy, c, s, m, (b.range_end_m - b.range_start_m) / (CURVE_SAMPLES - 1),
                           b.offset_m + (t + h * m) * m, t + 2.0 * h * m, h))
        self._curves = curves

    def _follow(self, px: np.ndarray, py: np.ndarray, sides: np.ndarray, kappa: float, c: float, s: float
                ) -> list[Boundary]:
        """Both sides' boundaries near last cycle's: each curve moved into this frame and straightened, its
        inliers fitted (UNAVAILABLE for a side that had none or lost it). The two sides in one pass each."""
        ox, oy = self._pose[0], self._pose[1]
        follow, line = [False, False], [[0.0, 0.0], [0.0, 0.0]]
        for k in range(2):
            if self._followed[k] and np.count_nonzero(sides[k]) >= 4:
                line_u = predicted_line(self._curves[k], ox, oy, c, s, kappa)
                if line_u is not None:
                    follow[k], line[k] = True, line_u
        if not (follow[0] or follow[1]):
            return [UNAVAILABLE, UNAVAILABLE]
        # the line is re-fitted to the points within band_m of it until the inliers settle (a few passes):
        # starting from the prediction, the gate centres itself on the points instead of on last cycle's error
        pw = powers(px, py)                              # the points' moments, for every fit of this cycle
        allowed = sides if follow[0] and follow[1] else sides & np.array(follow)[:, None]
        inliers = self._gate(pw, line, allowed)
        mom = None
        for _ in range(FOLLOW_PASSES):
            mom = moments(pw, inliers)
            lost = [follow[k] and mom[k][0] < 4.0 for k in range(2)]
            if lost[0] or lost[1]:
                follow = [follow[k] and not lost[k] for k in range(2)]
                if not (follow[0] or follow[1]):
                    return [UNAVAILABLE, UNAVAILABLE]
                allowed = sides & np.array(follow)[:, None]
                inliers &= allowed
                mom = moments(pw, inliers)
            again = self._gate(pw, solve_u(mom, _LINES), allowed)
            if (again == inliers).all():
                break
            inliers, mom = again, None
        return self._fit(px, py, inliers, follow, kappa, pw, mom)

    def _gate(self, pw: np.ndarray, line_u: list, allowed: np.ndarray) -> np.ndarray:
        """The points ``allowed`` (2, n) within band_m of each row's line y = a + b·u (u = (x − FIT_CENTRE_M) /
        FIT_SCALE_M; ``line_u`` a pair (a, b) a row; ``pw``: the points' :func:`powers`, whose rows 1, u, y give every
        residual in one matrix product)."""
        res = np.array([[-ln[0], -ln[1], 1.0] for ln in line_u]) @ pw[:3]
        np.abs(res, out=res)
        near = res <= self.band_m
        near &= allowed
        return near

    def _side(self, x: np.ndarray, y: np.ndarray, kappa: float) -> Boundary:
        """The nearest strong near-longitudinal Hough line among a side's points (straightened frame), fitted."""
        if x.size < 4:
            return UNAVAILABLE
        acc = accumulate(x, y, self.grid, scratch=self._scratch)
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
             pw: np.ndarray | None = None, mom: list[list[float]] | None = None) -> list[Boundary]:
        """Seed 002's gap rule on each row's inliers (``inliers`` (S, n), rows where ``use``), then
        y = c0 + c1·x (+ c2·x²) with the path curvature added back; one Boundary per row (``pw``: the points'
        :func:`powers`, if known; ``mom``: the inliers' :func:`moments`, if known)."""
        rows = inliers.shape[0]
        if mom is None:
            mom = moments(powers(x, y) if pw is None else pw, inliers)
        count = [int(mom[k][0]) if use[k] else 0 for k in range(rows)]
        if max(count) < 4:
            return [UNAVAILABLE] * rows
        # seed 002: M cross-sections along x from each row's nearest inlier, at most k of them without a point (a row's
        # inliers taken out once: its cells are few, so the rest is in Python numbers)
        sections = self.sections
        ok, seen, deg2, start, x_max = [False] * rows, [0] * rows, [False] * rows, [0.0] * rows, [0.0] * rows
        for k in range(rows):
            if count[k] < 4:
                continue
            xs = x.compress(inliers[k])
            lo, x_max[k] = float(np.minimum.reduce(xs)), float(np.maximum.reduce(xs))
            xs -= lo
            xs /= self.section_m                          # (x > 0: the nearest inlier is the start)
            # the sections with a point: how far they reach (the last one's end) and how many there are
            filled = np.bincount(xs.astype(np.intp), minlength=sections)[:sections].nonzero()[0]
            start[k] = max(lo, 0.0)
            reach = int(filled[-1]) + 1 if filled.size else 0
            seen[k] = filled.size
            missing = (reach - seen[k]) + max(0, sections - reach - self.max_missing)
            ok[k] = missing <= self.max_missing and reach >= 2
            deg2[k] = ok[k] and x_max[k] - lo > 40.0 and count[k] >= 8
        if not any(ok):
            return [UNAVAILABLE] * rows
        coef = solve_x(mom, deg2)
        out = []
        for k in range(rows):
            if not ok[k]:
                out.append(UNAVAILABLE)
                continue
            c0, c1, c2 = coef[k]
            out.append(Boundary.found(c0, math.atan(c1), 2.0 * c2 + kappa, start[k], x_max[k], seen[k] / self.sections))
        return out
