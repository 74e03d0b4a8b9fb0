"""The detection statistic, derived (issue 9 item 1): exact CFAR thresholds for the non-coherent sum of N
windowed channels, measured false-alarm probability on noise-only cubes, Pd against theory, unbiased noise floor."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.stats

from radarnode.consumer.evaluate import simulate
from radarnode.dsp import detection_stats as ds
from radarnode.radar.chain import DspChain, DspConfig
from radarnode.dsp.spectra import noncoherent_power, range_doppler, window
from radarnode.errors import ConfigError
from radarnode.radar import detection_model, equation
from radarnode.radar.presets import PRESETS
from radarnode.radar.scatterers import point_targets
from radarnode.radar.signal_model import synthesize


@pytest.mark.parametrize("n_channels", [1, 4, 12])
@pytest.mark.parametrize("pfa", [1e-3, 1e-6, 1e-9])
def test_ca_threshold_matches_the_beta_closed_form_without_correlation(n_channels, pfa):
    """With independent cells X/(X+Z) ~ Beta(N, N·N_T): an independent reference for the recurrence."""
    n_t = 248
    alpha = ds.ca_alpha(pfa, n_channels, np.ones(n_t))
    a = alpha / n_t
    assert scipy.stats.beta.sf(a / (1 + a), n_channels, n_channels * n_t) == pytest.approx(pfa, rel=1e-8)


@pytest.mark.parametrize("n_channels", [400, 449, 450, 451, 512, 900, 2304, 4096])
def test_ca_pfa_holds_for_hundreds_to_thousands_of_channels(n_channels):
    """The recurrence's terms pass 1e308 from N ≈ 450 on a 248-cell ring (α came out infinite: the radar blind, an
    independent tester's finding); scaled as it goes, log Pfa is the Beta closed form's at every N and α, and the
    threshold for 1e-6 gives 1e-6. A correlated (Hann) ring's α stays finite and falls with N, as more channels
    average the noise."""
    n_t = 248
    for alpha in (0.6, 1.0, 1.3, 2.5):
        a = alpha / n_t
        want = scipy.stats.beta.logsf(a / (1 + a), n_channels, n_channels * n_t)
        got = ds.ca_log_pfa(alpha, n_channels, np.ones(n_t))
        if math.isfinite(want):
            assert got == pytest.approx(want, rel=1e-9, abs=1e-9)
        else:                                   # beyond SciPy's reach (below 1e-308): ours finite, as far down
            assert -math.inf < got < math.log(1e-300)
    alpha = ds.ca_alpha(1e-6, n_channels, np.ones(n_t))
    a = alpha / n_t
    assert scipy.stats.beta.sf(a / (1 + a), n_channels, n_channels * n_t) == pytest.approx(1e-6, rel=1e-7)
    rho = ds.noise_correlation(window("hann", 128))
    eig = ds.ring_eigenvalues(ds.ring_offsets((2, 2), (4, 8)), rho, rho)
    hann = ds.ca_alpha(1e-3, n_channels, eig)
    assert 1.0 < hann < ds.ca_alpha(1e-3, n_channels // 2, eig) < math.inf


def test_a_preset_of_more_than_4096_virtual_channels_is_refused_by_name():
    from radarnode.errors import FieldError
    from radarnode.radar.presets import MAX_VIRTUAL_CHANNELS
    base = PRESETS["ars408_like"]
    assert base.with_overrides({"num_tx": 2, "num_rx": 2048}).num_virtual == MAX_VIRTUAL_CHANNELS == 4096
    with pytest.raises(FieldError, match=r"num_rx.*2049.*at most 4096 virtual channels"):
        base.with_overrides({"num_tx": 2, "num_rx": 2049})


def test_single_cell_formula_is_the_one_channel_case():
    n_t = 248
    assert ds.ca_alpha(1e-6, 1, np.ones(n_t)) == pytest.approx(n_t * (1e-6 ** (-1 / n_t) - 1), rel=1e-9)


@pytest.mark.parametrize("n_t", [4, 16, 248])
@pytest.mark.parametrize("pfa", [0.4, 1e-3, 1e-12])
def test_the_threshold_root_is_found_to_1e_13_in_few_evaluations(n_t, pfa):
    """The one-channel threshold has a closed form, α = N_T·(Pfa^(−1/N_T) − 1): the root finder (regula falsi with
    the Illinois rule, a bisection after any slow step) reaches it to about 1e-13 in at most 35 evaluations of the
    exact Pfa, the bracket's doublings included (bisection took 45–56 in all here)."""
    calls = []

    def f(alpha):
        calls.append(alpha)
        return ds.ca_log_pfa(alpha, 1, np.ones(n_t)) - np.log(pfa)

    root = ds._root_decreasing(f, 0.0)
    assert root == pytest.approx(n_t * (pfa ** (-1 / n_t) - 1), rel=2e-13)
    assert len(calls) <= 35


def test_hann_noise_correlation_and_its_guard():
    rho = ds.noise_correlation(window("hann", 256))
    np.testing.assert_allclose(rho[:4], [1.0, -2 / 3, 1 / 6, 0.0], atol=1e-12)
    assert ds.correlation_length(rho) == 2
    with pytest.raises(ConfigError, match="guard.*at least 2 guard cells in range"):
        DspChain(PRESETS["mimo12"], DspConfig(guard_range=1))


def test_old_single_cell_threshold_was_far_too_high():
    """The defect of issue 9: α for one exponential cell on a 12-channel sum sits ~6.7 dB above the exact one."""
    chain = DspChain(PRESETS["mimo12"])
    old = 248 * (1e-6 ** (-1 / 248) - 1)
    assert 10 * math.log10(old / chain.cfar.alpha) == pytest.approx(6.7, abs=0.2)


def _noise_maps(preset, frames, seed):
    rng = np.random.default_rng(seed)
    c, m, n = preset.num_virtual, preset.num_chirps, preset.num_samples
    for _ in range(frames):
        cube = (rng.standard_normal((c, m, n)) + 1j * rng.standard_normal((c, m, n))) * math.sqrt(0.5)
        yield noncoherent_power(range_doppler(cube))


def test_ca_false_alarm_probability_on_noise_cubes():
    """10⁷ cells of the real mimo12 chain (12 channels, Hann × Hann): within ±30 % at 1e-3 and 1e-4."""
    p = PRESETS["mimo12"]
    cfars = {pfa: DspChain(p, DspConfig(pfa=pfa)).cfar for pfa in (1e-3, 1e-4)}
    hits = dict.fromkeys(cfars, 0)
    cells = 0
    for power in _noise_maps(p, 153, 11):
        cells += power.size
        for pfa, cfar in cfars.items():
            hits[pfa] += int(cfar(power).mask.sum())
    assert cells >= 10_000_000
    for pfa, h in hits.items():
        assert h / cells == pytest.approx(pfa, rel=0.3), (pfa, h / cells)


def test_os_false_alarm_probability_on_noise_cubes():
    """OS-CFAR (k = 3/4 of the ring), its threshold from simulated correlated rings: 2·10⁶ cells at 1e-3."""
    p = PRESETS["mimo12"]
    cfar = DspChain(p, DspConfig(cfar="os", pfa=1e-3)).cfar
    hits = cells = 0
    for power in _noise_maps(p, 31, 12):
        hits += int(cfar(power).mask.sum())
        cells += power.size
    assert hits / cells == pytest.approx(1e-3, rel=0.3)


@pytest.mark.parametrize("swerling", [0, 1])
def test_the_detection_levels_draw_follows_the_exact_pd(swerling):
    stat = DspChain(PRESETS["mimo12"]).statistic
    rng = np.random.default_rng(3)
    for e_db in (12.0, 16.0, 20.0):
        e = np.full(40_000, 10 ** (e_db / 10))
        if swerling:
            e = e * rng.exponential(1.0, e.size)
        measured = stat.draw(e, rng)[0].mean()
        assert measured == pytest.approx(float(stat.pd(10 ** (e_db / 10), swerling)), abs=0.015)


def _detections(level: str, p, chain, scat, seed: int):
    """One frame's detections of ``scat`` at the detection level, or at the signal level through the chain (its
    range–Doppler synthesis), drawn from ``seed``."""
    from radarnode.radar.signal_model import synthesize_rd
    rng = np.random.default_rng(seed)
    return detection_model.detect(p, scat, rng, chain.statistic) if level == "detection" \
        else chain.process_rd(synthesize_rd(p, scat, rng))


def _crowd(n: int):
    """``n`` returns crowded within a few bins (positions in bins, d·sinθ, coherent fields 0–30 dB, tags of several
    bodies and posts), from seed 11: the lobe test's crowd; and the generator, to draw on from."""
    rng = np.random.default_rng(11)
    r, v = rng.uniform(20.0, 60.0, n), rng.uniform(-8.0, 8.0, n)
    u = rng.uniform(-0.5, 0.5, n)
    field = rng.normal(size=n) * 10.0 ** rng.uniform(0.0, 3.0, n) * np.exp(2j * np.pi * rng.random(n))
    return r, v, u, field, rng.integers(-1, 6, n), rng


def _small_preset():
    """A 4-channel, 64 × 64 radar: the same chain, cheap enough for hundreds of trials in a test."""
    return PRESETS["mimo12"].with_overrides({"num_chirps": 64, "num_samples": 64, "num_tx": 1})


@pytest.mark.parametrize("swerling", [0, 1])
def test_signal_chain_pd_matches_theory_within_half_a_db(swerling):
    """On-bin targets at the SNR where theory gives Pd 0.5 and 0.9: measured Pd within 0.5 dB of it."""
    p = _small_preset()
    chain = DspChain(p)
    stat = chain.statistic
    rng = np.random.default_rng(21 + swerling)
    grid = np.arange(0.0, 30.0, 0.01)
    theory = stat.pd(stat.energy(10 ** (grid / 10)), swerling)
    n_r = p.num_samples
    for target in (0.5, 0.9):
        snr = float(np.interp(target, theory, grid))
        hits, trials = 0, 300
        for _ in range(trials):
            r = (rng.integers(10, n_r - 10)) * p.range_resolution_m          # on a bin centre
            v = rng.integers(-20, 20) * p.speed_resolution_mps
            rcs = snr - float(equation.snr_db(p, r, 0.0, azimuth_rad=0.0))
            if swerling:
                rcs += 10 * math.log10(rng.exponential())
            det = chain.process(synthesize(p, point_targets([r], [0.0], [v], rcs), rng))
            hits += bool(np.any((np.abs(det.range_m - r) < p.range_resolution_m)
                                & (np.abs(det.range_rate_mps - v) < p.speed_resolution_mps)))
        # slope of Pd at this point, to turn 0.5 dB into a Pd tolerance (plus 2.5σ of sampling error)
        slope = float(np.interp(snr + 0.5, grid, theory) - target)
        tol = abs(slope) + 2.5 * math.sqrt(target * (1 - target) / trials)
        assert hits / trials == pytest.approx(target, abs=tol), (target, hits / trials, tol)


def test_noise_floor_and_rcs_are_unbiased():
    """Point targets of 10 dBsm anywhere in range, speed and angle: median RCS error within 0.3 dB."""
    p = PRESETS["mimo12"]
    chain = DspChain(p)
    rng = np.random.default_rng(7)
    errors = []
    for _ in range(6):
        r, az, v = rng.uniform(20, 100, 5), rng.uniform(-40, 40, 5), rng.uniform(-25, 25, 5)
        det = chain.process(synthesize(p, point_targets(r, az, v, 10.0), rng))
        for i in range(5):
            j = np.argmin(np.abs(det.range_m - r[i]) + np.abs(det.range_rate_mps - v[i]))
            errors.append(det.rcs_dbsm[j] - 10.0)
    assert abs(np.median(errors)) <= 0.3
    # and the floor of a pure-noise map is its per-channel variance
    power = next(_noise_maps(p, 1, 3))
    w = window("hann", 256)
    sigma2 = float((w ** 2).sum() ** 2)          # per channel: Σw_r²·Σw_d², unit-variance samples
    assert chain.statistic.noise_floor(power) == pytest.approx(sigma2, rel=0.01)


