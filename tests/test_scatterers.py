"""Scatterers on the visible outline of actors, their RCS budget, and the field of view."""

from __future__ import annotations

import numpy as np
import pytest

from radarnode.radar.setup import radar_config
from radarnode.radar.scatterers import actor_scatterers, scene_scatterers
from radarnode.scene.world import Scene
from tests.helpers import scenario


def test_points_lie_on_the_edges_that_face_the_sensor():
    sc = scenario("  - {id: side, class: car, x_m: 14.0, y_m: 4.0, speed_mps: 20.0}")
    scene = Scene(sc)
    view = scene.view(0.0)
    sc_ = actor_scatterers(scene, view)
    cx, cy = view.centre_x_m[0], view.centre_y_m[0]
    hl, hw = 4.5 / 2, 1.8 / 2
    lx, ly = sc_.x_m - cx, sc_.y_m - cy
    on_rear = np.isclose(lx, -hl)
    on_right = np.isclose(ly, -hw)
    assert np.all(on_rear | on_right)              # only the rear and the right side face a sensor behind-right
    assert on_rear.any() and on_right.any()
    assert np.all(np.abs(lx) <= hl + 1e-9) and np.all(np.abs(ly) <= hw + 1e-9)
    # the actor's RCS is shared among its points
    assert 10 * np.log10(np.sum(10 ** (sc_.rcs_dbsm / 10))) == pytest.approx(10.0)


def test_small_actors_are_one_point_and_hidden_ones_are_dropped():
    sc = scenario("""
  - {id: ped, class: pedestrian, x_m: 30.0, y_m: -3.0, speed_mps: 0.0}
  - {id: front, class: truck, x_m: 30.0, lane: 1, speed_mps: 20.0}
  - {id: hidden, class: car, x_m: 60.0, lane: 1, speed_mps: 20.0}
""", radar="{preset: mimo12}")
    scene = Scene(sc)
    view = scene.view(0.0)
    scat = scene_scatterers(scene, 0.0, view, radar_config(sc).preset, 112.5)
    assert (scat.actor_index == 0).sum() == 1
    assert (scat.actor_index == 1).sum() >= 3
    assert (scat.actor_index == 2).sum() == 0        # behind the truck
