"""Several radars on one bus (issue 11 item 2): a scenario's ``radars`` list, one node per radar driven by one scene
and one clock, the consumer decoding every sensor and fusing their object lists in the vehicle frame."""

from __future__ import annotations

import dataclasses
import math

import can
import numpy as np
import pytest

from radarnode.cli.main import main
from radarnode.consumer.assembler import CycleAssembler
from radarnode.consumer.fusion import FusingConsumer, ObjectFusion
from radarnode.consumer.path import SensorMount
from radarnode.errors import ScenarioError
from radarnode.perception.types import ObjectList
from radarnode.radar.setup import load_scenario, parse_scenario, radar_scenarios
from radarnode.wire import ars408 as P
from radarnode.wire.group import RadarGroup, ego_motion_for, make_node
from radarnode.wire.node import RadarNode
from radarnode.wire.runner import SimulatedClock, run_node
from tests.conftest import SCENARIOS
from tests.helpers import can_unshare, node_and_consumer_over_multicast

THREE = """
name: three
duration_s: {duration}
seed: 4
radars:
  - {{preset: ars408_like, sensor_id: 0, mount: {{x_m: 3.7, y_m: 0.0, yaw_deg: 0.0}}}}
  - {{preset: srr_corner, sensor_id: 1, mount: {{x_m: 3.5, y_m: 0.73, yaw_deg: 45.0}}}}
  - {{preset: srr_corner, sensor_id: 2, mount: {{x_m: 3.5, y_m: -0.73, yaw_deg: -45.0}}}}
ego: {{speed_mps: 6.0}}
road: {{lanes: 2, lane_width_m: 3.5, ego_lane: 0}}
actors:
  - {{id: car, class: car, x_m: 18.0, y_m: 0.0, speed_mps: 6.0}}
"""


def _frames(sc, fidelity=None):
    node = make_node(sc, fidelity=fidelity)
    frames, outs = [], []
    run_node(node, clock=SimulatedClock(), sinks=[frames.append], vehicle=ego_motion_for(node),
             on_cycle=outs.append)
    return node, frames, outs


def _mounts(sc):
    return {r.sensor_id: SensorMount.of(r.mount) for r in sc.sensors}


def _fused(sc, frames):
    fc = FusingConsumer(_mounts(sc))
    rounds = list(fc.feed(frames))
    fc.flush()
    return fc, rounds + fc.drain()


# --- the scenario -------------------------------------------------------------------------------------------


def test_radars_list_gives_every_radar_its_setup_and_a_seed_of_its_own():
    sc = parse_scenario(THREE.format(duration=1.0))
    assert [r.sensor_id for r in sc.sensors] == [0, 1, 2]
    assert sc.radar == sc.radars[0]
    per = radar_scenarios(sc)
    assert [s.radar.preset for s in per] == ["ars408_like", "srr_corner", "srr_corner"]
    assert per[0].seed == sc.seed and len({s.seed for s in per}) == 3
    assert all(s.period_s == sc.period_s for s in per)          # one clock


@pytest.mark.parametrize("edit, message", [
    (("sensor_id: 1,", "sensor_id: 0,"), r"radars\[1\]\.sensor_id': value 0 is not allowed; expected a sensor ID no "
                                         r"other radar uses \(radars\[0\] has 0;"),
    (("sensor_id: 2, mount", "sensor_id: 2, bitrate: 250000, mount"),
     r"radars\[2\]\.bitrate': value 250000 is not allowed; expected 500000 \(radars\[0\]\.bitrate\): the radars "
     r"share one bus"),
    (("preset: srr_corner, sensor_id: 2", "preset: srr_cornr, sensor_id: 2"), r"radars\[2\]\.preset': value "
                                                                              r"'srr_cornr' is not allowed"),
    (("ego:", "radar: {preset: mimo12}\nego:"), r"field 'radar'.*either 'radar' \(one radar\) or 'radars'"),
    (("yaw_deg: 45.0", "yaw_deg: .nan"), r"radars\[1\]\.mount\.yaw_deg"),
])
def test_bad_radars_are_refused_with_the_field_named(edit, message):
    with pytest.raises(ScenarioError, match=message):
        parse_scenario(THREE.format(duration=1.0).replace(*edit, 1))


# --- the nodes on one bus -----------------------------------------------------------------------------------


def test_every_radar_is_its_own_node_with_its_shifted_ids_and_none_collide():
    sc = parse_scenario(THREE.format(duration=1.5))
    node, frames, outs = _frames(sc)
    assert isinstance(node, RadarGroup) and len(outs) == sc.num_cycles
    by_sensor = {}
    for m in frames:
        for sid in (0, 1, 2):
            base = m.arbitration_id - 0x10 * sid
            if base in (P.OBJ_STATUS, P.RADAR_STATE, P.SPEED_INFO):
                by_sensor.setdefault(sid, set()).add(m.arbitration_id)
    assert by_sensor[1] == {P.OBJ_STATUS + 0x10, P.RADAR_STATE + 0x10, P.SPEED_INFO + 0x10}
    # each sensor's consumer takes its own cycles, every one of them, and counts the others' frames as not its own
    for sid in (0, 1, 2):
        a = CycleAssembler(sensor_id=sid)
        cycles = list(a.feed(frames))
        assert len(cycles) == sc.num_cycles and a.stats.dropped() == 0
        assert [c.meas_counter for c in cycles] == list(range(sc.num_cycles))
    # in each cycle sensor 1's frames follow sensor 0's on the wire, timestamps never go back
    stamps = [m.timestamp for m in frames]
    assert all(b >= a for a, b in zip(stamps, stamps[1:]))


