"""The consumer ECU when an input falls silent: the radar (FCW keeps judging its last object, dead-reckoned) and the
ego motion (a missing input, ACC in fault); both reported in ACC_Fault and FcwStatus' FCW_Fault.

An independent tester's findings (2026-12-03): with the radar silent 1.7 s before an impact FCW withdrew its warning
0.8 s before it (FcwStatus: level 0, TTC 25.5 s, no fault field); with SpeedInformation gone the ECU went on with
20 m/s for 7 s while the ego slowed to 10, ACC_Fault bit 1 ("ego-motion input missing") never set.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import can
import numpy as np
import pytest
from helpers import measured_objects

from radarnode.cli.main import main
from radarnode.consumer import ecu as ecu_module
from radarnode.consumer.acc import STATE_FAULT, AccSettings
from radarnode.consumer.assembler import CycleAssembler, ObjectCycle
from radarnode.consumer.ecu import FCW_COAST_S, Ecu
from radarnode.consumer.evaluate import simulate
from radarnode.consumer.fcw import LEVEL_WARNING
from radarnode.perception.types import ObjectList
from radarnode.radar.setup import load_scenario
from radarnode.wire.dbc import load_own_database
from radarnode.wire.ids import ACC_STATUS, FCW_STATUS

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
PERIOD = 0.072


def _stopped_car(tmp_path, ego_accel: str = "") -> Path:
    """The ego at 20 m/s towards a car stopped 130 m ahead in its lane (impact at 6.26 s without a driver)."""
    p = tmp_path / "stopped.yaml"
    p.write_text(f"""name: input_loss
duration_s: 8.0
seed: 1
radar: {{preset: ars408_like}}
ego: {{speed_mps: 20.0{ego_accel}}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1}}
ecu: {{acc_enabled: true, set_speed_mps: 20.0, expect: {{lead: stopped, fcw_required: true}}}}
actors:
  - {{id: stopped, class: car, x_m: 130.0, lane: 1, speed_mps: 0.0}}
