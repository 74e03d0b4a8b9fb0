"""A speed profile driven along waypoints, actors with heights, and the ego's driver model (issue 10)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from radarnode.consumer.evaluate import NO_BRAKING_MPS2, _judge, simulate
from radarnode.errors import ScenarioError
from radarnode.radar.setup import load_scenario
from radarnode.scene.scenario import Driver, read_scenario_text
from radarnode.scene.world import Scene
from tests.conftest import SCENARIOS

PATH = """name: t
duration_s: 10.0
seed: 1
ego: {{speed_mps: 20.0}}
road: {{lanes: 3, ego_lane: 1}}
actors:
  - id: a
    class: car
    {extra}
    waypoints: [{{x_m: 20.0, y_m: 3.5}}, {{x_m: 50.0, y_m: 3.5}}, {{x_m: 90.0, y_m: 0.0}}]
"""


def _scene(extra: str) -> Scene:
    sc = read_scenario_text(PATH.format(extra=extra))
    return Scene(dataclasses.replace(sc, cycle_period_s=0.072))


def test_a_speed_profile_drives_along_untimed_waypoints_and_on_beyond_the_last():
    scene = _scene("speed_mps: 10.0\n    accel: [{t_s: 5.0, accel_mps2: -2.0}]")
    leg2 = math.hypot(40.0, 3.5)
    ux, uy = 40.0 / leg2, -3.5 / leg2
    t = np.array([0.0, 2.0, 3.0, 5.0, 6.0, 9.0, 20.0])
    st = scene._movers.state(t)
    dist = np.array([0.0, 20.0, 30.0, 50.0, 59.0, 74.0, 75.0])        # 10 m/s, then −2 m/s² from 5 s: stops at 10 s
    on2 = dist >= 30.0
    x = np.where(on2, 50.0 + (dist - 30.0) * ux, 20.0 + dist)
    y = np.where(on2, 3.5 + (dist - 30.0) * uy, 3.5)
    beyond = dist > 30.0 + leg2                                       # past the last waypoint: straight on
    assert beyond[-1] and beyond[-2]
    np.testing.assert_allclose(st.x_m[:, 0], x, atol=1e-9)
    np.testing.assert_allclose(st.y_m[:, 0], y, atol=1e-9)
    speed = np.hypot(st.vx_mps[:, 0], st.vy_mps[:, 0])
    np.testing.assert_allclose(speed, [10, 10, 10, 10, 8, 2, 0], atol=1e-9)
    # the velocity points along the leg the actor is on; braking acts along it too
    assert st.vy_mps[4, 0] == pytest.approx(8.0 * uy) and st.ay_mps2[4, 0] == pytest.approx(-2.0 * uy)


def test_an_actor_without_a_path_beside_one_with_a_path_steps_without_a_nan_warning():
    """A car on a speed profile beside one driven along untimed waypoints warned "invalid value encountered in
    multiply" on every step (an independent tester's cut-out scene): the path's numbers of the car without one were
    inf·0, discarded but computed. Now they are finite, and the car's own motion is as without the other."""
    import warnings
    text = PATH.format(extra="speed_mps: 10.0") + "  - {id: b, class: car, x_m: 40.0, y_m: 0.0, speed_mps: 1.5}\n"
    scene = Scene(dataclasses.replace(read_scenario_text(text), cycle_period_s=0.072))
    t = np.array([0.0, 1.0, 5.0, 20.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        st = scene._movers.state(t)
    b = [a.id for a in scene.scenario.actors].index("b")
    np.testing.assert_allclose(st.x_m[:, b], 40.0 + 1.5 * t, atol=1e-9)
    np.testing.assert_allclose(st.y_m[:, b], 0.0, atol=1e-12)
    assert np.all(np.isfinite(st.x_m)) and np.all(np.isfinite(st.y_m))


def test_a_timed_path_is_as_before():
    text = PATH.format(extra="speed_mps: 10.0").replace("{x_m: 20.0, y_m: 3.5}", "{t_s: 0.0, x_m: 20.0, y_m: 3.5}") \
        .replace("{x_m: 50.0, y_m: 3.5}", "{t_s: 2.0, x_m: 50.0, y_m: 3.5}").replace(
            "{x_m: 90.0, y_m: 0.0}", "{t_s: 6.0, x_m: 90.0, y_m: 0.0}")
    scene = Scene(dataclasses.replace(read_scenario_text(text), cycle_period_s=0.072))
    st = scene._movers.state(np.array([1.0, 4.0, 8.0]))
    np.testing.assert_allclose(st.x_m[:, 0], [35.0, 70.0, 90.0])
    np.testing.assert_allclose(st.y_m[:, 0], [3.5, 1.75, 0.0])


def _refused(path, text: str, fragments, line: int | None = None) -> None:
    """Loading ``text`` written to ``path`` raises a ScenarioError naming every fragment (and the line, if given)."""
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    msg = str(info.value)
    if line is not None:
        assert msg.startswith(f"{path}:{line}:"), msg
    for f in fragments:
        assert f in msg, msg


@pytest.mark.parametrize("extra, fragments", [
    ("accel: [{t_s: 1.0, accel_mps2: -2.0}]\n    lane: 1", ("actors[0].lane", "value 1", "conflicts with",
                                                          "starts at the first waypoint, y_m 3.5")),
    ("y_m: 0.0", ("actors[0].y_m", "0.0", "it starts at the first waypoint")),
    ("heading_deg: 10.0", ("actors[0].heading_deg", "10.0", "they head 0.0, -5.0°")),
])
def test_a_path_refuses_what_contradicts_it(tmp_path, extra, fragments):
    _refused(tmp_path / "bad.yaml", PATH.format(extra=extra), fragments)


@pytest.mark.parametrize("extra", ["y_m: 3.5", "lane: 2", "heading_deg: 0.0", "heading_deg: -5.0", "x_m: 20.0"])
def test_a_path_takes_what_agrees_with_it_as_a_note(tmp_path, extra):
    """An untimed path refused a heading, y_m or lane even where they agreed with its waypoints (an independent
    tester's finding: the scenarios README says a field that agrees is taken as a note, as on a timed path)."""
    p = tmp_path / "ok.yaml"
    p.write_text(PATH.format(extra=extra + "\n    speed_mps: 10.0"))
    sc = load_scenario(p)
    times = np.array([0.0, 2.0, 4.0, 8.0])
    moved, bare = Scene(sc)._movers.state(times), _scene("speed_mps: 10.0")._movers.state(times)
    assert moved.x_m[-1, 0] > 90.0 and moved.y_m[-1, 0] < 0.5          # driven along its path
    np.testing.assert_array_equal(moved.x_m, bare.x_m)            # the note changes nothing of the path
    np.testing.assert_array_equal(moved.y_m, bare.y_m)


def test_mixed_timed_and_untimed_waypoints_and_accel_with_times_are_refused(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text(PATH.format(extra="speed_mps: 5.0").replace("{x_m: 50.0, y_m: 3.5}", "{t_s: 2.0, x_m: 50.0, y_m: 3.5}"))
    with pytest.raises(ScenarioError,
                       match=r":10: field 'actors\[0\].waypoints\[0\].t_s' \(actor 'a'\): value null.*on every waypoint"):
        load_scenario(p)
    timed = PATH.format(extra="accel: [{t_s: 1.0, accel_mps2: -2.0}]").replace(
        "{x_m: 20.0, y_m: 3.5}", "{t_s: 0.0, x_m: 20.0, y_m: 3.5}").replace(
        "{x_m: 50.0, y_m: 3.5}", "{t_s: 2.0, x_m: 50.0, y_m: 3.5}").replace(
        "{x_m: 90.0, y_m: 0.0}", "{t_s: 6.0, x_m: 90.0, y_m: 0.0}")
    p.write_text(timed)
    with pytest.raises(ScenarioError, match=r"field 'actors\[0\].accel'.*no accel with timed waypoints"):
        load_scenario(p)
    p.write_text(PATH.format(extra="speed_mps: 5.0").replace("{x_m: 90.0, y_m: 0.0}", "{x_m: 50.0, y_m: 3.5}"))
    with pytest.raises(ScenarioError, match=r"field 'actors\[0\].waypoints\[2\]'.*different from the one before"):
        load_scenario(p)


HEIGHTS = """name: t
duration_s: 2.0
seed: 1
actors:
  - {{id: a, class: {cls}, x_m: 100.0, y_m: 0.0{extra}}}
"""


def test_actors_have_a_height_and_overhead_classes_default_to_their_clearance():
    for cls, z, h, elevated in (("car", 0.0, 1.5, False), ("bridge", 5.0, 1.5, True), ("gantry", 5.5, 2.0, True),
                                ("truck", 0.0, 3.5, False)):
        a = read_scenario_text(HEIGHTS.format(cls=cls, extra="")).actors[0]
        assert (a.z, a.height, a.elevated) == (z, h, elevated), cls
    sign = read_scenario_text(HEIGHTS.format(cls="sign", extra=", z_m: 5.2, height_m: 1.2")).actors[0]
    assert (sign.z, sign.height, sign.elevated) == (5.2, 1.2, True)
    assert read_scenario_text(HEIGHTS.format(cls="bridge", extra="")).actors[0].swerling_case == 0


@pytest.mark.parametrize("extra, fragments", [
    (", z_m: -0.1", ("actors[0].z_m", "-0.1", "[0, 20]")),
    (", z_m: 20.5", ("actors[0].z_m", "20.5", "[0, 20]")),
    (", z_m: high", ("actors[0].z_m", "'high'", "a number")),
    (", height_m: 0", ("actors[0].height_m", "value 0", "(0, 50]")),
    (", height_m: .inf", ("actors[0].height_m", "inf", "finite")),
])
def test_bad_heights_name_the_field(tmp_path, extra, fragments):
    _refused(tmp_path / "bad.yaml", HEIGHTS.format(cls="sign", extra=extra), fragments, line=5)


@pytest.mark.parametrize("driver, fragments", [
    ("{reaction_s: -0.1}", ("ego.driver.reaction_s", "-0.1", "[0, 5]")),
    ("{reaction_s: 5.5}", ("ego.driver.reaction_s", "5.5")),
    ("{decel_mps2: 0.5}", ("ego.driver.decel_mps2", "0.5", "[1, 12]")),
    ("{decel_mps2: 13}", ("ego.driver.decel_mps2", "13")),
    ("{decel_mps2: hard}", ("ego.driver.decel_mps2", "'hard'")),
    ("{brake_mps2: 6}", ("unknown field 'ego.driver.brake_mps2'", "decel_mps2, reaction_s")),
])
def test_bad_driver_values_name_the_field(tmp_path, driver, fragments):
    _refused(tmp_path / "bad.yaml", f"name: t\nduration_s: 2.0\nseed: 1\nego:\n  speed_mps: 20.0\n  driver: {driver}\n",
             fragments, line=6)


def test_the_driver_brakes_a_reaction_time_after_the_warning_and_stops_in_time():
    sc = load_scenario(SCENARIOS / "nhtsa_lead_stopped.yaml")
    long = dataclasses.replace(sc, duration_s=9.0)
    alone = simulate(long)
    assert alone.impact_time_s is not None and alone.driver_brake_time_s is None      # no driver: it hits
    runs = {}
    for reaction, decel in ((0.8, 8.0), (0.5, 8.0), (1.2, 6.0)):
        r = simulate(dataclasses.replace(long, ego=dataclasses.replace(sc.ego, driver=Driver(reaction, decel))))
        runs[reaction] = r
        assert r.warning_time_s == alone.warning_time_s                              # the ECU is the same
        assert r.driver_brake_time_s == pytest.approx(r.warning_time_s + reaction, abs=1e-9)
        # before the driver's foot is on the brake the ego keeps its speed; then the brake builds up to his
        t, speed, accel = r.trace["t"], r.trace["speed"], r.trace["accel"]
        assert np.all(speed[t <= r.driver_brake_time_s] == pytest.approx(20.1))
        assert accel[np.searchsorted(t, r.driver_brake_time_s + 1.2)] == pytest.approx(-decel, abs=0.15)
    # an alert driver with an emergency stop avoids the car; 1.2 s and 6 m/s² are not enough at 45 mph from a
    # warning at TTC 2.7 s (54 m: 24 m of reaction, 6 m of brake build-up, 34 m of braking)
    for reaction in (0.8, 0.5):
        r = runs[reaction]
        assert r.impact_time_s is None and r.trace["speed"][-1] == 0.0 and r.min_gap_m > 0.0
    assert runs[1.2].impact_time_s is not None
    # 0.3 s sooner on the brake at 20.1 m/s is 6 m more room
    assert runs[0.5].min_gap_m - runs[0.8].min_gap_m == pytest.approx(0.3 * 20.1, abs=0.8)


def test_no_braking_fails_on_an_acc_braking_request_or_the_driver():
    sc = load_scenario(SCENARIOS / "bridge_90.yaml")
    r = simulate(dataclasses.replace(sc, duration_s=2.0))
    assert r.passed and r.checked
    for request, fails in ((NO_BRAKING_MPS2 + 0.01, False), (NO_BRAKING_MPS2, False), (NO_BRAKING_MPS2 - 0.01, True),
                           (2 * NO_BRAKING_MPS2, True)):
        res = dataclasses.replace(r, reasons=[], passed=True, trace=dict(r.trace))
        res.trace["request"] = r.trace["request"].copy()
        res.trace["request"][5] = request
        _judge(sc, res)
        assert res.passed != fails, (request, res.reasons)
    res = dataclasses.replace(r, reasons=[], passed=True, driver_brake_time_s=1.0)
    _judge(sc, res)
    assert not res.passed and "the driver braked" in res.reasons[0]
