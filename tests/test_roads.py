"""Roads of straight, arc and clothoid segments (issue 10): the geometry, the scenario format and its errors, and
everything in the scene that follows the road (actors, ego motion and yaw rate, guardrails, lane lines, the
judge's gap)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.special import fresnel

from radarnode.errors import ScenarioError
from radarnode.radar.setup import load_scenario
from radarnode.scene.road import TABLE_STEP_M, RoadGeometry
from radarnode.scene.scenario import read_scenario_text
from radarnode.scene.world import Scene

ENTRY = [(100.0, 0.0, 0.0), (60.0, 0.0, 0.004), (200.0, 0.004, 0.004)]    # straight, clothoid, arc

ROAD_YAML = """name: t
duration_s: 4.0
seed: 1
ego: {{speed_mps: 20.0}}
road:
  lanes: 2
  ego_lane: 0
  segments:
{segments}
actors:
  - {{id: a, class: car, x_m: 150.0, lane: 1}}
"""
SEGMENTS = """    - {type: straight, length_m: 100}
    - {type: clothoid, length_m: 60, curvature_start_1pm: 0, curvature_end_1pm: 0.004}
    - {type: arc, length_m: 200, curvature_1pm: 0.004}"""


def test_an_arc_is_the_closed_form_circle_in_both_directions():
    k = -0.004
    g = RoadGeometry(curvature_1pm=k)
    s = np.array([-300.0, -1.0, 0.0, 1.0, 250.0, 900.0])
    x, y, th = g.pose(s)
    np.testing.assert_allclose(x, np.sin(k * s) / k, atol=1e-9)
    np.testing.assert_allclose(y, (1.0 - np.cos(k * s)) / k, atol=1e-9)
    np.testing.assert_allclose(th, k * s, atol=1e-12)
    np.testing.assert_allclose(g.curvature(s), k)


def test_a_clothoid_is_the_fresnel_spiral_and_the_pieces_join_smoothly():
    g = RoadGeometry(ENTRY)
    u = np.linspace(0.0, 60.0, 61)
    x, y, th = g.pose(100.0 + u)
    a = math.sqrt(math.pi * 60.0 / 0.004)            # θ(u) = u²/(2·L/κ1)  ⇒  x + jy = a·(C + jS)(u/a)
    s_f, c_f = fresnel(u / a)
    np.testing.assert_allclose(x, 100.0 + a * c_f, atol=1e-9)
    np.testing.assert_allclose(y, a * s_f, atol=1e-9)
    np.testing.assert_allclose(th, u ** 2 * 0.004 / 120.0, atol=1e-12)
    np.testing.assert_allclose(g.curvature(100.0 + u), 0.004 * u / 60.0, atol=1e-15)
    for b in (100.0, 160.0, 360.0):                       # position and heading continuous at every joint
        p = np.array(g.pose(np.array([b - 1e-7, b + 1e-7])))
        assert np.all(np.abs(np.diff(p, axis=1)) < 1e-6), (b, p)
    # beyond the last segment the end curvature holds (an arc), before the first the start curvature (straight)
    assert g.curvature(np.array([5000.0]))[0] == 0.004 and g.curvature(np.array([-50.0]))[0] == 0.0
    np.testing.assert_allclose(g.pose(np.array([-50.0]))[0], [-50.0])


def test_the_table_step_does_not_change_the_answer():
    # between table points the clothoid is integrated, not interpolated: a point halfway is as exact as a knot
    g = RoadGeometry(ENTRY)
    u = np.array([0.5, 0.5 * TABLE_STEP_M, 0.999 * TABLE_STEP_M, 31.3])
    x, y, _ = g.pose(100.0 + u)
    a = math.sqrt(math.pi * 60.0 / 0.004)
    s_f, c_f = fresnel(u / a)
    np.testing.assert_allclose(y, a * s_f, atol=1e-9)


def test_queries_of_any_shape_and_offset_lines():
    g = RoadGeometry(ENTRY)
    s = np.linspace(0.0, 400.0, 24).reshape(4, 6)
    x, y, th = g.to_world(s, np.full(s.shape, 3.5))
    assert x.shape == y.shape == th.shape == (4, 6)
    xc, yc, _ = g.pose(s)
    np.testing.assert_allclose(np.hypot(x - xc, y - yc), 3.5, atol=1e-9)
    # the length of a line 3.5 m to the left between two stations: ∫(1 − κd) ds
    assert g.lane_length(0.0, 100.0, 3.5) == pytest.approx(100.0)
    arc = float(g.lane_length(200.0, 300.0, 3.5))
    assert arc == pytest.approx(100.0 * (1.0 - 0.004 * 3.5), rel=1e-12)
    # through the clothoid: s − d·Δθ, with Δθ = 0.12 rad over it
    assert float(g.lane_length(100.0, 160.0, -2.0)) == pytest.approx(60.0 + 2.0 * 0.12, rel=1e-12)


def test_segments_in_the_scenario_and_the_scene_following_them():
    sc = read_scenario_text(ROAD_YAML.format(segments=SEGMENTS))
    assert [s.type for s in sc.road.segments] == ["straight", "clothoid", "arc"]
    scene = Scene(dataclasses.replace(sc, cycle_period_s=0.072))
    g = scene.road
    # the ego's yaw rate is κ(s)·v: zero on the straight, a ramp through the clothoid, κ·v on the arc
    for s_m, kappa in ((50.0, 0.0), (130.0, 0.002), (155.0, 0.004 * 55 / 60), (250.0, 0.004)):
        e = scene.ego_state(s_m / 20.0)
        assert e.yaw_rate_rps == pytest.approx(kappa * 20.0, abs=1e-9), s_m
        x, y, th = g.pose(np.array([s_m]))
        assert (e.x_m, e.y_m, e.heading_rad) == pytest.approx((x[0], y[0], th[0]), abs=1e-9)
    # an actor in lane 1 at station 150 sits 3.5 m to the left of the reference line there, heading with the road
    view = scene.view(0.0)
    x, y, th = g.to_world(np.array([150.0]), np.array([3.5]))
    assert math.hypot(view.centre_x_m[0] - (x[0] - 3.7), view.centre_y_m[0] - y[0]) < 1e-6
    assert view.orientation_rad[0] == pytest.approx(th[0], abs=1e-9)
    # lane lines and guardrail posts follow the road: every point of the line 3.5 m left lies 3.5 m from it
    lx, ly = scene.road_line(2.0, 3.5, 200.0, 2.0)
    cx, cy = scene.road_line(2.0, 0.0, 200.0, 2.0)
    np.testing.assert_allclose(np.hypot(lx - cx, ly - cy), 3.5, atol=1e-6)
    assert ly[-1] > 20.0                     # 200 m ahead of station 40 the road has turned left


def test_guardrail_posts_and_the_judge_follow_the_segments():
    text = ROAD_YAML.format(segments=SEGMENTS).replace("  segments:", "  guardrails: {right_offset_m: 1.0}\n"
                                                                       "  segments:")
    sc = dataclasses.replace(read_scenario_text(text), cycle_period_s=0.072)
    scene = Scene(sc)
    gx, gy = scene.guardrail_posts(5.0, 250.0)
    # every post lies 2.75 m to the right of the reference line (ego lane 0 of two: edge 1.75 m, offset 1 m)
    ego = scene.ego_state(5.0)
    px, py, psi, _, _ = scene.sensor_pose(ego)
    wx = px + np.cos(psi) * gx - np.sin(psi) * gy
    wy = py + np.sin(psi) * gx + np.cos(psi) * gy
    s = np.linspace(-20.0, 500.0, 52001)
    rx, ry, _ = scene.road.pose(s)
    d = np.min(np.hypot(wx[:, None] - rx[None, :], wy[:, None] - ry[None, :]), axis=1)
    np.testing.assert_allclose(d, 2.75, atol=0.01)
    # the judge's gap to an actor is along the ego's lane, through the clothoid
    gap = scene.lane_gap(0.0, 0)[0]
    assert gap == pytest.approx(150.0 - 3.7 - 4.5 / 2.0, abs=1e-9)


def test_curvature_alone_is_still_one_arc():
    sc = load_scenario_text_with(road="{lanes: 2, ego_lane: 0, curvature_1pm: 0.004}")
    scene = Scene(sc)
    e = scene.ego_state(5.0)
    k, s = 0.004, 100.0
    assert (e.x_m, e.y_m, e.heading_rad) == pytest.approx((math.sin(k * s) / k, (1 - math.cos(k * s)) / k, k * s))
    assert e.yaw_rate_rps == pytest.approx(k * 20.0)


def load_scenario_text_with(road: str):
    text = ("name: t\nduration_s: 4.0\nseed: 1\nego: {speed_mps: 20.0}\n"
            f"road: {road}\nactors:\n  - {{id: a, class: car, x_m: 150.0, lane: 1}}\n")
    return dataclasses.replace(read_scenario_text(text), cycle_period_s=0.072)


@pytest.mark.parametrize("segment, fragments", [
    ("{type: spiral, length_m: 10}", ("road.segments[1].type", "'spiral'", "arc, clothoid, straight")),
    ("{type: straight, length_m: 0}", ("road.segments[1].length_m", "value 0", "(0, 100000]")),
    ("{type: straight, length_m: -5}", ("road.segments[1].length_m", "-5",)),
    ("{type: straight, length_m: 200000}", ("road.segments[1].length_m", "200000", "(0, 100000]")),
    ("{type: straight, length_m: .nan}", ("road.segments[1].length_m", "nan", "finite")),
    ("{type: straight, length_m: ten}", ("road.segments[1].length_m", "'ten'", "a number")),
    ("{type: arc, length_m: 10}", ("road.segments[1].curvature_1pm", "null", "curvature in 1/m for a arc")),
    ("{type: arc, length_m: 10, curvature_1pm: 0.06}", ("road.segments[1].curvature_1pm", "0.06", "[-0.05, 0.05]")),
    ("{type: straight, length_m: 10, curvature_1pm: 0.001}", ("road.segments[1].curvature_1pm", "0.001",
                                                              "not given for a straight segment")),
    ("{type: clothoid, length_m: 10, curvature_1pm: 0.001}", ("road.segments[1].curvature_1pm",
                                                              "curvature_start_1pm, curvature_end_1pm")),
    ("{type: clothoid, length_m: 10, curvature_start_1pm: 0}", ("road.segments[1].curvature_end_1pm", "null")),
    ("{type: clothoid, length_m: 10, curvature_start_1pm: 0, curvature_end_1pm: -0.051}",
     ("road.segments[1].curvature_end_1pm", "-0.051")),
    ("{type: arc, length_m: 10, radius_m: 250}", ("unknown field 'road.segments[1].radius_m'", "allowed here")),
])
def test_a_bad_segment_names_file_line_field_value_and_what_is_allowed(tmp_path, segment, fragments):
    text = ROAD_YAML.format(segments=f"    - {{type: straight, length_m: 100}}\n    - {segment}")
    p = tmp_path / "bad.yaml"
    p.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(p)
    msg = str(info.value)
    assert msg.startswith(f"{p}:10:"), msg          # the line of the bad segment
    for f in fragments:
        assert f in msg, msg


def test_curvature_and_segments_together_are_refused(tmp_path):
    p = tmp_path / "both.yaml"
    p.write_text(ROAD_YAML.format(segments=SEGMENTS).replace("  ego_lane: 0\n", "  ego_lane: 0\n"
                                                                                 "  curvature_1pm: 0.002\n"))
    with pytest.raises(ScenarioError, match=r"field 'road.segments'.*either curvature_1pm \(one arc\) or segments"):
        load_scenario(p)
    p.write_text(ROAD_YAML.format(segments="    - {type: straight, length_m: 100}").replace(
        "  segments:\n", "  segments: straight\n").replace("    - {type: straight, length_m: 100}\n", ""))
    with pytest.raises(ScenarioError, match=r"field 'road.segments': value 'straight'.*a list"):
        load_scenario(p)


@pytest.mark.parametrize("yaw_deg, x_m", [(180.0, -1.0), (135.0, -0.8), (45.0, 3.5), (90.0, 2.0), (0.0, 3.7)])
def test_guardrail_posts_reach_as_far_as_the_sensor_looks_whichever_way_it_faces(yaw_deg, x_m):
    """Posts were made from 5 m behind the ego to the range ahead of it: a rear radar (yaw 180°) saw none beyond 5 m
    behind at every level, 6 clusters where the front radar saw 200 (a tester's finding). Every post the sensor's
    ±90° about its yaw can reach, within the range, is there: as many as the road's posts put into the sensor's
    frame here."""
    text = f"""
name: t
duration_s: 1.0
seed: 1
radar: {{preset: ars408_like, mount: {{x_m: {x_m}, y_m: 0.0, yaw_deg: {yaw_deg}}}}}
ego: {{speed_mps: 20.0}}
road: {{lanes: 2, lane_width_m: 3.5, ego_lane: 0, guardrails: {{left_offset_m: 0.8, right_offset_m: 0.8}}}}
actors: []
"""
    sc = dataclasses.replace(read_scenario_text(text), cycle_period_s=0.072)
    scene = Scene(sc)
    reach = 250.0
    gx, gy = scene.guardrail_posts(0.5, reach)
    # every post 1 km either way of the road's start, into the sensor's frame
    st = np.arange(-500, 501) * sc.road.guardrails.post_spacing_m
    wx, wy = [], []
    for d in (sc.road.left_edge_y_m + 0.8, sc.road.right_edge_y_m - 0.8):
        x, y, _ = scene.road_to_world(st, np.full_like(st, d))
        wx.append(x)
        wy.append(y)
    px, py, psi, _, _ = scene.sensor_pose(scene.ego_state(0.5))
    dx, dy = np.concatenate(wx) - px, np.concatenate(wy) - py
    ax, ay = np.cos(psi) * dx + np.sin(psi) * dy, -np.sin(psi) * dx + np.cos(psi) * dy
    r, az = np.hypot(gx, gy), np.arctan2(gy, gx)
    ra, aza = np.hypot(ax, ay), np.arctan2(ay, ax)
    want = (ra <= reach) & (np.abs(aza) <= math.pi / 2)
    have = (r <= reach) & (np.abs(az) <= math.pi / 2)
    assert want.sum() > 100 and have.sum() == want.sum()
    if math.cos(math.radians(yaw_deg)) < 0.0:           # looking back: posts far behind the ego are seen
        assert r[have].max() > 200.0
