"""The consumer ECU under bad traffic (issue 4, item 7): it keeps working, and stops acting on stale data."""

from __future__ import annotations

import dataclasses
import math

import can
import numpy as np
import pytest

from radarnode.consumer.acc import STATE_ACTIVE, STATE_FAULT, AccSettings
from radarnode.consumer.assembler import CycleAssembler
from radarnode.consumer.ecu import Ecu
from radarnode.consumer.tracking import ospa
from radarnode.wire import ars408 as P
from radarnode.wire.node import EgoMotionSender, RadarNode
from tests.helpers import scenario

FOLLOW = "  - {id: lead, class: car, x_m: 45.0, lane: 1, speed_mps: 24.0}"


def _cycles(n=110, node=None, t0=0.0):
    """Frames per cycle of a following scene: [(t, [messages])]."""
    sc = scenario(FOLLOW, ego="{speed_mps: 25.0}", duration=n * 0.072 + 0.1)
    node = node or RadarNode(sc)
    veh = EgoMotionSender(node.scene)
    out = []
    for k in range(n):
        t = k * node.period_s
        ego = veh.frames(t)
        for m in ego:
            node.receive(m, t)
        out.append((t0 + t, ego + node.cycle(t).messages))
    return out


def _drive(cycles, mutate=lambda k, msgs: msgs):
    asm = CycleAssembler()
    ecu = Ecu(AccSettings(set_speed_mps=30.0, time_gap_s=1.5))
    decisions = []
    for k, (t, msgs) in enumerate(cycles):
        for m in mutate(k, list(msgs)):
            asm.on_message_received(m)
        ecu.set_ego(t, asm.ego_speed_mps, asm.ego_yaw_rate_dps)
        d = None
        for c in asm.drain():
            d = ecu.on_cycle(t, c)
        d = d or ecu.tick(t)
        if d is not None:
            for m in ecu.frames(d):
                asm.on_message_received(m)
            decisions.append(d)
    return asm, ecu, decisions


def _steady(decisions, start=20):
    d = decisions[start:]
    return all(x.radar_ok for x in d) and all(x.target is not None for x in d) and all(
        x.acc_state == STATE_ACTIVE for x in d)


def test_clean_traffic_follows_the_lead():
    asm, ecu, dec = _drive(_cycles())
    assert _steady(dec)
    assert dec[-1].target.distance_m == pytest.approx(asm.ecu_status["AccStatus"]["ACC_Distance"], abs=0.1)


def test_lost_cycles_and_missing_frames():
    def lose(k, msgs):
        if k % 7 == 3:
            return []                                                   # a whole cycle lost
        if k % 5 == 1:
            drop = next(i for i, m in enumerate(msgs) if m.arbitration_id == P.OBJ_GENERAL) \
                if any(m.arbitration_id == P.OBJ_GENERAL for m in msgs) else None
            return [m for i, m in enumerate(msgs) if i != drop]         # a frame missing inside a cycle
        return msgs
    asm, _, dec = _drive(_cycles(), lose)
    assert asm.stats.incomplete_cycles > 5 and asm.stats.lost_cycles > 5
    assert _steady(dec)                                                 # coasting, never a fault


def test_duplicated_reordered_and_wrong_dlc_frames():
    rng = np.random.default_rng(0)

    def mess(k, msgs):
        if len(msgs) > 4:
            msgs.insert(3, msgs[3])                                     # duplicate
            q = [i for i, m in enumerate(msgs) if m.arbitration_id == P.OBJ_QUALITY]
            if len(q) > 1:
                msgs[q[0]], msgs[q[1]] = msgs[q[1]], msgs[q[0]]         # reordered within a group
        msgs.append(can.Message(arbitration_id=P.OBJ_GENERAL, data=bytes(3), is_extended_id=False))  # wrong DLC
        rng.random()
        return msgs
    asm, _, dec = _drive(_cycles(), mess)
    assert asm.stats.duplicate_frames > 50 and asm.stats.wrong_dlc > 50
    assert _steady(dec)


