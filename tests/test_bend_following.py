"""A vehicle ahead on the ego's bend at the ego's speed: the gap along the lane stays constant, although its
velocity relative to the sensor points across the bend (issue 9: the levels agree with the truth; ACC right on
bends). The radar's tracker, the object level's smoothing and the ECU's tracker let their objects follow the
ego's road (radarnode.perception.tracker.predict, radarnode.consumer.tracking.road_turn), and the ECU takes the
lead's closing speed and deceleration along the path where the lead is."""

from __future__ import annotations

import dataclasses
import importlib.util
import math

import numpy as np
import pytest

from radarnode.consumer.evaluate import simulate
from radarnode.consumer.tracking import predict as ecu_predict
from radarnode.perception.motion import road_turn, transition
from radarnode.perception.tracker import predict as radar_predict
from radarnode.radar.models import make_model
from radarnode.radar.object_model import RuntimeConfig
from radarnode.radar.setup import parse_scenario, radar_config
from radarnode.scene.world import Scene
from tests.conftest import ROOT

def _bend(duration: float, seed: int, speed: float, radius: float):
    """``benchmarks/bends.py``'s scene: a lead at the ego's speed 1.5 s ahead on a constant bend, ACC closed loop."""
    spec = importlib.util.spec_from_file_location("bends_bench", ROOT / "benchmarks" / "bends.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    sc = parse_scenario(mod.FOLLOW.format(radius=radius, speed=speed, curv=1.0 / radius, gap=1.5,
                                          lead_x=round(1.5 * speed + 5.7, 2)))
    return dataclasses.replace(sc, duration_s=duration, seed=seed)


def _co_turning(dt=0.072, w=0.2, u=(20.0, 0.74)):
    """A lead on the ego's circle (κ = w/|u|) at its speed, 30 m ahead: its velocity relative to the sensor is
    ω × (its place) (both turn about the bend's centre), constant in the sensor's axes."""
    p = np.array([30.0, 4.6])
    v = w * np.array([-p[1], p[0]])
    return np.array([[*p, *v]]), dt, w, u


def test_road_turn_keeps_a_co_turning_lead_and_a_standing_object_where_they_are():
    x, dt, w, u = _co_turning()
    f, _ = transition("cv", dt, 4.0)
    moved, _ = road_turn(x, x @ f.T, w * dt, dt, u)
    assert np.allclose(moved[0, 2:], x[0, 2:], atol=0.01)               # its relative velocity stays
    # the world-fixed model (every vector turned by −ω·dt) turns it by 0.8° a cycle: 0.09 m/s across
    c, s = math.cos(-w * dt), math.sin(-w * dt)
    turned = np.array([c * x[0, 2] - s * x[0, 3], s * x[0, 2] + c * x[0, 3]])
    assert np.linalg.norm(turned - x[0, 2:]) > 0.05
    # a standing object: its velocity relative to the sensor is −u (sensor axes), and stays −u
    still = np.array([[40.0, -3.0, -u[0], -u[1]]])
    moved, _ = road_turn(still, still @ f.T, w * dt, dt, u)
    assert np.allclose(moved[0, 2:], [-u[0], -u[1]], atol=1e-12)
    # and its place moves by −u·dt, then turns by −ω·dt: where a point fixed on the ground is
    p = still[0, :2] - np.array(u) * dt
    assert np.allclose(moved[0, :2], [c * p[0] - s * p[1], s * p[0] + c * p[1]], atol=1e-12)


