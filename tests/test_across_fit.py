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


@pytest.mark.parametrize("ego_mps, car_mps", [(15.0, 20.0), (10.0, 20.0), (15.0, 15.0)])
def test_a_car_crossing_close_to_the_egos_road_draws_no_false_warning(ego_mps, car_mps):
    """A car crosses from 12 m to the left (first tracked within 20° of the ego's road, where the prior takes it to
    move along the road) and clears the ego's lane 1.5 s before the ego gets there: no warning is due. Its tracks
    started with no speed across, lost it and coasted into the lane, and the detection level warned (FCW) in 10, 2
    and 3 of 10 seeds (``benchmarks/crossing.py --only fcw``); the object level warned in 10 of 10 at 15 m/s (FCW took
    a car in the lane for a threat whatever its speed across). Now 0 of 10 at both levels. Seeds 1–3 here. A car
    crossing at 10 m/s is still warned for: braking at 10 m/s² it could stop within 5 m, in the path
    (CLEAR_BRAKE_MPS2). (With the ego at 20 m/s the detection level still warns in 7–10 of 10 at 15–20 m/s from 12 m:
    there the car's side, 45 m out, splits into groups of one or two detections, too few to fit, whose tracks start
    standing and coast into the lane — a known limit.)"""
    from radarnode.consumer.evaluate import simulate
    t_arrive = (12.0 + 4.0) / car_mps + 1.5
    for seed in (1, 2, 3):
        sc = _crossing(ego_mps, car_mps, seed, 3.7 + ego_mps * t_arrive, t_arrive + 0.5)
        warned = {level: simulate(sc, fidelity=level).warning_time_s for level in ("object", "detection")}
        assert warned == {"object": None, "detection": None}, (seed, warned)


@pytest.mark.parametrize("actor, from_y, speed, brake, ttc_min", [("car", 43.2, 12.0, -10.0, 1.7),
                                                                  ("bicycle", -16.58, 5.0, -6.0, 2.0)])
def test_a_road_user_crossing_that_stops_in_the_lane_is_warned_for(actor, from_y, speed, brake, ttc_min):
    """An independent tester's scenes (helper-89): a car crossing at 12 m/s brakes at 10 m/s² and stops on the ego
    lane's centre at TTC 1.8 s (ego 20 m/s); a bicycle crossing at 5 m/s from the right brakes at 6 m/s² and stops
    0.5 m left of it at TTC 2.5 s (ego 13.9 m/s). The radar's track lags the stop (still 5 m/s across 0.1 s after it,
    7–9σ off): with the cleared-path rule on the track's speed alone the detection level warned 0.08–1.23 s before the
    impact or not at all, and for the bicycle, reported 0.2 m long, 0.4–0.6 s before. Now a target counts as clearing
    only if braking at 10 m/s² could not stop it inside the path, with an extent of at least 5 m: warned as before
    the rule (car 1.81–2.02 s, bicycle 2.61 s TTC at the warning, seeds 1–3)."""
    from radarnode.consumer.evaluate import simulate
    heading = -90 if from_y > 0 else 90
    ego = 20.0 if actor == "car" else 13.9
    x = 124.6 if actor == "car" else 92.23
    for seed in (1, 2, 3):
        sc = scenario(f"  - {{id: c, class: {actor}, x_m: {x}, y_m: {from_y}, heading_deg: {heading}, speed_mps: {speed}, "
                      f"accel: [{{t_s: 3.0, accel_mps2: {brake}}}]}}", ego=f"{{speed_mps: {ego}}}",
                      road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0}", duration=6.3 if actor == "car" else 6.63,
                      seed=seed, extra="ecu: {acc_enabled: false, expect: {lead: c}}")
        r = simulate(sc, fidelity="detection")
        assert r.impact_time_s is not None                  # the ego does not brake: the scene ends in the crash
        assert r.ttc_at_warning_s is not None and ttc_min <= r.ttc_at_warning_s < 5.0, (seed, r.warning_time_s,
                                                                                        r.ttc_at_warning_s)


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
NEED = HALF + EXTENT


def _clears(offset, w, reach, sigma=0.0, along=0.0, accel=0.0):
    from radarnode.consumer.ecu import clears_path
    return bool(clears_path(np.array([offset]), np.array([w]), np.array([sigma]), np.array([reach]), HALF,
                            np.array([EXTENT]), np.array([along]), np.array([accel]))[0])


