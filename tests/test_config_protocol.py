"""The ARS 408 configuration protocol end to end on a bus (issue 13, item 4).

Every configuration message goes from an "ECU" over a python-can virtual bus to a node, whose frames go over
the same bus to consumers: FilterCfg 0x202 (every object index, the cluster indices), CollDetCfg 0x400 and
CollDetRegionCfg 0x401, RadarConfiguration's MaxDistance. Each test checks the reply (0x203/0x204, 0x408/0x402,
0x60E, RadarState) and the effect on the list, with a second node (sensor ID 1) on the same bus that must be
unaffected, and consumers of both sensors that must deliver every cycle intact.
"""

from __future__ import annotations

import itertools
import os

import can
import numpy as np
import pytest

from radarnode.consumer.assembler import CycleAssembler, ObjectCycle
from radarnode.errors import ScenarioError
from radarnode.wire import ars408 as P
from radarnode.wire.config import FILTER_NAMES, inside_raw
from radarnode.wire.dbc import load_database
from radarnode.wire.node import EgoMotionSender, RadarNode
from tests.helpers import scenario

ACTORS = """
  - {id: lead, class: car, x_m: 40.0, lane: 1, speed_mps: 23.0}
  - {id: truck, class: truck, x_m: 70.0, lane: 0, speed_mps: 15.0}
  - {id: fast, class: motorcycle, x_m: 25.0, lane: 2, speed_mps: 28.0}
  - {id: slow, class: car, x_m: 110.0, lane: 2, speed_mps: 8.0}
  - {id: ped, class: pedestrian, x_m: 70.0, y_m: -7.0, speed_mps: 1.5, heading_deg: 90.0}
  - {id: bike, class: bicycle, x_m: 80.0, y_m: 9.0, speed_mps: 4.0, heading_deg: -90.0}
"""
_channel = itertools.count()


def _frame(name: str, sensor: int = 0, **values) -> can.Message:
    m = load_database().get_message_by_name(name)
    if not m.is_multiplexed():
        values = {**{s.name: 0 for s in m.signals}, **values}
    return can.Message(arbitration_id=P.shifted(m.frame_id, sensor), data=m.encode(values), is_extended_id=False)


def filter_cfg(index: int, lo: float, hi: float, *, ftype: int = 1, active: int = 1, valid: int = 1,
               sensor: int = 0) -> can.Message:
    name = FILTER_NAMES[index]
    return _frame("FilterCfg", sensor, FilterCfg_Valid=valid, FilterCfg_Active=active, FilterCfg_Index=index,
                  FilterCfg_Type=ftype, **{f"FilterCfg_Min_{name}": lo, f"FilterCfg_Max_{name}": hi})


def region_cfg(rid: int, p1=(0.0, 0.0), p2=(0.0, 0.0), *, activate: int = 1, coords: int = 1,
               sensor: int = 0) -> can.Message:
    return _frame("CollDetRegionCfg", sensor, CollDetRegCfg_Activate=activate, CollDetRegCfg_Coordinates_valid=coords,
                  CollDetRegCfg_RegionID=rid, CollDetRegCfg_Point1X=p1[0], CollDetRegCfg_Point1Y=p1[1],
                  CollDetRegCfg_Point2X=p2[0], CollDetRegCfg_Point2Y=p2[1])


def coll_det_cfg(activate: int = 1, min_time: float | None = None, reset: int = 0, clear: int = 0,
                 sensor: int = 0) -> can.Message:
    return _frame("CollDetCfg", sensor, CollDetCfg_Activate=activate, CollDetCfg_WarningReset=reset,
                  CollDetCfg_ClearRegions=clear, CollDetCfg_MinTime_valid=int(min_time is not None),
                  CollDetCfg_MinDetectTime=min_time or 0.0)


def radar_cfg(sensor: int = 0, **fields) -> can.Message:
    return _frame("RadarConfiguration", sensor, **fields)


