"""benchmarks/calibration.py's fitted Pd offset: it recovers a known shift of theory's curve from binomial
draws, and the standard error it states is the spread of its estimates."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest

from tests.conftest import ROOT


def _calibration():
    spec = importlib.util.spec_from_file_location("calibration_bench", ROOT / "benchmarks" / "calibration.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _setup(swerling: int):
    """The calibration script, the mimo12 chain's statistic and the Pd tables' grid of ρ for this Swerling case."""
    cal = _calibration()
    top = 24.0 if swerling == 0 else 32.0
    return cal, cal.DspChain(cal.P).statistic, np.arange(12.0, top + 0.01, 1.0)


@pytest.mark.parametrize("swerling, target, shift", [(0, 0.5, 0.3), (0, 0.9, -0.2), (1, 0.5, -0.4), (1, 0.9, 0.35)])
def test_the_fitted_offset_recovers_a_known_shift_with_an_honest_standard_error(swerling, target, shift):
    cal, stat, grid = _setup(swerling)
    samples = 800
    rng = np.random.default_rng(7)
    truth = stat.pd_of_snr(grid - shift, swerling)
    est, ses = [], []
    for _ in range(60):
        pd = rng.binomial(samples, truth) / samples
        d, se, rows = cal.fitted_offset(stat, pd, grid, swerling, target, samples)
        assert rows >= 1
        est.append(d)
        ses.append(se)
    est = np.array(est)
    assert abs(est.mean() - shift) < 4.0 * est.std() / np.sqrt(est.size) + 0.01     # unbiased
    # the stated standard error is the estimates' spread, within a third (60 draws give the spread to ±10 %)
    assert 0.67 < est.std() / np.median(ses) < 1.5
    # and it beats one pair of rows' crossing (snr_at), most of all on Swerling 1's shallow slope near 0.9
    fine = np.arange(0.0, 40.0, 0.01)
    t = cal.snr_at(stat.pd_of_snr(fine, swerling), fine, target)
    cross = np.array([cal.snr_at(rng.binomial(samples, truth) / samples, grid, target) - t for _ in range(60)])
    assert est.std() <= np.nanstd(cross) * 1.1


@pytest.mark.parametrize("swerling, shift", [(0, 0.25), (1, -0.3)])
def test_the_fit_against_the_trials_theory_recovers_a_shift_that_theory_at_the_nominal_snr_would_misread(swerling,
                                                                                                       shift):
    """Trials whose SNR spreads about each row's ρ (±0.5 dB, as the Pd scene's drifting targets): a level that
    draws exactly from them, shifted by a known Δ, is fitted to that Δ against the trials' own theory
    (:class:`TrialTheory`), while the fit against the uniform curve at the nominal ρ reads the spread as a shift too
    (Swerling 0 near Pd 0.9, where the curve bends)."""
    cal, stat, grid = _setup(swerling)
    samples = 3200
    rng = np.random.default_rng(11)
    gain = 10.0 * np.log10(stat.window_gain)
    spread = rng.normal(0.0, 0.5, 400)
    # every trial on its own straddle (uniform in the cell) and SNR: the energies TrialTheory averages over
    u = rng.uniform(-0.5, 0.5, (2, 400))
    straddle = 10.0 * np.log10(stat.energy(1.0, u[0], u[1]) / stat.window_gain)
    energies = [rho + gain + straddle + spread for rho in grid]
    reference = cal.TrialTheory(stat, swerling, energies)
    # on-bin, no spread: the trials' theory is the test's exact Pd
    flat = cal.TrialTheory(stat, swerling, [np.full(4, 20.0 + gain)])
    assert flat(np.zeros(1), [0])[0, 0] == pytest.approx(float(stat.pd(np.array([10.0 ** ((20.0 + gain) / 10.0)]),
                                                                         swerling)[0]), abs=1e-4)
    truth = reference(np.array([shift]), np.arange(grid.size))[0]
    est, naive = [], []
    for _ in range(30):
        pd = rng.binomial(samples, truth) / samples
        est.append(cal.fitted_offset(stat, pd, grid, swerling, 0.9, samples, curve=reference)[0])
        naive.append(cal.fitted_offset(stat, pd, grid, swerling, 0.9, samples)[0])
    est, naive = np.array(est), np.array(naive)
    assert abs(est.mean() - shift) < 4.0 * est.std() / np.sqrt(est.size) + 0.01
    if swerling == 0:           # the spread alone reads as about +0.1 dB more against the nominal ρ
        assert naive.mean() - est.mean() > 0.05
