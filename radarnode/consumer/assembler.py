"""Assemble ARS 408-21 object and cluster cycles from a stream of CAN frames.

:class:`CycleAssembler` is a ``can.Listener``: put it on a ``can.Notifier`` (or
feed it frames from a log reader). It decodes every frame with the cantools
database, checks the DLC, joins the frames of a cycle by object ID, and emits
one :class:`ObjectCycle` or :class:`ClusterCycle` per well-formed cycle. A
cycle is well-formed when the header's count of general frames arrived and
every other group (quality, extended) arrived for exactly the same IDs or not
at all. Everything else is counted in :class:`ConsumerStats` and skipped; the
listener never raises on bad traffic.

A cycle ends when all groups the radar announced in RadarState (0x201) are
complete, when the next header arrives, or on :meth:`CycleAssembler.flush`
(end of a log, or a time-out).
"""

from __future__ import annotations

import dataclasses
import logging
import queue
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import can
import cantools
import numpy as np

from radarnode.perception.types import ClusterList, ObjectList
from radarnode.wire import ars408 as P
from radarnode.perception.boundaries import Boundary
from radarnode.wire.dbc import load_database, load_own_database
from radarnode.wire.e2e import E2EChecker

logger = logging.getLogger(__name__)


@dataclass
class ObjectCycle:
    """One decoded object list."""

    meas_counter: int
    timestamp: float
    objects: ObjectList
    has_quality: bool
    has_extended: bool


@dataclass
class ClusterCycle:
    """One decoded cluster list."""

    meas_counter: int
    timestamp: float
    clusters: ClusterList
    has_quality: bool


@dataclass
class ConsumerStats:
    """Counters of everything the consumer saw, accepted and dropped."""

    frames: int = 0
    cycles: int = 0                 # well-formed cycles emitted
    object_cycles: int = 0
    cluster_cycles: int = 0
    incomplete_cycles: int = 0      # started but not well-formed: dropped
    lost_cycles: int = 0            # gaps in MeasCounter
    counter_resets: int = 0         # MeasCounter went backwards: sensor restart
    unknown_id: int = 0
    wrong_dlc: int = 0
    decode_errors: int = 0
    orphan_frames: int = 0          # list frames with no header before them
    duplicate_frames: int = 0       # exact repeats, ignored
    conflicting_frames: int = 0     # same object ID twice with different content
    unexpected_ids: int = 0         # quality/extended for an ID the general group lacks
    extra_frames: int = 0           # more general frames than the header announced
    status_frames: int = 0          # RadarState, VersionID, ego motion, configuration
    errors_frames: int = 0          # CAN error and remote frames
    boundary_frames: int = 0        # radarnode's road-boundary frames accepted
    ecu_frames: int = 0             # AccStatus / FcwStatus frames accepted
    e2e_errors: int = 0             # own frames with a wrong E2E CRC: dropped
    e2e_repeated: int = 0           # own frames whose alive counter did not advance: dropped

    def dropped(self) -> int:
        return (self.unknown_id + self.wrong_dlc + self.decode_errors + self.orphan_frames
                + self.conflicting_frames + self.unexpected_ids + self.extra_frames + self.errors_frames
                + self.e2e_errors + self.e2e_repeated)

    def as_dict(self) -> dict[str, int]:
        return dataclasses.asdict(self)


class _Pending:
    """Frames of one cycle that is being assembled."""

    def __init__(self, kind: str, expected: int, meas_counter: int, timestamp: float, n_near: int = 0) -> None:
        self.kind = kind
        self.expected = expected
        self.meas_counter = meas_counter
        self.timestamp = timestamp
        self.n_near = n_near
        self.groups: dict[int, dict[int, tuple[bytes, dict]]] = {}
        self.order: list[int] = []
        self.bad = False


