"""A point-sized actor (a pedestrian) crossing the sensor's axis: where the radar sees it moves on.

Its reported point was its box's nearest point to the sensor, which stays on the axis for as long as the body takes
to cross it (0.6 m at 1.5 m/s: 0.4 s); the detection level's tracker then saw the pedestrian stop and reported it
"stopped" for about half a second, right in front of the car. The point is now where the line of sight through the
body's centre meets its outline (:data:`radarnode.scene.world.POINT_SIZE_M`)."""

from __future__ import annotations

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