def test_the_radar_tracker_and_the_ecu_tracker_predict_the_same_road_motion():
    x, dt, w, u = _co_turning()
    p = np.eye(4)[None] * 0.5
    xr, _ = radar_predict(x, p, dt, yaw_rate_rps=w, sensor_velocity=u)
    x6 = np.concatenate([x, np.zeros((1, 2))], axis=1)
    xe, pe = ecu_predict(x6, np.eye(6)[None], "ca", dt, 4.0, w * dt, (u, (0.0, 0.0)))
    assert np.allclose(xr[0], xe[0, :4], atol=1e-12)
    assert np.allclose(pe, np.swapaxes(pe, 1, 2)) and np.all(np.linalg.eigvalsh(pe) > 0)
    # on a straight road (no yaw) the road model is the constant-velocity step
    xs, _ = radar_predict(x, p, dt, yaw_rate_rps=0.0, sensor_velocity=u)
    assert np.allclose(xs[0], [x[0, 0] + x[0, 2] * dt, x[0, 1] + x[0, 3] * dt, x[0, 2], x[0, 3]])


@pytest.mark.parametrize("level, tol", [("object", (0.03, 0.1)), ("detection", (0.6, 0.6))])
def test_the_levels_report_a_lead_on_the_bend_at_its_true_relative_velocity(level, tol):
    # R 150 m at 20 m/s: relative velocity (−0.56, +4.22) m/s; the detection level's tracker reported (−0.10, +1.27)
    # (its model kept the lead's course over ground fixed while the ego turned) and the object level's smoothing
    # lagged by 0.09 m/s along (the −0.06 m/s across that is left at the object level with this seed is its noise:
    # the same on a straight road, +0.004 … +0.066 with other seeds; an independent tester's finding)
    sc = _bend(20.0, 1, 20.0, 150.0)
    cfg = radar_config(sc)
    model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(1), cfg.signal)
    err = []
    for k in range(200):
        frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=250.0))
        o = frame.objects
        mine = np.flatnonzero(o.actor_index == 0)
        if k >= 60 and mine.size:
            j = mine[0]
            err.append((o.vrel_long_mps[j] - view.vx_mps[0], o.vrel_lat_mps[j] - view.vy_mps[0]))
    err = np.array(err)
    assert len(err) > 100
    assert np.all(np.abs(err.mean(axis=0)) < tol), err.mean(axis=0)


@pytest.mark.parametrize("level", ["object", "detection"])
def test_acc_keeps_its_time_gap_behind_a_lead_on_a_bend(level):
    # R 100 m at 20 m/s (4 m/s² across): the ECU took the lead's relative velocity, which points across the bend,
    # for 0.6 m/s of closing and 1.2 m/s² of braking, and let the gap grow to 2.69 s (set 1.5 s)
    sc = _bend(24.0, 1, 20.0, 100.0)
    res = simulate(sc, fidelity=level)
    assert res.passed, res.reasons
    assert abs(res.final_time_gap_s - 1.5) < 0.15, res.final_time_gap_s
    # the truth's gap along the lane over the last 8 s: it settled
    gap = np.asarray(res.trace["time_gap"])[np.asarray(res.trace["t"]) > 16.0]
    assert np.ptp(gap) < 0.15


def _turned(speed, kappa, dt=0.072):
    """A vehicle 20 m ahead on the ego's circle at the ego's speed and a standing post, one step of road_turn."""
    w = kappa * speed
    p = np.array([20.0, 0.5 * kappa * 400.0])
    x = np.array([[*p, w * -p[1], w * p[0]], [15.0, -2.0, -speed, 0.0]])
    f, _ = transition("cv", dt, 4.0)
    return x, road_turn(x, x @ f.T, w * dt, dt, (speed, 0.0))[0], w * dt


def _world_fixed(x, yaw, speed):
    c, s = math.cos(-yaw), math.sin(-yaw)
    g = x[:, 2:4] + (speed, 0.0)
    return np.stack([c * g[:, 0] - s * g[:, 1], s * g[:, 0] + c * g[:, 1]], axis=1) - (speed, 0.0)