def test_ring_interference_is_the_sum_of_the_window_response_over_the_training_cells():
    st = DspChain(PRESETS["ars408_like"]).statistic
    rng = np.random.default_rng(0)
    cd, cr = rng.integers(0, 256, 30), rng.integers(0, 256, 30)
    pd, pr, e = rng.uniform(0, 256, 200), rng.uniform(0, 256, 200), rng.uniform(0, 10, 200)
    got = st.ring_interference(cd, cr, pd, pr, e, (256, 256))
    off = ds.ring_offsets(st.cfar.guard, st.cfar.train)
    want = np.zeros(30)
    for c in range(30):            # brute force over the ring's cells inside the map (targets wrap, as the FFTs do)
        dd = (pd - cd[c] + 128) % 256 - 128
        dr = (pr - cr[c] + 128) % 256 - 128
        near = (np.abs(dd) < 40) & (np.abs(dr) < 40)
        ring = off[(cr[c] + off[:, 1] >= 0) & (cr[c] + off[:, 1] <= 255)]
        k = ds.straddle_gain(st.doppler_window, ring[:, 0][:, None] - dd[near][None, :]) \
            * ds.straddle_gain(st.range_window, ring[:, 1][:, None] - dr[near][None, :])
        want[c] = (k.sum(axis=0) * e[near]).sum()
    assert np.allclose(got, want, rtol=1e-3, atol=1e-3)
    # a target in the guard cells or 2 boxes away adds nothing; one 4 range bins off its whole main lobe
    single = lambda d, r: st.ring_interference([100], [50], [d], [r], [1.0], (256, 256))[0]   # noqa: E731
    assert single(100.0, 50.0) < 1e-3 and single(100.0, 80.0) < 1e-6
    assert single(100.0, 54.0) == pytest.approx(1.5 * 1.5, rel=1e-3)


def test_masking_factor_is_one_alone_and_falls_with_the_interference():
    st = DspChain(PRESETS["ars408_like"]).statistic
    mean_z = st.n_channels * st.eigenvalues.sum()
    rho = np.full(6, 30.0)
    i = np.array([0.0, 0.005, 0.1, 1.0, 10.0, 100.0]) * mean_z
    f = st.masking_factor(rho, i, 1)
    assert f[0] == 1.0 and f[1] == 1.0 and np.all(np.diff(f[1:]) < 0) and f[-1] < 0.5
    exact = st.pd_interfered(rho[2:], i[2:], 1) / st.pd_interfered(rho[2:], np.zeros(4), 1)
    assert np.allclose(f[2:], exact, atol=0.01)


@pytest.mark.parametrize("rho_db", [79.0, 80.0, 81.0, 101.0, 160.0])
@pytest.mark.parametrize("swerling", [0, 1])
def test_the_masking_factor_holds_above_the_tables_top_snr(rho_db, swerling):
    # below, at, just above and at twice the table's top SNR (80 dB), against the exact ratio of pd_interfered: the
    # table clipped the SNR alone there, and read a car 8 m ahead (88 dB) as masked by a neighbour its own strength
    # (0.11 where the exact factor is 0.98)
    assert ds.DetectionStatistic.MASK_RHO_DB[-1] == 80.0
    st = DspChain(PRESETS["ars408_like"]).statistic
    e = st.energy(10.0 ** (rho_db / 10.0))
    rel_db = np.array([-10.0, 0.0, 10.0, 15.0, 20.0, 25.0])
    i = e * 10.0 ** (rel_db / 10.0)
    rho = np.full(rel_db.size, rho_db)
    f = st.masking_factor(rho, i, swerling)
    exact = st.pd_interfered(rho, i, swerling) / st.pd_interfered(rho, np.zeros(rel_db.size), swerling)
    assert np.allclose(f, exact, atol=0.02), (f, exact)
    # a neighbour 10 dB weaker than the target costs it almost nothing, one 25 dB stronger hides it
    assert f[0] > 0.98 and f[-1] < 0.05


# the signal level's case takes 14 s: -m slow (CI's 20 minutes; the two others run in CI)
@pytest.mark.parametrize("level", ["object", "detection", pytest.param("signal", marks=pytest.mark.slow)])
def test_a_weak_target_beside_a_strong_one_is_masked_at_every_level(level):
    # a 0 dBsm point in the next lane, 4 range bins behind a 35 dBsm one at the same speed, sits in its CA-CFAR
    # ring: the chain masks it; 40 range bins behind, or at another speed, it is seen. The levels must agree.
    from helpers import scenario
    from radarnode.radar.models import make_model
    from radarnode.radar.object_model import RuntimeConfig
    from radarnode.radar.setup import radar_config
    from radarnode.scene.world import Scene

    res = PRESETS["ars408_like"].range_resolution_m
    rates = []
    for gap, speed in ((4 * res, 20.0), (40 * res, 20.0), (4 * res, 26.0)):
        sc = scenario(f"""  - {{id: big, class: point, x_m: 40.0, lane: 1, speed_mps: 20.0, rcs_dbsm: 35.0}}
  - {{id: weak, class: point, x_m: {40.0 + gap:.2f}, lane: 2, speed_mps: {speed}, rcs_dbsm: 0.0, swerling: 0}}""",
                      duration=1.5, seed=2)
        rc = radar_config(sc)
        model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(2), rc.signal)
        cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m)
        seen = 0
        for k in range(sc.num_cycles):
            model.step(k * sc.period_s, cfg)
            seen += int((model.info.detections.actor_index == 1).any())
        rates.append(seen / sc.num_cycles)
    masked, far, other_speed = rates
    assert masked <= 0.3 and far >= 0.9 and other_speed >= 0.9, rates


def test_a_ring_the_range_edge_cuts_is_the_chains():
    """Within guard + train range bins of the map's first or last bin the chain's CA-CFAR ring holds only its cells
    inside the map, with their own α (radarnode.dsp.cfar.CellAveragingCfar): the detection level's draw and ring
    sum take the same ring (the count, α and training-sum law of each cut; the ring sum over its cells only)."""
    st = DspChain(PRESETS["ars408_like"]).statistic
    cfar, n = st.cfar, 256
    reach = cfar.guard[1] + cfar.train[1]
    bins = np.array([0, 1, reach - 1, reach, reach + 1, 100, n - 1 - reach, n - reach, n - 2, n - 1])
    alpha, mean, var, count = st.ring_cut(bins, n)
    cfar.noise(np.ones((st.doppler_window.size, n)))            # the chain's counts and α per column
    assert np.array_equal(count, cfar._count[0, bins]) and np.allclose(alpha, cfar._alpha[0, bins], rtol=1e-12)
    full = (bins >= reach) & (bins <= n - 1 - reach)
    eig = st.eigenvalues
    assert np.all(count[full] == eig.size) and np.all(count[~full] < eig.size)
    assert np.allclose(mean[full], st.n_channels * eig.sum()) and np.allclose(var[full], st.n_channels * np.sum(eig ** 2))
    assert np.all(alpha[~full] > alpha[full][0])                 # fewer training cells: a higher factor
    # the ring sum at edge cells against a brute force over the ring's cells inside the map
    rng = np.random.default_rng(3)
    cd = rng.integers(0, 128, bins.size)
    pd, pr, e = rng.uniform(0, 128, 300), rng.uniform(0, n, 300), rng.uniform(0, 10, 300)
    pr[:150] = rng.uniform(0, 15, 150)                            # half of them near the first bins
    got = st.ring_interference(cd, bins, pd, pr, e, (128, n))
    off = ds.ring_offsets(cfar.guard, cfar.train)
    for c in range(bins.size):
        inside = (bins[c] + off[:, 1] >= 0) & (bins[c] + off[:, 1] <= n - 1)
        dd = (pd - cd[c] + 64) % 128 - 64
        dr = (pr - bins[c] + n / 2) % n - n / 2
        near = (np.abs(dd) < 40) & (np.abs(dr) < 40)
        k = ds.straddle_gain(st.doppler_window, off[inside, 0][:, None] - dd[near][None, :]) \
            * ds.straddle_gain(st.range_window, off[inside, 1][:, None] - dr[near][None, :])
        assert got[c] == pytest.approx((k.sum(axis=0) * e[near]).sum(), rel=2e-3, abs=1e-3), bins[c]
    # away from the edges the ring kernel is the one it was (the same tables, the same numbers)
    dd, dr = rng.uniform(-20, 20, 50), rng.uniform(-20, 20, 50)
    assert np.array_equal(st.ring_kernel(dd, dr, np.full(50, 100), n), st.ring_kernel(dd, dr))


@pytest.mark.parametrize("base, masked", [(4.3, True), (60.3, False)])
def test_a_target_behind_a_strong_one_near_the_first_range_bins_is_masked_as_the_chain_masks_it(base, masked):
    """A 56 dB target 3 range bins before a 40 dB one (ρ, at different angles, the same speed): near the first bins
    the ring of the weak one's cell is cut, so the strong one's energy is shared by fewer cells and the chain masks
    the weak one in every frame; in mid-range the full ring keeps it about 80 % of the frames. The detection level
    draws the chain's cut ring (it gave 0.78 near the edge, where the chain gives 0, before)."""
    from radarnode.radar import detection_model
    p = PRESETS["ars408_like"]
    chain = DspChain(p)
    rs, rw = base * p.range_resolution_m, (base + 3.0) * p.range_resolution_m
    scat = point_targets([rs, rw], [-20.0, 0.0], [0.3, 0.3])
    scat.rcs_dbsm = np.array([56.0, 40.0]) - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    seen = {"detection": 0, "signal": 0}
    trials = 30
    for t in range(trials):
        for level in seen:
            det = _detections(level, p, chain, scat, 9000 + t)
            seen[level] += bool(np.any((np.abs(det.range_m - rw) < p.range_resolution_m)
                                       & (np.abs(det.azimuth_rad) < 0.05)))
    rate = {k: v / trials for k, v in seen.items()}
    if masked:
        assert rate["detection"] <= 0.1 and rate["signal"] <= 0.1, rate
    else:
        assert 0.5 <= rate["detection"] <= 1.0 and 0.5 <= rate["signal"] <= 1.0, rate
        assert abs(rate["detection"] - rate["signal"]) <= 0.25, rate


def test_the_signed_window_response_squares_to_the_power_response():
    """``DetectionStatistic.response``: 1 on the bin, its square the straddle power at every offset, 0 at the Hann main
    lobe's edge (2 bins) and negative in its first sidelobe (the sign the two-tone cross-term needs)."""
    stat = DspChain(PRESETS["mimo12"]).statistic
    d = np.linspace(-3.9, 3.9, 157)
    for axis, w in (("r", stat.range_window), ("d", stat.doppler_window)):
        a = stat.response(axis, d)
        assert np.max(np.abs(a * a - ds.straddle_gain(w, d))) < 1e-3
        assert stat.response(axis, 0.0) == pytest.approx(1.0)
        assert abs(stat.response(axis, 2.0)) < 1e-3 and stat.response(axis, 2.5) < -0.01
        assert stat.response(axis, 5.0) == 0.0


def test_the_window_response_looked_up_by_index_agrees_with_the_interpolated_table_at_every_offset():
    """Thousands of offsets (the lobe test's pairs) take the table by index instead of np.interp's search: the same
    values within 1e-15 of the peak over and beyond the table, 0 outside ±RESPONSE_REACH and at ±inf, NaN for a
    NaN offset, and squares within 1e-3 of the straddle power (as for a few offsets)."""
    stat = DspChain(PRESETS["mimo12"]).statistic
    reach = stat.RESPONSE_REACH
    d = np.concatenate([np.random.default_rng(3).uniform(-reach - 1.0, reach + 1.0, 5000),
                        np.arange(-reach, reach + 1e-9, 1.0 / stat.RESPONSE_PER_BIN),      # every grid point
                        [-reach, reach, np.nextafter(reach, np.inf), np.nextafter(-reach, -np.inf), 0.0,
                         np.inf, -np.inf, np.nan]])
    for axis, w in (("r", stat.range_window), ("d", stat.doppler_window)):
        big = stat.response(axis, d)
        small = np.concatenate([stat.response(axis, part) for part in np.array_split(d, 40)])   # < 512 each
        assert big.shape == d.shape and np.isnan(big[-1]) and np.isnan(small[-1])
        assert np.max(np.abs(big[:-1] - small[:-1])) < 1e-15
        outside = np.abs(d[:-1]) > reach
        assert np.all(big[:-1][outside] == 0.0)
        assert np.max(np.abs(big[:-1][~outside] ** 2 - ds.straddle_gain(w, d[:-1][~outside]))) < 1e-3


@pytest.mark.parametrize("case", ["one beam, 2 Doppler bins", "40 degrees apart, 1.5 range bins",
                                  "one beam, 3 Doppler bins", "one beam, 4 Doppler bins", "one beam, 8 Doppler bins"])