class Bench:
    """An ECU, two nodes (sensor IDs 0 and 1) and two consumers on one python-can virtual bus, stepped cycle by
    cycle in simulated time: a frame the ECU sends before :meth:`step` takes effect in that step's cycle."""

    def __init__(self, actors: str = ACTORS, radar: str = "", duration: float = 12.0) -> None:
        ch = f"cfg-{os.getpid()}-{next(_channel)}"
        self.ecu = can.Bus(interface="virtual", channel=ch)
        self.tap = can.Bus(interface="virtual", channel=ch)
        self.nodes, self.buses, self.vehicles = [], [], []
        for sensor in (0, 1):
            sc = scenario(actors, radar=f"{{preset: ars408_like, sensor_id: {sensor}{', ' + radar if radar else ''}}}",
                          duration=duration)
            node = RadarNode(sc)
            self.nodes.append(node)
            self.buses.append(can.Bus(interface="virtual", channel=ch))
            self.vehicles.append(EgoMotionSender(node.scene, sensor))
        self.asm = [CycleAssembler(0), CycleAssembler(1)]
        self.k = 0
        self.db = load_database()

    def close(self) -> None:
        for b in [self.ecu, self.tap, *self.buses]:
            b.shutdown()

    def send(self, *frames: can.Message) -> None:
        for m in frames:
            self.ecu.send(m)

    def step(self) -> list[dict]:
        """One cycle of both nodes; per sensor: its frames of the cycle and the cycles its consumer delivered."""
        t = self.k * self.nodes[0].period_s
        for v in self.vehicles:
            self.send(*v.frames(t))
        sent = []
        for node, bus in zip(self.nodes, self.buses):
            while (m := bus.recv(0)) is not None:
                node.receive(m, t)
            out = node.cycle(t)
            for m in out.messages:
                bus.send(m)
            sent.append(out)
        frames = []
        while (m := self.tap.recv(0)) is not None:
            frames.append(m)
        res = []
        for sensor, asm in enumerate(self.asm):
            for m in frames:
                asm.on_message_received(m)
            mine = [m for m in frames if m.arbitration_id in {m2.arbitration_id for m2 in sent[sensor].messages}]
            res.append({"frames": mine, "cycles": asm.drain(), "out": sent[sensor], "k": self.k})
        self.k += 1
        return res

    def run(self, n: int) -> list[list[dict]]:
        return [self.step() for _ in range(n)]

    def decode(self, m: can.Message) -> dict:
        return self.db.decode_message(P.unshifted(m.arbitration_id)[0], m.data, decode_choices=False)


@pytest.fixture
def bench():
    b = Bench()
    yield b
    b.close()


def _ids(step: dict, sensor: int = 0) -> list[int]:
    return [P.unshifted(m.arbitration_id)[0] for m in step["frames"]]


def _objects(steps: list[list[dict]], sensor: int = 0) -> list[ObjectCycle]:
    return [c for s in steps for c in s[sensor]["cycles"]]


def _consumers_unharmed(bench: Bench) -> None:
    for node, asm in zip(bench.nodes, bench.asm):
        asm.flush()
        st = asm.stats
        assert st.cycles == node.counters["cycles"] and st.incomplete_cycles == 0 and st.dropped() == 0, st
        assert st.lost_cycles == 0 and st.late_frames == 0


# --- FilterCfg 0x202 --------------------------------------------------------------------------------------------

def _quantity(index: int, c: ObjectCycle) -> tuple[np.ndarray, np.ndarray]:
    """The filter's quantity of each decoded object and where the filter applies to it (the consumer's view)."""
    ol = c.objects
    x, y, vx, vy = ol.dist_long_m, ol.dist_lat_m, ol.vrel_long_mps, ol.vrel_lat_mps
    r = np.hypot(x, y)
    vr = (x * vx + y * vy) / r
    every = np.ones(len(ol), dtype=bool)
    return {
        1: (r, every), 2: (np.degrees(np.arctan2(y, x)), every), 3: (-vr, vr < 0), 4: (vr, vr > 0),
        5: (ol.rcs_dbsm, every), 7: (ol.length_m * ol.width_m, every), 8: (ol.prob_of_exist.astype(float), every),
        9: (y, every), 10: (x, every), 11: (-vy, vy < 0), 12: (-vx, vx < 0), 13: (vy, vy > 0), 14: (vx, vx > 0),
    }[index]


