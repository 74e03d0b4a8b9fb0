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
LEAD_STOPPED_MPS = 0.5        # a lead slower than this is stopped
STOP_APPROACH_MPS = 5.0       # below this the ego brakes to stop exactly at the standstill gap behind a stopped lead
STANDSTILL_MPS = 0.1          # the ego is standing
STOP_DECEL_MPS2 = 1.0         # the stopping curve's deceleration behind a stopped lead
STOP_GAIN = 1.0               # 1/s, speed error to acceleration on that curve
STOP_RESPONSE_S = 0.5         # the brakes' response (actuator lag, ECU latency, jerk limit) in the stopping room
HOLD_MPS2 = -1.5              # brake request while holding the standstill
AUTO_RESUME_S = 3.0           # ISO 22179: after a longer standstill only the driver resumes


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
    path_from_trails: bool = True      # the trails of the vehicles ahead shape the predicted path (path.py)
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
        validate.boolean("path_from_trails", self.path_from_trails)
        validate.number("min_speed_mps", self.min_speed_mps, lo=0.0, hi=30.0)


def iso15622_limits(speed_mps: float) -> tuple[float, float, float]:
    """(max deceleration (negative), max acceleration, max jerk) at an ego speed; linear between 5 and 20 m/s."""
    f = min(max((speed_mps - 5.0) / 15.0, 0.0), 1.0)
    return -5.0 + 1.5 * f, 4.0 - 2.0 * f, 5.0 - 2.5 * f


@dataclass(frozen=True)
class Target:
    """The selected object: track ID, distance (m, along x), relative speed (m/s, negative closing), lead accel;
    ``coasted``: not measured this cycle — the ECU's track took no object of the cycle's list (it predicts it: the
    radar did not list it, or listed it where the track's gate did not take it, as at an impact), or a lost target
    carried on by dead reckoning."""

    track_id: int
    object_id: int
    distance_m: float
    lateral_m: float
    rel_speed_mps: float
    lead_accel_mps2: float
    coasted: bool = False


