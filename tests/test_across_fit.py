"""A detection group narrower than RIGID_MIN_SPAN_RAD measures its speed across the line of sight by the rigid fit of
its radial speeds, where that fit's σ across is at most ACROSS_FIT_MAX_SIGMA_MPS (radarnode/perception/tracker.py,
``_across_fits``): a car crossing 25 m ahead shows its side over 7–9° of azimuth, and where it crosses the sensor's
axis its radial speed is the standing world's."""
import math

import numpy as np
import pytest

from helpers import scenario
from radarnode.perception.tracker import (ACROSS_FIT_MAX_SIGMA_MPS, ACROSS_FIT_MIN_DETECTIONS, RIGID_MIN_SPAN_RAD,
                                          RIGID_RESIDUAL_MPS, RIGID_SPEED_FLOOR_MPS, ObjectTracker,
                                          group_detections)
from radarnode.perception.types import (AMBIG_AMBIGUOUS, AMBIG_STAGGERED, AMBIG_STATIONARY, AMBIG_UNAMBIGUOUS,
                                        Detections)


def _body(v, az_deg, r_m=27.0, offsets=None):
    """Detections of one rigid body at relative velocity ``v`` (sensor axes) at azimuths ``az_deg``, range ``r_m``:
    radial speeds exact, plus ``offsets`` (m/s) where given."""
    az = np.radians(np.asarray(az_deg, dtype=float))
    rate = v[0] * np.cos(az) + v[1] * np.sin(az)
    if offsets is not None:
        rate = rate + np.asarray(offsets, dtype=float)
    n = az.size
    return Detections(np.full(n, r_m), rate, az, np.full(n, 10.0), np.full(n, 30.0), np.zeros(n, dtype=np.int64))


def _sigma_across(az_deg, r_m=27.0):
    """The fit's σ across the line of sight to the group's point (nearest x, mean y) for detections at ``az_deg``
    whose residuals are below the floor: RIGID_SPEED_FLOOR_MPS · √(tᵀ(AᵀA)⁻¹t), computed here on its own."""
    az = np.radians(np.asarray(az_deg, dtype=float))
    a = np.stack([np.cos(az), np.sin(az)], axis=1)
    cov = RIGID_SPEED_FLOOR_MPS ** 2 * np.linalg.inv(a.T @ a)
    x, y = r_m * np.cos(az), r_m * np.sin(az)
    gx, gy = x.min(), y.mean()
    t = np.array([-gy, gx]) / math.hypot(gx, gy)
    return float(np.sqrt(t @ cov @ t))


CROSSING = np.array([-15.0, -20.0])          # ego 15 m/s, a car crossing to the right at 20 m/s


def test_a_crossing_cars_side_measures_its_velocity_across():
    """Five detections over 7.5° of azimuth (under the 10° of a wide group): the fit is the car's velocity, and the
    group's range rate the fit's radial part at the group's point."""
    az = np.linspace(3.3, 10.8, 5)
    g = group_detections(_body(CROSSING, az))
    assert len(g) == 1
    assert np.degrees(RIGID_MIN_SPAN_RAD) > 7.5
    assert not np.isfinite(g.velocity[0, 0])                    # not a wide group's full velocity
    assert g.across[0] == pytest.approx(CROSSING, abs=1e-9)
    r = math.hypot(g.x_m[0], g.y_m[0])
    assert g.range_rate_mps[0] == pytest.approx((CROSSING[0] * g.x_m[0] + CROSSING[1] * g.y_m[0]) / r, abs=1e-9)
    t = np.array([-g.y_m[0], g.x_m[0]]) / r
    assert math.sqrt(t @ g.across_cov[0] @ t) == pytest.approx(_sigma_across(az), rel=1e-9)


@pytest.mark.parametrize("count, fitted", [(ACROSS_FIT_MIN_DETECTIONS - 1, False), (ACROSS_FIT_MIN_DETECTIONS, True),
                                           (2 * ACROSS_FIT_MIN_DETECTIONS, True)])
def test_a_group_needs_enough_detections(count, fitted):
    """Two detections fit any velocity exactly (no residual to judge it by): three or more."""
    g = group_detections(_body(CROSSING, np.linspace(4.0, 11.0, count)))
    assert np.isfinite(g.across[0, 0]) == fitted


def _span_for_sigma(sigma, count=5):
    """The span (degrees, centred on 7°) at which the fit's σ across is ``sigma``: bisection on _sigma_across."""
    lo, hi = 0.05, 9.9
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        if _sigma_across(np.linspace(7.0 - mid / 2, 7.0 + mid / 2, count)) > sigma:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


