"""Several radars' object lists fused into one, in the vehicle frame, with track-to-track association.

Each sensor's objects are taken from its own frame (x forward, y left of the sensor) into the vehicle frame
(rear-axle centre) through its mount (:class:`radarnode.consumer.path.SensorMount`, calibrated into the ECU),
their positions with the covariance their σ fields give (rotated with the sensor's yaw) and their velocities
relative to the vehicle. The fusion keeps fused tracks from cycle to cycle:

1. **Continuity.** An object whose (sensor, object ID) fed a fused track last cycle feeds it again, as long as it
   still lies within the gate: a radar keeps its object IDs, so the association is kept where it holds.
2. **Association.** The others are assigned to fused tracks by a globally optimal assignment
   (``scipy.optimize.linear_sum_assignment``) on the Mahalanobis distance of the positions, with the fused
   track predicted to the object's time, the covariance of both and an extent term along and across the
   object's orientation — the better known of the track's and the object's, by the σ the radars report
   (:data:`EXTENT_SIGMA_LONG_M`, :data:`EXTENT_SIGMA_LAT_M`: two radars see
   different points of one car — the front radar its rear, a corner radar its side), gated at
   :data:`GATE_CHI2` (χ² with 2 degrees of freedom, 99.9 %) and never farther apart across the object's heading
   than :data:`MAX_ACROSS_M` (two cars in adjacent 3 m lanes, each seen by another radar, stay two however loose
   their σ); at most one object per sensor per fused track (a radar that reports two objects is believed).
3. **Fusion.** A fused track's position and velocity are the information-weighted mean of its objects this
   cycle (each predicted to the fusion time with its velocity: the sensors' cycles are not simultaneous); a track
   seen by no sensor coasts on its velocity for up to :data:`COAST_CYCLES` fusions, then ends. Unassigned objects
   start new fused tracks.
4. **Merging.** Two fused tracks that different sensors feed and that stay together (:meth:`ObjectFusion._merge`:
   within the association's own gate, with velocities that agree within their σ, three rounds in a row) are one
   object: the younger is merged into the older.

Fused IDs are stable and never reused while alive. ``sensors`` of a fused object is a bit field of the sensor
IDs that saw it this cycle.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from dataclasses import dataclass, field

import can
import numpy as np

from radarnode.consumer.path import SensorMount
from radarnode.perception.types import ObjectList

logger = logging.getLogger(__name__)

GATE_CHI2 = 13.82            # χ²(2) at 0.999
#: where on a vehicle's outline a radar's reference point falls: along the object's heading (the front radar sees
#: a car's rear, a corner radar its side) and across it (half a width at most)
EXTENT_SIGMA_LONG_M, EXTENT_SIGMA_LAT_M = 1.5, 0.5
MIN_SIGMA_M = 0.1            # an object without quality (σ) fields: this position σ, and …
MIN_SIGMA_MPS = 0.25         # … this velocity σ
COAST_CYCLES = 3
MAX_ACROSS_M = 1.5           # objects of two radars farther apart than this across the object's heading: two objects
MAX_GAP_S = 1.0              # a fusion this long after the last (or earlier than it) restarts the fused tracks
MERGE_SPEED_MPS = 1.5        # two fused tracks within the gate and this similar in velocity (or within their σ) …
MERGE_ROUNDS = 3             # … this many rounds in a row, seen by different sensors, are merged


@dataclass
class SensorObjects:
    """One sensor's objects of one cycle in the vehicle frame."""

    sensor_id: int
    t_s: float
    ids: np.ndarray              # the radar's object IDs
    pos: np.ndarray              # (n, 2) vehicle frame
    vel: np.ndarray              # (n, 2) relative to the vehicle, vehicle axes
    cov: np.ndarray              # (n, 2, 2) position covariance
    var_v: np.ndarray            # (n, 2) velocity variance (vehicle axes, diagonal after rotation)
    rcs: np.ndarray
    obj_class: np.ndarray
    length: np.ndarray
    width: np.ndarray
    dyn_prop: np.ndarray
    prob_of_exist: np.ndarray
    heading: np.ndarray          # (n,) the object's orientation in the vehicle frame (0: along the vehicle's x)
    heading_sigma: np.ndarray    # (n,) its σ as the radar reports it (π where it reports none)

    def finite(self) -> np.ndarray:
        """(n,) bool: the objects whose position, velocity and σ are all finite (the others cannot be fused)."""
        return (np.isfinite(self.pos).all(axis=1) & np.isfinite(self.vel).all(axis=1)
                & np.isfinite(self.cov).all(axis=(1, 2)) & np.isfinite(self.var_v).all(axis=1))

    def take(self, keep: np.ndarray) -> SensorObjects:
        return SensorObjects(self.sensor_id, self.t_s, *(getattr(self, f.name)[keep] for f in dataclasses.fields(self)
                                                         if f.name not in ("sensor_id", "t_s")))