# index: (min, max, tolerance of the decoded quantity: the wire's quantisation)
OBJECT_FILTERS = {
    1: (0.0, 50.0, 0.15), 2: (-5.0, 5.0, 0.5), 3: (0.0, 8.0, 0.2), 4: (0.0, 5.0, 0.2), 5: (5.0, 52.0, 0.26),
    7: (3.0, 102.0, 0.6), 8: (0.0, 6.0, 0.0), 9: (-3.1, 3.1, 0.11), 10: (0.0, 60.0, 0.11), 11: (0.0, 2.0, 0.2),
    12: (0.0, 8.0, 0.13), 13: (0.0, 1.0, 0.2), 14: (0.0, 5.0, 0.13),
}


@pytest.mark.parametrize("index", sorted(OBJECT_FILTERS), ids=lambda i: FILTER_NAMES[i])
def test_object_filter_is_answered_and_applied(bench, index):
    lo, hi, tol = OBJECT_FILTERS[index]
    before = bench.run(12)
    outside = [q for c in _objects(before[-3:]) for q, a in zip(*_quantity(index, c)) if a and not
               lo - tol <= q <= hi + tol]
    assert outside, "the scene has no object this filter would remove: the test would prove nothing"
    bench.send(filter_cfg(index, lo, hi))
    first, *after = bench.run(40)
    # the reply: FilterState_Header with one object filter, then its FilterState_Cfg, in the same cycle
    ids = _ids(first[0])
    assert ids.count(P.FILTER_STATE_HEADER) == 1 and ids.count(P.FILTER_STATE_CFG) == 1
    assert ids.index(P.FILTER_STATE_CFG) == ids.index(P.FILTER_STATE_HEADER) + 1 < ids.index(P.OBJ_STATUS)
    header = bench.decode(first[0]["frames"][ids.index(P.FILTER_STATE_HEADER)])
    assert header == {"FilterState_NofClusterFilterCfg": 0, "FilterState_NofObjectFilterCfg": 1}
    state = bench.asm[0].filter_state[(1, index)]
    name = FILTER_NAMES[index]
    assert state["FilterState_Active"] == 1 and state["FilterState_Index"] == index
    assert state[f"FilterState_Min_{name}"] == pytest.approx(lo, abs=0.05)
    assert state[f"FilterState_Max_{name}"] == pytest.approx(hi, abs=0.05)
    assert P.FILTER_STATE_HEADER not in _ids(after[0][0])             # answered once
    # the effect, from the first cycle on: every object inside the interval the sensor reports (where the filter
    # applies), exactly: the node filters on the values it sends (an independent tester found objects a few cm
    # beyond Max, filtered on their values before the wire's 0.2-m grid)
    lo_sent, hi_sent = state[f"FilterState_Min_{name}"], state[f"FilterState_Max_{name}"]
    cycles = _objects([first, *after])
    assert len(cycles) == 40
    for c in cycles:
        q, applies = _quantity(index, c)
        assert np.all(~applies | ((q >= lo_sent - 1e-9) & (q <= hi_sent + 1e-9))), (c.meas_counter, q[applies])
    assert sum(len(c.objects) for c in cycles) > 0 or index == 8     # ProbExists <= 6: only objects that coast
    assert bench.nodes[0].counters["items_filtered"] > 0
    # the other sensor was not configured: no reply, nothing filtered
    assert bench.nodes[1].counters["items_filtered"] == 0 and not bench.asm[1].filter_state
    assert all(P.FILTER_STATE_HEADER not in _ids(s[1]) for s in [first, *after])
    _consumers_unharmed(bench)


def test_nofobj_filter_caps_the_list_nearest_first(bench):
    before = bench.run(30)
    assert max(len(c.objects) for c in _objects(before)) >= 4
    bench.send(filter_cfg(0, 0, 2))
    after = bench.run(20)
    cycles = _objects(after)
    assert all(len(c.objects) <= 2 for c in cycles) and any(len(c.objects) == 2 for c in cycles)
    assert bench.asm[0].filter_state[(1, 0)]["FilterState_Max_NofObj"] == 2
    # the two kept are the two nearest the model reported (SortIndex range)
    out = after[-1][0]["out"]
    kept = np.sort(out.frame.objects.range_m)
    assert len(kept) == 2 and bench.nodes[0].counters["items_filtered"] > 0
    _consumers_unharmed(bench)