def test_a_weaker_target_in_a_stronger_ones_lobe_is_lost_as_the_chain_loses_it(case):
    """The chain looks for local maxima of its channel-summed range–Doppler map before it looks at angles: a 12 dB
    weaker target 2 Doppler bins from a stronger one in one beam is seldom a peak (0.20 of the frames), 1.5 range bins
    behind it 40° away never; 3 bins away it always is, and so at the lobe test's reach (4 bins) and twice it. The
    detection level's lobe test gives the same (it reported the first two in every frame before)."""
    from radarnode.radar import detection_model
    p = PRESETS["mimo12"]
    chain = DspChain(p)
    trials = 30
    seen = {"detection": 0, "signal": 0}
    for t in range(trials):
        rng0 = np.random.default_rng(7000 + t)
        r0 = (40.0 + rng0.random()) * p.range_resolution_m
        v0 = (3.0 + rng0.random()) * p.doppler_bin_mps
        if case.startswith("one beam"):
            sep = float(case.split(", ")[1].split()[0])
            r, v, az = [r0, r0], [v0, v0 + sep * p.doppler_bin_mps], [0.0, 0.0]
        else:
            r, v, az = [r0, r0 + 1.5 * p.range_resolution_m], [v0, v0], [-20.0, 20.0]
        scat = point_targets(r, az, v)
        scat.rcs_dbsm = np.array([50.0, 38.0]) - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
        for level in seen:
            det = _detections(level, p, chain, scat, 7000 + t)
            seen[level] += bool(np.any((np.abs(det.range_m - r[1]) < 0.75 * p.range_resolution_m)
                                       & (np.abs(det.range_rate_mps - v[1]) < 0.75 * p.doppler_bin_mps)
                                       & (np.abs(det.azimuth_rad - math.radians(az[1])) < math.radians(6.0))))
    rate = {k: n / trials for k, n in seen.items()}
    if case.startswith("one beam") and "2 Doppler" not in case:
        assert rate["signal"] >= 0.9 and rate["detection"] >= 0.9, rate
    else:
        assert rate["signal"] <= 0.35 and rate["detection"] <= 0.35, rate
    assert abs(rate["detection"] - rate["signal"]) <= 0.2, rate


@pytest.mark.parametrize("preset", ["ars408_like", "mimo12"])
@pytest.mark.parametrize("bins", [2.95, 2.99, 3.0, 3.01, 6.0])
def test_a_return_astride_its_cells_edge_is_not_lost_in_its_equal_neighbours_lobe(preset, bins):
    """Two equal returns ``bins`` range bins apart at one speed, 4° apart, ρ = 30 dB, the nearer astride its cell's
    edge (bin 22.5): the detection level reports both in every frame, as the chain does. Its lobe test hid the
    farther one where its own other half, in the cell towards the nearer one, stood higher than its cell: lost in
    8–27 % of the frames at 2.95–3.01 bins on ars408_like (the chain in none); 6 bins is twice the reach of that
    case."""
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS[preset]
    chain = DspChain(p)
    snr = 30.0 - 10.0 * math.log10(num_range_samples(p) * p.num_chirps * p.num_virtual)
    r = np.array([40.3, 40.3 + bins * p.range_resolution_m]) if preset == "ars408_like" else \
        np.array([22.514, 22.514 + bins]) * p.range_resolution_m
    v, az = np.array([0.7, 0.7]), np.array([0.0, 4.0])
    scat = point_targets(r, az, v, 40.0 * np.log10(r / r[0]))
    rng = np.random.default_rng(11)

    def both(det):
        return all(np.any((np.abs(det.range_m - r[t]) < 0.5 * p.range_resolution_m)
                          & (np.abs(det.range_rate_mps - v[t]) < 0.5 * p.doppler_bin_mps)) for t in range(2))
    assert all(both(detection_model.detect(p, scat, rng, chain.statistic, snr_db=snr)) for _ in range(150))
    assert all(both(chain.process_rd(synthesize_rd(p, scat, rng, snr_db=snr))) for _ in range(10))


@pytest.mark.parametrize("axis,sep", [("range", 1.0), ("range", 2.0), ("range", 3.0), ("Doppler", 1.0),
                                      ("Doppler", 2.0)])
def test_two_equal_returns_bins_apart_in_one_beam_are_never_both_lost(axis, sep):
    """Two equal steady returns 1, 2 or 3 bins apart in one beam, each astride its cell's edge (0.49 bin off its
    centre): the chain's map always has a maximum, so it reports one or both in every frame. The detection level lost
    both in about half the frames at 1 bin (the cell the stronger took the weaker's energy from counted again beside
    it and hid it) and in 1–2 of 14 at 2 bins (the map's maximum between them, where neither stands); an independent
    tester's finding on two motorcycles riding staggered. Now: never both lost at either level, and 2 or 3 bins apart
    the frames with two reported within 0.25 of each other (measured: 0.29 / 0.29 at 2 bins, 0.88 / 1.00 at 3)."""
    p = PRESETS["ars408_like"]
    chain = DspChain(p)
    trials = 24
    counts = {"detection": [], "signal": []}
    for t in range(trials):
        r0 = (22.49 + 0.02 * (t % 3)) * p.range_resolution_m
        if axis == "range":
            r, v = [r0, r0 + sep * p.range_resolution_m], [0.0, 0.0]
        else:
            r, v = [r0, r0], [0.49 * p.doppler_bin_mps, (0.49 + sep) * p.doppler_bin_mps]
        scat = point_targets(r, [0.0, 0.3], v)
        scat.rcs_dbsm = 45.0 - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)     # ρ 45 dB each
        for level in counts:
            det = _detections(level, p, chain, scat, 9100 + t)
            near = (np.abs(det.range_m - np.mean(r)) < (0.5 * sep + 1.0) * p.range_resolution_m) & \
                (np.abs(det.range_rate_mps - np.mean(v)) < (0.5 * sep + 1.0) * p.doppler_bin_mps)
            counts[level].append(int(near.sum()))
    for level, c in counts.items():
        assert min(c) >= 1, (level, c)
    two = {level: np.mean(np.array(c) >= 2) for level, c in counts.items()}
    if sep >= 2.0:     # (1 bin apart the chain splits the pair in 0.2–0.5 of these frames, by its phases; the
        # detection level's resolution box merges it in every frame: BENCHMARKS.md, "Resolution")
        assert abs(two["detection"] - two["signal"]) <= 0.25, (two, counts)


@pytest.mark.parametrize("axis", ["range", "doppler"])
@pytest.mark.parametrize("layout", ["two_cells_between", "row_behind_its_head"])
def test_a_group_of_returns_apart_from_the_rest_is_never_all_lost(axis, layout):
    """Returns each within a few bins of the next, in one beam, nothing else near: the chain's map has a maximum
    among them in every frame and reports it. Two equal returns at 22.49 and 24.50 bins (each peak lost to the cell
    on its own side, two different cells between them), and a peak astride its cell's edge at the head of a row of
    weaker returns a bin apart (−3, −6 dB; the row's slope hid it): the detection level lost every one of them in
    16–30 of 56 frames of an independent tester's scenes, the chain never. Now: at least one in every frame, at
    both levels."""
    p = PRESETS["ars408_like"]
    chain = DspChain(p)
    if layout == "two_cells_between":
        pos, gain_db = np.array([22.49, 24.50]), np.array([0.0, 0.0])
    else:
        pos, gain_db = np.array([22.49, 23.49, 24.49]), np.array([0.0, -3.0, -6.0])
    counts = {"detection": [], "signal": []}
    for t in range(24):
        shift = 0.01 * (t % 4)
        if axis == "range":
            r, v = (pos + shift) * p.range_resolution_m, np.zeros(pos.size)
        else:
            r, v = np.full(pos.size, 22.0 * p.range_resolution_m), (pos - 22.0 + shift) * p.doppler_bin_mps
        scat = point_targets(r, np.linspace(0.0, 0.6, pos.size), v)
        scat.rcs_dbsm = 45.0 + gain_db - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
        for level in counts:
            det = _detections(level, p, chain, scat, 9300 + t)
            near = (np.abs(det.range_m - r.mean()) < (np.ptp(r) / 2 + 1.5 * p.range_resolution_m)) & \
                (np.abs(det.range_rate_mps - v.mean()) < (np.ptp(v) / 2 + 1.5 * p.doppler_bin_mps))
            counts[level].append(int(near.sum()))
    for level, c in counts.items():
        assert min(c) >= 1, (level, c)


@pytest.mark.parametrize("axis", ["range", "doppler"])
@pytest.mark.parametrize("sep", [0.3, 0.8, 1.1, 2.2])
def test_returns_abreast_at_other_angles_are_angle_peaks_of_one_maximum_as_in_the_chain(axis, sep):
    """Two equal returns at ±10° (two cars abreast, one a little ahead), ``sep`` bins apart along one axis across a
    cell's edge: the chain's channel-summed map has one maximum and its snapshot both angles up to about 0.8 bins
    apart, one from 1.1 (SHARED_CELL_FLOOR_DB). The detection level reported one of them in every frame from 0.1 to
    0.8 bins (the lobe test hid the other, an independent tester's finding; 1.0 against the chain's 2.0); now it
    moves the lost one into the maximum's cell as an angle peak. Below (0.3), just below (0.8) and just above (1.1)
    the measured cut, and at twice it (2.2: two maxima): the two levels' mean counts within 0.3."""
    p = PRESETS["ars408_like"]
    chain = DspChain(p)
    pos = 40.5 + np.array([-0.5, 0.5]) * sep            # astride the edge of cells 40 and 41
    counts = {"detection": [], "signal": []}
    for t in range(8):
        if axis == "range":
            r, v = pos * p.range_resolution_m, np.full(2, 5.3 * p.doppler_bin_mps)
        else:
            r, v = np.full(2, 40.3 * p.range_resolution_m), (pos - 35.0) * p.doppler_bin_mps
        scat = point_targets(r, [-10.0, 10.0], v)
        scat.rcs_dbsm = 35.0 - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)     # ρ 35 dB each
        for level in counts:
            det = _detections(level, p, chain, scat, 700 + t)
            near = (np.abs(det.range_m - r.mean()) < (np.ptp(r) / 2 + 2.0 * p.range_resolution_m)) & \
                (np.abs(det.range_rate_mps - v.mean()) < (np.ptp(v) / 2 + 2.0 * p.doppler_bin_mps))
            counts[level].append(int(near.sum()))
    mean = {level: float(np.mean(c)) for level, c in counts.items()}
    assert abs(mean["detection"] - mean["signal"]) <= 0.3, counts
    if sep < 1.0:
        assert mean["detection"] >= 1.75, counts


def test_a_strong_return_lost_to_a_weak_ones_cell_is_reported_there_in_its_place():
    """A return astride its cell's edge (40.45 range bins, −10°) beside one 10 dB weaker 0.75 bins on at +10°: the
    weak one's lobe tips the strong one's cell below its neighbour, so the chain's maximum is the weak one's cell,
    and its snapshot there holds the strong one (the weak one 16 dB below it: no angle peak). The chain reports the
    strong one in 16 of 16 frames and the weak one in none; the detection level reported the weak one alone in 9 of
    them (the strong one lost). Now the strong one moves into that cell and the weak one is dropped there."""
    p = PRESETS["ars408_like"]
    chain = DspChain(p)
    r = np.array([40.45, 41.2]) * p.range_resolution_m
    scat = point_targets(r, [-10.0, 10.0], np.full(2, 5.3 * p.doppler_bin_mps))
    scat.rcs_dbsm = np.array([40.0, 30.0]) - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    seen = {"detection": [0, 0], "signal": [0, 0]}
    for seed in range(16):
        for level, count in seen.items():
            det = _detections(level, p, chain, scat, seed)
            az = np.degrees(det.azimuth_rad[np.abs(det.range_m - r.mean()) < 3.0 * p.range_resolution_m])
            count[0] += int(np.any(np.abs(az + 10.0) < 3.0))
            count[1] += int(np.any(np.abs(az - 10.0) < 3.0))
    assert seen["signal"] == [16, 0], seen
    assert seen["detection"] == seen["signal"], seen


