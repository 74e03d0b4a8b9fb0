"""The consumer ECU: decoded radar cycles → tracker → ACC and FCW → status frames on the bus.

:class:`Ecu` is fed by a :class:`~radarnode.consumer.assembler.CycleAssembler` (``on_cycle``), reads the
ego's speed and yaw rate from the same bus (0x300/0x301, as the radar does), and after every radar cycle
produces the ACC request, the FCW level and the two status frames AccStatus 0x6C0 and FcwStatus 0x6C1
(``dbc/radarnode.dbc``, E2E Profile 2; one ECU per bus, so these IDs do not move with the sensor ID). When no complete radar cycle has arrived for ``timeout_cycles``
cycle periods the radar is unavailable: ACC goes to fault and releases its request (:meth:`Ecu.tick`), and FCW
keeps judging the object it judged last, dead-reckoned with the ego motion (``FCW_COAST_S``), so that a warning is
not withdrawn because the sensor fell silent. Once the ECU reads the ego motion (:meth:`Ecu.set_ego`), no new
ego speed for the same time-out is a missing input too: ACC goes to fault and FCW goes on with the last values.
Both are reported in ACC_Fault and FCW_Fault (bit 0 radar, bit 1 ego motion).

Every time the ECU is given is checked before it reaches the tracker (:attr:`Ecu.stats` counts what was refused):
a timestamp that is not a finite number or lies beyond ±1e11 s is refused; one that runs backwards or jumps
ahead by more than ``max_gap_s`` skips its cycle, and when the next cycle continues from the skipped one (a
new time base: a restarted clock, a long pause) tracking restarts there, while a single stray timestamp
leaves the tracks as they were. A step ahead within ``max_gap_s`` but of more than ``STRAY_STEP_PERIODS``
cycles (a pause, or one cycle stamped ahead) is tracked, the state before it kept: a next cycle that continues
from before it shows it stray, and the tracks go back to that state (``stats.stray_undone``). No exception from the data escapes :meth:`Ecu.on_cycle`.
"""

from __future__ import annotations

import copy
import dataclasses
import logging
import math
from dataclasses import dataclass

import can
import numpy as np

from radarnode.consumer.acc import LEAD_STOPPED_MPS, Acc, AccSettings, Target
from radarnode.consumer.path import (BoundaryDrift, SensorMount, VehicleTrails, aligned_boundaries, boundary_reference,
                                     course_known, crossing_road, curvature, in_path, measured_reach_m, path_heading,
                                     path_offset_m, trail_fits)
from radarnode.consumer.assembler import ClusterCycle, ObjectCycle
from radarnode.consumer.fcw import LEVEL_WARNING, Fcw, FcwSettings
from radarnode.consumer.overhead import OVERHEAD_DEPTH_M, STRUCTURE_POSSIBLE, STRUCTURE_WIDE, LandmarkMap
from radarnode.consumer.tracking import Tracker, line_of_sight, radial_mismatch2
from radarnode.perception.motion import road_share
from radarnode.perception.types import DYN_MOVING, DYN_ONCOMING, MEAS_PREDICTED
from radarnode.wire import ids
from radarnode.wire.codec import MessageCodec
from radarnode.wire.dbc import load_own_database
from radarnode.wire.e2e import E2EProtector

logger = logging.getLogger(__name__)

ACC_STATUS, FCW_STATUS = ids.ACC_STATUS, ids.FCW_STATUS
VEHICLE_CLASSES = (1, 2, 4)          # car, truck, motorcycle: stationary ones still count in the path
#: a stationary object in the path is a collision candidate, whatever its class, when it reflects like a vehicle
#: (a car's rear ≈ 10 dBsm; a guardrail post, a pedestrian ≈ −5) and has been tracked for this many cycles
OBSTACLE_RCS_DBSM = 0.0          # of the track's power-averaged RCS: a car ≈ 10, a motorcycle ≈ 3, merged posts ≈ −2
OBSTACLE_MIN_AGE = 4
OBSTACLE_RCS_POWER = 10.0 ** (OBSTACLE_RCS_DBSM / 10.0)
RCS_AVERAGE_GAIN = 0.2
ENTER_CYCLES, EXIT_CYCLES = 3, 4     # target selection hysteresis (cycles in / out of the predicted path)
#: FCW leaves out a target whose speed across the path — the least of it within CLEAR_SIGMAS of its σ — carries the
#: point the radar reports more than the path's half-width plus the body's extent beyond the path's centre line by
#: the time the ego gets there (the gap over the closing speed): a car crossing the road that will have cleared it
#: (ISO 15623 warns for a collision, not for a car in the lane now). The body's extent: the larger of its length and
#: width as the radar reports them, at least CLEAR_EXTENT_M (the reported point may be any corner, and a body seen as
#: one detection is reported 0.2 m long: a bicycle that stopped in the lane was left out)
CLEAR_SIGMAS = 3.0
CLEAR_EXTENT_M = 5.0
#: … and only a target that moves across the path more than along it by this angle: its motion over ground at least
#: CLEAR_MIN_ANGLE_DEG off the path's direction where it is (a crossing road user, not a lead on a curve entry whose
#: road the yaw-rate circle does not follow yet)
CLEAR_MIN_ANGLE_DEG = 30.0
#: … and only one that cannot stop inside the path: braking at this deceleration from that least speed across, it
#: still carries its point beyond the path's half-width plus its extent (a car crossing that brakes to a stop in the
#: lane — its track's speed across lags the stop by several σ at the detection and signal levels — stays FCW's
#: candidate while it is in the path; a car's full braking on a dry road, the least stopping distance)
CLEAR_BRAKE_MPS2 = 10.0
#: … and only one not braking across the path: its track's acceleration across against its motion there is at most
#: this (a car crossing at 16–20 m/s that brakes at 9–10 m/s² to a stop in the lane: its track's speed across lags the
#: braking, and at that speed it looked unable to stop in the path — warned 0.5–0.7 s later at the detection level)
CLEAR_BRAKING_MPS2 = 1.0
#: … and a body is all its pieces: a long vehicle crossing (a truck, a bus) is several tracks at the detection and
#: signal levels, each reported 5–9 m long; the front pieces cleared by their own extent while the tail was still to
#: come, and the ego hit a 16.5-m truck's rear part unwarned in 6 of 8 seeds (an independent tester). Tracks moving
#: together — across the path the same way within CLEAR_BODY_SPEED_MPS, along it within the same, at most
#: CLEAR_BODY_DEPTH_M apart along the path and CLEAR_BODY_GAP_M across it (the longest road vehicles, 18.75 m, with a
#: piece's extent) — are one body: each piece's extent is at least the body's (body_extent), and a piece does not
#: clear while a piece trailing it has not (body_clears)
CLEAR_BODY_SPEED_MPS = 2.0
CLEAR_BODY_DEPTH_M = 4.0
CLEAR_BODY_GAP_M = 20.0
MOVING_MPS = 1.0                     # over ground: a track that moved faster has been seen moving
#: the highest reflector above the radar an overhead structure puts in its path (m): a stationary one at range R
#: seems to move away at up to v·(1 − cos asin(H/R)) (its Doppler is v·cos(elevation)); only more counts as moving
OVERHEAD_HEIGHT_M = 8.0
#: … but only for a track that could be a structure's reflector: one measured standing still (a structure's own track
#: is, from afar), one first seen at a structure recognised as overhead or reported as wide as one
#: (LandmarkMap.structure_at), or one first seen where a structure could stand that reflects less than a vehicle
#: (OBSTACLE_RCS_DBSM, power-averaged: a deck's or a gantry's parts first seen within 16 m were −6 … −33 dBsm, seen
#: from below through the elevation beam's sidelobes; a car is about 10). Any other track's speed over ground counts
#: from MOVING_MPS (a lead first seen 6 m ahead at the ego's 4 m/s was never followed — within 8 m the allowance
#: reaches the ego's speed — nor a car creeping at 1.5 m/s first seen 17–30 m ahead, nor either of them beside a
#: parked truck or a sign). What the ECU knows of where each track was first seen (_born's third field): one of these
BORN_CLEAR, BORN_NEAR_STRUCTURE, BORN_AT_STRUCTURE, STOOD_STILL = 0, 1, 2, 3
STATIONARY_MPS = 1.0                 # over ground: slower is stationary (filed in the landmark map)
MOVED_CYCLES = 3                     # cycles in a row of moving that make a track one seen moving
#: over ground, against the predicted path's direction where the track is: faster is oncoming traffic, which neither
#: ACC follows nor FCW warns for (ISO 15622/15623 address vehicles ahead moving our way or standing); 18 km/h, above
#: a car reversing towards the ego (3 m/s ignored one reversing at 11 km/h), below any oncoming traffic on a road
ONCOMING_MPS = 5.0
DEFAULT_WAVELENGTH_M = 299_792_458.0 / 77e9
MAX_TIME_S = 1e11                    # |t| beyond this (≈ 3000 years) is not a time but a broken value
#: a longer step between cycles is a discontinuity, not tracking (the default: this or STRAY_STEP_PERIODS + 1 cycle
#: periods, whichever is longer, as a radar may cycle up to every 10 s)
MAX_GAP_S = 5.0
#: the ego speed and yaw rates the bus carries (SpeedInformation 0x300: 0–163.82 m/s, forward or backward;
#: YawRateInformation 0x301: −327.68…327.66 °/s, as the radar node takes them): set_ego takes none beyond them
#: (counted in stats.bad_ego)
EGO_SPEED_LIMIT_MPS = 163.82
EGO_YAW_RATE_RANGE_DPS = (-327.68, 327.66)
#: a step ahead of more than this many cycle periods may be one stray timestamp: the tracking state before it is
#: kept until the next cycle shows which (:meth:`Ecu._accept_time`)
STRAY_STEP_PERIODS = 3.0
#: the least σ taken for a cluster's radial speed (its σ fields come quantised; a Doppler bin is 0.1–0.3 m/s)
RADIAL_SIGMA_FLOOR_MPS = 0.5
#: what tracking is: restored when the cycle after a jump ahead continues from before it (the jump was a stray)
TRACKING_STATE = ("tracker", "cluster_tracker", "_in_path", "_out_path", "_target_id", "_fcw_target_id", "_rcs_power",
                  "_lost_until", "_last_acc", "_last_acc_place", "_lost_place", "_path_inputs", "_braking_for",
                  "_obstacles", "_placed", "_born", "_moved", "_moving_for", "landmarks", "trails", "trail_fits",
                  "last_cycle_t", "_last_out_t", "acc", "fcw", "odometry", "drift", "_coast")