@pytest.mark.parametrize("factor, fitted", [(0.5, False), (0.99, False), (1.01, True), (2.0, True)])
def test_the_fit_is_taken_where_its_sigma_across_is_within_the_limit(factor, fitted):
    """σ across at ACROSS_FIT_MAX_SIGMA_MPS: just narrower (σ 1 % above), not taken; just wider, taken; half and
    twice the span at the limit too."""
    span = _span_for_sigma(ACROSS_FIT_MAX_SIGMA_MPS) * factor
    az = np.linspace(7.0 - span / 2, 7.0 + span / 2, 5)
    expected_sigma = _sigma_across(az)
    assert (expected_sigma <= ACROSS_FIT_MAX_SIGMA_MPS) == fitted
    g = group_detections(_body(CROSSING, az))
    assert len(g) == 1
    assert np.isfinite(g.across[0, 0]) == fitted


@pytest.mark.parametrize("span_deg, narrow", [(9.9, True), (10.1, False), (20.0, False)])
def test_a_group_of_ten_degrees_or_more_keeps_the_wide_rule(span_deg, narrow):
    """At RIGID_MIN_SPAN_RAD and beyond the group's full fitted velocity is the wide rule's (``velocity``), and it is
    not fitted twice; just below it, the narrow rule's."""
    az = np.linspace(2.0, 2.0 + span_deg, 6)
    g = group_detections(_body(CROSSING, az, r_m=15.0))
    assert len(g) == 1
    assert np.isfinite(g.across[0, 0]) == narrow
    assert np.isfinite(g.velocity[0, 0]) == (not narrow)


@pytest.mark.parametrize("off_mps, fitted", [(0.0, True), (0.5 * RIGID_RESIDUAL_MPS, True),
                                             (4.0 * RIGID_RESIDUAL_MPS, False)])
def test_radial_speeds_one_motion_does_not_explain_are_not_fitted(off_mps, fitted):
    """One detection off the rigid motion (a reflector of something else within the group's 1.5 m/s): no fit where
    the fit cannot explain every detection within RIGID_RESIDUAL_MPS."""
    off = np.zeros(6)
    off[2] = off_mps
    g = group_detections(_body(CROSSING, np.linspace(3.0, 10.0, 6), offsets=off))
    assert len(g) == 1
    assert np.isfinite(g.across[0, 0]) == fitted


def test_a_new_track_of_a_crossing_cars_side_starts_near_its_velocity():
    """The prior across (the road's direction, σ 2 m/s) updated with the fit (σ ≈ 1.2 m/s here): the new track's speed
    across is at least two thirds of the car's, where the prior alone started it at none."""
    sv = (15.0, 0.0)
    tracker = ObjectTracker()
    tracker.step(0.0, _body(CROSSING, np.linspace(3.3, 10.8, 5)), sv)
    assert len(tracker.x) == 1
    assert tracker.x[0, 3] <= 2.0 / 3.0 * CROSSING[1]
    assert tracker.x[0, 2] == pytest.approx(CROSSING[0], abs=1.5)


def _crossing(ego_mps, car_mps, seed, x_m, duration):
    return scenario(f"  - {{id: x, class: car, x_m: {x_m:.1f}, y_m: 12.0, speed_mps: {car_mps}, heading_deg: -90}}",
                    ego=f"{{speed_mps: {ego_mps}}}", road="{lanes: 2, lane_width_m: 3.6, ego_lane: 0}",
                    duration=round(duration, 2), seed=seed, extra="ecu: {acc_enabled: false}")


@pytest.mark.parametrize("ego_mps, car_mps", [(15.0, 20.0), (10.0, 20.0), (15.0, 15.0), (10.0, 10.0)])
def test_a_car_crossing_close_to_the_egos_road_draws_no_false_warning(ego_mps, car_mps):
    """A car crosses from 12 m to the left (first tracked within 20° of the ego's road, where the prior takes it to
    move along the road) and clears the ego's lane 1.5 s before the ego gets there: no warning is due. Its tracks
    started with no speed across, lost it and coasted into the lane, and the detection level warned (FCW) in 10, 10,
    3 and 10 of 10 seeds (``benchmarks/crossing.py --only fcw``); the object level warned in 10 of 10 at 15 and 10 m/s
    (FCW took a car in the lane for a threat whatever its speed across). Now 0 of 10 at both levels. Seeds 1–3 here.
    (With the ego at 20 m/s the detection level still warns in 3–10 of 10: there the car's side, 45 m out, splits
    into groups of one or two detections, too few to fit, whose tracks start standing and coast into the lane — a
    known limit.)"""
    from radarnode.consumer.evaluate import simulate
    t_arrive = (12.0 + 4.0) / car_mps + 1.5
    for seed in (1, 2, 3):
        sc = _crossing(ego_mps, car_mps, seed, 3.7 + ego_mps * t_arrive, t_arrive + 0.5)
        warned = {level: simulate(sc, fidelity=level).warning_time_s for level in ("object", "detection")}
        assert warned == {"object": None, "detection": None}, (seed, warned)