""", encoding="utf-8")
    return p


def _run_cut(monkeypatch, scenario: Path, cut_from_s: float, ids):
    """simulate() with the frames whose IDs ``ids`` accepts kept from the ECU's assembler from ``cut_from_s`` on;
    the decisions and the ECU frames as sent (decoded with the DBC after their E2E header)."""
    keep = CycleAssembler.on_message_received

    def cut(self, msg):
        if ids(msg.arbitration_id) and msg.timestamp is not None and msg.timestamp >= cut_from_s - 1e-9:
            return None
        return keep(self, msg)

    monkeypatch.setattr(CycleAssembler, "on_message_received", cut)
    decisions, sent = [], []
    frames = Ecu.frames

    def spy(self, out, timestamp=None):
        decisions.append(out)
        msgs = frames(self, out, timestamp)
        sent.extend(msgs)
        return msgs

    monkeypatch.setattr(Ecu, "frames", spy)
    res = simulate(load_scenario(scenario))
    db = load_own_database()
    wire = {base: [db.decode_message(base, bytes(m.data), decode_choices=False) for m in sent
                   if m.arbitration_id == base] for base in (ACC_STATUS, FCW_STATUS)}
    return res, decisions, wire


def _radar(i: int) -> bool:
    return 0x200 <= i < 0x300 or 0x600 <= i < 0x6C0


def _ego(i: int) -> bool:
    return i in (0x300, 0x301)


def test_a_warning_holds_through_a_silent_radar_with_its_ttc_running_down_to_the_impact(tmp_path, monkeypatch):
    res, dec, wire = _run_cut(monkeypatch, _stopped_car(tmp_path), 4.6, _radar)
    t = np.array([d.t_s for d in dec])
    assert res.warning_time_s is not None and res.warning_time_s < 4.6 and res.impact_time_s is not None
    impact = res.impact_time_s
    before = t < 4.6
    assert all(d.fault == 0 and d.radar_ok for d, b in zip(dec, before) if b)
    # unavailable after the time-out (3 periods after the last cycle at 4.54 s), never before
    late = t > 4.54 + 3 * PERIOD + 1e-9
    assert all(d.fault == 1 and not d.radar_ok and d.acc_state == STATE_FAULT and d.accel_request_mps2 == 0.0
               for d, b in zip(dec, late) if b)
    # the warning holds until the impact, on the object FCW judged last, its TTC the truth's within a cycle
    to_impact = late & (t < impact - 1e-9)                 # (at the impact the ego is at its place: let go)
    assert to_impact.sum() >= 15
    for d in (d for d, b in zip(dec, to_impact) if b):
        assert d.warning_level == LEVEL_WARNING and d.fcw_target is not None
        assert abs(d.ttc_s - (impact - d.t_s)) <= PERIOD, (d.t_s, d.ttc_s, impact)
    # on the wire: FCW_Fault bit 0, the level and a finite TTC, the same track as before the silence
    fcw = [w for w, b in zip(wire[FCW_STATUS], to_impact) if b]
    last_seen = [w for w, b in zip(wire[FCW_STATUS], before) if b][-1]
    assert all(w["FCW_Fault"] == 1 and w["FCW_WarningLevel"] == 2 and w["FCW_TTC"] < 25.5
               and w["FCW_TargetID"] == last_seen["FCW_TargetID"] != 255 for w in fcw)
    assert all(w["ACC_Fault"] == 1 for w, b in zip(wire[ACC_STATUS], late) if b)
    assert all(w["FCW_Fault"] == 0 for w, b in zip(wire[FCW_STATUS], before) if b)


def test_the_ego_motion_missing_is_a_fault_and_acc_leaves_control(tmp_path, monkeypatch):
    res, dec, wire = _run_cut(monkeypatch, _stopped_car(tmp_path), 0.5, _ego)
    t = np.array([d.t_s for d in dec])
    last_frame = 0.432                         # the last SpeedInformation kept (cycles at k·72 ms)
    fresh = t <= last_frame + 3 * PERIOD + 1e-9
    assert fresh.sum() == 10 and all(d.ego_ok and d.fault == 0 for d, b in zip(dec, fresh) if b)
    assert all(not d.ego_ok and d.fault == 2 and d.acc_state == STATE_FAULT and d.accel_request_mps2 == 0.0
               for d, b in zip(dec, fresh) if not b)
    assert all(a["ACC_Fault"] == f["FCW_Fault"] == (0 if b else 2)
               for a, f, b in zip(wire[ACC_STATUS], wire[FCW_STATUS], fresh))
    assert res.warning_time_s is not None        # FCW goes on, on the last values


def test_the_ego_motion_back_clears_the_fault(tmp_path):
    ecu = Ecu(acc=AccSettings(enabled=True, set_speed_mps=20.0))
    out = []
    for k in range(30):
        t = k * PERIOD
        if not 5 <= k < 15:
            ecu.set_ego(t, 20.0, 0.0, frames=k)
        else:
            ecu.set_ego(t, 20.0, 0.0, frames=4)         # the reader's latest, no new frame: no new measurement
        out.append(ecu.on_cycle(t, ObjectCycle(k, t, ObjectList.empty(0), True, True)))
    ok = [d.ego_ok for d in out]
    # last new frame at k = 4; fresh through 4 + 3 periods, missing from k = 8 to 14, back at 15
    assert ok == [True] * 8 + [False] * 7 + [True] * 15
    assert all(d.acc_state == STATE_FAULT for d in out[8:15]) and out[16].acc_state != STATE_FAULT


@pytest.mark.parametrize("after, ok", [(3 * PERIOD - 1e-6, True), (3 * PERIOD, True), (3 * PERIOD + 1e-6, False),
                                       (6 * PERIOD, False)])
def test_the_ego_motion_time_out_at_its_edge(after, ok):
    ecu = Ecu()
    ecu.set_ego(10.0, 15.0, 0.0, frames=1)
    ecu.set_ego(10.0 + after, 15.0, 0.0, frames=1)
    assert ecu.tick(10.0 + after).ego_ok is ok


def test_an_ecu_never_given_ego_motion_has_no_ego_fault_and_one_given_none_has():
    never = Ecu()
    assert never.tick(0.0).fault == 1                           # the radar only
    empty = Ecu()
    empty.set_ego(0.0, None, None, frames=0)                    # a reader that decoded no SpeedInformation yet
    assert empty.tick(0.0).fault == 3


def test_a_log_without_ego_motion_says_so_in_every_ecu_frame(tmp_path):
    out = tmp_path / "x.blf"
    args = ["log", str(SCENARIOS / "nhtsa_lead_stopped.yaml"), "--duration", "1", "--ecu", "-o", str(out)]
    db = load_own_database()
    for extra, fault in (([], 0), (["--no-ego-motion"], 2)):
        assert main(args + extra) == 0
        acc = [db.decode_message(ACC_STATUS, bytes(m.data)) for m in can.LogReader(str(out))
               if m.arbitration_id == ACC_STATUS]
        assert len(acc) >= 13 and all(a["ACC_Fault"] == fault for a in acc), (extra, {a["ACC_Fault"] for a in acc})


def _approach(ecu: Ecu, cycles: int, gap0: float = 60.0, closing: float = 20.0) -> float:
    """Cycles of one car standing ``gap0`` m ahead, closed on at ``closing`` m/s; returns the last cycle's time."""
    t = 0.0
    for k in range(cycles):
        t = k * PERIOD
        ecu.set_ego(t, closing, 0.0)
        ol = measured_objects({"id": 3, "dist_long_m": gap0 - closing * t, "dist_lat_m": 0.0, "rcs_dbsm": 10.0,
                               "obj_class": 1, "vrel_long_mps": -closing, "vrel_lat_mps": 0.0, "dyn_prop": 3})
        ecu.on_cycle(t, ObjectCycle(k, t, ol, True, True))
    return t