@pytest.mark.parametrize("asked, moves", [(0, False), (2, False), (1, False), (5, True)])
def test_a_radar_configuration_moves_a_radar_of_a_group_only_to_a_free_sensor_id(asked, moves):
    """A RadarConfiguration 0x200 + 0x10 with SensorID valid to sensor 1 of a group of three (0, 1, 2): the ID of
    another radar of the group is refused (config_rejected, RadarState_Temporary_Error set, the ID in force echoed) —
    it had been taken at once, and two radarnode nodes sent every message on the same CAN IDs (an independent
    tester's finding: also from random bytes on 0x200); its own ID changes nothing; a free one moves it, and its
    frames go out on the new IDs from the next cycle, none of them on another radar's."""
    sc = parse_scenario(THREE.format(duration=1.5))
    group = make_node(sc)
    db = group.nodes[1].db
    m = db.get_message_by_frame_id(P.RADAR_CFG)
    values = {sig.name: 0 for sig in m.signals}
    values.update(RadarCfg_SensorID_valid=1, RadarCfg_SensorID=asked)
    outs = []
    for k in range(4):
        if k == 2:
            group.receive(can.Message(arbitration_id=P.shifted(P.RADAR_CFG, 1), data=m.encode(values),
                                      is_extended_id=False), k * group.period_s)
        outs.append(group.cycle(k * group.period_s))
    out = outs[-1]
    assert group.sensor_ids == ([0, asked, 2] if moves else [0, 1, 2])
    rejected = group.nodes[1].counters["config_rejected"]
    assert rejected == int(asked in (0, 2))
    # the answer goes out with the cycle the configuration came before
    state = next(db.decode_message(P.RADAR_STATE, x.data, decode_choices=False) for x in outs[2].outputs[1].messages
                 if x.arbitration_id - 0x10 * group.sensor_ids[1] == P.RADAR_STATE)
    assert state["RadarState_SensorID"] == group.sensor_ids[1]
    assert bool(state["RadarState_Temporary_Error"]) == bool(rejected)
    ids = [{x.arbitration_id for x in o.messages} - {P.COLL_DET_RELAY} for o in out.outputs]
    assert not (ids[0] & ids[1] or ids[1] & ids[2] or ids[0] & ids[2])
    assert P.shifted(P.OBJ_STATUS, group.sensor_ids[1]) in ids[1]


def test_adding_radars_does_not_change_the_first_radars_frames():
    from radarnode.wire.node import EgoMotionSender
    sc = parse_scenario(THREE.format(duration=1.5))
    alone = dataclasses.replace(sc, radars=(), radar=sc.radars[0])
    _, multi, _ = _frames(sc)
    node = RadarNode(alone)
    single = []
    run_node(node, clock=SimulatedClock(), sinks=[single.append], vehicle=EgoMotionSender(node.scene, 0))
    ids0 = {m.arbitration_id for m in single}
    mine = [m for m in multi if m.arbitration_id in ids0]
    assert len(single) > 100
    assert [(m.arbitration_id, bytes(m.data)) for m in mine] == [(m.arbitration_id, bytes(m.data)) for m in single]


def test_same_scenario_and_seed_give_the_same_frames():
    sc = parse_scenario(THREE.format(duration=1.0))
    _, a, _ = _frames(sc)
    _, b, _ = _frames(sc)
    assert [(m.arbitration_id, bytes(m.data), m.timestamp) for m in a] == \
        [(m.arbitration_id, bytes(m.data), m.timestamp) for m in b]


def test_closed_loop_drives_one_ego_for_every_radar():
    from radarnode.consumer.evaluate import EgoActuator
    sc = parse_scenario(THREE.format(duration=1.0))
    node = make_node(sc)
    act = EgoActuator(node.scene, 0.2, 6.0)
    act.at(0.0)
    node.cycle(0.0)
    assert all(n.scene._ego is node.scene._ego for n in node.nodes)


# --- fusion -------------------------------------------------------------------------------------------------


def _objects(x, y, vx=0.0, vy=0.0, ids=None, sigma=0.2):
    n = len(x)
    nan = np.full(n, np.nan)
    f = lambda v: np.asarray(v, dtype=np.float64)   # noqa: E731
    return ObjectList(id=np.arange(n) if ids is None else np.asarray(ids), dist_long_m=f(x), dist_lat_m=f(y),
                      vrel_long_mps=f(np.broadcast_to(vx, (n,))), vrel_lat_mps=f(np.broadcast_to(vy, (n,))),
                      dyn_prop=np.zeros(n, dtype=np.int64), rcs_dbsm=np.full(n, 10.0),
                      dist_long_sigma_m=np.full(n, sigma), dist_lat_sigma_m=np.full(n, sigma),
                      vrel_long_sigma_mps=np.full(n, 0.1), vrel_lat_sigma_mps=np.full(n, 0.5),
                      arel_long_sigma_mps2=nan, arel_lat_sigma_mps2=nan, orientation_sigma_rad=nan,
                      meas_state=np.ones(n, dtype=np.int64), prob_of_exist=np.full(n, 7),
                      arel_long_mps2=nan, arel_lat_mps2=nan, obj_class=np.ones(n, dtype=np.int64),
                      orientation_rad=nan, length_m=np.full(n, 4.0), width_m=np.full(n, 1.8),
                      actor_index=np.full(n, -1))


