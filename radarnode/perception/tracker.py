"""The radar's own perception for the detection and signal levels: detections -> clusters -> objects.

A short composition of single-purpose roles (Stone Soup style), each a plain
function that can be tested alone:

* :func:`group_detections` — DBSCAN over position and radial speed, and groups
  of one near body joined by the rigid motion that explains them
  (:func:`join_rigid`); one measurement per group (nearest-face position, mean
  radial speed, extent; a joined body's centroid and fitted velocity);
* :func:`predict` — constant-velocity Kalman prediction;
* :func:`update` — extended Kalman update with position and radial speed;
* :func:`associate` — Mahalanobis gating and global nearest neighbour
  (``scipy.optimize.linear_sum_assignment``);
* :class:`ObjectTracker` — initiation, M-of-N confirmation, coasting, deletion
  and stable lowest-free IDs, and the ARS 408 fields of the object list.

The object level does not run this: it models the result of such a tracker
statistically (see ``radarnode.radar.object_model``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radarnode.dsp.cluster import dbscan
from radarnode.perception.motion import road_predict, road_share, transition
from radarnode.perception.types import (
    AMBIG_AMBIGUOUS, AMBIG_STAGGERED, AMBIG_UNAMBIGUOUS, DYN_CROSSING_MOVING, DYN_MOVING, DYN_ONCOMING,
    DYN_STATIONARY, DYN_STOPPED, MEAS_MEASURED, MEAS_NEW, MEAS_PREDICTED, ClusterList, Detections, ObjectList)

GATE_CHI2_3DOF = 16.27        # 99.9 % gate for (x, y, radial speed)
TRACKER_SIGMA_POS_M = 0.5     # a detection group's position noise (ObjectTracker's default)
CONFIRM_HITS, CONFIRM_WINDOW = 2, 3
#: how far along the line of sight a detection may lie from a young track's prediction and still be its (the χ² gate
#: on a radial residual whose variance is the track's and the measurement's position noise, 2·σ²): 2.85 m. A target
#: a single ramp reports at an aliased speed lands (true − aliased)·cycle from the prediction of a track that took
#: that speed: within it the track follows the target, beyond it never confirms it
ALIAS_GATE_M = math.sqrt(GATE_CHI2_3DOF * 2.0) * TRACKER_SIGMA_POS_M
#: a single ramp's track is listed once the ranges of this many of its hits resolved its wrap (ObjectTracker(
#: range_walk=True)): two hits cannot tell a wrap from a step between a long vehicle's reflectors (a truck's second
#: track on fast_chirp was moved a wrap by one and listed at +30 m/s where the truck closed at 8 m/s); three can (a
#: step that mimics a wrap is as long as the tracker's gate)
RANGE_WALK_MIN_HITS = 3
#: … of the last this many hits
RANGE_WALK_HITS = 4
#: an unresolved track within a confirmed track's body extent and this far (m) beyond it, its range rate that body's
#: there modulo the span within BODY_WRAP_TOL_MPS, is another reflector of it (ObjectTracker._body_wrap)
BODY_MARGIN_M = 1.0
BODY_WRAP_TOL_MPS = 1.5
COAST_CYCLES = 3
#: a confirmed track standing still over ground coasts longer: the ego motion predicts where it is, and a
#: stopped car in the training ring of a bridge deck's CA-CFAR is detected in only a third of the cycles
COAST_STATIONARY_CYCLES = 10
#: … and is confirmed by CONFIRM_HITS detections in this many cycles (a tentative one survives the misses between)
CONFIRM_WINDOW_STATIONARY = 5
MOVING_THRESHOLD_MPS = 1.0
#: a track of a standing reflector whose next detection lies this far across the line of sight (m; no road user
#: moves 2.5 m sideways in a cycle, 35 m/s at 72 ms) has taken another reflector's detection — the next guardrail
#: post, the other rail merged with it at long range: it moves there, but the jump is not taken for motion (its
#: velocity across the line of sight is set back to the standing world's). Without it, tracks hopping from post to
#: post across the rails became crossing objects at 130 km/h, some in the ego lane.
HOP_M = 2.5
#: … and so has a standing track that takes a detection after this many cycles without one (see Tracker._hops)
COAST_REANCHOR_MISSES = 2
#: a new or re-anchored track's prior on its velocity across the line of sight, σ 2 m/s (initial_velocity; a
#: re-anchored standing track: the standing world's) …
TANGENTIAL_PRIOR_VAR = 4.0
#: … but σ 10 m/s for a new track of a moving reflector (its range rate not the standing world's) where no road
#: direction is known at it (initial_velocity: the sensor slower than PRIOR_MIN_SENSOR_MPS, or the line of sight more
#: than PRIOR_MAX_ANGLE_RAD off the road there): the standing world's speed across the line of sight is then a guess,
#: not knowledge. A road user crossing the ego's road moves mostly across the line of sight, where only its positions
#: measure it, and with σ 2 m/s the track lagged it until it lost it: a car crossing 35 m ahead at 20 m/s (ego
#: standing, ars408_like) was listed at its velocity in 0 of 138 cycles at the detection level, under five IDs a seed,
#: where the object level lists it in all; and a car crossing 60 m ahead of an ego at 15 m/s, clear of its lane 1.5 s
#: before the ego got there, left a track standing in the lane that FCW warned for (benchmarks/crossing.py)
CROSSING_PRIOR_VAR = 100.0
#: below this speed the sensor's motion gives a new track no direction (initial_velocity) …
PRIOR_MIN_SENSOR_MPS = 1.0
#: … nor beyond this angle between the line of sight and the road where the body is: a road user crossing it (whose
#: radial speed the prior would read as motion along the road, scaled by 1/cos of that angle) takes the standing
#: world's prior. At 60° crossing cars (ego 8–22 m/s, cars at 6–12 m/s from 25–40° off the axis) started 1.5× as far
#: off and split in 140 cycles of 864 (85 with the standing world's prior alone); at 30° in 95; at 20° in 85, as
#: before (an independent tester's sweep); a car in the next lane is still taken for one on the road from 10 m out
PRIOR_MAX_ANGLE_RAD = math.radians(20.0)
#: the yaw rate is taken for a bend (the road's curvature, initial_velocity) only where it has kept its sign and stayed
#: within a factor of 2 over this long (s): a lane change's yaw rate turns within about 1.5 s
BEND_STEADY_S = 2.0
#: a track never seen moving near the sensor whose detections' radial speeds are the standing world's (and not a
#: near body whose detections' radial speeds fit a velocity across the line of sight) is reported
#: moving only once its speed over ground has stood out of its uncertainty in this many of its last measured cycles:
#: motion across the line of sight is seen only in position, and one detection of the next guardrail post (a standing
#: track at 50–57° near the sensor that missed its own post took the post 2 m behind, 1.4 m across the line of sight:
#: under HOP_M) reads as a speed of some 20 m/s across it for that cycle — the track then coasted out of the field of
#: view as a crossing object at 130 km/h. A reflector that does move across the line of sight goes on showing it; a
#: detection whose radial speed is not the standing world's is motion at once. Three of three since 2026-12-03: with
#: two, a standing track of a guardrail 0–7 m ahead at 45–60°, at 130 km/h past posts 2 m apart, took the next post
#: in two cycles running and was reported crossing for its last 2–3 cycles (an independent tester: detection, auto
#: and signal levels, in 2–3 of seeds 1, 3, 6 of ars408_like and mimo12; none with three). What it costs: motion seen
#: in position alone within MOVING_EVIDENCE_RANGE_M is reported a cycle later (the ECU files a track as seen moving
#: only after MOVED_CYCLES = 3 of its own anyway)
MOVING_EVIDENCE_CYCLES = 3
#: … of the last this many measured cycles …
MOVING_EVIDENCE_WINDOW = 3
#: … within this range (m): where a guardrail's next post lies 1–2 m across the line of sight from a track's own. Beyond
#: it motion shows at once, as before: a car crossing 60 m ahead at 3 m/s was called moving in 0.65 of its cycles with
#: the rule at every range instead of 0.76 (each new track of it waited), and no post hop needs it there
MOVING_EVIDENCE_RANGE_M = 20.0
_EVIDENCE_MASK = (1 << MOVING_EVIDENCE_WINDOW) - 1
_POPCOUNT = np.array([bin(k).count("1") for k in range(1 << MOVING_EVIDENCE_WINDOW)])
SIZE_DECAY = 0.95             # per cycle: the extent seen 14 cycles (1 s) ago counts half
RCS_GAIN = 0.2                # exponential average of the RCS in power
VEHICLE_RCS_DBSM, TRUCK_RCS_DBSM = 5.0, 17.0
BODY_MIN_RCS_DBSM = 0.0       # an extended group weaker than this is not classed as a vehicle
WALK_MAX_MPS, BICYCLE_MAX_MPS = 3.0, 9.0
#: the smallest body of a vehicle class (length, width, m): a radar sees the faces towards it, and a car seen
#: from behind at range is one detection; its class says the body is at least this big
#: (rows: ARS 408 class code 0…6; point, pedestrian, bicycle and wide keep what was measured)
MIN_BODY_M = np.array([[0.0, 0.0], [3.8, 1.6], [8.0, 2.3], [0.0, 0.0], [1.8, 0.7], [0.0, 0.0], [0.0, 0.0]])
_PROB_EDGES = np.array([0.25, 0.5, 0.75, 0.9, 0.99, 0.999])
ACCEL_WINDOW = 8              # cycles over which an object's acceleration is the slope of its velocity
#: σ of the ego speed the radar is sent (RadarDevice_SpeedInformation 0x300: 0.02 m/s a step)
EGO_SPEED_SIGMA_MPS = 0.02


def accel_sigma_mps2(speed_sigma_mps: np.ndarray, period_s: float, window: int = ACCEL_WINDOW) -> np.ndarray:
    """σ of an acceleration estimated as the least-squares slope of ``window`` velocities ``period_s`` apart,
    each with σ ``speed_sigma_mps``: σ_v · √(12 / (N (N² − 1))) / T (the slope's variance of a straight-line fit)."""
    n = window
    return np.asarray(speed_sigma_mps) * math.sqrt(12.0 / (n * (n * n - 1))) / max(period_s, 1e-3)


def _standing_rate(z: np.ndarray, sensor_velocity, ambiguous: np.ndarray | None = None,
                   span_mps: float = 0.0) -> np.ndarray:
    """Whether each detection group ``z`` (x, y, range rate; shape (n, 3)) has the range rate of a standing reflector
    where it is, within MOVING_THRESHOLD_MPS, for a sensor moving at ``sensor_velocity`` (its axes); where
    ``ambiguous`` (n,) is true, modulo ``span_mps`` (a range rate that may be aliased)."""
    r = np.maximum(np.hypot(z[:, 0], z[:, 1]), 1e-3)
    standing = -(sensor_velocity[0] * z[:, 0] + sensor_velocity[1] * z[:, 1]) / r
    off = z[:, 2] - standing
    if ambiguous is not None and span_mps > 0.0:
        off = np.where(ambiguous, wrap_rate(off, span_mps), off)
    return np.abs(off) < MOVING_THRESHOLD_MPS


def initial_velocity(x_m: np.ndarray, y_m: np.ndarray, range_rate_mps: np.ndarray, sensor_velocity,
                     yaw_rate_rps: float = 0.0, with_direction: bool = False) -> tuple[np.ndarray, ...]:
    """A new track's velocity relative to the sensor (its axes) from one detection group at (``x_m``, ``y_m``): the
    radial component measured (``range_rate_mps``), the tangential one from the prior that the body moves over
    ground along the ego's road where it is — the sensor's own direction of motion, turned on a bend as the ego's
    circle (curvature κ, the yaw rate over the sensor's speed) and the lanes beside it turn at the body's angle about
    their centre, as much as :func:`~radarnode.perception.motion.road_share` says the others follow the ego's road —,
    as a standing reflector (ground speed 0) and most road users do. Where that motion is not known or says little (the
    sensor slower than ``PRIOR_MIN_SENSOR_MPS``, the line of sight more than ``PRIOR_MAX_ANGLE_RAD`` off the body's
    road, or a ground speed beyond ``RIGID_MAX_SPEED_MPS``): the standing world's tangential velocity. ``yaw_rate_rps``
    is the bend's (:meth:`ObjectTracker.steady_yaw_rate`: a lane change's yaw rate is no bend, and taken for one it
    started a car 120 m ahead at the ego's speed 6.5 m/s across, an independent tester's finding).

    The standing world's prior alone gave a car in the next lane at the ego's speed the standing world's speed
    across the line of sight, v·sin(azimuth): 2.8 m/s outwards at 30 m ahead and 20 m/s, which the track carried for
    ten cycles and more (the detection level reported it 0.5 m beyond its centre line; the object level, whose
    tracker starts from the measured velocity, never did).

    ``with_direction``: also return where the road's direction at the body is known (the sensor moves and the line of
    sight lies within PRIOR_MAX_ANGLE_RAD of the road there), a boolean array: elsewhere the velocity across the line
    of sight is the standing world's for want of another (ObjectTracker gives a moving reflector's track
    CROSSING_PRIOR_VAR there)."""
    svx, svy = float(sensor_velocity[0]), float(sensor_velocity[1])
    r = np.maximum(np.hypot(x_m, y_m), 1e-3)
    ux, uy = x_m / r, y_m / r
    standing_r = -(svx * ux + svy * uy)
    vx = -svx + (range_rate_mps - standing_r) * ux
    vy = -svy + (range_rate_mps - standing_r) * uy
    speed = math.hypot(svx, svy)
    if speed < PRIOR_MIN_SENSOR_MPS:
        return (vx, vy, np.zeros(np.shape(vx), dtype=bool)) if with_direction else (vx, vy)
    kappa = float(yaw_rate_rps) / speed
    dx, dy = svx / speed, svy / speed
    # the road's heading where the body is: the ego's circle's (or a concentric lane's) at the body's angle about
    # its centre, (0, 1/κ) in axes along and across the sensor's motion
    turn = road_share(speed, kappa) * np.arctan2(kappa * (dx * x_m + dy * y_m), 1.0 - kappa * (dx * y_m - dy * x_m))
    dx, dy = dx * np.cos(turn) - dy * np.sin(turn), dx * np.sin(turn) + dy * np.cos(turn)
    du = dx * ux + dy * uy
    # ground velocity g·(dx, dy): its radial part relative to the sensor, g·du − sv·u, is the range rate
    ok = np.abs(du) >= math.cos(PRIOR_MAX_ANGLE_RAD)
    g = (range_rate_mps - standing_r) / np.where(ok, du, 1.0)
    along = ok & (np.abs(g) <= RIGID_MAX_SPEED_MPS)
    out = np.where(along, g * dx - svx, vx), np.where(along, g * dy - svy, vy)
    return (*out, ok) if with_direction else out


def velocity_slope(history: np.ndarray, times: np.ndarray, count: np.ndarray, min_count: int = 3
                   ) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares slope (m/s², shape (n, 2)) of each row's last ``count`` velocities of ``history`` (n, W, 2;
    oldest first) against their ``times`` (n, W, seconds), and 1/√Σ(t − t̄)² (n,): the slope's σ per m/s of the
    velocities' (:func:`accel_sigma_mps2`'s √(12 / (N (N² − 1))) / T for N velocities T apart). Zero slope and
    infinite σ factor where fewer than ``min_count`` are there."""
    n, w, _ = history.shape
    if n == 0:
        return np.zeros((0, 2)), np.zeros(0)
    k = np.arange(w)
    valid = k[None, :] >= (w - count)[:, None]                       # (n, W): the last ``count`` slots
    m = np.maximum(valid.sum(axis=1), 1)
    tbar = np.where(valid, times, 0.0).sum(axis=1) / m
    dt = np.where(valid, times - tbar[:, None], 0.0)
    den = (dt * dt).sum(axis=1)
    ok = (count >= min_count) & (den > 0.0)
    slope = np.einsum("nw,nwc->nc", dt, np.where(valid[:, :, None], history, 0.0)) / np.where(ok, den, 1.0)[:, None]
    return np.where(ok[:, None], slope, 0.0), np.where(ok, 1.0 / np.sqrt(np.where(ok, den, 1.0)), np.inf)


def orientation_sigma_rad(position_sigma_m: np.ndarray, length_m: np.ndarray) -> np.ndarray:
    """σ of a body's heading taken from its two ends, ``length_m`` apart, each placed with σ ``position_sigma_m``
    across the body: atan(√2 σ / L); a body shorter than 0.5 m counts as 0.5 m."""
    return np.arctan(math.sqrt(2.0) * np.asarray(position_sigma_m) / np.maximum(length_m, 0.5))


@dataclass
class Groups:
    """One measurement per detection group; arrays of shape (n,)."""

    x_m: np.ndarray
    y_m: np.ndarray
    range_rate_mps: np.ndarray
    length_m: np.ndarray
    width_m: np.ndarray
    rcs_dbsm: np.ndarray
    snr_db: np.ndarray
    actor_index: np.ndarray     # most common truth tag of the group (-1 if none)
    labels: np.ndarray | None = None   # per detection: its group (shape (detections,))
    cross_sigma_m: np.ndarray | None = None   # glint across the line of sight: half the span its reflector shows
    velocity: np.ndarray | None = None        # (n, 2) a joined near body's fitted relative velocity (NaN: none)
    velocity_cov: np.ndarray | None = None    # (n, 2, 2) its covariance
    ambiguous: np.ndarray | None = None       # (n,) every detection's range rate known only modulo 2·v_max
    across: np.ndarray | None = None          # (n, 2) a narrower group's fitted relative velocity, a measurement of its
    across_cov: np.ndarray | None = None      # part across the line of sight only (NaN: none); (n, 2, 2) covariance

    def __len__(self) -> int:
        return int(self.x_m.shape[0])


#: two groups whose nearest detections lie this close are joined when one rigid motion explains both (below)
RIGID_TOUCH_M = 1.5
#: … within this radial speed at every detection (the chain measures radial speed to a few cm/s) …
RIGID_RESIDUAL_MPS = 0.5
#: … over at least this span of azimuth (narrower, the speed across the line of sight is not observable) …
RIGID_MIN_SPAN_RAD = math.radians(10.0)
#: … at a relative speed no road user exceeds
RIGID_MAX_SPEED_MPS = 70.0
#: the least σ of a radial speed in the fit of a joined group's velocity
RIGID_SPEED_FLOOR_MPS = 0.1
#: a group narrower than RIGID_MIN_SPAN_RAD with this many detections or more, whose radial speeds one velocity
#: explains (RIGID_RESIDUAL_MPS), measures its speed across the line of sight by that fit where the fit's σ across is
#: at most ACROSS_FIT_MAX_SIGMA_MPS (the road prior's, TANGENTIAL_PRIOR_VAR): a car crossing 25 m ahead, its side's
#: detections over 7–9° of azimuth
ACROSS_FIT_MIN_DETECTIONS = 3
ACROSS_FIT_MAX_SIGMA_MPS = 2.0


#: detections further apart than this along the sensor's x are never one group by distance alone (
#: :func:`group_detections`' DBSCAN scale along x)
GROUP_EPS_LONG_M = 4.5
#: … and across it, along the sensor's y (:func:`group_detections`' DBSCAN scale along y)
GROUP_EPS_M = 2.8


def group_detections(det: Detections, eps_m: float = GROUP_EPS_M, eps_mps: float = 1.5,
                     eps_long_m: float = GROUP_EPS_LONG_M, staggered: bool = False) -> Groups:
    """DBSCAN over (x, y, radial speed) scaled by (eps_long_m, eps_m, eps_mps); a group per cluster.

    Longer along x than across: the side of a truck or a bus comes out as detections 3–4 m apart (its
    reflection points merge within a resolution cell), lanes are 3.5 m apart (1.25 eps: never one group), a car's
    rear and its side on a bend some 2 m (one group).

    Near the sensor one body spans tens of degrees, and its radial speed v·u changes across it by more than
    ``eps_mps`` (a car passing 2 m from a corner radar: −2 … +4.5 m/s over 90°): groups that touch and that one
    rigid velocity explains are one group (:func:`join_rigid`), measured with that velocity's radial part.
    ``staggered``: the detections come from staggered ramps; only the range rates the pair measured enter a fit
    (:func:`speed_known`)."""
    n = len(det)
    if n == 0:
        z = np.zeros(0)
        return Groups(z, z, z, z, z, z, z, np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), z,
                      np.zeros((0, 2)), np.zeros((0, 2, 2)), np.zeros(0, dtype=bool), np.zeros((0, 2)),
                      np.zeros((0, 2, 2)))
    x, y = det.x_m, det.y_m
    labels = dbscan(np.stack([x / eps_long_m, y / eps_m, det.range_rate_mps / eps_mps], axis=1), 1.0, 1)
    known = speed_known(det, staggered)
    labels, rigid_v, rigid_cov = join_rigid(det, labels, known)
    g = labels.max() + 1
    power = 10.0 ** (det.snr_db / 10.0)
    wsum = np.bincount(labels, weights=power, minlength=g)
    # the reported point: the group's nearest detection in x (the face towards the sensor), mean lateral
    xmin = np.full(g, np.inf)
    np.minimum.at(xmin, labels, x)
    xmax = np.full(g, -np.inf)
    np.maximum.at(xmax, labels, x)
    ymin = np.full(g, np.inf)
    np.minimum.at(ymin, labels, y)
    ymax = np.full(g, -np.inf)
    np.maximum.at(ymax, labels, y)
    gy = np.bincount(labels, weights=power * y, minlength=g) / wsum
    vr = np.bincount(labels, weights=power * det.range_rate_mps, minlength=g) / wsum
    gx = xmin
    joined = np.isfinite(rigid_v[:, 0])
    if joined.any():
        # a joined near body wraps around the sensor (a car beside a corner radar): its nearest x and mean y may lie
        # off the body, its power centroid does not; measured with the rigid velocity's radial part there
        gx = np.where(joined, np.bincount(labels, weights=power * x, minlength=g) / wsum, xmin)
        vr = np.where(joined, _radial_at(rigid_v, gx, gy), vr)
    # a group of its own spread over RIGID_MIN_SPAN_RAD or more of azimuth (a body beside the sensor) whose radial
    # speeds one velocity explains: that velocity too, and its radial part at the group's place (which stays its
    # own). A truck parked beside a sensor passing at 5 m/s: its side's detections, 1–3 m ahead at 35–60°, read as
    # one standing body, where the nearest point alone — which stays beside the sensor as it passes — with the mean
    # of the radial speeds made a track crossing into the lane at 2.8 m/s, and FCW warned and braked (an independent
    # tester's scene at the detection level)
    alone = ~joined & (np.bincount(labels, minlength=g) >= 2)
    if alone.any():
        own = np.flatnonzero(alone)
        own = own[_rigid_fit_ok(det, labels, np.stack([own, own], axis=1), known)]
        if own.size:
            rigid_v[own], rigid_cov[own] = _rigid_velocity(det, labels, own, known)   # (join_rigid's own arrays)
            vr[own] = _radial_at(rigid_v[own], gx[own], gy[own])
    across, across_cov = _across_fits(det, labels, gx, gy, np.isfinite(rigid_v[:, 0]), known)
    narrow = np.flatnonzero(np.isfinite(across[:, 0]))
    if narrow.size:    # measured with the fit's radial part at the group's place too, as a wider group is
        vr[narrow] = _radial_at(across[narrow], gx[narrow], gy[narrow])
    rcs = 10.0 * np.log10(np.bincount(labels, weights=10.0 ** (det.rcs_dbsm / 10.0), minlength=g))
    snr = 10.0 * np.log10(wsum)
    tags = np.full(g, -1, dtype=np.int64)
    tagged = det.actor_index >= 0
    if tagged.any():
        counts = np.zeros((g, int(det.actor_index.max()) + 1))
        np.add.at(counts, (labels[tagged], det.actor_index[tagged]), 1)
        tags = np.where(counts.max(axis=1) > 0, counts.argmax(axis=1), -1)
    # an extended reflector's angle glints over the span its snapshot shows (radarnode.dsp.spread): half of it
    # across the line of sight is the group's position uncertainty from glint
    glint = np.zeros(g)
    np.maximum.at(glint, labels, 0.5 * det.range_m * det.azimuth_spread_rad)
    # a group of only ambiguous detections (a staggered pair's unpaired ones): its range rate is known modulo 2·v_max
    ambiguous = np.bincount(labels, weights=det.ambig_state != AMBIG_AMBIGUOUS, minlength=g) == 0
    return Groups(gx, gy, vr, xmax - xmin, ymax - ymin, rcs, snr, tags, labels, glint, rigid_v, rigid_cov,
                  ambiguous, across, across_cov)


def _radial_at(v: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The radial part of velocities ``v`` (n, 2) at the points (x, y): a fitted body's range rate there."""
    r = np.maximum(np.hypot(x, y), 1e-6)
    return (v[:, 0] * x + v[:, 1] * y) / r