def to_vehicle(sensor_id: int, t_s: float, objects: ObjectList, mount: SensorMount) -> SensorObjects:
    """One sensor's object list in the vehicle frame (positions, velocities, covariances)."""
    yaw = math.radians(mount.yaw_deg)
    c, s = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s], [s, c]])
    x, y = mount.to_vehicle(objects.dist_long_m, objects.dist_lat_m)
    vx, vy = mount.rotate(objects.vrel_long_mps, objects.vrel_lat_mps)
    # a list without quality fields (σ NaN) gets the floors; an infinite σ makes a non-finite covariance, and the
    # object is left out by the fusion (SensorObjects.finite)
    nan_to = lambda v, floor: np.where(np.isnan(v), floor, np.maximum(v, floor))   # noqa: E731
    sx, sy = nan_to(objects.dist_long_sigma_m, MIN_SIGMA_M), nan_to(objects.dist_lat_sigma_m, MIN_SIGMA_M)
    svx, svy = nan_to(objects.vrel_long_sigma_mps, MIN_SIGMA_MPS), nan_to(objects.vrel_lat_sigma_mps, MIN_SIGMA_MPS)
    d = np.zeros((len(objects), 2, 2))
    dv = np.zeros((len(objects), 2, 2))
    with np.errstate(invalid="ignore"):                  # ∞·0 in the rotation of an infinite σ: NaN, left out
        d[:, 0, 0], d[:, 1, 1] = sx ** 2, sy ** 2
        cov = rot @ d @ rot.T
        dv[:, 0, 0], dv[:, 1, 1] = svx ** 2, svy ** 2
        cov_v = rot @ dv @ rot.T
    return SensorObjects(sensor_id, t_s, np.asarray(objects.id, dtype=np.int64), np.stack([x, y], axis=1),
                         np.stack([vx, vy], axis=1), cov, np.stack([cov_v[:, 0, 0], cov_v[:, 1, 1]], axis=1),
                         np.asarray(objects.rcs_dbsm, dtype=np.float64), np.asarray(objects.obj_class),
                         np.asarray(objects.length_m, dtype=np.float64), np.asarray(objects.width_m, dtype=np.float64),
                         np.asarray(objects.dyn_prop, dtype=np.int64), np.asarray(objects.prob_of_exist, dtype=np.int64),
                         np.nan_to_num(np.asarray(objects.orientation_rad, dtype=np.float64), nan=0.0) + yaw,
                         np.nan_to_num(np.asarray(objects.orientation_sigma_rad, dtype=np.float64), nan=math.pi))


