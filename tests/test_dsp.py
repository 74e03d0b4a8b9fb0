"""DSP building blocks alone: CFAR false-alarm rate, DOA over angles, peak interpolation, DBSCAN, registries."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.dsp.cfar import CFAR_KINDS, make_cfar
from radarnode.dsp.cluster import dbscan
from radarnode.dsp.doa import DOA_METHODS, make_doa
from radarnode.dsp.peaks import interpolate
from radarnode.dsp.spectra import noncoherent_power, range_doppler, window
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


@pytest.mark.parametrize("seed", range(12))
def test_os_cfar_detect_gives_the_rank_filters_mask_bit_for_bit(seed):
    # the bounded OS-CFAR (the order statistic only where neither bound settles a cell) against the rank filter
    # over the whole map: noise of 1–12 channels, targets from 0 to 120 dB at random places (range edges and the
    # Doppler wrap included), a band of zeros, rings of several sizes and ranks
    rng = np.random.default_rng(seed)
    ch = int(rng.choice([1, 4, 8, 12]))
    cfar = make_cfar("os", pfa=float(rng.choice([1e-2, 1e-3, 1e-6])), guard=(int(rng.integers(0, 3)), 2),
                     train=(int(rng.integers(1, 6)), int(rng.integers(2, 10))), n_channels=ch)
    m, n = int(rng.choice([8, 64, 128])), int(rng.choice([24, 256]))
    power = rng.gamma(ch, 1.0, (m, n)) * 10.0 ** rng.uniform(-3, 3)
    for _ in range(int(rng.integers(0, 60))):
        d, r = int(rng.integers(0, m)), int(rng.integers(0, n))
        power[d, r] += 10.0 ** rng.uniform(0, 12) * power.mean()
    if seed % 3 == 0:
        power[:, : n // 8] = 0.0
    assert np.array_equal(cfar.detect(power), cfar(power).mask)


def test_ca_cfar_detect_is_its_mask():
    rng = np.random.default_rng(3)
    power = rng.gamma(8, 1.0, (32, 64))
    power[5, 7] += 1e4
    cfar = make_cfar("ca", pfa=1e-3, n_channels=8)
    assert np.array_equal(cfar.detect(power), cfar(power).mask) and cfar.detect(power)[5, 7]


def test_cfar_and_doa_reject_unknown_names_and_bad_values():
    with pytest.raises(ConfigError, match="cfar kind: value 'xx'"):
        make_cfar("xx")
    with pytest.raises(ConfigError, match="pfa"):
        make_cfar("ca", pfa=0.7)
    with pytest.raises(ConfigError, match="doa method"):
        make_doa("maximum_entropy", 4)
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


def test_doa_takes_a_strong_source_out_before_looking_for_another():
    # a 60 dB source's sidelobes (−13 dB) and their noise are no second source; a real second one 1.0
    # beamwidths away, 3 dB weaker, is found on the residual, at its angle
    doa = make_doa("fft", 12, 0.5)
    k = np.arange(12)
    rng = np.random.default_rng(5)
    steer = lambda s: np.exp(2j * np.pi * 0.5 * k * s)
    noise = (rng.standard_normal((200, 12)) + 1j * rng.standard_normal((200, 12))) / math.sqrt(2)
    rows, _, _ = doa.estimate_peaks(1000.0 * steer(0.3)[None, :] + noise, noise_power=1.0)
    assert rows.size == 200
    s2 = 0.3 + 1.0 * 2.0 / 12                           # a beamwidth is 1/K in d·sinθ, d = λ/2
    snap = 100.0 * steer(0.3)[None, :] + 70.0 * np.exp(2j * np.pi * rng.random((200, 1))) * steer(s2)[None, :]
    rows, sin_t, rel = doa.estimate_peaks(snap + noise, noise_power=1.0)
    two = np.bincount(rows, minlength=200) == 2
    assert two.mean() > 0.9
    second = sin_t[np.flatnonzero(np.isin(rows, np.flatnonzero(two)) & (rel < -1.0))]
    assert np.median(np.abs(second - s2)) < 0.02


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



@pytest.mark.parametrize("n, k", [(1, 0), (6, 0), (60, 40), (400, 500), (1500, 4000)])
def test_components_are_scipys_connected_components(n, k):
    """The same partition as scipy's connected_components on random graphs (labels: the smallest node of each)."""
    import scipy.sparse
    import scipy.sparse.csgraph

    from radarnode.dsp.cluster import components
    edges = np.random.default_rng(n + k).integers(0, n, (k, 2))
    _, want = scipy.sparse.csgraph.connected_components(
        scipy.sparse.coo_matrix((np.ones(k), (edges[:, 0], edges[:, 1])), shape=(n, n)), directed=False)
    got = components(n, edges)
    assert len(set(zip(want.tolist(), got.tolist()))) == len(set(want.tolist())) == len(set(got.tolist()))
    assert all(got[i] == i for i in set(got.tolist())) and np.all(got <= np.arange(n))
    # component_labels: scipy's numbering itself (the detection level's lobe groups, which were scipy's until
    # 2026-12-04), self-loops and duplicate edges included
    from radarnode.dsp.cluster import component_labels
    np.testing.assert_array_equal(component_labels(n, edges), want)