@pytest.mark.parametrize("ego_mps, car_mps", [(10.0, 5.0), (15.0, 10.0)])
def test_a_car_crossing_into_the_egos_way_still_draws_the_warning(ego_mps, car_mps):
    """The same crossing timed so that the car is in the ego's lane when the ego gets there (a collision course): the
    rule that leaves out a target clearing the path must not leave it out. Both levels warn, at the same times as
    before the rule (seeds 1–3; late — 2.18–2.32 s for a car on the ego's line at 2.4 s, 1.17–1.24 s for one there at
    1.2 s — as FCW takes a target only once it is in the path three cycles: the consumer's rule, unchanged)."""
    from radarnode.consumer.evaluate import simulate
    t_hit = 12.0 / car_mps
    sc = _crossing(ego_mps, car_mps, 1, 3.7 + ego_mps * t_hit, t_hit + 0.3)
    for level in ("object", "detection"):
        t = simulate(sc, fidelity=level).warning_time_s
        assert t is not None and t < t_hit + 0.1, (level, t)


@pytest.mark.parametrize("state, fitted", [(AMBIG_UNAMBIGUOUS, True), (AMBIG_STAGGERED, True),
                                           (AMBIG_AMBIGUOUS, False), (AMBIG_STATIONARY, False)])
def test_only_range_rates_as_measured_are_fitted(state, fitted):
    """A single ramp's moving detections (ambiguous: known modulo 2·v_max) and stationary candidates (taken for the
    standing world's rate) are no radial speeds to fit: a wrap leaks into the fit across as the wrap times the span
    (guardrail posts on fast_chirp were listed crossing the ego's lane at 3–4 m/s)."""
    det = _body(CROSSING, np.linspace(3.3, 10.8, 5))
    det.ambig_state = np.full(len(det), state, dtype=np.int64)
    g = group_detections(det)
    assert np.isfinite(g.across[0, 0]) == fitted


HALF, EXTENT = 1.8, 4.5


@pytest.mark.parametrize("later, clears", [(HALF + EXTENT - 0.01, False), (HALF + EXTENT + 0.01, True),
                                           (2.0 * (HALF + EXTENT), True), (0.0, False)])
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_fcw_leaves_out_a_target_only_once_it_will_have_cleared_the_path(later, clears, side):
    """The reported point, where its speed across puts it when the ego gets there, beyond the path's half-width plus
    the body's extent on the side it moves to: just short of that, not cleared; just beyond and twice, cleared; on
    either side."""
    from radarnode.consumer.ecu import clears_path
    reach, w = 2.0, 10.0 * side
    offset = side * later - w * reach
    assert bool(clears_path(np.array([offset]), np.array([w]), np.zeros(1), np.array([reach]), HALF,
                            np.array([EXTENT]))[0]) == clears


@pytest.mark.parametrize("sigmas, clears", [(0.0, True), (0.99, True), (1.01, False), (2.0, False)])
def test_fcw_clears_a_target_on_the_least_speed_across_its_sigma_allows(sigmas, clears):
    """A car at the path's centre line, 10 m/s across, 2 s away: it clears by 20 m with an exact speed. Its σ in
    units of what would leave it just short (speed less CLEAR_SIGMAS σ bringing it to the edge): below 1, cleared;
    above, not; twice, not."""
    from radarnode.consumer.ecu import CLEAR_SIGMAS, clears_path
    reach, w = 2.0, 10.0
    edge_sigma = (w - (HALF + EXTENT) / reach) / CLEAR_SIGMAS       # the σ that leaves it exactly at the edge
    assert bool(clears_path(np.zeros(1), np.array([w]), np.array([sigmas * edge_sigma]), np.array([reach]), HALF,
                            np.array([EXTENT]))[0]) == clears


def test_a_target_not_moving_across_or_not_reached_never_clears():
    """A stopped car in the lane (no speed across) and one the ego does not close on (reach 0) stay candidates."""
    from radarnode.consumer.ecu import clears_path
    out = clears_path(np.array([0.5, 0.5]), np.array([0.0, 10.0]), np.zeros(2), np.array([3.0, 0.0]), HALF,
                      np.full(2, EXTENT))
    assert not out.any()


@pytest.mark.parametrize("angle_deg, clears", [(15.0, False), (29.0, False), (31.0, True), (60.0, True), (90.0, True)])
def test_fcw_clears_only_a_target_moving_across_the_path(angle_deg, clears):
    """A target 10 m/s over ground, its motion ``angle_deg`` off the path's direction, far enough across to clear in
    2 s (offset beyond the half-width plus extent by then at any of these angles): left out only beyond
    CLEAR_MIN_ANGLE_DEG (30°), not a lead on a curve entry whose road the yaw-rate circle does not follow yet."""
    from radarnode.consumer.ecu import CLEAR_MIN_ANGLE_DEG, clears_path
    assert CLEAR_MIN_ANGLE_DEG == 30.0
    a = math.radians(angle_deg)
    w, along, reach = 10.0 * math.sin(a), 10.0 * math.cos(a), 4.0
    offset = (HALF + EXTENT + 1.0) - w * reach          # 1 m beyond the limit when the ego gets there
    assert bool(clears_path(np.array([offset]), np.array([w]), np.zeros(1), np.array([reach]), HALF,
                            np.array([EXTENT]), np.array([along]))[0]) == clears
