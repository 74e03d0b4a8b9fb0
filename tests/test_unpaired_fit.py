"""A staggered radar's unpaired detections in the rigid fits (radarnode.perception.tracker.speed_known).

With staggered ramps a detection that the second chirp sequence did not confirm (AmbigState ambiguous) has a range
rate known only modulo 2·v_max, and near a strong reflector it is often a spur whose range rate is no body's. The
signal level's truck passed on the left (benchmarks/side_pass.py) had one: 2 m beside the sensor, unpaired at
+4.0 m/s where the side's paired detection read −1.4 m/s. Two detections fit a rigid velocity exactly, so the two were
joined with (16, −17.5) m/s, the track took that velocity across, left the truck's lane and coasted through the
ego's: ACC's target and an FCW warning. The fits now use the paired detections only; a single ramp, whose every
moving detection is flagged ambiguous, keeps taking its range rates as measured.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from radarnode.perception.tracker import ObjectTracker, group_detections, join_rigid, speed_known
from radarnode.perception.types import (AMBIG_AMBIGUOUS, AMBIG_INVALID, AMBIG_STAGGERED, AMBIG_STATIONARY,
                                        AMBIG_UNAMBIGUOUS, Detections)
from radarnode.radar.models import tracker_for
from radarnode.radar.presets import get_preset
from tests.test_rigid_groups import _cat, _dbscan, _detections
from tests.test_side_pass import ARS_FOV

# the traced cycle (signal level, truck passed on the left 2 m/s slower, seed 1, t = 16.85 s): the side's paired
# detection and an unpaired spur 1.1 m from it
_SIDE = (2.20, 2.26, -1.376)
_SPUR = (3.11, 2.00, 3.995)
_SNR_DB = (104.3, 20.9)


def _points(points, states, snr_db=None):
    x, y, vr = (np.array(c, float) for c in zip(*points))
    r, az = np.hypot(x, y), np.arctan2(y, x)
    n = x.size
    snr = np.full(n, 40.0) if snr_db is None else np.asarray(snr_db, float)
    det = Detections(r, vr, az, np.full(n, 5.0), snr, np.zeros(n, dtype=np.int64))
    det.ambig_state = np.asarray(states, dtype=np.int64)
    return det


def _with_states(det, states):
    out = dataclasses.replace(det)
    out.ambig_state = np.asarray(states, dtype=np.int64)
    return out


def test_the_traced_spur_is_not_joined_with_staggered_ramps():
    det = _points([_SIDE, _SPUR], [AMBIG_STAGGERED, AMBIG_AMBIGUOUS])
    labels = _dbscan(det)
    assert labels.max() == 1                                    # two speed groups
    # taken as measured (a single ramp; what the staggered radar's tracker did before): joined, exactly fitted, wild
    new, v, _ = join_rigid(det, labels)
    assert new.max() == 0 and np.hypot(*v[0]) > 20.0
    g = group_detections(det)
    assert len(g) == 1 and np.hypot(*g.velocity[0]) > 20.0
    # the unpaired spur's range rate enters no fit: two groups, no fitted velocity
    new, v, _ = join_rigid(det, labels, speed_known(det, staggered=True))
    assert new.max() == 1 and not np.isfinite(v).any()
    g = group_detections(det, staggered=True)
    assert len(g) == 2 and not np.isfinite(g.velocity).any()


def test_speed_known():
    """Paired (2) and unambiguous (3) range rates are measurements; unpaired (1), a stationary candidate's hypothesis
    (4) and invalid (0) are not — with staggered ramps; a single ramp takes every one as measured."""
    states = [AMBIG_STAGGERED, AMBIG_AMBIGUOUS, AMBIG_UNAMBIGUOUS, AMBIG_STATIONARY, AMBIG_INVALID]
    det = _points([_SIDE] * 5, states)
    assert speed_known(det, staggered=True).tolist() == [True, False, True, False, False]
    assert speed_known(det, staggered=False).tolist() == [True] * 5


@pytest.mark.parametrize("state", [AMBIG_AMBIGUOUS, AMBIG_STATIONARY])
def test_a_spur_taken_for_the_standing_world_is_not_joined_either(state):
    """The tester's case: a truck's side 2 m/s slower seen at 80°, and a spur 1.2 m from it at 51° flagged a stationary
    candidate (its range rate the standing world's, −30·cos az at 30 m/s): taken as measured the two join with an exact,
    wild velocity; with staggered ramps neither an unpaired nor a stationary candidate's range rate is fitted."""
    side = (2.0 * np.cos(np.radians(80.0)) / np.sin(np.radians(80.0)), 2.0, -2.0 * np.cos(np.radians(80.0)))
    az = np.radians(51.0)
    spur_r = np.hypot(side[0], side[1]) - 0.5
    spur = (spur_r * np.cos(az), spur_r * np.sin(az), -30.0 * np.cos(az))
    det = _points([side, spur], [AMBIG_STAGGERED, state])
    labels = _dbscan(det)
    assert labels.max() == 1
    new, v, _ = join_rigid(det, labels)
    assert new.max() == 0 and np.hypot(*v[0]) > 20.0
    new, v, _ = join_rigid(det, labels, speed_known(det, staggered=True))
    assert new.max() == 1 and not np.isfinite(v).any()


def test_a_group_of_its_own_is_fitted_from_its_paired_detections():
    """One speed group (DBSCAN keeps it whole) spread over 24° at 4 m, its detections at the car's motion but the
    unpaired one 0.4 m/s off: with staggered ramps its fit is the paired ones', exact; taken as measured it is biased."""
    v = (-2.0, 1.0)
    det = _arc_states(4.0, [0.0, 8.0, 16.0, 24.0], v, [0.0, 0.0, 0.4, 0.0], [AMBIG_STAGGERED, AMBIG_STAGGERED,
                                                                           AMBIG_AMBIGUOUS, AMBIG_STAGGERED])
    assert _dbscan(det).max() == 0
    g = group_detections(det, staggered=True)
    assert len(g) == 1 and np.allclose(g.velocity[0], v, atol=1e-9)
    g = group_detections(det)
    assert len(g) == 1 and np.isfinite(g.velocity[0]).all() and not np.allclose(g.velocity[0], v, atol=1e-3)


def test_the_span_is_that_of_the_paired_detections():
    """A group whose paired detections span 8° and whose unpaired one lies 8° further: the speed across is measured over
    the paired ones' 8°, under the 10° a fit needs — no fit with staggered ramps (taken as measured: 16°, fitted)."""
    v = (-2.0, 1.0)
    det = _arc_states(4.0, [0.0, 4.0, 8.0, 16.0], v, [0.0] * 4, [AMBIG_STAGGERED] * 3 + [AMBIG_AMBIGUOUS])
    assert _dbscan(det).max() == 0
    assert not np.isfinite(group_detections(det, staggered=True).velocity).any()
    assert np.allclose(group_detections(det).velocity[0], v, atol=1e-9)


def test_a_body_is_not_joined_to_a_group_without_a_paired_range_rate():
    """A body's paired detections, one speed group over 12° that a fit explains exactly, touching an unpaired detection
    2 m/s off (a group of its own): nothing measures that one motion explains both, so they stay apart (taken as
    measured, the 2 m/s keeps them apart too)."""
    v = (-2.0, 1.0)
    det = _arc_states(4.0, [0.0, 4.0, 8.0, 12.0, 16.0], v, [0.0] * 4 + [2.0], [AMBIG_STAGGERED] * 4 + [AMBIG_AMBIGUOUS])
    labels = _dbscan(det)
    assert labels[:4].tolist() == [0] * 4 and labels[4] == 1
    new, _, _ = join_rigid(det, labels, speed_known(det, staggered=True))
    assert new[4] != new[0]
    new, _, _ = join_rigid(det, labels)
    assert new[4] != new[0]


def _arc_states(r, az_deg, v, off, states):
    az = np.radians(np.asarray(az_deg, float))
    det = _detections(r * np.cos(az), r * np.sin(az), v, extra_vr=np.asarray(off, float))
    return _with_states(det, states)


# a car's side 2 m from the sensor, from −20° to 70° of azimuth, overtaking at (3.5, −3.4) m/s relative
_SIDE_X = np.array([3.73, 3.09, 2.45, 1.82, 1.31, 0.67])
_SIDE_Y = np.array([-1.08, -0.45, 0.19, 0.83, 1.34, 1.97])
_V = (3.5, -3.4)


@pytest.mark.parametrize("off_mps", [0.0, 0.3, 3.0])
def test_a_body_keeps_its_fit_from_its_paired_detections(off_mps):
    """A car beside the sensor whose last detection (at 71°) is unpaired and reads a range rate ``off_mps`` off the
    car's motion: with staggered ramps the car's fit is that of its paired detections, exact. Taken as measured, 0.3
    m/s off (within the fit's 0.5 m/s) joins it and biases the fit, 3 m/s off spoils the fit of the speed group it
    falls into (DBSCAN puts it with the detection at 46°, 0.9 m/s apart)."""
    extra = np.zeros(6)
    extra[-1] = off_mps
    det = _with_states(_detections(_SIDE_X, _SIDE_Y, _V, extra_vr=extra), [AMBIG_STAGGERED] * 5 + [AMBIG_AMBIGUOUS])
    g = group_detections(det, staggered=True)
    assert g.labels[:5].tolist() == [0] * 5
    assert np.allclose(g.velocity[0], _V, atol=1e-9)
    g_old = group_detections(det)
    if off_mps == 0.3:
        k = g_old.labels[0]
        assert not np.isfinite(g_old.velocity[k, 0]) or not np.allclose(g_old.velocity[k], _V, atol=1e-3)


def test_a_group_of_unpaired_detections_only_is_joined_to_nothing():
    """An unpaired single detection touching a car's paired side at a range rate that the car's motion explains: no
    range rate of it may be used, so nothing tells that one motion explains both, and it stays a group of its own
    (taken as measured it is joined)."""
    car = _with_states(_detections(_SIDE_X[:5], _SIDE_Y[:5], _V), [AMBIG_STAGGERED] * 5)
    other = _with_states(_detections([_SIDE_X[5]], [_SIDE_Y[5]], _V), [AMBIG_AMBIGUOUS])
    det = _cat([car, other])
    det.ambig_state = np.concatenate([car.ambig_state, other.ambig_state])
    labels = _dbscan(det)
    assert labels[-1] != labels[0]
    new, v, _ = join_rigid(det, labels)
    assert new.max() == 0
    new, v, _ = join_rigid(det, labels, speed_known(det, staggered=True))
    assert new[-1] != new[0] and new[:5].tolist() == [0] * 5
    assert np.allclose(v[0], _V, atol=1e-9)


@pytest.mark.parametrize("preset, staggered", [("ars408_like", True), ("mimo12", False), ("fast_chirp", False),
                                               ("acc_lrr", False)])
def test_the_trackers_of_the_presets(preset, staggered):
    """Only a staggered radar's tracker leaves unpaired range rates out of its fits (models.tracker_for)."""
    p = get_preset(preset)
    assert bool(p.stagger_chirp_period_s) == staggered
    assert tracker_for(p, 0.072).staggered == staggered
    assert not ObjectTracker().staggered


def test_the_tracker_does_not_take_the_spur_across():
    """The tracker of a staggered radar following the side at (−2, 0) m/s, the ARS 408's field of view cutting it: the
    cycle with the spur leaves its velocity across where the side's detections put it; the same cycle taken as
    measured (the tracker without staggered ramps) pulls it across towards the joined fit's −17.5 m/s."""
    def run(staggered):
        trk = ObjectTracker(alias_span_mps=39.0 if staggered else None, fov=ARS_FOV)
        assert trk.staggered == staggered
        for k in range(20):        # the side's detection, coming back at 2 m/s towards the traced cycle's place
            x = _SIDE[0] + 2.0 * 0.072 * (20 - k)
            vr = -2.0 * x / np.hypot(x, 2.26)
            trk.step(k * 0.072, _points([(x, 2.26, vr)], [AMBIG_STAGGERED]), (30.0, 0.0))
        assert len(trk.x) == 1 and trk.confirmed[0]
        vy = trk.x[0, 3]
        trk.step(20 * 0.072, _points([_SIDE, _SPUR], [AMBIG_STAGGERED, AMBIG_AMBIGUOUS], _SNR_DB), (30.0, 0.0))
        side = np.flatnonzero(trk.confirmed)
        assert side.size == 1
        return trk.x[side[0], 3] - vy, abs(trk.x[side[0], 1] - 2.26)
    dvy, dy = run(True)
    assert abs(dvy) < 0.05 and dy < 0.1
    dvy, _ = run(False)
    assert dvy < -0.15
