"""The consumer tracker's roles, alone and together; filter consistency (NEES) and OSPA."""

from __future__ import annotations

import numpy as np
import pytest

from radarnode.consumer.tracking import (
    Tracker, associate, initiate, measurement_matrix, nees, nees_bounds, ospa, predict, transition, update)
from radarnode.errors import ConfigError


def test_predict_cv_and_ca_and_the_ego_rotation():
    x = np.array([[10.0, 0.0, 2.0, 1.0]])
    p = np.tile(np.eye(4), (1, 1, 1))
    xp, pp = predict(x, p, "cv", 0.5, 1.0)
    assert xp[0].tolist() == pytest.approx([11.0, 0.5, 2.0, 1.0])
    assert np.all(np.diag(pp[0]) > 1.0)
    xa, _ = predict(np.array([[0.0, 0.0, 10.0, 0.0, -2.0, 0.0]]), np.tile(np.eye(6), (1, 1, 1)), "ca", 1.0, 0.1)
    assert xa[0, :4].tolist() == pytest.approx([9.0, 0.0, 8.0, 0.0])
    # the sensor turns left by 0.1 rad: a point straight ahead appears slightly to the right
    xr, _ = predict(np.array([[50.0, 0.0, 0.0, 0.0]]), np.tile(np.eye(4), (1, 1, 1)), "cv", 0.1, 0.0, 0.1)
    assert xr[0, 1] == pytest.approx(-50.0 * np.sin(0.1))
    with pytest.raises(ConfigError):
        transition("singer", 0.1, 1.0)


def test_update_pulls_towards_the_measurement_and_shrinks_the_covariance():
    h = measurement_matrix(4, "clusters")
    x, p = np.array([[0.0, 0.0, 0.0, 0.0]]), np.tile(np.eye(4) * 4.0, (1, 1, 1))
    xn, pn = update(x, p, np.array([[2.0, 0.0]]), np.tile(np.eye(2), (1, 1, 1)), h)
    assert xn[0, 0] == pytest.approx(1.6) and pn[0, 0, 0] == pytest.approx(0.8)
    assert np.allclose(pn[0], pn[0].T)


def test_associate_gates_and_prefers_ids():
    d2 = np.array([[1.0, 2.0], [2.0, 1.5], [50.0, 60.0]])
    assert sorted(associate(d2, 9.0)) == [(0, 0), (1, 1)]
    # IDs say track 0 is object 7 (column 1): within the gate the ID wins
    pairs = associate(d2, 9.0, np.array([7, 3, 5]), np.array([3, 7]))
    assert sorted(pairs) == [(0, 1), (1, 0)]


def test_initiate_sets_unmeasured_parts_wide():
    x, p = initiate(np.array([[10.0, 1.0]]), np.tile(np.eye(2) * 0.25, (1, 1, 1)), 6, "clusters")
    assert x[0].tolist() == [10.0, 1.0, 0.0, 0.0, 0.0, 0.0]
    assert p[0, 0, 0] == 0.25 and p[0, 2, 2] == 100.0 and p[0, 4, 4] == 9.0


def test_m_of_n_confirmation_coasting_and_deletion():
    tr = Tracker("objects", "cv", confirm=(2, 3), max_coast=2)
    r = np.tile(np.eye(4) * 0.1, (1, 1, 1))
    z = np.array([[20.0, 0.0, -1.0, 0.0]])
    assert tr.step(0.0, z, r, np.array([5])) == []                   # tentative
    conf = tr.step(0.1, z + [[-0.1, 0, 0, 0]], r, np.array([5]))
    assert len(conf) == 1 and conf[0].meas_id == 5
    for k in range(2):                                               # coasting through two misses
        assert len(tr.step(0.2 + 0.1 * k, np.zeros((0, 4)), np.zeros((0, 4, 4)), np.zeros(0, int))) == 1
    assert tr.step(0.4, np.zeros((0, 4)), np.zeros((0, 4, 4)), np.zeros(0, int)) == []   # third miss: gone
    assert tr.tracks == []