def test_lifetime_filter_holds_back_new_objects(bench):
    bench.send(filter_cfg(6, 2.0, 409.5))
    steps = bench.run(60)
    cycles = _objects(steps)
    period = bench.nodes[0].period_s
    assert all(len(c.objects) == 0 for c in cycles if c.meas_counter * period < 2.0 - 1e-9)
    assert len(cycles[40].objects) >= 3
    assert bench.asm[0].filter_state[(1, 6)]["FilterState_Min_Lifetime"] == 2.0
    # deactivated: the objects come back at once, and the filter stays configured (inactive)
    bench.send(filter_cfg(6, 2.0, 409.5, active=0))
    bench.run(1)
    assert bench.asm[0].filter_header["FilterState_NofObjectFilterCfg"] == 1
    assert bench.asm[0].filter_state[(1, 6)]["FilterState_Active"] == 0
    _consumers_unharmed(bench)


def test_filter_messages_late_twice_refused_and_for_someone_else(bench, caplog):
    bench.run(5)
    good = filter_cfg(1, 0.0, 50.0)
    # twice, a refused one (min above max), one with Valid 0, one for sensor 1's other filter type, a reserved
    # index: one reply with the state in force
    bench.send(good, good, filter_cfg(1, 60.0, 10.0), filter_cfg(10, 0.0, 5.0, valid=0),
               filter_cfg(9, -2.0, 2.0, sensor=1, ftype=0), filter_cfg(6, 0, 1, ftype=0),
               _frame("FilterCfg", FilterCfg_Valid=1, FilterCfg_Active=1, FilterCfg_Index=15, FilterCfg_Type=1))
    (s0, s1), = bench.run(1)
    assert _ids(s0).count(P.FILTER_STATE_HEADER) == 1 and _ids(s1).count(P.FILTER_STATE_HEADER) == 1
    assert set(bench.asm[0].filter_state) == {(1, 1)}
    assert bench.asm[0].filter_state[(1, 1)]["FilterState_Max_Distance"] == 50.0
    assert set(bench.asm[1].filter_state) == {(0, 9)}                # a cluster filter of the other sensor
    assert bench.asm[1].filter_header == {"FilterState_NofClusterFilterCfg": 1, "FilterState_NofObjectFilterCfg": 0}
    assert bench.nodes[0].counters["config_rejected"] == 3             # min > max, cluster Lifetime, index 15
    assert bench.nodes[0].counters["rx_filter_cfg"] == 6                 # not the one for sensor 1
    assert "Min_Distance=60 is above" in caplog.text
    # refused: RadarState goes out with the cycle, with Temporary_Error
    state = bench.asm[0].radar_state
    assert state["RadarState_Temporary_Error"] == 1 and bench.asm[1].radar_state["RadarState_Temporary_Error"] == 0
    # a later refusal leaves the filter in force; late by a cycle is still applied, from the next cycle
    bench.send(filter_cfg(1, 80.0, 20.0))
    after = bench.run(20)
    assert bench.asm[0].filter_state[(1, 1)]["FilterState_Max_Distance"] == 50.0
    assert all(np.all(c.objects.range_m <= 50.15) for c in _objects(after))
    _consumers_unharmed(bench)


def test_cluster_filters():
    b = Bench(radar="output: clusters")
    try:
        before = b.run(10)
        clusters = [c for s in before for c in s[0]["cycles"]]
        assert max(np.max(c.clusters.range_m, initial=0) for c in clusters) > 40.0
        b.send(filter_cfg(1, 0.0, 40.0, ftype=0), filter_cfg(0, 0, 3, ftype=0),
               filter_cfg(7, 0.0, 5.0, ftype=0))                      # Size: clusters have none, refused
        after = b.run(15)
        cycles = [c for s in after for c in s[0]["cycles"]]
        assert len(cycles) == 15
        assert all(len(c.clusters) <= 3 and np.all(c.clusters.range_m <= 40.0 + 1e-9) for c in cycles)   # as sent
        assert any(len(c.clusters) == 3 for c in cycles)
        assert all(np.array_equal(c.clusters.id, np.arange(len(c.clusters))) for c in cycles)
        assert b.asm[0].filter_header == {"FilterState_NofClusterFilterCfg": 2, "FilterState_NofObjectFilterCfg": 0}
        assert set(b.asm[0].filter_state) == {(0, 0), (0, 1)}
        assert b.nodes[0].counters["config_rejected"] == 1
        # an object filter does not touch the cluster list
        b.send(filter_cfg(5, 40.0, 52.0))
        (s0, _), = b.run(1)
        assert len(s0["cycles"][0].clusters) > 0
        assert b.asm[0].filter_header["FilterState_NofObjectFilterCfg"] == 1
        _consumers_unharmed(b)
    finally:
        b.close()


