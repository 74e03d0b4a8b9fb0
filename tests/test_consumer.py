"""The consumer: a real ARS 408-21 capture, round trips through the bus, and malformed traffic."""

from __future__ import annotations

import random

import can
import numpy as np
import pytest

from radarnode.consumer.assembler import CycleAssembler, ObjectCycle, summarize_objects
from radarnode.wire import ars408 as P
from radarnode.wire.node import EgoMotionSender, RadarNode
from radarnode.wire.runner import SimulatedClock, run_node
from tests.helpers import scenario

TRAFFIC = """
  - {id: a, class: car, x_m: 40.0, lane: 1, speed_mps: 22.0}
  - {id: b, class: truck, x_m: 70.0, lane: 0, speed_mps: 18.0}
  - {id: c, class: motorcycle, x_m: 55.0, lane: 2, speed_mps: 25.0}
"""


def test_real_ars408_capture_holds_three_stable_objects(reference_dir):
    assembler = CycleAssembler()
    cycles = list(assembler.feed(can.LogReader(str(reference_dir / "candump-ars408-parked.log"))))
    assert len(cycles) == 515 and assembler.stats.incomplete_cycles == 0 and assembler.stats.dropped() == 0
    assert assembler.stats.lost_cycles == 0            # the real sensor counts in steps of 2
    first = cycles[:50]
    assert all(set(c.objects.id.tolist()) == {0, 32, 56} for c in first)
    summary = summarize_objects(first)
    assert summary[56]["dist_long_m"] == pytest.approx(5.6, abs=0.3) and summary[56]["obj_class"] == 0
    assert summary[32]["dist_long_m"] == pytest.approx(11.4, abs=0.3) and summary[32]["obj_class"] == 1
    assert summary[0]["dist_long_m"] == pytest.approx(17.6, abs=0.3) and summary[0]["obj_class"] == 6
    assert assembler.radar_state["RadarState_MaxDistanceCfg"] == 200
    assert all(c.has_quality and c.has_extended for c in cycles)


def _node_frames(sc, with_vehicle=True):
    node = RadarNode(sc)
    frames, outs = [], []
    run_node(node, clock=SimulatedClock(), sinks=[frames.append], on_cycle=outs.append,
             vehicle=EgoMotionSender(node.scene) if with_vehicle else None)
    return node, frames, outs


def test_round_trip_matches_what_the_node_sent_within_one_lsb():
    node, frames, outs = _node_frames(scenario(TRAFFIC, duration=4.0))
    assembler = CycleAssembler()
    cycles = list(assembler.feed(frames))
    assert len(cycles) == len(outs) and assembler.stats.dropped() == 0
    assert assembler.ego_speed_mps == pytest.approx(20.0, abs=0.02)
    for cyc, out in zip(cycles, outs):
        sent = out.frame.objects
        got = cyc.objects
        np.testing.assert_array_equal(got.id, sent.id)
        np.testing.assert_allclose(got.dist_long_m, sent.dist_long_m, atol=0.1 + 1e-9)
        np.testing.assert_allclose(got.dist_lat_m, sent.dist_lat_m, atol=0.1 + 1e-9)
        np.testing.assert_allclose(got.vrel_long_mps, sent.vrel_long_mps, atol=0.125 + 1e-9)
        np.testing.assert_array_equal(got.obj_class, sent.obj_class)
        np.testing.assert_array_equal(got.dyn_prop, sent.dyn_prop)
        assert np.all(got.dist_long_sigma_m >= sent.dist_long_sigma_m)


def test_objects_track_ground_truth_within_the_noise():
    node, frames, outs = _node_frames(scenario(TRAFFIC, duration=5.0))
    cycles = list(CycleAssembler().feed(frames))
    errors = []
    for cyc, out in zip(cycles, outs):
        idx = out.frame.objects.actor_index
        errors += list(np.hypot(cyc.objects.dist_long_m - out.view.x_m[idx],
                                cyc.objects.dist_lat_m - out.view.y_m[idx]))
    assert len(errors) > 150
    assert np.percentile(errors, 95) < 1.5