@pytest.mark.parametrize("after, coasting", [(FCW_COAST_S - 0.01, True), (FCW_COAST_S, True),
                                             (FCW_COAST_S + 0.01, False), (2 * FCW_COAST_S, False)])
def test_fcw_coasts_its_object_for_fcw_coast_s_and_no_longer(after, coasting):
    ecu = Ecu()
    last = _approach(ecu, 10, gap0=200.0)
    judged = ecu.outputs[-1].fcw_target
    assert judged is not None
    # the radar silent: the ECU's timer ticks a cycle apart, the last one at `after` since the last cycle
    ticks = last + after - 1.001 * PERIOD * np.arange(int(after / PERIOD))[::-1]      # (≥ a period apart)
    d = None
    for t in ticks[ticks > last + 3.5 * PERIOD]:
        ecu.set_ego(t, 20.0, 0.0)
        d = ecu.tick(t)
        assert d is not None and not d.radar_ok
    assert d.t_s == pytest.approx(last + after)
    assert (d.fcw_target is not None) is coasting
    if coasting:
        assert d.fcw_target.track_id == judged.track_id
        assert d.fcw_target.distance_m == pytest.approx(judged.distance_m - 20.0 * (d.t_s - last), abs=0.05)


def test_a_coasted_object_gives_way_to_the_radar_when_it_returns():
    ecu = Ecu()
    last = _approach(ecu, 10, gap0=100.0)
    for k in range(1, 10):
        ecu.set_ego(last + k * PERIOD, 20.0, 0.0)
        ecu.tick(last + k * PERIOD)
    assert ecu.outputs[-1].fcw_target is not None and not ecu.outputs[-1].radar_ok
    t = last + 10 * PERIOD
    ecu.set_ego(t, 20.0, 0.0)
    d = ecu.on_cycle(t, ObjectCycle(99, t, ObjectList.empty(0), True, True))       # back (its track still alive)
    assert d.radar_ok and d.fault == 0
    assert ecu._coast is not None and ecu._coast["since"] == t       # the coast starts afresh from this selection
    assert d.fcw_target == ecu._coast["target"]


def _coasting(ecu: Ecu, target, lead_v: float, lead_a: float, level: int = LEVEL_WARNING) -> None:
    """Start ``ecu``'s coast of ``target`` as its last radar cycle at time 0 would have (ego at the origin)."""
    px, py = ecu._vehicle_to_odometry(target.distance_m + ecu.mount.x_m, target.lateral_m)
    ecu._coast = {"target": target, "x": px, "y": py, "heading": ecu.odometry[2], "v": lead_v, "a": min(lead_a, 0.0),
                  "since": 0.0, "level": level}


def _move_ego(ecu: Ecu, speed: float, yaw_rps: float, dt: float) -> None:
    """The ego's dead reckoning one step on, as Ecu._decide advances it."""
    ox, oy, oh = ecu.odometry
    ecu.ego_speed_mps, ecu.ego_yaw_rate_rps = speed, yaw_rps
    ecu.odometry = (ox + speed * dt * math.cos(oh + 0.5 * yaw_rps * dt),
                    oy + speed * dt * math.sin(oh + 0.5 * yaw_rps * dt), oh + yaw_rps * dt)


def test_a_lead_that_brakes_is_coasted_to_its_stop_and_stays():
    """A lead at 10 m/s braking at 4 m/s², 30 m ahead, the ego at 15 m/s on the straight: the coasted gap and
    speed are the kinematics' (the lead stops after 2.5 s, 12.5 m on, and stays), until the ego reaches it."""
    ecu = Ecu()
    _coasting(ecu, ecu_module.Target(1, 1, 30.0, 0.0, -5.0, -4.0), 10.0, -4.0)
    gap, v_lead = 30.0, 10.0
    for k in range(1, 100):
        dt = PERIOD
        _move_ego(ecu, 15.0, 0.0, dt)
        target = ecu._coasted(k * dt, dt)
        new = max(v_lead - 4.0 * dt, 0.0)
        gap = gap + (0.5 * (v_lead + new) - 15.0) * dt
        v_lead = new
        if target is None:
            break
        assert target.coasted and target.object_id == 1     # what `run` prints as "object 1 (coasted)"
        assert target.distance_m == pytest.approx(max(gap, 0.0), abs=1e-9)
        assert target.rel_speed_mps == pytest.approx(v_lead - 15.0, abs=1e-9)
        assert (target.lead_accel_mps2 == 0.0) is (v_lead == 0.0)
    # it ends once the ego has passed its place, within the coast's time
    assert v_lead == 0.0 and -15.0 * PERIOD - 1e-9 <= gap <= 0.0 and k * PERIOD < FCW_COAST_S
    # a lead that accelerates away is not counted on: coasted at its speed
    _coasting(ecu, ecu_module.Target(1, 1, 30.0, 0.0, 0.0, +3.0), 15.0, +3.0)
    _move_ego(ecu, 15.0, 0.0, PERIOD)
    assert ecu._coasted(PERIOD, PERIOD).distance_m == pytest.approx(30.0)