@dataclass
class FusedObjects:
    """The fused object list of one fusion step (vehicle frame, rear-axle centre; velocities relative)."""

    t_s: float
    id: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    vx_mps: np.ndarray
    vy_mps: np.ndarray
    sigma_x_m: np.ndarray
    sigma_y_m: np.ndarray
    rcs_dbsm: np.ndarray
    obj_class: np.ndarray
    length_m: np.ndarray
    width_m: np.ndarray
    sensors: np.ndarray          # bit field: bit k set when sensor ID k saw it this cycle
    coasting: np.ndarray         # bool: no sensor saw it this cycle
    sigma_vx_mps: np.ndarray
    sigma_vy_mps: np.ndarray
    dyn_prop: np.ndarray         # of the strongest object that fed it (ARS 408 codes)
    prob_of_exist: np.ndarray    # the highest of its objects' (ARS 408 codes)
    new: np.ndarray              # bool: its first cycle
    members: list                # per object: {sensor ID: that radar's object ID} this cycle

    def __len__(self) -> int:
        return int(self.id.size)

    def sensor_ids(self, k: int) -> list[int]:
        """The sensor IDs that saw fused object ``k`` this cycle (its ``sensors`` bit field), ascending."""
        return [b for b in range(8) if int(self.sensors[k]) >> b & 1]

    def in_sensor_frame(self, mount: SensorMount) -> ObjectList:
        """The fused list as an object list in the frame of a radar at ``mount`` (what an ECU written for one
        front radar takes: the fused objects where that radar would report them). IDs are the fused IDs."""
        from radarnode.perception.types import MEAS_MEASURED, MEAS_NEW, MEAS_PREDICTED
        yaw = math.radians(mount.yaw_deg)
        c, s = math.cos(yaw), math.sin(yaw)
        dx, dy = self.x_m - mount.x_m, self.y_m - mount.y_m
        n = len(self)
        nan = np.full(n, np.nan)
        rot = lambda a, b: (c * a + s * b, -s * a + c * b)       # noqa: E731  vehicle axes -> sensor axes
        x, y = rot(dx, dy)
        vx, vy = rot(self.vx_mps, self.vy_mps)
        # σ along the sensor's axes (the covariance's diagonal after the rotation; the fused ones are near round)
        sx = np.sqrt((c * self.sigma_x_m) ** 2 + (s * self.sigma_y_m) ** 2)
        sy = np.sqrt((s * self.sigma_x_m) ** 2 + (c * self.sigma_y_m) ** 2)
        svx = np.sqrt((c * self.sigma_vx_mps) ** 2 + (s * self.sigma_vy_mps) ** 2)
        svy = np.sqrt((s * self.sigma_vx_mps) ** 2 + (c * self.sigma_vy_mps) ** 2)
        meas = np.where(self.coasting, MEAS_PREDICTED, np.where(self.new, MEAS_NEW, MEAS_MEASURED))
        return ObjectList(id=self.id.copy(), dist_long_m=x, dist_lat_m=y, vrel_long_mps=vx, vrel_lat_mps=vy,
                          dyn_prop=self.dyn_prop.copy(), rcs_dbsm=self.rcs_dbsm.copy(),
                          dist_long_sigma_m=sx, dist_lat_sigma_m=sy, vrel_long_sigma_mps=svx,
                          vrel_lat_sigma_mps=svy, arel_long_sigma_mps2=nan, arel_lat_sigma_mps2=nan,
                          orientation_sigma_rad=nan, meas_state=meas.astype(np.int64),
                          prob_of_exist=self.prob_of_exist.copy(), arel_long_mps2=nan, arel_lat_mps2=nan,
                          obj_class=self.obj_class.copy(), orientation_rad=nan, length_m=self.length_m.copy(),
                          width_m=self.width_m.copy(), actor_index=np.full(n, -1, dtype=np.int64))


@dataclass
class _Track:
    fid: int
    t_s: float
    pos: np.ndarray
    vel: np.ndarray
    cov: np.ndarray
    members: dict = field(default_factory=dict)       # sensor ID -> radar object ID, last cycle
    misses: int = 0
    rcs: float = math.nan
    obj_class: int = -1
    length: float = math.nan
    width: float = math.nan
    sensors: int = 0
    var_v: np.ndarray = field(default_factory=lambda: np.full(2, MIN_SIGMA_MPS ** 2))
    dyn_prop: int = 0
    prob_of_exist: int = 0
    updates: int = 0
    heading: float = 0.0
    heading_sigma: float = math.pi


def _pair_heading(h1: np.ndarray, s1: np.ndarray, h2: np.ndarray, s2: np.ndarray) -> np.ndarray:
    """The orientation of each pair of the sets (A,) and (B,) as the better-known of the two: (A, B). At the detection
    and signal levels a radar's orientation of a near car comes from a short track's velocity and may be tens of
    degrees off (and says so in its σ); the extent term and the cap across follow the orientation that is known."""
    return np.where(s1[:, None] < s2[None, :], h1[:, None], h2[None, :])