@pytest.mark.parametrize("layout", ["fz35", "fz26"])
def test_returns_moved_into_one_maximum_are_judged_against_its_strongest(layout):
    """Several returns at several angles within a bin or two (an independent tester's random layouts on srr_corner):
    where the one peak left standing is weak, every return lost beside it went into its cell and was compared with
    that weak one, so the detection level reported 2.6–3.0 a frame where the chain reports 1.0–1.7. The chain fits
    the maximum's snapshot at its strongest return and sees each other one through the windows' response at its
    offset from it: now so does the detection level, within 0.5 of the chain."""
    r, v, az, rho, seed0 = {
        "fz35": ([40.99, 40.13, 41.56, 41.13], [6.54, 5.46, 6.21, 5.64], [-27.9, 35.3, -49.7, 0.4],
                 [32.0, 35.0, 25.0, 25.0], 1460),
        "fz26": ([40.21, 41.07, 41.92, 40.65, 41.54], [5.21] * 5, [-33.5, -16.6, 27.2, -34.6, 4.8],
                 [35.0, 32.0, 35.0, 35.0, 32.0], 1316)}[layout]
    p = PRESETS["srr_corner"]
    chain = DspChain(p)
    r, v = np.array(r) * p.range_resolution_m, np.array(v) * p.doppler_bin_mps
    scat = point_targets(r, az, v)
    scat.actor_index = np.arange(r.size)
    scat.rcs_dbsm = np.array(rho) - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    counts = {"detection": [], "signal": []}
    for seed in range(seed0, seed0 + 16):
        for level, c in counts.items():
            det = _detections(level, p, chain, scat, seed)
            near = ((det.range_m > r.min() - 2 * p.range_resolution_m)
                    & (det.range_m < r.max() + 2 * p.range_resolution_m)
                    & (det.range_rate_mps > v.min() - 2 * p.doppler_bin_mps)
                    & (det.range_rate_mps < v.max() + 2 * p.doppler_bin_mps))
            c.append(int(near.sum()))
    assert abs(np.mean(counts["detection"]) - np.mean(counts["signal"])) <= 0.5, counts


@pytest.mark.parametrize("preset,r,v,az,rho", [
    ("mimo12", [40.0, 41.45], [5.0, 6.45], [-20.0, 20.0], [35.0, 36.0]),
    ("ars408_like", [39.9, 41.1], [4.9, 6.1], [-10.0, 10.0], [35.0, 35.0])])
def test_a_return_moved_from_afar_does_not_take_the_maximum_from_the_peak_standing_there(preset, r, v, az, rho):
    """Two returns 1.2–1.45 bins apart on both axes at two angles: the chain reports the one standing in the maximum's
    cell, at its full SNR. Ranked at its own bin's centre, the other one (lost, moved in from 1.7–2 bins' diagonal)
    took the maximum, the peak standing there was dropped and the moved one kept only its energy at that offset:
    frames empty, or a detection 7–15 dB low at the other return's angle (an independent tester's finding). Now the
    highest in the cell holds it: one detection at one of the returns' angles (equal ones: the chain takes either, by
    its noise) and within 2 dB of the chain's SNR, every frame."""
    p = PRESETS[preset]
    chain = DspChain(p)
    rr, vv = np.array(r) * p.range_resolution_m, np.array(v) * p.doppler_bin_mps
    scat = point_targets(rr, az, vv)
    scat.rcs_dbsm = np.array(rho) - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    for seed in range(700, 704):
        out = {}
        for level in ("detection", "signal"):
            det = _detections(level, p, chain, scat, seed)
            near = np.abs(det.range_m - rr.mean()) < 3.0 * p.range_resolution_m
            out[level] = (np.degrees(det.azimuth_rad[near]), det.snr_db[near])
        (az_d, snr_d), (az_s, snr_s) = out["detection"], out["signal"]
        assert az_s.size == 1 and az_d.size == 1, (seed, out)
        assert np.min(np.abs(az_d[0] - np.array(az))) < 3.0 and abs(snr_d[0] - snr_s[0]) < 2.0, (seed, out)


@pytest.mark.parametrize("n", [3, 4, 5, 6, 8])
def test_a_cell_gives_at_most_the_chains_four_angle_peaks(n):
    """``n`` equal returns at ``n`` angles in one range–Doppler cell (mimo12, 1.1 beamwidths apart at the closest):
    the chain's angle estimator takes at most DOA_MAX_SOURCES (4) sources out of a snapshot; the detection level
    reported all six. Below (3), at (4), just above (5) and at twice (8) the cap, and the six of the finding: the
    detection level reports min(n, 4) in every frame, the chain never more than 4 and, on the mean, within 0.5 of it."""
    from radarnode.radar.calibration import DOA_MAX_SOURCES
    p = PRESETS["mimo12"]
    chain = DspChain(p)
    az = np.linspace(-52.5, 52.5, n) if n > 6 else np.linspace(-50.0, 50.0, n)
    r = np.full(n, 40.2 * p.range_resolution_m)
    scat = point_targets(r, az, np.full(n, 5.2 * p.doppler_bin_mps))
    scat.rcs_dbsm = 35.0 - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    counts = {"detection": [], "signal": []}
    for seed in range(4):
        for level, c in counts.items():
            det = _detections(level, p, chain, scat, seed)
            c.append(int(np.sum(np.abs(det.range_m - r[0]) < 2 * p.range_resolution_m)))
    assert counts["detection"] == [min(n, DOA_MAX_SOURCES)] * 4, counts
    assert max(counts["signal"]) <= DOA_MAX_SOURCES, counts
    assert abs(np.mean(counts["detection"]) - np.mean(counts["signal"])) <= 0.5, counts


@pytest.mark.parametrize("beams,both", [(0.68, False), (0.70, True), (0.72, True), (1.4, True)])
def test_a_return_abreast_moves_into_the_maximum_only_resolved_in_angle(beams, both):
    """Two equal returns 0.3 range bins apart astride a cell's edge (ars408_like, ρ 35 dB), ``beams`` beamwidths
    apart in d·sinθ: the lost one is an angle peak of the other's cell only where it is RESOLUTION[2] (0.7) beamwidths
    or more from every peak standing there. Just below (0.68), at (0.70), just above (0.72) and at twice (1.4) the
    cut: one detection below it, two from it, in every frame; at twice it the chain's two in every frame as well.
    (At 0.6–0.72 beamwidths the chain, counting the residues of its CLEAN search, reads 1.75–1.81 a frame on both sides
    of the step: README, known limits.)"""
    p = PRESETS["ars408_like"]
    chain = DspChain(p)
    u = (np.array([-0.5, 0.5]) * beams + 0.13) / p.num_virtual
    az = np.degrees(np.arcsin(u / p.element_spacing_wl))
    r = (40.5 + np.array([-0.15, 0.15])) * p.range_resolution_m
    scat = point_targets(r, az, np.full(2, 5.3 * p.doppler_bin_mps))
    scat.rcs_dbsm = 35.0 - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    levels = ("detection", "signal") if beams > 1.0 else ("detection",)
    for seed in range(900, 908):
        for level in levels:
            det = _detections(level, p, chain, scat, seed)
            n = int(np.sum(np.abs(det.range_m - r.mean()) < 2.5 * p.range_resolution_m))
            assert n == (2 if both else 1), (level, seed, n)


@pytest.mark.parametrize("rho,drop", [
    (18.0, 8.0), (18.0, 6.0), (18.0, 5.0), (26.0, 2.0),        # the weaker one at ρ 10, 12, 13 and 24 dB
    (30.0, 8.5), (30.0, 9.0), (30.0, 9.5), (30.0, 18.0)])     # 8.5, 9, 9.5 and 18 dB below the stronger
def test_a_weaker_source_in_a_cell_is_found_as_often_as_the_chains_angle_search_finds_it(rho, drop):
    """Two returns in one range–Doppler cell, 3 beamwidths apart (mimo12): the chain's CLEAN search takes the weaker
    one only where its beam peak stands DOA_SECONDARY_SNR_DB (12 dB) above the beam noise and within DOA_FLOOR_DB
    (9 dB) of the stronger one's, both measured through the snapshot's noise. Across the first threshold (the weaker
    at ρ 10, 12, 13 and twice it, 24 dB) and across the second (8.5, 9, 9.5 and twice, 18 dB, below a 30-dB one):
    the fraction of frames in which the detection level reports the weaker one within 0.2 of the chain's. Before,
    the detection level applied the floor without noise and the secondary test not at all: 0.50 against the
    chain's 0.09 at ρ 10 dB, 0.88 against 0.50 at 9 dB, 0.00 against 0.22 at 9.5 dB."""
    p = PRESETS["mimo12"]
    chain = DspChain(p)
    u = (np.array([-1.5, 1.5]) + 0.4) / p.num_virtual
    az = np.degrees(np.arcsin(u / p.element_spacing_wl))
    r, v = np.full(2, 40.2 * p.range_resolution_m), np.full(2, 5.3 * p.doppler_bin_mps)
    scat = point_targets(r, az, v)
    scat.rcs_dbsm = np.array([rho, rho - drop]) - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    seen = {}
    for level in ("detection", "signal"):
        hits = 0
        for seed in range(4200, 4232):
            det = _detections(level, p, chain, scat, seed)
            hits += bool(np.any((np.abs(det.range_m - r[1]) < 2 * p.range_resolution_m)
                                & (np.abs(np.degrees(det.azimuth_rad) - az[1]) < 3.0)))
        seen[level] = hits / 32
    assert abs(seen["detection"] - seen["signal"]) <= 0.2, seen


def test_returns_moved_into_a_maximum_keep_its_angle_resolution():
    """A return at −10° with one on either side of it 0.9 range bins away, at 10° and 8.5° (1.8 bins apart: two
    peaks of their own; in some frames the middle one's cell hides both, each within SHARED_CELL_FLOOR_DB of it
    there): both go into the middle one's cell, where they are closer than RESOLUTION[2] in angle, so they are one
    angle peak there, as the chain's snapshot has one: never two detections on the positive side within half a bin
    of each other, and the −10° one in every frame. (Both sides happen in these eight frames: the two moved, and
    the three standing apart.)"""
    p = PRESETS["ars408_like"]
    stat = DspChain(p).statistic
    r = np.array([40.0, 40.9, 39.1]) * p.range_resolution_m
    scat = point_targets(r, [-10.0, 10.0, 8.5], np.full(3, 5.3 * p.doppler_bin_mps))
    scat.rcs_dbsm = 35.0 - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    shapes = set()
    for seed in range(8):
        det = detection_model.detect(p, scat, np.random.default_rng(seed), stat)
        near = np.abs(det.range_m - r[0]) < 3.0 * p.range_resolution_m
        az, rng_bins = np.degrees(det.azimuth_rad[near]), det.range_m[near] / p.range_resolution_m
        pos = np.sort(rng_bins[az > 0.0])
        assert np.all(np.diff(pos) > 0.5), (seed, az, rng_bins)
        assert np.sum(az < 0.0) == 1, (seed, az)
        shapes.add(int(near.sum()))
    assert shapes == {2, 3}, shapes


@pytest.mark.parametrize("preset", ["ars408_like", "mimo12"])
@pytest.mark.parametrize("centre_beams, sep_beams", [(0.0, 1.0)] + [(c, s) for c in (0.0, 0.5, -0.5, 2.0, -2.0)
                                                                     for s in (1.0 + 1e-6, 2.0)])
def test_two_returns_a_beam_apart_never_share_an_angle_cell(preset, centre_beams, sep_beams):
    """Angle cells are half-open, [k − ½, k + ½) beams: two equal returns more than a beamwidth apart lie in two cells
    wherever the pair sits, and both are reported; so are two exactly one beamwidth apart centred on boresight, at
    ±½ beam, which rint's ties to even put in one cell on ars408_like, resolved in none of the frames where the chain
    resolves 0.85 (an independent tester's finding; on mimo12 rounding happened to split them). Elsewhere a pair
    exactly one beam apart is a tie of floating-point rounding, either way. Just above one beam and at two, centred
    on a cell's middle or its edge on either side, and two beams out."""
    p = PRESETS[preset]
    stat = DspChain(p).statistic
    beam = 1.0 / (p.num_virtual * p.element_spacing_wl)            # one beamwidth in sin θ
    u = (centre_beams + np.array([-0.5, 0.5]) * sep_beams) * beam
    scat = point_targets([40.0, 40.0], np.degrees(np.arcsin(u)), [0.0, 0.0], 0.0)
    scat.rcs_dbsm = 30.0 - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    for seed in range(6):
        det = detection_model.detect(p, scat, np.random.default_rng(seed), stat)
        near = np.abs(det.range_m - 40.0) < 1.0
        assert near.sum() == 2, (seed, np.degrees(det.azimuth_rad[near]))