@pytest.mark.parametrize("speed, kappa", [(0.99, 0.01), (1.0, 0.01), (1.01, 0.01), (2.0, 0.01), (2.99, 0.01),
                                          (3.0, 0.01), (3.01, 0.01), (6.0, 0.01),
                                          (10.0, 0.0199), (10.0, 0.02), (10.0, 0.0201), (10.0, 0.03),
                                          (10.0, 0.0399), (10.0, 0.04), (10.0, 0.0401), (10.0, 0.08)])
def test_the_road_model_fades_out_at_walking_pace_and_on_junction_turns_without_a_jump(speed, kappa):
    """Below 1 m/s, or on a path tighter than R 25 m (a junction, a car park), the objects keep their course over
    ground; from 3 m/s and up to R 50 m they follow the ego's road; linear between: no jump at any edge."""
    from radarnode.perception.motion import ROAD_CURVATURE_1PM, ROAD_SPEED_MPS, road_share

    share = road_share(speed, kappa)
    x, moved, yaw = _turned(speed, kappa)
    fixed = _world_fixed(x, yaw, speed)
    assert np.allclose(moved[1, 2:], [-speed, 0.0], atol=1e-12)          # the post stands still either way
    if speed <= ROAD_SPEED_MPS[1] or kappa >= ROAD_CURVATURE_1PM[1]:
        assert share == 0.0 and np.allclose(moved[:, 2:], fixed, atol=1e-12)
    if speed >= ROAD_SPEED_MPS[0] and kappa <= ROAD_CURVATURE_1PM[0]:
        assert share == 1.0 and np.allclose(moved[0, 2:], x[0, 2:], atol=0.02 * speed * kappa * 20)
    # continuity: a step of 0.01 m/s or 1e-4 1/m across an edge changes the predicted change of velocity by little
    # (at R 25 m and 10 m/s the world-fixed model turns this vehicle's by 0.3 m/s a cycle, the road model not at all)
    step = moved[0, 2:] - x[0, 2:]
    for ds, dk in ((0.01, 0.0), (-0.01, 0.0), (0.0, 1e-4), (0.0, -1e-4)):
        x2, near, _ = _turned(speed + ds, kappa + dk)
        assert np.all(np.abs((near[0, 2:] - x2[0, 2:]) - step) < 0.003)


JUNCTION = """
name: junction_turn
duration_s: 10.0
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: 6.0}}
road: {{lanes: 2, lane_width_m: 3.5, ego_lane: 0, segments: [{{type: straight, length_m: 5.0}},
        {{type: arc, length_m: {arc}, curvature_1pm: {curv}}}, {{type: straight, length_m: 300.0}}]}}
ecu: {{acc_enabled: true, set_speed_mps: 6.0, time_gap_s: 1.5, closed_loop: false,
      expect: {{no_fcw: true}}}}
actors:
  - {{id: cross, class: car, x_m: {x}, y_m: 40.0, speed_mps: 8.0, heading_deg: -90.0}}
"""


@pytest.mark.parametrize("level, radius", [("object", 20.0), ("object", 25.0), ("object", 30.0), ("object", 40.0),
                                           ("detection", 25.0), ("detection", 30.0), ("detection", 40.0)])
def test_crossing_traffic_while_the_ego_turns_at_a_junction_draws_no_warning(level, radius):
    # a quarter turn of R 20–40 m at 6 m/s, a car crossing 10 m beyond it, long before the ego gets there: its speed
    # projected on the yaw-rate circle's tangent 50° off made it traffic coming towards the ego, and FCW warned in
    # 5–13 cycles (an independent tester's scene); where the others do not drive the ego's circle, along the axis.
    # Left as they were before the road model: at R 20 m the detection level warns (5 cycles), and ACC takes the
    # crossing car for its target for 5–7 cycles at R 30–40 m
    arc = round(math.pi / 2 * radius, 2)
    res = simulate(parse_scenario(JUNCTION.format(seed=1, arc=arc, curv=1.0 / radius, x=round(5.0 + arc + 10.0, 2))),
                   fidelity=level)
    assert res.passed, res.reasons