def _corrupt(frames, rng):
    """Return the corrupted stream and how many well-formed object cycles it still holds."""
    cycles, current = [], None
    for m in frames:
        if m.arbitration_id == P.OBJ_STATUS:
            current = [m]
            cycles.append(current)
        elif current is not None:
            current.append(m)
        else:
            cycles.append([m])
    out, good = [], 0
    kinds = ["ok", "dlc", "unknown", "short_header", "missing", "duplicate", "reorder_groups"]
    expected = {k: 0 for k in kinds}
    for cyc in cycles:
        kind = rng.choice(kinds) if cyc[0].arbitration_id == P.OBJ_STATUS and len(cyc) > 4 else "ok"
        cyc = [can.Message(arbitration_id=m.arbitration_id, data=bytes(m.data), is_extended_id=False,
                           timestamp=m.timestamp) for m in cyc]
        expected[kind] += 1
        if kind == "dlc":          # a general frame with a wrong DLC: the cycle misses an object
            i = next(i for i, m in enumerate(cyc) if m.arbitration_id == P.OBJ_GENERAL)
            cyc[i] = can.Message(arbitration_id=P.OBJ_GENERAL, data=bytes(cyc[i].data[:6]), is_extended_id=False)
        elif kind == "unknown":    # foreign traffic in the middle of a cycle does not hurt it
            cyc.insert(2, can.Message(arbitration_id=0x123, data=b"\x00" * 8, is_extended_id=False))
            good += 1
        elif kind == "short_header":   # header announces more objects than follow
            hdr = bytearray(cyc[0].data)
            hdr[0] += 2
            cyc[0] = can.Message(arbitration_id=P.OBJ_STATUS, data=bytes(hdr), is_extended_id=False)
        elif kind == "missing":    # one frame of the cycle lost
            i = next(i for i, m in enumerate(cyc) if m.arbitration_id == P.OBJ_EXTENDED)
            del cyc[i]
        elif kind == "duplicate":  # a frame repeated: ignored, cycle kept
            cyc.insert(2, cyc[1])
            good += 1
        elif kind == "reorder_groups":  # frames of one group shuffled: joined by ID, cycle kept
            idx = [i for i, m in enumerate(cyc) if m.arbitration_id == P.OBJ_QUALITY]
            moved = [cyc[i] for i in idx][::-1]
            for i, m in zip(idx, moved):
                cyc[i] = m
            good += 1
        else:
            good += cyc[0].arbitration_id == P.OBJ_STATUS
        out += cyc
    return out, good, expected


def test_consumer_survives_malformed_traffic_and_keeps_every_good_cycle():
    sc = scenario(TRAFFIC, duration=12.0)
    _, frames, _ = _node_frames(sc)
    clean = [c for c in CycleAssembler().feed(frames) if isinstance(c, ObjectCycle)]
    rng = random.Random(3)
    bad, good, expected = _corrupt(frames, rng)
    assembler = CycleAssembler()
    cycles = [c for c in assembler.feed(bad) if isinstance(c, ObjectCycle)]
    s = assembler.stats
    assert len(cycles) == good
    assert s.wrong_dlc == expected["dlc"] and s.unknown_id == expected["unknown"]
    assert s.duplicate_frames == expected["duplicate"]
    assert s.incomplete_cycles == expected["dlc"] + expected["short_header"] + expected["missing"]
    # every cycle that came through is identical to the clean decode of the same MeasCounter
    by_counter = {c.meas_counter: c for c in clean}
    for c in cycles:
        ref = by_counter[c.meas_counter]
        np.testing.assert_array_equal(np.sort(c.objects.id), np.sort(ref.objects.id))


def test_orphans_extra_frames_and_restart_are_counted():
    sc = scenario(TRAFFIC, duration=2.0)
    node, frames, _ = _node_frames(sc, with_vehicle=False)
    general = next(m for m in frames if m.arbitration_id == P.OBJ_GENERAL)
    assembler = CycleAssembler()
    assembler.on_message_received(general)                  # no header yet
    assert assembler.stats.orphan_frames == 1
    list(assembler.feed(frames))
    list(assembler.feed(frames))                            # the node restarts: MeasCounter jumps back
    assert assembler.stats.counter_resets == 1
    assembler.on_message_received(can.Message(arbitration_id=P.OBJ_STATUS, data=b"\x00\x00\x50\x10",
                                              is_extended_id=False))
    assembler.on_message_received(general)                  # header said 0 objects: that cycle is over
    assert assembler.stats.orphan_frames == 2
    assembler.on_message_received(can.Message(arbitration_id=P.OBJ_STATUS, data=b"\x01\x00\x51\x10",
                                              is_extended_id=False))
    other = can.Message(arbitration_id=P.OBJ_GENERAL, data=b"\x07" + bytes(general.data[1:]), is_extended_id=False)
    assembler.on_message_received(general)
    assembler.on_message_received(other)                    # header said 1 object
    assert assembler.stats.extra_frames == 1
    assembler.flush()
    assert assembler.stats.incomplete_cycles == 1
    assembler.on_message_received(can.Message(arbitration_id=0x60B, is_extended_id=True, data=b"\x00" * 8))
    assert assembler.stats.errors_frames == 1


def test_lost_cycles_are_counted():
    _, frames, _ = _node_frames(scenario(TRAFFIC, duration=2.0), with_vehicle=False)
    headers = [i for i, m in enumerate(frames) if m.arbitration_id == P.OBJ_STATUS]
    cut = frames[:headers[5]] + frames[headers[8]:]
    assembler = CycleAssembler()
    list(assembler.feed(cut))
    assert assembler.stats.lost_cycles == 3


def test_cluster_list_round_trip():
    sc = scenario(TRAFFIC, radar="{preset: ars408_like, output: clusters}",
                  road="{lanes: 3, guardrails: {left_offset_m: 1.0, right_offset_m: 1.0}}", duration=2.0)
    _, frames, outs = _node_frames(sc)
    cycles = list(CycleAssembler().feed(frames))
    assert len(cycles) == len(outs)
    for cyc, out in zip(cycles, outs):
        assert len(cyc.clusters) == len(out.frame.clusters)
        np.testing.assert_allclose(cyc.clusters.dist_long_m, out.frame.clusters.dist_long_m, atol=0.1 + 1e-9)
        np.testing.assert_array_equal(cyc.clusters.is_near, out.frame.clusters.is_near)
    assert max(len(c.clusters) for c in cycles) > 20        # guardrail posts
