"""The node: frame order, status frames, RadarConfiguration, ego-motion input, saturation, bus-load budget."""

from __future__ import annotations

import dataclasses
import logging

import can
import numpy as np

from radarnode.perception.types import MEAS_PREDICTED
from radarnode.wire import ars408 as P
from radarnode.wire.busload import bus_load, frame_bits
from radarnode.wire.node import EgoMotionSender, RadarNode
from radarnode.wire.runner import SimulatedClock, run_node
from tests.helpers import scenario

TRAFFIC = """
  - {id: a, class: car, x_m: 40.0, lane: 1, speed_mps: 22.0}
  - {id: b, class: car, x_m: 80.0, lane: 2, speed_mps: 25.0}
  - {id: c, class: truck, x_m: 60.0, lane: 0, speed_mps: 18.0}
"""


def _cfg_frame(db, sensor_id=0, **fields) -> can.Message:
    msg = db.get_message_by_frame_id(P.RADAR_CFG)
    values = {s.name: 0 for s in msg.signals}
    values.update(fields)
    return can.Message(arbitration_id=P.shifted(P.RADAR_CFG, sensor_id), data=msg.encode(values),
                       is_extended_id=False)


def _cycles(node, n, start=0):
    return [node.cycle(k * node.period_s) for k in range(start, start + n)]


def test_bit_lengths():
    assert frame_bits(8, worst_case=False) == 111
    assert frame_bits(8) == 135
    assert frame_bits(0, worst_case=False) == 47
    assert bus_load([8] * 301, 500_000, 0.072) > 1.0   # 100 objects x 3 frames do not fit in 72 ms


def test_object_cycle_order_and_counters(db):
    node = RadarNode(scenario(TRAFFIC))
    outs = _cycles(node, 30)
    counters = []
    for out in outs:
        ids = [m.arbitration_id for m in out.messages]
        if ids[0] == P.RADAR_STATE:
            assert ids[1] == P.VERSION_ID
            ids = ids[2:]
        assert ids[0] == P.OBJ_STATUS
        hdr = db.decode_message(ids[0], out.messages[len(out.messages) - len(ids)].data)
        n = hdr["Obj_NofObjects"]
        counters.append(hdr["Obj_MeasCounter"])
        assert ids[1:] == [P.OBJ_GENERAL] * n + [P.OBJ_QUALITY] * n + [P.OBJ_EXTENDED] * n
        frames = out.messages[len(out.messages) - len(ids):]
        order = [[f.data[0] for f in frames[1 + g * n:1 + (g + 1) * n]] for g in range(3)]
        assert order[0] == order[1] == order[2]                  # same object order in every group
        for f in frames:
            assert len(f.data) == db.get_message_by_frame_id(f.arbitration_id).length
        ts = [m.timestamp for m in out.messages]
        assert ts == sorted(ts)
    assert counters == list(range(30))
    assert max(len(o.frame.objects) for o in outs) == 3


def test_radar_state_at_start_and_every_second():
    node = RadarNode(scenario(TRAFFIC, duration=3.0))
    times = [o.t_s for o in _cycles(node, 41) if o.messages[0].arbitration_id == P.RADAR_STATE]
    assert times[0] == 0.0
    assert np.allclose(np.diff(times), 1.0, atol=node.period_s)
    assert len(times) == 3