def _in_sensor(mount: SensorMount, xv, yv):
    """Vehicle-frame points in a sensor's frame (the inverse of SensorMount.to_vehicle)."""
    c, s = math.cos(math.radians(mount.yaw_deg)), math.sin(math.radians(mount.yaw_deg))
    dx, dy = np.asarray(xv) - mount.x_m, np.asarray(yv) - mount.y_m
    return c * dx + s * dy, -s * dx + c * dy


def test_one_object_seen_by_two_turned_radars_is_one_fused_object_where_it_is():
    m0, m1 = SensorMount(3.7, 0.0, 0.0), SensorMount(3.5, 0.73, 45.0)
    fusion = ObjectFusion({0: m0, 1: m1})
    truth = np.array([[12.0, 4.0], [20.0, -1.0]])
    x0, y0 = _in_sensor(m0, truth[:, 0], truth[:, 1])
    x1, y1 = _in_sensor(m1, truth[:1, 0], truth[:1, 1])                 # sensor 1 sees only the first
    out = fusion.step(0.0, {0: (0.0, _objects(x0, y0)), 1: (0.0, _objects(x1, y1, ids=[7]))})
    assert len(out) == 2
    k = int(np.argmin(np.hypot(out.x_m - 12.0, out.y_m - 4.0)))
    assert abs(out.x_m[k] - 12.0) < 1e-9 and abs(out.y_m[k] - 4.0) < 1e-9
    assert out.sensors[k] == 0b11 and out.sensors[1 - k] == 0b01
    # two looks of 0.2 m each: the fused σ is 0.2/√2
    assert abs(out.sigma_x_m[k] - 0.2 / math.sqrt(2)) < 1e-6


def test_fused_ids_stay_while_an_object_passes_from_one_radar_to_another():
    """A car crossing in front: the right corner radar, then the front one, then the left; one fused ID."""
    sc = load_scenario(SCENARIOS / "intersection_crossing.yaml")
    _, frames, outs = _frames(sc)
    _, rounds = _fused(sc, frames)
    assert len(rounds) == sc.num_cycles
    ids = {int(i) for _, f in rounds for i in f.id[f.sensors > 0]}
    seen_by = [int(s) for _, f in rounds for s in f.sensors[f.sensors > 0]]
    assert ids == {0}                                                  # one object, one fused ID all along
    # every radar takes part, one alone at times and several together at the hand-overs (each sees the part of the
    # car inside its own sectors: the left corner radar shares it with the front one all the while it sees it)
    bits = set(seen_by)
    assert all(any(s & b for s in bits) for b in (0b001, 0b010, 0b100)), bits
    assert any(bin(s).count("1") == 1 for s in bits) and any(bin(s).count("1") >= 2 for s in bits), bits
    # against the truth (vehicle frame: the sensor-0 view plus the mount), within a car's half length
    m0 = sc.radars[0].mount
    errs = []
    for (_, f), out in zip(rounds, outs):
        if len(f) and f.sensors[0] and out.view.range_m[0] < 25.0:
            errs.append(math.hypot(f.x_m[0] - (out.view.x_m[0] + m0.x_m), f.y_m[0] - out.view.y_m[0]))
    assert len(errs) > 20 and np.median(errs) < 2.5


def test_fusion_keeps_going_when_a_radar_falls_silent_and_ignores_strangers_duplicates_and_reordering():
    sc = load_scenario(SCENARIOS / "intersection_crossing.yaml")
    _, frames, _ = _frames(sc)
    _, clean = _fused(sc, frames)
    t_cut = 2.0
    # sensor 1 (left corner) falls silent after 2 s; a stranger (sensor 5, radarnode's own IDs) talks; every
    # frame arrives twice; RadarState and VersionID swap places with their neighbours
    messy = []
    for m in frames:
        if (m.arbitration_id & 0xFF0) in (0x610, 0x210, 0x710, 0x310) and m.timestamp > t_cut:
            continue
        messy += [m, m]
        if m.arbitration_id == P.OBJ_STATUS:
            messy.append(can.Message(arbitration_id=P.OBJ_STATUS + 0x50, data=m.data, timestamp=m.timestamp,
                                     is_extended_id=False))
    for i in range(len(messy) - 1):            # each RadarState arrives after the frame that followed it
        if messy[i].arbitration_id in (P.RADAR_STATE, P.RADAR_STATE + 0x20) and \
                messy[i + 1].arbitration_id not in (P.RADAR_STATE, P.RADAR_STATE + 0x20):
            messy[i], messy[i + 1] = messy[i + 1], messy[i]
    fc, rounds = _fused(sc, messy)
    assert abs(len(rounds) - len(clean)) <= 2
    late = [f for _, f in rounds if f.t_s > t_cut + 0.5]
    assert late and all(not (s & 0b010) for f in late for s in f.sensors)     # no word from sensor 1 …
    assert any(len(f) for f in late)                                        # … yet the fused list goes on
    assert all(fc.stats[sid].as_dict()["duplicate_frames"] > 0 for sid in (0, 2))       # counted, not used twice
    assert fc.stats[0].as_dict()["lost_cycles"] == 0