class CycleAssembler(can.Listener):
    """Decode and assemble radar cycles; a ``can.Listener``.

    Parameters
    ----------
    sensor_id : int
        Which radar to listen to (its IDs are shifted by 0x10 × sensor_id).
    database : cantools Database, optional
        Defaults to the project's ARS 408 DBC.
    on_cycle : callable, optional
        Called with every emitted cycle (from the notifier's thread).
    maxsize : int
        Size of the internal queue read by :meth:`get`; when full, the oldest
        cycle is discarded (and counted) so a slow reader never stalls the bus.
    """

    def __init__(self, sensor_id: int = 0, database: cantools.database.can.Database | None = None,
                 on_cycle: Callable[[ObjectCycle | ClusterCycle], None] | None = None, maxsize: int = 10_000) -> None:
        self.db = database if database is not None else load_database()
        self.sensor_id = sensor_id
        self.on_cycle = on_cycle
        self.stats = ConsumerStats()
        self.radar_state: dict | None = None
        self.version: dict | None = None
        self.ego_speed_mps: float | None = None
        self.ego_yaw_rate_dps: float | None = None
        self.queue_overflow = 0
        self._queue: queue.Queue = queue.Queue(maxsize=maxsize)
        self._pending: _Pending | None = None
        self._last_counter: dict[str, int] = {}
        self._stride: dict[str, int] = {}
        self._messages = {m.frame_id: m for m in self.db.messages}
        self._own = {m.frame_id: m for m in load_own_database().messages}
        self.e2e = E2EChecker()
        #: latest decoded road boundaries: {"left": Boundary, "right": Boundary}
        self.road_boundaries: dict[str, Boundary] = {}
        #: latest decoded AccStatus / FcwStatus signals, by message name
        self.ecu_status: dict[str, dict] = {}

    # --- can.Listener ---------------------------------------------------------
    def on_message_received(self, msg: can.Message) -> None:
        try:
            self._handle(msg)
        except Exception:  # noqa: BLE001 - a listener must survive any frame
            self.stats.decode_errors += 1
            logger.debug("frame %r could not be handled", msg, exc_info=True)

    def on_error(self, exc: Exception) -> None:
        logger.warning("bus error in consumer: %s", exc)

    def stop(self) -> None:
        self.flush()

    # --- reading cycles ----------------------------------------------------------
    def get(self, timeout: float | None = None) -> ObjectCycle | ClusterCycle | None:
        """The next assembled cycle, or None after ``timeout`` seconds."""
        try:
            return self._queue.get(timeout=timeout)
        except queue.Empty:
            return None

    def drain(self) -> list[ObjectCycle | ClusterCycle]:
        """Every cycle assembled so far."""
        out = []
        while True:
            try:
                out.append(self._queue.get_nowait())
            except queue.Empty:
                return out

    def feed(self, messages) -> Iterator[ObjectCycle | ClusterCycle]:
        """Assemble cycles from an iterable of frames (e.g. a log reader); flushes at the end."""
        for msg in messages:
            self.on_message_received(msg)
            yield from self.drain()
        self.flush()
        yield from self.drain()

    def flush(self) -> None:
        """Close the cycle being assembled (end of data or time-out)."""
        if self._pending is not None:
            self._finish(self._pending)
            self._pending = None

    # --- internals ----------------------------------------------------------------
    def _handle(self, msg: can.Message) -> None:
        self.stats.frames += 1
        if msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id:
            self.stats.errors_frames += 1
            return
        base = msg.arbitration_id - 0x10 * self.sensor_id if msg.arbitration_id != P.COLL_DET_RELAY else 0x008
        message = self._messages.get(base)
        if message is None:
            if base in self._own:
                self._own_frame(base, msg)
                return
            self.stats.unknown_id += 1
            return
        data = bytes(msg.data)
        if len(data) != message.length:
            self.stats.wrong_dlc += 1
            return
        try:
            values = message.decode(data, decode_choices=False, scaling=True)
        except (cantools.database.DecodeError, ValueError, KeyError):
            self.stats.decode_errors += 1
            return
        if base in (P.OBJ_STATUS, P.CLUSTER_STATUS):
            self._header(base, values, msg.timestamp)
        elif base in (P.OBJ_GENERAL, P.OBJ_QUALITY, P.OBJ_EXTENDED, P.CLUSTER_GENERAL, P.CLUSTER_QUALITY):
            self._list_frame(base, values, data)
        else:
            self.stats.status_frames += 1
            if base == P.RADAR_STATE:
                self.radar_state = values
            elif base == P.VERSION_ID:
                self.version = values
            elif base == P.SPEED_INFO:
                sign = -1.0 if int(values["RadarDevice_SpeedDirection"]) == 2 else 1.0
                self.ego_speed_mps = sign * values["RadarDevice_Speed"]
            elif base == P.YAW_RATE_INFO:
                self.ego_yaw_rate_dps = values["RadarDevice_YawRate"]

    def _own_frame(self, base: int, msg: can.Message) -> None:
        """radarnode's own E2E-protected messages: checked, then decoded."""
        message = self._own[base]
        data = bytes(msg.data)
        if len(data) != message.length:
            self.stats.wrong_dlc += 1
            return
        before = (self.e2e.stats.crc_errors, self.e2e.stats.repeated)
        if not self.e2e.check(msg.arbitration_id, data):
            self.stats.e2e_errors += self.e2e.stats.crc_errors - before[0]
            self.stats.e2e_repeated += self.e2e.stats.repeated - before[1]
            return
        v = message.decode(data, decode_choices=False)
        if base not in (P.ROAD_BOUNDARY_LEFT, P.ROAD_BOUNDARY_RIGHT):
            # the consumer ECU's AccStatus / FcwStatus, as another ECU on the bus would read them
            self.ecu_status[message.name] = v
            self.stats.ecu_frames += 1
            return
        prefix, side = ("RBL", "left") if base == P.ROAD_BOUNDARY_LEFT else ("RBR", "right")
        self.road_boundaries[side] = Boundary(
            bool(v[f"{prefix}_Valid"]), v[f"{prefix}_LatOffset"], np.radians(v[f"{prefix}_Heading"]),
            v[f"{prefix}_Curvature"], v[f"{prefix}_RangeStart"], v[f"{prefix}_RangeEnd"],
            v[f"{prefix}_Confidence"] / 7.0)
        self.stats.boundary_frames += 1

    def _header(self, base: int, values: dict, timestamp: float) -> None:
        self.flush()
        if base == P.OBJ_STATUS:
            kind, n, n_near, counter = "obj", int(values["Obj_NofObjects"]), 0, int(values["Obj_MeasCounter"])
        else:
            n_near = int(values["Cluster_NofClustersNear"])
            kind, counter = "cl", int(values["Cluster_MeasCounter"])
            n = n_near + int(values["Cluster_NofClustersFar"])
        last = self._last_counter.get(kind)
        if last is not None:
            gap = (counter - last) & 0xFFFF
            if gap == 0 or gap > 0x8000:
                self.stats.counter_resets += 1
            else:
                # The real ARS 408 advances MeasCounter by 2 per object cycle (near and far scans);
                # radarnode by 1. The stride is the smallest step seen.
                stride = self._stride.get(kind)
                if stride is None or gap < stride:
                    self._stride[kind] = stride = gap
                if gap > stride:
                    self.stats.lost_cycles += gap // stride - 1
        self._last_counter[kind] = counter
        self._pending = _Pending(kind, n, counter, timestamp, n_near)
        self._maybe_complete()

    def _list_frame(self, base: int, values: dict, data: bytes) -> None:
        pending = self._pending
        kind = "obj" if base in (P.OBJ_GENERAL, P.OBJ_QUALITY, P.OBJ_EXTENDED) else "cl"
        if pending is None or pending.kind != kind:
            self.stats.orphan_frames += 1
            return
        oid = int(values["Obj_ID" if kind == "obj" else "Cluster_ID"])
        group = pending.groups.setdefault(base, {})
        if oid in group:
            if group[oid][0] == data:
                self.stats.duplicate_frames += 1
            else:
                self.stats.conflicting_frames += 1
                pending.bad = True
            return
        general = P.OBJ_GENERAL if kind == "obj" else P.CLUSTER_GENERAL
        if base == general:
            if len(group) >= pending.expected:
                self.stats.extra_frames += 1
                pending.bad = True
                return
            pending.order.append(oid)
        elif oid not in pending.groups.get(general, {}):
            self.stats.unexpected_ids += 1
            pending.bad = True
            return
        group[oid] = (data, values)
        self._maybe_complete()

    def _expected_groups(self, kind: str) -> list[int] | None:
        """Groups the radar announced in RadarState, or None when no RadarState was seen yet."""
        st = self.radar_state
        if st is None:
            return None
        quality = bool(st["RadarState_SendQualityCfg"])
        if kind == "obj":
            return ([P.OBJ_GENERAL] + ([P.OBJ_QUALITY] if quality else [])
                    + ([P.OBJ_EXTENDED] if st["RadarState_SendExtInfoCfg"] else []))
        return [P.CLUSTER_GENERAL] + ([P.CLUSTER_QUALITY] if quality else [])

    def _maybe_complete(self) -> None:
        p = self._pending
        expected = self._expected_groups(p.kind)
        if expected is None or p.bad:
            return
        if all(len(p.groups.get(g, {})) == p.expected for g in expected):
            self._finish(p)
            self._pending = None

    def _finish(self, p: _Pending) -> None:
        general_id = P.OBJ_GENERAL if p.kind == "obj" else P.CLUSTER_GENERAL
        general = p.groups.get(general_id, {})
        others = [g for g in p.groups if g != general_id]
        complete = (not p.bad and len(general) == p.expected
                    and all(set(p.groups[g]) == set(general) for g in others))
        if not complete:
            self.stats.incomplete_cycles += 1
            return
        rows = [general[i][1] for i in p.order]
        if p.kind == "obj":
            q = p.groups.get(P.OBJ_QUALITY)
            e = p.groups.get(P.OBJ_EXTENDED)
            ol = P.objects_from_signals(rows, [q[i][1] if q else None for i in p.order],
                                        [e[i][1] if e else None for i in p.order])
            cycle: ObjectCycle | ClusterCycle = ObjectCycle(p.meas_counter, p.timestamp, ol, q is not None,
                                                            e is not None)
            self.stats.object_cycles += 1
        else:
            q = p.groups.get(P.CLUSTER_QUALITY)
            cl = P.clusters_from_signals(rows, [q[i][1] if q else None for i in p.order], p.n_near)
            cycle = ClusterCycle(p.meas_counter, p.timestamp, cl, q is not None)
            self.stats.cluster_cycles += 1
        self.stats.cycles += 1
        if self._queue.full():
            self._queue.get_nowait()
            self.queue_overflow += 1
        self._queue.put_nowait(cycle)
        if self.on_cycle is not None:
            self.on_cycle(cycle)


def summarize_objects(cycles: list[ObjectCycle]) -> dict[int, dict[str, float]]:
    """Per object ID: cycles seen, median distances, class (mode), for reports and tests."""
    per_id: dict[int, dict[str, list]] = {}
    for c in cycles:
        ol = c.objects
        for k in range(len(ol)):
            d = per_id.setdefault(int(ol.id[k]), {"long": [], "lat": [], "cls": []})
            d["long"].append(ol.dist_long_m[k])
            d["lat"].append(ol.dist_lat_m[k])
            d["cls"].append(int(ol.obj_class[k]))
    out = {}
    for oid, d in per_id.items():
        classes = np.array(d["cls"])
        out[oid] = {"cycles": len(d["long"]), "dist_long_m": float(np.median(d["long"])),
                    "dist_lat_m": float(np.median(d["lat"])),
                    "obj_class": int(np.bincount(classes[classes >= 0]).argmax()) if (classes >= 0).any() else -1}
    return out
