"""The CAN ID plan (issue 13, item 1): no collisions across sensor IDs 0–7 and the ECU, and E2E Data IDs
that name the sensor and the message; two nodes and an ECU on one bus, each consumer takes only its own."""

from __future__ import annotations

import uuid
from collections import Counter

import can
import numpy as np
import pytest

from radarnode.consumer.acc import AccSettings
from radarnode.consumer.assembler import ClusterCycle, CycleAssembler, ObjectCycle
from radarnode.consumer.ecu import Ecu
from radarnode.wire import ars408 as P
from radarnode.wire import ids
from radarnode.wire.dbc import load_own_database
from radarnode.wire.node import EgoMotionSender, RadarNode
from tests.helpers import scenario

TRAFFIC_A = """
  - {id: a, class: car, x_m: 40.0, lane: 1, speed_mps: 22.0}
  - {id: b, class: truck, x_m: 70.0, lane: 0, speed_mps: 18.0}
"""
TRAFFIC_B = """
  - {id: c, class: car, x_m: 25.0, lane: 2, speed_mps: 15.0}
  - {id: d, class: motorcycle, x_m: 90.0, lane: 1, speed_mps: 30.0}
  - {id: e, class: car, x_m: 120.0, lane: 0, speed_mps: 26.0}
"""


def _road(left_offset_m: float) -> str:
    return (f"{{lanes: 3, lane_width_m: 3.5, ego_lane: 1, "
            f"guardrails: {{left_offset_m: {left_offset_m}, right_offset_m: 1.0}}}}")


def _sent_ids(sensor_id: int, output: str) -> tuple[set[int], set[int]]:
    """CAN IDs a node with ``sensor_id`` and its vehicle really send in a few cycles: (all, road-boundary)."""
    sc = scenario(TRAFFIC_A, radar=f"{{preset: ars408_like, sensor_id: {sensor_id}, output: {output}}}",
                  road=_road(1.0), duration=0.5)
    node = RadarNode(sc)
    vehicle = EgoMotionSender(node.scene, sensor_id)
    sent, boundary = set(), set()
    for k in range(3):
        frames = vehicle.frames(k * node.period_s)
        for m in frames:
            node.receive(m, k * node.period_s)
        out = node.cycle(k * node.period_s)
        assert out.boundaries is not None
        sent |= {m.arbitration_id for m in frames + out.messages}
        boundary |= {m.arbitration_id for m in out.messages[-2:]}       # the boundaries close the cycle
    return sent, boundary


def _ars_ids(database) -> dict[int, set[int]]:
    """ARS 408 IDs of every sensor: the DBC's IDs shifted by 0x10 × SensorID (0x008 stays)."""
    return {s: {m.frame_id if m.frame_id == P.COLL_DET_RELAY else m.frame_id + 0x10 * s for m in database.messages}
            for s in range(8)}


def _check_plan(ars: dict[int, set[int]]) -> None:
    all_ars = set().union(*ars.values())
    # the ARS 408's own IDs are unique across sensors, but for the unshifted relay control 0x008
    for s in range(8):
        for o in range(s + 1, 8):
            assert ars[s] & ars[o] <= {P.COLL_DET_RELAY}
    own_db = load_own_database()
    ecu_ids = {ids.own_id(m.frame_id) for m in own_db.messages if not ids.is_sensor_message(m.frame_id)}
    assert len(ecu_ids) == 2
    sent_by = {}
    for s in range(8):
        for output in ("objects", "clusters"):
            sent, boundary = _sent_ids(s, output)
            assert len(boundary) == 2
            assert sent - boundary <= ars[s], f"sensor {s} sends ARS IDs outside its shifted set"
            sent_by.setdefault(s, set()).update(sent)
            # every own message in the DBC, for this sensor, lands where the node really sends it
            plan = {ids.own_id(m.frame_id, s) for m in own_db.messages if ids.is_sensor_message(m.frame_id)}
            assert boundary == plan
        own = sent_by[s] - ars[s]
        assert own and not own & all_ars, f"sensor {s}: own IDs {sorted(map(hex, own & all_ars))} are ARS 408 IDs"
        assert all(0x680 <= i <= 0x6BF for i in own)
    for s in range(8):
        for o in range(s + 1, 8):
            assert not sent_by[s] & sent_by[o], (s, o, sorted(map(hex, sent_by[s] & sent_by[o])))
    ecu = Ecu()
    out = ecu.tick(1.0)
    really_sent = {m.arbitration_id for m in ecu.frames(out)}
    assert really_sent == ecu_ids
    assert not really_sent & all_ars and not any(really_sent & sent_by[s] for s in range(8))
    assert all(0x6C0 <= i <= 0x6FF for i in really_sent)


