"""DSP building blocks alone: CFAR false-alarm rate, DOA over angles, peak interpolation, DBSCAN, registries."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.dsp.cfar import CFAR_KINDS, make_cfar
from radarnode.dsp.cluster import dbscan
from radarnode.dsp.doa import DOA_METHODS, make_doa
from radarnode.dsp.peaks import interpolate
from radarnode.dsp.spectra import range_doppler, window
from radarnode.errors import ConfigError


@pytest.mark.parametrize("kind", sorted(CFAR_KINDS))
def test_cfar_false_alarm_rate_on_noise(kind):
    pfa = 1e-3
    cfar = make_cfar(kind, pfa=pfa, guard=(1, 1), train=(3, 3))
    rng = np.random.default_rng(0)
    rates = [cfar(rng.exponential(size=(128, 128))).mask.mean() for _ in range(6)]
    assert np.mean(rates) == pytest.approx(pfa, rel=0.25)


@pytest.mark.parametrize("kind", sorted(CFAR_KINDS))
def test_cfar_finds_a_target_and_handles_the_edges(kind):
    cfar = make_cfar(kind, pfa=1e-6)
    power = np.random.default_rng(1).exponential(size=(64, 128))
    power[10, 0] = power[30, 127] = power[50, 64] = 1e3
    mask = cfar(power).mask
    assert mask[10, 0] and mask[30, 127] and mask[50, 64]
    assert mask.sum() <= 4


def test_cfar_and_doa_reject_unknown_names_and_bad_values():
    with pytest.raises(ConfigError, match="cfar kind: value 'xx'"):
        make_cfar("xx")
    with pytest.raises(ConfigError, match="pfa"):
        make_cfar("ca", pfa=0.7)
    with pytest.raises(ConfigError, match="doa method"):
        make_doa("music", 4)
    with pytest.raises(ConfigError, match="window"):
        window("kaiser-bessel", 8)
    with pytest.raises(ConfigError, match="cube: shape"):
        range_doppler(np.zeros((4, 4)))


@pytest.mark.parametrize("method", sorted(DOA_METHODS))
@pytest.mark.parametrize("elements", [4, 12])
@pytest.mark.parametrize("angle_deg", [-60.0, -40.0, -6.34, 0.0, 1.4, 10.0, 30.0, 60.0])
def test_doa_recovers_a_synthetic_source(method, elements, angle_deg):
    doa = make_doa(method, elements, 0.5)
    rng = np.random.default_rng(2)
    k = np.arange(elements)
    snap = np.exp(2j * np.pi * 0.5 * k * math.sin(math.radians(angle_deg)))[None, :] * 10.0
    snap = snap + (rng.standard_normal((1, elements)) + 1j * rng.standard_normal((1, elements))) / math.sqrt(2)
    est = math.degrees(math.asin(doa.estimate(snap)[0]))
    # 3σ of the Cramér–Rao bound at this SNR (20 dB per element)
    rho = 100.0
    crb = 1.0 / (2 * math.pi * 0.5 * math.cos(math.radians(angle_deg))) * math.sqrt(6 / (rho * elements * (elements ** 2 - 1)))
    assert abs(est - angle_deg) <= 3 * math.degrees(crb) + 0.05


def test_doa_finds_two_sources_in_one_cell():
    doa = make_doa("fft", 12, 0.5)
    k = np.arange(12)
    snap = sum(np.exp(2j * np.pi * 0.5 * k * math.sin(math.radians(a))) for a in (-30.0, 30.0))[None, :]
    rows, sin_t, rel = doa.estimate_peaks(snap)
    assert sorted(np.round(np.degrees(np.arcsin(sin_t)), 1).tolist()) == [-30.0, 30.0]


def test_peak_interpolation_is_nearly_unbiased_for_hann():
    n = 256
    w = window("hann", n)
    errs = []
    for true_bin in np.linspace(40.0, 41.0, 11):
        x = np.exp(2j * np.pi * true_bin * np.arange(n) / n) * w
        p = np.abs(np.fft.fft(x)) ** 2
        k = int(np.argmax(p))
        _, dr = interpolate(p[None, :], np.array([0]), np.array([k]))
        errs.append(k + dr[0] - true_bin)
    assert np.max(np.abs(errs)) < 1e-6     # exact for one tone with the Hann ratio estimator


def test_dbscan_groups_chains_and_marks_noise():
    pts = np.array([[0, 0], [0.8, 0], [1.6, 0], [10, 10], [10.5, 10], [30, 30]], dtype=float)
    assert dbscan(pts, 1.0, 2).tolist() == [0, 0, 0, 1, 1, -1]
    assert dbscan(pts, 1.0, 1).tolist() == [0, 0, 0, 1, 1, 2]
    assert dbscan(np.zeros((0, 2)), 1.0).tolist() == []
    with pytest.raises(ConfigError):
        dbscan(pts, 0.0)


def test_ml_range_refinement_reaches_the_cramer_rao_bound():
    from radarnode.dsp.peaks import refine_ml
    n, c = 256, 12
    w = window("hann", n)
    rng = np.random.default_rng(3)
    snr_db = 20.0
    err_ml, err_3 = [], []
    for _ in range(200):
        f = 40.0 + rng.random()
        amp = math.sqrt(10 ** (snr_db / 10) / n / c)
        x = amp * np.exp(2j * np.pi * (f * np.arange(n) / n + rng.random((c, 1))))
        x = x + (rng.standard_normal((c, n)) + 1j * rng.standard_normal((c, n))) / math.sqrt(2)
        spec = np.fft.fft(x * w, axis=1)
        p = (np.abs(spec) ** 2).sum(axis=0)
        k = int(np.argmax(p))
        _, dr = interpolate(p[None, :], np.array([0]), np.array([k]))
        err_3.append(k + dr[0] - f)
        err_ml.append(refine_ml(spec[None], np.array([k + dr[0]]), w)[0] - f)
    crb = math.sqrt(6) / (2 * math.pi * math.sqrt(10 ** (snr_db / 10)))
    rmse_ml = math.sqrt(np.mean(np.square(err_ml)))
    rmse_3 = math.sqrt(np.mean(np.square(err_3)))
    assert rmse_ml < 1.5 * crb < rmse_3
