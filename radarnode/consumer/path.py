"""Where the ego will drive, in the vehicle frame, and where the radar sits in it (DESIGN §7; issue 10).

The ECU knows the radar's mount as it is calibrated into a real ECU: its position from the rear-axle centre
(x forward, y left) and its yaw. Tracks arrive in the sensor frame; :meth:`SensorMount.to_vehicle` moves them
to the vehicle frame. The predicted path is the circle the rear axle drives at the curvature
κ = yaw rate / speed (a vehicle turns about its rear axle); a point is in the path when its lateral distance
from that circle is within the path's half-width. Where the radar reports both road edges, the path may not
leave the road (the edges are in the sensor frame, as they were measured).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radarnode import validate

MIN_SPEED_FOR_CURVATURE_MPS = 1.0


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
    inside = (xv > m.x_m) & (np.abs(path_offset_m(xv, yv, kappa)) <= half_width_m)
    if boundaries:
        left, right = boundaries.get("left"), boundaries.get("right")
        if left is not None and left.valid:
            inside &= y < left.y_at(x)
        if right is not None and right.valid:
            inside &= y > right.y_at(x)
    return inside


__all__ = ["SensorMount", "in_path", "path_offset_m"]