# --- the commands -------------------------------------------------------------------------------------------


def test_run_prints_the_fused_list(capsys):
    rc = main(["run", str(SCENARIOS / "front_and_corners.yaml"), "--fast", "--every", "20"])
    out = capsys.readouterr().out
    assert rc == 0
    assert "ars408_like (sensor 0), srr_corner (sensor 1), srr_corner (sensor 2)" in out
    assert "fused t=" in out and "0,1,2" in out                             # the overtaker seen by all three


def test_log_then_decode_fuse(tmp_path, capsys):
    log = tmp_path / "x.blf"
    assert main(["log", str(SCENARIOS / "front_and_corners.yaml"), "-o", str(log)]) == 0
    capsys.readouterr()
    assert main(["decode", str(log), "--fuse", str(SCENARIOS / "front_and_corners.yaml"), "--summary"]) == 0
    out = capsys.readouterr().out
    assert "sensor 1: consumer:" in out and "fused: 111 rounds" in out
    assert "seen by several sensors: 1" in out or "seen by several sensors: 2" in out
    assert main(["decode", str(log), "--sensor-id", "2", "--summary"]) == 0
    assert "object_cycles=111" in capsys.readouterr().out
    assert main(["decode", str(log), "--fuse", str(SCENARIOS / "front_and_corners.yaml"), "--format", "json"]) == 2
    assert "option --fuse: not allowed with --format json" in capsys.readouterr().err
    assert main(["decode", str(log), "--fuse", str(tmp_path / "none.yaml")]) == 1
    assert "none.yaml" in capsys.readouterr().err


@pytest.mark.skipif(not can_unshare(), reason="udp_multicast traffic is kept inside a private network namespace "
                    "(unshare -n, needs root and iproute2) so it never leaves this machine; not available here")
def test_three_radar_nodes_and_a_fusing_consumer_in_two_processes(tmp_path):
    import json
    scen = SCENARIOS / "intersection_crossing.yaml"
    out = node_and_consumer_over_multicast(tmp_path, "239.74.163.3", f"{scen} --duration 3.0 --send-ego-motion",
                                           f"--fuse {scen} --json --count 30 --timeout 20", "fused.jsonl")
    lines = [json.loads(x) for x in out.splitlines()]
    # the node sends 41 cycles in real time and the consumer stops at 30 fused rounds; on a loaded machine (a full test
    # run beside two benchmarks, load 4.6) it printed 15 (not traced further: both processes starved of a core)
    assert len(lines) >= 10 and all(x["type"] == "fused_objects" for x in lines)
    seen = {s for x in lines for o in x["objects"] for s in o["sensors"]}
    assert {0, 2} <= seen                                   # the front and the right corner radar, over the bus
    assert "sensor 1: consumer:" in (tmp_path / "consume.err").read_text()


def test_report_gives_the_ecu_the_fused_list(capsys):
    """front_and_corners: ACC follows the lead and never the overtaker in the fused list; widen the path to 4.5 m
    and the overtaker beside the ego — which only the left corner radar sees there — becomes ACC's target."""
    from radarnode.consumer.evaluate import simulate
    sc = load_scenario(SCENARIOS / "front_and_corners.yaml")
    res = simulate(sc)
    assert res.passed, res.reasons
    wide = dataclasses.replace(sc, ecu=dataclasses.replace(sc.ecu, path_half_width_m=4.5))
    res = simulate(wide)
    over = [a.id for a in sc.actors].index("overtaker")
    first = int(np.flatnonzero(res.trace["target"] == over)[0])
    t = res.trace["t"][first]
    node = make_node(sc)
    view = node.nodes[0].scene.view(t)
    # where the overtaker is when ACC first takes it: beside the front radar, outside its field of view
    from radarnode.radar.object_model import in_fov
    assert not res.passed and not in_fov(node.nodes[0].preset, view.range_m, view.azimuth_rad)[over]


def test_two_tracks_of_one_object_merge_but_two_cars_side_by_side_do_not():
    m0, m1 = SensorMount(0.0, 0.0, 0.0), SensorMount(0.0, 0.0, 0.0)
    fusion = ObjectFusion({0: m0, 1: m1})
    ids = []
    # sensor 1 first reports the object 6 m off (beyond the gate: a track of its own), then converges onto it
    for k, off in enumerate([6.0, 4.0, 1.0, 0.6, 0.5, 0.4, 0.3, 0.3]):
        out = fusion.step(0.072 * k, {0: (0.072 * k, _objects([20.0], [0.0])),
                                      1: (0.072 * k, _objects([20.0], [off], ids=[5]))})
        ids.append(out.id.tolist())
    assert len(ids[0]) == 2 and len(ids[-1]) == 1                    # two tracks first, merged at the end
    assert ids[-1][0] in ids[0]                                      # into one of the two, its ID kept
    fusion = ObjectFusion({0: m0, 1: m1})
    for k in range(12):                                              # two cars 3.5 m apart, one sensor each
        out = fusion.step(0.072 * k, {0: (0.072 * k, _objects([20.0], [0.0])),
                                      1: (0.072 * k, _objects([20.0], [3.5]))})
    assert len(out) == 2 and sorted(np.round(out.y_m, 6).tolist()) == [0.0, 3.5]