#: while the radar is unavailable FCW judges the object it judged last, where the ego motion and the object's last
#: speed and acceleration put it (a lead that brakes stops and stays), while it stays in the predicted path, at no
#: higher a level than when the radar fell silent (dead reckoning alone raises no warning: a coast that did warned for
#: a stopped car the ego was steering away from, an independent tester's finding), for at most this long (s): the
#: time-out and this cover the TTC at which FCW pre-warns (4 s); after it the warning falls as the hysteresis lets it
FCW_COAST_S = 4.0
#: a target ACC followed that vanished from the object list within this distance (m) …
LOST_NEAR_M = 20.0
#: … holds ACC from accelerating this long (s) unless another target is taken: the radar lost a lead braking beside a
#: truck parked in the next lane (masked in its CA-CFAR ring) and ACC accelerated into it
LOST_HOLD_S = 2.0
#: ACC begins to brake for the object FCW warns of when it has no nearer target of its own (a stationary object it
#: never saw move, which it does not follow) up to this ego speed (m/s), and once braking goes on while FCW keeps that
#: object, whatever the speed (braking only up to 5 m/s, a car warned for at 4.7 m/s was run into at 5.2 m/s once a
#: jerk-limited ramp let the speed pass 5 m/s — an independent tester's finding). Above it ACC leaves a stationary
#: object to the driver FCW warns, as ISO 15622 does: begun wherever stopping was within ACC's authority, it braked
#: at up to −4.7 m/s² for FCW's false alarms at curve entries at 8–16 m/s (a second tester's finding).
#: A target lost within LOST_NEAR_M while it went at most this fast over ground (stop-and-go), and a standing one that
#: leaves ACC while its track lives on, is remembered standing (:meth:`Ecu._remembered`): ACC stops behind that place,
#: while it lies in the path, and holds there until the driver resumes (the radar lost a lead braking to a stop
#: beside a truck parked in the next lane, masked in its CA-CFAR ring; after LOST_HOLD_S ACC accelerated from
#: 0.3 m/s into it, 8 m ahead — an independent tester's scene) …
FCW_BRAKE_MAX_MPS = 5.0
#: … the place where it stands if it braked this hard (m/s², about what a car's brakes can) from its last speed: as
#: near as it can be (taken where it was last seen, ACC stopped a lead's length short of a lead lost at 10 m, 5 m/s)
LOST_LEAD_DECEL_MPS2 = 8.0
#: a target ACC takes within this distance (m) of a lost target's place along the path, and within
#: LOST_MATCH_LATERAL_M across it, is that target found again (a track of a parked truck's side 1.2 m ahead at the
#: lane's edge was not the lead lost 3 m ahead of it)
LOST_MATCH_M = 3.0
LOST_MATCH_LATERAL_M = 1.0
TRAIL_MIN_LENGTH_M = 2.5             # an object of another class leaves a trail when it is at least this long …
TRAIL_MIN_WIDTH_M = 1.4              # … or wide (a vehicle the radar did not classify)
#: … once its track has run this long (s): a track's first second is its tracker's convergence, not the vehicle's
#: course (a car at 10 m/s in the next lane, first seen 100 m ahead as the ego closed at 20 m/s: its reported place
#: drifted 0.5 m in that second, the course fitted to its 16-m trail 50–66 m ahead took the drift for the road's
#: heading and ran 2.6 m towards it 60 m ahead, and FCW warned for it: benchmarks/abreast_fcw.py's one-car rows)
TRAIL_MIN_AGE_S = 1.0


def clears_path(offset_m: np.ndarray, across_mps: np.ndarray, sigma_mps: np.ndarray, reach_s: np.ndarray,
                half_width_m: float, extent_m: np.ndarray, along_mps: np.ndarray | float = 0.0,
                across_accel_mps2: np.ndarray | float = 0.0) -> np.ndarray:
    """Whether targets at ``offset_m`` from the path's centre line (left positive), moving across it at
    ``across_mps`` (σ ``sigma_mps``) and along it at ``along_mps`` over ground, will have cleared it ``reach_s`` from
    now: the least speed across within CLEAR_SIGMAS of its σ carries the reported point more than ``half_width_m`` +
    ``extent_m`` beyond the centre line on the side it moves to (a body of that extent around the point then lies
    wholly outside the path), that speed is more than CLEAR_MIN_ANGLE_DEG off the path's direction, and braking at
    CLEAR_BRAKE_MPS2 from it the point would still get that far (it cannot stop in the path), and it is not braking:
    its acceleration across (``across_accel_mps2``) against its motion there at most CLEAR_BRAKING_MPS2."""
    w = np.asarray(across_mps, dtype=np.float64)
    least = np.sign(w) * np.maximum(np.abs(w) - CLEAR_SIGMAS * np.asarray(sigma_mps, dtype=np.float64), 0.0)
    offset = np.asarray(offset_m, dtype=np.float64)
    need = half_width_m + np.asarray(extent_m, dtype=np.float64)
    later = offset + least * np.asarray(reach_s, dtype=np.float64)
    stops = np.sign(least) * offset + least * least / (2.0 * CLEAR_BRAKE_MPS2)      # where it stands if it brakes now
    crossing = np.abs(least) > math.tan(math.radians(CLEAR_MIN_ANGLE_DEG)) * np.abs(np.asarray(along_mps, dtype=float))
    braking = np.sign(least) * np.asarray(across_accel_mps2, dtype=np.float64) < -CLEAR_BRAKING_MPS2
    return crossing & ~braking & (np.sign(least) * later > need) & (stops > need)


def _same_body(offset_m: np.ndarray, across_mps: np.ndarray, along_mps: np.ndarray, ahead_m: np.ndarray
               ) -> tuple[np.ndarray, np.ndarray]:
    """(together, behind), shape (n, n): whether targets i and j move as one body — across the path the same way within
    CLEAR_BODY_SPEED_MPS, along it within the same, at most CLEAR_BODY_DEPTH_M apart in ``ahead_m`` (distance along
    the path), at most CLEAR_BODY_GAP_M apart across it — and how far j trails i in i's motion across (``offset_m``
    left of the path's centre line, ``across_mps`` to the left)."""
    w = np.asarray(across_mps, dtype=np.float64)
    off = np.asarray(offset_m, dtype=np.float64)
    along = np.asarray(along_mps, dtype=np.float64)
    ahead = np.asarray(ahead_m, dtype=np.float64)
    side = np.sign(w)
    behind = side[:, None] * (off[:, None] - off[None, :])
    together = ((side[:, None] == side[None, :]) & (side[:, None] != 0)
                & (np.abs(w[:, None] - w[None, :]) <= CLEAR_BODY_SPEED_MPS)
                & (np.abs(along[:, None] - along[None, :]) <= CLEAR_BODY_SPEED_MPS)
                & (np.abs(ahead[:, None] - ahead[None, :]) <= CLEAR_BODY_DEPTH_M)
                & (np.abs(behind) <= CLEAR_BODY_GAP_M))
    np.fill_diagonal(together, False)
    return together, behind