@pytest.mark.parametrize("preset", ["ars408_like", "mimo12"])
@pytest.mark.parametrize("centre_beams", [0.0, 3.0, -2.0])
@pytest.mark.parametrize("sep_beams, resolved", [(0.35, False), (0.69, False), (0.71, True), (0.9, True)])
def test_two_returns_in_one_angle_cell_are_resolved_as_two_cells_would_be(preset, centre_beams, sep_beams, resolved):
    """Two equal returns in one angle cell (centred on the cell's middle, boresight or off it) are one return below
    the chain's angle resolution (``RESOLUTION[2]``, 0.7 beamwidth) and two at and above it, as two returns in two
    cells are: below it (half and just below), just above it and at 0.9 beam (a cell is one beam wide: twice the
    limit cannot lie in one). Before :func:`detection_model.split_cells` a pair in one cell was never resolved."""
    from radarnode.radar.calibration import RESOLUTION
    assert RESOLUTION[2] == 0.7
    p = PRESETS[preset]
    stat = DspChain(p).statistic
    beam = 1.0 / (p.num_virtual * p.element_spacing_wl)
    u = (centre_beams + np.array([-0.5, 0.5]) * sep_beams) * beam
    scat = point_targets([40.0, 40.0], np.degrees(np.arcsin(u)), [0.0, 0.0], 0.0)
    scat.rcs_dbsm = 30.0 - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    rb, vb, ub = detection_model.apparent_positions(p, scat)
    cells = np.floor(ub * p.num_virtual + 0.5)
    assert cells[0] == cells[1]                          # one angle cell
    for seed in range(6):
        det = detection_model.detect(p, scat, np.random.default_rng(seed), stat)
        near = np.abs(det.range_m - 40.0) < 1.0
        assert near.sum() == (2 if resolved else 1), (seed, np.degrees(det.azimuth_rad[near]))


def test_split_cells_cuts_a_cell_only_between_returns_a_resolution_apart():
    """:func:`detection_model.split_cells` on three cells at once, in a shuffled order: two clusters 0.8 beam apart
    (the near sides of two cars abreast) are cut at the gap between them; a body spread evenly over 0.95 beam and a
    pair 0.6 beam apart are not; a cell of one scatterer is not; the sides do not depend on the input's order."""
    ub = np.concatenate([[-0.45, -0.4, -0.38, 0.37, 0.4], np.linspace(-0.475, 0.475, 11), [-0.3, 0.3], [0.1]])
    cell = np.concatenate([np.full(5, 7), np.full(11, 3), np.full(2, 12), [5]])
    power = np.concatenate([[1.0, 2.0, 1.0, 1.5, 2.5], np.ones(11), [1.0, 1.0], [1.0]])
    side = detection_model.split_cells(cell, ub, power)
    assert side[:5].tolist() == [0, 0, 0, 1, 1]
    assert not side[5:].any()
    perm = np.random.default_rng(3).permutation(cell.size)
    assert np.array_equal(detection_model.split_cells(cell[perm], ub[perm], power[perm]), side[perm])
    # a weak return far from a strong one is cut off too: the centroids, not the powers, decide
    assert detection_model.split_cells(np.zeros(2, dtype=np.int64), np.array([-0.45, 0.3]),
                                       np.array([1.0, 1e-4])).tolist() == [0, 1]
    assert detection_model.split_cells(np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0)).size == 0


def _two_cars_abreast(seed: int, duration_s: float = 9.5) -> str:
    """A straight three-lane road, the ego at 30 m/s in the middle lane, FCW on, no ACC; a car at 20 m/s in each lane
    beside it, their rear 100 m ahead of the sensor at the start (benchmarks/abreast_fcw.py's ars408_like pair 10 m/s
    slower)."""
    return f"""
name: two_cars_abreast
duration_s: {duration_s}
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: 30.0}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1}}
ecu: {{acc_enabled: false, expect: {{no_fcw: true}}}}
actors:
  - {{id: left, class: car, x_m: 105.95, lane: 2, speed_mps: 20.0}}
  - {{id: right, class: car, x_m: 105.95, lane: 0, speed_mps: 20.0}}
"""


def test_two_cars_abreast_within_30_m_are_not_one_return_in_the_ego_lane():
    """Two cars abreast 20–30 m ahead of ars408_like, ±3.5 m: their near sides lie either side of boresight, 0.6–0.8
    beam apart, in one angle cell. The detection level reported one return between them in 0.27 of those frames
    and a radar object in the ego's lane in 0.32 (seeds 1–4) before :func:`detection_model.split_cells`; the chain
    0.07 and none. Now at most a tenth of the frames, and no object in the lane (seeds 1–2)."""
    from radarnode.radar.models import make_model
    from radarnode.radar.object_model import RuntimeConfig
    from radarnode.radar.setup import parse_scenario, radar_config
    from radarnode.scene.world import Scene
    between = in_lane = frames = 0
    for seed in (1, 2):
        sc = parse_scenario(_two_cars_abreast(seed))
        rc = radar_config(sc)
        model = make_model("detection", Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal)
        cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
        for k in range(int(sc.duration_s / sc.period_s)):
            frame, _ = model.step(k * sc.period_s, cfg)
            gap = 100.0 - 10.0 * k * sc.period_s
            if not 20.0 <= gap < 30.0:
                continue
            d = model.info.detections
            x, y = d.range_m * np.cos(d.azimuth_rad), d.range_m * np.sin(d.azimuth_rad)
            o = frame.objects
            frames += 1
            between += bool(np.any((np.abs(x - gap) < 4.0) & (np.abs(y) < 1.5)))
            in_lane += bool(np.any((np.abs(o.dist_long_m - gap) < 6.0) & (np.abs(o.dist_lat_m) < 1.5)))
    assert frames >= 26
    assert between <= 0.1 * frames and in_lane == 0, (between, in_lane, frames)


@pytest.mark.parametrize("seed", [1, 3])
def test_two_cars_abreast_draw_no_fcw_at_the_detection_level_where_the_chain_resolves_them(seed):
    """The pair 10 m/s slower than the ego: FCW's time to collision falls below its threshold 26 m before them, where
    the chain resolves them (none of 12 seeds warned at the signal level); the detection level warned in 10 of 12,
    these seeds among them (for the right car and the left), before :func:`detection_model.split_cells`."""
    from radarnode.radar.setup import parse_scenario
    r = simulate(parse_scenario(_two_cars_abreast(seed)), fidelity="detection")
    assert r.checked and r.passed and r.warning_time_s is None, r.reasons


@pytest.mark.parametrize("axis", ["range", "doppler"])
@pytest.mark.parametrize("sep,joined", [(2.0, True), (4.0 - 1e-9, True), (4.08, False), (8.0, False)])
def test_two_returns_are_one_group_only_within_the_lobe_reach(axis, sep, joined):
    """The groups of :func:`_strongest_of_lost_groups` (returns each within ``LOBE_REACH_BINS``, 4, of the next,
    circular axes): two returns apart from a crowd (which hides some cells, so that the groups are found) are one
    group below and at the reach and two just beyond it and at twice it, along either axis; across the range axis's
    wrap too."""
    from radarnode.radar import detection_model
    p = PRESETS["ars408_like"]
    stat = DspChain(p).statistic
    n = 300
    r, v, u, field, tag, _ = _crowd(n)
    for at in (150.0, p.num_range_bins - 0.5 * sep):          # the second pair astride the range axis's wrap
        a, b = (at, 40.0), (at + sep, 40.0) if axis == "range" else (at, 40.0 + sep)
        rr = np.concatenate([r, [a[0], np.mod(b[0], p.num_range_bins)]])
        vv = np.concatenate([v, [a[1], b[1]]])
        ff = np.concatenate([field, [100.0, 100.0j]])
        args = (rr, vv, np.concatenate([u, [0.0, 0.0]]), ff, np.abs(ff) ** 2, np.concatenate([tag, [7, 8]]),
                p.num_range_bins, p.num_chirps, p.num_virtual, stat)
        hidden, _, group = detection_model._inside_lobes(*args, hiders=True)
        assert hidden.any()
        assert (group[n] == group[n + 1]) == joined
        assert group[n] not in group[:n]           # far from the crowd


@pytest.mark.parametrize("tested", [0.0, 0.4, 1.0])
def test_the_lobe_test_of_some_cells_is_their_answer_among_every_cell(tested):
    """The detection level asks the lobe test about its peaks only (0.4 of the cells on a guardrail road): each
    tested cell's answer is bit for bit the one it has when every cell is tested (every cell still counts as another
    return), and an untested cell is never hidden. Crowded cells (a few hundred within a few bins, several bodies
    and posts) so that many are hidden."""
    from radarnode.radar import detection_model
    p = PRESETS["ars408_like"]
    stat = DspChain(p).statistic
    n = 300
    r, v, u, field, tag, rng = _crowd(n)
    energy = np.abs(field) ** 2
    args = (r, v, u, field, energy, tag, p.num_range_bins, p.num_chirps, p.num_virtual, stat)
    every = detection_model._inside_lobes(*args)
    assert 20 < every.sum() < n - 20               # the crowd hides many, not all
    some = rng.random(n) < tested
    got = detection_model._inside_lobes(*args, some)
    assert np.array_equal(got[some], every[some]) and not got[~some].any()


@pytest.mark.parametrize("name", ["hann", "hamming", "blackman", "boxcar", "blackmanharris"])
@pytest.mark.parametrize("n", [4, 5, 7, 16, 63, 64, 65, 256, 300])
def test_straddle_gain_is_the_windowed_tone_power_summed_directly(name, n):
    """The split sum (e^{iθ(Ba+b)} = e^{iθBa}·e^{iθb}) against Σ_n w_n e^{2πiδn/N} term by term, for square and
    non-square window lengths (the last block padded), on the bin, between bins, at the cell's edge and far out:
    the same powers within 1e-13 (an error in the split or the padding is of order one)."""
    w = window(name, n)
    d = np.concatenate([np.linspace(-0.5, 0.5, 41), [0.0, 1.0, -1.0, 2.5, -7.25, 31.0], np.linspace(-40, 40, 33)])
    direct = np.abs(np.exp(2j * np.pi * np.multiply.outer(d, np.arange(n)) / n) @ w) ** 2 / w.sum() ** 2
    got = ds.straddle_gain(w, d.reshape(4, -1)).ravel()          # (any shape of delta)
    assert got.shape == direct.shape
    np.testing.assert_allclose(got, direct, rtol=1e-12, atol=1e-13)
    assert ds.straddle_gain(w, 0.0) == pytest.approx(1.0, abs=1e-14)


@pytest.mark.parametrize("offset", [(0.0, 0.0), (0.5, 0.5), (0.3, -0.2)])
def test_the_block_draw_has_the_law_of_the_chains_strongest_of_nine_cells(offset):
    """draw_block's statistic (the strongest of the 3 × 3 cells about the return's nearest one) against the same
    nine cells of windowed, FFT-ed cubes of a tone in white noise, brute force: the same quantiles within their
    sampling error. A draw that left out the windows' noise correlation (−2/3 between Hann neighbours) or put the
    return's share in the wrong neighbour moves them by several times that."""
    p = _small_preset()
    stat = DspChain(p).statistic
    c, m, n = p.num_virtual, p.num_chirps, p.num_samples
    w_d, w_r = stat.doppler_window, stat.range_window
    dr, dd = offset
    e0 = 10 ** (14.0 / 10)                    # on-bin windowed energy over the per-cell noise, all channels
    rng = np.random.default_rng(5)
    amp = math.sqrt(e0 * np.sum(w_r ** 2) * np.sum(w_d ** 2)) / (w_r.sum() * w_d.sum())
    kd, kr = 20, 30
    tone = amp * np.exp(2j * np.pi * ((kd + dd) * np.arange(m)[:, None] / m + (kr + dr) * np.arange(n)[None, :] / n))
    scale = math.sqrt(np.sum(w_r ** 2) * np.sum(w_d ** 2))
    cells_d = [kd - 1, kd, kd + 1]                # the 3 × 3 cells about the nearest one
    cells_r = [kr - 1, kr, kr + 1]
    brute = []
    for _ in range(1500):
        cube = (rng.standard_normal((c, m, n)) + 1j * rng.standard_normal((c, m, n))) * math.sqrt(0.5)
        cube[0] += tone
        spec = np.fft.fft2(cube * w_d[None, :, None] * w_r[None, None, :]) / scale
        power = np.sum(np.abs(spec) ** 2, axis=0)
        brute.append(power[np.ix_(cells_d, cells_r)].max())
    near = float(stat.energy(e0 / stat.window_gain, dr, dd))
    drawn = stat.draw_block(np.full(30_000, near), np.full(30_000, dr), np.full(30_000, dd), rng)[1]
    for q in (0.1, 0.5, 0.9):
        b, d = np.quantile(brute, q), np.quantile(drawn, q)
        # the brute-force quantile's sampling error: sqrt(q(1−q)/n) / density, the density from the draws
        dens = np.mean(np.abs(drawn - d) < 1.0) / 2.0
        se = math.sqrt(q * (1 - q) / len(brute)) / dens
        assert abs(b - d) < 4.0 * se + 0.02 * d, (q, b, d, se)