# --- collision detection 0x400 / 0x401 --------------------------------------------------------------------------

REGIONS = {0: ((20.0, -2.4), (60.0, 2.4)), 3: ((15.0, -12.0), (45.0, -3.0))}


def _check_regions(steps, bench, min_time: float, since: int) -> tuple[int, int]:
    """Check every cycle's 0x408, 0x402 and 0x60E against the decoded objects, the consumer's way.

    Returns (objects seen inside a region, object warnings)."""
    period = bench.nodes[0].period_s
    entered: dict[tuple[int, int], float] = {}
    latched = {rid: False for rid in REGIONS}
    n_inside = n_warn = 0
    for s in steps:
        st = s[0]
        ids = _ids(st)
        (c,) = st["cycles"]
        assert ids.index(P.COLL_DET_STATE) + 1 + len(REGIONS) == ids.index(P.OBJ_STATUS)   # before the header
        state = bench.decode(st["frames"][ids.index(P.COLL_DET_STATE)])
        assert state["CollDetState_Active"] == 1 and state["CollDetState_NofRegions"] == len(REGIONS)
        assert state["CollDetState_MeasCounter"] == c.meas_counter
        assert c.has_warning and len(c.collision_regions) == len(c.objects)
        regions = {int(v["CollDetRegState_RegionID"]): v for v in
                   (bench.decode(m) for m in st["frames"] if P.unshifted(m.arbitration_id)[0] == P.COLL_DET_REGION_STATE)}
        assert set(regions) == set(REGIONS)
        t = c.meas_counter * period
        for rid, (p1, p2) in REGIONS.items():
            inside = inside_raw(c.objects.dist_long_m, c.objects.dist_lat_m, p1, p2)
            now = set(c.objects.id[inside].tolist())
            entered = {k: v for k, v in entered.items() if k[0] != rid or k[1] in now}
            for oid in now:
                entered.setdefault((rid, oid), t)
            warns = {oid for oid in now if t - entered[(rid, oid)] >= min_time - 1e-9 and st["k"] >= since}
            got = {int(i) for i, b in zip(c.objects.id, c.collision_regions) if b >> rid & 1}
            assert got == warns, (st["k"], rid, got, warns)
            latched[rid] |= bool(warns)
            v = regions[rid]
            assert v["CollDetRegState_NofObjects"] == len(now)
            assert v["CollDetRegState_WarningLevel"] == (1 if latched[rid] else 0)
            assert (v["CollDetRegState_Point1X"], v["CollDetRegState_Point2Y"]) == pytest.approx((p1[0], p2[1]))
            n_inside += len(now)
            n_warn += len(warns)
    return n_inside, n_warn


def test_collision_detection_regions_warnings_and_state(bench):
    bench.run(3)
    bench.send(*[region_cfg(rid, p1, p2) for rid, (p1, p2) in REGIONS.items()], coll_det_cfg(1, min_time=0.5))
    steps = bench.run(60)
    n_inside, n_warn = _check_regions(steps, bench, 0.5, since=3)
    assert n_inside > 60 and n_warn > 30                    # the lead sits in region 0, the pedestrian crosses 3
    assert bench.asm[0].coll_det_regions[0]["CollDetRegState_WarningLevel"] == 1
    # the other sensor was not configured: no 0x418 / 0x412 / 0x61E
    assert all(not set(_ids(s[1])) & {P.COLL_DET_STATE, P.COLL_DET_REGION_STATE, P.OBJ_WARNING} for s in steps)
    assert bench.asm[1].coll_det_state is None
    _consumers_unharmed(bench)


