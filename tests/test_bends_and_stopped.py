"""ADAS on roads that are not straight (issue 10) and stopped vehicles at every level (issue 15).

The sensor sits 3.7 m ahead of the rear axle; the ECU knows it (``radar.mount`` reaches it as a calibrated
``SensorMount``) and predicts the path about the rear axle. Judged as ``radarnode report`` judges: the TTC at
the warning is measured along the ego's lane.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import pytest

from radarnode.consumer.evaluate import simulate
from radarnode.radar.setup import load_scenario

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"


def _at(name: str, x_m: float, seed: int):
    sc = load_scenario(SCENARIOS / f"{name}.yaml")
    lead = dataclasses.replace(sc.actors[0], x_m=x_m)
    return dataclasses.replace(sc, actors=(lead,), seed=seed, duration_s=min(sc.duration_s, x_m / 20.0 + 1.0))


@pytest.mark.parametrize("name", ["bend_r250_left_stopped_outer_lane", "bend_r250_right_stopped_outer_lane",
                                  "bend_r500_left_stopped_inner_lane", "bend_r250_right_stopped_inner_lane"])
@pytest.mark.parametrize("x_m", [50.0, 80.0, 110.0, 140.0])
def test_a_car_stopped_in_the_next_lane_of_a_bend_draws_no_warning(name, x_m):
    for seed in (1, 2):
        r = simulate(_at(name, x_m, seed), fidelity="object")
        assert r.warning_time_s is None, (name, x_m, seed, r.warning_time_s)


@pytest.mark.parametrize("x_m", [80.0, 110.0, 140.0])
def test_a_car_stopped_in_the_own_lane_of_a_250_m_bend_is_warned_in_time(x_m):
    for seed in (1, 2):
        r = simulate(_at("bend_r250_left_stopped_own_lane", x_m, seed), fidelity="object")
        assert r.warning_time_s is not None and r.ttc_at_warning_s >= 2.1, (x_m, seed, r.ttc_at_warning_s)


def test_the_judge_measures_the_ttc_along_the_bend():
    # before, a lead on a bend was "not ahead" (more than 2 m off the sensor's axis): the TTC at the warning
    # was infinite and passed any minimum
    r = simulate(_at("bend_r250_left_stopped_own_lane", 110.0, 1), fidelity="object")
    assert 2.0 < r.ttc_at_warning_s < 4.0 and r.min_gap_m < 10.0


@pytest.mark.parametrize("level", ["object", "detection"])
@pytest.mark.parametrize("name", ["ncap_ccrs_10kmh_full", "ncap_ccrs_10kmh_left50", "ncap_ccrs_50kmh_full",
                                  "ncap_ccrs_50kmh_right50", "nhtsa_lead_stopped"])
def test_a_stopped_car_in_the_path_is_warned_at_every_level(name, level):
    sc = load_scenario(SCENARIOS / f"{name}.yaml")
    r = simulate(sc, fidelity=level)
    assert r.passed, (name, level, r.reasons)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["ncap_ccrs_10kmh_right50", "ncap_ccrs_50kmh_left50", "nhtsa_lead_stopped"])
def test_a_stopped_car_in_the_path_is_warned_at_signal_level(name):
    r = simulate(load_scenario(SCENARIOS / f"{name}.yaml"), fidelity="signal")
    assert r.passed, (name, r.reasons)


@pytest.mark.parametrize("level", ["object", "detection"])
def test_a_car_stopped_beside_the_path_and_guardrails_draw_no_warning(level):
    for name in ("no_fcw_adjacent_stopped", "guardrail_traffic"):
        sc = load_scenario(SCENARIOS / f"{name}.yaml")
        r = simulate(sc, fidelity=level)
        assert r.warning_time_s is None or not sc.ecu.expect.no_fcw, (name, level, r.warning_time_s)
        assert r.passed, (name, level, r.reasons)


def test_acc_on_a_250_m_bend_follows_its_lead_and_never_the_truck_in_the_outer_lane():
    sc = load_scenario(SCENARIOS / "acc_follow_bend_250.yaml")
    r = simulate(sc)
    assert r.passed, r.reasons
    # the judge can fail: the same run, judged as if the truck were the one to follow (the expectation does not
    # steer the run: judged again, not simulated again, which took half of this test's minute)
    from radarnode.consumer.evaluate import _judge
    e = dataclasses.replace(sc.ecu.expect, acc_follows="truck", never_target=("lead",))
    again = dataclasses.replace(r, reasons=[], passed=True)
    _judge(dataclasses.replace(sc, ecu=dataclasses.replace(sc.ecu, expect=e)), again)
    assert not again.passed and any("lead selected as the target" in x for x in again.reasons), again.reasons
    assert any("ACC followed truck in 0%" in x for x in again.reasons), again.reasons


def test_an_expectation_names_actors_that_exist(tmp_path):
    from radarnode.errors import ScenarioError
    p = tmp_path / "x.yaml"
    p.write_text((SCENARIOS / "acc_follow_bend_250.yaml").read_text().replace("never_target: [truck]",
                                                                              "never_target: [lorry]"))
    with pytest.raises(ScenarioError, match=r"ecu.expect.never_target.*'lorry'.*lead, truck"):
        load_scenario(p)


def test_a_warning_after_the_impact_does_not_count():
    sc = load_scenario(SCENARIOS / "ncap_ccrb_12m.yaml")
    r = simulate(sc)
    assert r.impact_time_s is not None and r.warning_time_s < r.impact_time_s and r.passed
    # the judge: the same run with the warning moved to one cycle after the impact fails
    from radarnode.consumer.evaluate import _judge
    late = dataclasses.replace(r, warning_time_s=r.impact_time_s + 0.072, reasons=[], passed=True)
    _judge(sc, late)
    assert not late.passed and any("after the impact" in x for x in late.reasons), late.reasons


def test_the_ecu_settings_of_a_scenario_reach_the_ecu():
    from radarnode.consumer.evaluate import make_ecu
    sc = load_scenario(SCENARIOS / "nhtsa_lead_stopped.yaml")
    spec = dataclasses.replace(sc.ecu, path_half_width_m=1.2, fcw_ttc_warn_s=2.2, fcw_decel_warn_mps2=6.0,
                               acc_min_speed_mps=5.0)
    ecu = make_ecu(dataclasses.replace(sc, ecu=spec), 0.072)
    assert (ecu.acc.settings.path_half_width_m, ecu.acc.settings.min_speed_mps) == (1.2, 5.0)
    assert (ecu.fcw.settings.ttc_warn_s, ecu.fcw.settings.decel_warn_mps2) == (2.2, 6.0)
    assert ecu.mount.x_m == sc.radar.mount.x_m
    # a later threshold warns later: TTC at the warning follows the setting
    early = simulate(sc)
    late = simulate(dataclasses.replace(sc, ecu=dataclasses.replace(sc.ecu, fcw_ttc_warn_s=2.2,
                                                                      fcw_decel_warn_mps2=9.0)))
    assert late.ttc_at_warning_s < early.ttc_at_warning_s - 0.3, (early.ttc_at_warning_s, late.ttc_at_warning_s)


def test_prewarning_time_before_impact_and_the_lvd_ttc_can_be_required():
    sc = load_scenario(SCENARIOS / "ncap_ccrb_12m.yaml")
    r = simulate(sc)
    before = r.impact_time_s - r.warning_time_s
    assert r.prewarning_time_s is not None and r.prewarning_time_s <= r.warning_time_s
    from radarnode.consumer.evaluate import _judge
    for need, ok in ((before - 0.2, True), (before + 0.2, False)):
        e = dataclasses.replace(sc.ecu.expect, fcw_before_impact_s=round(need, 2), fcw_prewarning=True)
        res = dataclasses.replace(r, reasons=[], passed=True)
        _judge(dataclasses.replace(sc, ecu=dataclasses.replace(sc.ecu, expect=e)), res)
        assert res.passed == ok, (need, before, res.reasons)
    # NHTSA LVD: the TTC counts the lead's deceleration, so it is shorter than the constant-speed one
    lvd = load_scenario(SCENARIOS / "nhtsa_lead_decelerating.yaml")
    with_decel = simulate(lvd)
    const = simulate(dataclasses.replace(lvd, ecu=dataclasses.replace(
        lvd.ecu, expect=dataclasses.replace(lvd.ecu.expect, ttc_with_lead_decel=False))))
    assert with_decel.warning_time_s == const.warning_time_s
    assert with_decel.ttc_at_warning_s < const.ttc_at_warning_s - 0.1
    assert with_decel.passed and with_decel.ttc_at_warning_s >= 2.4


def test_an_expectation_with_nothing_to_check_says_so():
    sc = load_scenario(SCENARIOS / "ncap_ccrs.yaml")
    bare = dataclasses.replace(sc, ecu=dataclasses.replace(sc.ecu, expect=type(sc.ecu.expect)(lead="target")))
    assert simulate(sc).checked and not simulate(bare).checked


def test_the_ecu_outputs_carry_its_processing_latency():
    sc = load_scenario(SCENARIOS / "nhtsa_lead_stopped.yaml")
    lag = simulate(sc)
    zero = simulate(dataclasses.replace(sc, ecu=dataclasses.replace(sc.ecu, processing_latency_s=0.0)))
    assert lag.latency_s == 0.02 and zero.latency_s == 0.0
    assert abs((lag.warning_time_s - zero.warning_time_s) - 0.02) < 1e-9
    assert abs((zero.ttc_at_warning_s - lag.ttc_at_warning_s) - 0.02) < 0.01
    # in closed loop the request acts a latency later: ACC still settles, on a different trajectory
    acc = load_scenario(SCENARIOS / "acc_cut_in.yaml")
    slow = simulate(dataclasses.replace(acc, ecu=dataclasses.replace(acc.ecu, processing_latency_s=0.1)))
    fast = simulate(dataclasses.replace(acc, ecu=dataclasses.replace(acc.ecu, processing_latency_s=0.0)))
    assert slow.passed and fast.passed, (slow.reasons, fast.reasons)
    assert slow.trace["speed"][-1] != fast.trace["speed"][-1]


@pytest.mark.parametrize("level", ["object", "detection"])
@pytest.mark.parametrize("name", ["ncap_ccrb_12m", "ncap_ccrb_40m", "nhtsa_lead_decelerating"])
def test_the_lead_track_survives_hard_braking(name, level):
    r = simulate(load_scenario(SCENARIOS / f"{name}.yaml"), fidelity=level)
    tracks = r.trace["target_track"][r.trace["target"] == 0]
    assert tracks.size > 10 and len(set(tracks.tolist())) == 1, sorted(set(tracks.tolist()))


@pytest.mark.parametrize("level", ["object", "detection"])
@pytest.mark.parametrize("name", ["lane_change_to_stopped", "lane_change_past_stopped"])
def test_an_ego_lane_change_towards_and_away_from_a_stopped_car(name, level):
    for seed in (1, 2):
        r = simulate(dataclasses.replace(load_scenario(SCENARIOS / f"{name}.yaml"), seed=seed), fidelity=level)
        assert r.passed, (name, level, seed, r.reasons)


def test_a_lane_change_moves_and_turns_the_ego_and_is_checked(tmp_path):
    from radarnode.errors import ScenarioError
    from radarnode.scene.world import Scene
    sc = load_scenario(SCENARIOS / "lane_change_to_stopped.yaml")
    scene = Scene(sc)
    before, mid, after = (scene.ego_state(t) for t in (0.5, 2.5, 5.0))
    assert before.y_m == 0.0 and abs(after.y_m - 3.5) < 1e-9 and abs(mid.y_m - 1.75) < 1e-9
    # the heading and yaw rate of a cosine step: peak heading atan(dy·π/(2T)/v) at mid-manoeuvre
    assert abs(mid.heading_rad - math.atan(3.5 * math.pi / 6.0 / 20.0)) < 1e-3
    assert scene.ego_state(1.75).yaw_rate_rps > 0.02 and scene.ego_state(3.25).yaw_rate_rps < -0.02
    assert after.heading_rad == 0.0 and after.yaw_rate_rps == 0.0
    text = (SCENARIOS / "lane_change_to_stopped.yaml").read_text()
    for bad, msg in (("to_lane: 1}", "to_lane: 2}"), ("to_lane: 1}", "to_lane: 1, by_m: 3.5}"),
                     ("duration_s: 3.0", "duration_s: 0.1")):
        p = tmp_path / "lane_change.yaml"
        p.write_text(text.replace(bad, msg))
        with pytest.raises(ScenarioError, match=r"ego.lane_change"):
            load_scenario(p)


def _variant(name: str, seed: int, **radar):
    sc = load_scenario(SCENARIOS / f"{name}.yaml")
    mount = dataclasses.replace(sc.radar.mount, **radar)
    return dataclasses.replace(sc, radar=dataclasses.replace(sc.radar, mount=mount), seed=seed)


@pytest.mark.parametrize("yaw_deg", [-3.5, 3.5, 8.0])
def test_a_car_stopped_on_a_curve_entry_is_warned_in_time_with_the_sensor_yawed(yaw_deg):
    """The shipped clothoid entry with the sensor yawed: from 3.5° on the ECU took the straight road's boundaries for a
    lane change, dropped them and warned at TTC 1.69–1.84 s (required ≥ 2.1 s; an independent tester's finding)."""
    for seed in (1, 2):
        r = simulate(_variant("clothoid_stopped_own_lane", seed, yaw_deg=yaw_deg), fidelity="object")
        assert r.passed, (yaw_deg, seed, r.reasons)


@pytest.mark.parametrize("yaw_deg", [-3.5, 3.5])
def test_a_car_stopped_in_the_outer_lane_of_a_curve_entry_is_left_alone_with_the_sensor_yawed(yaw_deg):
    for seed in (1, 2):
        r = simulate(_variant("clothoid_stopped_outer_lane", seed, yaw_deg=yaw_deg), fidelity="object")
        assert r.passed, (yaw_deg, seed, r.reasons)


@pytest.mark.parametrize("mount_y", [-0.5, 0.5])
def test_a_car_stopped_in_the_next_lane_is_no_target_with_the_sensor_off_centre(mount_y):
    """Straight road, 3.0 m lanes, guardrails, a car stopped at the centre of the next lane: with the sensor 0.5 m
    left of the car's centre line the far path (the boundaries' course) followed the sensor's line, and FCW took the
    car as its object in 0 of 5 seeds passing (an independent tester's finding)."""
    from radarnode.radar.setup import parse_scenario
    text = f"""
name: next_lane_off_centre
duration_s: 6.0
seed: 1
radar: {{preset: ars408_like, mount: {{x_m: 3.7, y_m: {mount_y}, yaw_deg: 0.0}}}}
ego: {{speed_mps: 22.0}}
road: {{lanes: 2, lane_width_m: 3.0, ego_lane: 0, guardrails: {{left_offset_m: 0.8, right_offset_m: 0.8,
        post_spacing_m: 4.0, rcs_dbsm: -3.0}}}}
ecu: {{acc_enabled: false, expect: {{lead: stopped, no_fcw: true, never_target: [stopped]}}}}
actors:
  - {{id: stopped, class: car, x_m: 130.0, lane: 1, speed_mps: 0.0}}
"""
    for seed in (1, 2, 3):
        r = simulate(dataclasses.replace(parse_scenario(text), seed=seed), fidelity="object")
        assert r.passed, (mount_y, seed, r.reasons)


_ONCOMING = """
name: {name}
duration_s: 10.0
seed: 1
radar: {{preset: ars408_like}}
ego: {{speed_mps: 20.0}}
road:
  lanes: 2
  lane_width_m: 3.5
  ego_lane: 0
  segments:
{segments}
ecu: {{acc_enabled: true, set_speed_mps: 20.0, closed_loop: true, expect: {{lead: onc, no_fcw: true,
      never_target: [onc]}}}}
actors:
  - {{id: onc, class: car, x_m: {x}, lane: 1, speed_mps: 20.0, heading_deg: 180.0}}
"""


@pytest.mark.parametrize("name, segments, x", [
    ("curve_entry_right", "    - {type: straight, length_m: 100}\n"
                          "    - {type: clothoid, length_m: 80, curvature_start_1pm: 0.0, curvature_end_1pm: -0.004}\n"
                          "    - {type: arc, length_m: 600, curvature_1pm: -0.004}", 400.0),
    ("curve_exit_left", "    - {type: arc, length_m: 100, curvature_1pm: 0.004}\n"
                        "    - {type: clothoid, length_m: 60, curvature_start_1pm: 0.004, curvature_end_1pm: 0.0}\n"
                        "    - {type: straight, length_m: 600}", 420.0)])
def test_an_oncoming_car_at_a_curve_entry_or_exit_is_neither_acc_s_target_nor_fcw_s(name, segments, x):
    """The yaw-rate circle lags a curve entry (and a curve exit) and puts the oncoming lane in the path: ACC took an
    oncoming car as its target for 11–12 cycles and braked at −2.2 m/s², FCW warned at TTC 2.8 s (0 of 3 seeds
    passing; an independent tester's finding). Oncoming tracks are no target for either now."""
    from radarnode.radar.setup import parse_scenario
    sc = parse_scenario(_ONCOMING.format(name=name, segments=segments, x=x))
    for seed in (1, 2, 3):
        r = simulate(dataclasses.replace(sc, seed=seed), fidelity="object")
        assert r.passed and r.warning_time_s is None and r.peak_decel_mps2 < 0.3, (name, seed, r.reasons,
                                                                                   r.peak_decel_mps2)


@pytest.mark.parametrize("speed, warned", [(1.5, True), (3.1, True), (4.5, True), (10.0, False)])
def test_a_car_coming_our_way_in_the_own_lane_is_fcw_s_below_the_oncoming_speed_and_not_at_twice_it(speed, warned):
    """The oncoming rule's threshold (ONCOMING_MPS = 5 m/s against the path): a car rolling or reversing towards the
    ego at 1.5–4.5 m/s is a vehicle in the path to warn for (at 3 m/s, the first threshold, one reversing at 3.1 m/s
    drew no warning: an independent tester's finding); one at 10 m/s (twice the limit) is oncoming traffic, which
    neither ACC nor FCW addresses (ISO 15622/15623; a wrong-way driver is out of their scope)."""
    from radarnode.radar.setup import parse_scenario
    text = f"""
name: rolling_back
duration_s: 6.0
seed: 1
radar: {{preset: ars408_like}}
ego: {{speed_mps: 20.0}}
road: {{lanes: 2, lane_width_m: 3.5, ego_lane: 0}}
ecu: {{acc_enabled: false, expect: {{lead: back}}}}
actors:
  - {{id: back, class: car, x_m: 120.0, lane: 0, speed_mps: {speed}, heading_deg: 180.0}}
"""
    r = simulate(parse_scenario(text), fidelity="object")
    assert (r.warning_time_s is not None) == warned, (speed, r.warning_time_s, r.reasons)
