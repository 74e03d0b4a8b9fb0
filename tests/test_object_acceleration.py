"""Obj_ArelLong / Obj_ArelLat at the detection and signal levels: the radar tracker's constant-velocity filter
reports the slope of its filtered relative velocity over the last cycles (radarnode.perception.tracker), as the
object level reports its truth with noise; before, these two levels put a constant 0 on the wire."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.perception.tracker import ACCEL_WINDOW, accel_sigma_mps2, velocity_slope
from radarnode.radar.models import make_model
from radarnode.radar.object_model import RuntimeConfig
from radarnode.radar.setup import load_scenario, radar_config
from radarnode.scene.world import Scene
from tests.conftest import SCENARIOS


def test_the_slope_of_a_ramp_is_its_acceleration_and_needs_three_velocities():
    t = 0.072
    ramp = np.zeros((4, ACCEL_WINDOW, 2))
    times = np.tile(t * np.arange(ACCEL_WINDOW), (4, 1))
    ramp[:, :, 0] = 20.0 - 2.94 * times                               # braking along x
    ramp[:, :, 1] = 0.5 * times                                        # drifting across
    count = np.array([ACCEL_WINDOW, 3, 2, 0])
    slope, per = velocity_slope(ramp, times, count)
    assert np.allclose(slope[:2], [[-2.94, 0.5], [-2.94, 0.5]], atol=1e-9)
    assert np.all(slope[2:] == 0.0) and np.all(np.isinf(per[2:]))    # fewer than three: not measured yet
    # the slope's σ per m/s of the velocities': the straight-line fit's, √(12 / (N (N² − 1))) / T
    assert np.allclose(per[:2], [math.sqrt(12 / 504) / t, math.sqrt(12 / 24) / t])
    assert np.allclose([accel_sigma_mps2(0.1, t, 8), accel_sigma_mps2(0.1, t, 3)], 0.1 * per[:2])
    # only the last ``count`` entries count: garbage before them changes nothing
    ramp[1, :ACCEL_WINDOW - 3] = 1e3
    assert np.allclose(velocity_slope(ramp, times, count)[0][1], [-2.94, 0.5], atol=1e-9)
    # a gap (a coast: the history waits for the next measurement) is taken at its real times
    gap = times.copy()
    gap[:, -2:] += 3 * t
    ramp2 = 20.0 - 2.94 * gap
    assert np.allclose(velocity_slope(np.stack([ramp2, 0 * ramp2], -1), gap, count)[0][0], [-2.94, 0.0])


@pytest.mark.parametrize("level", ["object", "detection", "signal"])
def test_a_braking_lead_is_reported_braking_at_every_level(level):
    """NHTSA test 2: the lead brakes at 2.94 m/s² from 2 s. Before that each level reports it near 0, from 3 s on
    near −2.94, within the σ it reports."""
    sc = load_scenario(SCENARIOS / "nhtsa_lead_decelerating.yaml")
    cfg = radar_config(sc)
    model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(1), cfg.signal)
    rows = []
    for k in range(int(4.5 / sc.period_s)):
        t = k * sc.period_s
        frame, _ = model.step(t, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
        lead = frame.objects.actor_index == 0
        if lead.any():
            i = int(np.flatnonzero(lead)[0])
            rows.append((t, frame.objects.arel_long_mps2[i], frame.objects.arel_long_sigma_mps2[i]))
    r = np.array(rows)
    steady, braking = r[(r[:, 0] > 0.7) & (r[:, 0] < 2.0)], r[r[:, 0] > 3.0]
    assert len(steady) > 10 and len(braking) > 10
    assert abs(np.median(steady[:, 1])) < 0.2
    assert abs(np.median(braking[:, 1]) + 2.94) < 0.2
    assert np.all(np.abs(braking[:, 1] + 2.94) < 3.0 * braking[:, 2] + 0.05)


# the signal level's case takes 13 s: -m slow (CI's 20 minutes)
@pytest.mark.parametrize("level", ["detection", pytest.param("signal", marks=pytest.mark.slow)])
def test_the_posts_behind_a_braking_ego_read_the_egos_deceleration(level):
    """A standing object's relative acceleration is the standing world's: the ego brakes at 4 m/s² from 1 s, every
    guardrail post reads +4 (its track, re-anchored at each hop, has no velocity history of its own; before, 55–64 %
    of the posts' rows read 0 and some ±26 m/s²)."""
    from radarnode.radar.setup import parse_scenario
    sc = parse_scenario("""
name: t
duration_s: 3.0
seed: 3
radar: {preset: ars408_like}
ego: {speed_mps: 25.0, accel: [{t_s: 1.0, accel_mps2: -4.0}]}
road: {lanes: 2, lane_width_m: 3.5, ego_lane: 0, guardrails: {left_offset_m: 1.0, right_offset_m: 1.0, post_spacing_m: 2.0}}
actors: []
""")
    cfg = radar_config(sc)
    model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(3), cfg.signal)
    got = []
    for k in range(sc.num_cycles):
        t = k * sc.period_s
        frame, _ = model.step(t, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
        o = frame.objects
        if t > 2.0:
            standing = (o.actor_index < 0) & (o.dyn_prop == 1) & np.isfinite(o.arel_long_sigma_mps2)
            got.append(o.arel_long_mps2[standing])
    a = np.concatenate(got)
    assert a.size > 50
    assert abs(np.median(a) - 4.0) < 0.1 and np.mean(np.abs(a - 4.0) < 0.3) > 0.9, np.percentile(a, [5, 50, 95])


def test_the_radar_trackers_prediction_keeps_a_standing_track_standing_while_the_ego_changes_speed():
    """radarnode.perception.tracker.predict: where the sensor's own velocity changed by Δu over the cycle, a track
    marked standing has its relative velocity changed by −Δu and its position by its old relative velocity × dt −
    Δu·dt/2, the exact kinematics of a post ahead of an ego braking uniformly at 6 m/s² (before, the relative velocity
    was kept, and a post gained 0.3 m/s a cycle of motion over ground: an independent tester's finding). A moving
    track keeps its relative velocity, as before: its own acceleration is not known to the prediction, and a lead
    braking along with the ego (ACC following) keeps a relative velocity of 0 (a constant velocity over ground for
    every track biased it by up to 3 m/s: a second tester's finding)."""
    from radarnode.perception.tracker import predict
    dt, a, u0 = 0.072, -6.0, 45.0
    u1 = u0 + a * dt
    x = np.array([[80.0, -6.0, -u0, 0.0], [50.0, 0.0, 0.0, 0.0]])
    p = np.repeat(np.eye(4)[None], 2, axis=0)
    standing = np.array([True, False])
    moved, cov = predict(x, p, dt, sensor_velocity=(u1, 0.0), previous_sensor_velocity=(u0, 0.0), standing=standing)
    ego_travel = u0 * dt + 0.5 * a * dt * dt
    assert moved[0] == pytest.approx([80.0 - ego_travel, -6.0, -u1, 0.0], abs=1e-12)
    assert np.array_equal(moved[1], predict(x, p, dt)[0][1])       # the moving one: as before, to the bit
    assert np.allclose(cov, predict(x, p, dt)[1])                  # a known change adds no uncertainty
    kept = predict(x, p, dt, sensor_velocity=(u0, 0.0), previous_sensor_velocity=(u0, 0.0), standing=standing)[0]
    assert np.array_equal(kept, predict(x, p, dt)[0])              # a constant ego speed: as before, to the bit
    # on a bend (the road-following branch) the same: a standing post stays standing over ground
    moved_bend, _ = predict(x[:1], p[:1], dt, yaw_rate_rps=u0 / 250.0, sensor_velocity=(u1, 0.0),
                            previous_sensor_velocity=(u0, 0.0), standing=standing[:1])
    assert np.hypot(moved_bend[0, 2] + u1, moved_bend[0, 3]) < 1e-9


@pytest.mark.parametrize("accel, curvature", [(-10.0, 0.0), (-6.0, 0.0), (-3.0, 0.0), (4.0, 0.0), (-6.0, 0.004)])
def test_a_lead_braking_along_with_the_ego_keeps_a_relative_speed_of_zero(accel, curvature):
    """helper-88's scene: the ego and its lead 60 m ahead, both at 30 m/s (5 m/s when accelerating), brake (or
    accelerate) together from 0.5 s, between guardrails. Their relative speed stays 0. With a constant velocity over
    ground for every track (7cf5dab) the detection level listed the lead moving away by up to 3.1 m/s and changed its
    ID every 0.36 s at −10 m/s²; now, as before 7cf5dab, within 0.3 m/s under one ID on the straight road, and no
    post listed moving (before 7cf5dab 3–15 post rows at −3 to −10 m/s²). On a 250-m bend the lead's speed is off by up
    to 0.87 m/s, under 2 IDs, at every acceleration and at a constant speed too, as before 7cf5dab (an older limit on
    bends; 2.28 m/s with 7cf5dab)."""
    from tests.helpers import scenario
    v0 = 5.0 if accel > 0 else 30.0
    rails = "guardrails: {left_offset_m: 1.0, right_offset_m: 1.0, post_spacing_m: 2.0}"
    sc = scenario(f"  - {{id: lead, class: car, x_m: 60.0, lane: 0, speed_mps: {v0}, "
                  f"accel: [{{t_s: 0.5, accel_mps2: {accel}}}]}}\n",
                  ego=f"{{speed_mps: {v0}, accel: [{{t_s: 0.5, accel_mps2: {accel}}}]}}",
                  radar="{preset: ars408_like, output: objects}", duration=3.0,
                  road=f"{{lanes: 2, lane_width_m: 3.5, ego_lane: 0, curvature_1pm: {curvature}, {rails}}}")
    cfg = radar_config(sc)
    model = make_model("detection", Scene(sc), cfg.preset, np.random.default_rng(1), cfg.signal)
    errors, ids, moving_posts = [], set(), 0
    for k in range(sc.num_cycles):
        frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
        o = frame.objects
        lead = o.actor_index == 0
        errors += list(np.abs(o.vrel_long_mps[lead] - view.vx_mps[0]))
        ids.update(o.id[lead].tolist())
        moving_posts += int(np.sum(~lead & np.isin(o.dyn_prop, (0, 2, 6))))
    limit, most_ids = (0.3, 1) if curvature == 0.0 else (1.0, 2)
    assert len(errors) >= sc.num_cycles - 3 and max(errors) < limit and len(ids) <= most_ids, (max(errors), ids)
    assert moving_posts == 0


@pytest.mark.parametrize("preset", ["ars408_like", "mimo12"])
@pytest.mark.parametrize("curvature", [0.0, 0.004])
@pytest.mark.parametrize("accel", [-6.0, -2.0, 0.0, 3.0])
def test_no_guardrail_post_is_listed_moving_while_the_ego_brakes_or_accelerates(preset, curvature, accel):
    """helper-86's scene: an ego at 45 m/s braking at 6 m/s² between guardrails (posts every 4 m), straight and on a
    250-m bend. At the detection level 63–144 rows of posts a run were listed moving, oncoming or crossing on
    ``ars408_like``, 105–133 on ``mimo12``, none at −2 m/s² or at a constant speed: a coasting or barely measured
    track kept its relative velocity while the ego's changed. Now none at −6, −2, 0 or +3 m/s², except on
    ``mimo12``'s bend, where 5–25 rows are listed moving at every one of them, at a constant speed too (an older
    limit on bends, not the ego's acceleration: 133 at −6 m/s² before)."""
    from tests.helpers import scenario
    rails = "guardrails: {left_offset_m: 1.0, right_offset_m: 1.0, post_spacing_m: 4.0, rcs_dbsm: 5.0}"
    sc = scenario(ego=f"{{speed_mps: 45.0, accel: [{{t_s: 0.0, accel_mps2: {accel}}}]}}",
                  radar=f"{{preset: {preset}, output: objects}}", duration=6.0,
                  road=f"{{lanes: 3, lane_width_m: 3.5, ego_lane: 1, curvature_1pm: {curvature}, {rails}}}")
    cfg = radar_config(sc)
    model = make_model("detection", Scene(sc), cfg.preset, np.random.default_rng(1), cfg.signal)
    rows = moving = 0
    for k in range(sc.num_cycles):
        o = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))[0].objects
        rows += len(o)
        moving += int(np.sum(np.isin(o.dyn_prop, (0, 2, 6))))
    assert rows > 500 and moving <= (30 if (preset, curvature) == ("mimo12", 0.004) else 0), (rows, moving)