def body_extent(extent_m: np.ndarray, offset_m: np.ndarray, across_mps: np.ndarray, along_mps: np.ndarray,
                ahead_m: np.ndarray) -> np.ndarray:
    """Each target's extent for :func:`clears_path`, at least that of the body it is a piece of (:func:`_same_body`):
    the span of the body's pieces across the path plus the largest piece's extent (a 12-m truck seen as two tracks
    4.5 m apart, each reported 5–6 m long: its trailing piece cleared the path by 0.07 m with its own extent while
    its tail, 6 m behind that piece's point, was still to come)."""
    extent = np.asarray(extent_m, dtype=np.float64)
    if extent.size < 2:
        return extent
    together, behind = _same_body(offset_m, across_mps, along_mps, ahead_m)
    if not together.any():
        return extent
    span = np.where(together, np.abs(behind), 0.0).max(axis=1)
    largest = np.maximum(extent, np.where(together, extent[None, :], 0.0).max(axis=1))
    return np.where(together.any(axis=1), span + largest, extent)


def body_clears(clears: np.ndarray, offset_m: np.ndarray, across_mps: np.ndarray, along_mps: np.ndarray,
                ahead_m: np.ndarray) -> np.ndarray:
    """``clears`` (:func:`clears_path` of each target) where no other piece of the same body (:func:`_same_body`)
    trails it uncleared."""
    clears = np.asarray(clears, dtype=bool)
    if clears.size < 2 or not clears.any():
        return clears
    together, behind = _same_body(offset_m, across_mps, along_mps, ahead_m)
    return clears & ~np.any(together & (behind > 0.0) & ~clears[None, :], axis=1)


@dataclass
class EcuStats:
    """What the ECU refused or repaired, besides the cycles it used."""

    cycles: int = 0                  # radar cycles tracked
    rejected_time: int = 0           # timestamps that are NaN, infinite or beyond ±MAX_TIME_S: refused
    time_jumps: int = 0              # cycles skipped: time ran backwards or jumped ahead by more than max_gap_s
    stray_undone: int = 0            # a cycle stamped ahead (within max_gap_s) that the next one showed stray: undone
    time_resyncs: int = 0            # a new time base confirmed by the next cycle: tracking restarted
    bad_measurements: int = 0        # list entries with a non-finite value: left out
    bad_ego: int = 0                 # ego-motion inputs with a non-finite time or value: ignored
    internal_errors: int = 0         # the tracker failed on a cycle: tracks restarted (should stay 0)

    def as_dict(self) -> dict[str, int]:
        return dataclasses.asdict(self)


@dataclass
class EcuOutput:
    """What the ECU decided in one cycle."""

    t_s: float
    accel_request_mps2: float
    acc_state: int
    fault: int
    warning_level: int
    ttc_s: float
    required_decel_mps2: float
    target: Target | None
    radar_ok: bool
    take_over: bool = False        # the driver must brake: the target needs more than ACC's authority
    standstill: bool = False       # ACC holds the ego at a standstill
    fcw_target: Target | None = None   # the object FCW judges (ACC's target, or a stationary object ACC ignores)
    ego_ok: bool = True            # the ego motion is current (fault bit 1 when not)