@pytest.mark.parametrize("order", ["random", "near and far alternating", "sorted", "reversed"])
def test_components_of_a_long_chain_in_any_order_settle_to_one_label(order):
    """A row of 100,000 posts numbered in any order is one component (in about log₂ n passes: an earlier version
    propagated labels one edge a pass and took 44 s on a randomly numbered chain of this length; the time is
    benchmarked, not asserted here)."""
    from radarnode.dsp.cluster import components
    n = 100_000
    perm = {"random": np.random.default_rng(2).permutation(n),
            "near and far alternating": np.concatenate([np.arange(0, n, 2), np.arange(1, n, 2)[::-1]]),
            "sorted": np.arange(n), "reversed": np.arange(n)[::-1]}[order]
    assert np.all(components(n, np.stack([perm[:-1], perm[1:]], axis=1)) == 0)
    assert components(3, np.zeros((0, 2), dtype=np.int64)).tolist() == [0, 1, 2]
    assert components(4, np.array([[2, 2], [3, 1], [1, 3]])).tolist() == [0, 1, 2, 1]   # self-loop, duplicates

def _tone_map(m, n, xd, xr, amp, rng=None, noise=1.0):
    """Windowed range–Doppler spectra (channel, doppler, range) of one tone at (xd, xr) bins, Doppler unshifted."""
    t_d, t_r = np.arange(m), np.arange(n)
    x = amp[:, None, None] * np.exp(2j * np.pi * xd * t_d / m)[None, :, None] * np.exp(2j * np.pi * xr * t_r / n)
    if rng is not None:
        x = x + (rng.standard_normal(x.shape) + 1j * rng.standard_normal(x.shape)) * math.sqrt(noise / 2)
    x = x * window("hann", m)[None, :, None] * window("hann", n)[None, None, :]
    return np.fft.fft(np.fft.fft(x, axis=2), axis=1)


def _rmse_over_crb(errors, rho):
    """RMSE of (Doppler, range) errors in bins over the CRB of one tone's frequency, √6/(2π√ρ) bins."""
    return np.sqrt(np.mean(np.square(errors), axis=0)) / (math.sqrt(6) / (2 * math.pi * math.sqrt(rho)))


def _strongest_cell(rd, lo, hi):
    """The non-coherent power map of ``rd`` and its strongest cell within [lo, hi) on both axes, as (1,) arrays."""
    p = (np.abs(rd) ** 2).sum(axis=0)
    sub = p[lo:hi, lo:hi]
    d, r = np.unravel_index(np.argmax(sub), sub.shape)
    return p, np.array([d + lo]), np.array([r + lo])


@pytest.mark.parametrize("xd, xr", [(10.3, 20.0), (20.5, 7.25), (0.2, 63.6), (31.0, 0.5)])
def test_patch_fit_is_exact_without_noise_and_keeps_the_channel_phases(xd, xr):
    from radarnode.dsp.peaks import PatchFit
    m = n = 64
    amp = np.exp(2j * np.pi * np.array([0.0, 0.1, 0.37, 0.8]))
    rd = _tone_map(m, n, xd, xr, amp)
    d, r = np.array([int(np.rint(xd)) % m]), np.array([int(np.rint(xr)) % n])
    fit = PatchFit(window("hann", m), window("hann", n), 12)
    fd, fr, snap = fit(rd, d, r, np.zeros(1), np.zeros(1))
    # circular axes: a tone at 63.6 sits 0.4 bin below bin 0
    assert (d + fd)[0] == pytest.approx(xd, abs=1e-4)
    assert (r + fr - xr + n / 2) % n - n / 2 == pytest.approx(0.0, abs=1e-4)
    rel = snap[0] / snap[0, 0]
    assert np.allclose(rel, amp / amp[0], atol=1e-9)


def test_patch_fit_reaches_the_cramer_rao_bound_where_the_interpolator_does_not():
    from radarnode.dsp.peaks import PatchFit
    m = n = 64
    c, rho_db = 4, 30.0
    rho = 10 ** (rho_db / 10)
    rng = np.random.default_rng(3)
    fit = PatchFit(window("hann", m), window("hann", n), 12)
    err_fit, err_3 = [], []
    for _ in range(300):
        xd, xr = 30.0 + rng.random(), 30.0 + rng.random()
        amp = np.exp(2j * np.pi * rng.random(c))                   # unit amplitude: ρ = m·n·c / noise
        rd = _tone_map(m, n, xd, xr, amp, rng, noise=m * n * c / rho)
        p, d, r = _strongest_cell(rd, 28, 34)
        dd, dr = interpolate(p, d, r)
        fd, fr, _ = fit(rd, d, r, dd, dr)
        err_fit.append(((d + fd)[0] - xd, (r + fr)[0] - xr))
        err_3.append(((d + dd)[0] - xd, (r + dr)[0] - xr))
    rmse_fit, rmse_3 = _rmse_over_crb(err_fit, rho), _rmse_over_crb(err_3, rho)
    assert np.all(rmse_fit < 1.3) and np.all(rmse_3 > 1.5), (rmse_fit, rmse_3)