def test_collision_detection_reset_deactivate_clear_relay(bench, caplog):
    # region 0 out to the near half of the right lane: the truck there (its rear face's middle, 3.0–3.2 m right) is
    # inside throughout, the lead in the own lane too, but for two cycles behind the crossing bicycle
    bench.send(region_cfg(0, (20.0, -3.6), (60.0, 2.4)), coll_det_cfg(1, min_time=0.0),
               radar_cfg(RadarCfg_CtrlRelay_valid=1, RadarCfg_CtrlRelay=1))
    steps = bench.run(10)
    relay = [bench.decode(m)["CollDetRelayCtrl_Param"] for s in steps for m in s[0]["frames"]
             if m.arbitration_id == P.COLL_DET_RELAY]
    assert len(relay) == 10 and relay[-1] == 1                 # region 0 warns: bit 0
    # a region switched on without ever having corners: refused
    bench.send(region_cfg(5, coords=0))
    # the region switched off: warning deactivated (3), nothing counted, no object warns
    bench.send(region_cfg(0, activate=0, coords=0))
    (s0, _), = bench.run(1)
    v = bench.asm[0].coll_det_regions
    assert set(v) == {0} and v[0]["CollDetRegState_WarningLevel"] == 3 and v[0]["CollDetRegState_NofObjects"] == 0
    assert not s0["cycles"][0].collision_regions.any()
    assert bench.nodes[0].counters["config_rejected"] == 1 and "RegionID=5 has no corners" in caplog.text
    # on again: the latched warning is still there until a WarningReset; after it, it comes back at once
    # because the lead is still inside (MinDetectTime 0)
    bench.send(region_cfg(0, activate=1, coords=0))
    bench.run(1)
    assert bench.asm[0].coll_det_regions[0]["CollDetRegState_WarningLevel"] == 1
    bench.send(coll_det_cfg(1, min_time=2.0, reset=1))
    steps = bench.run(30)
    levels = [bench.asm[0].coll_det_regions[0]["CollDetRegState_WarningLevel"]]
    assert bench.asm[0].coll_det_state["CollDetState_MinDetectTime"] == pytest.approx(2.0)
    first = [bench.decode(m)["CollDetRegState_WarningLevel"] for m in steps[0][0]["frames"]
             if P.unshifted(m.arbitration_id)[0] == P.COLL_DET_REGION_STATE]
    assert first == [0] and levels == [1]       # reset, then the truck has been inside 2 s again: it warns
    # collision detection off: one CollDetState with Active 0, regions "warning deactivated", no more 0x60E
    bench.send(coll_det_cfg(0))
    steps = bench.run(6)
    ids0 = _ids(steps[0][0])
    assert P.COLL_DET_STATE in ids0 and P.OBJ_WARNING not in ids0
    assert bench.asm[0].coll_det_state["CollDetState_Active"] == 0
    assert bench.asm[0].coll_det_regions[0]["CollDetRegState_WarningLevel"] == 3
    assert all(P.COLL_DET_STATE not in _ids(s[0]) and P.OBJ_WARNING not in _ids(s[0]) for s in steps[1:])
    assert not any(c.has_warning for c in _objects(steps))
    # on again with ClearRegions: no region left
    bench.send(coll_det_cfg(1, clear=1))
    (s0, _), = bench.run(1)
    assert bench.asm[0].coll_det_state["CollDetState_NofRegions"] == 0 and not bench.asm[0].coll_det_regions
    assert P.COLL_DET_REGION_STATE not in _ids(s0)
    _consumers_unharmed(bench)


# --- MaxDistance ------------------------------------------------------------------------------------------------

def test_max_distance_honoured_up_to_the_preset_and_refused_beyond(bench, caplog):
    before = bench.run(20)
    assert max(np.max(c.objects.range_m, initial=0) for c in _objects(before)) > 100.0
    bench.send(radar_cfg(RadarCfg_MaxDistance_valid=1, RadarCfg_MaxDistance=400))
    steps = bench.run(30)
    states = [bench.decode(m) for s in steps for m in s[0]["frames"] if m.arbitration_id == P.RADAR_STATE]
    assert states[0]["RadarState_MaxDistanceCfg"] == 250 and states[0]["RadarState_Temporary_Error"] == 1
    assert states[-1]["RadarState_Temporary_Error"] == 0 and len(states) == 3     # cleared after a second
    assert bench.nodes[0].config.max_distance_m == 250.0
    assert bench.nodes[0].counters["config_rejected"] == 1
    assert "MaxDistance=400 m is not allowed (allowed 10..250 m: what preset ars408_like can see)" in caplog.text
    # 100 m is honoured: echoed, and nothing farther is reported (the tracker lets a coasting object go)
    bench.send(radar_cfg(RadarCfg_MaxDistance_valid=1, RadarCfg_MaxDistance=100))
    steps = bench.run(25)
    state = bench.asm[0].radar_state
    assert state["RadarState_MaxDistanceCfg"] == 100 and state["RadarState_Temporary_Error"] == 0
    assert all(np.all(c.objects.range_m <= 100.2) for c in _objects(steps[8:]))
    assert bench.asm[1].radar_state["RadarState_MaxDistanceCfg"] == 250
    _consumers_unharmed(bench)


