"""Assemble ARS 408-21 object and cluster cycles from a stream of CAN frames.

:class:`CycleAssembler` is a ``can.Listener``: put it on a ``can.Notifier`` (or
feed it frames from a log reader). It decodes every frame with the cantools
database, checks the DLC, joins the frames of a cycle by object ID, and emits
one :class:`ObjectCycle` or :class:`ClusterCycle` per well-formed cycle. A
cycle is well-formed when the header's count of general frames arrived and
every other group (quality, extended, collision warning) arrived for exactly
the same IDs or not at all. Everything else is counted in :class:`ConsumerStats` and skipped; the
listener never raises on bad traffic. A cycle is delivered whole or counted as
dropped (``incomplete_cycles``), never in part.

Where a cycle ends is decided from the cycles' own frames, never from one
RadarState 0x201 (a stray or forged one must not strip groups):

* a cycle is complete as soon as the header's count of frames arrived in every
  group of the expected *layout*; the layout is learned from the cycles
  themselves: every group seen in any of the last ``LAYOUT_MEMORY`` complete
  cycles (0x60B, 0x60C, 0x60D until the first cycle is seen). A group the node
  stopped sending drops out after two cycles without it (below);
* Obj_4_Warning 0x60E is a group like the others (one frame per object, after
  0x60D) but is not expected before a cycle showed it: it comes only with
  collision detection, and CollDetState 0x408 with Active set (sent before the
  header every cycle while it is on) adds it to the layout for
  ``LAYOUT_MEMORY`` headers, as RadarState does for the groups below;
* RadarState's SendQuality/SendExtInfo bits can only *add* groups to the
  layout, for ``LAYOUT_MEMORY`` headers (so a configuration change that adds a
  group is waited for); bits that are off are ignored;
* a header whose MeasCounter does not move on from the last accepted one, or
  jumps more than ``MAX_JUMP_STRIDES`` strides ahead (a stale, replayed,
  forged or corrupted header, or the first of a restarted sensor or after a
  long gap) cuts nothing: it is held beside the cycle in progress with the
  frames that fit its own cycle and not the one in progress; a next header that
  continues its count — at least ``CONTINUE_MIN_PERIODS`` of the sensor's period
  after it, where the times can tell — shows a restart (``counter_resets``) or a
  gap (``lost_cycles``; ``quiet_cycles`` after RadarState said OutputType none and
  then the output back) and its cycle is delivered if whole; one that continues the
  old count drops it (``stray_headers``). Up to ``HELD_HEADERS`` are held at
  once (an old header replayed between a restarted sensor's cycles must not
  push its first header out); an earlier one, continued, must have taken frames;
* a header that announced objects and got no frame before the next one,
  which continues the count from before it and not from it, was stray (a
  forged header with a plausible MeasCounter just before the sensor's own):
  taken out, it steals nothing. (A forged *empty* header of that kind is
  whole at once, and is delivered as an empty cycle: a known limit;)
* a cycle that ends whole in itself but without a group of the expected
  layout (a stray header cut it before its last groups) is held: the late
  frames of that group make it whole and it is delivered; if the next cycle has
  a group it lacked of those the last complete cycles had, it was cut short and
  is dropped; if the next cycle lacks them too, the sensor stopped sending them
  and both are delivered (the layout forgets them at once); one short only of
  groups announced (RadarState, CollDetState) is delivered. Empty cycles that
  end meanwhile wait behind it (``LAYOUT_MEMORY`` at most);
* otherwise the cycle ends at the next header of its kind (an object and a
  cluster cycle are assembled side by side, so a stray header of the other
  kind cuts nothing), after ``cycle_timeout_s`` of
  silence on the cycle (checked by :meth:`CycleAssembler.get` and
  :meth:`CycleAssembler.expire`, in wall-clock time of arrival), or on
  :meth:`CycleAssembler.flush` (end of a log).

Frames on the list's IDs that are not the sensor's (random or forged content with the right DLC) cost no cycle
they can be told apart in, and never enter a delivered one:

* a general frame beyond the header's count is kept beside the others; at the cycle's end the later groups, which
  name the sensor's objects, tell which are its if they all name the same ones, as many as the count (the others are
  counted in ``extra_frames``); otherwise (no later group, or one holding a frame that is not the sensor's too) the
  cycle is dropped;
* a later group's frame for an object the general group lacks waits aside to the cycle's end: it takes its place if
  its general frame came meanwhile (a gateway's reordering), else it is counted in ``orphan_frames``;
* a later group's frame out of the general group's order (the sensor sends every group in one order) holds the cycle
  to its end instead of delivering it the moment its layout is complete, so that a second frame for the same place
  is seen as a conflict and the cycle dropped (a forged frame for the last place of the last group, sent before the
  group's own frames, was delivered with the cycle); a frame for the same place after a cycle delivered whole in
  order is counted in ``conflicting_frames`` (the cycle went out with the first: a known limit, for a forged frame
  that imitates the sensor's last frame in its place). Two frames for one place in an open cycle drop it: which is
  the sensor's cannot be told.

A frame of a group that arrives before the groups the sensor sends ahead of it (0x60B, 0x60C, 0x60D, 0x60E,
each whole before the next) are whole in the cycle in progress waits aside: the next header, of higher CAN
priority, overtakes the last frames of a cycle, which must not take the next cycle's places. The cycle's own
frame, in order, takes the place; at the cycle's end a frame aside fills a place still empty (a cycle reordered)
or is counted in ``orphan_frames``. The places a cycle that ended short lacked after its last frame (its *tail*, in the
sensor's order) are filled by the first frames on their IDs after the next header that fit them in that order (one
sender sends one ID in order): a cycle whole up to its tail is held and completed by them; a dropped cycle's are
orphans, and a late copy of one is a duplicate, never a frame aside for the next cycle. A frame for another object
of either cycle first on such an ID ends the tail, and drops the held cycle; so does the next cycle's end.

A general group repeated whole, in the sensor's order, after a later group of the cycle began is the next cycle's,
its header lost (a standing sensor repeats its frames): the cycle is sealed, and a frame that fills one of its places
after that drops it; so does a general frame that fills a place right after ``RERUN_FILL`` of the general group's
frames repeated so, from its first (the next cycle's general frame for the place this cycle lost).

Frames of a group that arrive after their cycle was delivered are counted as
``late_frames`` and put their group back into the layout at once.

IDs are looked up in this consumer's ID plan (:mod:`radarnode.wire.ids`): the
ARS 408 IDs of its sensor, its sensor's own messages, the ECU's; frames of the
other seven sensors are counted in ``other_sensor_frames``, never decoded as
this sensor's. The sensor's configuration replies (FilterState 0x203/0x204,
CollDetState 0x408, CollDetRegionState 0x402, CollDetRelayCtrl 0x008) are
counted in ``config_state_frames`` (0x008, which no sensor shifts, only while
this sensor's RadarState does not say CtrlRelay off: another sensor's then)
and kept as last decoded (:attr:`CycleAssembler.filter_state`, :attr:`CycleAssembler.coll_det_regions`, …);
they never cut a cycle.
"""

from __future__ import annotations

import collections
import dataclasses
import logging
import math
import queue
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import can
import cantools
import numpy as np

from radarnode.perception.boundaries import Boundary
from radarnode.perception.types import ClusterList, ObjectList
from radarnode.wire import ars408 as P
from radarnode.wire import ids
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
    has_warning: bool = False
    #: Obj_4_Warning's Obj_CollDetRegionBitfield per object (bit r: it warns in region r), when the cycle had 0x60E
    collision_regions: np.ndarray | None = None


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
    timed_out_cycles: int = 0       # closed after cycle_timeout_s of silence (delivered or dropped)
    unfinished_cycles: int = 0      # in progress when the listener was stopped on purpose: neither sent nor dropped
    lost_cycles: int = 0            # gaps in MeasCounter
    quiet_cycles: int = 0           # gaps in MeasCounter after RadarState said OutputType none: not sent, not lost
    counter_resets: int = 0         # MeasCounter went backwards: sensor restart
    unknown_id: int = 0
    other_sensor_frames: int = 0    # frames of another sensor ID (its ARS 408 or own messages): not ours
    wrong_dlc: int = 0
    padded_frames: int = 0          # ego motion 0x300/0x301 with a longer DLC (padded): taken, their first bytes read
    decode_errors: int = 0
    orphan_frames: int = 0          # list frames with no header before them
    late_frames: int = 0            # list frames of a group that came after their cycle was delivered
    duplicate_frames: int = 0       # exact repeats, ignored
    stray_headers: int = 0          # headers that did not advance MeasCounter and that no cycle followed: ignored
    conflicting_frames: int = 0     # same object ID twice with different content
    unexpected_ids: int = 0         # quality/extended for an ID the general group lacks
    extra_frames: int = 0           # more general frames than the header announced
    status_frames: int = 0          # RadarState, VersionID, ego motion, configuration
    config_state_frames: int = 0    # the sensor's replies: FilterState 0x203/0x204, CollDet 0x408/0x402, relay 0x008
    errors_frames: int = 0          # CAN error and remote frames
    fd_frames: int = 0              # CAN FD frames: a classical CAN ECU never takes them
    bus_errors: int = 0             # frames the bus could not read (reported through on_error)
    boundary_frames: int = 0        # radarnode's road-boundary frames accepted
    ecu_frames: int = 0             # AccStatus / FcwStatus frames accepted
    e2e_errors: int = 0             # own frames with a wrong E2E CRC: dropped
    e2e_repeated: int = 0           # own frames whose alive counter did not advance: dropped
    e2e_wrong_sequence: int = 0     # own frames whose counter jumped back or too far ahead (late, replayed): dropped

    def dropped(self) -> int:
        return (self.unknown_id + self.wrong_dlc + self.decode_errors + self.orphan_frames + self.late_frames
                + self.stray_headers + self.conflicting_frames + self.unexpected_ids + self.extra_frames
                + self.errors_frames + self.fd_frames + self.e2e_errors + self.e2e_repeated + self.e2e_wrong_sequence
                + self.bus_errors)

    def as_dict(self) -> dict[str, int]:
        return dataclasses.asdict(self)