def test_configuration_is_applied_with_valid_bits_and_echoed(db):
    node = RadarNode(scenario(TRAFFIC))
    _cycles(node, 3)
    # OutputType without its valid bit: ignored
    node.receive(_cfg_frame(db, RadarCfg_OutputType=2), 0.2)
    assert node.config.output_type == P.OUTPUT_OBJECTS
    node.receive(_cfg_frame(db, RadarCfg_OutputType_valid=1, RadarCfg_OutputType=2, RadarCfg_SendQuality_valid=1,
                            RadarCfg_SendQuality=0, RadarCfg_MaxDistance_valid=1, RadarCfg_MaxDistance=196,
                            RadarCfg_SortIndex_valid=1, RadarCfg_SortIndex=2), 0.2)
    out = node.cycle(3 * node.period_s)
    ids = [m.arbitration_id for m in out.messages]
    assert ids[0] == P.RADAR_STATE   # echoed at once
    state = db.decode_message(P.RADAR_STATE, out.messages[0].data, decode_choices=False)
    assert state["RadarState_OutputTypeCfg"] == 2 and state["RadarState_SendQualityCfg"] == 0
    assert state["RadarState_MaxDistanceCfg"] == 196 and state["RadarState_SortIndex"] == 2
    assert P.OBJ_STATUS not in ids and P.CLUSTER_STATUS in ids and P.CLUSTER_QUALITY not in ids
    hdr = db.decode_message(P.CLUSTER_STATUS, out.messages[ids.index(P.CLUSTER_STATUS)].data)
    n = hdr["Cluster_NofClustersNear"] + hdr["Cluster_NofClustersFar"]
    assert ids.count(P.CLUSTER_GENERAL) == n > 0


def test_sensor_id_shifts_every_id(db):
    node = RadarNode(scenario(TRAFFIC))
    node.receive(_cfg_frame(db, RadarCfg_SensorID_valid=1, RadarCfg_SensorID=3), 0.0)
    out = node.cycle(0.0)
    assert {m.arbitration_id for m in out.messages} <= {0x231, 0x730, 0x63A, 0x63B, 0x63C, 0x63D}
    # the node now listens on 0x230; a frame on 0x200 is not for it
    node.receive(_cfg_frame(db, 0, RadarCfg_SendExtInfo_valid=1, RadarCfg_SendExtInfo=0), 0.1)
    assert node.config.send_ext_info
    node.receive(_cfg_frame(db, 3, RadarCfg_SendExtInfo_valid=1, RadarCfg_SendExtInfo=0), 0.1)
    assert not node.config.send_ext_info


def test_a_sensor_id_change_is_said_and_counted(db, caplog):
    """Obeyed as the ARS 408 obeys it, but not silently (an independent tester: one RadarConfiguration on the bus
    moved the node to sensor 3 with no line in its log, and the consumer of sensor 0 saw only other sensors'
    frames): a warning names both IDs and ``sensor_id_changes`` counts it; the same ID again changes nothing."""
    node = RadarNode(scenario(TRAFFIC))
    with caplog.at_level(logging.WARNING):
        node.receive(_cfg_frame(db, RadarCfg_SensorID_valid=1, RadarCfg_SensorID=3), 0.0)
        node.receive(_cfg_frame(db, 3, RadarCfg_SensorID_valid=1, RadarCfg_SensorID=3), 0.1)
    assert node.config.sensor_id == 3 and node.counters["sensor_id_changes"] == 1
    assert "SensorID 0 -> 3" in caplog.text and caplog.text.count("SensorID") == 1


def test_invalid_configuration_values_are_rejected_and_counted(db, caplog):
    node = RadarNode(scenario(TRAFFIC))
    with caplog.at_level(logging.WARNING):
        node.receive(_cfg_frame(db, RadarCfg_OutputType_valid=1, RadarCfg_OutputType=3, RadarCfg_RadarPower_valid=1,
                                RadarCfg_RadarPower=5), 0.0)
    assert node.config.output_type == P.OUTPUT_OBJECTS and node.config.radar_power == 0
    assert node.counters["config_rejected"] == 2
    assert "OutputType=3 is not allowed" in caplog.text
    node.receive(can.Message(arbitration_id=0x200, data=b"\x01\x02", is_extended_id=False), 0.0)
    assert node.counters["rx_wrong_dlc"] == 1