def test_a_return_half_a_bin_off_in_both_axes_is_seen_by_the_chain_as_the_block_draw_says_not_as_one_cell():
    """The chain finds a return that straddles four cells in any of them: its Pd half a bin off in range and in
    Doppler is draw_block's (which the detection level tests its cells with), well above the one-cell test's
    (draw)."""
    p = _small_preset()
    chain = DspChain(p)
    stat = chain.statistic
    rng = np.random.default_rng(8)
    trials = 400
    rho = 18.0
    hits = 0
    for _ in range(trials):
        r = (rng.integers(10, p.num_samples - 10) + 0.5) * p.range_resolution_m
        v = (rng.integers(-20, 20) + 0.5) * p.doppler_bin_mps
        r -= v * p.range_rate_coupling_s                   # the chain's peak sits at the coupled range
        rcs = rho - float(equation.snr_db(p, r, 0.0, azimuth_rad=0.0))
        det = chain.process(synthesize(p, point_targets([r], [0.0], [v], rcs), rng))
        hits += bool(np.any((np.abs(det.range_m - r) < 1.5 * p.range_resolution_m)
                            & (np.abs(det.range_rate_mps - v) < 1.5 * p.speed_resolution_mps)))
    e = np.full(20_000, float(stat.energy(10 ** (rho / 10), 0.5, 0.5)))
    block = stat.draw_block(e, np.full(e.size, 0.5), np.full(e.size, 0.5), rng)[0].mean()
    one_cell = stat.draw(e, rng)[0].mean()
    sig = hits / trials
    se = math.sqrt(0.25 / trials)
    assert abs(block - sig) < 3.0 * se, (block, sig)
    assert sig > one_cell + 4 * se, (one_cell, sig)


def test_a_cells_energy_and_position_are_the_channel_summed_maps():
    """detection_model._cell_sums against the per-channel sums written out: cells of one to four scatterers spread
    over a beam; the energy is the channels' mean of |S_k|², each position the channel-power-weighted glint (the
    centroid of the angle spectrum across the channels), within the span ± half a cell; one channel is the plain
    coherent sum."""
    rng = np.random.default_rng(5)
    inv = np.repeat(np.arange(6), [1, 2, 3, 4, 1, 2])
    z = rng.standard_normal(inv.size) + 1j * rng.standard_normal(inv.size)
    u = rng.uniform(-0.05, 0.05, inv.size)
    rb = 40.0 + rng.uniform(-0.5, 0.5, inv.size)
    vb = -7.0 + rng.uniform(-0.5, 0.5, inv.size)
    field = np.bincount(inv, weights=z.real) + 1j * np.bincount(inv, weights=z.imag)
    for n in (1, 8, 12):
        e, c_r, c_v, c_u = detection_model._cell_sums(z, rb, vb, u, field.copy(), inv, n, 1.0 / max(n, 2))
        for c in range(6):
            s = np.flatnonzero(inv == c)
            snap = [sum(z[i] * np.exp(2j * np.pi * u[i] * k) for i in s) for k in range(n)]
            assert math.isclose(e[c], np.mean(np.abs(snap) ** 2), rel_tol=1e-12)
            for got, x, margin in ((c_r, rb, 0.5), (c_v, vb, 0.5), (c_u, u, 0.5 / max(n, 2))):
                num = [sum(z[i] * x[i] * np.exp(2j * np.pi * u[i] * k) for i in s) for k in range(n)]
                want = sum((a * np.conj(b)).real for a, b in zip(num, snap)) / sum(abs(b) ** 2 for b in snap)
                want = min(max(want, x[s].min() - margin), x[s].max() + margin)
                assert math.isclose(got[c], want, rel_tol=1e-9, abs_tol=1e-12), (n, c, got[c], want)


@pytest.mark.parametrize("beams_apart, fades", [(0.0, True), (1.0 / 3.0, False)])
def test_two_reflectors_of_a_body_in_one_beam_fade_only_as_their_channel_phases_allow(beams_apart, fades):
    """A body's two equal reflectors at one range and speed, in one angle cell: at one angle their random phases
    cancel in every channel alike (the chain loses them in the frames where the two are nearly opposite), a third of
    a beamwidth apart the chain's channel-summed map never falls below 2·(1 − |ρ|) = −4.6 dB of their power sum
    (|ρ| = 0.83, 8 channels). The detection level summed them with one phase for all channels and lost a lead car
    at 25 m (70 dB) in one frame of an NHTSA run; 25 dB above the threshold it must now see them in every frame."""
    p = PRESETS["ars408_like"]
    chain = DspChain(p)
    du = beams_apart / p.num_virtual                         # in d·sinθ
    half = math.asin(du / 2 / p.element_spacing_wl)
    r, v = 30.0 + 0.5 * p.range_resolution_m, 3.0
    az = np.array([-half, half]) if beams_apart else np.array([0.0, 0.0])
    scat = point_targets(np.full(2, r), np.degrees(az), np.full(2, v), 0.0)
    scat.actor_index = np.zeros(2, dtype=np.int64)          # one body
    # 25 dB above the mean threshold for the pair's power sum (two scatterers at −3 dB each)
    thr_db = 10 * math.log10(chain.statistic.threshold_mean() / chain.statistic.window_gain)
    snr = thr_db + 25.0 - 3.0 - 10 * math.log10(p.num_range_bins * p.num_chirps * p.num_virtual)
    rng = np.random.default_rng(3)
    frames = 1500
    seen = sum(bool(np.any(detection_model.detect(p, scat, rng, chain.statistic, snr_db=snr).actor_index == 0))
               for _ in range(frames))
    if fades:
        # P(|cos(φ/2)|² < 10^−2.5 against the mean) ≈ 0.036 with φ uniform: about 54 of 1500 lost
        assert frames - seen >= 20, seen
    else:
        assert seen == frames, seen


@pytest.mark.parametrize("level", ["detection", "signal"])
@pytest.mark.parametrize("snr_db", [1e6, 3000.0, 100.5, -60.5, "5", True])
def test_an_snr_beyond_what_a_scenario_takes_is_refused_by_name_at_both_levels(level, snr_db):
    """The levels' functions take snr_db directly: beyond signal.snr_db's bounds (−60 … 100 dB) or not a number, a
    ConfigError naming it, at both levels (1e6 dB raised a bare OverflowError, 3000 dB came out as a 3054 dB
    detection at the detection level)."""
    p = PRESETS["mimo12"]
    scat = point_targets([30.0], [0.0], [5.0])
    rng = np.random.default_rng(1)
    with pytest.raises(ConfigError, match="snr_db"):
        if level == "detection":
            detection_model.detect(p, scat, rng, DspChain(p).statistic, snr_db=snr_db)
        else:
            synthesize(p, scat, rng, snr_db=snr_db)


def test_a_statistic_built_for_another_preset_is_refused():
    p = PRESETS["mimo12"]
    with pytest.raises(ConfigError, match="statistic.*mimo12"):
        detection_model.detect(p, point_targets([30.0], [0.0], [5.0]), np.random.default_rng(1),
                               DspChain(PRESETS["acc_lrr"]).statistic)


@pytest.mark.parametrize("level", ["detection", "signal"])
@pytest.mark.parametrize("snr_db", [-60.0, -59.5, 99.5, 100.0])
def test_an_snr_at_and_inside_the_bounds_is_taken_at_both_levels(level, snr_db):
    """The other side of the refusal above: −60 and 100 dB themselves, and just inside them, are taken."""
    p = PRESETS["mimo12"]
    scat = point_targets([30.0], [0.0], [5.0])
    rng = np.random.default_rng(1)
    if level == "detection":
        det = detection_model.detect(p, scat, rng, DspChain(p).statistic, snr_db=snr_db)
        assert np.all(np.isfinite(det.snr_db))
    else:
        assert np.all(np.isfinite(synthesize(p, scat, rng, snr_db=snr_db)))


def test_the_block_signal_of_returns_is_the_windowed_spectrum_of_their_tones():
    """DetectionStatistic.block_signal against the windowed 2-D FFT of noise-free tones written out, channel by
    channel and cell by cell: one return, and two returns of one group at their own offsets (up to 2.4 bins from the
    group's cell) and angles, with their own phases; complex values to 1e-6 of the strongest cell. One return's
    nine cells carry draw_block's own rank-one signal: the same energy in every cell."""
    p = _small_preset()
    stat = DspChain(p).statistic
    c, m, n = p.num_virtual, p.num_chirps, p.num_samples
    w_d, w_r = stat.doppler_window, stat.range_window
    scale = math.sqrt(np.sum(w_r ** 2) * np.sum(w_d ** 2))
    kd, kr = 20, 30
    rng = np.random.default_rng(4)
    cases = [([0.3], [-0.2], [0.1]), ([0.45, -0.4], [0.1, 0.35], [0.05, 0.2]), ([2.4, -0.1], [-1.3, 0.2], [-0.3, 0.0])]
    for dr, dd, u in cases:
        dr, dd, u = map(np.array, (dr, dd, u))
        z = 3.0 * np.exp(2j * np.pi * rng.random(dr.size))            # on-bin windowed amplitudes
        cube = np.zeros((c, m, n), dtype=np.complex128)
        for j in range(dr.size):
            a = z[j] * scale / (w_r.sum() * w_d.sum()) / math.sqrt(c)
            tone = a * np.exp(2j * np.pi * ((kd + dd[j]) * np.arange(m)[:, None] / m
                                            + (kr + dr[j]) * np.arange(n)[None, :] / n))
            cube += tone[None] * np.exp(2j * np.pi * u[j] * np.arange(c))[:, None, None]
        spec = np.fft.fft2(cube * w_d[None, :, None] * w_r[None, None, :]) / scale
        want = np.stack([spec[:, kd + t, kr + s] for s in (-1, 0, 1) for t in (-1, 0, 1)], axis=1)   # (c, 9)
        got = stat.block_signal(z, dr, dd, u, np.zeros(dr.size, dtype=np.int64), 1)[0]
        np.testing.assert_allclose(got, want, atol=1e-6 * np.abs(want).max())
    # one return: per cell the energy draw_block's rank-one signal has
    grid, resp_r, resp_d, _ = stat._block_tables()
    e = float(stat.energy(10.0, 0.3, -0.2))
    got = stat.block_signal(np.array([math.sqrt(float(stat.energy(10.0)))]), np.array([0.3]), np.array([-0.2]),
                            np.array([0.1]), np.zeros(1, dtype=np.int64), 1)[0]
    a_r = np.interp(0.3 - np.array([-1.0, 0.0, 1.0]), grid, np.abs(resp_r))
    a_d = np.interp(-0.2 - np.array([-1.0, 0.0, 1.0]), grid, np.abs(resp_d))
    near = float(np.interp(0.3, grid, np.abs(resp_r)) * np.interp(-0.2, grid, np.abs(resp_d)))
    np.testing.assert_allclose(np.sum(np.abs(got) ** 2, axis=0), e / near ** 2 * np.outer(a_r, a_d).ravel() ** 2,
                               rtol=1e-6)


# doppler and angle take 15 s each on the CI machine: -m slow (range, the same test along the axis the chain
# fits finest, runs in CI)
@pytest.mark.parametrize("axis", ["range", pytest.param("doppler", marks=pytest.mark.slow),
                                  pytest.param("angle", marks=pytest.mark.slow)])
