"""The signal chain's tables, built once per process and shared: the same numbers as built directly, shared by every
fit of the same windows, and read only (benchmarks/first_frame.py times what sharing them saves)."""

from __future__ import annotations

import numpy as np
import pytest

from radarnode.dsp import detection_stats as stats
from radarnode.dsp import peaks
from radarnode.dsp.cfar import CellAveragingCfar
from radarnode.dsp.detection_stats import noise_correlation
from radarnode.dsp.spectra import window


@pytest.mark.parametrize("name, length, half", [("hann", 256, 12), ("hann", 64, 3), ("hamming", 128, 6),
                                                ("blackman", 256, 1), ("np.hanning", 64, 12), ("np.kaiser", 64, 6)])
def test_the_norm_table_is_h_r_inverse_h_computed_directly(name, length, half):
    """h^H R⁻¹ h at the table's grid points against R built from the window's noise correlation and inverted here,
    for every patch size up to the half-width; numpy's symmetric Hann and a Kaiser window are not DFT-even, so their
    noise correlation and R⁻¹ are complex (an independent tester found the table taking R⁻¹'s real part only)."""
    w = {"np.hanning": lambda n: np.hanning(n), "np.kaiser": lambda n: np.kaiser(n, 8.0)}.get(
        name, lambda n: window(name, n))(length)
    axis = peaks._PatchAxis(w, half)
    rho = noise_correlation(w)
    grid = axis._norm_grid[::257]
    h = axis.response(grid)                                                     # (G, 2·half + 1)
    assert np.all(axis._norm[0] == 0.0)
    for m in range(1, half + 1):
        lag = np.arange(-m, m + 1)
        r_inv = np.linalg.inv(rho[(lag[:, None] - lag[None, :]) % length])
        hb = h[:, half - m: half + m + 1]
        direct = np.einsum("gj,jl,gl->g", hb.conj(), r_inv, hb).real
        np.testing.assert_allclose(axis._norm[m, ::257], direct, rtol=1e-9)
        np.testing.assert_allclose(axis.norm(grid[None, :], np.array([m])), direct[None, :], rtol=1e-9)


def test_fits_of_the_same_windows_share_their_axes_and_the_shared_arrays_are_read_only():
    w, other = window("hann", 128), window("hamming", 128)
    a, b = peaks.PatchFit(w, w, 12), peaks.PatchFit(w.copy(), w.copy(), 12)
    mig = peaks.MigrationFit(w, w, 12)
    assert a.axes[12][0] is b.axes[12][0] is mig.axes[12][0] is a.axes[12][1]
    assert peaks.PatchFit(other, w, 12).axes[12][0] is not a.axes[12][0]          # another window: its own
    assert peaks.PatchFit(w, w, 6).axes[6][0] is a.axes[6][0]                      # a bucket of the larger fit
    assert peaks.MigrationFit(w.copy(), w.copy(), 12)._doppler is mig._doppler
    for arr in (a.axes[12][0].inverse, a.axes[12][0].inverse_real, a.axes[12][0]._norm, a.axes[12][0]._mix,
                a.axes[12][0]._den, mig._doppler.value, mig._range.slope, mig.nodes):
        with pytest.raises(ValueError, match="read-only"):
            arr[(0,) * arr.ndim] = 1.0


def test_a_shared_patch_fit_fits_as_a_fit_of_its_own():
    """Two fits of one map, one of them sharing the first's tables, give the same offsets and snapshots; a fit after
    a first one has built the tables, the same as the first."""
    rng = np.random.default_rng(3)
    m = n = 64
    rd = (rng.standard_normal((4, m, n)) + 1j * rng.standard_normal((4, m, n))) * 0.1
    dd, rr = np.meshgrid(np.arange(m) - 20.3, np.arange(n) - 30.6, indexing="ij")
    tone = np.sinc(dd / 2.0) * np.sinc(rr / 2.0)
    rd += 40.0 * tone[None] * np.exp(1j * np.arange(4))[:, None, None]
    w = window("hann", m)
    first = peaks.PatchFit(w, w, 6)(rd, np.array([20]), np.array([31]), np.zeros(1), np.zeros(1))
    again = peaks.PatchFit(w.copy(), w.copy(), 6)(rd, np.array([20]), np.array([31]), np.zeros(1), np.zeros(1))
    for x, y in zip(first, again):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("cut", [(None, None), (0, 10), (3, 10), (10, 0), (10, 5)])
def test_the_memoised_threshold_of_a_cut_ring_is_the_exact_one(cut):
    """α of a ring that the range edges cut, from a CFAR that memoises it, against ca_alpha on that ring's own
    eigenvalues (and the false-alarm probability it gives, the set one)."""
    w = window("hann", 128)
    rho = noise_correlation(w)
    cfar = CellAveragingCfar(pfa=1e-5, guard=(2, 2), train=(4, 10), n_channels=12, correlation=(rho, rho))
    off = cfar.offsets()
    left, right = cut
    if left is not None:
        off = off[(off[:, 1] >= -left) & (off[:, 1] <= right)]
    eig = stats.ring_eigenvalues(off, rho, rho)
    alpha = cfar.alpha_for_cut(left, right)
    assert alpha == stats.ca_alpha(1e-5, 12, eig)
    assert np.exp(stats.ca_log_pfa(alpha, 12, eig)) == pytest.approx(1e-5, rel=1e-9)
    other = CellAveragingCfar(pfa=1e-4, guard=(2, 2), train=(4, 10), n_channels=12, correlation=(rho, rho))
    assert other.alpha_for_cut(left, right) < alpha                                # another Pfa: its own


def test_a_cfar_with_eigenvalues_of_its_own_gets_its_own_thresholds():
    """A subclass that models the ring its own way (here: independent cells) is not given the shared threshold of the
    correlated ring (an independent tester's case)."""
    class Independent(CellAveragingCfar):
        def _eigenvalues(self, offsets):
            return np.ones(len(offsets))

    rho = noise_correlation(window("hann", 64))
    own = Independent(pfa=1e-6, n_channels=4, correlation=(rho, rho))
    shared = CellAveragingCfar(pfa=1e-6, n_channels=4, correlation=(rho, rho))
    assert own.alpha == stats.ca_alpha(1e-6, 4, np.ones(own.n_train))
    assert own.alpha_for_cut(2, 10) == stats.ca_alpha(1e-6, 4, np.ones(int(np.sum(own.offsets()[:, 1] >= -2))))
    assert shared.alpha != own.alpha
