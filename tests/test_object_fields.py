"""Objects built from their detections (issue 15): RCS, class and size at every level."""

from __future__ import annotations

import numpy as np
import pytest

from helpers import scenario
from radarnode.radar.models import make_model
from radarnode.radar.object_model import RuntimeConfig
from radarnode.radar.setup import radar_config
from radarnode.scene.world import Scene

CAR = "  - {id: a, class: car, x_m: 36.0, lane: 1, speed_mps: 20.0}"
POINT = "  - {id: a, class: point, x_m: 34.0, lane: 1, speed_mps: 20.0, rcs_dbsm: 10.0}"


def _fields(actor: str, level: str, duration: float = 3.0, seed: int = 1, ego: str = "{speed_mps: 20.0}"):
    sc = scenario(actor, duration=duration, seed=seed, ego=ego)
    rc = radar_config(sc)
    model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
    rows = []
    for k in range(sc.num_cycles):
        frame, _ = model.step(k * sc.period_s, cfg)
        ol = frame.objects
        for j in np.flatnonzero(ol.actor_index == 0)[:1]:
            rows.append((int(ol.obj_class[j]), ol.rcs_dbsm[j], ol.length_m[j], ol.width_m[j]))
    assert len(rows) >= 0.6 * sc.num_cycles, f"{level}: the actor was an object in {len(rows)} cycles"
    a = np.array(rows)
    return a[:, 0].astype(int), a[:, 1], a[:, 2], a[:, 3]


@pytest.mark.parametrize("level", ["object", "detection", "signal"])
def test_a_point_target_of_known_rcs_is_reported_within_1_db(level):
    _, rcs, _, _ = _fields(POINT, level, duration=2.0 if level == "signal" else 3.0)
    assert abs(np.median(rcs) - 10.0) <= 1.0, np.median(rcs)


@pytest.mark.parametrize("level", ["detection", "signal"])
@pytest.mark.parametrize("rcs_b", [10.0, 4.0])
def test_two_reflectors_one_range_doppler_cell_apart_in_angle_each_have_their_own_rcs(level, rcs_b):
    """Two steady point reflectors at the same range and speed, 30° apart (two of ars408_like's beams): one range–
    Doppler cell, two angle peaks. Each cluster's RCS is its reflector's, within 0.5 dB: the peaks share the cell's
    energy in proportion to their powers. (The strongest took all of it before and the other its share on top: two
    equal reflectors came out 3 dB above their RCS, 10 and 4 dBsm as 11 and 5.)"""
    actors = ("  - {id: a, class: point, x_m: 40.0, y_m: 10.7, speed_mps: 0.0, rcs_dbsm: 10.0, swerling: 0}\n"
              f"  - {{id: b, class: point, x_m: 40.0, y_m: -10.7, speed_mps: 0.0, rcs_dbsm: {rcs_b}, swerling: 0}}")
    sc = scenario(actors, duration=1.5, ego="{speed_mps: 0.0}")
    rc = radar_config(sc)
    model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(2), rc.signal)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m)
    left, right = [], []
    for k in range(sc.num_cycles):
        cl = model.step(k * sc.period_s, cfg)[0].clusters
        near = np.abs(np.hypot(cl.dist_long_m, cl.dist_lat_m) - 38.0) < 4.0     # the sensor sits 3.6 m ahead
        for side, out in ((cl.dist_lat_m > 5.0, left), (cl.dist_lat_m < -5.0, right)):
            if np.count_nonzero(near & side) == 1:
                out.append(float(cl.rcs_dbsm[near & side][0]))
    assert len(left) >= 0.9 * sc.num_cycles and len(right) >= 0.9 * sc.num_cycles, (len(left), len(right))
    assert abs(np.median(left) - 10.0) <= 0.5 and abs(np.median(right) - rcs_b) <= 0.5, (np.median(left),
                                                                                          np.median(right))


@pytest.mark.parametrize("level", ["object", "detection", "signal"])
def test_a_car_at_30_m_is_a_car_of_a_car_s_rcs_and_width(level):
    cls, rcs, length, width = _fields(CAR, level, duration=2.0 if level == "signal" else 3.0)
    assert np.mean((cls == 1) | (cls == 2)) >= 0.9, np.bincount(cls, minlength=7)
    assert abs(np.median(rcs) - 10.0) <= 2.0, np.median(rcs)
    assert abs(np.median(width) - 1.8) <= 0.5 and np.median(length) >= 3.0, (np.median(length), np.median(width))


PEDESTRIAN = "  - {id: a, class: pedestrian, x_m: 30.0, lane: 1, speed_mps: 1.4}"


@pytest.mark.parametrize("level", ["object", "detection", "signal"])
def test_a_pedestrian_walking_at_30_m_is_a_pedestrian_of_a_pedestrian_s_size(level):
    # walking away along the lane ahead of a slow ego (30 → 34 m); its speed over ground tells it from a post
    cls, rcs, length, width = _fields(PEDESTRIAN, level, duration=2.0 if level == "signal" else 3.0,
                                      ego="{speed_mps: 0.1}")
    assert np.mean(cls == 3) >= 0.8, np.bincount(cls, minlength=7)
    assert np.median(length) <= 1.0 and np.median(width) <= 1.0, (np.median(length), np.median(width))
    assert abs(np.median(rcs) + 5.0) <= 3.0, np.median(rcs)       # the scene's pedestrian: −5 dBsm