class ObjectFusion:
    """Track-to-track fusion of several radars' object lists (see the module docstring).

    Parameters
    ----------
    mounts : dict sensor ID -> SensorMount
        Where each radar sits; objects of a sensor not in it are refused (counted in ``unknown_sensor``).
    """

    def __init__(self, mounts: dict[int, SensorMount]) -> None:
        if not mounts:
            raise ValueError("mounts: value {} is not allowed; expected at least one sensor ID with its mount")
        self.mounts = dict(mounts)
        self.tracks: list[_Track] = []
        self._together: dict[tuple[int, int], int] = {}     # fused ID pairs: rounds in a row close enough to merge
        self._next_id = 0
        self._last_t: float | None = None
        #: what was not fused: lists of a sensor not in ``mounts``, lists too old or with a time that is not a
        #: number, objects with a non-finite position, velocity or σ, and restarts after a gap in time
        self.unknown_sensor = self.stale_lists = self.bad_objects = self.restarts = self.bad_times = 0

    def _new_id(self) -> int:
        used = {t.fid for t in self.tracks}
        while self._next_id in used:
            self._next_id = (self._next_id + 1) % 65536
        fid = self._next_id
        self._next_id = (self._next_id + 1) % 65536
        return fid

    def step(self, t_s: float, cycles: dict[int, tuple[float, ObjectList]]) -> FusedObjects:
        """Fuse the latest object list of each sensor, ``{sensor ID: (its cycle's time, objects)}``, at ``t_s``.

        Nothing that cannot be fused is fused: a fusion time that is not a finite number is refused (the tracks
        stay as they were); one more than :data:`MAX_GAP_S` after the last, or before it, restarts the fused tracks
        (new IDs); a sensor's list more than :data:`MAX_GAP_S` from ``t_s``, and objects with a non-finite
        position, velocity or σ, are left out. Each is counted (``bad_times``, ``restarts``, ``stale_lists``,
        ``bad_objects``).
        """
        if not (isinstance(t_s, (int, float, np.floating)) and math.isfinite(t_s)):
            self.bad_times += 1
            return self._output(self._last_t if self._last_t is not None else 0.0)
        if self._last_t is not None and not 0.0 <= t_s - self._last_t <= MAX_GAP_S:
            self.restarts += bool(self.tracks)
            self.tracks, self._together = [], {}
        self._last_t = float(t_s)
        parts = []
        for sid, (ts, objects) in sorted(cycles.items()):
            if sid not in self.mounts:
                self.unknown_sensor += 1
                continue
            if not (math.isfinite(ts) and abs(t_s - ts) <= MAX_GAP_S):
                self.stale_lists += 1
                continue
            so = to_vehicle(sid, ts, objects, self.mounts[sid])
            ok = so.finite()
            self.bad_objects += int(np.count_nonzero(~ok))
            parts.append(so if ok.all() else so.take(ok))
        # every track predicted to the fusion time
        for tr in self.tracks:
            dt = t_s - tr.t_s
            tr.pos = tr.pos + tr.vel * dt
            tr.t_s = t_s
        assigned: dict[int, list[tuple[SensorObjects, int]]] = {id(t): [] for t in self.tracks}
        new_tracks: list[tuple[SensorObjects, int]] = []
        for so in parts:
            self._associate(so, t_s, assigned, new_tracks)
        kept = []
        for tr in self.tracks:
            got = assigned[id(tr)]
            if got:
                self._update(tr, got, t_s)
                kept.append(tr)
            else:
                tr.misses += 1
                tr.members = {}
                tr.sensors = 0
                if tr.misses <= COAST_CYCLES:
                    kept.append(tr)
        # objects no track took: grouped into new tracks (the same object seen by two sensors in its first cycle
        # becomes one track: each new one is offered to the tracks started before it in this step)
        started: list[_Track] = []
        members: dict[int, list[tuple[SensorObjects, int]]] = {}
        for so, i in new_tracks:
            best = None
            open_ = [tr for tr in started if so.sensor_id not in tr.members]
            if open_:
                d = _track_distances(open_, so, np.array([i]), (so.pos[i] + so.vel[i] * (t_s - so.t_s))[None])[:, 0]
                k = int(np.argmin(d))
                best = open_[k] if d[k] < GATE_CHI2 else None
            if best is None:
                best = _Track(self._new_id(), t_s, so.pos[i].copy(), so.vel[i].copy(), so.cov[i].copy())
                self.tracks.append(best)      # reserves the ID
                started.append(best)
                members[id(best)] = []
            members[id(best)].append((so, i))
            self._update(best, members[id(best)], t_s)
        self.tracks = kept + started
        got = {id(t): assigned.get(id(t)) or members.get(id(t)) or [] for t in self.tracks}
        self._merge(got, t_s)
        return self._output(t_s)

    def _merge(self, got: dict, t_s: float) -> None:
        """Two fused tracks fed by different sensors that stay together are one object: merged into the older.

        A radar's object keeps its fused track (continuity), so an object that two radars first reported apart —
        each its own track — would stay two. Tracks seen this round by disjoint sets of sensors whose positions
        lie within the association's gate (:data:`GATE_CHI2` with the extent term, :data:`MAX_ACROSS_M` across) and
        whose velocities agree (:func:`_same_velocity`) for :data:`MERGE_ROUNDS` rounds in a row are merged: what
        one round would have associated is merged once it has held for three. Two vehicles
        side by side in adjacent lanes (3.5 m apart) are not, and one radar seeing both keeps them apart."""
        live = [t for t in self.tracks if t.misses == 0 and got.get(id(t))]
        close: set[tuple[int, int]] = set()
        if len(live) > 1:
            pos, cov = np.array([t.pos for t in live]), np.array([t.cov for t in live])
            vel, (h, hs) = np.array([t.vel for t in live]), _track_headings(live)
            seen = np.array([t.sensors for t in live])                 # the sensors' bit field of each
            near = ((_distances(pos, cov, pos, cov, _pair_heading(h, hs, h, hs)) < GATE_CHI2)
                    & _same_velocity(vel, np.array([t.var_v for t in live]))
                    & ((seen[:, None] & seen[None, :]) == 0))
            for i, j in zip(*np.nonzero(np.triu(near, 1))):
                a, b = live[i], live[j]
                close.add((min(a.fid, b.fid), max(a.fid, b.fid)))
        self._together = {pair: self._together.get(pair, 0) + 1 for pair in close}
        gone: set[int] = set()
        by_fid = {t.fid: t for t in self.tracks}
        for (fa, fb), n in sorted(self._together.items()):
            if n < MERGE_ROUNDS or fa in gone or fb in gone:
                continue
            older, younger = by_fid[fa], by_fid[fb]
            if older.updates < younger.updates:
                older, younger = younger, older
            self._update(older, got[id(older)] + got[id(younger)], t_s)
            older.updates -= 1                 # one round, not two
            got[id(older)] = got[id(older)] + got[id(younger)]
            gone.add(younger.fid)
        if gone:
            self.tracks = [t for t in self.tracks if t.fid not in gone]
            self._together = {k: v for k, v in self._together.items() if not (set(k) & gone)}

    def _associate(self, so: SensorObjects, t_s: float, assigned: dict, new_tracks: list) -> None:
        n = len(so.ids)
        if n == 0:
            return
        # a fused track takes at most one object of each sensor
        free = [tr for tr in self.tracks if all(p.sensor_id != so.sensor_id for p, _ in assigned[id(tr)])]
        pos = so.pos + so.vel * (t_s - so.t_s)
        taken = np.zeros(n, dtype=bool)
        # 1. continuity: the same radar object keeps its fused track while it stays within the gate
        pairs = []
        for tr in free:
            hit = np.flatnonzero(so.ids == tr.members.get(so.sensor_id, -1))
            if hit.size:
                pairs.append((tr, int(hit[0])))
        if pairs:
            idx = np.array([j for _, j in pairs])
            d = np.diagonal(_track_distances([tr for tr, _ in pairs], so, idx, pos[idx]))
            for (tr, j), dj in zip(pairs, d):
                if dj < GATE_CHI2 and not taken[j]:
                    assigned[id(tr)].append((so, j))
                    taken[j] = True
                    free.remove(tr)
        # 2. the rest by a global assignment on the Mahalanobis distance
        rest = np.flatnonzero(~taken)
        if rest.size and free:
            cost = _track_distances(free, so, rest, pos[rest])
            import scipy.optimize  # imported when first needed: a faster start
            big = 1e6
            rows, cols = scipy.optimize.linear_sum_assignment(np.where(cost < GATE_CHI2, cost, big))
            for r, c in zip(rows, cols):
                if cost[r, c] < GATE_CHI2:
                    assigned[id(free[r])].append((so, int(rest[c])))
                    taken[rest[c]] = True
        for i in np.flatnonzero(~taken):
            new_tracks.append((so, int(i)))

    @staticmethod
    def _update(tr: _Track, got: list[tuple[SensorObjects, int]], t_s: float) -> None:
        """The information-weighted mean of the track's objects this cycle (each predicted to ``t_s``)."""
        info = np.zeros((2, 2))
        acc = np.zeros(2)
        w_v = np.zeros(2)
        acc_v = np.zeros(2)
        for so, i in got:
            p = so.pos[i] + so.vel[i] * (t_s - so.t_s)
            inv = np.linalg.inv(so.cov[i] + 1e-9 * np.eye(2))
            info += inv
            acc += inv @ p
            wv = 1.0 / so.var_v[i]
            w_v += wv
            acc_v += wv * so.vel[i]
        tr.cov = np.linalg.inv(info)
        tr.pos = tr.cov @ acc
        tr.vel = acc_v / w_v
        tr.var_v = 1.0 / w_v
        tr.updates += 1
        tr.t_s = t_s
        tr.misses = 0
        tr.members = {so.sensor_id: int(so.ids[i]) for so, i in got}
        tr.sensors = sum(1 << so.sensor_id for so, _ in got)
        strongest = max(got, key=lambda g: g[0].rcs[g[1]] if np.isfinite(g[0].rcs[g[1]]) else -np.inf)
        so, i = strongest
        tr.rcs, tr.obj_class, tr.dyn_prop = float(so.rcs[i]), int(so.obj_class[i]), int(so.dyn_prop[i])
        tr.prob_of_exist = int(max(g[0].prob_of_exist[g[1]] for g in got))
        # the orientation of the member that knows it best (the strongest reflection need not be the best track)
        so_h, i_h = min(got, key=lambda g: g[0].heading_sigma[g[1]])
        tr.heading, tr.heading_sigma = float(so_h.heading[i_h]), float(so_h.heading_sigma[i_h])
        tr.length = float(np.nanmax([g[0].length[g[1]] for g in got]))
        tr.width = float(np.nanmax([g[0].width[g[1]] for g in got]))

    def _output(self, t_s: float) -> FusedObjects:
        ts = sorted(self.tracks, key=lambda t: t.fid)
        arr = lambda f, dt=np.float64: np.array([f(t) for t in ts], dtype=dt)   # noqa: E731
        return FusedObjects(
            t_s, arr(lambda t: t.fid, np.int64), arr(lambda t: t.pos[0]), arr(lambda t: t.pos[1]),
            arr(lambda t: t.vel[0]), arr(lambda t: t.vel[1]), arr(lambda t: math.sqrt(t.cov[0, 0])),
            arr(lambda t: math.sqrt(t.cov[1, 1])), arr(lambda t: t.rcs), arr(lambda t: t.obj_class, np.int64),
            arr(lambda t: t.length), arr(lambda t: t.width), arr(lambda t: t.sensors, np.int64),
            arr(lambda t: t.misses > 0, bool), arr(lambda t: math.sqrt(t.var_v[0])),
            arr(lambda t: math.sqrt(t.var_v[1])), arr(lambda t: t.dyn_prop, np.int64),
            arr(lambda t: t.prob_of_exist, np.int64), arr(lambda t: t.updates == 1 and t.misses == 0, bool),
            [dict(t.members) for t in ts])


