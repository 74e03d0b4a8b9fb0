"""Where the ego will drive, in the vehicle frame, and where the radar sits in it (DESIGN §7; issue 10).

The ECU knows the radar's mount as it is calibrated into a real ECU: its position from the rear-axle centre
(x forward, y left) and its yaw. Tracks arrive in the sensor frame; :meth:`SensorMount.to_vehicle` moves them
to the vehicle frame. The predicted path is the circle the rear axle drives at the curvature
κ = yaw rate / speed (a vehicle turns about its rear axle); a point is in the path when its lateral distance
from that circle is within the path's half-width. Where the radar reports both road edges, the path may not
leave the road (the edges are in the sensor frame, as they were measured).

The yaw rate knows only the curve the ego is in, not the one ahead: entering a curve through a clothoid it still
says "straight" while the lane ahead already bends. Where the radar reports a road boundary, its course ahead —
y_b(x) − y_b(0), the lateral shift of a line parallel to the road — is where the ego will be at x if it keeps
its place on the road, and it takes over from the yaw-rate circle between :data:`BLEND_START_M` and
:data:`BLEND_END_M` ahead, up to :data:`COURSE_EXTENT` times the boundary's valid range (its curvature carries it
on) (what production course prediction does with the road geometry from stationary
targets). Not while the ego turns across the road (a lane change: its heading to the boundaries, averaged,
beyond :data:`LANE_KEEPING_HEADING_RAD`; a single boundary's heading is not enough, as a quadratic fit to a
clothoid tilts it by a degree or two): then the yaw rate is the better guess.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radarnode import validate

MIN_SPEED_FOR_CURVATURE_MPS = 1.0
BLEND_START_M, BLEND_END_M = 20.0, 60.0     # the road's course takes over from the yaw-rate circle over this span
LANE_KEEPING_HEADING_RAD = 0.05             # 2.9°: beyond it the ego crosses the road (a lane change)
MAX_BOUNDARY_HEADING_RAD = 0.1              # 5.7°: a boundary at a steeper angle to the ego is no road edge
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
        c, s = math.cos(math.radians(self.yaw_deg)), math.sin(math.radians(self.yaw_deg))
        return self.x_m + c * x - s * y, self.y_m + s * x + c * y

    def rotate(self, vx: np.ndarray, vy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Sensor-frame velocities (relative to the sensor) to vehicle axes."""
        c, s = math.cos(math.radians(self.yaw_deg)), math.sin(math.radians(self.yaw_deg))
        return c * vx - s * vy, s * vx + c * vy


def path_offset_m(x: np.ndarray, y: np.ndarray, curvature_1pm: float) -> np.ndarray:
    """Signed lateral distance (left positive) of vehicle-frame points from the rear axle's circle."""
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    if abs(curvature_1pm) < 1e-9:
        return y
    r = 1.0 / curvature_1pm                                  # centre at (0, r); left turn r > 0
    return math.copysign(1.0, r) * (abs(r) - np.hypot(x, y - r))


def in_path(x: np.ndarray, y: np.ndarray, ego_speed_mps: float, yaw_rate_rps: float, half_width_m: float,
            boundaries: dict | None = None, mount: SensorMount | None = None) -> np.ndarray:
    """Which sensor-frame points lie ahead in the ego's predicted path.

    ``mount=None`` takes the sensor at the rear axle (the circle then starts at the sensor).
    """
    x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
    kappa = yaw_rate_rps / ego_speed_mps if ego_speed_mps > MIN_SPEED_FOR_CURVATURE_MPS else 0.0
    m = mount if mount is not None else SensorMount(0.0, 0.0, 0.0)
    xv, yv = m.to_vehicle(x, y)
    offset = path_offset_m(xv, yv, kappa)
    course = road_course(x, boundaries)
    if course is not None:
        shift, covered = course
        w = np.clip((x - BLEND_START_M) / (BLEND_END_M - BLEND_START_M), 0.0, 1.0) * covered
        offset = (1.0 - w) * offset + w * (y - shift)
    inside = (xv > m.x_m) & (np.abs(offset) <= half_width_m)
    for side, b in plausible(boundaries):
        inside &= (y < b.y_at(x)) if side == "left" else (y > b.y_at(x))
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


def road_course(x: np.ndarray, boundaries: dict | None) -> tuple[np.ndarray, np.ndarray] | None:
    """The road's lateral course ahead from the valid reported boundaries, sensor frame: (shift (m) at ``x``, 1
    where a boundary covers ``x`` else 0), averaged over the boundaries; None without one, or while the ego's
    heading to the road (the boundaries' average) exceeds LANE_KEEPING_HEADING_RAD (it is crossing the road)."""
    valid = [b for _, b in plausible(boundaries)]
    if not valid or abs(sum(b.heading_rad for b in valid) / len(valid)) > LANE_KEEPING_HEADING_RAD:
        return None
    x = np.asarray(x, dtype=np.float64)
    shift = np.zeros(x.shape)
    n = np.zeros(x.shape)
    for b in valid:
        on = (x >= 0.0) & (x <= COURSE_EXTENT * b.range_end_m)
        shift += np.where(on, b.y_at(x) - b.offset_m, 0.0)
        n += on
    return np.where(n > 0, shift / np.maximum(n, 1), 0.0), (n > 0).astype(np.float64)


__all__ = ["SensorMount", "in_path", "path_offset_m", "plausible", "road_course"]
