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


@pytest.mark.parametrize("mount_y", [-1.0, 0.5, 1.0])
def test_the_far_path_follows_the_car_s_centre_line_whatever_the_sensor_s_lateral_place(mount_y):
    """The boundaries' course blended in beyond BLEND_START_M was applied to the sensor-frame lateral: with the sensor
    1 m left of centre, a point 2 m left of the car's centre line (beyond the 1.6 m half-width) was in the path at
    40 and 80 m and one 1.2 m right of it was not (an independent tester's finding). Straight road, edges 5.25 m
    either side of the car's centre line, reported in the sensor frame."""
    m = SensorMount(3.7, mount_y, 0.0)
    b = {"left": Boundary(True, 5.25 - mount_y, 0.0, 0.0, 0.0, 150.0, 1.0),
         "right": Boundary(True, -5.25 - mount_y, 0.0, 0.0, 0.0, 150.0, 1.0)}
    for x in (10.0, 40.0, 80.0, 120.0):
        for y_vehicle, inside in ((-2.0, False), (-1.5, True), (-1.2, True), (0.0, True), (1.2, True), (1.5, True),
                                  (2.0, False)):
            got = in_path(np.array([x]), np.array([y_vehicle - mount_y]), 20.0, 0.0, 1.6, b, m)[0]
            assert got == inside, (x, y_vehicle, mount_y)


@pytest.mark.parametrize("yaw_deg", [-8.0, -3.5, 2.0, 3.5, 8.0])
def test_a_yawed_sensor_s_boundaries_are_turned_to_the_car_s_axes(yaw_deg):
    """A sensor yawed by ψ sees a straight road's edge at heading −ψ: the ECU compared that with its 2.9° lane-change
    and 5.7° plausibility limits and dropped the boundaries from 3.5° on (warnings late on a curve entry; an
    independent tester's finding). In the car's axes the edge runs at 0° again, at its lateral distance."""
    m = SensorMount(3.7, 0.3, yaw_deg)
    psi = math.radians(yaw_deg)
    # the edge y_vehicle = −4.0 m (straight) in the sensor frame: points (xv, −4) moved by −mount and turned by −ψ
    xv = np.linspace(10.0, 120.0, 50)
    dx, dy = xv - m.x_m, -4.0 - m.y_m
    xs, ys = math.cos(psi) * dx + math.sin(psi) * dy, -math.sin(psi) * dx + math.cos(psi) * dy
    c = np.polyfit(xs, ys, 2)
    sensor = Boundary(True, float(c[2]), math.atan(c[1]), 2.0 * float(c[0]), 5.0, 100.0, 1.0)
    assert abs(sensor.heading_rad + psi) < 1e-9
    got = P.aligned_boundaries({"right": sensor}, m)["right"]
    assert abs(got.heading_rad) < 1e-9 and abs(got.curvature_1pm) < 1e-12
    assert got.offset_m == pytest.approx(-4.0 - m.y_m, abs=1e-9)      # the aligned frame's origin is the sensor
    assert plausible({"right": got}) and road_course(np.array([50.0]), {"right": got}) is not None
    # no yaw: the boundaries as reported, the same object
    flat = {"right": sensor}
    assert P.aligned_boundaries(flat, SensorMount(3.7, 0.3, 0.0)) is flat