def _same_velocity(vel: np.ndarray, var_v: np.ndarray) -> np.ndarray:
    """(A, A): velocities (A, 2) that agree within :data:`MERGE_SPEED_MPS`, or within their own σ (``var_v`` (A, 2),
    the χ² of the difference under :data:`GATE_CHI2`): a radar that tracks a car beside it from its glinting
    reflections knows its lateral speed only to a few m/s, and says so."""
    dv = vel[:, None, :] - vel[None, :, :]
    return (np.hypot(dv[..., 0], dv[..., 1]) < MERGE_SPEED_MPS) | (
        (dv * dv / (var_v[:, None, :] + var_v[None, :, :])).sum(axis=-1) < GATE_CHI2)


def _track_headings(tracks: list) -> tuple[np.ndarray, np.ndarray]:
    return np.array([t.heading for t in tracks]), np.array([t.heading_sigma for t in tracks])


def _track_distances(tracks: list, so: SensorObjects, idx: np.ndarray, pos: np.ndarray) -> np.ndarray:
    """:func:`_distances` of fused tracks (A) to a sensor's objects ``idx`` (B) at positions ``pos`` (B, 2) (predicted
    to the fusion time), each pair judged by the better-known orientation: (A, B)."""
    return _distances(np.array([t.pos for t in tracks]), np.array([t.cov for t in tracks]), pos, so.cov[idx],
                      _pair_heading(*_track_headings(tracks), so.heading[idx], so.heading_sigma[idx]))


