"""radarnode.dsp.lcacm (seed 001): two-circle geometry against an independent computation, the transform of eq. 3,
the compensator's weights against the normal equations, recovery of one and two targets, the beam scan against the
stochastic CRB, and finite output over −20…+60 dB and degenerate inputs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.dsp import lcacm as lc
from radarnode.dsp import subspace as ss
from radarnode.errors import ConfigError

GEO = lc.PairGeometry()

pytestmark = pytest.mark.filterwarnings("error::RuntimeWarning")


def scene(rng, az_deg, snr_db, trials, range_m=10.0, range_sigma_m=0.0, k=1):
    """Snapshots of both radars and their measured ranges for targets at ``az_deg`` (from the baseline's middle)."""
    az = np.radians(np.atleast_1d(az_deg))
    x, y = lc.polar_to_xy(range_m, az)
    _, th = lc.seen_from(x, y, GEO)
    ys = [lc.snapshots(rng, np.broadcast_to(th[i], (trials, az.size)), snr_db, 12, 0.5, k) for i in range(2)]
    r, _ = lc.seen_from(np.array(x.mean()), np.array(y.mean()), GEO)
    rm = r[:, None] + range_sigma_m * rng.standard_normal((2, trials))
    return ys, rm, th


# ---------------------------------------------------------------------------------------------------------
# geometry

def test_two_circle_intersection_recovers_points_placed_independently():
    rng = np.random.default_rng(0)
    b = 1.46
    # points anywhere ahead, ranges measured with math.dist from the two phase centres
    pts = np.column_stack((rng.uniform(-30, 30, 200), rng.uniform(0.01, 30, 200)))
    r1 = np.array([math.dist(p, (-b / 2, 0.0)) for p in pts])
    r2 = np.array([math.dist(p, (b / 2, 0.0)) for p in pts])
    x, y, ok = lc.two_circle_intersection(r1, r2, b)
    assert ok.all()
    np.testing.assert_allclose(x, pts[:, 0], atol=1e-9)
    np.testing.assert_allclose(y, pts[:, 1], atol=1e-6)      # y from a square root: less precise near y = 0


def test_circles_that_do_not_meet_are_flagged_and_stay_finite():
    x, y, ok = lc.two_circle_intersection(np.array([10.0, 0.5, 10.0]), np.array([12.0, 0.5, 10.0]), 1.46)
    assert list(ok) == [False, False, True]
    assert np.all(np.isfinite(x)) and np.all(np.isfinite(y)) and y[0] == 0.0 and y[1] == 0.0


def test_seen_from_matches_the_mounts():
    # a point straight out along radar 2's boresight (45° to the right of ahead, from radar 2) is at its local 0
    x, y = 0.73 + 5.0 * math.sin(math.radians(45)), 5.0 * math.cos(math.radians(45))
    r, th = lc.seen_from(np.array(x), np.array(y), GEO)
    assert r[1] == pytest.approx(5.0) and th[1] == pytest.approx(0.0, abs=1e-12)
    assert math.degrees(float(th[0])) > 45.0          # radar 1 looks 45° to the left: the point is far to its right


# ---------------------------------------------------------------------------------------------------------
# transform and compensator

def test_eq3_moves_the_centre_to_broadside():
    u0 = np.array([0.3, -0.55])
    y = lc.steering(12, u0[:, None])                                  # (2, 12, 1): one source per trial
    z = lc.derotate(y, u0)
    np.testing.assert_allclose(z, np.ones_like(z), atol=1e-12)


def test_compensator_weights_solve_the_normal_equations_and_eq8_as_printed():
    rng = np.random.default_rng(1)
    x = rng.standard_normal((3, 40)) + 1j * rng.standard_normal((3, 40))
    x0, x1, x2 = x

    def m(a, b):
        return np.mean(a * np.conj(b))

    c1, c2 = lc.acm_weights(None, m(x1, x1).real, m(x2, x2).real, m(x0, x1), m(x0, x2), m(x2, x1), loading=0.0)
    # minimise <|x0 + c1 x1 + c2 x2|²>: the least-squares solution of [x1 x2] c = −x0
    want = np.linalg.lstsq(np.column_stack((x1, x2)), -x0, rcond=None)[0]
    np.testing.assert_allclose([c1, c2], want, rtol=1e-10)
    eq8 = (m(x0, x2) * m(x2, x1) - m(x0, x1) * m(x2, x2)) / (m(x1, x1) * m(x2, x2) - abs(m(x2, x1)) ** 2)
    assert c1 == pytest.approx(eq8, rel=1e-12)


def test_compensator_passes_the_look_direction_and_cancels_another_source():
    # two sources in the transformed domain; looking at one, the output keeps its power and loses the other's
    rng = np.random.default_rng(2)
    q, s = 8, 400
    a, b = lc.steering(q, np.array([0.0])), lc.steering(q, np.array([0.12]))
    amp = rng.standard_normal((2, s)) + 1j * rng.standard_normal((2, s))
    samples = (a @ amp[:1] + 3.0 * b @ amp[1:]).T[None]                  # (1, S, Q), no noise
    p = lc.acm_spectrum(samples, np.array([0.0]))[0, 0]
    want = np.mean(np.abs(amp[0]) ** 2)
    assert p == pytest.approx(want, rel=0.05)
    beam = np.mean(np.abs(samples[0] @ np.conj(a[:, 0]) / q) ** 2)
    assert beam > 1.3 * want                                            # the plain beam lets the other in


# ---------------------------------------------------------------------------------------------------------
# recovery

def test_lcacm_recovers_two_targets_at_high_snr():
    rng = np.random.default_rng(3)
    truth = np.array([2.0, 12.0])
    ys, rm, _ = scene(rng, truth, 40.0, 200)
    est = lc.lcacm(ys[0], ys[1], rm[0], rm[1], GEO, n_max=3)
    two = est.count == 2
    # the two amplitudes fade independently (complex Gaussian): in some trials one is > 10 dB below the other and
    # falls under the peak floor; measured when written: 0.875
    assert two.mean() >= 0.8, two.mean()
    got = np.sort(np.degrees(est.azimuth_rad[two][:, :2]), axis=1)
    # even at 40 dB the spread is ~0.8°: the pair is cos θ₁·10° wide in radar 1's sine domain and cos θ₂·10° in
    # radar 2's (56° and −42° local), eq. 3 cannot align both, and which radar dominates follows the fading.
    # Measured when written: means 2.27° and 11.94°, spread 0.76° and 0.87°, 95th percentile error 1.9°
    np.testing.assert_allclose(got.mean(axis=0), truth, atol=0.5)
    assert np.percentile(np.abs(got - truth).max(axis=1), 95) < 2.5


def test_lcacm_corrects_the_error_of_the_two_circle_point():
    # ranges 5 cm off: the two-circle direction φ alone errs by degrees; the compensator brings it back
    rng = np.random.default_rng(4)
    ys, rm, _ = scene(rng, [7.0], 30.0, 300, range_sigma_m=0.05)
    est = lc.lcacm(ys[0], ys[1], rm[0], rm[1], GEO, n_max=2)
    ok = est.count == 1
    assert ok.mean() > 0.95
    err_phi = np.degrees(est.centre_azimuth_rad) - 7.0
    err = np.degrees(est.azimuth_rad[ok, 0]) - 7.0
    rms_phi, rms = math.sqrt(np.mean(err_phi ** 2)), math.sqrt(np.mean(err ** 2))
    # measured when written: φ 2.8°, LC-ACM 0.15°
    assert rms_phi > 2.0 and rms < 0.3, (rms_phi, rms)


@pytest.mark.parametrize("estimator", ["beam_scan", "capon_scan"])
def test_single_radar_scans_find_one_target(estimator):
    rng = np.random.default_rng(5)
    ys, _, th = scene(rng, [7.0], 30.0, 200)
    u, ok = getattr(lc, estimator)(ys[0], 2)
    assert (ok.sum(axis=1) == 1).mean() > 0.95
    assert np.median(np.abs(np.arcsin(u[:, 0]) - th[0, 0])) < math.radians(0.2)


def test_beam_scan_rmse_approaches_the_stochastic_crb():
    # one target, 64 snapshots, 20 dB: the stochastic CRB is tight there (with one snapshot it is not: the fading
    # of a complex-Gaussian target dominates); the bound is on sin θ
    rng = np.random.default_rng(6)
    u0 = 0.3
    y = lc.snapshots(rng, np.full((200, 1), math.asin(u0)), 20.0, 12, 0.5, 64)
    u, ok = lc.beam_scan(y, 1)
    ratio = math.sqrt(np.mean((u[:, 0] - u0) ** 2) / ss.crb_sin([u0], 12, 64, 20.0)[0])
    # measured when written: 1.08
    assert ok.all() and 0.85 < ratio < 1.25, ratio


# ---------------------------------------------------------------------------------------------------------
# never NaN, and errors

@pytest.mark.parametrize("snr_db", [-20.0, 0.0, 30.0, 60.0])
def test_finite_from_minus_20_to_plus_60_db(snr_db):
    rng = np.random.default_rng(7)
    ys, rm, _ = scene(rng, [5.0, 8.0], snr_db, 50)
    for centre in ("circle", "scan"):
        est = lc.lcacm(ys[0], ys[1], rm[0], rm[1], GEO, centre=centre)
        assert np.all(np.isfinite(est.azimuth_rad)) and np.all(np.isfinite(est.centre_azimuth_rad))
    for fn in (lc.beam_scan, lc.capon_scan):
        u, ok = fn(ys[0], 3)
        assert np.all(np.isfinite(u)) and np.all(np.abs(u) <= 1.0)


def test_zero_data_and_degenerate_ranges_give_flags_not_nan():
    y = np.zeros((3, 12, 1), dtype=complex)
    u, ok = lc.beam_scan(y, 2)
    assert np.all(np.isfinite(u)) and not ok.any()
    u, ok = lc.capon_scan(y, 2)
    assert np.all(np.isfinite(u))
    est = lc.lcacm(y, y, np.array([10.0, 10.0, 30.0]), np.array([10.0, 12.0, 1.0]), GEO)
    assert np.all(np.isfinite(est.azimuth_rad)) and list(est.circles_meet) == [True, False, False]


@pytest.mark.parametrize("kwargs, match", [
    ({"y1": np.zeros((2, 12))}, "shape"),
    ({"y1": np.full((2, 12, 1), np.nan)}, "non-finite"),
    ({"y2": np.zeros((2, 10, 1))}, "shape"),
    ({"r1_m": np.array([-1.0, 10.0])}, "range"),
    ({"centre": "middle"}, "centre: value 'middle'"),
    ({"offset": "cosine"}, "offset: value 'cosine'"),
])
def test_errors_name_the_argument_and_value(kwargs, match):
    args = {"y1": np.ones((2, 12, 1)), "y2": np.ones((2, 12, 1)), "r1_m": np.full(2, 10.0), "r2_m": np.full(2, 10.0)}
    opts = {k: kwargs.pop(k) for k in ("centre", "offset") if k in kwargs}
    args.update(kwargs)
    with pytest.raises(ConfigError, match=match):
        lc.lcacm(args["y1"], args["y2"], args["r1_m"], args["r2_m"], GEO, **opts)


def test_geometry_is_validated():
    with pytest.raises(ConfigError, match="baseline_m"):
        lc.PairGeometry(baseline_m=0.0)
    with pytest.raises(ConfigError, match="yaw_rad"):
        lc.PairGeometry(yaw_rad=(0.0, 2.0))