def test_where_the_grid_cuts_a_pair_of_reflectors_does_not_change_how_often_it_is_seen(axis):
    """Two equal reflectors of one body a tenth of a cell apart, 4 dB above the threshold's mean: their random
    phases fade the pair as one return |1 + e^{iφ}|² of one at their middle, wherever the cells' grid cuts it. Inside
    one cell and astride a cell's edge the detection level's Pd must be that fading return's, as draw_block (the
    chain's law, tested above) gives it at their middle's offset (the chain's, measured by an independent tester:
    0.70–0.76 either way); summing cells before testing them gave the pair astride the edge Pd 1.00, a return that
    never fades."""
    p = PRESETS["ars408_like"]
    stat = DspChain(p).statistic
    thr_db = 10 * math.log10(stat.threshold_mean() / stat.window_gain)
    snr = thr_db + 4.0 - 3.0 - 10 * math.log10(p.num_range_bins * p.num_chirps * p.num_virtual)
    v0 = 10 * p.doppler_bin_mps
    r0 = 17 * p.range_resolution_m - v0 * p.range_rate_coupling_s
    beam = 1.0 / p.num_virtual

    def pair(centre):
        off = np.array([centre - 0.05, centre + 0.05])
        if axis == "range":
            s = point_targets(r0 + off * p.range_resolution_m, 0.0, np.full(2, v0), 0.0)
        elif axis == "doppler":
            s = point_targets(np.full(2, r0) - off * p.doppler_bin_mps * p.range_rate_coupling_s, 0.0,
                              v0 + off * p.doppler_bin_mps, 0.0)
        else:
            s = point_targets(np.full(2, r0), np.degrees(np.arcsin(off * beam / p.element_spacing_wl)),
                              np.full(2, v0), 0.0)
        s.actor_index = np.zeros(2, dtype=np.int64)
        return s
    frames = 1500
    rho_each = 10 ** ((snr + 10 * math.log10(p.num_range_bins * p.num_chirps * p.num_virtual)) / 10)
    for centre in (0.0, 0.5):
        rng = np.random.default_rng(11)
        scat = pair(centre)
        pd = np.mean([bool(np.any(detection_model.detect(p, scat, rng, stat, snr_db=snr).actor_index == 0))
                      for _ in range(frames)])
        dr, dd = (centre, 0.0) if axis == "range" else (0.0, centre) if axis == "doppler" else (0.0, 0.0)
        phi = rng.uniform(0.0, 2.0 * np.pi, 40_000)
        e = stat.energy(rho_each, dr, dd) * np.abs(1.0 + np.exp(1j * phi)) ** 2
        want = stat.draw_block(e, np.full(e.size, dr), np.full(e.size, dd), rng)[0].mean()
        assert 0.6 < want < 0.85, want                  # a fading pair, not a steady return
        assert abs(pd - want) < 0.04, (centre, pd, want)    # 3.5 standard errors


def test_two_sources_in_one_range_doppler_cell_each_report_their_own_energy_at_both_levels():
    """Two equal reflectors at one range and speed, three beamwidths apart: the chain's map holds both in one
    cell, and its angle peaks share the cell's energy in proportion to their powers — each reflector's own 30 dB,
    at both levels alike. (Until 2026-11-30 the chain gave the strongest peak the whole cell and the other that
    energy times its power over the strongest's, both about 3 dB above either reflector, and this test asked the
    detection level for the same.)"""
    p = PRESETS["mimo12"]
    chain = DspChain(p)
    beam = 1.0 / p.num_virtual
    az = np.degrees(np.arcsin(np.array([-1.5, 1.5]) * beam / p.element_spacing_wl))
    r, v = 30.0 + 0.3 * p.range_resolution_m, 2.0
    scat = point_targets(np.full(2, r), az, np.full(2, v), 0.0)
    snr = 30.0 - 10 * math.log10(p.num_range_bins * p.num_chirps * p.num_virtual)     # ρ 30 dB each
    got = {}
    for level in ("detection", "signal"):
        rng = np.random.default_rng(6)
        rows = []
        for _ in range(30 if level == "signal" else 120):
            det = (detection_model.detect(p, scat, rng, chain.statistic, snr_db=snr) if level == "detection"
                   else chain.process(synthesize(p, scat, rng, snr_db=snr)))
            near = np.abs(det.range_m - r) < 2 * p.range_resolution_m
            if near.sum() == 2:
                rows.append(np.sort(det.snr_db[near]))
        assert len(rows) >= 20, (level, len(rows))
        got[level] = np.mean(rows, axis=0)
    for level, (weaker, stronger) in got.items():
        assert abs(stronger - 30.0) < 0.6 and abs(weaker - 30.0) < 0.6, (level, weaker, stronger)
    assert np.all(np.abs(got["detection"] - got["signal"]) < 0.6), got


def _one_body(p, ranges_bins, doppler_bins):
    """Reflectors of one body at the given range and Doppler bins (the chain's peak at the coupled range)."""
    v = np.asarray(doppler_bins, dtype=float) * p.doppler_bin_mps
    r = np.asarray(ranges_bins, dtype=float) * p.range_resolution_m - v * p.range_rate_coupling_s
    s = point_targets(r, 0.0, v, 0.0)
    s.actor_index = np.zeros(len(r), dtype=np.int64)
    return s


@pytest.mark.parametrize("doppler", [10.0, -20.0])
def test_a_pair_astride_a_range_edge_is_reported_within_its_span_opening_or_closing(doppler):
    """Two equal reflectors at range bins 17.35 and 17.65 (one each side of an edge), 10 dB above the threshold,
    opening and closing: the detection level reports them within their span (at the stronger cell's reflector; the
    chain about their middle, README's known limit), with the range–Doppler coupling taken out with the speed as
    measured (a closing body's peak placed from its cell's index in [0, M) once took it out a Doppler span off)."""
    p = PRESETS["ars408_like"]
    stat = DspChain(p).statistic
    thr_db = 10 * math.log10(stat.threshold_mean() / stat.window_gain)
    snr = thr_db + 10.0 - 3.0 - 10 * math.log10(p.num_range_bins * p.num_chirps * p.num_virtual)
    scat = _one_body(p, [17.35, 17.65], [doppler, doppler])
    rng = np.random.default_rng(2)
    got = []
    for _ in range(400):
        det = detection_model.detect(p, scat, rng, stat, snr_db=snr)
        near = det.actor_index == 0
        if near.any():
            v = det.range_rate_mps[near][0]
            got.append((det.range_m[near][0] + v * p.range_rate_coupling_s) / p.range_resolution_m)
    assert len(got) > 300
    assert 17.3 < np.mean(got) < 17.7, np.mean(got)
    assert np.all(np.abs(np.array(got) - 17.5) < 0.5), (np.min(got), np.max(got))


@pytest.mark.parametrize("name", ["mimo12", "ars408_like"])
def test_a_body_astride_the_alias_speed_is_reported_there_not_standing(name):
    """Two reflectors of one body 0.3 Doppler bin apart astride +v_max (one aliases to −v_max): the chain reports
    the body at ±v_max and at its range; the detection level averaged the two aliased speeds as numbers and reported
    a standing object (0 m/s) in almost every frame, and took the range–Doppler coupling out with the wrong sign."""
    p = PRESETS[name]
    stat = DspChain(p).statistic
    m = p.num_chirps
    scat = _one_body(p, [17.0, 17.0], [m / 2 - 0.15, m / 2 + 0.15])
    rng = np.random.default_rng(4)
    speeds, ranges = [], []
    for _ in range(200):
        det = detection_model.detect(p, scat, rng, stat, snr_db=-5.0)
        near = det.actor_index == 0
        speeds += list(det.range_rate_mps[near] / p.doppler_bin_mps)
        ranges += list((det.range_m[near] + det.range_rate_mps[near] * p.range_rate_coupling_s)
                       / p.range_resolution_m)
    assert len(speeds) > 150
    assert np.all(np.abs(speeds) > m / 2 - 2.0), np.min(np.abs(speeds))
    assert np.median(np.abs(speeds)) > m / 2 - 0.5, np.median(np.abs(speeds))
    assert np.all(np.abs(np.array(ranges) - 17.0) < 0.5), (np.min(ranges), np.max(ranges))


def test_the_block_draw_refuses_a_signal_that_does_not_fit_its_rows():
    stat = DspChain(_small_preset()).statistic
    rng = np.random.default_rng(1)
    e = np.ones(3)
    with pytest.raises(ConfigError, match="signal"):
        stat.draw_block(e, np.zeros(3), np.zeros(3), rng, signal=np.zeros((1, stat.n_channels, 9)))
    with pytest.raises(ConfigError, match="signal"):
        stat.draw_block(e, np.zeros(3), np.zeros(3), rng, signal=np.zeros((1, stat.n_channels, 9)),
                        signal_rows=np.array([3]))
    with pytest.raises(ConfigError, match="group"):
        stat.block_signal(np.ones(2), np.zeros(2), np.zeros(2), np.zeros(2), np.array([0, -1]), 2)


@pytest.mark.parametrize("car_dbsm, post_dbsm, other, expected", [
    (10.0, -10.0, -1, 0),        # a car and a post in one cell: the car's detection
    (-10.0, 10.0, -1, -1),       # a strong post beside a weak car: the post's
    (3.0, -3.0, 1, 0),           # two cars: the stronger
    (-3.0, 3.0, 1, 1),
    (10.0, 10.0, 0, 0),          # one body in the cell
])
def test_a_mixed_cell_is_tagged_with_the_actor_that_puts_most_power_into_it(car_dbsm, post_dbsm, other, expected):
    """The detection level's truth tag (evaluation only): a cell whose scatterers belong to several actors was tagged
    −1, so a car in a guardrail post's cell was reported as no actor in those cycles and a scenario's check took the
    car's FCW warning for someone else's. Now the actor with most power in the cell; the detections are the same."""
    p = PRESETS["ars408_like"]
    chain = DspChain(p)
    r, v = 40.0 + 0.5 * p.range_resolution_m, -5.0
    scat = point_targets(np.full(2, r), np.zeros(2), np.full(2, v), np.array([car_dbsm, post_dbsm]))
    scat.actor_index = np.array([0, other], dtype=np.int64)
    det = detection_model.detect(p, scat, np.random.default_rng(5), chain.statistic)
    near = np.abs(det.range_m - r) < 2 * p.range_resolution_m
    assert np.count_nonzero(near) == 1
    assert int(det.actor_index[near][0]) == expected
    # the same detections whatever the tags say
    same = point_targets(np.full(2, r), np.zeros(2), np.full(2, v), np.array([car_dbsm, post_dbsm]))
    same.actor_index = np.array([0, 0], dtype=np.int64)
    ref = detection_model.detect(p, same, np.random.default_rng(5), chain.statistic)
    np.testing.assert_array_equal(ref.range_m, det.range_m)
    np.testing.assert_array_equal(ref.snr_db, det.snr_db)


# --- the reading of a detected return, drawn with its detection (the object level's cluster RCS) ---------------------

def test_the_normal_quantile_and_cdf_without_scipy_match_scipy():
    """:func:`normal_isf` (Acklam) and :func:`normal_cdf` (Abramowitz–Stegun) against scipy's, over the whole range
    the readings use: relative 1.2e-9 and absolute 3e-7."""
    import scipy.special
    p = np.concatenate([np.geomspace(1e-300, 0.5, 3000), 1.0 - np.geomspace(1e-16, 0.5, 3000)])
    ref = -scipy.special.ndtri(p)
    assert np.max(np.abs(ds.normal_isf(p) - ref) / np.maximum(np.abs(ref), 1e-3)) < 1.2e-9
    z = np.linspace(-8.0, 8.0, 16001)
    assert np.max(np.abs(ds.normal_cdf(z) - scipy.special.ndtr(z))) < 3e-7


@pytest.mark.parametrize("n_channels, tol_db", [(1, 0.55), (2, 0.4), (12, 0.12), (48, 0.04), (192, 0.015)])
def test_the_statistic_s_quantile_matches_the_noncentral_chi_square(n_channels, tol_db):
    """:func:`statistic_isf` (Patnaik's central approximation with the Wilson–Hilferty cube) against
    ``scipy.stats.ncx2.isf``: the energy it reads, x − N, within ``tol_db`` over E = 3 … 1e5 and s = 1e-4 … 0.9
    wherever x − N is above half the energy (where a detected return lies)."""
    s = np.array([1e-4, 1e-3, 0.01, 0.1, 0.5, 0.9])[:, None]
    e = np.array([3.0, 5.0, 10.0, 30.0, 100.0, 1e3, 1e5])[None, :]
    exact = scipy.stats.ncx2.isf(s, 2 * n_channels, 2.0 * e) / 2.0 - n_channels
    approx = ds.statistic_isf(s, e, n_channels) - n_channels
    use = exact > 0.5 * e
    err = np.abs(10.0 * np.log10(np.maximum(approx, 1e-9) / np.maximum(exact, 1e-9)))[use]
    assert use.sum() >= 30 and err.max() < tol_db, err.max()