@pytest.mark.parametrize("later, clears", [(NEED - 0.01, False), (NEED + 0.01, True), (2.0 * NEED, True),
                                           (0.0, False)])
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_fcw_leaves_out_a_target_only_once_it_will_have_cleared_the_path(later, clears, side):
    """The reported point, where its speed across puts it when the ego gets there, beyond the path's half-width plus
    the body's extent on the side it moves to: just short of that, not cleared; just beyond and twice, cleared; on
    either side. (30 m/s across: braking could not stop it within the path, the other condition.)"""
    reach, w = 0.5, 30.0 * side
    assert _clears(side * later - w * reach, w, reach) == clears


@pytest.mark.parametrize("factor, clears", [(0.5, False), (0.99, False), (1.01, True), (2.0, True)])
def test_fcw_leaves_out_a_target_only_if_it_cannot_stop_in_the_path(factor, clears):
    """On the centre line, far from the ego: braking at CLEAR_BRAKE_MPS2 from its speed across it stops w²/2a on —
    cleared only where that is beyond the half-width plus the extent (speed² at 0.5, 0.99, 1.01 and 2 times the
    limit's)."""
    from radarnode.consumer.ecu import CLEAR_BRAKE_MPS2
    w = math.sqrt(factor * 2.0 * CLEAR_BRAKE_MPS2 * NEED)
    assert _clears(0.0, w, 100.0) == clears


@pytest.mark.parametrize("sigmas, clears", [(0.0, True), (0.99, True), (1.01, False), (2.0, False)])
def test_fcw_clears_a_target_on_the_least_speed_across_its_sigma_allows(sigmas, clears):
    """On the centre line at 20 m/s across, far from the ego: its σ in units of the one whose CLEAR_SIGMAS σ leave it
    just able to stop at the edge: below 1 cleared, above not; twice, not."""
    from radarnode.consumer.ecu import CLEAR_BRAKE_MPS2, CLEAR_SIGMAS
    w = 20.0
    edge_sigma = (w - math.sqrt(2.0 * CLEAR_BRAKE_MPS2 * NEED)) / CLEAR_SIGMAS
    assert _clears(0.0, w, 100.0, sigma=sigmas * edge_sigma) == clears


def test_a_target_not_moving_across_or_not_reached_never_clears():
    """A stopped car in the lane (no speed across) and one the ego does not close on (reach 0) stay candidates."""
    assert not _clears(0.5, 0.0, 3.0)
    assert not _clears(0.5, 30.0, 0.0)


@pytest.mark.parametrize("angle_deg, clears", [(15.0, False), (29.0, False), (31.0, True), (60.0, True), (90.0, True)])
def test_fcw_clears_only_a_target_moving_across_the_path(angle_deg, clears):
    """A target 30 m/s over ground on the centre line, its motion ``angle_deg`` off the path's direction, far from the
    ego (both other conditions met at each of these angles): left out only beyond CLEAR_MIN_ANGLE_DEG (30°) — not a
    lead on a curve entry whose road the yaw-rate circle does not follow yet."""
    from radarnode.consumer.ecu import CLEAR_MIN_ANGLE_DEG
    assert CLEAR_MIN_ANGLE_DEG == 30.0
    a = math.radians(angle_deg)
    assert _clears(0.0, 30.0 * math.sin(a), 4.0, along=30.0 * math.cos(a)) == clears


@pytest.mark.parametrize("braking, clears", [(0.0, True), (0.99, True), (1.01, False), (2.0, False), (-5.0, True)])
@pytest.mark.parametrize("side", [1.0, -1.0])
def test_fcw_does_not_clear_a_target_braking_across_the_path(braking, clears, side):
    """30 m/s across on the centre line, far from the ego (every other condition met), its acceleration across
    against its motion ``braking`` times CLEAR_BRAKING_MPS2 (negative: speeding up): a target braking harder than that
    may stop in the path (its track's speed lags the braking) and stays a candidate; either side."""
    from radarnode.consumer.ecu import CLEAR_BRAKING_MPS2
    assert _clears(0.0, 30.0 * side, 100.0, accel=-side * braking * CLEAR_BRAKING_MPS2) == clears