def test_e2e_failures_are_counted_and_dropped():
    asm, ecu, dec = _drive(_cycles(60))
    bad = ecu.frames(dec[-1])[0]
    data = bytearray(bad.data)
    data[2] ^= 0x40
    before = asm.stats.ecu_frames
    asm.on_message_received(can.Message(arbitration_id=bad.arbitration_id, data=bytes(data), is_extended_id=False))
    assert asm.stats.e2e_errors == 1 and asm.stats.ecu_frames == before


def test_node_restart_and_bus_silence_fault_then_recover():
    first = _cycles(60)
    silent = [(first[-1][0] + 0.072 * (k + 1), []) for k in range(14)]          # 1 s without a frame
    restarted = _cycles(60, t0=silent[-1][0] + 0.072)                           # a new node: counters from 0
    asm, _, dec = _drive(first + silent + restarted)
    assert asm.stats.counter_resets >= 1
    during = [d for d in dec if first[-1][0] + 0.3 < d.t_s < silent[-1][0]]
    assert during and all(d.acc_state == STATE_FAULT and d.accel_request_mps2 == 0.0 and d.fault for d in during)
    assert all(not d.radar_ok for d in during)
    assert dec[-1].acc_state == STATE_ACTIVE and dec[-1].target is not None       # back after the restart
    assert asm.ecu_status["AccStatus"]["ACC_State"] == STATE_ACTIVE


def test_tracks_against_truth_ospa():
    sc = scenario("""
  - {id: a, class: car, x_m: 40.0, lane: 1, speed_mps: 22.0}
  - {id: b, class: car, x_m: 80.0, lane: 2, speed_mps: 27.0}
  - {id: c, class: truck, x_m: 60.0, lane: 0, speed_mps: 20.0}
""", duration=8.0)
    node = RadarNode(sc)
    veh = EgoMotionSender(node.scene)
    asm, ecu = CycleAssembler(), Ecu()
    dist = []
    for k in range(100):
        t = k * node.period_s
        for m in veh.frames(t):
            node.receive(m, t)
            asm.on_message_received(m)
        out = node.cycle(t)
        for m in out.messages:
            asm.on_message_received(m)
        for c in asm.drain():
            ecu.set_ego(t, asm.ego_speed_mps, asm.ego_yaw_rate_dps)
            ecu.on_cycle(t, c)
        if k >= 10:
            est = np.array([t_.x[:2] for t_ in ecu.tracker.tracks if t_.confirmed])
            truth = np.stack([out.view.x_m, out.view.y_m], axis=1)
            dist.append(ospa(est, truth, c=10.0))
    assert np.median(dist) < 1.0 and np.percentile(dist, 95) < 3.0


def test_ecu_tracks_cluster_lists_too():
    sc = scenario(FOLLOW, ego="{speed_mps: 25.0}", radar="{preset: ars408_like, output: clusters}", duration=5.0)
    node = RadarNode(sc)
    _, _, dec = _drive(_cycles(60, node=node))
    late = dec[20:]
    assert all(d.target is not None for d in late)
    # the lead's rear is 45 − 2.25 − 3.7 = 39 m ahead at the start and closes at 1 m/s
    assert late[-1].target.distance_m == pytest.approx(39.05 - 60 * 0.072, abs=1.5)
    assert late[-1].target.rel_speed_mps == pytest.approx(-1.0, abs=0.5)


def _assembled(n=90):
    """(t, decoded object cycle, ego speed, yaw rate) per cycle of the following scene."""
    asm = CycleAssembler()
    out = []
    for t, msgs in _cycles(n):
        for m in msgs:
            asm.on_message_received(m)
        (cycle,) = asm.drain()
        out.append((t, cycle, asm.ego_speed_mps, asm.ego_yaw_rate_dps))
    return out


def _run_ecu(feed):
    """Feed (t, cycle, speed, yaw) to a fresh ECU; returns it and the decision per cycle (None: refused)."""
    ecu = Ecu(AccSettings(set_speed_mps=30.0, time_gap_s=1.5))
    decisions = []
    for t, cycle, speed, yaw in feed:
        ecu.set_ego(t, speed, yaw)
        decisions.append(ecu.on_cycle(t, cycle))
    return ecu, decisions


