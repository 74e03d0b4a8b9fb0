"""Numerical stability at the extremes: no NaN, no inf, no numpy warning, aliasing as a real radar aliases."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from radarnode.radar.chain import DspChain
from radarnode.radar import detection_model
from radarnode.radar.presets import PRESETS
from radarnode.radar.scatterers import Scatterers, point_targets
from radarnode.radar.signal_model import synthesize

P = PRESETS["mimo12"]


def _process(scat, dtype=np.complex128, seed=0, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with np.errstate(all="raise", under="ignore"):
            cube = synthesize(P, scat, np.random.default_rng(seed), dtype=dtype, **kw)
            det = DspChain(P).process(cube)
            ana = detection_model.detect(P, scat, np.random.default_rng(seed), DspChain(P).statistic)
    for d in (det, ana):
        for name in ("range_m", "range_rate_mps", "azimuth_rad", "rcs_dbsm", "snr_db"):
            assert np.all(np.isfinite(getattr(d, name))), name
    assert np.all(np.isfinite(cube.real)) and np.all(np.isfinite(cube.imag))
    return det, ana


def _nearest(det, r):
    return det.take(np.array([int(np.argmin(np.abs(det.range_m - r)))]))


@pytest.mark.parametrize("dtype", [np.complex128, np.complex64])
def test_minimum_range_and_beyond_the_unambiguous_range(dtype):
    r_max = P.unambiguous_range_m
    # a 10 dBsm target at 1 m has 111 dB SNR: its window sidelobes would bury anything else, so it gets
    # a frame of its own
    near, _ = _process(point_targets([1.0], [0.0], [0.0]), dtype)
    assert np.min(np.abs(near.range_m - 1.0)) < P.range_resolution_m
    det, ana = _process(point_targets([r_max - 2.0, r_max + 20.0], [5.0, -5.0], [0.0, 3.0]), dtype)
    assert np.min(np.abs(det.range_m - (r_max - 2.0))) < P.range_resolution_m
    # beyond R_max the beat frequency wraps: the target appears at R − R_max, as in a real complex-sampled radar
    assert np.min(np.abs(det.range_m - 20.0) + np.abs(det.range_rate_mps - 3.0)) < 1.0
    assert np.min(np.abs(ana.range_m - 20.0) + np.abs(ana.range_rate_mps - 3.0)) < 1.0


@pytest.mark.parametrize("dtype", [np.complex128, np.complex64])
def test_speed_at_and_beyond_vmax_aliases(dtype):
    vmax = P.max_unambiguous_speed_mps
    det, ana = _process(point_targets([20.0, 40.0, 60.0], [0.0, 0.0, 0.0], [vmax - 0.3, -vmax + 0.3, vmax + 5.0]),
                        dtype)
    assert abs(_nearest(det, 20.0).range_rate_mps[0] - (vmax - 0.3)) < P.speed_resolution_mps
    assert abs(_nearest(det, 40.0).range_rate_mps[0] - (-vmax + 0.3)) < P.speed_resolution_mps
    # v_max + 5 folds to −v_max + 5
    assert abs(_nearest(det, 60.0).range_rate_mps[0] - (-vmax + 5.0)) < 2 * P.speed_resolution_mps
    assert abs(_nearest(ana, 60.0).range_rate_mps[0] - (-vmax + 5.0)) < 2 * P.speed_resolution_mps


def test_azimuth_at_the_fov_edge_at_85_and_at_90_degrees():
    """The element pattern (two-way cos²θ here) attenuates a target at ±85° by 21 dB, and one at ±90° to nothing.
    At ±85° a λ/2 array is at the edge of its spatial frequency (d·sinθ = ±0.498 of ±0.5): noise may put the
    peak on either side of the wrap, which is why the radar levels report nothing outside the field of view
    (tests/test_ambiguity.py); here the chain alone is checked for what it can promise."""
    az = [60.0, 85.0, -85.0, 90.0, -89.99]
    rng_m = [20.0, 30.0, 40.0, 50.0, 60.0]
    det, ana = _process(point_targets(rng_m, az, [0.0, 2.0, -2.0, 1.0, -1.0], [10.0, 30.0, 30.0, 30.0, 30.0]))
    for d in (det, ana):
        assert abs(math.degrees(_nearest(d, 20.0).azimuth_rad[0]) - 60.0) < 1.0
        for r in (30.0, 40.0):
            near = d.take(np.abs(d.range_m - r) < P.range_resolution_m)
            assert len(near) >= 1 and np.all(np.abs(np.degrees(near.azimuth_rad)) > 75.0)
        for r in (50.0, 60.0):
            assert not np.any(np.abs(d.range_m - r) < P.range_resolution_m)


def test_rcs_from_minus_20_to_plus_40_dbsm_in_one_frame():
    """A −20 dBsm target in its own cell survives next to a +40 dBsm one: a 60 dB near–far spread."""
    scat = point_targets([90.0, 20.0], [0.0, -30.0], [10.0, -5.0], [40.0, -20.0])
    det, ana = _process(scat)
    strong, weak = _nearest(det, 90.0), _nearest(det, 20.0)
    assert abs(strong.range_m[0] - 90.0) < P.range_resolution_m and abs(weak.range_m[0] - 20.0) < P.range_resolution_m
    assert strong.rcs_dbsm[0] - weak.rcs_dbsm[0] == pytest.approx(60.0, abs=3.0)


@pytest.mark.parametrize("snr", [-20.0, 0.0, 30.0, 60.0])
def test_snr_from_minus_20_to_60_db(snr):
    det, _ = _process(point_targets([50.0], [10.0], [5.0]), snr_db=snr)
    processed = snr + 10 * math.log10(256 * 256 * 12)
    if processed > 25:
        hit = _nearest(det, 50.0)
        assert abs(hit.range_m[0] - 50.0) < P.range_resolution_m


@pytest.mark.parametrize("n", [0, 1, 10_000])
def test_zero_one_and_ten_thousand_scatterers(n):
    rng = np.random.default_rng(1)
    if n == 0:
        scat = Scatterers.empty(0)
    else:
        scat = point_targets(rng.uniform(1, 110, n), rng.uniform(-60, 60, n), rng.uniform(-30, 30, n),
                             rng.uniform(-20, 10, n))
    det, ana = _process(scat, np.complex64 if n > 1000 else np.complex128)
    if n == 0:
        assert len(det) == 0 or np.all(det.snr_db < 30)
    if n == 1:
        assert len(det) >= 1


def test_impairments_keep_the_chain_finite_and_the_target():
    from radarnode.radar.options import Impairments
    imp = Impairments(multipath=True, phase_noise_deg=0.5, iq_gain_db=0.5, iq_phase_deg=3.0,
                      channel_gain_sigma_db=0.5, channel_phase_sigma_deg=3.0, adc_bits=10)
    det, _ = _process(point_targets([40.0], [10.0], [5.0], [10.0]), impairments=imp)
    hit = _nearest(det, 40.0)
    assert abs(hit.range_m[0] - 40.0) < P.range_resolution_m
    assert abs(math.degrees(hit.azimuth_rad[0]) - 10.0) < 2.0