def test_every_message_times_every_sensor_id_is_unique_against_the_public_dbc(reference_dir, reference_db):
    import cantools
    ars = _ars_ids(reference_db)
    # the public DBC of sensor 1 is sensor 0's shifted by 0x10, which is the rule used above
    id1 = cantools.database.load_file(str(reference_dir / "ARS408_id1.dbc"), encoding="latin-1", strict=False)
    assert {m.frame_id for m in id1.messages} == ars[1]
    _check_plan(ars)


def test_every_message_times_every_sensor_id_is_unique_against_the_project_dbc(db):
    _check_plan(_ars_ids(db))


def test_e2e_data_id_names_the_sensor_and_the_message():
    keys = {(t, s): ids.e2e_key(t, s) for t in (ids.ROAD_BOUNDARY_LEFT, ids.ROAD_BOUNDARY_RIGHT) for s in range(8)}
    keys |= {(t, None): ids.e2e_key(t) for t in (ids.ACC_STATUS, ids.FCW_STATUS)}
    assert len(set(keys.values())) == len(keys)
    with pytest.raises(ValueError, match="sensor_id: value 8 is not allowed; expected an integer 0..7"):
        ids.own_id(ids.ROAD_BOUNDARY_LEFT, 8)
    with pytest.raises(ValueError, match="template ID: value 0x690"):
        ids.own_id(0x690, 0)


def _frames(sc, cycles: int):
    node = RadarNode(sc)
    vehicle = EgoMotionSender(node.scene, sc.radar.sensor_id)
    out = []
    for k in range(cycles):
        t = k * node.period_s
        ego = vehicle.frames(t)
        for m in ego:
            node.receive(m, t)
        out.append((ego, node.cycle(t)))
    return out


def test_a_frame_of_another_sensor_or_message_fails_the_e2e_check():
    """A boundary frame moved onto another sensor's or message's ID (a misconfigured node or gateway)."""
    sc0 = scenario(TRAFFIC_A, radar="{preset: ars408_like, sensor_id: 0}", road=_road(1.0), duration=0.5)
    sc1 = scenario(TRAFFIC_A, radar="{preset: ars408_like, sensor_id: 1}", road=_road(1.0), duration=0.5)
    (ego0, out0), = _frames(sc0, 1)
    (_, out1), = _frames(sc1, 1)
    left0, right0 = out0.messages[-2:]
    left1 = out1.messages[-2]
    asm = CycleAssembler(sensor_id=0)
    ecu = Ecu()
    acc = ecu.frames(ecu.tick(1.0))[0]

    def moved(msg, can_id):
        return can.Message(arbitration_id=can_id, data=bytes(msg.data), is_extended_id=False)

    for m in ego0 + out0.messages:
        asm.on_message_received(m)
    assert asm.stats.boundary_frames == 2 and asm.stats.e2e_errors == 0
    base = dict(asm.stats.as_dict())
    forged = [moved(left1, left0.arbitration_id),                      # sensor 1's left on sensor 0's ID
              moved(left0, right0.arbitration_id),                     # left payload on the right's ID
              moved(acc, left0.arbitration_id),                        # ECU status on a boundary ID
              moved(left0, acc.arbitration_id)]                        # a boundary on the ECU's ID
    for m in forged:
        asm.on_message_received(m)
    assert asm.stats.e2e_errors == base["e2e_errors"] + len(forged)
    assert asm.stats.boundary_frames == 2 and asm.stats.ecu_frames == 0
    # the same frames on their own IDs pass: the CRC failures above are the Data ID, not the payloads
    asm1 = CycleAssembler(sensor_id=1)
    asm1.on_message_received(left1)
    asm.on_message_received(acc)
    assert asm1.stats.boundary_frames == 1 and asm.stats.ecu_frames == 1


def _same_list(cycle, sent) -> bool:
    got = cycle.objects if isinstance(cycle, ObjectCycle) else cycle.clusters
    if len(got) != len(sent) or not np.array_equal(got.id, sent.id):
        return False
    return bool(np.allclose(got.dist_long_m, sent.dist_long_m, atol=0.1 + 1e-9)
                and np.allclose(got.dist_lat_m, sent.dist_lat_m, atol=0.1 + 1e-9))