def _distances(p1: np.ndarray, c1: np.ndarray, p2: np.ndarray, c2: np.ndarray, heading: np.ndarray,
               max_across_m: float = MAX_ACROSS_M) -> np.ndarray:
    """The Mahalanobis distance² of every pair, with both covariances and the extent term (reference points spread
    along and across the object's heading): positions (A, 2) and (B, 2), covariances (A, 2, 2) and (B, 2, 2), each
    pair's orientation (A, B) (:func:`_pair_heading`) → (A, B); ∞ where a pair lies more than ``max_across_m`` apart
    across it."""
    d = p2[None, :, :] - p1[:, None, :]                                          # (A, B, 2)
    c, s = np.cos(heading), np.sin(heading)                                     # (A, B)
    across = np.abs(-s * d[..., 0] + c * d[..., 1])
    el, et = EXTENT_SIGMA_LONG_M ** 2, EXTENT_SIGMA_LAT_M ** 2
    ext = np.stack([np.stack([el * c * c + et * s * s, (el - et) * c * s], axis=-1),
                    np.stack([(el - et) * c * s, el * s * s + et * c * c], axis=-1)], axis=-2)    # (A, B, 2, 2)
    m = c1[:, None] + c2[None, :] + ext                                         # (A, B, 2, 2)
    a, b, cc, dd = m[..., 0, 0], m[..., 0, 1], m[..., 1, 0], m[..., 1, 1]
    det = a * dd - b * cc
    x, y = d[..., 0], d[..., 1]
    with np.errstate(divide="ignore", invalid="ignore"):
        q = (dd * x * x - (b + cc) * x * y + a * y * y) / det                  # dᵀ M⁻¹ d for a 2×2 M
    return np.where((across > max_across_m) | ~np.isfinite(q) | (det <= 0), np.inf, q)