def _oriented(objs: ObjectList, heading_deg: float, sigma_deg: float) -> ObjectList:
    objs.orientation_rad = np.full(len(objs), math.radians(heading_deg))
    objs.orientation_sigma_rad = np.full(len(objs), math.radians(sigma_deg))
    return objs


@pytest.mark.parametrize("track_sigma_deg, object_sigma_deg, fused", [(2.0, 40.0, True), (30.0, 1.0, False)])
def test_the_cap_across_follows_the_better_known_orientation(track_sigma_deg, object_sigma_deg, fused):
    """A crossing car (heading 90°, along the vehicle's y): radar 0's point and radar 1's lie 2 m apart along it,
    which its extent allows. Radar 1 reports the car at 0°: taken at its word the 2 m are across the car, beyond
    the 1.5 m cap. The pair is judged by whichever orientation has the smaller σ, as each radar reports it."""
    m = SensorMount(0.0, 0.0, 0.0)
    fusion = ObjectFusion({0: m, 1: m})
    out = fusion.step(0.0, {0: (0.0, _oriented(_objects([20.0], [0.0], vy=5.0), 90.0, track_sigma_deg)),
                            1: (0.0, _oriented(_objects([20.0], [2.0], vy=5.0, ids=[4]), 0.0, object_sigma_deg))})
    assert len(out) == (1 if fused else 2)


@pytest.mark.parametrize("lat_sigma_mps, merged", [(0.1, False), (2.0, True)])
def test_two_tracks_whose_velocities_differ_merge_only_within_their_sigma(lat_sigma_mps, merged):
    """Radar 1 first sees the car 6 m off (a track of its own), then comes within 1.2 m of radar 0's point — closer than
    the association gate but not within 1 (the merge rule before issue 10's glint) — and 3 m/s apart in lateral speed:
    a radar tracking a car beside it from glinting reflections. Merged when that is within their σ, never when not."""
    m = SensorMount(0.0, 0.0, 0.0)
    fusion = ObjectFusion({0: m, 1: m})
    for k, off in enumerate([6.0, 4.8, 3.6, 2.4] + [1.2] * 6):      # converging: radar 1's object keeps its track
        a, b = _objects([20.0], [0.0], vy=0.0), _objects([20.0], [off], vy=3.0, ids=[5])
        a.vrel_lat_sigma_mps[:] = b.vrel_lat_sigma_mps[:] = lat_sigma_mps
        out = fusion.step(0.072 * k, {0: (0.072 * k, a), 1: (0.072 * k, b)})
    assert len(out) == (1 if merged else 2)


def test_a_second_object_of_one_radar_beside_a_fused_track_is_a_second_fused_object():
    """The radar says two (a pedestrian stepping out beside a stopped car): the fusion does not swallow it."""
    fusion = ObjectFusion({0: SensorMount(0.0, 0.0, 0.0)})
    for k in range(6):
        objs = _objects([20.0], [0.0], ids=[1]) if k < 3 else _objects([20.0, 21.0], [0.0, 0.4], ids=[1, 2])
        out = fusion.step(0.072 * k, {0: (0.072 * k, objs)})
    assert len(out) == 2 and sorted(m[0] for m in out.members) == [1, 2]


def test_adjacent_lane_cars_each_seen_by_another_radar_stay_two_however_loose_their_sigma():
    m = SensorMount(0.0, 0.0, 0.0)
    for spacing in (2.0, 2.5, 3.0):
        fusion = ObjectFusion({0: m, 1: m})
        for k in range(6):
            out = fusion.step(0.072 * k, {0: (0.072 * k, _objects([30.0], [0.0], sigma=1.0)),
                                          1: (0.072 * k, _objects([30.0], [spacing], sigma=1.0))})
        assert len(out) == 2, spacing


def test_fusion_refuses_what_cannot_be_fused_and_restarts_after_a_gap():
    m = SensorMount(0.0, 0.0, 0.0)
    fusion = ObjectFusion({0: m, 1: m})
    good = _objects([20.0], [1.0])
    for k in range(3):
        out = fusion.step(0.072 * k, {0: (0.072 * k, good), 1: (0.072 * k, good)})
    fid = int(out.id[0])
    # a NaN time: refused, the tracks as they were
    out = fusion.step(float("nan"), {0: (0.3, good)})
    assert fusion.bad_times == 1 and out.id.tolist() == [fid]
    # a NaN position from one radar and an infinite σ from the other: left out, the track goes on, no NaN
    bad = _objects([float("nan")], [1.0])
    inf_sigma = _objects([20.0], [1.0], sigma=float("inf"))
    out = fusion.step(0.3, {0: (0.3, bad), 1: (0.3, inf_sigma)})
    assert fusion.bad_objects == 2 and np.isfinite(out.x_m).all() and out.id.tolist() == [fid]
    out = fusion.step(0.372, {0: (0.372, good), 1: (0.372, good)})
    assert out.id.tolist() == [fid] and abs(out.x_m[0] - 20.0) < 1e-6
    # a list 10 s old is stale; a fusion 600 s later restarts (no track coasts 600 s of its old velocity)
    fusion.step(0.444, {0: (0.444, good), 1: (-9.6, good)})
    assert fusion.stale_lists == 1
    out = fusion.step(600.0, {0: (600.0, _objects([50.0], [0.0]))})
    assert fusion.restarts == 1 and len(out) == 1 and abs(out.x_m[0] - 50.0) < 1e-6 and out.id[0] != fid