class Acc:
    """The ACC state machine and controller; call :meth:`step` once per radar cycle."""

    def __init__(self, settings: AccSettings = AccSettings()) -> None:
        self.settings = settings
        self.state = STATE_ACTIVE if settings.enabled else STATE_OFF
        self.request = 0.0
        self.fault = False
        self.standstill = False          # holding the ego at a standstill (behind a stopped lead, or with none)
        self.behind_lead = False         # … entered behind a stopped lead (it may resume by itself when the lead goes)
        self.departing = False           # resumed from a standstill, the ego not moving yet
        self.standstill_s = 0.0          # how long it has held
        self.resume_confirmed = False    # the driver's resume (needed after AUTO_RESUME_S of standstill)
        self.take_over = False           # the required deceleration exceeds ACC's authority: driver must brake

    def confirm_resume(self) -> None:
        """The driver confirms driving off (the resume button or a tap on the accelerator, ISO 22179)."""
        self.resume_confirmed = True

    def step(self, dt: float, ego_speed_mps: float, target: Target | None, radar_ok: bool,
             no_accel: bool = False, borrowed: bool = False) -> float:
        """The acceleration request (m/s²) for this cycle; ``no_accel`` (a collision warning is on, or a near target
        was just lost): none above 0, reached within the jerk limit. ``borrowed``: the target is the object FCW warns
        of, not a vehicle ACC follows: stopped behind it, ACC holds until the driver resumes."""
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
        self.take_over = False
        if target is not None:
            lead_v = ego_speed_mps + target.rel_speed_mps
            # the time gap is the setting; the standstill gap only matters at low speed
            d_des = max(s.standstill_gap_m, s.time_gap_s * ego_speed_mps)
            gap = (s.k_gap * (target.distance_m - d_des) + s.k_rel_speed * target.rel_speed_mps
                   + 0.5 * target.lead_accel_mps2)
            if lead_v < LEAD_STOPPED_MPS and ego_speed_mps < STOP_APPROACH_MPS:
                # behind a stopped lead: close to the standstill gap on a comfortable stopping curve,
                # v = √(2·a·room), and stop there (the gap loop alone creeps: its speed term and its gap term
                # cancel near the lead)
                # (never accelerating towards it; the room counts what the ego covers while the brakes respond)
                # below the curve, the constant deceleration that stops in the room: the ego slows all the way
                # instead of coasting up to the curve (at 2.7 m/s 11.7 m behind, request 0 until 9 m, then the curve's
                # 1 m/s²: the time to collision at 0 m/s² fell to 2.3 s and FCW warned behind a lead that ACC was
                # stopping for — a tester's finding)
                # (that deceleration from the room to the standstill gap itself: v²/(2·room) is then the same at every
                # step of a constant-deceleration stop, which ends at the gap; taken with the brakes' response in the
                # room, it shrank with the speed and the ego crept the last metre for seconds)
                room = max(target.distance_m - s.standstill_gap_m - ego_speed_mps * STOP_RESPONSE_S, 0.0)
                v_curve = math.sqrt(2.0 * STOP_DECEL_MPS2 * room)
                steady = -ego_speed_mps ** 2 / (2.0 * max(target.distance_m - s.standstill_gap_m, 0.05))
                gap = min(STOP_GAIN * (v_curve - ego_speed_mps), steady) if room > 0.2 else -2.0 * STOP_DECEL_MPS2
            want = min(want, gap)
            # what avoiding the lead needs beyond ACC's authority is the driver's: take-over request
            closing = -target.rel_speed_mps
            if closing > 0 and target.distance_m > 0:
                need = target.lead_accel_mps2 - closing ** 2 / (2.0 * max(target.distance_m - 1.0, 0.1))
                self.take_over = need < a_min
        else:
            lead_v = math.inf
        # standstill: hold the brake (no creep); drive off when the lead has, automatically after a short stop,
        # with the driver's confirmation after a long one (ISO 22179)
        # standing with no lead to follow (engaged at a standstill, or stopped without one): it holds until the driver
        # resumes — it drove off towards its set speed into a stopped car 4–32 m ahead that it had never seen move
        # (an independent tester's finding; ISO 22179 leaves such a start to the driver)
        if self.standstill:
            self.standstill_s += max(dt, 0.0)
            lead_gone = target is None or lead_v > LEAD_STOPPED_MPS + 0.5
            # by itself only behind a lead seen driving off: one that vanished or left the path standing was the
            # radar's loss (a track that slid from the lead onto a truck parked beside it left the path, and ACC
            # drove into the lead — an independent tester's finding at the detection level)
            auto = self.behind_lead and self.standstill_s <= AUTO_RESUME_S and target is not None
            if lead_gone and (auto or self.resume_confirmed):
                self.standstill, self.standstill_s, self.resume_confirmed = False, 0.0, False
                self.departing = True
            else:
                self.request = HOLD_MPS2
                return self.request
        elif ego_speed_mps < STANDSTILL_MPS and ((target is None and not self.departing)
                                                 or (target is not None and lead_v < LEAD_STOPPED_MPS)):
            self.standstill, self.standstill_s, self.resume_confirmed = True, 0.0, False
            self.behind_lead = target is not None and not borrowed
            self.request = HOLD_MPS2
            return self.request
        if ego_speed_mps >= STANDSTILL_MPS:
            self.departing = False
        want = min(max(want, a_min), 0.0 if no_accel else a_max)
        if dt > 0:
            step = jerk * dt
            want = min(max(want, self.request - step), self.request + step)
        self.request = want
        return want

    @staticmethod
    def time_gap(distance_m: float, ego_speed_mps: float) -> float:
        return distance_m / ego_speed_mps if ego_speed_mps > 0.1 else math.inf