@pytest.mark.parametrize("other, output", [(1, "objects"), (7, "clusters"), (7, "objects")])
def test_two_nodes_and_an_ecu_on_one_virtual_bus(other, output):
    """Nodes with sensor IDs 0 and ``other`` and the ECU of sensor 0 share one python-can virtual bus."""
    n_cycles = 30
    scs = {0: scenario(TRAFFIC_A, radar=f"{{preset: ars408_like, sensor_id: 0, output: {output}}}",
                       road=_road(1.0), duration=n_cycles * 0.072 + 0.1),
           other: scenario(TRAFFIC_B, radar=f"{{preset: ars408_like, sensor_id: {other}, output: {output}}}",
                           road=_road(3.0), duration=n_cycles * 0.072 + 0.1, seed=5)}
    nodes = {s: RadarNode(sc) for s, sc in scs.items()}
    vehicles = {s: EgoMotionSender(nodes[s].scene, s) for s in nodes}
    ecu = Ecu(AccSettings(set_speed_mps=30.0, time_gap_s=1.5), sensor_id=0)
    channel = f"idplan-{uuid.uuid4().hex}"
    buses = {name: can.Bus(interface="virtual", channel=channel) for name in ("tx0", "tx1", "ecu", "rx0", "rx1")}
    tx = {0: buses["tx0"], other: buses["tx1"]}
    rx = {0: buses["rx0"], other: buses["rx1"]}
    asm = {s: CycleAssembler(sensor_id=s) for s in nodes}
    sent = {s: Counter() for s in nodes}
    sent_lists = {s: [] for s in nodes}
    got = {s: [] for s in nodes}
    decisions = []

    def pump():
        for s, bus in rx.items():
            while (m := bus.recv(0.0)) is not None:
                asm[s].on_message_received(m)
            got[s] += asm[s].drain()

    try:
        for k in range(n_cycles):
            t = k * 0.072
            for s, node in nodes.items():
                ego = vehicles[s].frames(t)
                for m in ego:
                    node.receive(m, t)
                out = node.cycle(t)
                for m in ego + out.messages:
                    tx[s].send(m)
                sent[s]["frames"] += len(ego) + len(out.messages)
                sent[s]["boundary"] += 2 if out.boundaries is not None else 0
                sent_lists[s].append(out.frame.objects if output == "objects" else out.frame.clusters)
            pump()
            if got[0]:
                ecu.set_ego(t, asm[0].ego_speed_mps, asm[0].ego_yaw_rate_dps, asm[0].ego_frames)
                d = ecu.on_cycle(t, got[0][-1])
                assert d is not None
                decisions.append(d)
                for m in ecu.frames(d):
                    buses["ecu"].send(m)
                pump()
    finally:
        for bus in buses.values():
            bus.shutdown()

    ecu_frames = 2 * len(decisions)
    assert ecu_frames >= 2 * (n_cycles - 1)
    # the two nodes really sent different lists: a mix-up would show
    assert any(len(a) != len(b) or not np.allclose(a.dist_long_m, b.dist_long_m)
               for a, b in zip(sent_lists[0], sent_lists[other]))
    for s in nodes:
        o = other if s == 0 else 0
        st = asm[s].stats
        assert st.cycles == n_cycles and len(got[s]) == n_cycles
        assert all(isinstance(c, ObjectCycle if output == "objects" else ClusterCycle) for c in got[s])
        assert all(_same_list(c, ref) for c, ref in zip(got[s], sent_lists[s]))
        assert st.boundary_frames == sent[s]["boundary"] == 2 * n_cycles
        assert st.other_sensor_frames == sent[o]["frames"]              # every frame of the other node, set aside
        assert st.ecu_frames == ecu_frames                              # the ECU's frames, not a boundary among them
        assert st.e2e_errors == st.e2e_repeated == 0 and st.dropped() == 0 and st.incomplete_cycles == 0
        assert st.frames == sent[0]["frames"] + sent[other]["frames"] + ecu_frames
        # what each consumer reads as its road and as the ECU's status is what was sent
        assert asm[s].road_boundaries["left"].offset_m == pytest.approx(
            nodes[s].last_boundaries[0].offset_m, abs=0.02)
        acc = asm[s].ecu_status["AccStatus"]
        assert acc["ACC_State"] == decisions[-1].acc_state and acc["ACC_Fault"] == decisions[-1].fault
        assert decisions[-1].fault == 0                                 # its ego motion read, each cycle's
        fcw = asm[s].ecu_status["FcwStatus"]
        assert fcw["FCW_WarningLevel"] == decisions[-1].warning_level and fcw["FCW_Fault"] == decisions[-1].fault
    assert abs(asm[0].road_boundaries["left"].offset_m - asm[other].road_boundaries["left"].offset_m) > 1.5