def test_a_radar_in_cluster_mode_closes_its_rounds_on_time_and_is_counted_not_fused():
    sc = parse_scenario(THREE.format(duration=1.0).replace("sensor_id: 2, mount", "sensor_id: 2, output: clusters, "
                                                                                   "mount"))
    _, frames, outs = _frames(sc)
    fc, rounds = _fused(sc, frames)
    assert len(rounds) == len(outs) and fc.cluster_lists == len(outs)
    # every round closes within its own cycle: the fusion time is the cycle's, not the next one's
    assert all(abs(f.t_s - o.t_s) < 0.05 for (_, f), o in zip(rounds, outs))


def test_report_takes_a_cluster_list_radar(capsys):
    """A single radar sending cluster lists: the ECU follows on the clusters (it was given nothing before)."""
    from radarnode.consumer.evaluate import simulate
    sc = load_scenario(SCENARIOS / "acc_follow_90.yaml")
    sc = dataclasses.replace(sc, radar=dataclasses.replace(sc.radar, output="clusters"))
    res = simulate(sc)
    assert res.passed, res.reasons


def test_decode_fuse_says_which_sensor_of_the_scenario_sent_nothing(tmp_path, capsys):
    sc = parse_scenario(THREE.format(duration=0.5))
    _, frames, _ = _frames(sc)
    log = tmp_path / "x.asc"
    with can.ASCWriter(str(log)) as w:
        for m in frames:
            if (m.arbitration_id & 0xFF0) not in (0x620, 0x220, 0x720, 0x320):     # sensor 2 silent
                w.on_message_received(m)
    scen = tmp_path / "three.yaml"
    scen.write_text(THREE.format(duration=0.5))
    assert main(["decode", str(log), "--fuse", str(scen), "--summary"]) == 0
    err = capsys.readouterr().err
    assert f"warning: sensor 2 of --fuse {scen} sent no cycle in {log}\n" in err
    # a scenario whose radars are other sensor IDs than the log's: each warning names the IDs the log holds
    moved = tmp_path / "moved.yaml"
    moved.write_text(THREE.format(duration=0.5).replace("sensor_id: 1", "sensor_id: 5").replace("sensor_id: 2",
                                                                                                "sensor_id: 6"))
    assert main(["decode", str(log), "--fuse", str(moved), "--summary"]) == 0
    err = capsys.readouterr().err
    for sid in (5, 6):
        assert (f"warning: sensor {sid} of --fuse {moved} sent no cycle in {log} (the log holds frames of sensor ID 1, "
                "which it has no radar for)") in err, err


@pytest.mark.parametrize("gap_s, restarts", [(0.9, 0), (1.0, 0), (1.1, 1), (2.0, 1)])
def test_a_gap_restarts_the_tracks_only_beyond_a_second(gap_s, restarts):
    fusion = ObjectFusion({0: SensorMount(0.0, 0.0, 0.0)})
    first = fusion.step(0.0, {0: (0.0, _objects([20.0], [0.0]))})
    out = fusion.step(gap_s, {0: (gap_s, _objects([20.0], [0.0]))})
    assert fusion.restarts == restarts
    assert (out.id[0] == first.id[0]) == (restarts == 0)


@pytest.mark.parametrize("age_s, stale", [(0.9, 0), (1.0, 0), (1.1, 1), (2.0, 1)])
def test_a_list_older_than_a_second_is_stale(age_s, stale):
    fusion = ObjectFusion({0: SensorMount(0.0, 0.0, 0.0), 1: SensorMount(0.0, 0.0, 0.0)})
    out = fusion.step(5.0, {0: (5.0, _objects([20.0], [0.0])), 1: (5.0 - age_s, _objects([40.0], [0.0]))})
    assert fusion.stale_lists == stale and len(out) == 2 - stale


@pytest.mark.parametrize("across_m, fused", [(1.4, True), (1.5, True), (1.6, False), (3.0, False)])
def test_two_radars_objects_are_one_only_within_the_cap_across_the_heading(across_m, fused):
    """σ 1 m: by the covariances alone every spacing here would be one object; the 1.5 m cap across decides."""
    m = SensorMount(0.0, 0.0, 0.0)
    fusion = ObjectFusion({0: m, 1: m})
    out = fusion.step(0.0, {0: (0.0, _objects([30.0], [0.0], sigma=1.0)),
                            1: (0.0, _objects([30.0], [across_m], sigma=1.0))})
    assert len(out) == (1 if fused else 2)