@pytest.mark.parametrize("bad, counter", [(-1e9, "time_jumps"), (1e300, "rejected_time"), (float("nan"), "rejected_time"),
                                          (float("inf"), "rejected_time"), (-float("inf"), "rejected_time"),
                                          (1e6, "time_jumps")])
def test_ecu_skips_a_stray_timestamp_and_keeps_its_tracks(bad, counter):
    cycles = _assembled()
    feed = [(bad if k == 40 else t, c, v, w) for k, (t, c, v, w) in enumerate(cycles)]
    ecu, dec = _run_ecu(feed)
    st = ecu.stats
    assert dec[40] is None and getattr(st, counter) == 1
    assert st.internal_errors == 0 and st.time_resyncs == 0 and st.cycles == len(cycles) - 1
    assert all(d is not None for i, d in enumerate(dec) if i != 40)
    # a single stray time leaves the tracks alone: the same track is followed before and after
    before, after = dec[39].target, dec[41:]
    assert before is not None and all(d.target is not None and d.target.track_id == before.track_id for d in after)
    assert after[-1].target.distance_m == pytest.approx(cycles[-1][1].objects.dist_long_m.min() - 2.25, abs=3.0)
    assert ecu.ego_accel_mps2 == pytest.approx(0.0, abs=0.05)          # no acceleration made up from the jump


@pytest.mark.parametrize("ahead_s", [0.3, 3.0, 4.9])
def test_ecu_undoes_one_cycle_stamped_ahead_within_the_gap_it_tracks_through(ahead_s):
    """One cycle stamped 0.3–4.9 s ahead (within max_gap_s, so tracked as a pause would be): the next cycle, back on
    the old time base, was refused and the one after restarted tracking (ACC without a target for 4 cycles; an
    independent tester's finding). Now the next cycle shows the jump stray, and the tracks go back to before it."""
    cycles = _assembled()
    feed = [(t + (ahead_s if k == 40 else 0.0), c, v, w) for k, (t, c, v, w) in enumerate(cycles)]
    ecu, dec = _run_ecu(feed)
    st = ecu.stats
    assert st.stray_undone == (1 if ahead_s > 3 * 0.072 else 0) and st.time_resyncs == 0 and st.internal_errors == 0
    assert all(d is not None for d in dec)
    before = dec[39].target
    assert before is not None and all(d.target is not None and d.target.track_id == before.track_id for d in dec[41:])
    # the same as a stream that lost that cycle: the same decisions after it
    ref = _run_ecu(cycles[:40] + cycles[41:])[1]
    assert [d.target.distance_m for d in dec[41:]] == pytest.approx([d.target.distance_m for d in ref[40:]], abs=1e-9)


def test_ecu_tracks_through_a_pause_of_several_cycles():
    """A real pause (no cycle for 2 s, then the stream goes on from there) is no stray: tracked through."""
    cycles = _assembled()
    feed = [(t + (2.0 if k >= 40 else 0.0), c, v, w) for k, (t, c, v, w) in enumerate(cycles)]
    ecu, dec = _run_ecu(feed)
    assert ecu.stats.stray_undone == 0 and ecu.stats.time_resyncs == 0 and all(d is not None for d in dec)
    assert dec[39].target is not None and all(d.target is not None for d in dec[43:])


@pytest.mark.parametrize("shift_s, label", [(600.0, "10-minute gap"), (-1e9, "clock restarted far back"),
                                            (-2.5, "clock 2.5 s back")])
def test_ecu_restarts_tracking_on_a_new_time_base(shift_s, label):
    cycles = _assembled()
    feed = [(t + (shift_s if k >= 40 else 0.0), c, v, w) for k, (t, c, v, w) in enumerate(cycles)]
    ecu, dec = _run_ecu(feed)
    st = ecu.stats
    assert dec[40] is None and st.time_jumps == 1 and st.time_resyncs == 1, label
    assert st.rejected_time == 0 and st.internal_errors == 0
    assert dec[39].target is not None and all(d is not None for d in dec[41:])
    # tracking starts again on the new time base: confirmed within a few cycles and held to the end
    assert all(d.target is not None for d in dec[45:]), label
    assert max(t.age for t in ecu.tracker.tracks) < len(cycles) - 41            # born after the restart
    assert all(np.isfinite(t.x).all() and np.isfinite(t.p).all() for t in ecu.tracker.tracks)