def test_radar_power_lowers_snr_and_detections():
    far = "\n".join(f"  - {{id: c{i}, class: car, x_m: {215 + 8 * i}.0, y_m: {6.0 * i - 12.0}, speed_mps: 20.0}}"
                    for i in range(5))
    counts = []
    for power in (0, 3):
        sc = scenario(far, radar=f"{{preset: ars408_like, radar_power: {power}}}", road="{lanes: 9, ego_lane: 4}",
                      duration=4.0)
        node = RadarNode(sc)
        # objects measured this cycle (not coasting): the detections behind the object list
        counts.append(sum(int((o.frame.objects.meas_state != MEAS_PREDICTED).sum()) for o in _cycles(node, 50)))
    assert counts[0] > 150 and counts[1] < 0.8 * counts[0]


def test_motion_rx_state(db):
    node = RadarNode(scenario(TRAFFIC))
    assert node.motion_rx_state(0.0) == 3
    sender = EgoMotionSender(node.scene)
    speed, yaw = sender.frames(0.0)
    node.receive(speed, 0.0)
    assert node.motion_rx_state(0.1) == 2
    node.receive(yaw, 0.1)
    assert node.motion_rx_state(0.2) == 0
    assert node.motion_rx_state(5.0) == 3          # stale input is missing input
    out = node.cycle(0.2)
    assert db.decode_message(P.RADAR_STATE, out.messages[0].data)["RadarState_MotionRxState"] == "Input ok"
    fresh = RadarNode(scenario(TRAFFIC))
    state = db.decode_message(P.RADAR_STATE, fresh.cycle(0.0).messages[0].data)
    assert state["RadarState_MotionRxState"] == "Speed and yaw rate missing"


def test_out_of_range_values_are_saturated_and_counted(db):
    sc = scenario("  - {id: fast, class: car, x_m: 40.0, lane: 1, speed_mps: 0.0, heading_deg: 180.0}",
                  ego="{speed_mps: 70.0}",
                  # a sensor specified to −200 m/s (its staggered ramps resolve 273 m/s): VrelLong must saturate
                  radar="{preset: ars408_like, overrides: {max_range_m: 250.0, min_range_rate_mps: -200.0}}")
    node = RadarNode(sc)
    # closing speed 70 m/s is within VrelLong's -128..127.75; make it overflow with a wrong-way car
    sc2 = dataclasses.replace(sc, actors=(dataclasses.replace(sc.actors[0], speed_mps=70.0),))
    node = RadarNode(sc2)
    outs = _cycles(node, 5)
    assert node.saturated["Obj_VrelLong"] > 0
    vrel = [db.decode_message(m.arbitration_id, m.data)["Obj_VrelLong"] for o in outs for m in o.messages
            if m.arbitration_id == P.OBJ_GENERAL]
    assert min(vrel) == -128.0


def test_bus_load_budget_drops_the_farthest_objects(caplog):
    many = "\n".join(f"  - {{id: c{i}, class: car, x_m: {20 + 2.5 * i}, y_m: {(i % 9 - 4) * 1.5}, "
                     f"speed_mps: 20.0}}" for i in range(60))
    sc = scenario(many, radar="{preset: ars408_like, bus_load_limit: 0.06}", road="{lanes: 9, ego_lane: 4}")
    node = RadarNode(sc)
    with caplog.at_level(logging.WARNING):
        outs = _cycles(node, 5)
    assert node.counters["objects_dropped_busload"] > 0
    assert caplog.text.count("does not fit") == 1          # warned once
    for o in outs:
        assert o.bits <= 0.06 * 500_000 * node.period_s + 1
    # the objects kept are the nearest ones the model reported
    model_ranges = np.hypot(node.model.state[:, 0], node.model.state[:, 1])[node.model.alive]
    kept = np.sort(outs[-1].frame.objects.range_m)
    assert outs[-1].objects_dropped > 0 and len(kept) > 0
    np.testing.assert_allclose(kept, np.sort(model_ranges)[:len(kept)])


def test_same_scenario_and_seed_give_identical_frames():
    def frames(seed):
        node = RadarNode(scenario(TRAFFIC, seed=seed))
        out = []
        run_node(node, clock=SimulatedClock(), sinks=[out.append], vehicle=EgoMotionSender(node.scene))
        return [(m.arbitration_id, bytes(m.data), m.timestamp) for m in out]
    a, b, c = frames(5), frames(5), frames(6)
    assert a == b
    assert a != c