@pytest.mark.parametrize("value", [300, 252, 5, 8, 101])
def test_a_scenario_max_distance_the_sensor_would_not_take_is_an_error(value):
    """Beyond what the preset sees, below the 10 m RadarConfiguration takes, or off RadarState's 2-m grid: 5 m was
    in force while RadarState echoed 4 m, which sent back was refused (an independent tester's finding)."""
    with pytest.raises(ScenarioError, match=rf"field 'radar.max_distance_m': value {value} is not allowed; expected "
                                            r"10\.\.250 m \(what preset ars408_like can see\) in steps of 2 m"):
        RadarNode(scenario(ACTORS, radar=f"{{preset: ars408_like, max_distance_m: {value}}}"))


@pytest.mark.parametrize("reach", [1.0, 1.99])
def test_a_preset_reach_under_radar_states_2_m_step_is_refused(reach):
    """A second independent tester's finding: a preset overridden to 1 m had 1 m in force while RadarState said 0
    (its MaxDistance field counts in steps of 2 m): such a reach is refused by name; 2 m loads."""
    with pytest.raises(ScenarioError, match=rf"max_range_m': value {reach} is not allowed; expected a number >= 2"):
        RadarNode(scenario(ACTORS, radar=f"{{preset: ars408_like, overrides: {{max_range_m: {reach}}}}}"))
    node = RadarNode(scenario(ACTORS, radar="{preset: ars408_like, overrides: {max_range_m: 2.0}}"))
    assert node.config.max_distance_m == 2.0


def test_a_preset_that_sees_less_than_the_smallest_max_distance_still_loads():
    """A preset whose range is overridden below 10 m (the smallest MaxDistance the sensor takes) works to its range
    by default; a max_distance_m given for it names why no value fits (an independent tester's finding: the default
    was refused, the error naming a field the user never wrote)."""
    node = RadarNode(scenario(ACTORS, radar="{preset: ars408_like, overrides: {max_range_m: 9.0}}"))
    assert node.config.max_distance_m == 8.0          # on RadarState's 2-m grid, as it echoes it (below)
    with pytest.raises(ScenarioError, match=r"value 10 is not allowed; expected no value: preset ars408_like sees "
                                            r"9 m, less than the 10 m"):
        scenario(ACTORS, radar="{preset: ars408_like, max_distance_m: 10, overrides: {max_range_m: 9.0}}")


@pytest.mark.parametrize("preset, given, in_force", [("mimo12", None, 112.0), ("ars408_like", None, 250.0),
                                                     ("ars408_like", 10, 10.0), ("mimo12", 112, 112.0),
                                                     ("ars408_like:5", None, 4.0), ("ars408_like:249", None, 248.0),
                                                     ("ars408_like:250", None, 250.0)])
def test_radar_state_echoes_the_max_distance_in_force(preset, given, in_force):
    """mimo12 sees 112.5 m, which RadarState's 2-m grid cannot say (it echoed 112 with 112.5 in force): 112 m is in
    force by default, and what RadarState says is what the model uses. A preset's range overridden to 5 m: 5 m was
    in force while it said 4 (an independent tester's finding). (Overrides beyond the field of view's reach, which
    this test once took up to 3000 m, are refused: test_a_preset_reach_beyond_its_field_of_view_is_refused.)"""
    extra = "" if given is None else f", max_distance_m: {given}"
    name, _, reach = preset.partition(":")
    if reach:
        extra += f", overrides: {{max_range_m: {reach}}}"
    node = RadarNode(scenario(ACTORS, radar=f"{{preset: {name}{extra}}}"))
    assert node.config.max_distance_m == in_force
    state = next(m for m in node.cycle(0.0).messages if m.arbitration_id == P.RADAR_STATE)
    assert node.db.decode_message(P.RADAR_STATE, state.data)["RadarState_MaxDistanceCfg"] == in_force


