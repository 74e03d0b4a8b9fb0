"""The predicted path follows the road's course from the reported boundaries where the yaw rate cannot know the
curve ahead (issue 10 item 1: a curve entered through a clothoid)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.consumer import path as P
from radarnode.consumer.path import SensorMount, in_path, plausible, road_course
from radarnode.perception.boundaries import Boundary


def _road(curv=0.004, heading_deg=0.0, end=100.0):
    h = math.radians(heading_deg)
    return {"left": Boundary(True, 5.25, h, curv, 0.0, end, 1.0), "right": Boundary(True, -5.25, h, curv, 0.0, end, 1.0)}


def test_a_curve_ahead_is_in_the_path_before_the_yaw_rate_knows_it():
    b = _road()
    x = np.array([10.0, 50.0, 80.0])
    y = 0.5 * 0.004 * x ** 2                               # the lane's centre 0.2, 5.0 and 12.8 m to the left
    m = SensorMount()
    straight = in_path(x, y, 20.0, 0.0, 1.6, None, m)      # yaw rate 0: the ego still drives straight
    assert straight.tolist() == [True, False, False]
    with_road = in_path(x, y, 20.0, 0.0, 1.6, b, m)
    assert with_road.tolist() == [True, True, True]
    # the lane beside it (3.5 m to the right of the course) stays out of the path at any range
    assert not in_path(x[1:], y[1:] - 3.5, 20.0, 0.0, 1.6, b, m).any()
    # near the ego the yaw-rate circle rules: the course only starts to count at BLEND_START_M
    near = np.array([P.BLEND_START_M - 0.5, P.BLEND_END_M])
    # 1.5 m right of the straight path, 3.4 m (resp. 19.5 m) right of a course of κ = 0.01
    assert in_path(near, np.array([-1.5, -1.5]), 20.0, 0.0, 1.6, _road(curv=0.01), m).tolist() == [True, False]


@pytest.mark.parametrize("heading_deg, used", [(0.0, True), (math.degrees(P.LANE_KEEPING_HEADING_RAD) - 0.01, True),
                                               (math.degrees(P.LANE_KEEPING_HEADING_RAD) + 0.01, False),
                                               (2 * math.degrees(P.LANE_KEEPING_HEADING_RAD), False)])
def test_not_while_the_ego_crosses_the_road(heading_deg, used):
    assert (road_course(np.array([50.0]), _road(heading_deg=heading_deg)) is not None) == used


def test_the_course_reaches_its_extent_of_the_boundary_s_range():
    shift, covered = road_course(np.array([0.0, 149.0, 151.0]), _road(end=100.0))
    assert covered.tolist() == [1.0, 1.0, 0.0] and P.COURSE_EXTENT == 1.5
    assert shift[1] == pytest.approx(0.5 * 0.004 * 149.0 ** 2)


def test_implausible_boundaries_are_ignored():
    good = _road()
    wrong_side = {"left": Boundary(True, -21.9, math.radians(4.0), 0.0007, 0.0, 149.0, 1.0), "right": good["right"]}
    assert [s for s, _ in plausible(wrong_side)] == ["right"]
    lim = P.MAX_BOUNDARY_HEADING_RAD
    for heading, kept in ((lim - 1e-3, True), (lim, True), (lim + 1e-3, False), (2 * lim, False)):
        b = {"right": Boundary(True, -5.0, heading, 0.0, 0.0, 80.0, 1.0)}
        assert bool(plausible(b)) == kept, heading
    invalid = {"left": Boundary(False), "right": Boundary(False)}
    assert plausible(invalid) == [] and road_course(np.array([50.0]), invalid) is None


def test_the_measured_reach_is_the_farthest_boundary_range_used_and_nothing_without_a_course():
    """``measured_reach_m`` says how far the road's course is measured (the ECU lets a stationary object never seen
    moving become FCW's target only within it, or where the yaw-rate circle agrees): the farthest valid range of the
    boundaries the course uses; None without one, or when the course is not used (the ego crossing the road)."""
    mount = SensorMount()
    assert P.measured_reach_m(_road(end=77.0), None, mount) == 77.0
    one = {"left": Boundary(True, 5.25, 0.0, 0.004, 0.0, 60.0, 1.0), "right": Boundary(False)}
    assert P.measured_reach_m(one, None, mount) == 60.0
    assert P.measured_reach_m(None, None, mount) is None
    assert P.measured_reach_m({"left": Boundary(False), "right": Boundary(False)}, [], mount) is None
    assert P.measured_reach_m(_road(heading_deg=10.0), None, mount) is None        # crossing: no course


def test_a_stationary_object_is_on_a_known_course_just_below_and_at_the_reach_not_above_or_at_twice_it():
    """The ECU's rule (``course_known``): a stationary object never seen moving may become FCW's target within the
    measured course (x ≤ reach, inclusive), or beyond it where the yaw-rate circle alone also puts it in the path.
    Swept just below, at and just above the reach and at twice it, on a straight circle and on a left-hand one, in
    the own lane and in the lane beside it; the sensor ahead of the rear axle, 0.5 m left of the centre line."""
    m = SensorMount(3.7, 0.5, 0.0)
    reach = 60.0
    x = np.array([np.nextafter(reach, 0.0), reach, np.nextafter(reach, np.inf), 2.0 * reach])
    speed, half = 25.0, 1.6
    for yaw_rate in (0.0, 25.0 * 0.002):                  # a straight circle; a 500-m left bend
        kappa = yaw_rate / speed
        xv = x + m.x_m
        own = 0.5 * kappa * xv ** 2 - m.y_m                # the circle's centre line, in the sensor frame
        beside = own - 3.5                                 # the lane to the right of it
        assert P.course_known(x, own, reach, speed, yaw_rate, half, m).tolist() == [True] * 4
        assert P.course_known(x, beside, reach, speed, yaw_rate, half, m).tolist() == [True, True, False, False]
        # nothing measured: the circle is the only prediction, and nothing is held back
        assert P.course_known(x, beside, None, speed, yaw_rate, half, m).tolist() == [True] * 4