@pytest.mark.parametrize("rho_db", [60.0, 80.0])
def test_patch_fit_stays_at_the_cramer_rao_bound_at_high_snr(rho_db):
    """At 60–80 dB the bound is 4e-4–4e-5 bin: what the searches' last parabola leaves on a noise-free tone must lie
    well below it (a last grid step of 1/32 bin left 7e-5 bin: 1.7× the bound at 80 dB)."""
    from radarnode.dsp.peaks import PatchFit
    m = n = 64
    c, rho = 4, 10 ** (rho_db / 10)
    rng = np.random.default_rng(3)
    fit = PatchFit(window("hann", m), window("hann", n), 12)
    err, still = [], []
    for _ in range(150):
        xd, xr = 30.0 + rng.random(), 30.0 + rng.random()
        amp = np.exp(2j * np.pi * rng.random(c))
        for noise, out in ((m * n * c / rho, err), (0.0, still)):
            rd = _tone_map(m, n, xd, xr, amp, rng if noise else None, noise=noise)
            p, d, r = _strongest_cell(rd, 28, 34)
            dd, dr = interpolate(p, d, r)
            fd, fr, _ = fit(rd, d, r, dd, dr)
            out.append(((d + fd)[0] - xd, (r + fr)[0] - xr))
    assert np.max(np.abs(still)) < 2e-5
    rmse = _rmse_over_crb(err, rho)
    assert np.all(rmse < 1.25), rmse


def test_patch_stops_short_of_the_next_peak():
    from radarnode.dsp.peaks import patch_halves
    d = np.array([10, 10, 100, 0, 0])
    r = np.array([10, 15, 100, 254, 2])
    half = patch_halves(d, r, np.arange(5), (128, 256), 8)
    # 5 bins to the next peak: 2; alone: 8; range bins 254 and 2 are 4 apart across the wrap: 1
    assert half.tolist() == [2, 2, 8, 1, 1]