@pytest.mark.parametrize("reach", [251, 2046, 2047, 3000])
def test_a_preset_reach_beyond_its_field_of_view_is_refused(reach):
    """ars408_like's sectors reach 250 m: a max_range_m of 1000 was taken, said in the warnings and RadarState, and
    seen to 250 m (an independent tester's finding, 2026-12-03). Just above the reach and beyond RadarState's 2046 m
    are refused by name, with the sectors."""
    with pytest.raises(ScenarioError, match=rf"max_range_m': value {reach} is not allowed; expected a number in "
                                            r"\[2, 250\]: at most the farthest its field of view's sectors reach"):
        RadarNode(scenario(ACTORS, radar=f"{{preset: ars408_like, overrides: {{max_range_m: {reach}}}}}"))


def test_relay_frames_of_another_sensor_are_not_taken_for_ours(bench):
    """0x008 is not shifted by SensorID (as on the ARS 408): with only sensor 1 driving its relay, sensor 0's
    consumer (whose RadarState says CtrlRelay off) counts its 0x008 as another sensor's (an independent tester
    found sensor 0's consumer reporting sensor 1's relay state as its own)."""
    bench.run(16)                                      # RadarState of both sensors seen (once a second)
    bench.send(region_cfg(0, *REGIONS[0], sensor=1), coll_det_cfg(1, min_time=0.0, sensor=1),
               radar_cfg(1, RadarCfg_CtrlRelay_valid=1, RadarCfg_CtrlRelay=1))
    steps = bench.run(20)
    on_bus = sum(m.arbitration_id == P.COLL_DET_RELAY for s in steps for m in s[1]["frames"])
    assert on_bus > 0 and bench.asm[1].relay is not None and bench.asm[1].relay["CollDetRelayCtrl_Param"] == 1
    assert bench.asm[0].relay is None and bench.asm[0].stats.other_sensor_frames >= on_bus
    _consumers_unharmed(bench)


def test_filter_cfg_of_continentals_sensor_1_dbc_is_understood(bench, reference_dir):
    """Continental's public DBC for sensor 1 gives FilterCfg 0x212 five bytes (sensor 0's: eight); a tool built on
    it is answered and obeyed (an independent tester found the 5-byte frame dropped as a wrong DLC, unanswered)."""
    import cantools
    db1 = cantools.database.load_file(str(reference_dir / "ARS408_id1.dbc"), encoding="latin-1", strict=False)
    m = db1.get_message_by_frame_id(0x212)
    assert m.length == 5
    data = m.encode({"FilterCfg_Valid": 1, "FilterCfg_Active": 1, "FilterCfg_Type": 1, "FilterCfg_Index": 1,
                     "FilterCfg_Min_Distance": 0.0, "FilterCfg_Max_Distance": 50.0}, strict=False)
    bench.run(3)
    bench.send(can.Message(arbitration_id=0x212, data=data, is_extended_id=False))
    first, *after = bench.run(10)
    ids = _ids(first[1])
    assert ids.count(P.FILTER_STATE_HEADER) == 1 and ids.count(P.FILTER_STATE_CFG) == 1
    assert bench.asm[1].filter_state[(1, 1)]["FilterState_Max_Distance"] == pytest.approx(50.0)
    assert all(np.all(c.objects.range_m <= 50.0 + 1e-9) for c in _objects([first, *after], sensor=1))
    assert bench.nodes[1].counters["rx_wrong_dlc"] == 0 and not bench.nodes[0].filters.filters


def test_nvm_write_status_is_the_last_writes(bench):
    """NVMwriteStatus reports the last write of the configuration (0 before any, as the public capture shows a
    parked sensor): StoreInNVM on writes it (1); StoreInNVM off writes nothing and leaves the status."""
    def status():
        (s0, _), = bench.run(1)
        return [bench.decode(m)["RadarState_NVMwriteStatus"] for m in s0["frames"]
                if m.arbitration_id == P.RADAR_STATE]
    bench.run(1)
    assert bench.nodes[0].config.nvm_write_ok is False
    bench.send(radar_cfg(RadarCfg_StoreInNVM_valid=1, RadarCfg_StoreInNVM=1))
    assert status() == [1]
    bench.send(radar_cfg(RadarCfg_StoreInNVM_valid=1, RadarCfg_StoreInNVM=0))
    assert status() == [1]
