"""The angular spread of a cell's reflector (radarnode.dsp.spread) and how the trackers use it and stationarity."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.dsp import spread
from radarnode.perception.tracker import (COAST_CYCLES, COAST_STATIONARY_CYCLES, CONFIRM_WINDOW_STATIONARY,
                                          ObjectTracker)
from radarnode.perception.types import Detections


def _steer(n, d, s):
    return np.exp(2j * np.pi * d * np.outer(np.atleast_1d(s), np.arange(n)))


@pytest.mark.parametrize("n, d", [(8, 0.5), (12, 0.5), (4, 0.5)])
def test_a_plane_wave_leaves_nothing_unexplained_and_has_no_spread(n, d):
    for s in (-0.95, -0.3, 0.0, 0.41, 0.99):
        x = 3.0 * np.exp(0.7j) * _steer(n, d, s)
        frac = spread.unexplained_fraction(x, np.array([0]), np.array([s]), d)
        assert frac[0] < 1e-12 and spread.angular_spread(frac, n, d)[0] < 1e-9
    # two plane waves, both fitted: nothing left either (the least-squares path for several sources)
    x = _steer(n, d, -0.4) + 0.5 * _steer(n, d, 0.35)
    assert spread.unexplained_fraction(x, np.array([0, 0]), np.array([-0.4, 0.35]), d)[0] < 1e-12
    # no source found: all of it is unexplained; noise's expected share is taken out and never goes below 0
    assert spread.unexplained_fraction(x, np.zeros(0, int), np.zeros(0), d)[0] == 1.0
    assert spread.unexplained_fraction(x, np.array([0]), np.array([-0.4]), d, noise_power=1e6)[0] == 0.0


@pytest.mark.parametrize("n", [8, 12])
def test_the_expected_fraction_of_a_uniform_spread_is_the_closed_form_and_inverts(n):
    """Monte Carlo: many scatterers with random phases spread uniformly over Δs about s0, fitted with the steering
    vector at s0; the mean unexplained fraction against 1 − ΣΣ sinc(d(k−l)Δs)/N² (an independent computation of the
    same expectation), and angular_spread inverting it."""
    d, rng = 0.5, np.random.default_rng(5)
    k = np.arange(n)
    for ds in (0.02, 0.06, 0.12):
        frac, total = [], []
        for _ in range(600):
            u = 0.2 + rng.uniform(-ds / 2, ds / 2, 64)
            x = (np.exp(2j * np.pi * rng.random(64))[:, None] * np.exp(2j * np.pi * d * np.outer(u, k))).sum(0)
            frac.append(spread.unexplained_fraction(x, np.array([0]), np.array([0.2]), d)[0])
            total.append(np.sum(np.abs(x) ** 2))
        lag = k[:, None] - k[None, :]
        expected = 1.0 - np.sinc(d * lag * ds).sum() / n ** 2
        # the expectation of the unexplained energy over that of the energy (one snapshot's fraction scatters
        # around it, large in the fades of the coherent sum, where the glint is large too)
        assert np.average(frac, weights=total) == pytest.approx(expected, rel=0.1), ds
        assert spread.angular_spread(np.array([expected]), n, d)[0] == pytest.approx(ds, rel=1e-2)
    # beyond what the aperture can tell the estimate saturates instead of extrapolating
    assert spread.angular_spread(np.array([1.0]), n, d)[0] == pytest.approx(2.0 / (n * d))


def _dets(r, az, vr):
    r = np.atleast_1d(np.asarray(r, float))
    return Detections(r, np.full(r.size, vr), np.full(r.size, az), np.full(r.size, 10.0), np.full(r.size, 30.0),
                      np.zeros(r.size, dtype=np.int64))


def _empty():
    return Detections(*(np.zeros(0),) * 5, np.zeros(0, dtype=np.int64))


def _run(pattern, vr, ego=20.0, period=0.072):
    """Track one point 60 m ahead detected in the cycles where ``pattern`` is true; per cycle the reported IDs."""
    tr, ids = ObjectTracker(), []
    for k, hit in enumerate(pattern):
        r = 60.0 + (vr * k * period)
        ol = tr.step(k * period, _dets(r, 0.0, vr) if hit else _empty(), (ego, 0.0))
        ids.append(tuple(ol.id.tolist()))
    return ids


@pytest.mark.parametrize("n, d", [(2, 0.5), (8, 0.5), (12, 0.5), (8, 0.7), (64, 0.5)])
def test_the_spread_table_is_the_double_sum_over_element_pairs_and_stays_small_for_thousands(n, d):
    """The table's ΣΣ_{k,l} sinc(d(k−l)Δs), summed over the lags (each N − |lag| times), is the double sum over
    the (N, N) pairs written out here, to rounding; at 4096 elements it no longer needs 512 × 4096² floats (64 GiB,
    an independent tester's finding: the detection level ran out of memory)."""
    spread._table.cache_clear()
    s, frac = spread._table(n, d)
    pairs = np.arange(n)[:, None] - np.arange(n)[None, :]
    grid = np.linspace(0.0, 2.0 / (n * d), spread._TABLE_POINTS)
    direct = 1.0 - np.sinc(d * pairs[None, :, :] * grid[:, None, None]).sum(axis=(1, 2)) / n ** 2
    top = int(np.argmax(direct))
    assert np.array_equal(s, grid[: top + 1])
    assert np.allclose(frac, np.maximum.accumulate(direct[: top + 1]), rtol=0.0, atol=1e-12)
    big_s, big = spread._table(4096, 0.5)
    assert big.size > 10 and np.all(np.diff(big) >= 0.0) and 0.0 <= big[0] < 1e-9


def test_a_standing_object_detected_one_cycle_in_three_is_kept_and_a_moving_one_is_not():
    every_third = [k % 3 == 0 for k in range(30)]
    still = _run(every_third, vr=-20.0)           # stands still: it closes at the ego's speed
    assert all(len(i) == 1 for i in still[4:]) and len({i for i in still[4:]}) == 1
    moving = _run(every_third, vr=-5.0)            # a vehicle ahead driving at 15 m/s: the usual 2-of-3 rule
    assert all(len(i) == 0 for i in moving)


@pytest.mark.parametrize("vr, coast", [(-20.0, COAST_STATIONARY_CYCLES), (-5.0, COAST_CYCLES)])
def test_coasting_ends_just_after_the_limit(vr, coast):
    ids = _run([True] * 6 + [False] * (coast + 2), vr=vr)
    assert len(ids[5 + coast]) == 1 and len(ids[5 + coast + 1]) == 0     # kept through `coast` misses, then gone


def test_the_object_level_keeps_standing_and_moving_actors_by_the_same_rules():
    from radarnode.radar.object_model import ObjectModel
    m = ObjectModel.__new__(ObjectModel)
    n = 2
    m.hist, m.misses, m.alive = np.zeros(n, np.uint8), np.zeros(n, np.int64), np.zeros(n, bool)
    m.reportable = np.ones(n, bool)
    det = np.array([[k % 3 == 0] * n for k in range(30)])
    flags = m._track_flags(det, np.ones(det.shape, bool), np.array([[True, False]] * 30))
    assert flags["alive"][4:, 0].all() and not flags["alive"][:, 1].any()
    assert CONFIRM_WINDOW_STATIONARY == 5 and math.isfinite(COAST_STATIONARY_CYCLES)