def _mimo12_statistic():
    return DspChain(PRESETS["mimo12"], DspConfig()).statistic


@pytest.mark.parametrize("pd_target", [0.05, 0.3, 0.7, 0.97])
def test_a_detected_fluctuation_follows_its_posterior_against_rejection_sampling(pd_target):
    """:meth:`fluctuation_given_detection` against an independent reference: Exp(1) fluctuations kept with
    probability Pd₀(ρ·g) (rejection sampling from the prior). Quantiles 10/50/90 % within 3 %; far above the
    threshold the posterior is the prior (median ln 2)."""
    stat = _mimo12_statistic()
    grid = np.arange(0.0, 40.0, 0.01)
    rho_db = float(grid[np.argmin(np.abs(stat.pd_of_snr(grid, 1) - pd_target))])
    rng = np.random.default_rng(7)
    g = rng.exponential(size=2_000_000)
    kept = g[rng.random(g.size) < stat.pd_of_snr(rho_db + 10.0 * np.log10(g), 0)]
    assert kept.size > 50_000
    q = np.array([0.1, 0.5, 0.9])
    got = stat.fluctuation_given_detection(np.full(3, rho_db), q)
    np.testing.assert_allclose(got, np.quantile(kept, q), rtol=0.03)
    if pd_target < 0.5:
        assert got[1] > 1.5 * math.log(2.0)           # faded up
    far = stat.fluctuation_given_detection(np.full(3, 55.0), q)
    np.testing.assert_allclose(far, -np.log1p(-q), rtol=0.01)


def test_the_posterior_table_built_row_by_row_answers_as_one_built_at_once():
    """:meth:`fluctuation_given_detection` builds its table's rows when first asked for: a statistic asked in four
    calls (rows in any order, overlapping, the grid's ends and beyond) answers each call bit for bit as a new one
    asked only that call, and builds only the rows asked for."""
    shared = _mimo12_statistic()                     # (one a process: a new one takes its Pd tables, not its rows)

    def new_statistic():
        stat = ds.DetectionStatistic(shared.cfar, shared.range_window, shared.doppler_window)
        stat.import_tables(shared.export_tables())
        return stat

    rng = np.random.default_rng(11)
    calls = [rng.uniform(20.0, 30.0, 50), rng.uniform(-45.0, 75.0, 400), np.array([-30.0, 60.0, 25.04, 25.06]),
             rng.uniform(0.0, 22.0, 300)]
    stat = new_statistic()
    asked = set()
    for rho in calls:
        w = rng.random(rho.size)
        w[:2] = [0.0, 1.0]
        np.testing.assert_array_equal(stat.fluctuation_given_detection(rho, w),
                                      new_statistic().fluctuation_given_detection(rho, w))
        asked |= set(np.clip(np.rint((rho + 30.0) / 0.1), 0, 900).astype(int).tolist())
        rows = stat._posterior[0]
        assert list(rows) == sorted(asked)

@pytest.mark.parametrize("swerling", [0, 1])
@pytest.mark.parametrize("pd_target", [0.1, 0.5, 0.9])
def test_the_reading_of_a_detected_return_matches_the_one_cell_test_drawn_with_a_signal(swerling, pd_target):
    """:meth:`DetectionStatistic.reading` against the detection level's own one-cell test, drawn with a signal
    (:meth:`DetectionStatistic.draw`: the cell's statistic with its noise, a random CFAR threshold, a position
    uniform in the cell, a Swerling 1 energy drawn from the exponential law first): of the returns it detects,
    the integrated SNR read (statistic less N over the window's and straddle's loss at the position) over the
    mean. The quartiles and the median of the two within 0.35 dB, at Pd 0.1, 0.5 and 0.9."""
    stat = _mimo12_statistic()
    grid = np.arange(0.0, 40.0, 0.01)
    rho_db = float(grid[np.argmin(np.abs(stat.pd_of_snr(grid, swerling) - pd_target))])
    rng = np.random.default_rng(3)
    n = 400_000
    dr, dd = rng.uniform(-0.5, 0.5, n), rng.uniform(-0.5, 0.5, n)
    e = stat.energy(10.0 ** (rho_db / 10.0), dr, dd)
    if swerling:
        e = e * rng.exponential(size=n)
    hit, x = stat.draw(e, rng)
    ref = (x[hit] - stat.n_channels) / stat.energy(10.0 ** (rho_db / 10.0), dr[hit], dd[hit])
    u = rng.random(n)
    pd = stat.pd_of_snr(np.full(n, rho_db), swerling)
    det = u < pd
    got = stat.reading(np.full(det.sum(), rho_db), u[det] / pd[det], rng.random(det.sum()), swerling == 1)
    q = [0.25, 0.5, 0.75]
    diff = 10.0 * np.log10(np.quantile(got, q) / np.quantile(np.maximum(ref, 1e-9), q))
    assert np.max(np.abs(diff)) < 0.35, (rho_db, diff)
    assert hit.mean() == pytest.approx(pd_target, abs=0.03)


def test_a_deep_fade_far_above_the_threshold_reads_as_deep_as_the_chain_reads_it():
    """A Swerling 1 return at ρ = 40 dB on mimo12: its readings reach below −20 dB, 3–5 % of them lie below −12.9 dB
    (the detection and signal levels' 3.4 and 4.4 %, down to −22.0 and −21.1 dB; Exp(1) would have 5.0 %, less the
    deep fades the test misses), none pile up on a floor (a floor at −13 dB held 4 % of them: an independent
    tester's finding), and its quartiles are Exp(1)'s (−5.4, −1.6, +1.4 dB) within 0.1 dB."""
    stat = _mimo12_statistic()
    rng = np.random.default_rng(9)
    n = 200_000
    read_db = 10.0 * np.log10(stat.reading(np.full(n, 40.0), rng.random(n), rng.random(n), True))
    assert read_db.min() < -20.0 and 0.03 < np.mean(read_db < -12.9) < 0.05
    assert np.max(np.unique(np.round(read_db, 3), return_counts=True)[1]) < 50
    np.testing.assert_allclose(np.percentile(read_db, [25, 50, 75]), [-5.41, -1.59, 1.42], atol=0.1)


@pytest.mark.parametrize("swerling, rho_db, ring, tol_db", [(1, 40.0, 10.0, 0.15), (1, 40.0, 30.0, 0.15),
                                                             (1, 20.0, 0.3, 0.15), (0, 22.0, 1.0, 0.3),
                                                             (0, 19.0, 0.3, 0.35)])
def test_the_reading_of_a_masked_return_matches_the_one_cell_test_with_interference(swerling, rho_db, ring, tol_db):
    """Other targets' energy in the training ring (``ring`` × the noise's training sum) raises the CA-CFAR threshold,
    so the returns the test still detects are the ones that faded up: against the one-cell test drawn with that
    interference (:meth:`DetectionStatistic.draw`), :meth:`DetectionStatistic.reading` with the masking's
    equivalent loss (:meth:`snr_of_pd` of the Pd alone and masked) reads every quartile within 0.15 dB for
    Swerling 1 (the masked Pd 0.37–0.9 here) and 0.3–0.35 dB for a steady return (the loss is an approximation:
    a raised threshold is not a lower SNR). Without it (as until 2026-12-03) it read as if nothing masked: on
    ``ars408_like`` ten fluctuating points 8 m apart read 1–1.3 dB low at their lower quartile, an independent
    tester's finding; here the loss must matter (> 0.5 dB)."""
    stat = _mimo12_statistic()
    interference = ring * stat.n_channels * stat.eigenvalues.sum()
    rng = np.random.default_rng(5)
    n = 400_000
    dr, dd = rng.uniform(-0.5, 0.5, n), rng.uniform(-0.5, 0.5, n)
    mean = stat.energy(10.0 ** (rho_db / 10.0), dr, dd)
    e = mean * rng.exponential(size=n) if swerling else mean
    hit, x = stat.draw(e, rng, interference=interference)
    ref = np.maximum((x[hit] - stat.n_channels) / mean[hit], 1e-9)
    alone = stat.pd_of_snr(rho_db, swerling)
    masked = alone * stat.masking_factor(rho_db, interference, swerling)
    assert hit.mean() == pytest.approx(masked, abs=0.02)          # (the masking table, interpolated)
    loss = float(stat.snr_of_pd(alone, swerling) - stat.snr_of_pd(masked, swerling))
    q = [0.25, 0.5, 0.75]
    m = int(hit.sum())
    diffs = []
    for lost in (loss, 0.0):
        got = stat.reading(np.full(m, rho_db), rng.random(m), rng.random(m), swerling == 1, lost)
        diffs.append(10.0 * np.log10(np.quantile(got, q) / np.quantile(ref, q)))
    assert loss > 0.0 and np.max(np.abs(diffs[0])) < tol_db, (loss, diffs[0])
    assert np.max(np.abs(diffs[1])) > 0.5, diffs[1]


def test_snr_of_pd_inverts_pd_of_snr():
    """:meth:`snr_of_pd` is :meth:`pd_of_snr`'s inverse where the Pd rises (within 0.01 dB), both Swerling cases."""
    stat = _mimo12_statistic()
    rho = np.arange(5.0, 35.0, 0.37)
    for swerling in (0, 1):
        pd = stat.pd_of_snr(rho, swerling)
        rising = (pd > 1e-4) & (pd < 1.0 - 1e-6)
        np.testing.assert_allclose(stat.snr_of_pd(pd[rising], swerling), rho[rising], atol=0.01)


@pytest.mark.parametrize("field", ["rho_db", "loss_db"])
@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_reading_refuses_a_value_that_is_not_finite_by_name(field, bad):
    """:meth:`DetectionStatistic.reading` given a NaN or an infinite SNR or loss: a ValueError that names it, not an
    IndexError from deep inside the posterior's table (an independent tester's finding)."""
    stat = _mimo12_statistic()
    args = {"rho_db": np.array([20.0, 25.0]), "loss_db": np.array([0.0, 1.0])}
    args[field] = np.array([20.0, bad])
    with pytest.raises(ValueError, match=field):
        stat.reading(args["rho_db"], np.array([0.5, 0.5]), np.array([0.5, 0.5]), True, args["loss_db"])


@pytest.mark.parametrize("field, bad", [("v", math.nan), ("v", 2.0), ("v", -0.1), ("w", math.nan), ("w", 5.0),
                                        ("w", -0.5), ("rho_db", 1e308), ("fluctuating", math.nan)])
def test_reading_refuses_a_uniform_outside_its_range_a_huge_snr_and_a_nan_flag_by_name(field, bad):
    """:meth:`DetectionStatistic.reading`'s uniforms outside [0, 1], an SNR beyond ±300 dB and a fluctuation flag
    that is not boolean are refused by name: before, v = 2 read −315 dB, v ≤ 0 +17 dB, w = 5 ×28, a NaN v read NaN,
    1e308 dB NaN with overflow warnings and a NaN flag counted as True (an independent tester's findings)."""
    stat = _mimo12_statistic()
    args = {"rho_db": np.array([20.0, 25.0]), "v": np.array([0.5, 0.5]), "w": np.array([0.5, 0.5]),
            "fluctuating": np.array([True, True])}
    args[field] = np.array([args[field][0], bad])
    with pytest.raises(ValueError, match=field):
        stat.reading(args["rho_db"], args["v"], args["w"], args["fluctuating"])


def test_the_posterior_the_inverse_and_the_masking_refuse_values_outside_their_range():
    """``fluctuation_given_detection`` with w outside [0, 1] (1.5 had given 32.5, −0.5 1e-8), ``snr_of_pd`` with a NaN
    or a probability above 1, ``masking_factor`` with a NaN interference (read as unmasked): each a ValueError naming
    the argument; the edges themselves are taken."""
    stat = _mimo12_statistic()
    for w in (1.5, -0.5):
        with pytest.raises(ValueError, match="w"):
            stat.fluctuation_given_detection(np.array([20.0]), np.array([w]))
    assert np.all(np.isfinite(stat.fluctuation_given_detection(np.array([20.0, 20.0]), np.array([0.0, 1.0]))))
    for pd in (math.nan, 1.5):
        with pytest.raises(ValueError, match="pd"):
            stat.snr_of_pd(np.array([pd]))
    assert np.all(np.isfinite(stat.snr_of_pd(np.array([0.0, 1.0]))))
    with pytest.raises(ValueError, match="interference"):
        stat.masking_factor(np.array([20.0]), np.array([math.nan]))