def test_filter_is_consistent_over_monte_carlo_runs():
    """Average NEES of a CV filter on white-acceleration truth stays inside the χ² bounds."""
    rng = np.random.default_rng(0)
    runs, steps, dt, q, sigma = 50, 60, 0.072, 1.0, 0.3
    f, qq = transition("cv", dt, q)
    h = measurement_matrix(4, "clusters")
    values = np.zeros(steps)
    for _ in range(runs):
        truth = np.array([30.0, 2.0, -3.0, 0.5])
        x, p = initiate((truth[:2] + rng.normal(0, sigma, 2))[None], np.tile(np.eye(2) * sigma ** 2, (1, 1, 1)),
                        4, "clusters", v_sigma=5.0)
        x[0, 2:] = truth[2:] + rng.normal(0, 5.0, 2)
        for k in range(steps):
            truth = f @ truth + rng.multivariate_normal(np.zeros(4), qq)
            x, p = predict(x, p, "cv", dt, q)
            z = truth[:2] + rng.normal(0, sigma, 2)
            x, p = update(x, p, z[None], np.tile(np.eye(2) * sigma ** 2, (1, 1, 1)), h)
            values[k] += nees(x, p, truth[None])[0] / runs
    lo, hi = nees_bounds(4, runs, 0.99)
    inside = (values[10:] >= lo) & (values[10:] <= hi)
    assert inside.mean() >= 0.9, values


def test_ospa():
    a = np.array([[0.0, 0.0], [10.0, 0.0]])
    assert ospa(a, a) == 0.0
    assert ospa(a, a + [1.0, 0.0], c=10.0) == pytest.approx(1.0)
    assert ospa(a, a[:1], c=10.0) == pytest.approx(np.sqrt(100.0 / 2))
    assert ospa(np.zeros((0, 2)), np.zeros((0, 2))) == 0.0


def test_gospa_counts_misses_and_false_tracks_without_normalising():
    from radarnode.consumer.tracking import gospa
    a = np.array([[0.0, 0.0], [10.0, 0.0]])
    assert gospa(a, a) == 0.0
    assert gospa(a, a + [1.0, 0.0], c=10.0) == pytest.approx(np.sqrt(2.0))
    # one truth missed: c²/2 added
    assert gospa(a[:1], a, c=10.0) == pytest.approx(np.sqrt(50.0))
    # a far-away estimate counts as one miss and one false track
    assert gospa(np.array([[100.0, 0.0]]), np.array([[0.0, 0.0]]), c=10.0) == pytest.approx(10.0)


def _braking_target(model, rng):
    """A lead at 20 m/s that brakes at 6 m/s² from 3 s; position and velocity measured with noise."""
    tr = Tracker("objects", model, q=2.0, confirm=(1, 1), max_coast=5)
    dt, err, mu_ca = 0.072, [], []
    x, v = 40.0, 0.0          # relative: the ego keeps 20 m/s
    for k in range(100):
        t = k * dt
        a = -6.0 if t >= 3.0 else 0.0
        v += a * dt
        x += v * dt
        z = np.array([[x + rng.normal(0, 0.2), rng.normal(0, 0.2), v + rng.normal(0, 0.1), rng.normal(0, 0.3)]])
        r = np.tile(np.diag([0.04, 0.04, 0.01, 0.09]), (1, 1, 1))
        conf = tr.step(t, z, r, np.array([1]))
        if conf and t >= 3.0:
            err.append(conf[0].x[2] - v)
            if model == "imm":
                mu_ca.append(conf[0].mu[1])
    return np.sqrt(np.mean(np.square(err))), mu_ca


def test_imm_follows_a_braking_lead_better_than_constant_velocity():
    rng = np.random.default_rng(4)
    rmse_cv, _ = _braking_target("cv", rng)
    rmse_imm, mu_ca = _braking_target("imm", rng)
    assert rmse_imm < 0.7 * rmse_cv
    assert max(mu_ca) > 0.8                      # the constant-acceleration mode takes over while braking


def test_imm_mixing_keeps_probabilities_and_moments():
    from radarnode.consumer.tracking import imm_combine, imm_mix
    xm = np.array([[[0.0] * 6, [1.0] + [0.0] * 5]])
    pm = np.tile(np.eye(6), (1, 2, 1, 1))
    mu = np.array([[0.25, 0.75]])
    x0, p0, c = imm_mix(xm, pm, mu)
    assert c.sum() == pytest.approx(1.0)
    x, p = imm_combine(xm, pm, mu)
    assert x[0, 0] == pytest.approx(0.75) and p[0, 0, 0] == pytest.approx(1.0 + 0.25 * 0.75)