def test_ecu_guards_its_other_inputs():
    cycles = _assembled(30)
    ecu, dec = _run_ecu(cycles)
    assert ecu.tick(float("nan")) is None and ecu.stats.rejected_time == 1
    ecu.set_ego(cycles[-1][0] + 0.072, float("nan"), 0.0)
    ecu.set_ego(float("inf"), 20.0, 0.0)
    assert ecu.stats.bad_ego == 2 and math.isfinite(ecu.ego_speed_mps)
    t, cycle, _, _ = cycles[-1]
    broken = dataclasses.replace(cycle, objects=cycle.objects.take(np.arange(len(cycle.objects))))
    broken.objects.dist_long_m[0] = np.nan
    d = ecu.on_cycle(t + 0.072, broken)
    assert d is not None and ecu.stats.bad_measurements == 1 and ecu.stats.internal_errors == 0
    with pytest.raises(TypeError, match="Ecu.on_cycle cycle: value of type str is not allowed"):
        ecu.on_cycle(t + 0.144, "not a cycle")
    for name, kwargs in (("period_s", {"period_s": float("nan")}), ("max_gap_s", {"max_gap_s": 0.01})):
        with pytest.raises(ValueError, match=f"Ecu {name}: value"):
            Ecu(**kwargs)


@pytest.mark.parametrize("step_periods, undone", [(2.9, False), (3.1, True), (6.0, True)])
def test_ecu_keeps_the_state_before_a_step_of_more_than_three_cycles(step_periods, undone):
    """STRAY_STEP_PERIODS (3): a cycle stamped so that its step from the last is just below, just above and twice
    that. Above, the state before it is kept and the stray undone; below, the next cycle, back in time, is skipped
    (time_jumps) and the one after it is ahead of the stray again and tracked on: no restart either way."""
    from radarnode.consumer.ecu import STRAY_STEP_PERIODS
    assert STRAY_STEP_PERIODS == 3.0
    cycles = _assembled()
    ahead = (step_periods - 1.0) * 0.072
    feed = [(t + (ahead if k == 40 else 0.0), c, v, w) for k, (t, c, v, w) in enumerate(cycles)]
    ecu, dec = _run_ecu(feed)
    st = ecu.stats
    assert st.stray_undone == int(undone) and st.time_jumps == int(not undone) and st.time_resyncs == 0, st
    assert all(d is not None and d.target is not None for d in dec[42:])


@pytest.mark.parametrize("speed, yaw, refused", [
    (25.0, 327.65, False), (25.0, 327.66, False), (25.0, 327.67, True), (25.0, -327.68, False), (25.0, -327.69, True),
    (25.0, -655.36, True), (25.0, 1e6, True), (25.0, 1e300, True), (163.82, 0.0, False), (-163.82, 0.0, False),
    (163.83, 0.0, True), (327.64, 0.0, True)])
def test_ecu_refuses_an_ego_motion_beyond_what_the_bus_carries(speed, yaw, refused):
    """Ecu.set_ego took any finite yaw rate: 1e6 °/s overflowed the path prediction and restarted every track (an
    independent tester's finding). Just below, at, just above and at twice the bus's limits (0x301: −327.68…327.66 °/s,
    as the radar node takes them; 0x300: 163.82 m/s): beyond them the value is counted in bad_ego and ignored, and the tracks go on undisturbed."""
    cycles = _assembled(70)
    ecu = Ecu(AccSettings(set_speed_mps=30.0, time_gap_s=1.5))
    decisions = []
    for k, (t, cycle, v, w) in enumerate(cycles):
        if k == 40:
            ecu.set_ego(t, speed, yaw)
        else:
            ecu.set_ego(t, v, w)
        decisions.append(ecu.on_cycle(t, cycle))
    assert ecu.stats.bad_ego == int(refused) and ecu.stats.internal_errors == 0, ecu.stats
    if refused:
        assert ecu.ego_speed_mps == pytest.approx(cycles[-1][2])
        ids = {d.target.track_id for d in decisions[30:] if d.target is not None}
        assert len(ids) == 1 and all(d.target is not None for d in decisions[30:])