class Ecu:
    """ACC and FCW on the decoded object list of one radar."""

    def __init__(self, acc: AccSettings = AccSettings(), fcw: FcwSettings = FcwSettings(), sensor_id: int = 0,
                 period_s: float = 0.072, timeout_cycles: int = 3, max_gap_s: float | None = None,
                 mount: SensorMount = SensorMount(), wavelength_m: float = DEFAULT_WAVELENGTH_M) -> None:
        for name, value in (("period_s", period_s), ("max_gap_s", max_gap_s)):
            if name == "max_gap_s" and value is None:
                # a few missed cycles are no discontinuity, however slow the radar's cycle (the schema allows 10 s)
                value = max_gap_s = max(MAX_GAP_S, (STRAY_STEP_PERIODS + 1.0) * period_s)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0.0 < value < math.inf:
                raise ValueError(f"Ecu {name}: value {value!r} is not allowed; expected a finite number of seconds > 0")
        if max_gap_s < period_s:
            raise ValueError(f"Ecu max_gap_s: value {max_gap_s!r} is not allowed; expected at least period_s "
                             f"({period_s!r} s)")
        self.tracker = Tracker("objects", "imm")
        self.cluster_tracker = Tracker("clusters", "ca")
        self.max_gap_s = float(max_gap_s)
        self.stats = EcuStats()
        self._candidate_t: float | None = None     # a skipped cycle's time: a new time base if the next follows it
        self._before_jump: dict | None = None      # the tracking state before a step ahead of several cycles
        self.acc = Acc(acc)
        self.fcw = Fcw(fcw)
        self.sensor_id = sensor_id
        self.mount = mount              # the radar's calibrated position on the ego: the path turns about the rear axle
        self.period_s = period_s
        self.timeout_s = timeout_cycles * period_s
        self.last_cycle_t: float | None = None
        self.ego_speed_mps = 0.0
        self.ego_yaw_rate_rps = 0.0
        self.ego_accel_mps2 = 0.0
        self._prev_speed: tuple[float, float] | None = None
        self._ego_t: float | None = None          # when the last new ego speed was given (None: none yet)
        self._ego_frames: int | None = None       # the reader's count of ego-speed frames at that time
        self._ego_read = False                    # whether ego motion is an input at all (set_ego was called)
        self._yaw_t: float | None = None          # … and the same of the yaw rate, where its frames are counted
        self._yaw_frames: int | None = None
        self._yaw_read = False
        # FCW's object while the radar is unavailable (_coasted): its target, place (odometry frame) and heading, speed
        # and acceleration over ground, when it was last measured and FCW's level then
        self._coast: dict | None = None
        self.outputs: list[EcuOutput] = []
        db = load_own_database()
        self._acc_codec = MessageCodec(db.get_message_by_frame_id(ACC_STATUS))
        self._fcw_codec = MessageCodec(db.get_message_by_frame_id(FCW_STATUS))
        self._e2e = E2EProtector()
        self.boundaries: dict | None = None
        self._in_path: dict[int, int] = {}      # consecutive cycles each track has been in the predicted path
        self._out_path: dict[int, int] = {}
        self._target_id: int | None = None
        self._fcw_target_id: int | None = None
        self._last_acc: Target | None = None      # ACC's target in the last cycle
        self._lost_until = -math.inf              # ACC holds from accelerating until then (LOST_HOLD_S)
        # where ACC's last target would stop (odometry frame; LOST_LEAD_DECEL_MPS2), its speed, its track
        self._last_acc_place: tuple[float, float, float, int] | None = None
        self._lost_place: tuple[float, float, Target] | None = None   # a near, slow target lost: its place
        self._path_inputs: tuple = (None, None, None)   # the path test's boundaries, trails, crossing (last _select)
        self._braking_for: int | None = None      # the track of FCW's object ACC brakes for (FCW_BRAKE_MAX_MPS)
        self._rcs_power: dict[int, float] = {}   # per track: RCS averaged in power over its life
        self._obstacles: set[int] = set()         # stationary tracks that qualified as collision candidates
        self._placed: set[int] = set()            # tracks whose place was judged for continuing an object there
        # where each track was first seen (odometry frame), and whether it may be a structure's (BORN_CLEAR …)
        self._born: dict[int, tuple[float, float, int]] = {}
        self._last_out_t: float | None = None
        if not (isinstance(wavelength_m, (int, float)) and 1e-4 < wavelength_m < 1.0):
            raise ValueError(f"Ecu wavelength_m: value {wavelength_m!r} is not allowed; expected the radar's carrier "
                             "wavelength in metres (1e-4 … 1)")
        self.wavelength_m = float(wavelength_m)
        self._moved: set[int] = set()             # tracks seen moving over ground (beyond what elevation explains)
        self._moving_for: dict[int, int] = {}      # cycles in a row each track has been seen moving
        self.landmarks = LandmarkMap(mount.z_m, self.wavelength_m)
        self.trails = VehicleTrails()             # where the vehicles ahead drove, vehicle frame (path.py)
        self.drift = BoundaryDrift()              # how fast the reported road edges move across (a lane change)
        self.trail_fits: list = []                # the trails that shaped the last predicted path
        self.odometry = (0.0, 0.0, 0.0)           # the ECU's own dead reckoning: x, y (m), heading (rad)

    @staticmethod
    def _finite_time(t_s) -> float | None:
        """``t_s`` as a float when it is a usable time, else None."""
        try:
            t = float(t_s)
        except (TypeError, ValueError, OverflowError):
            return None
        return t if math.isfinite(t) and abs(t) <= MAX_TIME_S else None

    def set_ego(self, t_s: float, speed_mps: float | None, yaw_rate_dps: float | None, frames: int | None = None,
                yaw_frames: int | None = None) -> None:
        """Ego motion as read from the bus; the acceleration is differentiated (and smoothed).

        ``frames``: the reader's count of ego-speed frames decoded so far (:attr:`CycleAssembler.ego_frames`), when
        the values are the reader's latest, which stay there when no new frame comes: a call with the count of the
        call before is no new measurement. Without it each call with a speed is one. From the first call on, ego motion
        is an input: none new for ``timeout_cycles`` cycle periods is a missing input (fault bit 1; ACC goes to
        fault). An ECU never given ego motion takes the ego as standing, without a fault (a library use).
        ``yaw_frames``: the same for the yaw rate (:attr:`CycleAssembler.yaw_frames`): once given, a yaw rate none new
        of which came for as long is a missing input too (it shapes the predicted path: a yaw rate kept from the
        straight into a clothoid drew an FCW for a car in the outer lane, with no fault shown — a tester's finding).

        A non-finite time, or a speed or yaw rate that is not finite or beyond what the bus carries
        (``EGO_SPEED_LIMIT_MPS``, ``EGO_YAW_RATE_RANGE_DPS``), is ignored (counted in ``stats.bad_ego``); after a backwards step
        or a gap longer than ``max_gap_s`` the differentiation starts again instead of using that step.
        """
        self._ego_read = True
        lo, hi = EGO_YAW_RATE_RANGE_DPS
        if yaw_frames is not None:
            self._yaw_read = True
            t = self._finite_time(t_s)
            if t is not None and yaw_frames != self._yaw_frames and isinstance(yaw_rate_dps, (int, float)) \
                    and not isinstance(yaw_rate_dps, bool) and lo <= yaw_rate_dps <= hi:
                self._yaw_t, self._yaw_frames = t, yaw_frames
        if speed_mps is None or (frames is not None and frames == self._ego_frames):
            return
        t = self._finite_time(t_s)
        yaw = 0.0 if yaw_rate_dps is None else yaw_rate_dps
        if t is None or isinstance(speed_mps, bool) or not (abs(speed_mps) <= EGO_SPEED_LIMIT_MPS and lo <= yaw <= hi):
            # (NaN fails the test too) a value the bus cannot carry is no measurement: a yaw rate of 1e6 °/s
            # overflowed the tracker's path and restarted every track
            self.stats.bad_ego += 1
            return
        if self._prev_speed is not None and 0.0 < t - self._prev_speed[0] <= self.max_gap_s:
            a = (speed_mps - self._prev_speed[1]) / (t - self._prev_speed[0])
            self.ego_accel_mps2 += 0.5 * (a - self.ego_accel_mps2)
        self._prev_speed = (t, speed_mps)
        self._ego_t, self._ego_frames = t, frames
        self.ego_speed_mps = speed_mps
        self.ego_yaw_rate_rps = math.radians(yaw)

    def _accept_time(self, t_s) -> float | None:
        """The cycle's time if tracking may use it, else None (counted); restarts tracking on a new time base."""
        t = self._finite_time(t_s)
        if t is None:
            self.stats.rejected_time += 1
            return None
        last = self.last_cycle_t
        if last is None or 0.0 <= t - last <= self.max_gap_s:
            self._candidate_t = None
            # a step ahead of several cycles: a pause, or one stray timestamp — the state before it is kept until the
            # next cycle tells (it continues from this one: kept no longer; from before: restored)
            self._before_jump = None if last is None or t - last <= STRAY_STEP_PERIODS * self.period_s else \
                copy.deepcopy({key: getattr(self, key) for key in TRACKING_STATE})
            return t
        kept = self._before_jump
        if kept is not None and kept["last_cycle_t"] is not None \
                and 0.0 <= t - kept["last_cycle_t"] <= self.max_gap_s:
            # this cycle continues from before the last one, which was stamped ahead: that one was stray — the
            # tracks as they were before it, and this cycle on them (one stray timestamp leaves the tracks)
            for key, value in kept.items():
                setattr(self, key, value)
            self._before_jump = None
            self._candidate_t = None
            self.stats.stray_undone += 1
            return t
        cand = self._candidate_t
        if cand is not None and 0.0 <= t - cand <= self.max_gap_s:
            # two cycles in a row on another time base: the old tracks' time is gone, start again
            self.stats.time_resyncs += 1
            self._restart_tracking()
            return t
        self._candidate_t = t
        self.stats.time_jumps += 1
        return None

    def _restart_tracking(self) -> None:
        self.tracker = Tracker("objects", "imm")
        self.cluster_tracker = Tracker("clusters", "ca")
        self._in_path, self._out_path, self._target_id, self._fcw_target_id = {}, {}, None, None
        self._last_acc, self._lost_until, self._braking_for = None, -math.inf, None
        self._last_acc_place, self._lost_place, self._path_inputs = None, None, (None, None, None)
        self._rcs_power, self._obstacles, self._placed, self._born = {}, set(), set(), {}
        self._moved, self._moving_for = set(), {}
        self.landmarks = LandmarkMap(self.mount.z_m, self.wavelength_m)
        self.trails.clear()
        self.drift = BoundaryDrift()
        self.trail_fits = []
        self.last_cycle_t = None
        self._last_out_t = None
        self._prev_speed = None
        self._coast = None
        self._candidate_t = None
        self._before_jump = None

    def on_cycle(self, t_s: float, cycle: ObjectCycle | ClusterCycle) -> EcuOutput | None:
        """A complete radar cycle (object or cluster list) arrived at ``t_s``.

        Returns the decision, or None when the cycle was refused (a timestamp that is not a usable time, runs
        backwards or jumps; see the module docstring and :attr:`stats`).
        """
        if not isinstance(cycle, (ObjectCycle, ClusterCycle)):
            raise TypeError(f"Ecu.on_cycle cycle: value of type {type(cycle).__name__} is not allowed; expected "
                            "an ObjectCycle or a ClusterCycle")
        t = self._accept_time(t_s)
        if t is None:
            return None
        try:
            out = self._on_clusters(t, cycle) if isinstance(cycle, ClusterCycle) else self._on_objects(t, cycle)
        except (np.linalg.LinAlgError, ValueError, ArithmeticError) as exc:
            # the guards above should make this unreachable; if not, restart rather than fail every cycle
            self.stats.internal_errors += 1
            logger.warning("ECU: tracking failed on the cycle at t=%r (%s); tracks restarted", t, exc)
            self._restart_tracking()
            return None
        self.stats.cycles += 1
        return out

    def _finite_rows(self, z: np.ndarray) -> np.ndarray:
        ok = np.isfinite(z).all(axis=1)
        self.stats.bad_measurements += int(np.count_nonzero(~ok))
        return ok

    def _sensor_velocity(self) -> tuple[float, float]:
        """The sensor's velocity over ground in the vehicle's axes, from the ego motion on the bus: the ego's plus
        the yaw rate times the mount's lever arm (a radar 3.7 m ahead of the rear axle moves sideways at ω·3.7 m
        on a bend); the radar's relative velocities are relative to it."""
        w, mnt = self.ego_yaw_rate_rps, self.mount
        return self.ego_speed_mps - w * mnt.y_m, w * mnt.x_m

    def _sensor_motion(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """:meth:`_sensor_velocity` in the sensor's own axes, and the ego's acceleration along its path (the
        trackers' objects follow the ego's road with them: :func:`radarnode.perception.motion.road_turn`, where
        the turning itself is the road's, so an acceleration is only a change of speed)."""
        mnt = self.mount
        c, s = math.cos(math.radians(mnt.yaw_deg)), math.sin(math.radians(mnt.yaw_deg))
        vx, vy = self._sensor_velocity()
        a = self.ego_accel_mps2
        return (c * vx + s * vy, -s * vx + c * vy), (c * a, -s * a)

    def _on_objects(self, t_s: float, cycle: ObjectCycle) -> EcuOutput:
        ol = cycle.objects
        n = len(ol)
        z = np.stack([ol.dist_long_m, ol.dist_lat_m, ol.vrel_long_mps, ol.vrel_lat_mps], axis=1) if n else \
            np.zeros((0, 4))
        ok = self._finite_rows(z)
        if not ok.all():
            ol, z = ol.take(np.flatnonzero(ok)), z[ok]
            n = len(ol)
        sig = np.stack([ol.dist_long_sigma_m, ol.dist_lat_sigma_m, ol.vrel_long_sigma_mps, ol.vrel_lat_sigma_mps],
                       axis=1) if n else np.zeros((0, 4))
        sig = np.where(np.isfinite(sig), np.maximum(sig, [0.1, 0.1, 0.1, 0.3]), [0.5, 0.5, 0.3, 0.8])
        r = np.zeros((n, 4, 4))
        r[:, np.arange(4), np.arange(4)] = sig ** 2
        tracks = self.tracker.step(t_s, z, r, ol.id.astype(np.int64), self.ego_yaw_rate_rps, self._sensor_motion())
        by_id = {int(ol.id[k]): k for k in range(n)}
        self.last_cycle_t = t_s
        return self._decide(t_s, tracks, ol, by_id, radar_ok=True)

    def _on_clusters(self, t_s: float, cycle: ClusterCycle) -> EcuOutput:
        """Cluster lists carry no IDs: the tracker associates them by position alone."""
        cl = cycle.clusters
        n = len(cl)
        z = np.stack([cl.dist_long_m, cl.dist_lat_m], axis=1) if n else np.zeros((0, 2))
        ok = self._finite_rows(z)
        if not ok.all():
            cl, z = cl.take(np.flatnonzero(ok)), z[ok]
            n = len(cl)
        sig = np.stack([cl.dist_long_sigma_m, cl.dist_lat_sigma_m], axis=1) if n else np.zeros((0, 2))
        sig = np.where(np.isfinite(sig), np.maximum(sig, 0.2), 0.5)
        r = np.zeros((n, 2, 2))
        r[:, np.arange(2), np.arange(2)] = sig ** 2
        radial = self._radial_speeds(cl, z)
        tracks = self.cluster_tracker.step(t_s, z, r, None, self.ego_yaw_rate_rps, self._sensor_motion(),
                                           radial=radial)
        # a cluster track is a road user when it moves over ground or is as strong as a vehicle
        # (its own cluster: the nearest whose radial speed is the track's — a standing clutter track beside a car
        # took the car's RCS, and FCW warned for it as for a stopped vehicle)
        strong = {}
        if tracks:
            own = radial_mismatch2(np.stack([t.x for t in tracks]), np.stack([t.p for t in tracks]), z,
                                   *radial) <= 9.0                                       # (tracks, clusters): 3σ
        for i, t in enumerate(tracks):
            d = np.where(own[i], np.hypot(cl.dist_long_m - t.x[0], cl.dist_lat_m - t.x[1]), np.inf) if n \
                else np.zeros(0)
            k = int(np.argmin(d)) if d.size and np.isfinite(d).any() else -1
            strong[t.id] = bool(k >= 0 and cl.rcs_dbsm[k] >= 5.0)
        self.last_cycle_t = t_s
        return self._decide(t_s, tracks, None, {}, radar_ok=True, cluster_strength=strong)

    @staticmethod
    def _radial_speeds(cl, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each cluster's measured radial speed and its variance: a cluster's VrelLong/VrelLat are that one speed
        split along its azimuth (a value not finite: no speed, a variance that gates nothing)."""
        if not len(z):
            return np.zeros(0), np.zeros(0)
        los = line_of_sight(z)
        vr = cl.vrel_long_mps * los[:, 0] + cl.vrel_lat_mps * los[:, 1]
        sig = np.hypot(cl.vrel_long_sigma_mps * los[:, 0], cl.vrel_lat_sigma_mps * los[:, 1])
        sig = np.where(np.isfinite(sig), np.maximum(sig, RADIAL_SIGMA_FLOOR_MPS), 1.0)
        good = np.isfinite(vr)
        return np.where(good, vr, 0.0), np.where(good, sig ** 2, 1e6)

    def tick(self, t_s: float) -> EcuOutput | None:
        """Call between cycles (e.g. on a timer): reports the radar unavailable after the time-out.

        A time that is not usable (NaN, infinite, beyond ±1e11 s) is refused and counted."""
        t = self._finite_time(t_s)
        if t is None:
            self.stats.rejected_time += 1
            return None
        if self.last_cycle_t is not None and 0.0 <= t - self.last_cycle_t <= self.timeout_s:
            return None
        # (a period apart by the cycle times k·period: 48·0.072 − 47·0.072 < 0.072 skipped every seventh decision,
        # its status frames missing from the bus: an independent tester's finding)
        if self._last_out_t is not None and 0.0 <= t - self._last_out_t < self.period_s * (1.0 - 1e-9):
            return None
        return self._decide(t, [], None, {}, radar_ok=False)

    def _moving(self, ground_mps: float, range_m: float, clear: bool = False) -> bool:
        """Whether a track moves over ground more than a stationary reflector up to OVERHEAD_HEIGHT_M above the
        radar seems to: its Doppler is the ego's speed times cos(elevation), so at short range it seems to
        move away slowly (a bridge at 10 m, at 36 m/s: 3.2 m/s). ``clear``: the track cannot be a structure's
        (:data:`BORN_CLEAR`), and moving is faster than MOVING_MPS."""
        if clear:
            return ground_mps > MOVING_MPS
        el = math.asin(min(OVERHEAD_HEIGHT_M / max(range_m, 0.1), 1.0))      # highest elevation at that range
        return ground_mps > MOVING_MPS + abs(self.ego_speed_mps) * (1.0 - math.cos(el))

    def _select(self, t_s, tracks, ol, by_id, cluster_strength=None) -> tuple[Target | None, Target | None]:
        """ACC's target and FCW's: the nearest track steadily in the predicted path that is a road user for each.

        ACC follows vehicles it has seen moving (also once they stopped) and never brakes for a stationary object
        never seen moving (ISO 15622 does not ask it to; production ACC does not). Neither takes a track coming
        towards the ego (faster than ONCOMING_MPS against the path's direction where it is). FCW also warns for a stationary
        object that reflects like a vehicle, unless the overhead test found it to be a bridge or a gantry
        (:mod:`radarnode.consumer.overhead`) or the ego is faster than ``stationary_max_speed_mps``.
        """
        if not tracks:
            self._target_id = self._fcw_target_id = None
            self.trails.keep(t_s, ())
            self.trail_fits = []
            return None, None
        x = np.array([t.x[0] for t in tracks])
        y = np.array([t.x[1] for t in tracks])
        trail = np.zeros(len(tracks), dtype=bool)     # a vehicle ahead driving our way, measured this cycle
        xv, yv = self.mount.to_vehicle(x, y)
        ox, oy, oh = self.odometry
        wxs, wys = self._vehicle_to_odometry(xv, yv)           # each track's place in the odometry frame
        # stationary objects never seen moving count only up to this speed (above it the overhead test cannot
        # have its evidence before the warning distance: radarnode.consumer.overhead)
        stationary_ok = self.ego_speed_mps <= self.fcw.settings.stationary_max_speed_mps
        moved = np.zeros(len(tracks), dtype=bool)
        obstacle = np.zeros(len(tracks), dtype=bool)
        oncoming = np.zeros(len(tracks), dtype=bool)
        # tracks that ended leave their landmarks first (a new track at the place of one that ended continues its
        # history; one at the place of a track still alive is another object)
        self.landmarks.forget({t.id for t in tracks}, ox, oy)
        self.landmarks.next_cycle()
        filed: set[int] = set()                       # the tracks filed at their landmarks this cycle (standing, measured)
        # a structure across the road lies across the road *where it stands*: on a bend that is the predicted
        # path's heading there (the ego's heading plus the path's curvature times the distance), not the ego's now
        kappa = curvature(self.ego_speed_mps, self.ego_yaw_rate_rps)
        su, sv = self._sensor_velocity()
        ssv = self._sensor_motion()[0]                # the same, in the sensor's axes (the trackers' states)
        along = np.zeros(len(tracks))                 # each track's speed over ground along the path where it is
        tangent = np.zeros((len(tracks), 2))          # the path's direction there (vehicle axes)
        across = np.zeros(len(tracks))                # … across it (to the left)
        across_sigma = np.zeros(len(tracks))          # … its σ
        across_accel = np.zeros(len(tracks))          # … the track's acceleration across it
        extent = np.full(len(tracks), CLEAR_EXTENT_M)  # the body's length or width, the larger, at least CLEAR_EXTENT_M
        for i, t in enumerate(tracks):
            vx, vy = self.mount.rotate(t.x[2], t.x[3])
            gx, gy = vx + su, vy + sv                         # over ground, vehicle axes
            ground = math.hypot(gx, gy)
            rng = math.hypot(t.x[0], t.x[1])
            # the road's direction where the track is, for its speed along the road: the yaw-rate circle's tangent
            # there on a road's bend; along the car's axis where the others do not drive the ego's circle (a turn
            # at a junction: crossing traffic projected on a tangent 50° off looked like traffic coming towards the
            # ego, and FCW warned), faded as the trackers fade their road model (road_share)
            there = road_share(self.ego_speed_mps, kappa) * path_heading(kappa, max(xv[i], 0.0))
            tangent[i] = math.cos(there), math.sin(there)
            along[i] = gx * tangent[i, 0] + gy * tangent[i, 1]
            nx, ny = self.mount.rotate(-tangent[i, 1], tangent[i, 0], inverse=True)        # across, sensor axes
            normal = np.array([nx, ny])
            across[i] = -gx * tangent[i, 1] + gy * tangent[i, 0]
            across_sigma[i] = math.sqrt(max(float(normal @ t.p[2:4, 2:4] @ normal), 0.0))
            if t.x.size >= 6:
                across_accel[i] = float(normal @ t.x[4:6])
            # coming towards us along the path where it is (on a curve entry the yaw-rate circle lags the road and
            # can put the oncoming lane in the path: ACC braked for an oncoming car and FCW warned for it)
            ahead = kappa * max(xv[i], 0.0)
            oncoming[i] = gx * math.cos(ahead) + gy * math.sin(ahead) < -ONCOMING_MPS
            if cluster_strength is not None:
                # moving over ground beyond its own velocity's uncertainty along that motion: a cluster track's
                # velocity across the line of sight comes from positions alone, and standing clutter strung
                # together looked like a pedestrian walking into the path (a false FCW on highway_mimo12)
                g = np.array([t.x[2] + ssv[0], t.x[3] + ssv[1]])                   # over ground, sensor axes
                unit = g / max(float(np.hypot(*g)), 1e-9)
                sigma = math.sqrt(max(float(unit @ t.p[2:4, 2:4] @ unit), 0.0))
                # … in MOVED_CYCLES cycles in a row, as for objects (one glitch of a standing track is no road user)
                moving_now = ground > max(1.0, 3.0 * sigma)
                self._moving_for[t.id] = self._moving_for.get(t.id, 0) + 1 if moving_now else 0
                moved[i] = self._moving_for[t.id] >= MOVED_CYCLES
                obstacle[i] = cluster_strength.get(t.id, False)
                continue
            k = by_id.get(t.meas_id)
            if k is not None:
                size = max(float(ol.length_m[k]), float(ol.width_m[k]))
                if math.isfinite(size):
                    extent[i] = max(size, CLEAR_EXTENT_M)
            landmark = self.landmarks.by_track.get(t.id)
            # its place in the odometry frame, and the road's heading there
            wx, wy = float(wxs[i]), float(wys[i])
            heading_there = oh + kappa * max(xv[i], 0.0)
            if t.id not in self._born:
                at = self.landmarks.structure_at(wx, wy, heading_there)
                self._born[t.id] = (wx, wy, BORN_AT_STRUCTURE if at >= STRUCTURE_WIDE
                                    else BORN_NEAR_STRUCTURE if at == STRUCTURE_POSSIBLE else BORN_CLEAR)
            if k is not None:
                # what it reflects over its track's life (power average: one fade of a fluctuating car must not drop
                # it; two merged guardrail posts stay near −2 dBsm): a stationary object is a collision candidate by it
                # (below), and a track reflecting like a vehicle is no structure's part seen from below
                rcs = float(ol.rcs_dbsm[k])
                if math.isfinite(rcs):
                    old = self._rcs_power.get(t.id)
                    p = 10.0 ** (rcs / 10.0)
                    self._rcs_power[t.id] = p if old is None else (1.0 - RCS_AVERAGE_GAIN) * old + RCS_AVERAGE_GAIN * p
                born = self._born[t.id][2]
                structure = born in (STOOD_STILL, BORN_AT_STRUCTURE) or (
                    born == BORN_NEAR_STRUCTURE and self._rcs_power.get(t.id, 0.0) < OBSTACLE_RCS_POWER)
                dyn = int(ol.dyn_prop[k])
                trail[i] = (dyn == DYN_MOVING and gx > MOVING_MPS and t.age * self.period_s >= TRAIL_MIN_AGE_S - 1e-9
                            and int(ol.meas_state[k]) != MEAS_PREDICTED and xv[i] > self.mount.x_m
                            and (int(ol.obj_class[k]) in VEHICLE_CLASSES or ol.length_m[k] >= TRAIL_MIN_LENGTH_M
                                 or ol.width_m[k] >= TRAIL_MIN_WIDTH_M))
                # seen moving: the radar says so and its speed over ground is more than elevation explains, in
                # MOVED_CYCLES cycles in a row (one glitch of a stationary object's velocity is no vehicle)
                moving_now = dyn in (DYN_MOVING, DYN_ONCOMING) and self._moving(ground, rng, not structure)
                self._moving_for[t.id] = self._moving_for.get(t.id, 0) + 1 if moving_now else 0
                if self._moving_for[t.id] >= MOVED_CYCLES:
                    self._moved.add(t.id)
                # standing still by its speed along the line of sight, what the radar measures (Doppler): the
                # lateral speed of an object whose angle glints (a bridge deck) is seconds-long noise
                lx, ly = self.mount.rotate(t.x[0], t.x[1])          # line of sight, vehicle axes
                radial = (gx * lx + gy * ly) / max(rng, 0.1)
                if abs(radial) < STATIONARY_MPS and int(ol.meas_state[k]) != MEAS_PREDICTED:
                    # standing still: filed at its place (with its RCS, for the overhead test); a vehicle that
                    # stopped marks its place, so that a track the radar creates there anew is still one
                    filed.add(t.id)
                    bx, by, _ = self._born[t.id]
                    self._born[t.id] = (bx, by, STOOD_STILL)     # it could be a structure's after all
                    landmark = self.landmarks.observe(t.id, int(ol.id[k]), wx, wy, heading_there, rng,
                                                      float(ol.rcs_dbsm[k]), moved=t.id in self._moved,
                                                      in_path=self._in_path.get(t.id, 0) > 0,
                                                      drove_m=math.hypot(wx - bx, wy - by),
                                                      width_m=float(ol.width_m[k]))
                    if landmark.moved:
                        self._moved.add(t.id)
                elif landmark is not None and int(ol.meas_state[k]) != MEAS_PREDICTED:
                    landmark.left = True          # measured moving: the object left its place (it vouches for nothing)
                # a stationary object counts by what it reflects over its track's life (averaged above), once
                # tracked OBSTACLE_MIN_AGE cycles; once it qualified it stays a candidate (latched)
                if t.age >= OBSTACLE_MIN_AGE and self._rcs_power.get(t.id, 0.0) >= OBSTACLE_RCS_POWER:
                    self._obstacles.add(t.id)
                if t.id in self._obstacles and landmark is not None and int(ol.obj_class[k]) in VEHICLE_CLASSES:
                    landmark.obstacle = True      # a vehicle standing here (not clutter: posts merged, a sign)
            # (a coasting track keeps what it was); any track never seen moving at the place of a bridge is part of it
            # (the radar reports its parts as objects of their own, moving or not as its Doppler makes them) —
            # unless an object of its own stood there, measured together with the structure: then it is that object
            # again (the radar lost a car under a deck for a while: LandmarkMap.separate)
            place = landmark
            overhead = landmark is not None and landmark.overhead
            if not overhead and landmark is None and t.id not in self._moved and self.landmarks.landmarks:
                structure = self.landmarks.match(wx, wy, heading_there, overhead_only=True, beyond_m=OVERHEAD_DEPTH_M)
                if structure is not None:
                    place = self.landmarks.separate(wx, wy, heading_there, structure)
                    overhead = place is None
            if place is not None and not overhead and t.id not in self._placed:
                # where a vehicle stood in the path as a collision candidate, a track the radar creates anew is that
                # vehicle again: a candidate from its first cycle there if it reflects like one, and in the path (the
                # car the deck masked for a second must not cost the warning the four cycles of a new object); judged
                # once, on the place as the track finds it
                self._placed.add(t.id)
                if place.continues():
                    if self._rcs_power.get(t.id, 0.0) >= OBSTACLE_RCS_POWER:
                        self._obstacles.add(t.id)
                    self._in_path[t.id] = max(self._in_path.get(t.id, 0), ENTER_CYCLES - 1)
            # a bridge or a gantry is no road user, whatever its Doppler makes of it at short range
            moved[i] = t.id in self._moved and not overhead
            obstacle[i] = t.id in self._obstacles and not overhead
        ids = [t.id for t in tracks]
        alive = set(ids)
        # the trails of the vehicles ahead (seen moving, moving our way now, not a bridge's part), then the path
        trail &= moved
        self.trails.add(t_s, np.array(ids)[trail], xv[trail], yv[trail])
        self.trails.keep(t_s, alive)
        bounds = aligned_boundaries(self.boundaries, self.mount)     # the ego's heading to the road, not the sensor's
        # a lane change (not a boundary fit tilted by a curve's exit): the road's course then gives way to the circle
        self.drift.update(t_s, bounds, self.ego_speed_mps)
        crossing = crossing_road(bounds, self.drift)
        self.trail_fits = (trail_fits(self.trails.trails(), curvature(self.ego_speed_mps, self.ego_yaw_rate_rps),
                                      boundary_reference(bounds, self.mount, crossing))
                           if self.acc.settings.path_from_trails else [])
        self._path_inputs = (bounds, self.trail_fits, crossing)
        ok = in_path(x, y, self.ego_speed_mps, self.ego_yaw_rate_rps, self.acc.settings.path_half_width_m,
                     bounds, self.mount, self.trail_fits, crossing)
        # beyond where the road's course is measured (the boundaries' valid range, the trails' farthest point) the
        # course is extrapolated: on a curve entry it bends too little, and a car standing in the outer lane a
        # hundred metres ahead lies in it. A stationary object never seen moving becomes FCW's only where the path
        # there is known — measured, or the yaw-rate circle puts it in the path too (on a straight road and a
        # constant bend the two agree)
        known = course_known(x, y, measured_reach_m(bounds, self.trail_fits, self.mount, crossing), self.ego_speed_mps,
                             self.ego_yaw_rate_rps, self.acc.settings.path_half_width_m, self.mount)
        self._rcs_power = {k: v for k, v in self._rcs_power.items() if k in alive}
        self._obstacles &= alive
        self._placed &= alive
        self._born = {k: v for k, v in self._born.items() if k in alive}
        self._moved &= alive
        self._moving_for = {k: v for k, v in self._moving_for.items() if k in alive}
        # lane association with hysteresis, as production ACC does it: a track becomes a candidate after
        # ENTER_CYCLES cycles in the path in a row; the current target stays one until it has been out of the
        # path EXIT_CYCLES cycles in a row (one cycle of a neighbour drifting into the path's edge, or of
        # the target at its edge, does not switch)
        self._in_path = {tid: (self._in_path.get(tid, 0) + 1 if o else 0) for tid, o in zip(ids, ok)}
        for tid, o in zip(ids, ok):        # a place counts the cycles its object was measured standing in the path
            lm = self.landmarks.by_track.get(tid)
            if lm is not None and tid in filed:
                lm.in_path = lm.in_path + 1 if o else 0
                lm.crossed_path |= bool(o)
        self._out_path = {tid: (0 if o else self._out_path.get(tid, 0) + 1) for tid, o in zip(ids, ok)}
        entered = np.array([self._in_path[tid] >= ENTER_CYCLES for tid in ids])
        held = np.array([self._out_path[tid] < EXIT_CYCLES for tid in ids])

        def pick(user: np.ndarray, current: int | None) -> Target | None:
            steady = entered | (held & (np.array(ids) == (-1 if current is None else current)))
            cand = np.flatnonzero(steady & user)
            if cand.size == 0:
                return None
            i = int(cand[np.argmin(xv[cand])])
            t = tracks[i]
            ax, ay = self.mount.rotate(t.x[4], t.x[5]) if t.x.size == 6 else (0.0, 0.0)
            # the gap along the path changes at the lead's speed along the path less the ego's, and the lead brakes
            # by its change of speed along the path (the tracker's relative acceleration is the change of speed
            # over the ego's: the turning is the road's, radarnode.perception.motion.road_turn): a lead that keeps
            # its speed on the ego's bend closes at nothing and brakes at nothing, although its velocity relative
            # to the sensor points across the bend
            lead_accel = (ax + self.ego_accel_mps2) * tangent[i, 0] + ay * tangent[i, 1]
            # distance ahead of the sensor along the vehicle's axis, lateral from the vehicle's centre line
            return Target(t.id, t.meas_id, float(xv[i] - self.mount.x_m), float(yv[i]),
                          float(along[i] - self.ego_speed_mps), float(lead_accel), t.misses > 0)

        # when the ego gets to each track (a track not closing is never reached), and whether it has cleared the
        # path by then
        closing = self.ego_speed_mps - along
        reach_s = np.where(closing > 0.1, np.maximum(xv - self.mount.x_m, 0.0) / np.maximum(closing, 0.1), 0.0)
        offset = path_offset_m(xv, yv, kappa)
        clears = clears_path(offset, across, across_sigma, reach_s, self.acc.settings.path_half_width_m,
                             body_extent(extent, offset, across, along, xv), along, across_accel)
        clears = body_clears(clears, offset, across, along, xv)
        acc = pick(moved & ~oncoming, self._target_id)
        fcw = pick((moved | (obstacle & stationary_ok & known)) & ~oncoming & ~clears, self._fcw_target_id)
        self._target_id = acc.track_id if acc is not None else None
        self._fcw_target_id = fcw.track_id if fcw is not None else None
        return acc, fcw

    def _decide(self, t_s, tracks, ol, by_id, radar_ok: bool, cluster_strength=None) -> EcuOutput:
        dt = self.period_s if self._last_out_t is None else t_s - self._last_out_t
        if not 0.0 <= dt <= self.max_gap_s:
            dt = self.period_s           # the ACC's rate limits need a sane step; the time itself was checked
        self._last_out_t = t_s
        # dead reckoning from the ego motion on the bus (places the landmarks of stationary objects)
        ox, oy, oh = self.odometry
        v, w = self.ego_speed_mps, self.ego_yaw_rate_rps
        self.odometry = (ox + v * dt * math.cos(oh + 0.5 * w * dt), oy + v * dt * math.sin(oh + 0.5 * w * dt),
                         oh + w * dt)
        self.trails.advance(v, w, dt)           # the same motion carries the trails into this cycle's frame
        target, fcw_target = self._select(t_s, tracks, ol, by_id, cluster_strength) if radar_ok else (None, None)
        v = self.ego_speed_mps
        ego_ok = self._fresh(t_s, self._ego_read, self._ego_t) and self._fresh(t_s, self._yaw_read, self._yaw_t)
        if radar_ok:
            self._coast = None
            if fcw_target is not None:
                px, py = self._vehicle_to_odometry(fcw_target.distance_m + self.mount.x_m, fcw_target.lateral_m)
                self._coast = {"target": fcw_target, "x": px, "y": py, "heading": self.odometry[2],
                               "v": max(v + fcw_target.rel_speed_mps, 0.0),
                               "a": min(fcw_target.lead_accel_mps2, 0.0), "since": t_s}
        else:
            fcw_target = self._coasted(t_s, dt)
        if fcw_target is not None:
            lead_v = max(v + fcw_target.rel_speed_mps, 0.0)
            level = self.fcw.step(fcw_target.distance_m, v, lead_v, self.ego_accel_mps2, fcw_target.lead_accel_mps2)
        else:
            level = self.fcw.step(None, v, 0.0, 0.0, 0.0)
        if self._coast is not None:
            if radar_ok:
                self._coast["level"] = level         # the most a coast of this object may warn
            elif fcw_target is not None:
                level = self.fcw.level = min(level, self._coast["level"])
        # while FCW warns, ACC asks for no acceleration (it went on towards its set speed, at up to 4 m/s², into a
        # stopped car FCW warned for and ACC, never having seen it move, does not follow)
        no_accel = level >= LEVEL_WARNING
        # a target that vanished near (not one that left the path: its track is gone) holds ACC from accelerating for
        # LOST_HOLD_S, or until another target is taken: masked beside a truck parked in the next lane, a lead
        # braking to a stop was lost 9–11 m ahead and ACC accelerated into it (an independent tester's finding)
        alive = {t.id for t in tracks} if radar_ok else set()
        last = self._last_acc
        vanished = last is not None and last.track_id not in alive and last.distance_m <= LOST_NEAR_M
        if target is None and vanished:
            self._lost_until = t_s + LOST_HOLD_S
        if target is not None:
            self._lost_until = -math.inf
        no_accel |= t_s < self._lost_until
        remembered = self._remembered(target, last, vanished, v)
        self._last_acc = target
        # at low speed ACC brakes for the object FCW warns of, if it has no nearer target of its own (a stopped car it
        # never saw move: FCW warned for seconds while the ego, at 3–4.5 m/s, coasted into it), and goes on braking for
        # it while FCW keeps it as its object, after the warning too and at any speed, so the ego stops behind it
        # (then holds until the driver resumes)
        # (the decision's target stays ACC's own, the vehicle it follows: this is braking, not following)
        controlled, borrowed = target, False
        # (not for an object only coasted while the radar is unavailable: ACC is in fault then)
        if radar_ok and fcw_target is not None and (
                target is None or fcw_target.distance_m < target.distance_m - 0.5) and (
                fcw_target.track_id == self._braking_for or (level >= LEVEL_WARNING and v <= FCW_BRAKE_MAX_MPS)):
            controlled, borrowed = fcw_target, True
        self._braking_for = fcw_target.track_id if borrowed else None
        if remembered is not None and (controlled is None or remembered.distance_m < controlled.distance_m):
            controlled, borrowed = remembered, True
        accel = self.acc.step(dt, v, controlled, radar_ok and ego_ok, no_accel=no_accel, borrowed=borrowed)
        fault = (0 if radar_ok else 1) | (0 if ego_ok else 2)
        out = EcuOutput(t_s, accel, self.acc.state, fault, level, self.fcw.ttc_s, self.fcw.required_decel_mps2,
                        target, radar_ok,
                        self.acc.take_over and self.acc.settings.enabled, self.acc.standstill, fcw_target, ego_ok)
        self.outputs.append(out)
        return out

    def _fresh(self, t_s: float, read: bool, since: float | None) -> bool:
        """Whether an input read since ``since`` is current at ``t_s`` (within the time-out; cycle times k·period:
        rounding must not decide the edge); one never read is no input, and never missing."""
        return not read or (since is not None and 0.0 <= t_s - since <= self.timeout_s + 1e-9)

    def _coasted(self, t_s: float, dt: float) -> Target | None:
        """While the radar is unavailable: FCW's last object, moved over ``dt`` along its heading by its last speed
        and acceleration (a lead that brakes stops and stays; one that accelerates is not counted on), seen from where
        the ego motion put the ego (its odometry, turned by the yaw rate); for FCW_COAST_S after it was last measured
        and while it lies ahead in the predicted path; else None (and forgotten)."""
        c = self._coast
        if c is None:
            return None
        new_v = max(c["v"] + c["a"] * dt, 0.0)
        step = 0.5 * (c["v"] + new_v) * dt
        c["x"] += step * math.cos(c["heading"])
        c["y"] += step * math.sin(c["heading"])
        c["v"] = new_v
        xv, yv = self._odometry_to_vehicle(c["x"], c["y"])
        m = self.mount
        xs, ys = m.to_sensor(xv, yv)
        bounds, trails, crossing = self._path_inputs
        v = self.ego_speed_mps
        if not 0.0 <= t_s - c["since"] <= FCW_COAST_S or not in_path(
                np.array([xs]), np.array([ys]), v, self.ego_yaw_rate_rps, self.acc.settings.path_half_width_m,
                bounds, m, trails, crossing)[0]:
            self._coast = None
            return None
        along = new_v * math.cos(c["heading"] - self.odometry[2])        # its speed along the ego's heading now
        return dataclasses.replace(c["target"], distance_m=max(xv - m.x_m, 0.0), lateral_m=yv,
                                   rel_speed_mps=along - v, lead_accel_mps2=c["a"] if new_v > 0 else 0.0,
                                   coasted=True)

    def _vehicle_to_odometry(self, x_m, y_m):
        """Vehicle-frame points (floats or arrays) in the odometry frame (the dead-reckoned pose of this cycle)."""
        ox, oy, oh = self.odometry
        c, s = math.cos(oh), math.sin(oh)
        return ox + c * x_m - s * y_m, oy + s * x_m + c * y_m

    def _odometry_to_vehicle(self, x_m: float, y_m: float) -> tuple[float, float]:
        """An odometry-frame point in the vehicle frame of this cycle (the inverse of :meth:`_vehicle_to_odometry`)."""
        ox, oy, oh = self.odometry
        c, s = math.cos(oh), math.sin(oh)
        return (x_m - ox) * c + (y_m - oy) * s, -(x_m - ox) * s + (y_m - oy) * c

    def _remembered(self, target: Target | None, last: Target | None, vanished: bool, v: float) -> Target | None:
        """A near, slow target lost (or a standing one that left ACC), as a standing object where it would stand had
        it braked hard when it was last seen (see FCW_BRAKE_MAX_MPS; a standing one where it stood), or None. Kept
        until ACC takes a target within LOST_MATCH_M along and LOST_MATCH_LATERAL_M across that place (the lead found
        again), the driver resumes, or the place leaves the predicted path or falls behind the sensor — not for a nearer
        target ACC takes meanwhile (it brakes for the nearer of the two), nor at a standstill (ACC, stopped behind a
        track of a truck's side that then vanished, resumed by itself into the lead it had lost). ``vanished``: the
        track of ``last`` (the target of the cycle before) ended within LOST_NEAR_M."""
        # lost: its track ended, or (alive) it left ACC standing — a standing car does not change lanes: the track
        # slid onto something beside it (a lead stopped beside a parked truck, its track drawn onto the truck's side
        # while the ego stood 4 m behind; ACC resumed by itself and drove into the lead — a tester's finding)
        if last is not None and last.distance_m <= LOST_NEAR_M and self._last_acc_place is not None \
                and (target is None or target.track_id != last.track_id) and (
                    (vanished and self._last_acc_place[2] <= FCW_BRAKE_MAX_MPS)
                    or self._last_acc_place[2] <= LEAD_STOPPED_MPS):
            # a second target lost while one is remembered: the nearer place is kept (with a cut-in prediction tried
            # in session 34, the track of a truck's side beside the ego in a jam, taken 1 m ahead and lost, replaced
            # the lead lost and remembered standing ahead of it; its place lay out of the path and was dropped, and
            # ACC drove off into that lead — any target taken and lost meanwhile could do the same)
            if self._lost_place is None or (self._odometry_to_vehicle(*self._last_acc_place[:2])[0]
                                            < self._odometry_to_vehicle(*self._lost_place[:2])[0]):
                self._lost_place = (*self._last_acc_place[:2], last)
        before, self._last_acc_place = self._last_acc_place, None
        if target is not None:
            lead_v = max(self.ego_speed_mps + target.rel_speed_mps, 0.0)
            ahead = target.distance_m + lead_v ** 2 / (2.0 * LOST_LEAD_DECEL_MPS2)
            place = self._vehicle_to_odometry(ahead + self.mount.x_m, target.lateral_m)
            if before is not None and before[3] == target.track_id and before[2] <= LEAD_STOPPED_MPS \
                    and lead_v <= LEAD_STOPPED_MPS:
                place = before[:2]          # a standing target stays where it stood, whatever its track does
            self._last_acc_place = (*place, lead_v, target.track_id)
        if self._lost_place is None:
            return None
        px, py, lost = self._lost_place
        xv, yv = self._odometry_to_vehicle(px, py)
        m = self.mount
        xs, ys = m.to_sensor(xv, yv)
        bounds, trails, crossing = self._path_inputs
        found = target is not None and abs(target.distance_m - (xv - m.x_m)) <= LOST_MATCH_M \
            and abs(target.lateral_m - yv) <= LOST_MATCH_LATERAL_M
        if found or self.acc.resume_confirmed or self.acc.departing or xv <= m.x_m or not in_path(
                np.array([xs]), np.array([ys]), v, self.ego_yaw_rate_rps, self.acc.settings.path_half_width_m,
                bounds, m, trails, crossing)[0]:
            self._lost_place = None
            return None
        return Target(lost.track_id, lost.object_id, xv - m.x_m, yv, -v, 0.0, True)

    def frames(self, out: EcuOutput, timestamp: float | None = None) -> list[can.Message]:
        """AccStatus and FcwStatus for ``out``, E2E protected."""
        tgt = out.target
        acc = self._acc_codec.encode({
            "ACC_CRC": 0, "ACC_Counter": 0, "ACC_State": out.acc_state, "ACC_Fault": out.fault,
            "ACC_TargetID": tgt.track_id % 255 if tgt else 255,
            "ACC_Distance": tgt.distance_m if tgt else 0.0, "ACC_RelSpeed": tgt.rel_speed_mps if tgt else 0.0,
            "ACC_TimeGap": min(Acc.time_gap(tgt.distance_m, self.ego_speed_mps), 6.35) if tgt else 6.35,
            "ACC_AccelRequest": out.accel_request_mps2, "ACC_TakeOverRequest": int(out.take_over),
            "ACC_Standstill": int(out.standstill)})[0]
        ft = out.fcw_target
        fcw = self._fcw_codec.encode({
            "FCW_CRC": 0, "FCW_Counter": 0, "FCW_WarningLevel": out.warning_level, "FCW_Fault": out.fault,
            "FCW_TargetID": ft.track_id % 255 if ft else 255, "FCW_TTC": min(out.ttc_s, 25.5),
            "FCW_RequiredDecel": -out.required_decel_mps2,
            "FCW_LeadAccel": ft.lead_accel_mps2 if ft else 0.0})[0]
        ts = out.t_s if timestamp is None else timestamp
        msgs = []
        for base, payload in ((ACC_STATUS, acc), (FCW_STATUS, fcw)):
            msgs.append(can.Message(arbitration_id=ids.own_id(base), data=self._e2e.protect(ids.e2e_key(base),
                                                                                            payload.tobytes()),
                                    is_extended_id=False, timestamp=ts, check=False))
        return msgs