def test_decode_of_a_capture_of_two_buses_picks_one_with_channel(tmp_path, capsys):
    """A capture of two CAN channels with a radar 0 on each was decoded as one bus: one radar's headers taken for stray
    ones and its frames for orphans (68 and 408 here), with no word (an independent tester's finding). Now decode
    warns that sensor 0 came on two channels, and --channel (by name or number) decodes one bus: every cycle of it,
    nothing stray or orphaned."""
    from tests.helpers import cli
    from tests.conftest import SCENARIOS
    logs = []
    for ch, name, start in (("can0", "highway_cut_in.yaml", "0"), ("can1", "stopped_vehicle.yaml", "0.003")):
        path = tmp_path / f"{ch}.log"
        rc, _, err = cli(capsys, "log", SCENARIOS / name, "--duration", "5", "--channel", ch, "--start-time", start,
                         "-o", path)
        assert rc == 0, err
        logs += list(can.LogReader(str(path)))
    both = tmp_path / "both.log"
    with can.CanutilsLogWriter(str(both)) as w:
        for m in sorted(logs, key=lambda m: m.timestamp):
            w.on_message_received(m)
    rc, out, err = cli(capsys, "decode", both, "--summary")
    assert rc == 0 and "warning: frames of sensor 0 on 2 channels (can0, can1)" in err and "orphan_frames=" in out
    for channel in ("can1", "1", "can0"):
        rc, out, err = cli(capsys, "decode", both, "--summary", "--channel", channel)
        assert rc == 0 and "warning" not in err, err
        assert "cycles=69," in out and "orphan_frames" not in out and "stray_headers" not in out, out
    # a channel the log does not have: an empty decode said nothing (the re-test's finding), then a warning with
    # status 0; now an error naming the channels it holds, status 1, and no output file (as export)
    rc, out, err = cli(capsys, "decode", both, "--summary", "--channel", "can2")
    assert rc == 1 and ("option --channel: value 'can2' is not allowed: no frame of the log is on it; expected one of "
                        "the channels its frames are on: can0, can1 (as the log names them)") in err, err
    # nothing on stdout before it (a "consumer: frames=0" line, a CSV header: read as a decode of a silent bus; and a
    # candump log names its channels, so no word of how ASC, BLF and TRC number theirs: a tester's findings)
    assert out == "" and "numbers its channels" not in err, (out, err)
    for fmt in ("text", "csv", "json"):
        rc, out, err = cli(capsys, "decode", both, "--format", fmt, "--channel", "can2")
        assert rc == 1 and out == "" and "value 'can2' is not allowed" in err, (fmt, out, err)
    rc, out, err = cli(capsys, "decode", both, "--format", "json", "--channel", "can2", "-o", tmp_path / "x.json")
    assert rc == 1 and "value 'can2' is not allowed" in err and not (tmp_path / "x.json").exists(), err


def test_a_bit_rate_too_low_for_the_cycle_keeps_the_log_in_time_order_and_says_so(capsys, caplog, tmp_path):
    """An independent tester's finding: at 10 kbit/s three radars' cycles need more than a 72-ms period holds, and the
    next cycle's frames were stamped at its start, before the last frames of the one before (8 of 1047 frames out of
    order in the log); and one radar's cycles whose fixed frames alone exceed the budget said nothing but the drops.
    The bus carries one frame at a time: a cycle's frames follow the last one before them, and the budget that
    cannot be kept is warned of and counted."""
    import can
    from tests.helpers import cli
    from tests.conftest import SCENARIOS
    rc, _, err = cli(capsys, "log", SCENARIOS / "highway_cut_in.yaml", "-o", tmp_path / "fast.log")
    assert rc == 0 and "fixed frames alone" not in caplog.text, caplog.text
    rc, _, err = cli(capsys, "log", SCENARIOS / "highway_cut_in.yaml", "-b", "10000", "-o", tmp_path / "one.log")
    assert rc == 0 and "its fixed frames alone need" in caplog.text and "cycles_over_budget" in caplog.text, err
    out = tmp_path / "three.log"
    rc, _, err = cli(capsys, "log", SCENARIOS / "front_and_corners.yaml", "-b", "10000", "-o", out)
    assert rc == 0, err
    stamps = [m.timestamp for m in can.LogReader(str(out))]
    assert len(stamps) > 500 and all(b >= a for a, b in zip(stamps, stamps[1:]))


def test_one_late_list_time_neither_drops_the_others_nor_restarts_the_fused_tracks(tmp_path, capsys):
    """One sensor's header stamped 3 s late (or not a number): the round's time was its lists' latest, so the other
    sensors' lists were left out as stale and every fused track restarted with new IDs, without a word (an
    independent tester's finding). The round's time is now the one most of its lists agree with; the late list is
    left out, counted and said."""
    log = tmp_path / "x.log"
    assert main(["log", str(SCENARIOS / "front_and_corners.yaml"), "-o", str(log)]) == 0
    capsys.readouterr()
    lines = log.read_text().splitlines()
    k = next(i for i, line in enumerate(lines) if " 61A#" in line and float(line[1:line.index(")")]) > 5.0)
    t = float(lines[k][1:lines[k].index(")")])
    glitch = tmp_path / "glitch.log"
    glitch.write_text("\n".join(lines[:k] + [f"({t + 3.0:.6f})" + lines[k][lines[k].index(")") + 1:]]
                                + lines[k + 1:]) + "\n")
    scen = str(SCENARIOS / "front_and_corners.yaml")
    assert main(["decode", str(log), "--fuse", scen]) == 0
    clean = capsys.readouterr()
    assert main(["decode", str(glitch), "--fuse", scen]) == 0
    out, err = capsys.readouterr()
    assert out.splitlines()[-1] == clean.out.splitlines()[-1]             # the same fused objects and rounds
    assert "warning: fusion: stale_lists=1" in err and "restarts" not in err, err
    assert "warning: fusion" not in clean.err