LAYOUT_MEMORY = 3            # cycles: how long a group stays expected after it was last seen or announced
CYCLE_TIMEOUT_S = 0.1        # silence after which a waiting cycle is closed (longer than a 72-ms cycle)
GROUPS = {"obj": (P.OBJ_GENERAL, P.OBJ_QUALITY, P.OBJ_EXTENDED, P.OBJ_WARNING),
          "cl": (P.CLUSTER_GENERAL, P.CLUSTER_QUALITY)}
# the layout expected before any cycle was seen: Obj_4_Warning only comes with collision detection, which
# CollDetState 0x408 announces, so it is not waited for by default
INITIAL_GROUPS = {"obj": (P.OBJ_GENERAL, P.OBJ_QUALITY, P.OBJ_EXTENDED), "cl": GROUPS["cl"]}
CONFIG_STATE = (P.FILTER_STATE_HEADER, P.FILTER_STATE_CFG, P.COLL_DET_STATE, P.COLL_DET_REGION_STATE,
                P.COLL_DET_RELAY)
GENERAL = {"obj": P.OBJ_GENERAL, "cl": P.CLUSTER_GENERAL}
HEADERS = {P.OBJ_STATUS: "obj", P.CLUSTER_STATUS: "cl"}
LIST_KIND = {g: kind for kind, groups in GROUPS.items() for g in groups}
#: a header whose MeasCounter jumps further ahead than this many strides (about 4.6 s of a 72-ms sensor) is held
#: until the next header continues its count, as one that does not advance is: a forged or corrupted header
#: must not cut the cycle in progress
MAX_JUMP_STRIDES = 64
#: headers held at once, the newest first in line for frames: a restarted sensor's next header still finds its
#: first one when a replayed old header came between them
HELD_HEADERS = 4
#: MeasCounters of the headers taken (per kind) and of cycles counted lost, remembered: about 5 minutes of a 72-ms
#: sensor, so that a switch of OutputType that long leaves no gap counted lost
COUNTER_MEMORY = 4096


def _advances(counter: int, last: int) -> bool:
    """True when MeasCounter ``counter`` follows ``last`` (16 bits, wrapping): forward by less than half the range."""
    gap = (counter - last) & 0xFFFF
    return 0 < gap <= 0x8000


def _within_reach(counter: int, last: int, stride: int) -> bool:
    """True when MeasCounter ``counter`` follows ``last`` by at most MAX_JUMP_STRIDES strides."""
    return _advances(counter, last) and (counter - last) & 0xFFFF <= MAX_JUMP_STRIDES * stride


#: a general frame that fills a place after this many of the general group's frames repeated in order, from its
#: first, after a later group began, is the next cycle's (its header lost): the cycle is dropped. One repeat is not
#: enough by arrival order alone: a cycle reordered within itself with one duplicate shows that too (the fuzz tests)
RERUN_FILL = 2
#: … and after this many where each repeat came a good part of a period after its first copy (RERUN_MIN_PERIODS)
RERUN_FILL_TIMED = 1

#: a repeat of a general frame that came at least this fraction of the sensor's cycle period after the first copy
#: (both times and the period known) is the next cycle's as much as its place in arrival order says: the next cycle's
#: frames come a period later. A run of such repeats needs only RERUN_FILL_TIMED; any other, RERUN_FILL
RERUN_MIN_PERIODS = 0.5

#: header-to-header periods remembered, per kind; their median is the sensor's cycle period
PERIOD_MEMORY = 5

#: a held header (a jump in MeasCounter) is continued only by a header at least this fraction of the sensor's cycle
#: period after it, where the times can tell (the period known, the last headers' times all apart): a restarted
#: sensor's next header comes a period after its first; two forged or random headers sent back to back, which
#: continue each other's count by chance, are not a restart (an independent tester's finding: such a pair went out
#: as two empty cycles, or took the sensor's next cycle under its count, and put up to 65,534 cycles in lost_cycles)
CONTINUE_MIN_PERIODS = 0.5
#: … but a run of this many headers, each continuing the last by its count and each too soon by the times, shows the
#: times cannot tell after all (a log stamped finely, then coarsely or not at all, after a restart: nothing was
#: delivered for the rest of it, an independent tester's finding): the period is forgotten, and the count decides
#: until it is learned again. Five forged headers back to back, counting on, pass for a restart (a known limit)
TOO_SOON_RUN = 4


class _Pending:
    """Frames of one cycle that is being assembled."""

    def __init__(self, kind: str, expected: int, meas_counter: int, timestamp: float, header: bytes,
                 n_near: int = 0) -> None:
        self.kind = kind
        self.expected = expected
        self.meas_counter = meas_counter
        self.timestamp = timestamp
        self.header = header
        self.n_near = n_near
        self.groups: dict[int, dict[int, tuple[bytes, dict]]] = {}
        # frames of a group that came before the group sent ahead of it was whole (a frame of an earlier cycle that
        # the next header overtook, or this cycle's own, reordered): not counted until the cycle ends (_promote)
        self.provisional: dict[int, dict[int, tuple[bytes, dict]]] = {}
        self.order: list[int] = []
        self.bad = False
        # a later group's frame came out of the general group's order (a gateway's reordering, or a frame that is not
        # the sensor's): the cycle is not delivered the moment its layout is complete, but at its end, so that a
        # frame for the same place after it is still seen as a conflict
        self.reordered = False
        # more general frames than the header's count (one that is not the sensor's among them): which are the
        # sensor's is read from the later groups (:meth:`CycleAssembler._resolve_overflow`)
        self.overflow = False
        self.early = False             # delivered as soon as the layout was complete
        # the general group repeated whole, in the sensor's order, after a later group began: the sensor's next
        # cycle, its header lost, repeating a standing scene's frames. A place of an earlier group filled after that
        # is the next cycle's, and drops this one. ``rerun``: how many of the general group's frames, in order,
        # repeated so far since a later group began (any other frame taken breaks the run)
        self.sealed = False
        self.rerun = 0
        self.rerun_timed = False      # each repeat of that run came a good part of a period after its first copy
        self.general_times: dict[int, float] = {}    # object ID → time its general frame was taken
        self.short = False             # held at its end short of a few frames of its later groups (overtaken)
        # places of later groups (group, object) whose first frame a held header's cycle took, as it held the object
        # too: a second frame for one of them drops both cycles (two senders)
        self.contested: set[tuple[int, int]] = set()
        # at its end, short of a general frame: the order of all its objects as a later group sent them (None: as
        # its general group's), and the places that came of the objects only later groups named (group, object)
        self.listed: list[int] | None = None
        self.unlisted_came: set[tuple[int, int]] = set()
        self.announced: frozenset[int] = frozenset()   # groups announced before its header
        # (last MeasCounter, stride, lost_cycles, last header's time, periods) before this header was taken
        self.before: tuple | None = None
        self.arrival = time.monotonic()


def _has_frames(p: _Pending) -> bool:
    """Whether cycle ``p`` took any list frame (in its groups or aside, out of order)."""
    return bool(p.groups) or any(p.provisional.values())


def _whole(p: _Pending) -> bool:
    """Whether every group cycle ``p`` holds frames of holds one for each object of its general group (a held cycle
    whose missing group came in part is not)."""
    general = set(p.groups.get(GENERAL[p.kind], {}))
    return len(general) == p.expected and all(set(group) == general for group in p.groups.values() if group)


def _present(p: _Pending) -> set[int]:
    """The groups cycle ``p`` holds frames of."""
    return {g for g, group in p.groups.items() if group}