def join_rigid(det: Detections, labels: np.ndarray, known: np.ndarray | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Groups (``labels``, DBSCAN's) whose nearest detections lie within :data:`RIGID_TOUCH_M` and whose radial
    speeds one relative velocity v explains — |v_r − v·u| ≤ :data:`RIGID_RESIDUAL_MPS` at every detection, u its
    line of sight, over at least :data:`RIGID_MIN_SPAN_RAD` of azimuth, |v| ≤ :data:`RIGID_MAX_SPEED_MPS` — are
    joined (a least-squares fit per candidate pair from per-group sums; a chain of joins is kept only where the
    whole joined group passes the same test). Returns the new labels, in the order of the groups' least label (of
    first detection, as DBSCAN numbers them), and
    per new group the fitted v (sensor axes; NaN for a group that was not joined), shape (g, 2), and its covariance
    (g, 2, 2). ``known``: the detections whose range rates the fits use (:func:`speed_known`; None: all)."""
    if known is None:
        known = np.ones(labels.size, dtype=bool)
    g = int(labels.max()) + 1 if labels.size else 0
    none = (labels, np.full((g, 2), np.nan), np.full((g, 2, 2), np.nan))
    if g < 2:
        return none
    import scipy.spatial  # imported when first needed: a faster start
    pairs = scipy.spatial.cKDTree(np.stack([det.x_m, det.y_m], axis=1)).query_pairs(RIGID_TOUCH_M,
                                                                                   output_type="ndarray")
    if pairs.size == 0:
        return none
    la, lb = labels[pairs[:, 0]], labels[pairs[:, 1]]
    apart = la != lb
    key = np.unique(np.minimum(la, lb)[apart] * g + np.maximum(la, lb)[apart])      # candidate group pairs
    if key.size == 0:
        return none
    cand = np.stack([key // g, key % g], axis=1)
    ok = _rigid_fit_ok(det, labels, cand, known)
    if not ok.any():
        return none
    # connected components of the accepted pairs: each group takes the least group index it is joined to
    # (min-label propagation with pointer jumping; a few passes over a handful of edges)
    a, b = cand[ok, 0], cand[ok, 1]
    comp = np.arange(g)
    while True:
        before = comp.copy()
        m = np.minimum(comp[a], comp[b])
        np.minimum.at(comp, a, m)
        np.minimum.at(comp, b, m)
        comp = comp[comp]
        if np.array_equal(comp, before):
            break
    # a component joined through a chain (a–b, b–c) must pass the test as a whole; else its groups stay apart
    whole = np.flatnonzero(np.bincount(comp, minlength=g) > 1)
    good = _rigid_fit_ok(det, comp[labels], np.stack([whole, whole], axis=1), known)
    comp = np.where(np.isin(comp, whole[~good]), np.arange(g), comp)
    # renumbered by their least group index (DBSCAN numbers its groups in order of first detection: so are these)
    uniq, new = np.unique(comp[labels], return_inverse=True)
    v, cov = np.full((uniq.size, 2), np.nan), np.full((uniq.size, 2, 2), np.nan)
    joined = np.searchsorted(uniq, np.flatnonzero(np.bincount(comp, minlength=g) > 1))   # made of several groups
    v[joined], cov[joined] = _rigid_velocity(det, new, joined, known)
    return new, v, cov


def speed_known(det: Detections, staggered: bool) -> np.ndarray:
    """Which detections' range rates a rigid fit may use, (n,) bool. With staggered ramps (``staggered``) the paired
    ones (AmbigState staggered ramp) and those of a speed no wrap reaches (unambiguous), as :func:`_across_fits` takes
    them: an unpaired one (ambiguous) has a range rate known only modulo 2·v_max, and one unpaired but taken for the
    standing world's (stationary candidate) a hypothesis, not a measurement. A weak spur of a truck's side 2 m beside the
    sensor, unpaired at +4.0 m/s where the side's paired detection read −1.4 m/s, was joined to it: the two fitted
    (16, −17.5) m/s exactly, the track took that velocity across, left the truck's lane and coasted through the ego's
    (the signal level, a truck passed on the left); a spur flagged a stationary candidate is joined the same way (an
    independent tester's case). A single ramp flags every moving detection ambiguous, and its range rates are taken as
    measured (:class:`ObjectTracker`): all of them."""
    if not staggered:
        return np.ones(len(det), dtype=bool)
    return rate_measured(det)


def rate_measured(det: Detections) -> np.ndarray:
    """Which detections carry a range rate as measured, (n,) bool: AmbigState staggered ramp (resolved by the pair)
    or unambiguous; not one known modulo 2·v_max (ambiguous) nor one taken for the standing world's (stationary
    candidate)."""
    return np.isin(det.ambig_state, (AMBIG_STAGGERED, AMBIG_UNAMBIGUOUS))


def _rigid_sums(det: Detections, labels: np.ndarray, known: np.ndarray) -> np.ndarray:
    """Per label the sums of the normal equations of v_r = v·u over the detections ``known`` (:func:`speed_known`):
    (L, 7) [Σc², Σcs, Σs², Σc·v_r, Σs·v_r, n, Σv_r²]."""
    known = known.astype(np.float64)
    c, s, vr = np.cos(det.azimuth_rad), np.sin(det.azimuth_rad), det.range_rate_mps * known
    n = int(labels.max()) + 1
    return np.stack([np.bincount(labels, weights=w, minlength=n)
                     for w in (c * c * known, c * s * known, s * s * known, c * vr, s * vr, known, vr * vr)], axis=1)


def _solve_rigid(sums: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """v (P, 2) from summed normal equations (P, 7) (:func:`_rigid_sums`), and whether the 2×2 system is solvable."""
    a, b, d, e, f = sums[:, 0], sums[:, 1], sums[:, 2], sums[:, 3], sums[:, 4]
    det_ = a * d - b * b
    ok = det_ > 1e-9 * np.maximum(a + d, 1e-300) ** 2
    safe = np.where(ok, det_, 1.0)
    return np.stack([(d * e - b * f) / safe, (a * f - b * e) / safe], axis=1), ok


def _rigid_velocity(det: Detections, labels: np.ndarray, which: np.ndarray, known: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """The fitted v (P, 2) of labels ``which`` and its covariance (P, 2, 2): s²·(AᵀA)⁻¹, s² the residual variance
    (at least :data:`RIGID_SPEED_FLOOR_MPS` squared: a fit through two or three detections is exact)."""
    sums = _rigid_sums(det, labels, known)[which]
    v, _ = _solve_rigid(sums)
    a, b, d, n = sums[:, 0], sums[:, 1], sums[:, 2], sums[:, 5]
    rss = np.maximum(sums[:, 6] - v[:, 0] * sums[:, 3] - v[:, 1] * sums[:, 4], 0.0)
    s2 = np.maximum(rss / np.maximum(n - 2.0, 1.0), RIGID_SPEED_FLOOR_MPS ** 2)
    det_ = a * d - b * b
    cov = np.stack([np.stack([d, -b], axis=-1), np.stack([-b, a], axis=-1)], axis=-2) * (s2 / det_)[:, None, None]
    return v, cov


def _rigid_fit_ok(det: Detections, labels: np.ndarray, cand: np.ndarray, known: np.ndarray,
                  min_span_rad: float = RIGID_MIN_SPAN_RAD) -> np.ndarray:
    """For label pairs ``cand`` (P, 2) (a pair (k, k) is label k alone): whether one rigid velocity explains the
    detections of both (see :func:`join_rigid`) over at least ``min_span_rad`` of azimuth, shape (P,)."""
    sums = _rigid_sums(det, labels, known)
    a, b = cand[:, 0], cand[:, 1]
    union = sums[a] + np.where((a != b)[:, None], sums[b], 0.0)
    v, solvable = _solve_rigid(union)
    # the members of each pair, contiguous: the detections sorted by label, each pair's two runs side by side
    order = np.argsort(labels, kind="stable")
    count = np.bincount(labels, minlength=sums.shape[0])
    start = np.concatenate([[0], np.cumsum(count)])
    na, nb = count[a], np.where(a != b, count[b], 0)
    per = na + nb
    pair = np.repeat(np.arange(len(cand)), per)
    offset = np.arange(per.sum()) - np.repeat(np.cumsum(per) - per, per)
    member = order[np.where(offset < na[pair], start[a][pair] + offset, start[b][pair] + offset - na[pair])]
    az = det.azimuth_rad[member]
    known = known[member]         # (the residuals and the span of the detections the fit used)
    resid = np.where(known, np.abs(det.range_rate_mps[member] - (v[pair, 0] * np.cos(az) + v[pair, 1] * np.sin(az))),
                     0.0)
    bounds = np.cumsum(per) - per
    worst = np.maximum.reduceat(resid, bounds)
    span = (np.maximum.reduceat(np.where(known, az, -np.inf), bounds)
            - np.minimum.reduceat(np.where(known, az, np.inf), bounds))
    measured = sums[:, 5] > 0          # a group with no range rate the fit may use is joined to nothing
    return (solvable & (worst <= RIGID_RESIDUAL_MPS) & (span >= min_span_rad)
            & (np.hypot(v[:, 0], v[:, 1]) <= RIGID_MAX_SPEED_MPS) & measured[a] & measured[b])


def _across_fits(det: Detections, labels: np.ndarray, gx: np.ndarray, gy: np.ndarray, fitted: np.ndarray,
                 known: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The velocity (G, 2) and its covariance (G, 2, 2) that one rigid motion fitted to the radial speeds of each group
    not ``fitted`` already gives, where the group has :data:`ACROSS_FIT_MIN_DETECTIONS` detections or more, each
    with a range rate as measured (AmbigState unambiguous or staggered ramp), the fit explains each within
    :data:`RIGID_RESIDUAL_MPS` and its σ across the line of sight to (gx, gy) is at most
    :data:`ACROSS_FIT_MAX_SIGMA_MPS`; NaN elsewhere. Its radial part is the
    group's range rate (:func:`group_detections`), so only its part across is a further measurement
    (:func:`tangential_update`): a car crossing 25 m ahead shows its side over 7–9° of azimuth, narrower than
    :data:`RIGID_MIN_SPAN_RAD`, and its radial speed where it crosses the sensor's axis is the standing world's."""
    g = gx.size
    v, cov = np.full((g, 2), np.nan), np.full((g, 2, 2), np.nan)
    # only range rates measured as they are (unambiguous, or resolved by a staggered pair): one known modulo 2·v_max
    # (a single ramp's moving detections) or taken for the standing world's (a stationary candidate) is no radial
    # speed to fit — a wrap, a constant over the group, leaks into the fit across as the wrap times the group's span
    # (guardrail posts on fast_chirp crossed the ego's lane at 3–4 m/s)
    sure = np.bincount(labels, weights=~rate_measured(det), minlength=g) == 0
    own = np.flatnonzero(~fitted & sure & (np.bincount(labels, minlength=g) >= ACROSS_FIT_MIN_DETECTIONS))
    if own.size:
        own = own[_rigid_fit_ok(det, labels, np.stack([own, own], axis=1), known, 0.0)]
    if own.size:
        fv, fcov = _rigid_velocity(det, labels, own, known)
        r = np.maximum(np.hypot(gx[own], gy[own]), 1e-6)
        t = np.stack([-gy[own] / r, gx[own] / r], axis=1)
        var = np.einsum("ni,nij,nj->n", t, fcov, t)
        good = var <= ACROSS_FIT_MAX_SIGMA_MPS ** 2
        v[own[good]], cov[own[good]] = fv[good], fcov[good]
    return v, cov


def extents_along(det: Detections, labels: np.ndarray, heading_rad: np.ndarray) -> np.ndarray:
    """Span (G, 2) of each group's detections along and across ``heading_rad`` (G,), the heading of the body it
    belongs to in sensor axes: its length and width as the ARS 408 reports them (along the object, not along the
    sensor's axes; a heading of 0 gives the sensor-axes spans)."""
    g = heading_rad.shape[0]
    h = heading_rad[labels]
    c, s = np.cos(h), np.sin(h)
    along = c * det.x_m + s * det.y_m
    across = -s * det.x_m + c * det.y_m
    out = np.empty((g, 2))
    for col, v in enumerate((along, across)):
        lo = np.full(g, np.inf)
        hi = np.full(g, -np.inf)
        np.minimum.at(lo, labels, v)
        np.maximum.at(hi, labels, v)
        out[:, col] = np.where(hi >= lo, hi - lo, 0.0)
    return out


def predict(x: np.ndarray, p: np.ndarray, dt: float, accel_sigma: float = 2.0, yaw_rate_rps: float = 0.0,
            sensor_velocity: tuple[float, float] = (0.0, 0.0),
            previous_sensor_velocity: tuple[float, float] | None = None,
            standing: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Constant-velocity prediction of states (n, 4) = [x, y, vx, vy] and covariances (n, 4, 4), on the road.

    The velocity is relative to the sensor (the object's over ground minus the sensor's, ``sensor_velocity`` in
    the sensor's axes). The sensor frame turns with the ego by θ = ``yaw_rate_rps``·dt; the objects follow the
    ego's road (:func:`radarnode.perception.motion.road_turn`): a standing object stays where it is on the ground,
    a vehicle ahead on the ego's bend at the ego's speed keeps its velocity relative to the sensor, where the
    world-fixed model (every velocity over ground turned by −θ) let it lag by metres per second across.

    A standing object's velocity over ground stays 0: where the sensor's own changed since the last cycle
    (``previous_sensor_velocity``, its axes then; the ego braking or accelerating), the relative velocity of the
    tracks ``standing`` (n,) marks changes by the opposite, and their position by half of that over ``dt`` (a
    uniform change). Without it a standing post's track kept the relative velocity of the cycle before: an ego
    braking at 6 m/s² from 45 m/s put 0.3 m/s a cycle of motion into every post it coasted or barely measured across,
    and posts were listed moving (an independent tester's finding: 63–144 rows a run at the detection level on
    ``ars408_like``). A moving object's acceleration is not known to the prediction: it keeps its relative velocity,
    right for a lead braking along with the ego (ACC following), where a constant velocity over ground biased its
    track by up to 3 m/s away and changed its ID every third of a second at −10 m/s² (a second tester's finding).
    """
    f, q = transition("cv", dt, accel_sigma ** 2)
    if previous_sensor_velocity is not None and standing is not None and dt:
        dv = np.array([previous_sensor_velocity[0] - sensor_velocity[0],
                       previous_sensor_velocity[1] - sensor_velocity[1]], dtype=np.float64)
        if dv.any() and standing.any():
            x = x.copy()
            x[standing, 2:4] += dv
            x[standing, 0:2] -= 0.5 * dt * dv   # the step below moves it by (v + dv)·dt; the mean is v + dv/2
    if not yaw_rate_rps or not dt:
        return x @ f.T, f @ p @ f.T + q
    return road_predict(x, p, f, q, yaw_rate_rps * dt, dt, sensor_velocity)


def measure(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Measurement function h(x) = [x, y, radial speed] and its Jacobian, for states (n, 4)."""
    px, py, vx, vy = x.T
    r = np.maximum(np.hypot(px, py), 1e-3)
    vr = (px * vx + py * vy) / r
    h = np.stack([px, py, vr], axis=1)
    jac = np.zeros((x.shape[0], 3, 4))
    jac[:, 0, 0] = jac[:, 1, 1] = 1.0
    jac[:, 2, 0] = vx / r - vr * px / r ** 2
    jac[:, 2, 1] = vy / r - vr * py / r ** 2
    jac[:, 2, 2] = px / r
    jac[:, 2, 3] = py / r
    return h, jac


def innovation(x, p, z, r_cov):
    """Innovations (n, m, 3) and their covariances (n, 3, 3) of n tracks against m measurements."""
    h, jac = measure(x)
    s = jac @ p @ np.transpose(jac, (0, 2, 1)) + r_cov
    return z[None, :, :] - h[:, None, :], s, jac


def mahalanobis3(nu: np.ndarray, s: np.ndarray) -> np.ndarray:
    """νᵀ S⁻¹ ν for 3-vectors ν (..., 3) and symmetric positive definite 3×3 covariances S (..., 3, 3)
    (broadcast), elementwise over every track–measurement pair instead of a batched matrix inverse.

    By S's LDLᵀ factorisation: νᵀS⁻¹ν = Σ_k y_k²/d_k with L·y = ν, a sum of squares over the positive pivots
    d_k, so never negative however ill-conditioned S is (an adjugate formula loses that at condition 1e12). A pair
    whose S is not positive definite (a pivot ≤ 0 or NaN) is at infinite distance: it never passes a gate.
    """
    s00, s01, s02 = s[..., 0, 0], s[..., 0, 1], s[..., 0, 2]
    s11, s12, s22 = s[..., 1, 1], s[..., 1, 2], s[..., 2, 2]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        l10, l20 = s01 / s00, s02 / s00
        d1 = s11 - l10 * s01
        l21 = (s12 - l20 * s01) / d1
        d2 = s22 - l20 * s02 - l21 * (s12 - l20 * s01)
        y0 = nu[..., 0]
        y1 = nu[..., 1] - l10 * y0
        y2 = nu[..., 2] - l20 * y0 - l21 * y1
        out = y0 * y0 / s00 + y1 * y1 / d1 + y2 * y2 / d2
    return np.where((s00 > 0) & (d1 > 0) & (d2 > 0) & np.isfinite(out), out, np.inf)


def follows_one_wrap(span_mps: float, period_s: float) -> bool:
    """Whether a track at a single ramp's aliased speed follows its target, whose position one wrap (``span_mps``)
    moves from the track's prediction every cycle (``period_s``): within the gate, ALIAS_GATE_M. Only then does the
    range the track walks resolve the wrap (ObjectTracker(range_walk=True))."""
    return span_mps * period_s <= ALIAS_GATE_M


def wrap_rate(nu: np.ndarray, span_mps: float) -> np.ndarray:
    """A range-rate difference ``nu`` taken modulo ``span_mps`` into −span/2 … span/2."""
    return np.mod(nu + 0.5 * span_mps, span_mps) - 0.5 * span_mps


def associate(x, p, z, r_cov, gate: float = GATE_CHI2_3DOF, wrap: np.ndarray | None = None,
              span_mps: float = 0.0) -> list[tuple[int, int]]:
    """Global nearest neighbour on the squared Mahalanobis distance, inside the gate.

    ``r_cov`` is one measurement covariance (3, 3) or one per measurement (m, 3, 3). Where ``wrap`` (n, m) is true
    the pair's range rates are compared modulo ``span_mps`` (an ambiguous measurement, or a track whose speed no
    unambiguous one has measured yet)."""
    if x.shape[0] == 0 or z.shape[0] == 0:
        return []
    r_cov = np.asarray(r_cov)
    if r_cov.ndim == 3:     # one covariance per measurement (m, 3, 3)
        nu, s, _ = innovation(x, p, z, 0.0)
        s = s[:, None] + r_cov[None]
    else:
        nu, s, _ = innovation(x, p, z, r_cov)
        s = s[:, None]
    if wrap is not None and span_mps > 0.0 and wrap.any():
        nu[..., 2] = np.where(wrap, wrap_rate(nu[..., 2], span_mps), nu[..., 2])
    d2 = mahalanobis3(nu, s)
    cost = np.where(d2 <= gate, d2, 1e9)
    import scipy.optimize  # imported when first needed: a faster start
    rows, cols = scipy.optimize.linear_sum_assignment(cost)
    return [(int(i), int(j)) for i, j in zip(rows, cols) if cost[i, j] < 1e9]


def update(x, p, z, r_cov):
    """EKF update of states (n, 4) with measurements (n, 3)."""
    h, jac = measure(x)
    s = jac @ p @ np.transpose(jac, (0, 2, 1)) + r_cov
    k = p @ np.transpose(jac, (0, 2, 1)) @ np.linalg.inv(s)
    x_new = x + np.einsum("nij,nj->ni", k, z - h)
    p_new = (np.eye(4)[None] - k @ jac) @ p
    return x_new, p_new


def along_body_cov(z: np.ndarray, heading_rad: np.ndarray, length_m: np.ndarray) -> np.ndarray:
    """Covariances (n, 4, 4) of a track's state (zero but the position block) of where along a moving body a group lies.

    A body of length L heading along h shows the sensor its side over L·|sin α| (α between the line of sight to the
    group ``z`` (n, ≥ 2) and h; 0 for a body seen end on), and its detections lie anywhere on that part: along h the
    group's position is the body's to σ = L·|sin α| / √12 (uniform over the visible side). Added to the track's
    position covariance before the update (not to the measurement's), a detection's step along the body moves the
    track's point, not its velocity: the radial speed keeps measuring that. The tracker adds it where a side edge of
    the field of view cuts the body (:meth:`ObjectTracker._body_in_fov`): there the visible part's near end is that
    edge, which stays where it is while the body moves on, and the detections follow it. Without it a car
    passing beside the sensor was tracked by that point: its radial speed then read as motion towards the sensor,
    the track drifted 1 m across into the ego's lane in 1 s, and FCW warned for a car or a truck in the next lane
    (ego 20–36 m/s passing one 1–3 m/s slower: 77 of 288 runs at the detection level, benchmarks/side_pass.py)."""
    r = np.maximum(np.hypot(z[:, 0], z[:, 1]), 1e-6)
    hx, hy = np.cos(heading_rad), np.sin(heading_rad)
    sin_a = (z[:, 0] * hy - z[:, 1] * hx) / r
    var = (np.asarray(length_m, dtype=np.float64) * sin_a) ** 2 / 12.0
    cov = np.zeros((len(z), 4, 4))
    cov[:, 0, 0], cov[:, 0, 1], cov[:, 1, 1] = var * hx * hx, var * hx * hy, var * hy * hy
    cov[:, 1, 0] = cov[:, 0, 1]
    return cov


def _across_known(groups: Groups, which: np.ndarray) -> np.ndarray:
    """Whether the groups ``which`` carry a narrower group's fit across the line of sight (:func:`_across_fits`)."""
    if groups.across is None:
        return np.zeros(which.size, dtype=bool)
    return np.isfinite(groups.across[which, 0])


def tangential_update(x, p, z, v, v_cov):
    """Kalman update of states (n, 4) with the part of a measured velocity ``v`` (n, 2), covariance ``v_cov``
    (n, 2, 2), across the line of sight to the measured positions ``z`` (n, ≥ 2): the radial part is already in the
    radial-speed update, and is not counted twice."""
    r = np.maximum(np.hypot(z[:, 0], z[:, 1]), 1e-6)
    t = np.stack([-z[:, 1] / r, z[:, 0] / r], axis=1)                     # across the line of sight
    h = np.zeros((len(x), 4))
    h[:, 2:4] = t
    innov = np.einsum("ni,ni->n", t, v) - np.einsum("ni,ni->n", h, x)
    ph = np.einsum("nij,nj->ni", p, h)
    s = np.einsum("ni,ni->n", h, ph) + np.einsum("ni,nij,nj->n", t, v_cov, t)
    k = ph / s[:, None]
    return x + k * innov[:, None], p - k[:, :, None] * ph[:, None, :]


class ObjectTracker:
    """Turns each cycle's detections into the ARS 408 object list.

    Parameters
    ----------
    sigma_pos_m, sigma_vr_mps : measurement noise of a detection group (position, range rate)
    sigma_az_rad : the group's bearing noise; across the line of sight it adds range × σ_az to the
        position noise, so a far object is placed less well sideways than a near one
    alias_span_mps : with staggered ramps, the first sequence's 2·v_max: a group of only ambiguous detections
        (AmbigState 1, unpaired) measures its range rate modulo this span. It joins a track at the wrap nearest the
        track's; a track started from such groups is not listed until an unambiguous group joins it (at the wrap
        that group shows: its speed is then moved by whole spans); the rigid fits of near bodies take only the
        range rates the pair measured (:func:`speed_known`). Without it (a single ramp, which flags every moving
        detection ambiguous) range rates are taken as measured.
    range_walk : with a single ramp's 2·v_max as ``alias_span_mps``: no detection resolves a wrap, and the range a
        track walks does (a single-PRF radar's tracker does the same). An ambiguous group joins a track at the wrap
        nearest the track's speed. After each hit of a track started from one, where the slope of its measured ranges
        (least squares over its last RANGE_WALK_HITS hits, from its second) lies within a quarter span of one wrap of
        its range rate, the track's velocity along the line of sight moves there by whole spans (none where it is the
        track's own); the track is listed once such a slope over RANGE_WALK_MIN_HITS hits or more resolved it. It can
        only resolve a target it follows: one wrap's drift a cycle within ALIAS_GATE_M (:func:`follows_one_wrap`,
        models.tracker_for).
    fov : the field of view as sectors (max range m, half angle rad) (the preset's, models.tracker_for; the default:
        the half plane ahead). Where its side edges cut a moving body, a detection's place along the body is not taken
        for the body's motion (:func:`along_body_cov`).
    """

    def __init__(self, sigma_pos_m: float = TRACKER_SIGMA_POS_M, sigma_vr_mps: float = 0.3, max_objects: int = 100,
                 sigma_az_rad: float = math.radians(0.3), alias_span_mps: float | None = None,
                 range_walk: bool = False, fov: tuple[tuple[float, float], ...] = ((math.inf, math.pi / 2),)
                 ) -> None:
        if range_walk and not alias_span_mps:
            raise ValueError("range_walk: True is not allowed without alias_span_mps; expected the single ramp's "
                             "2·v_max as alias_span_mps")
        self.alias_span_mps = alias_span_mps
        # staggered ramps: a rigid fit takes only the range rates the pair measured (speed_known)
        self.staggered = bool(alias_span_mps) and not range_walk
        self.range_walk = range_walk
        self.fov = tuple((float(r), float(a)) for r, a in fov)
        self.reach = max(r for r, _ in self.fov)      # the farthest sector's range
        self.r_cov = np.diag([sigma_pos_m ** 2, sigma_pos_m ** 2, sigma_vr_mps ** 2])
        self.sigma_az_rad = sigma_az_rad
        self.max_objects = max_objects
        self.x = np.zeros((0, 4))
        self.p = np.zeros((0, 4, 4))
        self.hist = np.zeros(0, dtype=np.uint8)
        self.misses = np.zeros(0, dtype=np.int64)
        self.confirmed = np.zeros(0, dtype=bool)
        # whether an unambiguous group has measured the track's range rate (always, without alias_span_mps)
        self.resolved = np.zeros(0, dtype=bool)
        self.ids = np.zeros(0, dtype=np.int64)
        self.was_moving = np.zeros(0, dtype=bool)
        # which of the last MOVING_EVIDENCE_WINDOW measured cycles showed the track moving, a bit each, newest lowest
        # (all at once where its detection's radial speed was not the standing world's, or it was beyond
        # MOVING_EVIDENCE_RANGE_M)
        self.evidence = np.zeros(0, dtype=np.int64)
        self.size = np.zeros((0, 2))
        self.power = np.zeros(0)      # RCS in m², averaged in power
        self.tag = np.zeros(0, dtype=np.int64)
        # the last ACCEL_WINDOW cycles' filtered relative velocities (oldest first) and how many of them there are:
        # the object's relative acceleration is their slope (:func:`velocity_slope`)
        self.vh = np.zeros((0, ACCEL_WINDOW, 2))
        self.th = np.zeros((0, ACCEL_WINDOW))
        self.nh = np.zeros(0, dtype=np.int64)
        # the last RANGE_WALK_HITS measured ranges of each track and their times, oldest first (range_walk)
        self.rh = np.zeros((0, RANGE_WALK_HITS))
        self.rth = np.zeros((0, RANGE_WALK_HITS))
        self.rn = np.zeros(0, dtype=np.int64)
        # the same for the sensor's own velocity over ground (sensor axes): a standing object's relative acceleration
        self.svh = np.zeros((1, ACCEL_WINDOW, 2))
        self.sth = np.zeros((1, ACCEL_WINDOW))
        self.snh = np.zeros(1, dtype=np.int64)
        self.last_yaw_rate_rps = 0.0
        self.last_t: float | None = None
        self.yaw_history: list[tuple[float, float]] = []      # (t, yaw rate) of the last 2·BEND_STEADY_S
        self.first_t: float | None = None                     # the time of the first step (the radar's start)

    def step(self, t_s: float, det: Detections, sensor_velocity: tuple[float, float], yaw_rate_rps: float = 0.0
             ) -> ObjectList:
        """One cycle: ``sensor_velocity`` (sensor axes) and ``yaw_rate_rps`` are the ego motion the radar knows."""
        groups = group_detections(det, staggered=self.staggered)
        dt = 0.0 if self.last_t is None else t_s - self.last_t
        self.last_t = t_s
        if self.first_t is None:
            self.first_t = float(t_s)
        if len(self.x):
            now = (float(sensor_velocity[0]), float(sensor_velocity[1]))
            before = (float(self.svh[0, -1, 0]), float(self.svh[0, -1, 1])) if self.snh[0] else None
            # which tracks stand still over ground, as the last cycle's estimate and sensor velocity say (only where
            # the ego's speed changed: nothing else depends on it)
            standing = None if before in (None, now) else ~self._heading(np.arange(len(self.x)), before)[1]
            self.x, self.p = predict(self.x, self.p, dt, yaw_rate_rps=yaw_rate_rps, sensor_velocity=now,
                                     previous_sensor_velocity=before, standing=standing)
        z = np.stack([groups.x_m, groups.y_m, groups.range_rate_mps], axis=1) if len(groups) else np.zeros((0, 3))
        r_cov = self._measurement_cov(z, groups.cross_sigma_m)
        span = self.alias_span_mps or 0.0
        wrap = (groups.ambiguous[None, :] | ~self.resolved[:, None]) if span else None
        pairs = associate(self.x, self.p, z, r_cov, wrap=wrap, span_mps=span)
        hit = np.zeros(len(self.x), dtype=bool)
        used = np.zeros(len(groups), dtype=bool)
        if pairs:
            ti, gi = np.array(pairs).T
            if span:
                z = self._unwrap(ti, gi, z, groups.ambiguous, span)
            if self.range_walk:
                self._walk_history(ti, z[gi], t_s)
            hop = self._hops(ti, z[gi], sensor_velocity)
            # a moving body a side edge of the field of view cuts: where along it the detection lies is not measured (its
            # length as the object list gives it: a car seen one detection a cycle measures no extent, its class does)
            heading, moving = self._heading(ti, sensor_velocity)
            speed = np.hypot(self.x[ti, 2] + sensor_velocity[0], self.x[ti, 3] + sensor_velocity[1])
            length = self._body(ti, speed, moving)[1]
            cut = moving & ~self._body_in_fov(z[gi], heading, length)
            p_pair = self.p[ti] + along_body_cov(z[gi], heading, np.where(cut, length, 0.0))
            self.x[ti], self.p[ti] = update(self.x[ti], p_pair, z[gi], r_cov[gi])
            if hop.any():
                self._standing_across(ti[hop], sensor_velocity, z[gi[hop]])
                self.nh[ti[hop]] = 0            # a re-anchored velocity starts the slope's history again
            fit = np.isfinite(groups.velocity[gi, 0])
            if fit.any():      # a joined near body: its fitted velocity across the line of sight too
                t, g = ti[fit], gi[fit]
                self.x[t], self.p[t] = tangential_update(self.x[t], self.p[t], z[g], groups.velocity[g],
                                                         groups.velocity_cov[g])
            narrow = _across_known(groups, gi)
            if narrow.any():   # a narrower group's fit: its speed across the line of sight, as far as it measures it
                t, g = ti[narrow], gi[narrow]
                self.x[t], self.p[t] = tangential_update(self.x[t], self.p[t], z[g], groups.across[g],
                                                         groups.across_cov[g])
            hit[ti], used[gi] = True, True
            if self.range_walk:
                walk = ti[~self.resolved[ti]]
                self._walk(walk[~self._body_wrap(walk, span, sensor_velocity)], span)
            _, shows = self._heading(ti, sensor_velocity)
            radial = ~_standing_rate(z[gi], sensor_velocity)
            # a joined near body's velocity fitted from its detections' radial speeds measures the motion across the
            # line of sight (not a position's step): motion at once, as a radial speed that is not the world's
            at_once = radial | fit | (np.hypot(z[gi, 0], z[gi, 1]) > MOVING_EVIDENCE_RANGE_M)
            self.evidence[ti] = np.where(shows & at_once, _EVIDENCE_MASK,
                                         ((self.evidence[ti] << 1) | shows) & _EVIDENCE_MASK)
            # extent: what the detections spanned over the last cycles (a decaying maximum: one cycle sees only a
            # part of a body, and a far one is a single detection until its parts are resolved)
            # measured along the body's heading over ground (a moving object; a standing one along the sensor's
            # axes, as its orientation is reported): a corner radar sees a car beside it as long, not as wide
            heading, moving = self._heading(ti, sensor_velocity)
            h_group = np.zeros(len(groups))
            h_group[gi] = np.where(moving, heading, 0.0)
            seen = extents_along(det, groups.labels, h_group)[gi]
            self.size[ti] = np.maximum(SIZE_DECAY * self.size[ti], seen)
            # RCS averaged in power, not in dB: a fluctuating (Swerling 1) target's mean of log power lies
            # 2.5 dB below its mean power, and its mean power is its RCS
            self.power[ti] = (1.0 - RCS_GAIN) * self.power[ti] + RCS_GAIN * 10.0 ** (groups.rcs_dbsm[gi] / 10.0)
            self.tag[ti] = groups.actor_index[gi]
        self.hist = ((self.hist << 1) | hit).astype(np.uint8)
        self.misses = np.where(hit, 0, self.misses + 1)
        if hit.any():           # a measured velocity joins the track's history; a coasting track's history waits
            self.vh[hit] = np.roll(self.vh[hit], -1, axis=1)
            self.th[hit] = np.roll(self.th[hit], -1, axis=1)
            self.vh[hit, -1], self.th[hit, -1] = self.x[hit, 2:4], t_s
            self.nh[hit] = np.minimum(self.nh[hit] + 1, ACCEL_WINDOW)
        self.svh, self.sth = np.roll(self.svh, -1, axis=1), np.roll(self.sth, -1, axis=1)
        self.svh[0, -1], self.sth[0, -1] = (float(sensor_velocity[0]), float(sensor_velocity[1])), t_s
        self.snh = np.minimum(self.snh + 1, ACCEL_WINDOW)
        self.last_yaw_rate_rps = float(yaw_rate_rps)
        self.yaw_history = [(t, w) for t, w in self.yaw_history if t >= t_s - 2.0 * BEND_STEADY_S and t < t_s]
        self.yaw_history.append((float(t_s), float(yaw_rate_rps)))
        new_tracks = np.flatnonzero(~used)
        self._initiate(groups, z, new_tracks, sensor_velocity, r_cov)
        # a track standing still over ground is confirmed over a longer window and coasts longer: the ego motion
        # predicts where it is (a stopped car under a bridge deck, masked in its CA-CFAR ring two cycles in three)
        _, moving = self._heading(np.arange(len(self.x)), sensor_velocity)
        bits = np.unpackbits(self.hist[:, None], axis=1)
        recent = np.where(moving, bits[:, -CONFIRM_WINDOW:].sum(axis=1),
                          bits[:, -CONFIRM_WINDOW_STATIONARY:].sum(axis=1))
        newly = ~self.confirmed & (recent >= CONFIRM_HITS) & self.resolved
        self._assign_ids(np.flatnonzero(newly))
        self.confirmed |= newly & (self.ids >= 0)
        coast = np.where(moving, COAST_CYCLES, COAST_STATIONARY_CYCLES)
        tentative = np.where(moving, 0, CONFIRM_WINDOW_STATIONARY - CONFIRM_HITS)
        # a track coasting beyond the farthest sector's range has left where the radar can see it (a rear radar's
        # posts receding at 130 km/h coasted 26 m past its 250 m, listed out to 276 m)
        beyond = (self.misses > 0) & (np.hypot(self.x[:, 0], self.x[:, 1]) > self.reach)
        self._delete((self.misses > coast) | (~self.confirmed & (self.misses > tentative)) | (self.x[:, 0] < 0.0)
                     | beyond | self._duplicates())
        return self._object_list(sensor_velocity)

    def _unwrap(self, ti: np.ndarray, gi: np.ndarray, z: np.ndarray, ambiguous: np.ndarray, span: float
                ) -> np.ndarray:
        """Tracks ``ti`` about to take groups ``gi`` whose range rates were compared modulo ``span``: an ambiguous
        group's measurement moved by whole spans to the track's (a copy of ``z`` returned); an unresolved track
        that takes an unambiguous group moved to the group's wrap instead (its velocity along the line of sight by
        the whole spans between them) and marked resolved."""
        h, _ = measure(self.x[ti])
        nu = z[gi, 2] - h[:, 2]
        shift = nu - wrap_rate(nu, span)                      # whole spans (0 where they agree already)
        amb = ambiguous[gi]
        z = z.copy()
        z[gi[amb], 2] -= shift[amb]
        move = ~amb & ~self.resolved[ti] & (shift != 0.0)
        if move.any():
            self._move_wraps(ti[move], shift[move])
        self.resolved[ti[~amb]] = True
        return z

    def _walk_history(self, idx: np.ndarray, z: np.ndarray, t_s: float) -> None:
        """Tracks ``idx`` took detections ``z`` (x, y, range rate) at ``t_s``: their measured ranges join the
        histories the range walk is measured on (:meth:`_walk`)."""
        if idx.size == 0:
            return
        self.rh[idx] = np.roll(self.rh[idx], -1, axis=1)
        self.rth[idx] = np.roll(self.rth[idx], -1, axis=1)
        self.rh[idx, -1], self.rth[idx, -1] = np.hypot(z[:, 0], z[:, 1]), t_s
        self.rn[idx] = np.minimum(self.rn[idx] + 1, RANGE_WALK_HITS)

    def _walk(self, idx: np.ndarray, span: float) -> None:
        """Unresolved tracks ``idx``, just updated (range_walk): where the slope of their last measured ranges (least
        squares over two hits or more) lies within a quarter ``span`` of a wrap of their range rate, the velocity
        along the line of sight moves by the whole spans to it (from the second hit: a track at the aliased speed
        loses its target at the third), and with at least RANGE_WALK_MIN_HITS hits the track is resolved."""
        idx = idx[self.rn[idx] >= 2]
        if idx.size == 0:
            return
        n = self.rn[idx]
        use = np.arange(RANGE_WALK_HITS)[None, :] >= RANGE_WALK_HITS - n[:, None]      # the hits held (newest last)
        t, r = np.where(use, self.rth[idx], 0.0), np.where(use, self.rh[idx], 0.0)
        t_mean = t.sum(axis=1) / n
        r_mean = r.sum(axis=1) / n
        dt = np.where(use, self.rth[idx] - t_mean[:, None], 0.0)
        den = np.sum(dt * dt, axis=1)
        slope = np.sum(dt * np.where(use, self.rh[idx] - r_mean[:, None], 0.0), axis=1) / np.maximum(den, 1e-12)
        h, _ = measure(self.x[idx])
        miss = slope - h[:, 2]
        k = np.round(miss / span)
        sure = (np.abs(miss - k * span) <= 0.25 * span) & (den > 0.0)
        self.resolved[idx[sure & (n >= RANGE_WALK_MIN_HITS)]] = True
        move = sure & (k != 0.0)
        if move.any():
            self._move_wraps(idx[move], k[move] * span)

    def _move_wraps(self, idx: np.ndarray, shift: np.ndarray) -> None:
        """Tracks ``idx``: their velocity along the line of sight moved by ``shift`` (whole spans, m/s); where it
        moved, their velocities so far were at another wrap, and the slope's history starts again."""
        r = np.maximum(np.hypot(self.x[idx, 0], self.x[idx, 1]), 1e-3)
        self.x[idx, 2] += shift * self.x[idx, 0] / r
        self.x[idx, 3] += shift * self.x[idx, 1] / r
        self.nh[idx] = np.where(shift != 0.0, 0, self.nh[idx])

    def _body_wrap(self, idx: np.ndarray, span: float, sensor_velocity) -> np.ndarray:
        """Which of the unresolved tracks ``idx``, just updated (range_walk), lie on the body of a confirmed, resolved
        track (within its extent along the sensor's axes, from its nearest face and about its mean lateral position,
        and BODY_MARGIN_M beyond) whose velocity gives their range rate there modulo ``span`` within
        BODY_WRAP_TOL_MPS: another reflector of a body already listed. Each takes that track's wrap (its velocity
        along the line of sight moved by the whole spans between them) and does not walk its own range, nor is it
        listed while it is there: the reflectors a long or passing body shows change from cycle to cycle, and their
        ranges step by about a wrap's drift (a truck closing at 4.8 m/s on fast_chirp: 74.2, 72.0, 69.8 m, three hits
        of a new track walking along its side at −42.8 m/s, listed oncoming beside the truck's own track)."""
        ref = np.flatnonzero(self.confirmed & self.resolved)
        if idx.size == 0 or ref.size == 0:
            return np.zeros(idx.size, dtype=bool)
        heading, moving = self._heading(ref, sensor_velocity)
        h = np.where(moving, heading, 0.0)            # a standing track's extent is along the sensor's axes
        length, width = self.size[ref, 0], self.size[ref, 1]
        ex = np.abs(length * np.cos(h)) + np.abs(width * np.sin(h))      # the body's extent along the sensor's x …
        ey = np.abs(length * np.sin(h)) + np.abs(width * np.cos(h))      # … and y
        dx = self.x[idx, None, 0] - self.x[None, ref, 0]                  # (n, m)
        dy = self.x[idx, None, 1] - self.x[None, ref, 1]
        on = (dx >= -BODY_MARGIN_M) & (dx <= ex[None, :] + BODY_MARGIN_M) \
            & (np.abs(dy) <= 0.5 * ey[None, :] + BODY_MARGIN_M) & (ref[None, :] != idx[:, None])
        r = np.maximum(np.hypot(self.x[idx, 0], self.x[idx, 1]), 1e-3)
        ux, uy = self.x[idx, 0] / r, self.x[idx, 1] / r
        own = self.x[idx, 2] * ux + self.x[idx, 3] * uy
        miss = self.x[None, ref, 2] * ux[:, None] + self.x[None, ref, 3] * uy[:, None] - own[:, None]
        k = np.round(miss / span)
        cost = np.where(on & (np.abs(miss - k * span) <= BODY_WRAP_TOL_MPS), dx * dx + dy * dy, np.inf)
        j = np.argmin(cost, axis=1)
        rows = np.arange(idx.size)
        ok = np.isfinite(cost[rows, j])
        if ok.any():
            self._move_wraps(idx[ok], k[rows[ok], j[ok]] * span)
        return ok

    def _hops(self, idx: np.ndarray, z: np.ndarray, sensor_velocity) -> np.ndarray:
        """Which of the tracks ``idx``, each about to take detection ``z`` (x, y, range rate), stand still (never
        seen moving, not moving now, the detection's range rate that of the standing world within
        MOVING_THRESHOLD_MPS) and take a detection more than HOP_M across the line of sight from where they are,
        beyond the extent they span."""
        x = self.x[idx]
        r = np.maximum(np.hypot(z[:, 0], z[:, 1]), 1e-3)
        ux, uy = z[:, 0] / r, z[:, 1] / r
        across = np.abs(-(z[:, 0] - x[:, 0]) * uy + (z[:, 1] - x[:, 1]) * ux)
        # within a body the detection wanders over what it spans across the line of sight (a standing track's extent
        # is along the sensor's axes): a truck crossing at 3 m/s hopped 19 times without this
        across = across - (np.abs(self.size[idx, 0] * uy) + np.abs(self.size[idx, 1] * ux))
        _, moving = self._heading(idx, sensor_velocity)
        # a standing track that coasted (its position across the line of sight extrapolated with a velocity only
        # position differences ever measured) and takes a detection again has nothing to move it by either: the
        # merged rails' glint at long range walks it across the road in steps under HOP_M otherwise
        coasted = self.misses[idx] >= COAST_REANCHOR_MISSES
        return ((across > HOP_M) | coasted) & ~moving & ~self.was_moving[idx] & _standing_rate(z, sensor_velocity)

    def _standing_across(self, idx: np.ndarray, sensor_velocity, z: np.ndarray) -> None:
        """Tracks ``idx`` that hopped to another standing reflector, detection ``z`` (x, y, range rate): their
        velocity across the line of sight set to the standing world's, its variance to the new track's prior
        (2 m/s), and their radial velocity over ground to what the detection's range rate measures (the update's
        own moved with the position jump: after a long coast a jump of a few metres put 1 m/s into it, and a post
        became a moving object)."""
        x, p = self.x[idx], self.p[idx]
        r = np.maximum(np.hypot(x[:, 0], x[:, 1]), 1e-3)
        u = np.stack([x[:, 0] / r, x[:, 1] / r], axis=1)
        world = -np.asarray(sensor_velocity, dtype=np.float64)
        rz = np.maximum(np.hypot(z[:, 0], z[:, 1]), 1e-3)
        radial = z[:, 2] - (world[0] * z[:, 0] + world[1] * z[:, 1]) / rz     # the range rate over the standing world's
        self.x[idx, 2:4] = world + radial[:, None] * u
        perp = np.stack([-u[:, 1], u[:, 0]], axis=1)
        pv = p[:, 2:4, 2:4]
        var_r = np.einsum("ki,kij,kj->k", u, pv, u)
        self.p[idx, 2:4, 2:4] = var_r[:, None, None] * u[:, :, None] * u[:, None, :] \
            + TANGENTIAL_PRIOR_VAR * perp[:, :, None] * perp[:, None, :]
        self.p[idx, 0:2, 2:4] = 0.0
        self.p[idx, 2:4, 0:2] = 0.0

    def _reported_motion(self, idx: np.ndarray, sensor_velocity) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`_heading`, and whether each of tracks ``idx`` is reported moving: where it moves now and, for a track
        never seen moving, did in :data:`MOVING_EVIDENCE_CYCLES` of its last :data:`MOVING_EVIDENCE_WINDOW` measured
        cycles (or its radial speed, or its range beyond MOVING_EVIDENCE_RANGE_M, said so at once). Only the list
        sent waits for the evidence: the tracker's own rules (hops, confirmation, coasting) take the motion as it
        shows (a car crossing close ahead, not yet reported moving, must not be re-anchored as a standing hop)."""
        heading, shows = self._heading(idx, sensor_velocity)
        return heading, shows & (self.was_moving[idx] | (_POPCOUNT[self.evidence[idx]] >= MOVING_EVIDENCE_CYCLES))

    def _heading(self, idx: np.ndarray, sensor_velocity) -> tuple[np.ndarray, np.ndarray]:
        """Heading over ground (sensor axes, rad) of tracks ``idx`` and whether each moves: only where the ground
        speed stands out of its own uncertainty (the lateral velocity of a far object is poorly observed, azimuth
        noise × range, and a post must not become a crossing object)."""
        x, pv = self.x[idx], self.p[idx][:, 2:4, 2:4]
        gx, gy = x[:, 2] + sensor_velocity[0], x[:, 3] + sensor_velocity[1]
        speed = np.hypot(gx, gy)
        ux, uy = gx / np.maximum(speed, 1e-9), gy / np.maximum(speed, 1e-9)
        sigma = np.sqrt(np.maximum(ux * ux * pv[:, 0, 0] + 2 * ux * uy * pv[:, 0, 1] + uy * uy * pv[:, 1, 1], 0.0))
        return np.arctan2(gy, gx), speed >= np.maximum(MOVING_THRESHOLD_MPS, 3.0 * sigma)

    def _body(self, idx: np.ndarray, ground_speed_mps: np.ndarray, moving: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Class, length and width of tracks ``idx`` as the object list gives them: the extent measured, at least
        the class's smallest body (:data:`MIN_BODY_M`)."""
        length, width = np.maximum(self.size[idx, 0], 0.2), np.maximum(self.size[idx, 1], 0.2)
        rcs = 10.0 * np.log10(np.maximum(self.power[idx], 1e-12))
        cls = classify(length, width, rcs, ground_speed_mps, moving)
        body = MIN_BODY_M[cls]
        return cls, np.maximum(length, body[:, 0]), np.maximum(width, body[:, 1])

    def _body_in_fov(self, z: np.ndarray, heading_rad: np.ndarray, length_m: np.ndarray) -> np.ndarray:
        """Whether the field of view's side edges leave a body of ``length_m`` heading along ``heading_rad`` whole from
        the groups ``z`` (n, ≥ 2) on: both points a body length ahead of and behind each group along the heading lie
        within the half angle of the widest sector that reaches the group's range (a group can lie anywhere on the
        body). Only the angle: a body reaching beyond a sector's range keeps its near end, the point it is reported
        by, where it is (a car crossing 25–35 m from a corner radar of 30 m range is not cut)."""
        reach = np.hypot(z[:, 0], z[:, 1])
        half = np.zeros(len(z))
        for max_range_m, half_angle_rad in self.fov:
            half = np.where(reach <= max_range_m, np.maximum(half, half_angle_rad), half)
        half = np.where(half > 0.0, half, max(a for _, a in self.fov))
        hx, hy = np.cos(heading_rad) * length_m, np.sin(heading_rad) * length_m
        inside = np.ones(len(z), dtype=bool)
        for sign in (1.0, -1.0):
            inside &= np.abs(np.arctan2(z[:, 1] + sign * hy, z[:, 0] + sign * hx)) <= half
        return inside

    def _measurement_cov(self, z: np.ndarray, glint_m: np.ndarray | None = None) -> np.ndarray:
        """Measurement covariances (m, 3, 3) of the groups: the position noise plus range × σ_az across the
        line of sight, and the glint of an extended reflector (``glint_m``, σ across the line of sight, m)."""
        r = np.hypot(z[:, 0], z[:, 1])
        u = np.stack([z[:, 0], z[:, 1]], axis=1) / np.maximum(r, 1e-3)[:, None]
        perp = np.stack([-u[:, 1], u[:, 0]], axis=1)
        cov = np.repeat(self.r_cov[None], len(z), axis=0)
        across = (r * self.sigma_az_rad) ** 2 + (0.0 if glint_m is None else glint_m ** 2)
        cov[:, :2, :2] += across[:, None, None] * perp[:, :, None] * perp[:, None, :]
        return cov

    def _initiate(self, groups, z, idx, sensor_velocity, r_cov) -> None:
        if idx.size == 0:
            return
        k = idx.size
        x0 = np.zeros((k, 4))
        x0[:, 0:2] = z[idx, 0:2]
        # velocity: the radial component is measured, the tangential one a prior (initial_velocity)
        x0[:, 2], x0[:, 3], known = initial_velocity(z[idx, 0], z[idx, 1], z[idx, 2], sensor_velocity,
                                                     self.steady_yaw_rate(), with_direction=True)
        r = np.maximum(np.hypot(z[idx, 0], z[idx, 1]), 1e-3)
        ux, uy = z[idx, 0] / r, z[idx, 1] / r
        fit = np.isfinite(groups.velocity[idx, 0])          # a joined near body: its fitted velocity
        # initial covariance: the position as measured; the velocity's radial part as measured, its tangential
        # part from the prior (initial_velocity; σ 2 m/s, a moving reflector's where no road direction is known σ 10
        # m/s: CROSSING_PRIOR_VAR). A looser position (it was 1 m) let a new track of a guardrail post take the next
        # post 4 m on, and leave at a false speed.
        p0 = np.zeros((k, 4, 4))
        p0[:, 0:2, 0:2] = r_cov[idx, 0:2, 0:2]
        u = np.stack([ux, uy], axis=1)
        # (a group whose range rate may be aliased stands where it does modulo the span: a guardrail post beyond
        # ±v_max, a staggered pair's unpaired detection at 130 km/h)
        stands = _standing_rate(z[idx], sensor_velocity, groups.ambiguous[idx], self.alias_span_mps or 0.0)
        across = np.where(known | stands, TANGENTIAL_PRIOR_VAR, CROSSING_PRIOR_VAR)
        p0[:, 2:4, 2:4] = (self.r_cov[2, 2] * u[:, :, None] * u[:, None, :]
                           + across[:, None, None] * (np.eye(2)[None] - u[:, :, None] * u[:, None, :]))
        if fit.any():
            x0[fit, 2:4] = groups.velocity[idx[fit]]
            p0[fit, 2:4, 2:4] = groups.velocity_cov[idx[fit]] + self.r_cov[2, 2] * np.eye(2)[None]
        narrow = _across_known(groups, idx)
        if narrow.any():       # the prior, updated with a narrower group's fit across the line of sight
            g = idx[narrow]
            x0[narrow], p0[narrow] = tangential_update(x0[narrow], p0[narrow], z[g], groups.across[g],
                                                       groups.across_cov[g])
        self.x = np.concatenate([self.x, x0])
        self.p = np.concatenate([self.p, p0])
        self.hist = np.concatenate([self.hist, np.ones(k, dtype=np.uint8)])
        self.misses = np.concatenate([self.misses, np.zeros(k, dtype=np.int64)])
        self.confirmed = np.concatenate([self.confirmed, np.zeros(k, dtype=bool)])
        self.resolved = np.concatenate([self.resolved, ~groups.ambiguous[idx] if self.alias_span_mps
                                        else np.ones(k, dtype=bool)])
        self.ids = np.concatenate([self.ids, np.full(k, -1, dtype=np.int64)])
        self.was_moving = np.concatenate([self.was_moving, np.zeros(k, dtype=bool)])
        near = np.hypot(z[idx, 0], z[idx, 1]) <= MOVING_EVIDENCE_RANGE_M
        self.evidence = np.concatenate([self.evidence, np.where(_standing_rate(z[idx], sensor_velocity) & near, 0,
                                                                _EVIDENCE_MASK)])
        self.size = np.concatenate([self.size, np.stack([groups.length_m[idx], groups.width_m[idx]], 1)])
        self.power = np.concatenate([self.power, 10.0 ** (groups.rcs_dbsm[idx] / 10.0)])
        self.tag = np.concatenate([self.tag, groups.actor_index[idx]])
        # a new track's first velocity is a prior, not a measurement of it: its slope starts with the next cycle's
        self.vh = np.concatenate([self.vh, np.zeros((k, ACCEL_WINDOW, 2))])
        self.th = np.concatenate([self.th, np.zeros((k, ACCEL_WINDOW))])
        self.nh = np.concatenate([self.nh, np.zeros(k, dtype=np.int64)])
        self.rh = np.concatenate([self.rh, np.zeros((k, RANGE_WALK_HITS))])
        self.rth = np.concatenate([self.rth, np.zeros((k, RANGE_WALK_HITS))])
        self.rn = np.concatenate([self.rn, np.zeros(k, dtype=np.int64)])
        if self.range_walk:
            self._walk_history(np.arange(len(self.x) - k, len(self.x)), z[idx], self.last_t)

    def steady_yaw_rate(self) -> float:
        """The yaw rate as a bend's (the mean over the last ``BEND_STEADY_S``) where it kept its sign and stayed within
        a factor of 2 that long, and a history covers it; 0 (a straight road) otherwise. In the radar's first
        ``BEND_STEADY_S`` the history since its first step covers it: a run that starts on a bend has no straight road
        behind it (its tracks started on the straight road's prior, 3 m/s across at 35 m on R 250 m, and a truck in the
        inner lane drew a trail that bent the ECU's path onto its own side; a lane change still never counts, as its yaw
        rate starts from 0 or changes sign). Its cost: a run that starts a few metres before a bend's exit starts a car
        already on the straight beyond it as if it followed the bend (``benchmarks/bends.py --only exit_at_start``)."""
        if not self.yaw_history:
            return 0.0
        t_last = self.yaw_history[-1][0]
        start = self.yaw_history[0][0]
        if start > t_last - BEND_STEADY_S + 1e-9 and start != self.first_t:
            return 0.0
        w = np.array([w for t, w in self.yaw_history if t >= t_last - BEND_STEADY_S - 1e-9])
        a = np.abs(w)
        if not (np.all(w > 0.0) or np.all(w < 0.0)) or a.min() < 0.5 * a.max():
            return 0.0
        return float(w.mean())

    def _acceleration(self, idx: np.ndarray, x: np.ndarray, moving: np.ndarray, sigma_vx: np.ndarray,
                      sigma_vy: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Relative acceleration (sensor axes, the scene's: the change of the relative velocity over ground, turned
        into the sensor's axes) of the tracks ``idx`` with states ``x`` and its σ: (long, lat, σ long, σ lat).

        A moving track's is the slope of its filtered relative velocity over the last :data:`ACCEL_WINDOW` cycles (the
        filter is a constant-velocity one: under a constant acceleration its velocity lags by a constant and its slope
        is the acceleration; about 5 cycles to half of a step, 9 to 90 %), σ that of such a slope of velocities known
        to the filter's σ; a coasting track's history waits for its next measurement (its σ grows with the
        filter's). A standing one's is the standing world's, the slope of the sensor's own velocity (the ego
        motion the radar is sent) with the sign turned, its σ that slope's for the track's own velocity σ (which grows
        while it coasts): a post's track, re-anchored at every hop, has no history of its own. Both in the turning
        sensor frame plus ω × v (the sensor turns at the yaw rate ω). NaN σ (the wire's Invalid) and 0 where fewer
        than three cycles are behind the slope."""
        slope, per = velocity_slope(self.vh[idx], self.th[idx], self.nh[idx])
        sig_x, sig_y = sigma_vx * per, sigma_vy * per
        world, world_per = velocity_slope(self.svh, self.sth, self.snh)
        standing = ~moving
        slope = np.where(standing[:, None], -world, slope)
        # a standing track's: the world's, as far as its own velocity (the filter's σ, grown while it coasts) says
        # that it stands
        sig_x = np.where(standing, np.hypot(EGO_SPEED_SIGMA_MPS, sigma_vx) * world_per[0], sig_x)
        sig_y = np.where(standing, np.hypot(EGO_SPEED_SIGMA_MPS, sigma_vy) * world_per[0], sig_y)
        w = self.last_yaw_rate_rps
        ax, ay = slope[:, 0] - w * x[:, 3], slope[:, 1] + w * x[:, 2]
        known = np.isfinite(sig_x)
        return (np.where(known, ax, 0.0), np.where(known, ay, 0.0), np.where(known, sig_x, np.nan),
                np.where(known, sig_y, np.nan))

    def _duplicates(self, eps_m: float = GROUP_EPS_M, eps_long_m: float = GROUP_EPS_LONG_M, eps_mps: float = 1.0
                    ) -> np.ndarray:
        """Tracks that are parts of an older track's body: within the grouping distance of it and moving with
        it (one body split into two groups for a few cycles leaves two tracks that would never meet again)."""
        n = len(self.x)
        if n < 2:
            return np.zeros(n, dtype=bool)
        dx = (self.x[:, None, 0] - self.x[None, :, 0]) / eps_long_m
        dy = (self.x[:, None, 1] - self.x[None, :, 1]) / eps_m
        dv = np.hypot(self.x[:, None, 2] - self.x[None, :, 2], self.x[:, None, 3] - self.x[None, :, 3]) / eps_mps
        close = (dx * dx + dy * dy <= 1.0) & (dv <= 1.0)
        older = np.arange(n)[None, :] < np.arange(n)[:, None]        # column j was created before row i
        return (close & older).any(axis=1)

    def _assign_ids(self, idx: np.ndarray) -> None:
        """IDs 0–255 (the ARS 408's 8-bit Obj_ID) for the tracks ``idx`` to confirm, nearest first; while all 256 are
        taken (hundreds of confirmed tracks: a Pfa of 1e-2 confirmed that many false ones) the rest stay tentative
        and try again next cycle (they raised StopIteration)."""
        used = np.zeros(256, dtype=bool)
        used[self.ids[self.ids >= 0]] = True
        free = np.flatnonzero(~used)
        if idx.size > free.size:
            idx = idx[np.argsort(np.hypot(self.x[idx, 0], self.x[idx, 1]), kind="stable")]
        take = min(idx.size, free.size)
        self.ids[idx[:take]] = free[:take]

    def _delete(self, gone: np.ndarray) -> None:
        keep = ~gone
        for name in ("x", "p", "hist", "misses", "confirmed", "resolved", "ids", "was_moving", "evidence", "size",
                     "power", "tag", "vh", "th", "nh", "rh", "rth", "rn"):
            setattr(self, name, getattr(self, name)[keep])

    def _object_list(self, sensor_velocity) -> ObjectList:
        idx = np.flatnonzero(self.confirmed)
        if idx.size > self.max_objects:
            idx = idx[np.argsort(np.hypot(self.x[idx, 0], self.x[idx, 1]))[: self.max_objects]]
        n = idx.size
        x = self.x[idx]
        ol = ObjectList.empty(n)
        ol.id = self.ids[idx].copy()
        ol.dist_long_m, ol.dist_lat_m, ol.vrel_long_mps, ol.vrel_lat_mps = x[:, 0], x[:, 1], x[:, 2], x[:, 3]
        gx, gy = x[:, 2] + sensor_velocity[0], x[:, 3] + sensor_velocity[1]
        speed = np.hypot(gx, gy)
        pv = self.p[idx][:, 2:4, 2:4]
        ux, uy = gx / np.maximum(speed, 1e-9), gy / np.maximum(speed, 1e-9)
        heading, moving = self._reported_motion(idx, sensor_velocity)
        self.was_moving[idx] |= moving
        angle = np.abs(heading)
        dyn = np.where(angle > np.radians(135), DYN_ONCOMING, np.where(angle > np.radians(45), DYN_CROSSING_MOVING,
                                                                        DYN_MOVING))
        ol.dyn_prop = np.where(moving, dyn, np.where(self.was_moving[idx], DYN_STOPPED, DYN_STATIONARY))
        rcs = 10.0 * np.log10(np.maximum(self.power[idx], 1e-12))
        ol.rcs_dbsm = rcs
        p = self.p[idx]
        ol.dist_long_sigma_m, ol.dist_lat_sigma_m = np.sqrt(p[:, 0, 0]), np.sqrt(p[:, 1, 1])
        ol.vrel_long_sigma_mps, ol.vrel_lat_sigma_mps = np.sqrt(p[:, 2, 2]), np.sqrt(p[:, 3, 3])
        ol.arel_long_mps2, ol.arel_lat_mps2, ol.arel_long_sigma_mps2, ol.arel_lat_sigma_mps2 = \
            self._acceleration(idx, x, moving, ol.vrel_long_sigma_mps, ol.vrel_lat_sigma_mps)
        fresh = np.unpackbits(self.hist[idx, None], axis=1).sum(axis=1) <= CONFIRM_HITS
        ol.meas_state = np.where(self.misses[idx] > 0, MEAS_PREDICTED, np.where(fresh, MEAS_NEW, MEAS_MEASURED))
        hits = np.unpackbits(self.hist[idx, None], axis=1).sum(axis=1)
        ol.prob_of_exist = np.searchsorted(_PROB_EDGES, 1.0 - 0.5 ** hits, side="right").astype(np.int64) + 1
        ol.obj_class, length, width = self._body(idx, speed, moving)
        ol.orientation_rad = np.where(moving, heading, 0.0)
        # heading of a moving object from its velocity's direction, of a standing one from its two ends
        across = np.sqrt(np.maximum(uy * uy * pv[:, 0, 0] - 2 * ux * uy * pv[:, 0, 1] + ux * ux * pv[:, 1, 1], 0.0))
        from_velocity = np.arctan2(across, np.maximum(speed, 1e-9))
        pos = np.sqrt(0.5 * (p[:, 0, 0] + p[:, 1, 1]))
        ol.orientation_sigma_rad = np.where(moving, np.minimum(from_velocity, math.pi),
                                            orientation_sigma_rad(pos, length))
        ol.length_m, ol.width_m = length, width
        ol.actor_index = self.tag[idx].copy()
        return ol


def classify(length_m, width_m, rcs_dbsm, ground_speed_mps, moving) -> np.ndarray:
    """An ARS 408 class from extent, RCS and speed over ground (point, car, truck, pedestrian, motorcycle,
    bicycle, wide).

    Extent first (a truck's length, a car's, a wide structure's width); where the body is not resolved (one
    detection at range), the RCS: a vehicle's rear returns 5 dBsm or more (a car about 10, a truck about 20);
    below that a moving object is told by its speed — a pedestrian walks below 3 m/s, a bicycle rides below
    9 m/s, faster is a motorcycle; a weak stationary one is a point (a post, a sign's edge, a pedestrian who
    stands).
    """
    extent = np.maximum(length_m, width_m)
    v = np.asarray(ground_speed_mps, dtype=np.float64)
    weak_moving = np.where(v < WALK_MAX_MPS, 3, np.where(v < BICYCLE_MAX_MPS, 5, 4))
    small = np.where(rcs_dbsm >= TRUCK_RCS_DBSM, 2,
                     np.where(rcs_dbsm >= VEHICLE_RCS_DBSM, 1, np.where(moving, weak_moving, 0)))
    # an extent with the RCS of a few posts (merged guardrail reflections, ≈ −2 dBsm) is no vehicle body
    body = np.where(rcs_dbsm >= TRUCK_RCS_DBSM, 2, np.where(rcs_dbsm >= BODY_MIN_RCS_DBSM, 1, 0))
    return np.where((extent > 8.0) & (rcs_dbsm >= BODY_MIN_RCS_DBSM), 2,
                    np.where(extent > 1.2, np.where(width_m > 3.0, 6, body), small)).astype(np.int64)


def cluster_dyn_prop(range_rate_mps: np.ndarray, azimuth_rad: np.ndarray, sensor_velocity,
                     cos_sin: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """DynProp of a single detection from what it measures: its radial speed over ground (ego-compensated).

    A cluster has no lateral speed of its own; its radial ground speed decides
    stationary (below ``MOVING_THRESHOLD_MPS``), oncoming (closing) or moving.
    ``cos_sin``: the azimuths' cosine and sine, where the caller has them.
    """
    c, s = (np.cos(azimuth_rad), np.sin(azimuth_rad)) if cos_sin is None else cos_sin
    ground = range_rate_mps + sensor_velocity[0] * c + sensor_velocity[1] * s
    return np.where(np.abs(ground) < MOVING_THRESHOLD_MPS, DYN_STATIONARY,
                    np.where(ground < 0, DYN_ONCOMING, DYN_MOVING)).astype(np.int64)


def clusters_from_detections(det: Detections, near_range_m: float, sensor_velocity: tuple[float, float],
                             max_clusters: int = 250) -> ClusterList:
    """Each detection is an ARS 408 cluster; near-scan clusters first, each part sorted by range."""
    r = det.range_m
    near = r <= near_range_m
    order = np.lexsort((r, ~near))[:max_clusters]
    d = det.take(order)
    n = len(d)
    cl = ClusterList.empty(n)
    cl.id = np.arange(n, dtype=np.int64)
    c, s = np.cos(d.azimuth_rad), np.sin(d.azimuth_rad)
    cl.dist_long_m, cl.dist_lat_m = d.range_m * c, d.range_m * s
    cl.vrel_long_mps, cl.vrel_lat_mps = d.range_rate_mps * c, d.range_rate_mps * s
    cl.dyn_prop = cluster_dyn_prop(d.range_rate_mps, d.azimuth_rad, sensor_velocity)
    cl.rcs_dbsm = d.rcs_dbsm
    cl.dist_long_sigma_m = np.full(n, 0.2)
    cl.dist_lat_sigma_m = np.maximum(0.2, d.range_m * 0.01)
    cl.vrel_long_sigma_mps = np.full(n, 0.1)
    cl.vrel_lat_sigma_mps = np.full(n, 0.5)
    cl.pdh0 = np.where(d.snr_db > 20.0, 1, 2).astype(np.int64)
    cl.ambig_state = d.ambig_state.copy()
    cl.invalid_state = np.zeros(n, dtype=np.int64)
    cl.is_near = near[order]
    cl.actor_index = d.actor_index.copy()
    return cl