@pytest.mark.parametrize("yaw_rps, kept", [(0.0, True), (0.005, True), (0.10, False), (-0.10, False)])
def test_a_coasted_object_the_ego_turns_away_from_leaves_the_path(yaw_rps, kept):
    """A car standing 60 m ahead; the ego at 20 m/s turns at a yaw rate while the radar is silent: on the straight
    and in a gentle turn the car stays in the predicted path and is coasted; turning away at 0.1 rad/s (a lane
    change's or a bend's) it leaves the path and FCW lets it go (it went on warning for it: a tester's finding)."""
    ecu = Ecu()
    _coasting(ecu, ecu_module.Target(1, 1, 60.0, 0.0, -20.0, 0.0), 0.0, 0.0)
    target = None
    for k in range(1, 6):
        _move_ego(ecu, 20.0, yaw_rps, PERIOD)
        target = ecu._coasted(k * PERIOD, PERIOD)
        if target is None:
            break
    assert (target is not None) is kept


def test_dead_reckoning_alone_raises_no_warning(tmp_path, monkeypatch):
    """The radar silent from 2.6 s while FCW pre-warns (TTC 3.6 s) for a car stopped ahead, the ego going on
    straight: the coast holds the pre-warning as the TTC runs down but never raises it to a warning (dead reckoning
    alone is no measurement; a second tester's finding raised one and held it to TTC 0)."""
    res, dec, wire = _run_cut(monkeypatch, _stopped_car(tmp_path), 2.6, _radar)
    t = np.array([d.t_s for d in dec])
    before = [d for d, x in zip(dec, t) if x < 2.6]
    assert before[-1].warning_level == 1 and before[-1].fcw_target is not None
    coasted = [d for d, x in zip(dec, t) if x > 2.6 and d.fcw_target is not None]
    assert len(coasted) >= 20 and all(d.warning_level <= 1 and not d.radar_ok for d in coasted)
    assert min(d.ttc_s for d in coasted) < 2.8                    # a warning's TTC reached, and not warned for


def test_the_yaw_rate_missing_is_a_fault_too(tmp_path, monkeypatch):
    """YawRateInformation 0x301 gone from 0.5 s (SpeedInformation still there): the ego motion is missing (bit 1);
    back from 3 s, current again within a cycle (a tester's finding: only 0x300's loss was a fault)."""
    keep = CycleAssembler.on_message_received

    def cut(self, msg):
        if msg.arbitration_id == 0x301 and msg.timestamp is not None and 0.5 - 1e-9 <= msg.timestamp < 3.0 - 1e-9:
            return None
        return keep(self, msg)

    monkeypatch.setattr(CycleAssembler, "on_message_received", cut)
    decisions = []
    frames = Ecu.frames
    monkeypatch.setattr(Ecu, "frames", lambda self, out, timestamp=None: decisions.append(out) or
                        frames(self, out, timestamp))
    simulate(load_scenario(_stopped_car(tmp_path)))
    for d in decisions:
        missing = 0.432 + 3 * PERIOD + 1e-9 < d.t_s < 3.0 - 1e-9
        assert (d.fault == 2) is missing and d.ego_ok is not missing, (d.t_s, d.fault)


def test_a_silent_radar_gets_a_decision_every_cycle(tmp_path, monkeypatch):
    """While the radar is silent the ECU decides on its timer once a cycle: cycle times k·0.072 are a period apart
    to rounding (48·0.072 − 47·0.072 < 0.072), and every seventh decision, its status frames and a coasted warning,
    was skipped (a tester's finding)."""
    res, dec, wire = _run_cut(monkeypatch, _stopped_car(tmp_path), 3.0, _radar)
    t = np.array([d.t_s for d in dec])
    silent = t[t > 2.952 + 3 * PERIOD + 1e-9]                # the last cycle at 2.952 s, unavailable 3 periods on
    assert silent.size == round((8.0 - 3.24) / PERIOD) and np.allclose(np.diff(silent), PERIOD)
    assert len(wire[FCW_STATUS]) == len(t)