class CycleAssembler(can.Listener):
    """Decode and assemble radar cycles; a ``can.Listener``.

    Parameters
    ----------
    sensor_id : int
        Which radar to listen to (0..7): its ARS 408 IDs are shifted by 0x10 × sensor_id, its own
        messages sit at 0x680 + 8 × sensor_id + slot (:mod:`radarnode.wire.ids`).
    database : cantools Database, optional
        Defaults to the project's ARS 408 DBC.
    on_cycle : callable, optional
        Called with every emitted cycle (from the notifier's thread).
    maxsize : int
        Size of the internal queue read by :meth:`get`; when full, the oldest
        cycle is discarded (and counted) so a slow reader never stalls the bus.
    cycle_timeout_s : float
        A cycle still waiting for groups is closed after this much silence on it (wall clock).
    """

    def __init__(self, sensor_id: int = 0, database: cantools.database.can.Database | None = None,
                 on_cycle: Callable[[ObjectCycle | ClusterCycle], None] | None = None, maxsize: int = 10_000,
                 cycle_timeout_s: float = CYCLE_TIMEOUT_S) -> None:
        if isinstance(sensor_id, bool) or not isinstance(sensor_id, int) or not 0 <= sensor_id < ids.NUM_SENSORS:
            raise ValueError(f"sensor_id: value {sensor_id!r} is not allowed; expected an integer 0..7")
        if not (isinstance(cycle_timeout_s, (int, float)) and 0.0 < cycle_timeout_s < float("inf")):
            raise ValueError(f"cycle_timeout_s: value {cycle_timeout_s!r} is not allowed; expected a finite "
                             "number of seconds > 0")
        self.db = database if database is not None else load_database()
        self.sensor_id = sensor_id
        self.on_cycle = on_cycle
        self.cycle_timeout_s = float(cycle_timeout_s)
        self.stats = ConsumerStats()
        self.radar_state: dict | None = None
        self.version: dict | None = None
        self.ego_speed_mps: float | None = None
        self.ego_yaw_rate_dps: float | None = None
        #: SpeedInformation frames decoded so far: a reader tells a new ego speed from the last one by it
        #: (:meth:`radarnode.consumer.ecu.Ecu.set_ego`'s ``frames``)
        self.ego_frames = 0
        self.yaw_frames = 0                   # … and YawRateInformation frames
        self.queue_overflow = 0
        self._queue: queue.Queue = queue.Queue(maxsize=maxsize)
        self._lock = threading.RLock()
        # one cycle being assembled per list kind: a header of the other kind (a switch of OutputType, or a stray
        # frame that looks like one) does not cut the cycle in progress
        self._pending: dict[str, _Pending] = {}
        self._last_done: dict[str, _Pending] = {}
        self._last_counter: dict[str, int] = {}
        # a header that did not advance MeasCounter, held until frames show whether the sensor restarted
        self._suspects: dict[str, _Pending] = {}
        self._two_senders_warned = False
        self._older_suspects: dict[str, list[_Pending]] = {}    # held before the newest one (HELD_HEADERS in all)
        # a cycle that ended whole in itself but without a group the layout expects: a stray header cut it before
        # its last groups (they follow, and it is delivered whole) or the sensor stopped sending the group (the next
        # cycle lacks it too, and both are delivered); never delivered without either
        self._held: dict[str, _Pending] = {}
        self._behind: dict[str, list[_Pending]] = {}    # empty cycles that ended while one was held: after it
        # the places the last cycle that ended short lacked after its last frame, in the sensor's order, by group: the
        # frames the next header overtook come first on their IDs (one sender sends one ID in order), so the first
        # frames of a group after it that fill those places in that order are its own, and the first that does not
        # ends them
        self._tails: dict[str, dict[int, collections.deque]] = {}
        # the frames those tails took (place → payload), of the last two cycles that ended short: a copy of one that
        # comes again out of its cycle's order (a bus or gateway repeat) is a duplicate, never a frame aside that
        # fills the next cycle's place (one such copy sent every later cycle out with its predecessor's frame)
        self._late: dict[str, collections.deque] = {k: collections.deque(maxlen=2) for k in GROUPS}
        self._tail_objects: dict[str, frozenset] = {}     # the objects of the cycle a tail is of
        # a frame that fills a tail's next place but came at the next cycle's own turn on its ID (the groups that
        # cycle sends ahead of it whole, and a place of its own for that object): the held cycle's late frame, or the
        # next cycle's own and the held one's lost. Undecided until the next frame on its ID (:meth:`_settles`) or
        # the next cycle's end: (the cycle in progress then, group, object ID, payload, signals)
        self._undecided: dict[str, tuple] = {}
        self._stride: dict[str, int] = {}
        # the sensor's cycle period per kind: the time between headers one stride apart (the last few), and the time
        # of the last header taken; a repeat of a general frame is the next cycle's only where it came a good part of
        # a period after the first copy (:meth:`_timed_rerun`)
        self._periods: dict[str, collections.deque] = {k: collections.deque(maxlen=PERIOD_MEMORY) for k in GROUPS}
        # … and whether those headers' times were apart at all (a logger that keeps whole seconds stamps most
        # consecutive headers alike: its times cannot tell a header sent back to back from one a period later)
        self._apart: dict[str, collections.deque] = {k: collections.deque(maxlen=PERIOD_MEMORY) for k in GROUPS}
        self._too_soon: dict[str, int] = {k: 0 for k in GROUPS}     # held headers in a row continued too soon
        self._header_time: dict[str, float] = {}
        self._stamp = float("nan")      # the time of the frame being handled
        #: at :meth:`stop`, leave the cycles in progress unfinished rather than close them (the listener stopped on
        #: purpose, before the sensor's cycle ended)
        self.leave_unfinished = False
        # what RadarState said of the output since the last header taken: 0 nothing, 1 OutputType none, 2 none and
        # then objects or clusters again (the sensor announces its output back before the list resumes)
        self._silence = 0
        # the MeasCounters of the headers taken, per kind: the sensor counts its cycles once for both lists, so a
        # gap in one kind's count that the other kind's cycles fill (a switch of OutputType) lost nothing
        self._counters: dict[str, collections.deque] = {k: collections.deque(maxlen=COUNTER_MEMORY) for k in GROUPS}
        self._lost: collections.deque = collections.deque(maxlen=COUNTER_MEMORY)   # counters counted lost
        # layout learned from complete cycles (group sets), and groups RadarState announced (headers left)
        self._seen_layouts: dict[str, collections.deque] = {k: collections.deque(maxlen=LAYOUT_MEMORY)
                                                            for k in GROUPS}
        self._announced: dict[str, dict[int, int]] = {k: {} for k in GROUPS}
        self._messages = {m.frame_id: m for m in self.db.messages}
        self._own = {m.frame_id: m for m in load_own_database().messages}
        self._routes = self._id_plan(sensor_id)
        self.e2e = E2EChecker()
        #: latest decoded road boundaries: {"left": Boundary, "right": Boundary}
        self.road_boundaries: dict[str, Boundary] = {}
        #: latest decoded AccStatus / FcwStatus signals, by message name
        self.ecu_status: dict[str, dict] = {}
        #: the sensor's configuration replies, as last decoded: FilterState_Header, FilterState_Cfg by
        #: (FilterState_Type, FilterState_Index), CollDetState, CollDetRegionState by region ID, CollDetRelayCtrl
        self.filter_header: dict | None = None
        self.filter_state: dict[tuple[int, int], dict] = {}
        self.coll_det_state: dict | None = None
        self.coll_det_regions: dict[int, dict] = {}
        self.relay: dict | None = None

    def _id_plan(self, sensor_id: int) -> dict[int, tuple[str, int]]:
        """CAN ID -> ('ars', base ID) | ('own', template ID) | ('other', CAN ID) for this consumer's sensor."""
        routes: dict[int, tuple[str, int]] = {}
        for other in range(ids.NUM_SENSORS):
            if other == sensor_id:
                continue
            for base in self._messages:
                routes[P.shifted(base, other)] = ("other", base)
            for tmpl in self._own:
                if ids.is_sensor_message(tmpl):
                    routes[ids.own_id(tmpl, other)] = ("other", tmpl)
        for base in self._messages:                  # the unshifted 0x008 belongs to every sensor
            routes[P.shifted(base, sensor_id)] = ("ars", base)
        for tmpl in self._own:
            routes[ids.own_id(tmpl, sensor_id)] = ("own", tmpl)
        return routes

    # --- can.Listener ---------------------------------------------------------
    def on_message_received(self, msg: can.Message) -> None:
        with self._lock:
            try:
                self._handle(msg)
            except Exception:  # noqa: BLE001 - a listener must survive any frame
                self.stats.decode_errors += 1
                logger.debug("frame %r could not be handled", msg, exc_info=True)

    def on_error(self, exc: Exception) -> None:
        """A frame the bus could not read (a notifier calls this): counted in ``bus_errors``, warned once, and
        the notifier goes on receiving."""
        self.stats.bus_errors += 1
        if self.stats.bus_errors == 1:
            logger.warning("bus error in consumer: %s (further ones are counted in bus_errors)", exc)

    def stop(self) -> None:
        """End of listening (a notifier calls this): the cycles in progress are closed (:meth:`flush`), as at the end
        of data — or, where :attr:`leave_unfinished` was set (``consume --count`` reached, or Ctrl-C: the listener
        stopped, not the sensor), left unfinished and counted in ``unfinished_cycles``, not in ``incomplete_cycles``
        (the cycle after the last one asked for was counted as incomplete: an independent tester's finding)."""
        if self.leave_unfinished:
            with self._lock:
                waiting = [p for p in self._pending.values() if not p.early] + list(self._held.values()) \
                    + [p for behind in self._behind.values() for p in behind]   # (empty cycles after a held one)
                self.stats.unfinished_cycles += len(waiting)
                self._pending.clear()
                self._held.clear()
                self._behind.clear()
        self.flush()

    # --- reading cycles ----------------------------------------------------------
    def get(self, timeout: float | None = None) -> ObjectCycle | ClusterCycle | None:
        """The next assembled cycle, or None after ``timeout`` seconds.

        While waiting, a cycle that has been silent for ``cycle_timeout_s`` is closed (:meth:`expire`).
        """
        deadline = None if timeout is None else time.monotonic() + max(timeout, 0.0)
        while True:
            step = self.cycle_timeout_s / 2
            if deadline is not None:
                step = min(step, max(deadline - time.monotonic(), 0.0))
            try:
                return self._queue.get(timeout=step) if step > 0 else self._queue.get_nowait()
            except queue.Empty:
                self.expire()
                try:
                    return self._queue.get_nowait()
                except queue.Empty:
                    if deadline is not None and time.monotonic() >= deadline:
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

    def flush(self, kind: str | None = None) -> None:
        """Close the cycle being assembled (of ``kind``, 'obj' or 'cl'; default both, the older first) — end of
        data or time-out."""
        with self._lock:
            waiting = [p for k, p in self._pending.items() if kind is None or k == kind]
            for p in sorted(waiting, key=lambda p: p.arrival):
                del self._pending[p.kind]
                self._finish(p)
            if kind is None:            # end of data: a header still held was continued by none
                for suspect in [*self._suspects.values(), *(o for lst in self._older_suspects.values() for o in lst)]:
                    self._drop_suspect(suspect)
                self._suspects.clear()
                self._older_suspects.clear()
                for held_kind in list(self._held):      # and a cycle short of a group was followed by none
                    self._drop_held(held_kind)

    def expire(self, now: float | None = None) -> bool:
        """Close the cycle being assembled when nothing arrived for it for ``cycle_timeout_s``.

        ``now`` is ``time.monotonic()`` by default. Returns True when a cycle was closed.
        """
        with self._lock:
            now = time.monotonic() if now is None else now
            silent = [p.kind for p in self._pending.values() if now - p.arrival > self.cycle_timeout_s]
            for kind in silent:
                self.stats.timed_out_cycles += 1
                self.flush(kind)
            for kind in [k for k, h in self._held.items() if k not in self._pending
                         and now - h.arrival > 2.0 * self.cycle_timeout_s]:
                self._drop_held(kind)           # no cycle followed the one short of a group: it stays unproven
            return bool(silent)

    # --- internals ----------------------------------------------------------------
    def _handle(self, msg: can.Message) -> None:
        self.stats.frames += 1
        if msg.is_error_frame or msg.is_remote_frame or msg.is_extended_id:
            self.stats.errors_frames += 1
            return
        if msg.is_fd:                   # (a 64-byte FD frame on 0x300 was read as a padded speed)
            self.stats.fd_frames += 1
            return
        route = self._routes.get(msg.arbitration_id)
        if route is None:
            self.stats.unknown_id += 1
            return
        kind, base = route
        if kind == "other":
            self.stats.other_sensor_frames += 1
            return
        if kind == "own":
            self._own_frame(base, msg)
            return
        message = self._messages[base]
        data = bytes(msg.data)
        if len(data) > message.length and base in (P.SPEED_INFO, P.YAW_RATE_INFO):
            # the vehicle's 2-byte frames padded to 8 by a gateway or bench tool: their signals are in the first
            # bytes (as the radar node takes them); the radar's own frames keep their exact length
            self.stats.padded_frames += 1
            data = data[:message.length]
        if len(data) != message.length:
            self.stats.wrong_dlc += 1
            return
        try:
            values = message.decode(data, decode_choices=False, scaling=True)
        except (cantools.database.DecodeError, ValueError, KeyError):
            self.stats.decode_errors += 1
            return
        self._stamp = float(msg.timestamp)
        if base in HEADERS:
            self._header(base, values, data, msg.timestamp)
        elif base in LIST_KIND:
            self._list_frame(base, values, data)
        elif base in CONFIG_STATE:
            self._config_state(base, values)
        else:
            self.stats.status_frames += 1
            if base == P.RADAR_STATE:
                self.radar_state = values
                self._announce(values)
            elif base == P.VERSION_ID:
                self.version = values
            elif base == P.SPEED_INFO:
                sign = -1.0 if int(values["RadarDevice_SpeedDirection"]) == 2 else 1.0
                self.ego_speed_mps = sign * values["RadarDevice_Speed"]
                self.ego_frames += 1
            elif base == P.YAW_RATE_INFO:
                self.ego_yaw_rate_dps = values["RadarDevice_YawRate"]
                self.yaw_frames += 1

    def _own_frame(self, template: int, msg: can.Message) -> None:
        """radarnode's own E2E-protected messages: checked with this sensor's Data ID, then decoded."""
        message = self._own[template]
        data = bytes(msg.data)
        if len(data) != message.length:
            self.stats.wrong_dlc += 1
            return
        e2e = self.e2e.stats
        before = (e2e.crc_errors, e2e.repeated, e2e.wrong_sequence)
        if not self.e2e.check(ids.e2e_key(template, self.sensor_id), data):
            self.stats.e2e_errors += e2e.crc_errors - before[0]
            self.stats.e2e_repeated += e2e.repeated - before[1]
            self.stats.e2e_wrong_sequence += e2e.wrong_sequence - before[2]
            return
        v = message.decode(data, decode_choices=False)
        if template not in (ids.ROAD_BOUNDARY_LEFT, ids.ROAD_BOUNDARY_RIGHT):
            # the consumer ECU's AccStatus / FcwStatus, as another ECU on the bus would read them
            self.ecu_status[message.name] = v
            self.stats.ecu_frames += 1
            return
        prefix, side = ("RBL", "left") if template == ids.ROAD_BOUNDARY_LEFT else ("RBR", "right")
        self.road_boundaries[side] = Boundary(
            bool(v[f"{prefix}_Valid"]), v[f"{prefix}_LatOffset"], np.radians(v[f"{prefix}_Heading"]),
            v[f"{prefix}_Curvature"], v[f"{prefix}_RangeStart"], v[f"{prefix}_RangeEnd"],
            v[f"{prefix}_Confidence"] / 7.0)
        self.stats.boundary_frames += 1

    def _config_state(self, base: int, v: dict) -> None:
        """The sensor's answers to configuration: kept as last decoded. A FilterState_Header starts a new
        filter table (the FilterState_Cfg frames that follow it fill it), a CollDetState a new region table (the
        CollDetRegionState frames that follow it); CollDetState with Active set announces
        Obj_4_Warning, like RadarState announces groups (it can only add a group, never remove one)."""
        if base == P.COLL_DET_RELAY and self.radar_state is not None \
                and not int(self.radar_state["RadarState_CtrlRelayCfg"]):
            # 0x008 is not shifted by SensorID (as on the ARS 408): this sensor's RadarState says it does not
            # drive its relay, so the frame is another sensor's
            self.stats.other_sensor_frames += 1
            return
        self.stats.config_state_frames += 1
        if base == P.FILTER_STATE_HEADER:
            self.filter_header = v
            self.filter_state = {}
        elif base == P.FILTER_STATE_CFG:
            self.filter_state[(int(v["FilterState_Type"]), int(v["FilterState_Index"]))] = v
        elif base == P.COLL_DET_STATE:
            if int(v["CollDetState_Active"]):
                self._announced["obj"][P.OBJ_WARNING] = LAYOUT_MEMORY
            self.coll_det_state = v
            self.coll_det_regions = {}
        elif base == P.COLL_DET_REGION_STATE:
            self.coll_det_regions[int(v["CollDetRegState_RegionID"])] = v
        else:
            self.relay = v

    def _announce(self, state: dict) -> None:
        """RadarState can add groups to the expected layout (for LAYOUT_MEMORY headers), never remove any; one that
        says OutputType none, and then objects or clusters again, marks the gap in the count up to the next header as the
        sensor's silence, not loss."""
        if int(state["RadarState_OutputTypeCfg"]) == 0:
            self._silence = 1
        elif self._silence == 1:
            self._silence = 2
        if int(state["RadarState_SendQualityCfg"]):
            self._announced["obj"][P.OBJ_QUALITY] = LAYOUT_MEMORY
            self._announced["cl"][P.CLUSTER_QUALITY] = LAYOUT_MEMORY
        if int(state["RadarState_SendExtInfoCfg"]):
            self._announced["obj"][P.OBJ_EXTENDED] = LAYOUT_MEMORY

    def _learned_groups(self, kind: str) -> set[int]:
        """Groups of the last complete cycles of ``kind`` (before the first: the default layout)."""
        seen = self._seen_layouts[kind]
        return set().union(*seen) if seen else set(INITIAL_GROUPS[kind])

    def expected_groups(self, kind: str) -> set[int]:
        """Groups a cycle of ``kind`` ('obj' or 'cl') must hold before it is delivered without waiting."""
        return self._learned_groups(kind) | {GENERAL[kind]} | set(self._announced[kind])

    def _expected_of(self, p: _Pending) -> set[int]:
        """:meth:`expected_groups` for cycle ``p``: the learned layout and what was announced before its header
        (a cycle that ends after a later announcement — reordered frames wait for its end — is not held for it)."""
        return self._learned_groups(p.kind) | {GENERAL[p.kind]} | set(p.announced)

    def _header(self, base: int, values: dict, data: bytes, timestamp: float) -> None:
        kind = HEADERS[base]
        held_header = self._suspects.get(kind)
        if held_header is not None and held_header.header == data and not _has_frames(held_header):
            # the header held (it came right after another with none of that one's frames yet) comes again, now in
            # its place: the first copy was early (a repeat sent ahead of time), this one is taken
            del self._suspects[kind]
            self.stats.duplicate_frames += 1
        for known in (self._pending.get(kind), self._last_done.get(kind), self._suspects.get(kind)):
            if known is not None and known.header == data:
                self.stats.duplicate_frames += 1     # the same header again: not a new cycle
                return
        if kind == "obj":
            n, n_near, counter = int(values["Obj_NofObjects"]), 0, int(values["Obj_MeasCounter"])
        else:
            n_near = int(values["Cluster_NofClustersNear"])
            counter = int(values["Cluster_MeasCounter"])
            n = n_near + int(values["Cluster_NofClustersFar"])
        header = _Pending(kind, n, counter, timestamp, data, n_near)
        # the groups announced before this header (RadarState, CollDetState: the sensor sends them ahead of the
        # header of the first cycle that has the group): one announced after it is not this cycle's to wait for
        header.announced = frozenset(self._announced[kind])
        self._unseat_frameless_header(kind, counter)
        last = self._last_counter.get(kind)
        suspect = self._suspects.pop(kind, None)
        if last is not None and not self._continues(kind, counter, last):
            # a header that continues the held one by its count but too soon: a run of TOO_SOON_RUN of them says
            # the times cannot tell (the period is forgotten, and the count decides below)
            if suspect is not None and self._continues(kind, counter, suspect.meas_counter) \
                    and not self._continues_held(kind, counter, timestamp, suspect):
                self._too_soon[kind] += 1
                if self._too_soon[kind] >= TOO_SOON_RUN:
                    self._periods[kind].clear()
                    self._apart[kind].clear()
            else:
                self._too_soon[kind] = 0
            # MeasCounter did not move on, or jumped far ahead: a stale, replayed, forged or corrupted header — or
            # the first of a restarted sensor, or the first after a long gap. It is held beside the cycle in
            # progress and cuts nothing; the frames that fit its cycle are kept with it. A next header that
            # continues its count shows a restart or a gap (its cycle is then delivered, if whole); one that
            # continues the old count drops it (stray_headers)
            if suspect is None or not self._continues_held(kind, counter, timestamp, suspect):
                older = self._older_suspects.setdefault(kind, [])
                # (only one that took frames: replayed old headers, one after each cycle, continue each other too)
                match = [o for o in older if _has_frames(o) and self._continues_held(kind, counter, timestamp, o)]
                if not match:
                    # held beside the earlier held headers (a few): a restarted sensor's headers between replayed
                    # old ones are still found continuing each other
                    if suspect is not None:
                        older.append(suspect)
                        while len(older) > HELD_HEADERS - 1:
                            self._drop_suspect(older.pop(0))
                    self._suspects[kind] = header
                    return
                # it continues an earlier held header: that one was the sensor's, the others stray
                chosen = match[-1]
                for other in [o for o in older if o is not chosen] + ([suspect] if suspect is not None else []):
                    self._drop_suspect(other)
                older.clear()
                suspect = chosen
            else:
                for other in self._older_suspects.pop(kind, []):
                    self._drop_suspect(other)
            # a second header continuing the first: the sensor restarted, or cycles were lost in between — or
            # were not sent: OutputType none for more than MAX_JUMP_STRIDES cycles, and the output back (RadarState
            # said both, as below; an independent tester found such a gap of 111 cycles in lost_cycles)
            self._too_soon[kind] = 0
            if _advances(suspect.meas_counter, last) and self._silence == 2:
                stride = self._stride.get(kind, 1)
                self.stats.quiet_cycles += ((suspect.meas_counter - last) & 0xFFFF) // stride - 1
            elif _advances(suspect.meas_counter, last):
                self._count_lost(kind, last, suspect.meas_counter, self._stride.get(kind, 1))
            else:
                self.stats.counter_resets += 1
            self.flush(kind)
            self._last_counter[kind] = last = suspect.meas_counter
            self._header_time[kind] = suspect.timestamp
            self._counters[kind].append(last)
            self._finish(suspect)
        else:
            pending = self._pending.get(kind)
            if pending is not None and pending.expected and not _has_frames(pending):
                # a header that continues the count right after one that announced objects and got none of its
                # frames yet: a forged header put just after the sensor's own would take that cycle's frames under its
                # count — it is held instead, the frames go to the cycle in progress, and the next header decides
                if suspect is not None:
                    self._drop_suspect(suspect)
                self._suspects[kind] = header
                return
            if suspect is not None:
                self._drop_suspect(suspect)
            for other in self._older_suspects.pop(kind, []):
                self._drop_suspect(other)
        held = self._held.get(kind)
        if held is not None and held.short and kind not in self._pending:
            # a cycle held short of frames, and the (empty) cycle after it ended too: their chance is over
            self._drop_held(kind)
        self.flush(kind)
        # what accepting this header changes, kept to undo it should the header prove stray
        header.before = (last, self._stride.get(kind), self.stats.lost_cycles, self._header_time.get(kind),
                         tuple(self._periods[kind]), tuple(self._apart[kind]))
        if last is not None:
            gap = (counter - last) & 0xFFFF
            # The real ARS 408 advances MeasCounter by 2 per object cycle (near and far scans);
            # radarnode by 1. The stride is the smallest step seen.
            stride = self._stride.get(kind)
            if stride is None or gap < stride:
                self._stride[kind] = stride = gap
            elapsed = timestamp - self._header_time.get(kind, float("nan"))
            if gap == stride and math.isfinite(elapsed) and elapsed > 0.0:
                self._periods[kind].append(elapsed)
            if gap == stride and math.isfinite(elapsed):
                self._apart[kind].append(elapsed > 0.0)
            if gap > stride and self._silence == 2:
                # cycles the sensor was told not to send (OutputType none; its RadarState says so at the change, and
                # says objects or clusters again before the list resumes) are counted apart: an independent tester
                # found ten such cycles in lost_cycles. A RadarState that said none with no word of the output back
                # before this header (a stray or forged one, or the sensor's lost) leaves the gap lost: random 0x201
                # frames on the bus put real losses in quiet_cycles (an independent tester's finding)
                self.stats.quiet_cycles += gap // stride - 1
            elif gap > stride:
                self._count_lost(kind, last, counter, stride)
        self._silence = 0
        self._header_time[kind] = timestamp
        self._last_counter[kind] = counter
        self._counters[kind].append(counter)
        announced = self._announced[kind]
        for g in list(announced):
            announced[g] -= 1
            if announced[g] < 0:
                del announced[g]
        self._pending[kind] = header
        self._maybe_complete(kind)

    def _count_lost(self, kind: str, last: int, counter: int, stride: int) -> None:
        """Count the cycles between MeasCounters ``last`` and ``counter`` of ``kind`` as lost, but for those another
        kind's cycles took (the sensor counts its cycles once for object and cluster lists: a switch of OutputType
        leaves a gap in each kind's count) and those counted lost already."""
        known = {c for k, seen in self._counters.items() if k != kind for c in seen} | set(self._lost)
        gap = (counter - last) & 0xFFFF
        lost = [c for c in ((last + j * stride) & 0xFFFF for j in range(1, gap // stride)) if c not in known]
        self.stats.lost_cycles += len(lost)
        self._lost.extend(lost)

    def _unseat_frameless_header(self, kind: str, counter: int) -> None:
        """A header that announced objects and got no frame before this next header, which continues the count
        from before it and not from it: it was stray (a forged or replayed header just before the sensor's own,
        with a plausible MeasCounter) — taken out, its effects on the count undone, so that it steals nothing
        from the cycle that follows."""
        p = self._pending.get(kind)
        if p is None or not p.expected or _has_frames(p) or p.before is None or p.before[0] is None:
            return
        last, stride, lost, header_time, periods, apart = p.before
        if not _within_reach(counter, last, stride or 1) or self._continues(kind, counter, p.meas_counter):
            return
        del self._pending[kind]
        self.stats.stray_headers += 1
        self._last_counter[kind] = last
        self.stats.lost_cycles = lost
        # (nor does its time count towards the sensor's period: a forged header stamped 1000 s back made the period
        # 1000 s, an independent tester's finding)
        if header_time is None:
            self._header_time.pop(kind, None)
        else:
            self._header_time[kind] = header_time
        self._periods[kind].clear()
        self._periods[kind].extend(periods)
        self._apart[kind].clear()
        self._apart[kind].extend(apart)
        if stride is None:
            self._stride.pop(kind, None)
        else:
            self._stride[kind] = stride

    def _continues(self, kind: str, counter: int, last: int) -> bool:
        """Whether MeasCounter ``counter`` continues the count at ``last``: forward, and by at most
        MAX_JUMP_STRIDES strides once the stride is known."""
        # (the stride not known yet: the ARS 408's 2; radarnode counts in 1s)
        return _within_reach(counter, last, self._stride.get(kind, 2))

    def _continues_held(self, kind: str, counter: int, timestamp: float, held: _Pending) -> bool:
        """Whether a header (MeasCounter ``counter``, time ``timestamp``) continues the count of the held header
        ``held`` as the sensor's next one would: by its count (:meth:`_continues`), and, where the times can tell, at
        least CONTINUE_MIN_PERIODS of the sensor's period after it. Times that cannot tell (the period not known yet, a
        time missing, the last headers' times not all apart) leave the count to decide: times only make it stricter."""
        if not self._continues(kind, counter, held.meas_counter):
            return False
        periods, apart = self._periods[kind], self._apart[kind]
        elapsed = timestamp - held.timestamp
        if not periods or not apart or not all(apart) or not math.isfinite(elapsed):
            return True
        return elapsed >= CONTINUE_MIN_PERIODS * float(np.median(periods))

    def _drop_suspect(self, suspect: _Pending) -> None:
        """A held header that no header continued: stray; the frames it collected are counted as orphans."""
        self.stats.stray_headers += 1
        self.stats.orphan_frames += sum(len(group) for group in (*suspect.groups.values(),
                                                                  *suspect.provisional.values()))

    @staticmethod
    def _fits(p: _Pending, base: int, oid: int) -> bool:
        """Whether a list frame has a place in cycle ``p``: a general frame while the header's count is not
        reached, another group's frame for an object of the general group that this group lacks. (The order of
        a cycle's frames does not decide a place: a gateway may reorder them, and a cycle reordered is still whole;
        it is delivered at its end rather than the moment its layout is complete.)"""
        general = p.groups.get(GENERAL[p.kind], {})
        if base == GENERAL[p.kind]:
            return len(general) < p.expected and oid not in general
        return oid in general and oid not in p.groups.get(base, {})

    def _list_frame(self, base: int, values: dict, data: bytes) -> None:
        kind = LIST_KIND[base]
        pending = self._pending.get(kind)
        oid = int(values["Obj_ID" if kind == "obj" else "Cluster_ID"])
        undecided = self._undecided.get(kind)
        if undecided is not None:
            if undecided[0] is not pending:              # (its cycle ended: settled there)
                del self._undecided[kind]
            elif self._settles(kind, undecided, base, oid, data):
                return                                   # (a repeat of it: still undecided)
        held = self._held.get(kind)
        tail = self._tails.get(kind, {}).get(base)
        if tail:
            if tail[0] == oid and held is not None and held.short and pending is not None \
                    and kind not in self._suspects and oid in pending.groups.get(GENERAL[kind], {}) \
                    and oid not in pending.groups.get(base, {}) and not self._ahead_of_order(pending, base):
                # at the next cycle's own turn on this ID: its own frame for that object as much as the held cycle's
                # late one (the next header overtook it, and the next cycle's frames of other IDs too). The next
                # frame on the ID decides (:meth:`_settles`), or the next cycle's end (:meth:`_finish`). Taken at
                # once, one lost last frame sent the held cycle out with the next cycle's frame where the next cycle
                # listed that object first (an independent tester's random faults: 2 of 3,222 cycles)
                self._undecided[kind] = (pending, base, oid, data, values)
                return
            if tail[0] == oid:
                # the next frame the last cycle lacked after its last one, first on its ID: that cycle's, overtaken
                # by the next header (and by the next cycle's frames of other IDs). Completes it where it is held;
                # else it was dropped, and the frame is an orphan (it filled the next cycle's place, which the next
                # header overtook in turn: one loss, and every later cycle went out with its predecessor's frame)
                self._take_late(kind, base, oid, data, values)
                return
            if oid in tail and (pending is None or oid not in pending.groups.get(GENERAL[kind], {})
                                or self._ahead_of_order(pending, base)):
                # a later place of the tail, before the next cycle's turn on this ID (the sensor sends a group's frames
                # only once the groups ahead of it are whole): the held cycle's late frame, the places before it lost.
                # Absorbed, and the held cycle dropped; aside in the next cycle it had filled that cycle's place, whose
                # own frame, overtaken in turn, filled the next one's (one loss among overtaking headers: 69 of 208
                # cycles out wrong, an independent tester's scripts)
                while tail[0] != oid:
                    tail.popleft()
                tail.popleft()
                self._late[kind][-1][(base, oid)] = data
                self._drop_held_short_of(kind, base)
                self.stats.orphan_frames += 1
                return
            # another frame first on that ID, for an object of that cycle or of the one in progress: the next cycle's
            # have begun there, and the rest of the tail never comes (a frame for neither, random content, ends nothing)
            if oid in self._tail_objects.get(kind, ()) or (
                    pending is not None and oid in pending.groups.get(GENERAL[kind], {})):
                tail.clear()
                if self._drop_held_short_of(kind, base):
                    held = None
        if base != GENERAL[kind] and pending is not None and any(
                late.get((base, oid)) == data for late in self._late[kind]) and (
                self._ahead_of_order(pending, base) or oid not in pending.groups.get(GENERAL[kind], {})):
            self.stats.duplicate_frames += 1
            return
        if held is not None and not held.short and base != GENERAL[kind] and self._fits(held, base, oid) \
                and not (pending is not None and self._fits(pending, base, oid)):
            # the next frame of a group that the cycle held back lacks, and no place in the cycle in progress: the
            # late groups of a cycle that a stray header cut; whole, it is delivered
            self._fill_held(held, base, oid, data, values)
            return
        suspect = self._suspects.get(kind)
        if suspect is not None:
            # beside a held header a frame goes with the cycle it fits. A general frame: the one in progress while
            # its count is not reached (a stale header inside a cycle steals nothing), else the held one (a
            # restarted sensor's cycle). Another group's frame: the held one when it holds that object, else the
            # one in progress where it has a place in a group the last complete cycles had (its groups after a
            # stale header; a group only announced is not waited for then). An exact repeat of a frame of the
            # cycle in progress is its duplicate; anything else goes with the held one, and is dropped with it
            # unless a header continues its count
            mine = pending.groups.get(base, {}) if pending is not None else {}
            if not (oid in mine and mine[oid][0] == data):
                general = base == GENERAL[kind]
                place = pending is not None and self._fits(pending, base, oid) and (
                    general or base in self._learned_groups(kind))
                if not place or (not general and self._fits(suspect, base, oid)):
                    if place:
                        # a later group's place in both cycles: the held one takes the frame (a restarted sensor's
                        # cycle, the one in progress cut), but a second frame for the place shows two senders
                        pending.contested.add((base, oid))
                    self._add(suspect, base, oid, data, values)
                    return
                if (base, oid) in pending.contested and not (pending.bad and suspect.bad) \
                        and self._held_frame(suspect, base, oid) != data:
                    # another frame for a place both cycles have, after the held one took the first (a copy of that
                    # one goes to the cycle in progress, as before: a duplicate): two senders of one sensor ID, or the
                    # bus replaying the last cycle (each frame of one beside the other's for the same place), whose
                    # later groups cannot be told apart. Neither cycle is delivered: each took one of the two, and
                    # went out with the other's sizes (an independent tester's finding: 18 of 20 cycles mixed)
                    pending.bad = suspect.bad = True
                    self.stats.conflicting_frames += 1
                    if not self._two_senders_warned:
                        self._two_senders_warned = True
                        logger.warning("sensor %d: two frames for one place of two cycles (another node with this "
                                       "sensor ID, or the bus replaying frames): both cycles dropped, and every such "
                                       "pair after them (counted in conflicting_frames)", self.sensor_id)
        if pending is None:
            self._stray_list_frame(kind, base, oid, data)
            return
        pending.arrival = time.monotonic()
        if self._add(pending, base, oid, data, values):
            self._maybe_complete(kind)

    @staticmethod
    def _held_frame(p: _Pending, base: int, oid: int) -> bytes | None:
        """The data of cycle ``p``'s frame for place (``base``, ``oid``), taken in order or aside; None: none."""
        frame = p.groups.get(base, {}).get(oid) or p.provisional.get(base, {}).get(oid)
        return None if frame is None else frame[0]

    def _settles(self, kind: str, undecided: tuple, base: int, oid: int, data: bytes) -> bool:
        """A list frame while a tail frame is undecided (``_undecided``): settle it where this frame tells, and return
        True where this frame is its repeat (counted; still undecided). On its ID the sensor sends the held cycle's
        late frame before the next cycle's own (one sender sends one ID in order): the same object again there, or
        another that the next cycle lists before it, shows the undecided one was the held cycle's; another object
        that the next cycle lists after it shows it was the next cycle's own (the held cycle's lost). A frame of a
        later group for an object of the next cycle shows that cycle has gone past the ID: its own, unless the frame
        is the held cycle's next late one. Any other frame (random content, an object of neither) tells nothing."""
        pending, u_base, u_oid, u_data, _ = undecided
        order = GROUPS[kind]
        listed = pending.order
        if base == u_base:
            if oid == u_oid and data == u_data:
                self.stats.duplicate_frames += 1
                return True
            if oid == u_oid:
                theirs = True
            elif oid in listed and u_oid in listed:
                theirs = listed.index(oid) < listed.index(u_oid)
            else:
                return False
        elif order.index(base) > order.index(u_base) and oid in listed:
            tail = self._tails.get(kind, {}).get(base)
            theirs = bool(tail) and tail[0] == oid and oid not in pending.groups.get(base, {})
        else:
            return False
        del self._undecided[kind]
        self._settle(kind, undecided, theirs)
        return False

    def _settle(self, kind: str, undecided: tuple, theirs: bool) -> None:
        """An undecided tail frame is the held cycle's late frame (``theirs``: it completes it), or the next cycle's own
        (the held cycle lost its frame: the tail ends, the held cycle is dropped, and the cycle in progress takes the
        frame as it would have; one that has ended takes it into its place)."""
        pending, base, oid, data, values = undecided
        tail = self._tails.get(kind, {}).get(base)
        if theirs:
            self._take_late(kind, base, oid, data, values)
            return
        if tail:
            tail.clear()
        self._drop_held_short_of(kind, base)
        if self._pending.get(kind) is pending:
            self._list_frame(base, values, data)
        else:
            self._add(pending, base, oid, data, values)

    def _take_late(self, kind: str, base: int, oid: int, data: bytes, values: dict) -> None:
        """The next place of the tail of group ``base`` filled by its late frame: recorded (a late copy of it is then a
        duplicate) and put into the cycle held short, whose it is; an orphan where that cycle was dropped."""
        tail = self._tails.get(kind, {}).get(base)
        if tail and tail[0] == oid:
            tail.popleft()
        if self._late[kind]:
            self._late[kind][-1][(base, oid)] = data
        held = self._held.get(kind)
        if held is not None and held.short and self._fits(held, base, oid):
            self._fill_held(held, base, oid, data, values)
        else:
            self.stats.orphan_frames += 1

    def _drop_held_short_of(self, kind: str, base: int) -> bool:
        """Drop the cycle held short of frames where it lacks some of group ``base`` (its tail there ended without
        them); whether it did."""
        held = self._held.get(kind)
        if held is not None and held.short and len(held.groups.get(base, ())) < held.expected:
            self._drop_held(kind)
            return True
        return False

    def _fill_held(self, held: _Pending, base: int, oid: int, data: bytes, values: dict) -> None:
        """A late frame into the held cycle; whole with it, the held cycle is delivered, and the empty cycles behind
        it after it."""
        self._add(held, base, oid, data, values)
        if self._layout_complete(held):
            del self._held[held.kind]
            self._deliver(held)
            self._release(held.kind)

    def _ahead_of_order(self, p: _Pending, base: int) -> bool:
        """Whether a frame of group ``base`` comes before cycle ``p`` holds every frame of the groups the sensor
        sends ahead of it (general, quality, extended, warning, each whole before the next)."""
        order = GROUPS[p.kind]
        before = order[:order.index(base)]
        wanted = self._expected_of(p) | set(p.groups)
        return any(len(p.groups.get(g, ())) < p.expected for g in before if g in wanted)

    def _promote(self, p: _Pending) -> None:
        """At the end of cycle ``p``: its frames that came out of order take the places still empty (a gateway
        reordered the cycle); any other had no place in it (an earlier cycle's, overtaken; ``orphan_frames``)."""
        general = p.groups.get(GENERAL[p.kind], {})
        for base, frames in p.provisional.items():
            for oid, frame in frames.items():
                if oid in general and oid not in p.groups.get(base, {}):
                    p.groups.setdefault(base, {})[oid] = frame
                else:
                    self.stats.orphan_frames += 1
        p.provisional = {}

    def _add(self, p: _Pending, base: int, oid: int, data: bytes, values: dict) -> bool:
        """Put a list frame into cycle ``p``; False when it was a repeat, a conflict or one too many (or came out of
        order: kept aside until it is the cycle's own, :meth:`_promote`)."""
        if base != GENERAL[p.kind]:
            aside = p.provisional.get(base, {})
            if self._ahead_of_order(p, base) or oid not in p.groups.get(GENERAL[p.kind], {}):
                # the next header overtakes the last frames of a cycle on a bus (it has the higher priority): such a
                # frame must not fill this cycle's place before its own frame comes. Nor does a frame for an object
                # the general group does not have (yet): one that is not the sensor's (it cost the cycle before), or
                # the sensor's own ahead of its general frame (a gateway's reordering, with a frame that is not the
                # sensor's filling the general group's count meanwhile). Aside until the cycle's end, where it takes
                # its place if its object came (:meth:`_promote`), else is an orphan
                if oid in aside:
                    # (two out of order for one place: the first stays; the cycle's own, in order, still decides)
                    if aside[oid][0] == data:
                        self.stats.duplicate_frames += 1
                    else:
                        self.stats.conflicting_frames += 1
                    return False
                p.provisional.setdefault(base, {})[oid] = (data, values)
                return False
            stale = aside.pop(oid, None)
            if stale is not None:
                if stale[0] == data:
                    self.stats.duplicate_frames += 1
                else:
                    self.stats.orphan_frames += 1      # the frame that came early was an earlier cycle's
        group = p.groups.setdefault(base, {})
        order = GROUPS[p.kind]
        later_begun = any(p.groups.get(g) or p.provisional.get(g) for g in order[order.index(base) + 1:])
        if oid in group:
            if group[oid][0] == data:
                self.stats.duplicate_frames += 1
                if base == GENERAL[p.kind] and later_begun and p.expected >= 2:
                    timed = self._timed_rerun(p, oid)
                    if p.rerun < len(p.order) and p.order[p.rerun] == oid:      # the run goes on
                        p.rerun_timed = timed and (p.rerun_timed or not p.rerun)
                        p.rerun += 1
                    else:                                                       # it starts again, or ends
                        p.rerun_timed = timed
                        p.rerun = int(p.order[0] == oid)
                    p.sealed |= p.rerun == p.expected
                else:
                    p.rerun = 0
            else:
                self.stats.conflicting_frames += 1
                p.bad = True
            return False
        if base == GENERAL[p.kind] and later_begun and \
                p.rerun >= (RERUN_FILL_TIMED if p.rerun_timed else RERUN_FILL):
            # a general frame for a place still empty right after the general group began to repeat, in the
            # sensor's order from its first frame, after a later group began: the next cycle's general group, its
            # header lost (a standing sensor repeats its frames; the one for this cycle's lost place differs)
            self.stats.orphan_frames += 1
            p.bad = True
            return False
        p.rerun = 0
        if p.sealed and (later_begun or base == GENERAL[p.kind]
                         or len(group) >= len(p.order) or p.order[len(group)] != oid):
            # a place filled after the general group came again whole, in order, that does not continue its group
            # where it stopped (a later group began, or out of the general group's order): the next cycle's frame (its
            # header lost, a standing sensor's frames repeated: the public capture's cycle took the next one's
            # Obj_2_Quality where its own was lost, an independent tester's finding). The cycle is dropped. (One that
            # continues it is the cycle's own after an echo of its general group: every cycle had been dropped)
            self.stats.orphan_frames += 1
            p.bad = True
            return False
        if base == GENERAL[p.kind]:
            if len(group) >= p.expected:
                # one too many: one of them is not the sensor's. Kept, and the later groups, which name the sensor's
                # objects, tell which (a frame of random content on the list's ID inside a cycle cost the cycle)
                self.stats.extra_frames += 1
                p.overflow = True
            p.order.append(oid)
            p.general_times[oid] = self._stamp
        else:
            at = len(group)
            if at >= len(p.order) or p.order[at] != oid:
                p.reordered = True
        group[oid] = (data, values)
        return True

    def _timed_rerun(self, p: _Pending, oid: int) -> bool:
        """Whether a repeat of cycle ``p``'s general frame for object ``oid``, now, came at least RERUN_MIN_PERIODS of
        the sensor's cycle period after the first copy: as the next cycle's would (a standing sensor's, its header
        lost). Then one repeat is enough (RERUN_FILL_TIMED). A repeat sooner, or times that cannot tell (the period
        not known yet, a time missing or running backwards), leave arrival order to decide with RERUN_FILL repeats:
        times only ever make the rule stricter. (A repeat sooner once reset the run, and let a cycle out with the next
        one's frame where a gateway held the cycle's frames back 40 ms, a logger kept whole seconds or the period had
        just shortened: an independent tester's finding.)"""
        periods = self._periods[p.kind]
        elapsed = self._stamp - p.general_times.get(oid, float("nan"))
        if not periods or not math.isfinite(elapsed) or elapsed < 0.0:
            return False
        return elapsed >= RERUN_MIN_PERIODS * float(np.median(periods))

    def _resolve_overflow(self, p: _Pending) -> None:
        """At the end of cycle ``p``, which took more general frames than its header's count: where every later group
        it holds names the same objects, as many as the count, all among the general frames, those are the sensor's,
        and the others (counted in ``extra_frames`` as they came) leave the cycle. Otherwise (a later group with one
        frame too many, or groups that disagree: a frame that is not the sensor's in a later group too) it stays
        unresolved, and the cycle is dropped. (Resolved as soon as one later group reached the count, a forged
        object's frames in every group took a genuine object's place: an independent tester's finding.)"""
        general = p.groups.get(GENERAL[p.kind], {})
        later = [set(group) for g, group in p.groups.items() if g != GENERAL[p.kind] and group]
        named = later[0] if later else None
        if named is None or len(named) != p.expected or not named <= set(general) \
                or any(ids_ != named for ids_ in later):
            return
        for oid in set(general) - named:
            del general[oid]
        p.order = [oid for oid in p.order if oid in named]
        p.overflow = False
        p.reordered = True            # (its later groups were checked against an order with the intruder in it)

    def _stray_list_frame(self, kind: str, base: int, oid: int, data: bytes) -> None:
        """A list frame with no cycle open: a repeat, a late group of the last cycle, or an orphan."""
        done = self._last_done.get(kind)
        if done is not None:
            prior = done.groups.get(base, {}).get(oid)
            if prior is not None and prior[0] == data:
                self.stats.duplicate_frames += 1
                return
            if prior is not None and done.early:
                # another frame for a place of the cycle just delivered, in order, whole: one of the two was not the
                # sensor's, and the cycle went out with the first (a known limit: a forged frame that imitates the
                # last frame of a cycle's last group, in its place, is taken; the sensor's own after it is counted
                # here)
                self.stats.conflicting_frames += 1
                return
            if base not in done.groups and oid in done.groups.get(GENERAL[kind], {}):
                # a group the layout did not expect, for an object of the last cycle: expect it again
                self.stats.late_frames += 1
                self._announced[kind][base] = LAYOUT_MEMORY
                return
        self.stats.orphan_frames += 1

    def _layout_complete(self, p: _Pending) -> bool:
        """Whether cycle ``p`` holds the header's count in its general group and in every group of the expected
        layout, every group for the same objects (none bad)."""
        if p.bad or p.overflow:
            return False
        general = p.groups.get(GENERAL[p.kind], {})
        if len(general) != p.expected:
            return False
        for g in self._expected_of(p):
            if len(p.groups.get(g, ())) != p.expected:
                return False
        return all(set(group) == set(general) for group in p.groups.values())

    def _maybe_complete(self, kind: str) -> None:
        p = self._pending[kind]
        if self._layout_complete(p) and not p.reordered:
            p.early = True
            del self._pending[kind]
            self._finish(p)

    def _drop_held(self, kind: str) -> None:
        """A held cycle that neither its late groups nor a like cycle after it vindicated (the end of data, a time-out,
        empty cycles behind it): dropped if it lacks a group the last complete cycles had; one short only of groups
        announced since (by RadarState or CollDetState, maybe forged) is as whole as those cycles, and delivered, as
        is the first cycle of all."""
        held = self._held.pop(kind)
        self._promote(held)
        present = _present(held)
        seen = self._seen_layouts[kind]
        if _whole(held) and (self._learned_groups(kind) <= present or not seen):
            # (before any complete cycle the layout is a guess: the first cycle, followed by nothing, goes out and
            # teaches it; a group it lacks and the next cycles have is waited for again: late_frames)
            if held.expected:
                seen.append(frozenset(present))
            self._deliver(held)
        else:
            self.stats.incomplete_cycles += 1
        self._release(kind)

    def _release(self, kind: str) -> None:
        """The empty cycles that waited behind a held one, in order, once it was delivered or dropped."""
        for p in self._behind.pop(kind, []):
            self._deliver(p)

    def _finish(self, p: _Pending) -> None:
        """A cycle ended (its layout complete, the next header, a time-out or the end of data): delivered whole,
        held while short of a group of the layout, or dropped. A tail frame still undecided at its turn in this
        cycle is this cycle's own (nothing after it on its ID showed it late)."""
        undecided = self._undecided.get(p.kind)
        if undecided is not None and undecided[0] is p:
            del self._undecided[p.kind]
            self._settle(p.kind, undecided, False)
        general = p.groups.get(GENERAL[p.kind], {})
        if len(general) < p.expected:
            # the objects its later groups name that its general group lacks (a general frame lost): its tail's too
            came = [(g, oid) for g in GROUPS[p.kind][1:] for oid in [*p.groups.get(g, {}), *p.provisional.get(g, {})]
                    if oid not in general]
            # the sensor's order of its objects, the lost one in its place: a later group's (every group is sent in
            # the general group's order; while that group is short every later frame waits aside, in arrival order)
            ref = max((list(p.provisional.get(g, {})) for g in GROUPS[p.kind][1:]), key=len, default=[])
            if set(general) <= set(ref):
                p.listed = ref
            p.unlisted_came = set(came)
        self._promote(p)
        if p.overflow:
            self._resolve_overflow(p)
        general_id = GENERAL[p.kind]
        general = p.groups.get(general_id, {})
        unexpected = sum(len(set(group) - set(general)) for g, group in p.groups.items() if g != general_id)
        self.stats.unexpected_ids += unexpected
        complete = (not p.bad and not unexpected and len(general) == p.expected
                    and all(set(group) == set(general) for group in p.groups.values()))
        present = _present(p)
        seen = self._seen_layouts[p.kind]
        self._tails.pop(p.kind, None)
        if not complete:
            held = self._held.get(p.kind)
            if held is not None:
                # the cycle after one held (short of frames, or of a group) ended without proving it: its chance is
                # over. (A cycle held short of a group stayed held behind every later cycle that ended short, none of
                # which could then be held for its own overtaken frames: every header ahead of the last two frames
                # of the cycle before and one lost frame, and every later cycle was dropped — 455 of the public
                # capture's 515 with three frames overtaken and none lost)
                self._drop_held(p.kind)
            tail, cut = self._tail_places(p)
            if tail:
                self._tails[p.kind] = {g: collections.deque(oid for gg, oid in tail if gg == g)
                                       for g in dict.fromkeys(gg for gg, _ in tail)}
                self._tail_objects[p.kind] = frozenset(p.order)
                self._late[p.kind].append({})
            if cut and self._short_of_frames(p, unexpected) and p.kind not in self._held:
                # whole up to its last frames, in the sensor's order: the next header overtook them (it has the
                # higher priority). Held, as a cycle short of a group is: its late frames, first on their IDs after
                # that header, complete it; a frame of another place first there, or the next cycle's end, drops it.
                # (A cycle with a hole inside is dropped at once: a later frame for that place, forged, replayed or
                # the next cycle's with its general frame lost, had completed it)
                p.short = True
                self._held[p.kind] = p
                return
            self.stats.incomplete_cycles += 1
            if p.expected and seen:
                seen[-1] = seen[-1] | present        # evidence that a group exists, never that it does not
            return
        if not p.expected and p.kind in self._held:
            # an empty cycle shows neither that the held one was cut short nor that the sensor stopped a group: it
            # waits behind it, so that cycles are delivered in their order — for LAYOUT_MEMORY cycles at most: then
            # the held one, unproven, is dropped, and they go out
            behind = self._behind.setdefault(p.kind, [])
            behind.append(p)
            if len(behind) >= LAYOUT_MEMORY:
                self._drop_held(p.kind)
            return
        held = self._held.pop(p.kind, None)
        missing = self._missing(p)
        if held is not None:
            # what the held cycle lacks of the groups the sensor was sending (not of those only announced)
            lacked = self._missing(held) & self._learned_groups(p.kind)
            self._promote(held)
            if lacked & present or not _whole(held):
                # this cycle has what the held one lacked: it was cut short, and its late groups never came — dropped
                self.stats.incomplete_cycles += 1
            else:
                if lacked:
                    # this cycle lacks them too: the sensor stopped sending them (RadarCfg). The layout no longer
                    # expects them, and the held cycle is delivered (one short only of announced groups too)
                    self._seen_layouts[p.kind] = seen = collections.deque(
                        (frozenset(x - lacked) for x in seen), maxlen=seen.maxlen)
                    for g in lacked:
                        self._announced[p.kind].pop(g, None)
                    seen.append(frozenset(_present(held)))
                    missing = self._missing(p)
                self._deliver(held)
            self._release(p.kind)
        if missing:
            self._held[p.kind] = p              # whole in itself, short of the layout: wait for what follows
            return
        if p.expected:
            seen.append(frozenset(present))
        self._deliver(p)

    def _tail_places(self, p: _Pending) -> tuple[list[tuple[int, int]], bool]:
        """The places (group, object ID) of cycle ``p``'s later groups after the last frame it holds, in the sensor's
        order (group by group, each in the general group's order), and whether it holds every place before them and
        its general group whole (cut at its tail). A cycle short of a general frame has a tail too (of the objects
        whose general frames came): its late frames are absorbed, though it is dropped (the next cycle took them, and
        every later one its predecessor's overtaken frame: one lost 0x60B, 69 cycles out wrong)."""
        if not p.expected:
            return [], False
        wanted = self._expected_of(p) | _present(p)
        # (an object whose general frame was lost, named by a later group, takes its place in that group's order: its
        # late frames too are the cycle's, absorbed; aside in the next cycle they filled its overtaken places, and each
        # cycle's its successor's — one lost 0x60B among overtaking headers, 69 of 208 cycles out wrong)
        listed = p.listed if p.listed is not None else p.order
        places = [(g, oid) for g in GROUPS[p.kind][1:] if g in wanted for oid in listed]
        have = [oid in p.groups.get(g, {}) or (g, oid) in p.unlisted_came for g, oid in places]
        last = max((i for i, h in enumerate(have) if h), default=-1)
        whole = len(p.groups.get(GENERAL[p.kind], {})) == p.expected
        return places[last + 1:], whole and all(have[:last + 1])

    @staticmethod
    def _short_of_frames(p: _Pending, unexpected: int) -> bool:
        """Whether cycle ``p`` (ended, not whole) holds its header's count of general frames and, in its later
        groups, frames for those objects only, some of them missing (none bad, none beyond the count, no repeat of
        a general frame after a later group began)."""
        general = p.groups.get(GENERAL[p.kind], {})
        return (p.expected > 0 and not p.bad and not p.overflow and not p.sealed and not unexpected
                and len(general) == p.expected and any(len(group) < p.expected for group in p.groups.values()))

    def _missing(self, p: _Pending) -> set[int]:
        """Groups of the expected layout that cycle ``p`` (with objects) lacks: what a stray header cuts off. The
        layout is the last complete cycles' groups (before the first: 0x60B, 0x60C and 0x60D) and those RadarState
        or CollDetState announced; a forged announcement costs a held cycle one cycle's delay, not the cycle (the
        next cycle without the group delivers both)."""
        if not p.expected:
            return set()
        return self._expected_of(p) - _present(p)

    def _deliver(self, p: _Pending) -> None:
        """Queue cycle ``p`` (whole) as an ObjectCycle or ClusterCycle."""
        general = p.groups.get(GENERAL[p.kind], {})
        self._last_done[p.kind] = p
        rows = [general[i][1] for i in p.order]
        if p.kind == "obj":
            q = p.groups.get(P.OBJ_QUALITY)
            e = p.groups.get(P.OBJ_EXTENDED)
            w = p.groups.get(P.OBJ_WARNING)
            ol = P.objects_from_signals(rows, [q[i][1] if q else None for i in p.order],
                                        [e[i][1] if e else None for i in p.order])
            regions = np.array([int(w[i][1]["Obj_CollDetRegionBitfield"]) for i in p.order], dtype=np.int64) \
                if w else None
            cycle: ObjectCycle | ClusterCycle = ObjectCycle(p.meas_counter, p.timestamp, ol, bool(q), bool(e),
                                                            bool(w), regions)
            self.stats.object_cycles += 1
        else:
            q = p.groups.get(P.CLUSTER_QUALITY)
            cl = P.clusters_from_signals(rows, [q[i][1] if q else None for i in p.order], p.n_near)
            cycle = ClusterCycle(p.meas_counter, p.timestamp, cl, bool(q))
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