def test_the_round_time_is_the_one_most_lists_agree_with():
    fc = FusingConsumer({0: SensorMount(), 1: SensorMount(), 2: SensorMount()})
    assert fc._round_time([5.0, 8.0, 5.01]) == 5.01                      # the majority's latest
    assert fc._round_time([8.0, 8.0, 8.01]) == 8.01                      # all moved: a jump, restarted later
    assert fc._round_time([5.0, math.inf, math.nan, 5.01]) == 5.01
    assert fc._round_time([math.nan, math.inf]) is None
    fc.fusion._last_t = 4.93
    assert fc._round_time([5.0, 8.0]) == 5.0                              # a tie: the one that continues
    fc.fusion._last_t = 7.95
    assert fc._round_time([5.0, 8.0]) == 8.0


def test_a_bus_error_neither_stops_the_fusing_consumer_nor_raises(caplog):
    """python-can's notifier ends its thread on an exception its listener does not take (``on_error``): one
    unreadable UDP datagram stopped ``consume --fuse`` for good, with a traceback (an independent tester's finding).
    The frames after it are fused; the error is counted and warned once."""
    import threading

    class Flaky(can.BusABC):
        def __init__(self, frames):
            super().__init__(channel="flaky")
            self.frames, self.done = list(frames), threading.Event()

        def _recv_internal(self, timeout):
            if len(self.frames) in (len(self.all) // 2, len(self.all) // 3):
                self.frames.pop(0)
                raise can.CanOperationError("could not unpack received message")
            if not self.frames:
                self.done.set()
                threading.Event().wait(timeout or 0.01)
                return None, False
            return self.frames.pop(0), False

        def send(self, msg, timeout=None):
            pass

    sc = load_scenario(SCENARIOS / "front_and_corners.yaml")
    _, frames, _ = _frames(sc)
    frames = frames[:600]
    bus = Flaky(frames)
    bus.all = frames
    fc = FusingConsumer(_mounts(sc))
    notifier = can.Notifier(bus, [fc], timeout=0.01)
    try:
        assert bus.done.wait(30)
    finally:
        notifier.stop()
        bus.shutdown()
    assert fc.bus_errors == 2 and fc.counters()["bus_errors"] == 2
    assert sum(st.frames for st in fc.stats.values()) == 3 * (len(frames) - 2)      # every frame after them read
    assert [r.getMessage() for r in caplog.records].count(
        "bus error in the fusing consumer: could not unpack received message (further ones are counted in "
        "bus_errors)") == 1


@pytest.mark.parametrize("late,time", [(0.9, 5.9), (1.0, 6.0), (1.1, 5.01), (2.0, 5.01)])
def test_the_round_time_at_the_gap_limit(late, time):
    """One list ``late`` s after the others' 5.0 and 5.01, around MAX_GAP_S (1 s) and at twice it: within it every
    list agrees with the latest time (all fused); beyond it the late one stands alone and the others' time is taken."""
    from radarnode.consumer.fusion import MAX_GAP_S
    assert MAX_GAP_S == 1.0
    fc = FusingConsumer({0: SensorMount(), 1: SensorMount(), 2: SensorMount()})
    assert fc._round_time([5.0, 5.0 + late, 5.01]) == pytest.approx(time, abs=1e-12)


@pytest.mark.parametrize("leave", [True, False])
def test_a_fusing_consumer_stopped_counts_each_sensors_cycle_in_progress(leave):
    """``consume --fuse`` stopped (by --count or Ctrl-C: ``leave_unfinished``; by --timeout: not) counted the cycles
    in progress nowhere: the fusing consumer had no ``stop`` (an independent tester's finding). Each sensor's is now
    unfinished or incomplete, as a lone consumer's."""
    from radarnode.cli.common import fusion_mounts
    sc = parse_scenario(THREE.format(duration=1.0))
    _, frames, _ = _frames(sc)
    heads = [i for i, m in enumerate(frames) if m.arbitration_id == P.OBJ_STATUS]
    cut = heads[8] + 2                        # sensor 0's ninth header and its first list frame
    assert frames[cut - 1].arbitration_id == P.OBJ_GENERAL
    fuser = FusingConsumer(fusion_mounts(sc))
    for m in frames[:cut]:
        fuser.on_message_received(m)
    fuser.leave_unfinished = leave
    fuser.stop()
    st = fuser.stats[0]
    assert (st.unfinished_cycles, st.incomplete_cycles) == ((1, 0) if leave else (0, 1)), st.as_dict()
    assert st.cycles == 8
