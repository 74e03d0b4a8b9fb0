"""A point-sized actor (a pedestrian) crossing the sensor's axis: where the radar sees it moves on.

Its reported point was its box's nearest point to the sensor, which stays on the axis for as long as the body takes
to cross it (0.6 m at 1.5 m/s: 0.4 s); the detection level's tracker then saw the pedestrian stop and reported it
"stopped" for about half a second, right in front of the car. The point is now where the line of sight through the
body's centre meets its outline (:data:`radarnode.scene.world.POINT_SIZE_M`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.perception.types import DYN_CROSSING_MOVING
from radarnode.radar.models import make_model
from radarnode.radar.object_model import RuntimeConfig
from radarnode.radar.setup import parse_scenario, radar_config
from radarnode.scene.world import Scene

CROSSING = """
name: t
duration_s: 8.0
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: 0.0}}
road: {{lanes: 2, lane_width_m: 3.25, ego_lane: 0}}
actors:
  - id: pedestrian
    class: pedestrian
    waypoints:
      - {{t_s: 0.0, x_m: 24.0, y_m: -6.0}}
      - {{t_s: 8.0, x_m: 24.0, y_m: 6.0}}
"""


def test_the_reported_point_of_a_crossing_pedestrian_moves_on_across_the_axis():
    sc = parse_scenario(CROSSING.format(seed=1))
    times = np.arange(3.0, 5.0, 0.01)
    view = Scene(sc).views(times)
    y, x = view.y_m[:, 0], view.x_m[:, 0]
    step = np.diff(y)
    assert np.all(step > 0.5 * 1.5 * 0.01)                       # never stalls (it did for 0.4 s at y = 0)
    # on the outline, on the line of sight through the centre, in front of the centre by the half depth (0.25 m)
    centre_r = np.hypot(view.centre_x_m[:, 0], view.centre_y_m[:, 0])
    assert np.allclose(np.arctan2(y, x), np.arctan2(view.centre_y_m[:, 0], view.centre_x_m[:, 0]), atol=1e-12)
    assert np.all((centre_r - np.hypot(x, y) > 0.24) & (centre_r - np.hypot(x, y) < 0.4))


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_detection_level_keeps_a_crossing_pedestrian_crossing_while_it_passes_in_front(seed):
    sc = parse_scenario(CROSSING.format(seed=seed))
    cfg = radar_config(sc)
    model = make_model("detection", Scene(sc), cfg.preset, np.random.default_rng(seed), cfg.signal)
    codes = []
    for k in range(111):
        t = k * sc.period_s
        frame, view = model.step(t, RuntimeConfig(max_distance_m=250.0))
        if 3.0 <= t <= 5.0:                                       # y from −1.5 to +1.5 m: in front of the car
            mine = frame.objects.actor_index == 0
            codes.append(int(frame.objects.dyn_prop[mine][0]) if mine.any() else -1)
    assert codes.count(DYN_CROSSING_MOVING) == len(codes), codes


SIZED = """
name: t
duration_s: 1.0
seed: 1
radar: {{preset: ars408_like}}
ego: {{speed_mps: 0.0}}
road: {{lanes: 2, lane_width_m: 3.25, ego_lane: 0}}
actors:
  - {{id: box, class: {cls}, length_m: {length}, width_m: {width}, rcs_dbsm: 7.0, x_m: 20.0, y_m: 4.0,
     heading_deg: 30.0, speed_mps: 0.0}}
"""


@pytest.mark.parametrize("length, width, point", [
    (0.99, 0.99, True), (1.0, 1.0, True), (1.01, 1.01, False), (2.0, 2.0, False),     # below, at, above, twice
    (1.0, 1.01, False), (1.01, 1.0, False), (0.5, 2.0, False)])                     # one side over is a body
def test_the_point_size_switch_at_1_m_just_below_at_above_and_twice(length, width, point):
    """At and below POINT_SIZE_M in both directions an actor is one point on the line of sight through its centre;
    above it in either direction, its outline's nearest point and scatterers along its facing edges. Either way
    its RCS is all there (its scatterers' powers add up to it)."""
    from radarnode.radar.scatterers import actor_scatterers
    from radarnode.scene.world import POINT_SIZE_M

    assert POINT_SIZE_M == 1.0
    cls = "pedestrian" if point else "car"
    scene = Scene(parse_scenario(SIZED.format(cls=cls, length=length, width=width)))
    view = scene.view(0.0)
    x, y = float(view.x_m[0]), float(view.y_m[0])
    cx, cy = float(view.centre_x_m[0]), float(view.centre_y_m[0])
    on_sight = abs(math.atan2(y, x) - math.atan2(cy, cx)) < 1e-12
    assert on_sight == point
    # on the outline either way: in the box's frame, one coordinate at its half size, the other within it
    h = float(view.orientation_rad[0])
    lx = math.cos(h) * (x - cx) + math.sin(h) * (y - cy)
    ly = -math.sin(h) * (x - cx) + math.cos(h) * (y - cy)
    inside = abs(lx) <= length / 2 + 1e-9 and abs(ly) <= width / 2 + 1e-9
    edge = min(abs(abs(lx) - length / 2), abs(abs(ly) - width / 2)) < 1e-9
    assert inside and edge, (lx, ly)
    if not point:                       # the nearest point of the outline is nearer than the one on the line of sight
        assert math.hypot(x, y) <= math.hypot(cx, cy) - min(length, width) / 2 + 1e-9
    sc = actor_scatterers(scene, view, spacing_m=0.5)
    assert (sc.x_m.size == 1) == point
    assert 10.0 * math.log10(np.sum(10.0 ** (sc.rcs_dbsm / 10.0))) == pytest.approx(7.0, abs=1e-9)