def _status_neighbours(ids: list[int]) -> tuple[set, set, int]:
    """Around each RadarState of a sequence of sensor frame IDs: the frames right before it, the two after it,
    and how many there are."""
    before, after = set(), set()
    at = [i for i, x in enumerate(ids) if x == P.RADAR_STATE]
    for i in at:
        before.add(ids[i - 1] if i else None)
        after.add(tuple(ids[i + 1:i + 3]))
    return before, after, len(at)


def test_status_frames_go_before_a_header_as_in_the_capture(reference_dir):
    """RadarState and VersionID go out once a second between two cycles: after the last frame of one cycle's
    last group, right before the next header — never inside a group. Checked on the capture, then on radarnode
    in simulated time."""
    capture = [(m.timestamp, m.arbitration_id) for m in can.LogReader(str(reference_dir / "candump-ars408-parked.log"))]
    ids = [i for _, i in capture]
    before, after, n = _status_neighbours(ids)
    follow = [ids[i + 1:i + 3] for i, x in enumerate(ids) if x == P.RADAR_STATE]
    # the capture's pattern: 0x201, 0x700, then the header, in all but one of its 38 seconds
    assert n >= 30 and sum(f == [P.VERSION_ID, P.OBJ_STATUS] for f in follow) >= n - 1
    stamps = [t for t, i in capture if i == P.RADAR_STATE]
    assert np.allclose(np.diff(stamps), 1.0, atol=0.01)

    node = RadarNode(scenario(TRAFFIC, duration=4.0))
    frames = []
    run_node(node, clock=SimulatedClock(), sinks=[frames.append], vehicle=EgoMotionSender(node.scene))
    sensor_ids = {P.RADAR_STATE, P.VERSION_ID, P.OBJ_STATUS, P.OBJ_GENERAL, P.OBJ_QUALITY, P.OBJ_EXTENDED}
    ours = [m.arbitration_id for m in frames if m.arbitration_id in sensor_ids]
    before, after, n = _status_neighbours(ours)
    assert n == 4
    assert after == {(P.VERSION_ID, P.OBJ_STATUS)}
    # the frame before is the last of the previous cycle's last group (or nothing, at the start)
    assert before <= {None, P.OBJ_EXTENDED}
    times = [m.timestamp for m in frames if m.arbitration_id == P.RADAR_STATE]
    assert np.allclose(np.diff(times), 1.0, atol=node.period_s)


def test_the_vehicles_ego_motion_follows_the_node_when_a_radar_configuration_moves_its_sensor_id():
    """An independent tester's finding: ``node --send-ego-motion`` kept sending 0x300/0x301 at the old sensor ID after
    a RadarConfiguration moved the node to another, so the node no longer heard them and went to MotionRxState 3
    (speed and yaw rate missing) two seconds later, its DynProp wrong for the rest of the run."""
    from radarnode.wire.group import ego_motion_for
    sc = scenario("  - {id: lead, class: car, x_m: 40.0, lane: 0, speed_mps: 20.0}\n", duration=4.0)
    from radarnode.wire.dbc import load_database
    node = RadarNode(sc, fidelity="object")
    db = load_database()
    vehicle = ego_motion_for(node)
    assert {m.arbitration_id for m in vehicle.frames(0.0)} == {0x300, 0x301}
    node.receive(_cfg_frame(db, RadarCfg_SensorID_valid=1, RadarCfg_SensorID=6), 0.0)
    for k in range(1, 50):                            # 3.5 s: past the node's motion time-out
        t = k * sc.period_s
        frames = vehicle.frames(t)
        assert {m.arbitration_id for m in frames} == {0x360, 0x361}
        for m in frames:
            node.receive(m, t)
        node.cycle(t)
    assert node.motion_rx_state(49 * sc.period_s) == 0