def test_patch_fit_of_several_peaks_at_once_equals_one_at_a_time():
    from radarnode.dsp.peaks import PatchFit
    m = n = 64
    rng = np.random.default_rng(8)
    amp = np.exp(2j * np.pi * rng.random(3))
    rd = sum(_tone_map(m, n, xd, xr, amp * a) for xd, xr, a in ((10.3, 20.2, 1.0), (40.6, 45.1, 0.5), (12.0, 50.7, 2.0)))
    rd = rd + _tone_map(m, n, 0.0, 0.0, np.zeros(3), rng, noise=1.0)
    d, r = np.array([10, 41, 12]), np.array([20, 45, 51])
    half = np.array([12, 3, 12])
    fit = PatchFit(window("hann", m), window("hann", n), 12)
    together = fit(rd, d, r, np.zeros(3), np.zeros(3), half)
    for i in range(3):
        alone = fit(rd, d[i:i + 1], r[i:i + 1], np.zeros(1), np.zeros(1), half[i:i + 1])
        for a, b in zip(together, alone):
            assert np.allclose(a[i], b[0], rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("few, joined", [(17, True), (18, False), (36, False)])
def test_a_small_bucket_joins_the_next_larger_call_only_where_that_is_cheaper(few, joined):
    """A call costs call_cells patch cells; a peak of bucket 6 costs 13² = 169 of them there and 25² = 625 in bucket
    12: ``few`` such peaks join the call of bucket 12 while few·456 < call_cells (456·17.5 here: 17 just below, 18
    just above, 36 twice the edge). The buckets that hold nothing or run alone are left alone."""
    from radarnode.dsp.peaks import _call_buckets
    buckets = (3, 6, 12)
    halves = np.array([5] * few + [12] * 4 + [2] * 200)
    got = _call_buckets(buckets, halves, 456 * 17.5)
    assert set(got[:few].tolist()) == {12 if joined else 6}
    assert set(got[few:few + 4].tolist()) == {12}
    assert set(got[few + 4:].tolist()) == {3}          # 200 peaks of 49 cells would cost 115,200 more in bucket 6
    assert _call_buckets(buckets, halves, 0.0).tolist() == [6] * few + [12] * 4 + [3] * 200   # 0: no joining
    assert _call_buckets(buckets, np.array([1, 2, 3]), 1e9).tolist() == [3, 3, 3]       # one bucket: as it is
    # a bucket two sizes down joins the largest when the middle one holds nothing
    assert _call_buckets(buckets, np.array([1, 12, 12]), 1e9).tolist() == [12, 12, 12]
    assert _call_buckets(buckets, halves, math.inf).tolist() == [12] * (few + 204)          # inf: one call
    for bad in (math.nan, -1.0, "8000"):
        with pytest.raises(ValueError, match="call_cells"):
            _call_buckets(buckets, halves, bad)


@pytest.mark.parametrize("cls", ["PatchFit", "MigrationFit"])
def test_joining_buckets_changes_no_fit(cls, monkeypatch):
    """A patch is exact in a larger bucket (R⁻¹ is zero outside its own cells): the fits with the buckets joined
    (call_cells huge) and each in its own call (0) agree to rounding, peaks of half-widths 2, 5 and 12 together."""
    from radarnode.dsp import peaks
    m = n = 64
    rng = np.random.default_rng(11)
    amp = np.exp(2j * np.pi * rng.random(3))
    tones = ((10.3, 20.2, 1.0), (40.6, 45.1, 0.5), (12.0, 50.7, 2.0), (30.4, 8.8, 1.5))
    rd = sum(_tone_map(m, n, xd, xr, amp * a) for xd, xr, a in tones)
    rd = rd + _tone_map(m, n, 0.0, 0.0, np.zeros(3), rng, noise=1.0)
    d, r = np.array([10, 41, 12, 30]), np.array([20, 45, 51, 9])
    half = np.array([12, 2, 5, 2])
    start = rng.uniform(-0.3, 0.3, (2, 4))
    fit = getattr(peaks, cls)(window("hann", m), window("hann", n), 12)
    extra = (np.full(4, 0.8),) if cls == "MigrationFit" else ()
    got = {}
    for cells in (0.0, 1e12):
        monkeypatch.setattr(type(fit), "CALL_CELLS", cells)
        assert len(set(peaks._call_buckets(fit.buckets, half, cells).tolist())) == (3 if cells == 0 else 1)
        got[cells] = fit(rd, d, r, *start, *extra, half)
    for a, b in zip(got[0.0], got[1e12]):
        np.testing.assert_allclose(a, b, rtol=1e-9, atol=1e-11)


@pytest.mark.parametrize("dtype", [np.complex64, np.complex128])
@pytest.mark.parametrize("shape", [(12, 256, 256), (1, 8, 6), (3, 1, 1), (72, 16, 64)])
def test_noncoherent_power_is_the_sum_over_channels_of_real_and_imaginary_squares(dtype, shape):
    """The power map read from the map's memory as reals gives the formula's values bit for bit, for every layout
    (strided and Fortran-ordered maps too), spans of 10^±30 and an overflow to inf; a real map is taken as it is."""
    rng = np.random.default_rng(sum(shape))
    rd = ((rng.standard_normal(shape) + 1j * rng.standard_normal(shape))
          * 10.0 ** rng.uniform(-30, 30, shape)).astype(dtype)
    for x in (rd, rd[:, ::2, :], rd[:, :, ::-1], np.asfortranarray(rd)):
        want = np.einsum("cdr,cdr->dr", x.real, x.real) + np.einsum("cdr,cdr->dr", x.imag, x.imag)
        with np.errstate(over="ignore"):
            got = noncoherent_power(x)
        assert got.dtype == want.dtype and got.shape == want.shape
        np.testing.assert_array_equal(got, want)
    real = rng.standard_normal(shape)
    np.testing.assert_array_equal(noncoherent_power(real), np.einsum("cdr,cdr->dr", real, real))


@pytest.mark.parametrize("name", ["hann", "hamming", "blackman", "boxcar", "blackmanharris"])
@pytest.mark.parametrize("n", [8, 255, 256])
def test_windows_are_scipys_dft_even_windows(name, n):
    import scipy.signal
    assert np.allclose(window(name, n), scipy.signal.get_window(name, n, fftbins=True), rtol=0, atol=1e-14)


def _migrating_map(m, n, xd, xr, mu, amp, rng=None, noise=1.0):
    """Windowed range–Doppler spectra of one target whose beat moves μ bins over the frame: chirp k sees it at
    xr + μ·(k − m/2)/m; xd is its Doppler at each chirp's first sample (computed directly, sample by sample)."""
    t_d, t_r = np.arange(m), np.arange(n)
    beat = xr + mu * (t_d - m / 2) / m
    x = amp[:, None, None] * np.exp(2j * np.pi * (xd * t_d[:, None] / m + beat[:, None] * t_r[None, :] / n))[None]
    if rng is not None:
        x = x + (rng.standard_normal(x.shape) + 1j * rng.standard_normal(x.shape)) * math.sqrt(noise / 2)
    x = x * window("hann", m)[None, :, None] * window("hann", n)[None, None, :]
    return np.fft.fft(np.fft.fft(x, axis=2), axis=1)


@pytest.mark.parametrize("xd, xr, mu", [(10.3, 20.0, 0.0), (20.5, 7.25, 1.2), (30.2, 40.6, -1.5), (5.0, 33.5, 3.0)])
def test_migration_fit_is_exact_without_noise(xd, xr, mu):
    """The migrating-target fit recovers a moving tone's offsets (Doppler at mid-chirp, sample N/2, where the chain
    takes λ: the first sample's plus μ/2) and its channel phases; at μ = 0 it is the separable patch fit."""
    from radarnode.dsp.peaks import MigrationFit, PatchFit
    m = n = 64
    amp = np.exp(2j * np.pi * np.array([0.0, 0.1, 0.37, 0.8]))
    rd = _migrating_map(m, n, xd, xr, mu, amp)
    p = (np.abs(rd) ** 2).sum(axis=0)
    d, r = (np.array([i]) for i in np.unravel_index(np.argmax(p), p.shape))
    # from the separable fit's estimate, as the chain starts it
    sd, sr, ssnap = PatchFit(window("hann", m), window("hann", n), 12)(rd, d, r, np.zeros(1), np.zeros(1))
    fd, fr, snap = MigrationFit(window("hann", m), window("hann", n), 12)(rd, d, r, sd, sr, np.array([mu]))
    assert (d + fd)[0] == pytest.approx(xd + mu / 2, abs=2e-4)
    assert (r + fr)[0] == pytest.approx(xr, abs=2e-4)
    assert np.allclose(snap[0] / snap[0, 0], amp / amp[0], atol=1e-6)
    if mu == 0.0:
        assert fd[0] == pytest.approx(sd[0], abs=2e-5) and fr[0] == pytest.approx(sr[0], abs=2e-5)
        # (the same amplitudes; the common phase of a template is arbitrary in both)
        assert np.allclose(np.abs(snap), np.abs(ssnap), rtol=1e-4)


def test_migration_fit_reaches_the_cramer_rao_bound_where_the_separable_fit_does_not():
    """A tone moving 1.5 bins over the frame, ρ = 20 dB: the separable fit's model is wrong and its errors grow;
    the migrating fit's stay near the bound (against the same closed-form CRB as the separable fit's test)."""
    from radarnode.dsp.peaks import MigrationFit, PatchFit
    m = n = 64
    c, rho_db, mu = 4, 20.0, 1.5
    rho = 10 ** (rho_db / 10)
    rng = np.random.default_rng(5)
    sep = PatchFit(window("hann", m), window("hann", n), 12)
    mig = MigrationFit(window("hann", m), window("hann", n), 12)
    err_sep, err_mig = [], []
    for _ in range(200):
        xd, xr = 30.0 + rng.random(), 30.0 + rng.random()
        amp = np.exp(2j * np.pi * rng.random(c))
        rd = _migrating_map(m, n, xd, xr, mu, amp, rng, noise=m * n * c / rho)
        p, d, r = _strongest_cell(rd, 28, 35)
        dd, dr = interpolate(p, d, r)
        fd, fr, s = sep(rd, d, r, dd, dr)
        gd, gr, _ = mig(rd, d, r, fd, fr, np.array([mu]), channels=s)
        truth_d = xd + mu / 2
        err_sep.append(((d + fd)[0] - truth_d, (r + fr)[0] - xr))
        err_mig.append(((d + gd)[0] - truth_d, (r + gr)[0] - xr))
    rmse_sep, rmse_mig = _rmse_over_crb(err_sep, rho), _rmse_over_crb(err_mig, rho)
    assert np.all(rmse_mig < 1.3) and np.any(rmse_sep > 1.5), (rmse_mig, rmse_sep)


@pytest.mark.parametrize("mu, other", [(1.2, -2.9), (-1.5, 1.5), (3.0, 0.3), (0.0, np.nan)])
def test_migration_fit_chooses_the_candidate_migration_that_explains_the_patch(mu, other):
    """Two candidate migrations a peak (the chain's two alias numbers of one TDM wrap), in either order, NaN for
    none: the fit takes the true one and recovers the tone as if it had been given that one alone."""
    from radarnode.dsp.peaks import MigrationFit, PatchFit
    m = n = 64
    amp = np.exp(2j * np.pi * np.array([0.0, 0.3, 0.55]))
    rd = _migrating_map(m, n, 20.4, 30.3, mu, amp)
    p = (np.abs(rd) ** 2).sum(axis=0)
    d, r = (np.array([i]) for i in np.unravel_index(np.argmax(p), p.shape))
    sd, sr, snap = PatchFit(window("hann", m), window("hann", n), 12)(rd, d, r, np.zeros(1), np.zeros(1))
    fit = MigrationFit(window("hann", m), window("hann", n), 12)
    alone = fit(rd, d, r, sd, sr, np.array([mu]), channels=snap)
    for cand in ([[mu, other]], [[other, mu]]):
        both = fit(rd, d, r, sd, sr, np.array(cand), channels=snap)
        assert both[0][0] == pytest.approx(alone[0][0], abs=1e-12) and both[1][0] == pytest.approx(alone[1][0], abs=1e-12)
    assert (d + alone[0])[0] == pytest.approx(20.4 + mu / 2, abs=2e-4)
    assert (r + alone[1])[0] == pytest.approx(30.3, abs=2e-4)


def test_migration_fit_refuses_a_peak_without_a_candidate():
    from radarnode.dsp.peaks import MigrationFit
    m = n = 64
    rd = _migrating_map(m, n, 30.2, 20.4, 0.0, np.ones(2))
    fit = MigrationFit(window("hann", m), window("hann", n), 12)
    with pytest.raises(ValueError, match="NaN for none, at least one a row"):
        fit(rd, np.array([30, 31]), np.array([20, 20]), np.zeros(2), np.zeros(2), np.array([[0.5, np.nan], [np.nan] * 2]))


@pytest.mark.parametrize("mu, xd, xr, start", [(3.0, 30.2, 20.6, (0.3, -0.3)), (3.0, 30.2, 20.6, (-0.45, 0.4)),
                                                (3.0, 30.2, 20.6, (0.0, 0.0)), (0.0, 30.7414, 30.6744, (0.0, -0.5)),
                                                (0.0, 30.6524, 30.2345, (-0.3, 0.0)), (0.3, 30.5, 30.5, (0.0, -0.3)),
                                                (3.0, 30.2807, 30.7377, (0.7, 0.7)), (0.0, 30.858, 30.8288, (0.9, 0.0)),
                                                (-3.0, 30.6, 30.2, (0.0, 0.65))])
def test_migration_fit_climbs_from_far_off_the_optimum(mu, xd, xr, start):
    """Newton steps on the 3 × 3 grid follow the likelihood's ridge across both axes: from 0.3–0.9 bin off (at
    3 bins of migration the still fit starts up to 0.9 bin off at ρ = 20 dB), with 0–3 bins of migration, the fit
    reaches the noise-free tone within 2e-4 bin (the alternate one-axis searches it replaced stopped 8e-4 bin short
    from the second start, 0.1 from the fourth and 0.46–0.66 from the seventh and eighth; versions that made the grid
    8× finer after a step that went down, or kept it at 1/16 bin far from the peak, stopped 2–4e-4 and 0.14–0.40
    short: an independent tester's cases)."""
    from radarnode.dsp.peaks import MigrationFit
    m = n = 64
    rd = _migrating_map(m, n, xd, xr, mu, np.exp(2j * np.pi * np.array([0.0, 0.4])))
    mid = xd + mu / 2                  # the Doppler at mid-chirp
    d, r = np.array([int(np.rint(mid))]), np.array([int(np.rint(xr))])
    truth_d, truth_r = mid - d[0], xr - r[0]
    fd, fr, _ = MigrationFit(window("hann", m), window("hann", n), 12)(
        rd, d, r, np.array([truth_d + start[0]]), np.array([truth_r + start[1]]), np.array([mu]))
    assert fd[0] == pytest.approx(truth_d, abs=2e-4) and fr[0] == pytest.approx(truth_r, abs=2e-4)


@pytest.mark.parametrize("half", [1, 2, 12])
def test_migration_fit_never_ends_less_likely_than_it_started(half):
    """At ρ = 10 dB the likelihood has several peaks and a Newton step on its local quadratic can go down (in the
    highway frame at 70 m/s, 8 % of the steps did): such a step is taken back and the grid made finer, so the
    answer is at least as likely as the start. Searched, as the chain does, on the patch along the still fit's
    channel vector u: the likelihood at the answer is |u^H s|² (s the snapshot; with no steps, at the start)."""
    from radarnode.dsp.peaks import MigrationFit, PatchFit
    m = n = 64
    rng = np.random.default_rng(11)
    fit = MigrationFit(window("hann", m), window("hann", n), 12)
    still = MigrationFit(window("hann", m), window("hann", n), 12)
    still.NEWTON_ITERATIONS = 0
    sep = PatchFit(window("hann", m), window("hann", n), 12)
    d, r, hw = np.array([31]), np.array([30]), np.array([half])
    for _ in range(40):
        mu = rng.choice([-3.0, -2.0, -1.2, 1.2, 2.0, 3.0])
        rd = _migrating_map(m, n, 30.0 + rng.random(), 30.0 + rng.random(), mu, np.exp(2j * np.pi * rng.random(4)),
                            rng, noise=m * n * 4 / 10.0)
        sd, sr, u = sep(rd, d, r, np.zeros(1), np.zeros(1), hw)
        un = u[0] / np.linalg.norm(u[0])
        end = abs(un.conj() @ fit(rd, d, r, sd, sr, np.array([mu]), hw, channels=u)[2][0]) ** 2
        start = abs(un.conj() @ still(rd, d, r, sd, sr, np.array([mu]), hw, channels=u)[2][0]) ** 2
        assert end >= start * (1.0 - 1e-12), (mu, start, end)


def test_the_fits_say_which_argument_is_wrong():
    """NaN offsets, a half-width that is not an integer, channel vectors of the wrong length, a patch longer than
    the map, a table read beyond its reach: a ValueError that names the argument (an IndexError, a matmul error,
    a LinAlgError "Singular" or a value a bin off before). A zero channel vector leaves the start as it is."""
    from radarnode.dsp.peaks import MigrationFit, PatchFit, _ShiftTable, _tone_table
    m = n = 64
    rd = _migrating_map(m, n, 30.2, 20.4, 0.0, np.ones(2))
    fit, sep = MigrationFit(window("hann", m), window("hann", n), 12), PatchFit(window("hann", m), window("hann", n))
    one, z = np.array([30]), np.zeros(1)
    for call in (lambda: fit(rd, one, np.array([20]), np.array([np.nan]), z, np.array([0.5])),
                 lambda: sep(rd, one, np.array([20]), z, np.array([np.inf]))):
        with pytest.raises(ValueError, match="delta_d, delta_r: NaN or infinite"):
            call()
    with pytest.raises(ValueError, match=r"half: values \[2.5\] are not allowed; expected integers"):
        fit(rd, one, np.array([20]), z, z, np.array([0.5]), np.array([2.5]))
    with pytest.raises(ValueError, match=r"channels: shape \(1, 3\) is not allowed; expected \(1, 2\)"):
        fit(rd, one, np.array([20]), z, z, np.array([0.5]), channels=np.ones((1, 3)))
    for cls in (MigrationFit, PatchFit):
        cls(window("hann", 63), window("hann", 64), 31)                   # at the limit: a 63-cell patch
        for half, said in ((32, " for a map of 64 × 64 bins; expected at most 31"),      # just above it
                           (62, "; expected an integer in 1…32")):                         # twice it
            with pytest.raises(ValueError, match=f"max_half: value {half} is not allowed{said}"):
                cls(window("hann", m), window("hann", n), half)
        with pytest.raises(ValueError, match="max_half: value 31 is not allowed for a map of 61 × 64 bins; expected "
                                             "at most 30"):
            cls(window("hann", 61), window("hann", 64), 31)                # the shorter axis sets it
    fd, fr, _ = fit(rd, one, np.array([20]), np.array([0.3]), np.array([-0.2]), np.array([0.5]),
                    channels=np.zeros((1, 2)))
    assert (fd[0], fr[0]) == (0.3, -0.2)
    table, start = _tone_table(window("hann", 64), 3.2, 10)
    st = _ShiftTable(table, start, 10)
    st.read(np.array([start]), 4)
    for u in (start - 0.05, -start, np.nan):
        with pytest.raises(ValueError, match="u: values from .* are allowed for windows of 4"):
            st.read(np.array([u]), 4)


def test_shift_table_reads_what_a_pointwise_interpolation_reads():
    """A window of J values of a tabulated tone at u, u + 1, …: the same numbers as interpolating each alone."""
    from radarnode.dsp.peaks import _ShiftTable, _tone_table
    table, start = _tone_table(window("hann", 64), 15.0, 256)
    multi = np.stack([table, 2.0 * table], axis=1)
    rng = np.random.default_rng(3)
    u = rng.uniform(-14.0, 14.0 - 9, size=(4, 3))
    for tab, extra in ((table, ()), (multi, (2,))):
        got = _ShiftTable(tab, start, 256).read(u, 9)                         # (4, 3, [2,] 9)
        assert got.shape == (4, 3) + extra + (9,)
        for j in range(9):
            pos = (u + j - start) * 256
            i0 = np.floor(pos).astype(int)
            frac = (pos - i0).reshape(pos.shape + (1,) * len(extra))
            want = tab[i0] + frac * (tab[i0 + 1] - tab[i0])
            assert np.allclose(got[..., j], want, rtol=0, atol=1e-12 * np.abs(table).max())


@pytest.mark.parametrize("mu, ok", [(2.9, True), (3.0, True), (3.1, False), (6.0, False), (-3.1, False)])
def test_migration_fit_takes_migrations_up_to_its_limit_and_refuses_beyond(mu, ok):
    """MAX_MIGRATION = 3 bins (the Chebyshev response's error there: 1.3e-3 of its norm): below and at it a fit,
    above it and at twice it an error that says the limit."""
    from radarnode.dsp.peaks import MigrationFit
    m = n = 64
    rd = _migrating_map(m, n, 30.2, 20.4, 0.0, np.ones(2))
    fit = MigrationFit(window("hann", m), window("hann", n), 12)
    args = (rd, np.array([30]), np.array([20]), np.zeros(1), np.zeros(1), np.array([mu]))
    if ok:
        assert np.all(np.isfinite(fit(*args)[2]))
    else:
        with pytest.raises(ValueError, match="within ±3"):
            fit(*args)


def test_the_sidelobe_envelope_is_the_hann_spectrums_worst_case_leak():
    """sidelobe_envelope against the closed form of a long Hann window's spectrum, |W(u)| ∝ |sinc u / (1 − u²)|:
    the worst over a tone's offset f ∈ [−½, ½] of |W(e + f)|² / |W(f)|², within 0.1 dB at 2–12 bins."""
    from radarnode.dsp.peaks import sidelobe_envelope
    env = sidelobe_envelope(window("hann", 4096))
    f = np.linspace(-0.5, 0.5, 2001)

    def w2(u):
        with np.errstate(divide="ignore", invalid="ignore"):
            out = (np.sinc(u) / (1.0 - u ** 2)) ** 2
        return np.where(np.isclose(np.abs(u), 1.0), 0.25, out)       # the limit at |u| = 1

    for e in range(2, 13):
        tail = max(np.max(w2(k + f) / w2(f)) for k in range(e, 40))     # non-increasing: the worst from e on
        assert abs(10 * np.log10(env[e] / tail)) < 0.1, (e, 10 * np.log10(env[e]), 10 * np.log10(tail))
    assert env[0] == 1.0 and np.all(np.diff(env) <= 0)


def test_a_loud_peaks_leak_reaches_the_patches_it_should():
    """PatchFit.leak_reach counts the distances at which power × envelope reaches the level; reached() compares each
    patch's nearest cell (distance less half-width, Chebyshev, circular) with the other peaks' reach."""
    from radarnode.dsp.peaks import PatchFit, reached
    fit = PatchFit(window("hann", 64), window("hann", 128), 6)
    reach = fit.leak_reach(np.array([1e6, 1.0, 0.5]), 0.99)
    assert reach[0] == np.sum(fit.envelope * 1e6 >= 0.99) and reach[0] > 3
    assert reach[1] == 2 and reach[2] == 0           # the envelope is 1 at 0 and 1 bin (a tone half a bin off)
    d, r = np.array([0, 0, 10, 32]), np.array([0, 10, 126, 64])
    # from peak 0: 10 bins to peaks 1 and 2 (2 in range across the map's edge), 64 to peak 3
    got = reached(d, r, np.arange(4), (64, 128), np.full(4, 3), np.array([8, 0, 0, 0]))
    assert got.tolist() == [False, True, True, False]      # 10 − 3 = 7 < 8 for peaks 1 and 2; 61 ≥ 8 for peak 3


@pytest.mark.parametrize("period", [256.0, 64, 7.5, 3.0, 1.0, 0.125, 1e6])
@pytest.mark.parametrize("dtype", [np.float64, np.float32, np.int64])
def test_circular_is_the_remainder_formula_bit_for_bit(period, dtype):
    """spectra.circular takes numpy's remainder only where x + period/2 lies outside [0, period): the same values,
    signs and dtype as np.mod(x + period/2, period) − period/2 for offsets mostly inside, mostly outside, at the
    edges, ±0, NaN, ±inf, huge, tiny and integer, in arrays below and above its small-array cut and of two dimensions."""
    from radarnode.dsp.spectra import circular

    def formula(x):
        with np.errstate(invalid="ignore"):
            return np.mod(x + period / 2.0, period) - period / 2.0

    rng = np.random.default_rng(7)
    p = float(period)
    edges = np.array([-p / 2, p / 2, 0.0, -0.0, p, -p, np.nextafter(p / 2, 0), np.nextafter(-p / 2, 0),
                      np.nextafter(-p / 2, -p), 1e300, -1e300, 5e-324, np.nan, np.inf, -np.inf])
    cases = [rng.normal(0, p / 4, 5000), rng.normal(0, 3 * p, 5000), rng.uniform(-p / 2, p / 2, 5000),
             rng.normal(0, p / 4, 63), rng.normal(0, p / 4, 64), np.tile(edges, 9), rng.normal(0, p, (3, 70))]
    for x in cases:
        if np.dtype(dtype).kind == "i":
            x = np.nan_to_num(np.clip(x, -1e9, 1e9), nan=0.0)
        x = x.astype(dtype)
        want = formula(x)
        with np.errstate(invalid="ignore"):
            got = circular(x, period)
        assert got.dtype == want.dtype and got.shape == want.shape
        assert np.array_equal(got, want, equal_nan=True)
        assert np.array_equal(np.signbit(got), np.signbit(want))
    assert circular(3.0, period) == formula(3.0)


@pytest.mark.parametrize("mu", [0.0, 0.3, 1.2, -2.0, 3.0])
@pytest.mark.parametrize("fd, fr", [(0.0, 0.0), (0.3, -0.4), (-0.5, 0.5)])
def test_migration_peak_gain_is_the_peak_cell_of_the_migrating_tone_s_windowed_ffts(mu, fd, fr):
    """MigrationFit.peak_gain against the windowed FFTs of the migrating tone computed sample by sample (its
    Doppler at mid-chirp, as the chain and the fit define it): the power of the cell the tone lands in over a still
    tone's at the same offsets, within 0.005 dB (the Chebyshev tables' error at 3 bins is about 1e-3 of the norm)."""
    from radarnode.dsp.peaks import MigrationFit
    m = n = 128
    wd, wr = window("hann", m), window("hann", n)
    chirp, sample = np.arange(m)[:, None], np.arange(n)[None, :]

    def cell_power(mu_):
        beat = 40.0 + fr + mu_ * (chirp - m / 2) / m
        x = np.exp(2j * np.pi * ((fd - mu_ / 2) * chirp / m + beat * sample / n))
        spec = np.fft.fft(np.fft.fft(x * wr[None, :], axis=1) * wd[:, None], axis=0)
        return abs(spec[0, 40]) ** 2

    want = 10 * np.log10(cell_power(mu) / cell_power(0.0))
    got = 10 * np.log10(MigrationFit(wd, wr, 12).peak_gain(np.array([fd]), np.array([fr]), np.array([mu]))[0])
    assert got == pytest.approx(want, abs=0.005)
    if mu == 0.0:
        assert got == pytest.approx(0.0, abs=1e-12)


def test_migration_fit_refuses_a_chosen_array_of_the_wrong_shape():
    """``chosen`` (the output array of the migration each peak was fitted with) must hold one value a peak."""
    from radarnode.dsp.peaks import MigrationFit
    m = n = 64
    rd = np.zeros((2, m, n), dtype=np.complex128)
    rd[:, 20, 30] = 1.0
    fit = MigrationFit(window("hann", m), window("hann", n), 12)
    with pytest.raises(ValueError, match=r"chosen: shape \(3,\) is not allowed; expected \(1,\)"):
        fit(rd, np.array([20]), np.array([30]), np.zeros(1), np.zeros(1), np.array([1.0]), chosen=np.zeros(3))
    got = np.full(1, np.nan)
    fit(rd, np.array([20]), np.array([30]), np.zeros(1), np.zeros(1), np.array([[1.0, -2.0]]), chosen=got)
    assert got[0] in (1.0, -2.0)


@pytest.mark.parametrize("n_el, n_fft", [(1, 1), (4, 256), (12, 256), (72, 2048)])
def test_the_beamformers_steering_table_is_the_exponential_it_replaces_bit_for_bit(n_el, n_fft):
    """``_steering_table`` (made once) against e^{2πi·k·b/n_fft} evaluated at the bins, as the joint fit of plane
    waves evaluated it before: the same bits at every bin, and read only (shared by every beamformer)."""
    from radarnode.dsp.doa import _steering_table
    table = _steering_table(n_el, n_fft)
    k = np.arange(n_el)
    bins = np.random.default_rng(n_fft).integers(0, n_fft, (7, 3))
    direct = np.exp(2j * np.pi * k[None, :, None] * bins[:, None, :] / n_fft)      # (n, elements, q)
    np.testing.assert_array_equal(table[bins].transpose(0, 2, 1), direct)
    np.testing.assert_array_equal(table[bins[:, 0]], np.exp(2j * np.pi * k * bins[:, 0, None] / n_fft))
    assert table.shape == (n_fft, n_el) and not table.flags.writeable
