"""Where the ego will drive, in the vehicle frame, and where the radar sits in it (DESIGN §7; issue 10).

The ECU knows the radar's mount as it is calibrated into a real ECU: its position from the rear-axle centre
(x forward, y left) and its yaw. Tracks arrive in the sensor frame; :meth:`SensorMount.to_vehicle` moves them
to the vehicle frame. The predicted path is the circle the rear axle drives at the curvature
κ = yaw rate / speed (a vehicle turns about its rear axle); a point is in the path when its lateral distance
from that circle is within the path's half-width. Where the radar reports both road edges, the path may not
leave the road (the edges are measured in the sensor frame; :func:`aligned_boundaries` turns them to the car's
axes, so that their headings are the car's to the road and a yawed sensor does not make a straight road look like a
lane change).

The yaw rate knows only the curve the ego is in, not the one ahead: entering a curve through a clothoid it still
says "straight" while the lane ahead already bends. Where the radar reports a road boundary, its course ahead —
y_b(x) − y_b(0), the lateral shift of a line parallel to the road — is where the ego will be at x if it keeps
its place on the road, and it takes over from the yaw-rate circle between :data:`BLEND_START_M` and
:data:`BLEND_END_M` ahead, up to :data:`COURSE_EXTENT` times the boundary's valid range (its curvature carries it
on) (what production course prediction does with the road geometry from stationary
targets). Not while the ego turns across the road (a lane change: its heading to the boundaries, averaged,
beyond :data:`LANE_KEEPING_HEADING_RAD`, and their offsets moving as that heading says, :func:`crossing_road`; a
single boundary's heading is not enough, as a quadratic fit to a clothoid tilts it by a degree or two, nor the
heading alone on a curve's exit, where the fit tilts by 3° while the offsets stay): then the yaw rate is the better
guess.

The vehicles ahead drove the road the ego is about to drive: :class:`VehicleTrails` keeps, per vehicle moving our
way, its positions of the last TRAIL_MAX_AGE_S in the vehicle frame, carried along every cycle by the ego's speed
and yaw rate (:func:`dead_reckon`). :func:`trail_fits` keeps the trails that describe the road (a vehicle changing
lane drifts from the others, from the boundaries, or — alone — from the yaw-rate course otherwise than a road
bends), :func:`fit_course` fits one clothoid y = c1·x + c2·x² + c3·x³ to them (per-trail offsets, weak priors from
the yaw rate), and :func:`in_path` blends it in like the boundaries' course, both counting equally where both
cover (production ACC's course prediction from the "history of vehicles ahead"). With neither, the yaw-rate
circle alone decides.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from radarnode import validate

MIN_SPEED_FOR_CURVATURE_MPS = 1.0
BLEND_START_M, BLEND_END_M = 20.0, 60.0     # the road's course takes over from the yaw-rate circle over this span
LANE_KEEPING_HEADING_RAD = 0.05             # 2.9°: beyond it the ego crosses the road (a lane change)
MAX_BOUNDARY_HEADING_RAD = 0.1              # 5.7°: a boundary at a steeper angle to the ego is no road edge
DRIFT_WINDOW_S = 0.5                        # BoundaryDrift: the offsets of the last 0.5 s …
DRIFT_MIN_SAMPLES = 4                       # … at least 4 of them on a side …
DRIFT_JUMP_M = 1.0                          # … a side whose offset jumps by more is another line (restarts) …
DRIFT_MIN_M = 0.3                           # … and the headings must predict a move of this much to be judged:
#: a lane change moves the edges by this share of what the headings predict or more (0.26–0.47 measured as the
#: heading passes 2.9°, the estimator's offsets lagging its headings; 1.0 ± 0.1 once under way); a curve's exit
#: −0.17 … +0.18 (the quadratic's heading tilted, the offsets staying)
DRIFT_FOLLOW_SHARE = 0.25
COURSE_EXTENT = 1.5                         # the boundary's course is used up to this multiple of its valid range


@dataclass(frozen=True)
class SensorMount:
    """The radar's position on the ego from the rear-axle centre (x forward, y left, metres), its yaw, and its
    height above the road (the overhead test predicts the road's reflection from it)."""

    x_m: float = 3.7
    y_m: float = 0.0
    yaw_deg: float = 0.0
    z_m: float = 0.5

    def __post_init__(self) -> None:
        validate.number("mount x_m", self.x_m, lo=-10.0, hi=10.0)
        validate.number("mount y_m", self.y_m, lo=-5.0, hi=5.0)
        validate.number("mount yaw_deg", self.yaw_deg, lo=-180.0, hi=180.0)
        validate.number("mount z_m", self.z_m, lo=0.0, hi=5.0)

    @classmethod
    def of(cls, mount) -> SensorMount:
        """From anything with ``x_m``, ``y_m``, ``yaw_deg`` and ``z_m`` (a scenario's ``radar.mount``)."""
        return cls(float(mount.x_m), float(mount.y_m), float(mount.yaw_deg), float(getattr(mount, "z_m", 0.5)))

    def to_vehicle(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Sensor-frame positions to the vehicle frame."""
        xr, yr = self.rotate(x, y)
        return self.x_m + xr, self.y_m + yr

    def to_sensor(self, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Vehicle-frame positions to the sensor frame (the inverse of :meth:`to_vehicle`)."""
        return self.rotate(x - self.x_m, y - self.y_m, inverse=True)

    def rotate(self, vx: np.ndarray, vy: np.ndarray, inverse: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Sensor-frame vectors to vehicle axes: velocities relative to the sensor, or positions into the sensor's
        vehicle-aligned frame (the origin at the sensor, the vehicle's axes: the vehicle frame less the mount's
        position); ``inverse``: vehicle axes to the sensor's."""
        c, s = math.cos(math.radians(self.yaw_deg)), math.sin(math.radians(self.yaw_deg))
        if inverse:
            s = -s
        return c * vx - s * vy, s * vx + c * vy


#: samples of a reported boundary taken into the aligned frame (:func:`aligned_boundaries`)
_ALIGN_SAMPLES = 16


def aligned_boundaries(boundaries: dict | None, mount: SensorMount) -> dict | None:
    """The reported boundaries (sensor frame, as the radar measured them) in the sensor's vehicle-aligned frame
    (:meth:`SensorMount.rotate`), the frame the path functions take them in: their headings are then the ego's
    heading to the road, whatever the sensor's yaw (a sensor yawed by 3.5° reported a straight road at −3.5°, past
    the lane-change limit). A yawed boundary is fitted again, a quadratic in the aligned x over its course
    (:data:`COURSE_EXTENT` times its valid range); with no yaw the boundaries are returned as they are."""
    if not boundaries or mount.yaw_deg == 0.0:
        return boundaries
    out = {}
    for side, b in boundaries.items():
        if b is None or not b.valid:
            out[side] = b
            continue
        xs = np.linspace(b.range_start_m, max(COURSE_EXTENT * b.range_end_m, b.range_start_m + 1.0), _ALIGN_SAMPLES)
        xa, ya = mount.rotate(xs, b.y_at(xs))
        c2, c1, c0 = np.polyfit(xa, ya, 2)
        ends = np.array([b.range_start_m, b.range_end_m])
        start, end = mount.rotate(ends, b.y_at(ends))[0]
        out[side] = replace(b, offset_m=float(c0), heading_rad=math.atan(c1), curvature_1pm=2.0 * float(c2),
                            range_start_m=float(start), range_end_m=float(end))
    return out


def path_offset_m(x: np.ndarray, y: np.ndarray, curvature_1pm: float) -> np.ndarray:
    """Signed lateral distance (left positive) of vehicle-frame points from the rear axle's circle."""
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    if abs(curvature_1pm) < 1e-9:
        return y
    r = 1.0 / curvature_1pm                                  # centre at (0, r); left turn r > 0
    return math.copysign(1.0, r) * (abs(r) - np.hypot(x, y - r))


def curvature(ego_speed_mps: float, yaw_rate_rps: float) -> float:
    """The rear axle's path curvature κ = yaw rate / speed (0 when too slow to tell)."""
    return yaw_rate_rps / ego_speed_mps if ego_speed_mps > MIN_SPEED_FOR_CURVATURE_MPS else 0.0


def path_heading(kappa: float, x_m: float) -> float:
    """The heading (rad, vehicle axes) of the yaw-rate circle of curvature ``kappa`` at ``x_m`` ahead of the rear
    axle: asin(κ·x) (a quarter turn where the circle turns back)."""
    return math.asin(max(-1.0, min(1.0, kappa * x_m)))


def in_path(x: np.ndarray, y: np.ndarray, ego_speed_mps: float, yaw_rate_rps: float, half_width_m: float,
            boundaries: dict | None = None, mount: SensorMount | None = None,
            trails: list | None = None, crossing: bool | None = None) -> np.ndarray:
    """Which sensor-frame points lie ahead in the ego's predicted path.

    ``mount=None`` takes the sensor at the rear axle (the circle then starts at the sensor). ``boundaries``: in the
    sensor's vehicle-aligned frame (:func:`aligned_boundaries`; the sensor frame itself for a sensor with no yaw).
    ``trails``: the vehicles' trails that describe the road (:func:`trail_fits`); where they and the boundaries
    both cover a range, the two courses count equally. ``crossing``: whether the ego turns across the road
    (:func:`crossing_road`; None: judged from the boundaries' headings alone).

    The boundaries' course is a line parallel to the road through the car's centre line: a point's distance from
    it is its vehicle-frame lateral position less the course's shift (the sensor's own lateral place on the car
    is no part of it: with the sensor 0.5 m left of centre the far path ran 0.5 m left of the car's).
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    kappa = curvature(ego_speed_mps, yaw_rate_rps)
    m = mount if mount is not None else SensorMount(0.0, 0.0, 0.0)
    xv, yv = m.to_vehicle(x, y)
    xa, ya = xv - m.x_m, yv - m.y_m                 # the aligned frame: x ahead of the sensor, along the car
    offset = path_offset_m(xv, yv, kappa)
    course = road_course(xa, boundaries, crossing)
    by_trails = trail_course(xv, trails, kappa) if trails else None
    far = cover = None
    if course is not None:
        shift, cover = course
        far = yv - shift
    if by_trails is not None:
        yc, covered_t = by_trails
        far_t = yv - yc
        if far is None:
            far, cover = far_t, covered_t
        else:
            n = cover + covered_t
            far = np.where(n > 0, (cover * far + covered_t * far_t) / np.maximum(n, 1.0), 0.0)
            cover = np.minimum(n, 1.0)
    if far is not None:
        w = np.clip((xa - BLEND_START_M) / (BLEND_END_M - BLEND_START_M), 0.0, 1.0) * cover
        offset = (1.0 - w) * offset + w * far
    inside = (xv > m.x_m) & (np.abs(offset) <= half_width_m)
    for side, b in plausible(boundaries):
        inside &= (ya < b.y_at(xa)) if side == "left" else (ya > b.y_at(xa))
    return inside


def plausible(boundaries: dict | None) -> list:
    """The reported boundaries to trust, as (side, boundary): valid, on their own side, running along the road
    (the estimator can take the far part of one guardrail that bends across the view for the other side's: an
    offset on the wrong side, a heading of 10° and more)."""
    if not boundaries:
        return []
    return [(side, b) for side, b in (("left", boundaries.get("left")), ("right", boundaries.get("right")))
            if b is not None and b.valid and (b.offset_m > 0.0) == (side == "left")
            and abs(b.heading_rad) <= MAX_BOUNDARY_HEADING_RAD]


def road_course(x: np.ndarray, boundaries: dict | None, crossing: bool | None = None
                ) -> tuple[np.ndarray, np.ndarray] | None:
    """The road's lateral course ahead from the valid reported boundaries, sensor frame: (shift (m) at ``x``, 1
    where a boundary covers ``x`` else 0), averaged over the boundaries; None without one, or while the ego crosses
    the road (``crossing``, :func:`crossing_road`; None: while its heading to the road, the boundaries' average,
    exceeds LANE_KEEPING_HEADING_RAD)."""
    valid = [b for _, b in plausible(boundaries)]
    if not valid or (crossing if crossing is not None else abs(_heading(valid)) > LANE_KEEPING_HEADING_RAD):
        return None
    x = np.asarray(x, dtype=np.float64)
    shift = np.zeros(x.shape)
    n = np.zeros(x.shape)
    for b in valid:
        on = (x >= 0.0) & (x <= COURSE_EXTENT * b.range_end_m)
        shift += np.where(on, b.y_at(x) - b.offset_m, 0.0)
        n += on
    return np.where(n > 0, shift / np.maximum(n, 1), 0.0), (n > 0).astype(np.float64)


def _heading(valid: list) -> float:
    """The ego's heading to the road: the reported boundaries' headings, averaged."""
    return sum(b.heading_rad for b in valid) / len(valid)


class BoundaryDrift:
    """Whether the reported road edges move across as the ego's heading to them says they must: the change of each
    boundary's offset over the last :data:`DRIFT_WINDOW_S` against what its headings predict, Σ v·sin ψ·Δt. A lane
    change moves them so (both the same sign, the same size, whatever the lag of a heading that builds up); on a
    curve's exit the boundaries' quadratic fits tilt by 3° at R 250 m while their offsets stay (the road's course
    and the ego's place on it have not changed)."""

    def __init__(self) -> None:
        self._hist: dict[str, list[tuple[float, float, float]]] = {"left": [], "right": []}
        self._seen = {"left": -math.inf, "right": -math.inf}      # when each edge was last reported

    def update(self, t_s: float, boundaries: dict | None, speed_mps: float) -> None:
        """Take this cycle's boundaries (those :func:`plausible` counts) and the ego's speed; a side not reported, or
        one whose offset jumped by more than :data:`DRIFT_JUMP_M` (another line taken), starts its history again."""
        seen = dict(plausible(boundaries))
        for side, hist in self._hist.items():
            b = seen.get(side)
            if b is None or (hist and abs(b.offset_m - hist[-1][1]) > DRIFT_JUMP_M):
                hist.clear()
            if b is not None:
                self._seen[side] = t_s
                hist.append((t_s, b.offset_m, speed_mps * math.sin(b.heading_rad)))
                while hist and hist[0][0] < t_s - DRIFT_WINDOW_S:
                    del hist[0]

    def follows_heading(self) -> bool | None:
        """Whether the offsets moved at least DRIFT_FOLLOW_SHARE of what the headings predict, the same way, over
        the sides with :data:`DRIFT_MIN_SAMPLES` samples: None on a road whose two edges were not both reported within
        the last DRIFT_WINDOW_S (with one guardrail the edge's offset lagged its heading at the start of a lane change
        for 3–4 cycles, and FCW prewarned for the car in the lane being left: an independent tester; on a curve's exit
        the estimator can lose one edge for a few cycles, the other's history then decides), or while the headings
        predict less than :data:`DRIFT_MIN_M`."""
        now = max(self._seen.values())
        if any(now - seen > DRIFT_WINDOW_S for seen in self._seen.values()):
            return None                          # one road edge only (or none) in the last DRIFT_WINDOW_S
        moved = predicted = 0.0
        for hist in self._hist.values():
            if len(hist) < DRIFT_MIN_SAMPLES:
                continue
            moved += hist[-1][1] - hist[0][1]
            predicted += sum(0.5 * (a[2] + b[2]) * (b[0] - a[0]) for a, b in zip(hist, hist[1:]))
        if abs(predicted) < DRIFT_MIN_M:
            return None
        return moved / predicted >= DRIFT_FOLLOW_SHARE


def crossing_road(boundaries: dict | None, drift: BoundaryDrift) -> bool | None:
    """Whether the ego turns across the road (a lane change), for :func:`road_course`: its heading to the reported
    boundaries beyond LANE_KEEPING_HEADING_RAD *and* the boundaries moving across as that heading says they do
    (:meth:`BoundaryDrift.follows_heading`); None without boundaries, the heading alone while the drift says
    nothing yet."""
    valid = [b for _, b in plausible(boundaries)]
    if not valid:
        return None
    if abs(_heading(valid)) <= LANE_KEEPING_HEADING_RAD:
        return False
    follows = drift.follows_heading()
    return True if follows is None else follows


def measured_reach_m(boundaries: dict | None, trails: list | None, mount: SensorMount,
                     crossing: bool | None = None) -> float | None:
    """How far ahead of the sensor the road's course is measured, not extrapolated: the farthest valid range of the
    boundaries :func:`road_course` uses and the farthest point of the trails :func:`trail_course` uses; None when
    neither is used (the yaw-rate circle alone predicts the path, nothing to tell apart)."""
    reach = []
    if road_course(np.zeros(1), boundaries, crossing) is not None:
        reach.append(max(b.range_end_m for _, b in plausible(boundaries)))
    if trails and trail_course(np.zeros(1), trails) is not None:
        reach.append(max(f.x_max for f in trails) - mount.x_m)
    return max(reach) if reach else None


def course_known(x: np.ndarray, y: np.ndarray, reach_m: float | None, ego_speed_mps: float, yaw_rate_rps: float,
                 half_width_m: float, mount: SensorMount) -> np.ndarray:
    """Which sensor-frame points lie where the ego's path is known: within the measured course (``reach_m`` ahead
    of the sensor along the car, :func:`measured_reach_m`), or in the path the yaw-rate circle alone predicts.
    Everywhere when nothing is measured (``reach_m`` None: the circle is then the only prediction there is)."""
    x = np.asarray(x, dtype=np.float64)
    if reach_m is None:
        return np.ones(x.shape, dtype=bool)
    xa = mount.rotate(x, np.asarray(y, dtype=np.float64))[0]
    return (xa <= reach_m) | in_path(x, y, ego_speed_mps, yaw_rate_rps, half_width_m, None, mount, None)


# --- the course from the trails of vehicles ahead ------------------------------------------------------------------
TRAIL_MAX_AGE_S = 3.0          # a trail keeps the points of the last 3 s …
TRAIL_MAX_POINTS = 60          # … and at most this many (60 × 72 ms ≈ 4.3 s)
TRAIL_MIN_POINTS = 5           # fewer points: no trail
TRAIL_MIN_SPAN_M = 15.0        # a trail shorter along x says nothing about curvature
TRAIL_MAX_RESIDUAL_M = 0.4     # rms about a cubic over the trail: more, and it is no smooth course (or no one track)
TRAIL_DRIFT_M = 0.9            # lateral drift (peak to peak) against the other trails or the boundaries: ¼ lane
TRAIL_LONE_DRIFT_M = 0.9       # … against the yaw-rate course when nothing else is known, unless it bends as a road
TRAIL_BEND_RATIO = 1.5         # a lone trail drifting from the yaw-rate course must bend as a road (_bends_like_a_road)
TRAIL_EXTENT = 1.5             # a trail's course is used up to this multiple of its farthest point
TRAIL_SIGMA_M = 0.1            # the weight of a trail: its length / (σ² + fit rms²)
_MAX_COND = 1e8                # the fit's condition number (x scaled to [-1, 1]); beyond it, no fit
_U = 100.0                     # x in the course fit, in units of 100 m (conditioning)
_PRIOR_HEADING = 0.02 * _U     # the priors' σ: heading to the road 0.02 rad, …
_PRIOR_CURVATURE = 0.5 * 0.002 * _U ** 2     # … curvature 0.002 1/m from the yaw rate's, …
_PRIOR_CURVATURE_RATE = 1e-4 / 6.0 * _U ** 3  # … curvature rate 1e-4 1/m² (0 to 1/250 m in 40 m)


def dead_reckon(x: np.ndarray, y: np.ndarray, speed_mps: float, yaw_rate_rps: float,
                dt_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Vehicle-frame points (fixed in the world) in the vehicle frame ``dt_s`` later: the rear axle moved
    ``speed_mps·dt_s`` along the mean heading of the step and turned by ``yaw_rate_rps·dt_s`` (the same motion
    model as the ECU's odometry)."""
    h = yaw_rate_rps * dt_s
    d = speed_mps * dt_s
    dx, dy = d * math.cos(0.5 * h), d * math.sin(0.5 * h)
    c, s = math.cos(h), math.sin(h)
    px, py = np.asarray(x, dtype=np.float64) - dx, np.asarray(y, dtype=np.float64) - dy
    return c * px + s * py, -s * px + c * py


@dataclass(frozen=True)
class TrailFit:
    """y = poly(u), u = (x − centre) / scale: one vehicle's trail smoothed (vehicle frame)."""

    coef: np.ndarray            # highest power first (numpy.polyval)
    centre: float
    scale: float
    x_min: float
    x_max: float
    rms_m: float
    weight: float
    xs: np.ndarray              # the trail's points
    ys: np.ndarray

    def y(self, x) -> np.ndarray:
        return np.polyval(self.coef, (np.asarray(x, dtype=np.float64) - self.centre) / self.scale)


def fit_trail(x: np.ndarray, y: np.ndarray) -> TrailFit | None:
    """One trail smoothed by a cubic over its own span (its noise, and its drift against a reference course), or
    None when it has fewer than TRAIL_MIN_POINTS finite points, spans less than TRAIL_MIN_SPAN_M, lies behind the
    ego, is ill-conditioned or ragged (rms beyond TRAIL_MAX_RESIDUAL_M)."""
    x, y = np.asarray(x, dtype=np.float64).reshape(-1), np.asarray(y, dtype=np.float64).reshape(-1)
    ok = np.isfinite(x) & np.isfinite(y)
    x, y = x[ok], y[ok]
    if x.size < TRAIL_MIN_POINTS:
        return None
    lo, hi = float(x.min()), float(x.max())
    if hi - lo < TRAIL_MIN_SPAN_M or hi <= 0.0:
        return None
    centre, scale = 0.5 * (lo + hi), 0.5 * (hi - lo)
    u = (x - centre) / scale
    deg = 3 if x.size > 6 else 2
    a = u[:, None] ** np.arange(deg, -1, -1)
    try:
        coef, _, rank, sv = np.linalg.lstsq(a, y, rcond=None)
    except np.linalg.LinAlgError:
        return None
    if rank < deg + 1 or not np.isfinite(coef).all() or sv[-1] <= 0.0 or sv[0] / sv[-1] > _MAX_COND:
        return None
    rms = float(np.sqrt(np.sum((a @ coef - y) ** 2) / max(x.size - deg - 1, 1)))
    if not math.isfinite(rms) or rms > TRAIL_MAX_RESIDUAL_M:
        return None
    return TrailFit(coef, centre, scale, lo, hi, rms, (hi - lo) / (TRAIL_SIGMA_M ** 2 + rms ** 2), x, y)


def _drift(f: TrailFit, ref, lo: float = -math.inf, hi: float = math.inf) -> float | None:
    """Peak-to-peak lateral drift of trail ``f`` (smoothed) against the course ``ref(x)`` over its points within
    [lo, hi] (None where they overlap over less than TRAIL_MIN_SPAN_M)."""
    xs = f.xs[(f.xs >= lo) & (f.xs <= hi)]
    if xs.size < 2 or xs.max() - xs.min() < TRAIL_MIN_SPAN_M:
        return None
    d = f.y(xs) - ref(xs)
    return float(np.ptp(d)) if np.isfinite(d).all() else math.inf


def _bends_like_a_road(f: TrailFit, curvature_1pm: float) -> bool:
    """Whether a lone trail's drift from the yaw-rate course can be a road that bends (its curvature changing
    through a clothoid, a curve's start or end) rather than a lane change: over the second half of the trail it
    drifts at least as much as over the first, in the same direction (a curve ahead bends the more the farther it
    goes, TRAIL_BEND_RATIO times as much at least: 3 for a constant curvature from the trail's start, 7 for a
    clothoid; a lane change is an S that drifts evenly across its middle and levels out past half-way, half a lane
    across). The first half of a lane change drifts ever faster like a curve entry (2.4 for a cosine profile):
    by its trail alone it cannot be told from one."""
    xs = np.array([f.x_min, 0.5 * (f.x_min + f.x_max), f.x_max])
    d = f.y(xs) - 0.5 * curvature_1pm * xs * xs
    first, second = d[1] - d[0], d[2] - d[1]
    s = math.copysign(1.0, first + second)
    return bool(s * second >= TRAIL_BEND_RATIO * s * first and s * first >= 0.0)


def trail_fits(trails, curvature_1pm: float, reference=None) -> list[TrailFit]:
    """The trails (each an (x, y) pair of vehicle-frame arrays) that describe the road. Each pair of trails is
    compared where both run (their lateral distance may change by TRAIL_DRIFT_M at most); the trail that disagrees
    with the most others (on a tie, the one drifting most from the yaw-rate course) is dropped, until all agree.
    Every trail must also agree within TRAIL_DRIFT_M with ``reference`` ((course(x), x from, x to): the
    boundaries' course in the vehicle frame, from :func:`boundary_reference`, or None). A trail that no other
    trail or reference overlaps must keep within TRAIL_LONE_DRIFT_M of the yaw-rate course or drift from it as a
    road bends (:func:`_bends_like_a_road`). A vehicle changing lane drifts against the others: it is dropped."""
    fits = [f for f in (fit_trail(x, y) for x, y in trails) if f is not None]
    circle = lambda xs: 0.5 * curvature_1pm * xs * xs        # noqa: E731 — the yaw-rate course, x ≪ radius
    if reference is not None:
        fits = [f for f in fits if (_drift(f, *reference) or 0.0) <= TRAIL_DRIFT_M]
    n = len(fits)
    agree = np.ones((n, n), dtype=bool)
    compared = np.eye(n, dtype=bool)
    for i in range(n):
        for j in range(i + 1, n):
            lo, hi = max(fits[i].x_min, fits[j].x_min), min(fits[i].x_max, fits[j].x_max)
            d = _drift(fits[i], fits[j].y, lo, hi)
            if d is not None:
                compared[i, j] = compared[j, i] = True
                agree[i, j] = agree[j, i] = d <= TRAIL_DRIFT_M
    keep = np.ones(n, dtype=bool)
    off_circle = np.array([_drift(f, circle) or 0.0 for f in fits])
    while True:
        against = np.sum(~agree[np.ix_(keep, keep)], axis=1)
        if not against.any():
            break
        live = np.flatnonzero(keep)
        worst = max(range(live.size), key=lambda k: (against[k], off_circle[live[k]]))
        keep[live[worst]] = False
    for i in np.flatnonzero(keep):
        alone = reference is None and not compared[i, keep & (np.arange(n) != i)].any()
        if alone and off_circle[i] > TRAIL_LONE_DRIFT_M and not _bends_like_a_road(fits[i], curvature_1pm):
            keep[i] = False
    return [f for f, k in zip(fits, keep) if k]


def boundary_reference(boundaries: dict | None, mount: SensorMount, crossing: bool | None = None):
    """The boundaries' course as a reference for :func:`trail_fits` (vehicle frame, the mount's yaw neglected: a
    drift is measured peak to peak), or None."""
    valid = [b for _, b in plausible(boundaries)]
    if road_course(np.zeros(1), boundaries, crossing) is None:
        return None
    end = COURSE_EXTENT * max(b.range_end_m for b in valid)
    return (lambda xs: road_course(xs - mount.x_m, boundaries, crossing)[0] + mount.y_m), mount.x_m, mount.x_m + end


def fit_course(fits: list[TrailFit], curvature_1pm: float) -> np.ndarray | None:
    """The road's course ahead of the rear axle as a clothoid, y = c1·x + c2·x² + c3·x³ (heading, curvature / 2,
    curvature rate / 6): one shape fitted to all trails at once, each with its own lateral offset, each point
    weighted by 1 / (TRAIL_SIGMA_M² + its trail's fit rms²) (a longer, smoother trail counts more). Weak priors
    tie it to what the ego knows where the trails say little: heading 0 (it keeps its lane), the curvature at the
    ego its yaw rate / speed, a steady curvature. Returns (c1, c2, c3), or None (ill-conditioned, not finite)."""
    if not fits:
        return None
    u = np.concatenate([f.xs for f in fits]) / _U
    ys = np.concatenate([f.ys for f in fits])
    sw = np.concatenate([np.full(f.xs.size, 1.0 / math.sqrt(TRAIL_SIGMA_M ** 2 + f.rms_m ** 2)) for f in fits])
    m = len(fits)
    a = np.zeros((u.size + 3, 3 + m))
    a[:u.size, 0], a[:u.size, 1], a[:u.size, 2] = u, u * u, u ** 3
    a[np.arange(u.size), 3 + np.repeat(np.arange(m), [f.xs.size for f in fits])] = 1.0
    a[:u.size] *= sw[:, None]
    b = np.concatenate([ys * sw, np.zeros(3)])
    for k, (prior, sigma) in enumerate(((0.0, _PRIOR_HEADING), (0.5 * curvature_1pm * _U ** 2, _PRIOR_CURVATURE),
                                        (0.0, _PRIOR_CURVATURE_RATE))):
        a[u.size + k, k] = 1.0 / sigma
        b[u.size + k] = prior / sigma
    try:
        coef, _, _, sv = np.linalg.lstsq(a, b, rcond=None)
    except np.linalg.LinAlgError:
        return None
    if not np.isfinite(coef).all() or sv[-1] <= 0.0 or sv[0] / sv[-1] > _MAX_COND:
        return None
    return coef[:3] / np.array([_U, _U ** 2, _U ** 3])


def trail_course(x: np.ndarray, fits: list[TrailFit], curvature_1pm: float = 0.0,
                 ) -> tuple[np.ndarray, np.ndarray] | None:
    """The road's lateral course ahead from the vehicles' trails, vehicle frame: (y of the course at ``x``, 1 where
    it is covered — up to TRAIL_EXTENT times the farthest trail point — else 0); None without a trail, or while
    the ego's heading to the course exceeds LANE_KEEPING_HEADING_RAD (it is crossing the road: the yaw rate is
    the better guess)."""
    c = fit_course(fits, curvature_1pm)
    if c is None or abs(c[0]) > LANE_KEEPING_HEADING_RAD:
        return None
    x = np.asarray(x, dtype=np.float64)
    y = x * (c[0] + x * (c[1] + x * c[2]))
    on = (x >= 0.0) & (x <= TRAIL_EXTENT * max(f.x_max for f in fits)) & np.isfinite(y)
    return np.where(on, y, 0.0), on.astype(np.float64)


class VehicleTrails:
    """Where the vehicles ahead drove: per track, its recent positions in the vehicle frame (rear axle), carried
    along by the ego's motion every cycle (:func:`dead_reckon`, all points at once), bounded to the last
    TRAIL_MAX_AGE_S and TRAIL_MAX_POINTS."""

    def __init__(self) -> None:
        self._xyt = np.zeros((0, 4))        # rows: track id, x, y, t

    def __len__(self) -> int:
        return len(np.unique(self._xyt[:, 0]))

    def advance(self, speed_mps: float, yaw_rate_rps: float, dt_s: float) -> None:
        """The ego moved for ``dt_s`` at this speed and yaw rate: every stored point into the new vehicle frame."""
        if self._xyt.size and all(math.isfinite(v) for v in (speed_mps, yaw_rate_rps, dt_s)):
            self._xyt[:, 1], self._xyt[:, 2] = dead_reckon(self._xyt[:, 1], self._xyt[:, 2], speed_mps,
                                                            yaw_rate_rps, dt_s)

    def add(self, t_s: float, track_ids, x: np.ndarray, y: np.ndarray) -> None:
        """This cycle's vehicle-frame positions of the vehicles ahead that qualify (finite ones only)."""
        ids = np.asarray(track_ids, dtype=np.float64).reshape(-1)
        new = np.stack([ids, np.asarray(x, np.float64).reshape(-1), np.asarray(y, np.float64).reshape(-1),
                        np.full(ids.shape, float(t_s))], axis=1)
        new = new[np.isfinite(new).all(axis=1)]
        self._xyt = np.concatenate([self._xyt, new])

    def keep(self, t_s: float, alive) -> None:
        """Forget the tracks not in ``alive`` and the points older than TRAIL_MAX_AGE_S (or beyond the last
        TRAIL_MAX_POINTS of a track)."""
        p = self._xyt
        p = p[np.isin(p[:, 0], np.fromiter(alive, dtype=np.float64)) & (t_s - p[:, 3] <= TRAIL_MAX_AGE_S)
              & (p[:, 3] <= t_s)]
        if p.size:
            p = p[np.lexsort((p[:, 3], p[:, 0]))]                 # by track, oldest first
            _, first, counts = np.unique(p[:, 0], return_index=True, return_counts=True)
            rank_from_end = np.repeat(first + counts, counts) - np.arange(len(p))
            p = p[rank_from_end <= TRAIL_MAX_POINTS]
        self._xyt = p

    def clear(self) -> None:
        self._xyt = np.zeros((0, 4))

    def trails(self) -> list[tuple[np.ndarray, np.ndarray]]:
        """Per track, its points (x, y), oldest first."""
        p = self._xyt
        if not p.size:
            return []
        p = p[np.lexsort((p[:, 3], p[:, 0]))]
        _, first = np.unique(p[:, 0], return_index=True)
        return [(s[:, 1], s[:, 2]) for s in np.split(p, first[1:])]


__all__ = ["SensorMount", "VehicleTrails", "boundary_reference", "curvature", "dead_reckon", "fit_course",
           "fit_trail", "in_path", "path_offset_m", "plausible", "road_course", "trail_course", "trail_fits",
           "BoundaryDrift", "crossing_road"]