class FusingConsumer(can.Listener):
    """Every radar's frames from one bus: one :class:`~radarnode.consumer.assembler.CycleAssembler` per sensor ID,
    and the fused object list each time every sensor has delivered a new object list.

    A sensor that delivers its next list before the others theirs (one is missing or slow) closes the round
    with what is there: a silent radar delays the fused list by one of the others' cycles, never stops it. A
    radar that sends cluster lists counts for its round (on time) but only object lists are fused
    (``cluster_lists`` counts what was left out).
    ``drain()`` returns ``(sensor_cycles, fused)`` pairs: the round's cycles by sensor ID and the fused list.
    """

    def __init__(self, mounts: dict[int, SensorMount], database=None) -> None:
        from radarnode.consumer.assembler import CycleAssembler
        self.fusion = ObjectFusion(mounts)
        self.assemblers = {sid: CycleAssembler(sid, database) for sid in sorted(mounts)}
        self._round: dict = {}
        self._out: list = []
        self.cluster_lists = 0          # cycles of a radar in cluster mode: they close a round, they are not fused
        self.bus_errors = 0             # frames the bus could not read (a notifier's on_error)
        #: at :meth:`stop`, each sensor's cycle in progress is left unfinished (``consume --fuse --count``, Ctrl-C)
        self.leave_unfinished = False

    def on_error(self, exc: Exception) -> None:
        """A frame the bus could not read (a notifier calls this): counted in ``bus_errors``, warned once, and the
        notifier goes on receiving (without it python-can's notifier raised in its thread, and ``consume --fuse``
        received nothing more: an independent tester's finding)."""
        self.bus_errors += 1
        if self.bus_errors == 1:
            logger.warning("bus error in the fusing consumer: %s (further ones are counted in bus_errors)", exc)

    def counters(self) -> dict[str, int]:
        """What the fusion left out or restarted, and the bus errors, by name."""
        f = self.fusion
        return {"stale_lists": f.stale_lists, "restarts": f.restarts, "bad_times": f.bad_times,
                "bad_objects": f.bad_objects, "unknown_sensor": f.unknown_sensor, "cluster_lists": self.cluster_lists,
                "bus_errors": self.bus_errors}

    def on_message_received(self, msg: can.Message) -> None:
        for a in self.assemblers.values():
            a.on_message_received(msg)
        self._collect()

    def stop(self) -> None:
        """End of listening (a notifier calls this): each sensor's consumer stops as a lone one does
        (:meth:`CycleAssembler.stop`: its cycle in progress closed, or counted in ``unfinished_cycles`` where
        :attr:`leave_unfinished` is set), and the cycles that closes join the rounds. (The cycles in progress were
        counted nowhere before: an independent tester's finding.)"""
        for a in self.assemblers.values():
            a.leave_unfinished = self.leave_unfinished
            a.stop()
        self._collect()

    def feed(self, messages):
        for m in messages:
            self.on_message_received(m)
            yield from self.drain()

    def _collect(self) -> None:
        for sid, a in self.assemblers.items():
            for cyc in a.drain():
                if sid in self._round:
                    self._close()
                self._round[sid] = cyc
                if len(self._round) == len(self.assemblers):
                    self._close()

    def _close(self) -> None:
        if not self._round:
            return
        from radarnode.consumer.assembler import ObjectCycle
        t = self._round_time([c.timestamp for c in self._round.values()])
        if t is None:                    # no list with a time: nothing to fuse at, nothing sent (bad_times)
            self.fusion.bad_times += 1
            self._round = {}
            return
        # a radar that sends its cluster list closes the round on time, but only object lists are fused
        self.cluster_lists += sum(not isinstance(c, ObjectCycle) for c in self._round.values())
        fused = self.fusion.step(t, {sid: (c.timestamp, c.objects) for sid, c in self._round.items()
                                     if isinstance(c, ObjectCycle)})
        self._out.append((dict(self._round), fused))
        self._round = {}

    def _round_time(self, times: list) -> float | None:
        """The round's fusion time: the latest list time that most of the round's lists lie within
        :data:`MAX_GAP_S` of, and of those, one that continues from the last fusion (without a restart) first; None
        where no time is a finite number. (The latest time of all let one list with a bad time — a header stamped
        3 s late — leave the others out as stale and restart every fused track: an independent tester's
        finding.)"""
        finite = [float(t) for t in times if isinstance(t, (int, float, np.floating)) and math.isfinite(t)]
        if not finite:
            return None
        last = self.fusion._last_t

        def rank(c: float) -> tuple:
            support = sum(abs(t - c) <= MAX_GAP_S for t in finite)
            return support, last is None or 0.0 <= c - last <= MAX_GAP_S, c

        return max(finite, key=rank)

    def flush(self) -> None:
        """Fuse what the last, incomplete round holds (at the end of a log)."""
        self._close()

    def drain(self) -> list:
        out, self._out = self._out, []
        return out

    @property
    def stats(self) -> dict:
        """Each sensor's consumer counters."""
        return {sid: a.stats for sid, a in self.assemblers.items()}
__all__ = ["FusedObjects", "FusingConsumer", "ObjectFusion", "SensorObjects", "to_vehicle"]
