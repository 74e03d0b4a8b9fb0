"""Adaptive cruise control on the tracked object list (ISO 15622 limits, DESIGN §7).

Target: the nearest track in the ego path (predicted from yaw rate over
speed, or the lane between the road boundaries when the radar reports them)
that is a road user: moving, stopped, or a stationary vehicle-class object.
Control: the smaller of a speed loop, k_s·(v_set − v), and a gap loop,
k_d·(d − d_des) + k_v·Δv + lead acceleration, with d_des = max(d_0, τ·v); then
the acceleration, deceleration and jerk limits of ISO 15622 by speed.
States: off, standby (no target handling, no request), active, fault (radar
unavailable or stale: the request is released to zero and flagged).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radarnode import validate
from radarnode.errors import FieldError
from radarnode.scene.scenario import ACC_TIME_GAPS_S

STATE_OFF, STATE_STANDBY, STATE_ACTIVE, STATE_FAULT = 0, 1, 2, 3
STATE_NAMES = ("off", "standby", "active", "fault")


@dataclass(frozen=True)
class AccSettings:
    """Driver settings and controller gains."""

    enabled: bool = True
    set_speed_mps: float = 30.0
    time_gap_s: float = 1.5
    standstill_gap_m: float = 4.0
    k_speed: float = 0.4
    k_gap: float = 0.2
    k_rel_speed: float = 0.8
    path_half_width_m: float = 1.6
    min_speed_mps: float = 0.0         # below it ACC waits in standby (ISO 15622 ACC without stop and go: ~5 m/s)

    def __post_init__(self) -> None:
        validate.boolean("enabled", self.enabled)
        validate.number("set_speed_mps", self.set_speed_mps, lo=0.0, hi=70.0)
        if self.time_gap_s not in ACC_TIME_GAPS_S:
            raise FieldError("time_gap_s", self.time_gap_s, "one of 1.0, 1.5, 2.0 s (ISO 15622 settings)")
        validate.number("standstill_gap_m", self.standstill_gap_m, lo=1.0, hi=20.0)
        for f in ("k_speed", "k_gap", "k_rel_speed"):
            validate.number(f, getattr(self, f), lo=0.0, hi=5.0)
        validate.number("path_half_width_m", self.path_half_width_m, lo=0.5, hi=5.0)
        validate.number("min_speed_mps", self.min_speed_mps, lo=0.0, hi=30.0)


def iso15622_limits(speed_mps: float) -> tuple[float, float, float]:
    """(max deceleration (negative), max acceleration, max jerk) at an ego speed; linear between 5 and 20 m/s."""
    f = min(max((speed_mps - 5.0) / 15.0, 0.0), 1.0)
    return -5.0 + 1.5 * f, 4.0 - 2.0 * f, 5.0 - 2.5 * f


@dataclass(frozen=True)
class Target:
    """The selected object: track ID, distance (m, along x), relative speed (m/s, negative closing), lead accel."""

    track_id: int
    object_id: int
    distance_m: float
    lateral_m: float
    rel_speed_mps: float
    lead_accel_mps2: float


class Acc:
    """The ACC state machine and controller; call :meth:`step` once per radar cycle."""

    def __init__(self, settings: AccSettings = AccSettings()) -> None:
        self.settings = settings
        self.state = STATE_ACTIVE if settings.enabled else STATE_OFF
        self.request = 0.0
        self.fault = False

    def step(self, dt: float, ego_speed_mps: float, target: Target | None, radar_ok: bool) -> float:
        """The acceleration request (m/s²) for this cycle."""
        s = self.settings
        if not s.enabled:
            self.state, self.request = STATE_OFF, 0.0
            return 0.0
        if not radar_ok:
            # never act on stale objects: release the request and flag the fault
            self.state, self.fault, self.request = STATE_FAULT, True, 0.0
            return 0.0
        if self.state == STATE_FAULT:
            self.state, self.fault = STATE_ACTIVE, False
        if ego_speed_mps < s.min_speed_mps:
            # standby: engaged by the driver but below the operating speed; the request ramps out
            self.state = STATE_STANDBY
            step = iso15622_limits(ego_speed_mps)[2] * dt if dt > 0 else abs(self.request)
            self.request = float(np.clip(0.0, self.request - step, self.request + step))
            return self.request
        self.state = STATE_ACTIVE
        a_min, a_max, jerk = iso15622_limits(ego_speed_mps)
        want = s.k_speed * (s.set_speed_mps - ego_speed_mps)
        if target is not None:
            # the time gap is the setting; the standstill gap only matters at low speed
            d_des = max(s.standstill_gap_m, s.time_gap_s * ego_speed_mps)
            gap = (s.k_gap * (target.distance_m - d_des) + s.k_rel_speed * target.rel_speed_mps
                   + 0.5 * target.lead_accel_mps2)
            want = min(want, gap)
        want = min(max(want, a_min), a_max)
        if dt > 0:
            step = jerk * dt
            want = min(max(want, self.request - step), self.request + step)
        self.request = want
        return want

    @staticmethod
    def time_gap(distance_m: float, ego_speed_mps: float) -> float:
        return distance_m / ego_speed_mps if ego_speed_mps > 0.1 else math.inf
