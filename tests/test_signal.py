"""Signal level and detection level: the source documents' cases, recovered through the real DSP chain."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.radar.chain import DspChain
from radarnode.radar import detection_model, equation
from radarnode.radar.presets import PRESETS
from radarnode.radar.scatterers import point_targets
from radarnode.radar.signal_model import synthesize


def _match(det, r_true, v_true, az_true_deg):
    """Nearest detection (in bins) to each truth: (range error m, speed error m/s, azimuth error deg)."""
    out = []
    for r, v, a in zip(r_true, v_true, az_true_deg):
        cost = np.abs(det.range_m - r) + np.abs(det.range_rate_mps - v) + np.abs(np.degrees(det.azimuth_rad) - a) / 5
        k = int(np.argmin(cost))
        out.append((det.range_m[k] - r, det.range_rate_mps[k] - v, math.degrees(det.azimuth_rad[k]) - a))
    return np.array(out)


def _run(preset, r, v, az, seed, **kw):
    scat = point_targets(r, az, v, kw.pop("rcs_dbsm", 10.0))
    cube = synthesize(preset, scat, np.random.default_rng(seed), **kw)
    return DspChain(preset).process(cube)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_seed000_three_point_targets_at_minus_5_db(seed):
    """Seed 000: 30/40/50 m, −40/30/10°, −20/0/15 m/s, SNR −5 dB, the 12-element mimo12 radar."""
    p = PRESETS["mimo12"]
    r, v, az = [30.0, 40.0, 50.0], [-20.0, 0.0, 15.0], [-40.0, 30.0, 10.0]
    det = _run(p, r, v, az, seed, snr_db=-5.0)
    err = _match(det, r, v, az)
    assert np.all(np.abs(err[:, 0]) <= p.range_resolution_m / 4)
    assert np.all(np.abs(err[:, 1]) <= p.speed_resolution_mps / 4)
    assert np.all(np.abs(err[:, 2]) <= math.degrees(p.angular_resolution_rad) / 10)
    assert len(det) == 3     # no false alarm at Pfa 1e-6 over 65 536 cells (expected 0.07)


def test_seed003_car_and_truck_range_and_speed():
    """Seed 003: ego 100 km/h; car 50 m ahead at 60 km/h, truck 150 m ahead at 130 km/h.

    Seed 003 counts approaching speed positive (11.1 and −8.3 m/s); radarnode's range rate is negative
    when closing.
    """
    p = PRESETS["acc_lrr"]
    r = [50.0, 150.0]
    v = [-(100 - 60) / 3.6, (130 - 100) / 3.6]
    det = _run(p, r, v, [0.0, 0.0], 3, rcs_dbsm=[10.0, 20.0])
    err = _match(det, r, v, [0.0, 0.0])
    assert -det.range_rate_mps[np.argmin(np.abs(det.range_m - 50))] == pytest.approx(11.1, abs=p.speed_resolution_mps / 4)
    assert -det.range_rate_mps[np.argmin(np.abs(det.range_m - 150))] == pytest.approx(-8.3, abs=p.speed_resolution_mps / 4)
    assert np.all(np.abs(err[:, 0]) <= p.range_resolution_m / 4)


def test_seed003_three_cars_doa_with_a_4_element_ula():
    """Seed 003's DOA scene: 20 m at 0°, 40.05 m at −2.9°, 80.03 m at 1.4° (85, 125, 110 km/h; ego 100)."""
    p = PRESETS["acc_lrr"]
    r, az = [20.0, 40.05, 80.03], [0.0, -2.9, 1.4]
    v = [(85 - 100) / 3.6, (125 - 100) / 3.6, (110 - 100) / 3.6]
    det = _run(p, r, v, az, 4)
    err = _match(det, r, v, az)
    res_deg = math.degrees(p.angular_resolution_rad)          # 28.6° for 4 elements at λ/2
    assert np.all(np.abs(err[:, 2]) <= res_deg / 20)
    assert np.all(np.abs(err[:, 0]) <= p.range_resolution_m / 4)


def test_seed004_table1_errors_no_larger_than_the_paper():
    """Seed 004, table 1: truth and the paper's measured values; our errors must not be larger.

    The paper prints whole degrees, so its 0° target shows no error; we hold that one to 0.05°.
    """
    p = PRESETS["fast_chirp"]
    r = np.array([10.0, 60.21, 60.21, 90.55])
    v = np.array([10.0, 14.95, 3.99, 4.97])
    az = np.array([0.0, 4.76, -4.76, -6.34])
    paper = np.array([[10.5, 60.75, 60.75, 90.75], [10.11, 14.86, 3.86, 5.05], [0.0, 5.0, -5.0, -6.0]])
    allowed = np.abs(paper - np.stack([r, v, az]))
    allowed[2, 0] = 0.05
    det = _run(p, r, v, az, 5)
    err = np.abs(_match(det, r, v, az)).T
    assert np.all(err <= allowed), (err, allowed)


def test_complex64_costs_little_accuracy():
    p = PRESETS["mimo12"]
    r, v, az = [30.0, 40.0, 50.0], [-20.0, 0.0, 15.0], [-40.0, 30.0, 10.0]
    e64 = np.abs(_match(_run(p, r, v, az, 7, snr_db=0.0, dtype=np.complex64), r, v, az))
    e128 = np.abs(_match(_run(p, r, v, az, 7, snr_db=0.0), r, v, az))
    np.testing.assert_allclose(e64, e128, atol=1e-3)


def test_detection_model_agrees_with_the_signal_chain():
    p = PRESETS["mimo12"]
    r, v, az = [30.0, 40.0, 50.0], [-20.0, 0.0, 15.0], [-40.0, 30.0, 10.0]
    det = detection_model.detect(p, point_targets(r, az, v, 10.0), np.random.default_rng(0), DspChain(p).statistic)
    sig = _run(p, r, v, az, 0)
    e_det, e_sig = np.abs(_match(det, r, v, az)), np.abs(_match(sig, r, v, az))
    for e in (e_det, e_sig):
        assert np.all(e[:, 0] <= p.range_resolution_m / 4) and np.all(e[:, 1] <= p.speed_resolution_mps / 4)
    # both estimate the same integrated SNR, the true one, within its statistical spread (±1 dB at 50 dB)
    truth = equation.snr_db(p, np.array(r), 10.0, azimuth_rad=np.radians(az))
    for d in (det, sig):
        assert len(d) == 3
        order = np.argsort(d.range_m)
        np.testing.assert_allclose(d.snr_db[order], truth, atol=1.0)


# standing (no coupling) takes 11 s: -m slow (CI's 20 minutes; the moving case, this test's own, runs in CI)
@pytest.mark.parametrize("v", [pytest.param(0.0, marks=pytest.mark.slow), 30.0])
def test_detection_model_has_the_chains_pd_where_the_coupling_moves_the_peak(v):
    """A point target on a range-bin centre at ρ = 20 dB: at 30 m/s the range–Doppler coupling moves its peak 0.42
    bin off that centre in the chain's map, with the straddle loss that brings; the detection level puts its peak
    there too, so its Pd is the chain's (200 frames each, fixed seeds; with the peak kept on the centre the
    detection level had 0.980 against the chain's 0.863 over 300 frames, an independent tester's run)."""
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS["mimo12"]
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    r0, vmax = 114 * p.range_resolution_m, p.alias_speed_mps
    per_sample = 20.0 - 10.0 * math.log10(n * m * c)
    chain = DspChain(p)
    hits = {"detection": 0, "signal": 0}
    frames = 200
    for t in range(frames):
        scat = point_targets([r0], [10.0], [v], 0.0)
        for level in hits:
            rng = np.random.default_rng(7000 + t)
            det = detection_model.detect(p, scat, rng, chain.statistic, snr_db=per_sample) if level == "detection" \
                else chain.process_rd(synthesize_rd(p, scat, rng, snr_db=per_sample))
            dv = (det.range_rate_mps - v + vmax) % (2 * vmax) - vmax
            hits[level] += bool(len(det) and np.any((np.abs(det.range_m - r0) < 1.5) & (np.abs(dv) < 1.0)))
    pd = {k: h / frames for k, h in hits.items()}
    assert abs(pd["detection"] - pd["signal"]) < 0.08, pd   # two Pd near 0.9, 200 frames each: σ of the difference 0.03


def test_cells_merge_in_the_detection_model():
    p = PRESETS["mimo12"]
    # two scatterers 0.1 m and 0.5° apart share one cell: one detection between them, tagged with one of the two
    # (the one that puts most power into the cell; tests/test_detection_stats.py has the rule)
    scat = point_targets([40.0, 40.1], [5.0, 5.5], [3.0, 3.0], [10.0, 10.0])
    scat.actor_index[:] = [0, 1]
    det = detection_model.detect(p, scat, np.random.default_rng(0), DspChain(p).statistic)
    assert len(det) == 1 and det.actor_index[0] in (0, 1)
    assert 39.8 < det.range_m[0] < 40.4


def test_the_cube_depends_only_on_the_seed():
    """Noise is drawn on a second thread; the numbers must still be those of the seed."""
    p = PRESETS["mimo12"]
    scat = point_targets([30.0, 40.0], [0.0, 10.0], [1.0, 2.0])
    cubes = [synthesize(p, scat, np.random.default_rng(3)) for _ in range(3)]
    assert all(np.array_equal(cubes[0], c) for c in cubes[1:])
    assert not np.array_equal(cubes[0], synthesize(p, scat, np.random.default_rng(4)))


def test_signal_level_accuracy_within_1_3_of_the_cramer_rao_bound_at_25_db():
    """Issue 9 item 7: range, range rate and azimuth RMSE ≤ 1.3× the CRB at the integrated SNR ρ (here
    25 dB; the benchmark sweeps 20–50 dB), through the range–Doppler synthesis and the whole chain."""
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS["mimo12"]
    chain = DspChain(p)
    rho_db, r0, az0 = 25.0, 42.3, 17.0
    snr_sample = rho_db - 10.0 * math.log10(num_range_samples(p) * p.num_chirps * p.num_virtual)
    rng = np.random.default_rng(11)
    err = []
    for _ in range(120):
        v = -3.0 + 6.0 * rng.random()
        det = chain.process_rd(synthesize_rd(p, point_targets([r0], [az0], [v], 0.0), rng, snr_db=snr_sample))
        err.append(_match(det, [r0], [v], [az0])[0])
    err = np.array(err)
    crb = (equation.crb_range_m(p, rho_db), equation.crb_speed_mps(p, rho_db),
           math.degrees(equation.crb_azimuth_rad(p, rho_db, math.radians(az0))))
    ratio = np.sqrt(np.mean(err ** 2, axis=0)) / np.asarray(crb, dtype=np.float64)
    assert np.all(ratio <= 1.3), ratio


@pytest.mark.parametrize("preset", ["mimo12", "ars408_like"])
# 4 bins, between the two in CI: -m slow (CI's 20 minutes)
@pytest.mark.parametrize("bins", [3.0, pytest.param(4.0, marks=pytest.mark.slow), 6.0])
def test_a_neighbour_a_few_bins_away_leaves_the_signal_levels_accuracy_at_the_bound(preset, bins):
    """Two equal returns ``bins`` range bins apart (0.4 Doppler bin, 4° apart), ρ = 30 dB, 100 frames: range, range
    rate and azimuth RMSE of both within 1.4× the CRB (measured over 200 draws: 1.13–1.33×; one alone 1.09–1.20×). The patch fit stopped 3 bins short of the neighbour's peak, and lost
    2.2× (3 bins), 1.8× (4) and 1.5× (6) in range on ars408_like, where the detection level (which models one
    return's patch fit) stayed at 1.2× (an independent tester's finding); now the patches cut short are fitted
    again, wider, with the other peaks' tones taken out (PatchFit.refit)."""
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS[preset]
    chain = DspChain(p)
    rho_db = 30.0
    snr_sample = rho_db - 10.0 * math.log10(num_range_samples(p) * p.num_chirps * p.num_virtual)
    rng = np.random.default_rng(21)
    r = np.array([40.3, 40.3 + bins * p.range_resolution_m])
    v, az = np.array([0.7, 0.7 + 0.4 * p.doppler_bin_mps]), np.array([0.0, 4.0])
    err = []
    for _ in range(100):
        # the same ρ for both (point_targets' RCS makes the nearer one stronger by the range's fourth power)
        rcs = 40.0 * np.log10(r / r[0])
        det = chain.process_rd(synthesize_rd(p, point_targets(r, az, v, rcs), rng, snr_db=snr_sample))
        err.append(_match(det, r, v, az))
    err = np.concatenate(err)
    crb = (equation.crb_range_m(p, rho_db), equation.crb_speed_mps(p, rho_db),
           math.degrees(equation.crb_azimuth_rad(p, rho_db, math.radians(2.0))))
    ratio = np.sqrt(np.mean(err ** 2, axis=0)) / np.asarray(crb, dtype=np.float64)
    assert np.all(ratio <= 1.4), ratio


# 2.1 and 2.2 bins, between the ends in CI: -m slow (CI's 20 minutes)
@pytest.mark.parametrize("bins, doppler_bins", [(2.0, 0.0), (2.0, 0.4), pytest.param(2.1, 0.0, marks=pytest.mark.slow),
                                                pytest.param(2.2, 0.0, marks=pytest.mark.slow), (2.5, 0.0)])
def test_two_returns_about_two_bins_apart_are_fitted_to_their_own_positions(bins, doppler_bins):
    """Two equal returns ``bins`` range bins apart (``doppler_bins`` in Doppler, 4° apart), ρ = 30 dB, 100 frames,
    those the chain resolves: range RMSE within 1.8× the CRB (1.17–1.38× on these frames; the detection level
    1.1–1.25×). Their first fits, on 3 × 3 patches each beside the other's main lobe, lean half a bin or more towards
    each other; refitted from there, or not at all under the refit's 1.5-bin rule before, they stayed where they met:
    3.0, 5.1 and 10.8× the CRB on these frames at 2.0, 2.0 (0.4 Doppler bin) and 2.1 bins. Now a peak whose first fit
    came within 1.5 bins of another's starts its refit again from its cell."""
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS["mimo12"]
    chain = DspChain(p)
    snr = 30.0 - 10.0 * math.log10(num_range_samples(p) * p.num_chirps * p.num_virtual)
    rng = np.random.default_rng(7)
    r = np.array([40.3, 40.3 + bins * p.range_resolution_m])
    v, az = np.array([0.7, 0.7 + doppler_bins * p.doppler_bin_mps]), np.array([0.0, 4.0])
    scat = point_targets(r, az, v, 40.0 * np.log10(r / r[0]))
    err = []
    for _ in range(100):
        det = chain.process_rd(synthesize_rd(p, scat, rng, snr_db=snr))
        cost = (np.abs(det.range_m[None] - r[:, None]) / p.range_resolution_m
                + np.abs(det.range_rate_mps[None] - v[:, None]) / p.doppler_bin_mps)
        if det.range_m.size >= 2:
            j = np.argmin(cost, axis=1)
            if j[0] != j[1] and np.all(cost[[0, 1], j] <= 1.0):
                err.append(det.range_m[j] - r)
    assert len(err) >= 60, len(err)
    assert np.sqrt(np.mean(np.square(err))) <= 1.8 * equation.crb_range_m(p, 30.0)


def _pair_rmse_over_crb(preset: str, bins: float, rho_db: float, weaker_db: float, frames: int) -> np.ndarray:
    """Two returns ``bins`` range bins apart (4° apart, the same speed) at ρ = ``rho_db`` and ``rho_db`` − ``weaker_db``,
    ``frames`` frames through the chain (those with both detected, at least half): RMSE over each one's own CRB,
    shape (return, quantity: range, range rate, azimuth)."""
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS[preset]
    chain = DspChain(p)
    snr = rho_db - 10.0 * math.log10(num_range_samples(p) * p.num_chirps * p.num_virtual)
    rng = np.random.default_rng(17)
    r, v, az = np.array([40.3, 40.3 + bins * p.range_resolution_m]), np.array([0.7, 0.7]), np.array([0.0, 4.0])
    err = []
    for _ in range(frames):
        rd = (synthesize_rd(p, point_targets(r[:1], az[:1], v[:1]), rng, snr_db=snr)
              + synthesize_rd(p, point_targets(r[1:], az[1:], v[1:]), rng, snr_db=snr - weaker_db, noise=False))
        det = chain.process_rd(rd)
        if det.range_m.size >= 2:                     # the 25-dB return beside an 80-dB one is lost in some frames
            err.append(_match(det, r, v, az))
    assert len(err) >= frames // 2, len(err)
    err = np.stack(err)                                                            # (frame, return, quantity)
    rho = np.array([rho_db, rho_db - weaker_db])
    crb = np.stack([equation.crb_range_m(p, rho), equation.crb_speed_mps(p, rho),
                    np.degrees(equation.crb_azimuth_rad(p, rho, np.radians(az)))], axis=1)
    return np.sqrt(np.mean(err ** 2, axis=0)) / crb


@pytest.mark.parametrize("preset, bins, rho_db, weaker_db", [("mimo12", 11.0, 45.0, 0.0), ("ars408_like", 16.0, 45.0, 0.0),
                                                            ("mimo12", 13.0, 60.0, 35.0), ("mimo12", 16.0, 60.0, 35.0),
                                                            ("ars408_like", 14.0, 80.0, 55.0), ("ars408_like", 11.0, 80.0, 0.0),
                                                            ("mimo12", 9.0, 70.0, 0.0)])
def test_a_loud_neighbours_sidelobes_at_the_patchs_edge_do_not_pull_the_fit(preset, bins, rho_db, weaker_db):
    """Two returns ``bins`` range bins apart at ρ = ``rho_db`` and ``rho_db`` − ``weaker_db``, 40 frames (those with both
    detected, at least 20): range, range rate and azimuth RMSE of each within 1.45× its own CRB. The patch fit's patch ends 3 bins short of the other
    peak but still holds its sidelobes, which at these SNRs pull the fit: before, such patches (half-width 6 or more)
    were not refitted, and came to 1.77× (11 bins), 2.73× (16 bins, ars408_like) and 2.0–11× (the weaker return
    13–16 bins from a 35 dB stronger one) the CRB in range (an independent tester's finding at 40–45 dB). Now a
    patch a loud neighbour's sidelobes reach is refitted with that tone taken out, from the three-bin
    interpolation where its first fit may have been pulled beyond the refit's search (with the first fit's wider
    search: an 80-dB return 14 bins from a 25-dB one came to 5× with the refit's, a second tester's finding), and the
    loudest after the weaker ones, whose first fits its sidelobes swamp. Two equal returns 9–11 bins apart at 70–80
    dB: each refit took out the other's first fit, which had taken this one's sidelobes for its own, and one pass left
    one of them at 1.9× (70 dB) and 4.9–5.2× (80 dB) the CRB in range; now every refitted peak takes every pass."""
    ratio = _pair_rmse_over_crb(preset, bins, rho_db, weaker_db, 40)
    # (beside the 80-dB return the 25-dB one is found in 27 of the 40 frames, whose RMSE carries about ±14 %: its range
    # rate is 1.50× there with and without the staging; the 80-dB return's range 1.72× without it, 1.01× with it)
    assert np.all(ratio <= (1.6 if rho_db == 80.0 else 1.45)), ratio


@pytest.mark.parametrize("preset, bins, rho_db, weaker_db", [("ars408_like", 6.0, 55.0, 10.0), ("mimo12", 7.0, 45.0, 0.0),
                                                            ("ars408_like", 8.0, 55.0, 10.0), ("ars408_like", 9.0, 55.0, 10.0),
                                                            ("ars408_like", 10.0, 55.0, 10.0)])
def test_returns_six_to_ten_bins_apart_are_fitted_again_until_their_tones_agree(preset, bins, rho_db, weaker_db):
    """Two returns 6–10 range bins apart at 45–55 dB, 40 frames: range RMSE of each within 1.3× its own CRB
    (1.05–1.22× on these frames; 1.27–1.76× before at 6–8 bins), range rate and azimuth within 1.45×. Their patches (half-width 3–5, up to 8 bins apart) are refitted at 6 with the other's tone
    taken out; that tone was the other's first fit, which leaned into this one's lobe. One pass (as for the peaks
    cut short by a neighbour 4–6 bins away at ρ = 30 dB) left the louder of a 55/45-dB pair at 1.6–2.0× the CRB in
    range (ars408_like, 6–8 bins) and the second of an equal 45-dB pair at 1.6× (mimo12, 7 bins); now every refitted
    peak takes all REFIT_PASSES. 9 and 10 bins, the other side of the patches' cut: half-width 6 and 7, refitted where
    the louder one's sidelobes reach them, from the three-bin interpolation."""
    ratio = _pair_rmse_over_crb(preset, bins, rho_db, weaker_db, 40)
    assert np.all(ratio[:, 0] <= 1.3) and np.all(ratio <= 1.45), ratio


def test_the_leak_refit_takes_a_patch_from_minus_30_db_of_a_neighbours_sidelobes_and_not_below(monkeypatch):
    """LEAK_REFIT_DB, swept across: a 30-dB return 30–33 range bins beyond a 60.5-dB one (ars408_like, one frame each,
    the same noise). Its patch (half-width 12) ends D − 12 bins from the loud cell, where the windows' worst-case
    sidelobe (sidelobe_envelope) times the loud cell's power, over one channel's noise variance measured here on cells
    far from both, is −27.9, −29.3, −30.7 and −32.0 dB: the chain refits it at 30 and 31 bins and not at 32 and 33."""
    from radarnode.dsp import peaks
    from radarnode.dsp.spectra import noncoherent_power, window
    from radarnode.radar.chain import LEAK_REFIT_DB
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS["ars408_like"]
    chain = DspChain(p)
    k = 10.0 * math.log10(num_range_samples(p) * p.num_chirps * p.num_virtual)

    def frame(bins: int) -> np.ndarray:
        rng = np.random.default_rng(3)
        weak = point_targets(np.array([40.3 + bins * p.range_resolution_m]), np.array([4.0]), np.array([0.7]))
        return (synthesize_rd(p, point_targets(np.array([40.3]), np.array([0.0]), np.array([0.7])), rng,
                              snr_db=60.5 - k)
                + synthesize_rd(p, weak, rng, snr_db=30.0 - k, noise=False))

    rd = frame(30)
    c, m, n = rd.shape
    power = noncoherent_power(rd)
    dl, rl = np.unravel_index(np.argmax(power), power.shape)
    far = np.ones((m, n), dtype=bool)
    far[max(dl - 40, 0):dl + 40, :] = False
    far[:, max(rl - 10, 0):rl + 60] = False
    sigma2 = np.mean(np.abs(rd[:, far]) ** 2)                   # one channel's noise variance, the loud one's cells out
    envelope = peaks.PatchFit(window(chain.config.doppler_window, m), window(chain.config.range_window, n)).envelope
    cells: list = []
    refit = peaks.PatchFit.refit

    def spy(self, rd, d, r, *args, **kwargs):
        which = args[4]                                        # (delta_d, delta_r, snapshot, half, which, …)
        cells.extend(zip(np.asarray(d)[which].tolist(), np.asarray(r)[which].tolist()))
        return refit(self, rd, d, r, *args, **kwargs)

    monkeypatch.setattr(peaks.PatchFit, "refit", spy)
    for bins in (30, 31, 32, 33):
        leak_db = 10.0 * math.log10(envelope[bins - 12] * power[dl, rl] / sigma2)
        assert abs(leak_db - LEAK_REFIT_DB) >= 0.5, leak_db              # the sweep's premise: clear of the threshold
        cells.clear()
        chain.process_rd(frame(bins))
        weak_refitted = any(abs(d - dl) <= 1 and abs(r - (rl + bins)) <= 1 for d, r in cells)
        assert weak_refitted == (leak_db >= LEAK_REFIT_DB), (bins, leak_db, sorted(set(cells)))


def test_the_patch_fits_snapshot_at_given_offsets_is_the_fits_own_there():
    """PatchFit.snapshot (no search) at the offsets the fit found gives the fit's snapshot; at other offsets another."""
    from radarnode.dsp.peaks import PatchFit
    from radarnode.dsp.spectra import range_doppler, window
    c, m, n = 4, 64, 128
    k = np.arange(m)[:, None], np.arange(n)[None, :]
    amp = np.array([1.0, 1j, -1.0, 0.5])
    rng = np.random.default_rng(5)
    cube = amp[:, None, None] * np.exp(2j * np.pi * (3.3 * k[0] / m + 40.27 * k[1] / n))[None] \
        + 0.01 * (rng.standard_normal((c, m, n)) + 1j * rng.standard_normal((c, m, n)))
    rd = range_doppler(cube)
    fit = PatchFit(window("hann", m), window("hann", n), 6)
    d, r = np.array([m // 2 + 3]), np.array([40])
    for half in (1, 3, 6):
        fd, fr, snap = fit(rd, d, r, 0.0, 0.0, half)
        assert np.allclose(fit.snapshot(rd, d, r, fd, fr, half), snap, rtol=1e-12, atol=0.0)
        assert not np.allclose(fit.snapshot(rd, d, r, 0.0, 0.0, half), snap, rtol=1e-3)


def test_the_patch_fits_refit_takes_a_neighbours_tone_out_exactly():
    """Two noise-free tones 4 range and 2 Doppler bins apart: the first fit, on patches cut 3 bins short of the
    other peak, is off by some 3e-5 bin; fitted again on the full patch with the other tone taken out, each comes
    out as it does alone (to 1.3e-7 bin after two passes and after five: the searches' grids, which sit around
    slightly different starts, leave each fit some 4e-6 bin from the truth on their own)."""
    from radarnode.dsp.peaks import PatchFit, patch_halves
    from radarnode.dsp.spectra import range_doppler, window
    c, m, n = 4, 128, 256
    k = np.arange(m)[:, None], np.arange(n)[None, :]

    def tone(fd, fr, amp):
        return np.asarray(amp)[:, None, None] * np.exp(2j * np.pi * (fd * k[0] / m + fr * k[1] / n))[None]

    tones = [(3.3, 40.27, [1, 1j, -1, 0.5]), (5.1, 43.6, [0.7, 0.2, 1, -1j])]
    rd = range_doppler(sum(tone(*t) for t in tones))
    fit = PatchFit(window("hann", m), window("hann", n), 12)
    d, r = np.array([m // 2 + 3, m // 2 + 5]), np.array([40, 44])
    alone = [fit(range_doppler(tone(*t)), d[i:i + 1], r[i:i + 1], 0.0, 0.0) for i, t in enumerate(tones)]
    half = patch_halves(d, r, np.arange(2), (m, n), 12)
    assert half.tolist() == [1, 1]
    fd, fr, snap = fit(rd, d, r, 0.0, 0.0, half)
    exact_d = np.array([a[0][0] for a in alone])
    exact_r = np.array([a[1][0] for a in alone])
    assert np.max(np.abs(fd - exact_d)) > 1e-5 or np.max(np.abs(fr - exact_r)) > 1e-5
    for _ in range(2):
        fd, fr, snap = fit.refit(rd, d, r, fd, fr, snap, half, np.arange(2), 12)
        half = np.full(2, 12)
    assert np.max(np.abs(fd - exact_d)) < 3e-7 and np.max(np.abs(fr - exact_r)) < 3e-7, (fd - exact_d, fr - exact_r)
    assert np.allclose(np.abs(snap), [np.abs(a[2][0]) for a in alone], rtol=1e-5)


@pytest.mark.parametrize("half", [1, 6, 12])
def test_the_patch_axis_response_is_the_windows_dft_at_every_offset(half):
    """``_PatchAxis.response`` (the Dirichlet kernels of the window's few DFT terms, one real product) against the
    windowed tone's DFT summed sample by sample, Σ_n w[n]·e^{−j2π(i−δ)n/L}·e^{−jπδ(L−1)/L}: offsets within a bin,
    on whole bins and within 1e-13 of them (the kernel's 0/0 limit), at ±1 (the fits' clip), for a scalar, a (K,)
    and a (K, P) offset."""
    from radarnode.dsp.peaks import _patch_axis
    from radarnode.dsp.spectra import window
    length = 64
    w = window("hann", length)
    axis = _patch_axis(w, half)
    i, n = np.arange(-half, half + 1), np.arange(length)

    def direct(delta):
        delta = np.ravel(delta)
        u = i[None, :] - delta[:, None]
        return (np.exp(-2j * np.pi * u[..., None] * n / length) @ w) \
            * np.exp(-1j * np.pi * delta * (length - 1) / length)[:, None]

    peak = np.abs(direct(0.0)).max()
    offsets = np.array([0.0, -1.0, 1.0, 0.5, -0.5, -0.37, 1e-13, -1e-13, 1.0 - 1e-13, 0.999])
    got = axis.response(offsets)
    assert got.shape == (offsets.size, 2 * half + 1)
    assert np.max(np.abs(got - direct(offsets))) < 1e-12 * peak
    grid = np.random.default_rng(3).uniform(-1.0, 1.0, (4, 5))
    got = axis.response(grid)
    assert got.shape == (4, 5, 2 * half + 1)
    assert np.max(np.abs(got.reshape(20, -1) - direct(grid))) < 1e-12 * peak
    assert axis.response(0.3).shape == (2 * half + 1,)
    assert np.max(np.abs(axis.response(0.3) - direct(0.3)[0])) < 1e-12 * peak


def _crowded_map(seed=4):
    """A noisy map of a line of nine tones 4 range bins apart (posts along a guardrail) and two louder ones beside
    them, and its peaks' first fit: (fit, rd, d, r, fd, fr, snap, half)."""
    from radarnode.dsp.peaks import PatchFit, local_maxima, patch_halves
    from radarnode.dsp.spectra import noncoherent_power, range_doppler, window
    c, m, n = 4, 64, 128
    k = np.arange(m)[:, None], np.arange(n)[None, :]
    rng = np.random.default_rng(seed)
    cube = 0.05 * (rng.standard_normal((c, m, n)) + 1j * rng.standard_normal((c, m, n)))
    tones = [(5.2 + 0.1 * j, 20.3 + 4.0 * j, 1.0) for j in range(9)] + [(9.6, 30.1, 3.0), (2.4, 37.7, 2.0)]
    for fd, fr, a in tones:
        cube += a * np.exp(2j * np.pi * rng.uniform(0, 1, c))[:, None, None] \
            * np.exp(2j * np.pi * (fd * k[0] / m + fr * k[1] / n))[None]
    rd = range_doppler(cube)
    power = noncoherent_power(rd)
    d, r = local_maxima(power, power > 40.0 * np.median(power))
    fit = PatchFit(window("hann", m), window("hann", n), 12)
    half = patch_halves(d, r, np.arange(d.size), (m, n), 12)
    fd, fr, snap = fit(rd, d, r, np.zeros(d.size), np.zeros(d.size), half)
    return fit, rd, d, r, fd, fr, snap, half


def test_a_patch_store_hands_the_refit_the_patches_it_cuts_itself_and_refuses_another_map():
    """The refit's passes with one ``PatchStore`` (each patch cut once, each set of peaks gathered once) give bit
    for bit what they give cutting every patch again; the store's patches are read only (a write raises instead of
    reaching the next pass) and handed out again for the same peaks; a store of another map or other peaks is
    refused, naming it."""
    from radarnode.dsp.peaks import PatchStore, _patches
    fit, rd, d, r, fd, fr, snap, half = _crowded_map()
    assert d.size >= 11
    which, wider = np.arange(d.size), np.full(d.size, 6)
    store = PatchStore(rd, d, r)
    plain, stored = (fd, fr, snap), (fd, fr, snap)
    for _ in range(3):
        plain = fit.refit(rd, d, r, *plain, half, which, wider)
        stored = fit.refit(rd, d, r, *stored, half, which, wider, store=store)
        for a, b in zip(plain, stored):
            assert np.array_equal(a, b)
    cut = store.take(which[:3], 6)
    with pytest.raises(ValueError, match="read-only"):
        cut[...] = 0.0
    assert store.take(which[:3], 6) is cut
    assert np.array_equal(cut, _patches(rd, d[:3], r[:3], 6, (1, 2, 0, 3)))
    assert np.array_equal(store.take(which[3:1:-1], 6), _patches(rd, d[3:1:-1], r[3:1:-1], 6, (1, 2, 0, 3)))
    for bad in (PatchStore(rd.copy(), d, r), PatchStore(rd, d[::-1], r[::-1]), PatchStore(rd, d[:-1], r[:-1])):
        with pytest.raises(ValueError, match="store: a PatchStore of another map or other peaks"):
            fit.refit(rd, d, r, fd, fr, snap, half, which, wider, store=bad)


def test_the_refit_takes_the_neighbours_tones_out_as_subtracting_them_from_the_patch_would():
    """The refit never forms a neighbour's tone over the patch: it takes each tone's share out of the patch's
    collapses on one axis' template (one inner product a tone). Fitting patches from which every neighbour's tone
    was subtracted cell by cell (a loop over the pairs here, as the refit did until 2026-12-05) gives the same
    offsets to 1e-12 bin and snapshots to 1e-12 of their size; the neighbours' counts differ from patch to patch
    (the padding of the refit's slots is exercised)."""
    from radarnode.dsp import peaks
    fit, rd, d, r, fd, fr, snap, half = _crowded_map()
    which, wider = np.arange(d.size), np.full(d.size, 6)
    got = fit.refit(rd, d, r, fd, fr, snap, half, which, wider)
    axis_d, axis_r = fit.axes[6]
    big_d, big_r = fit.axes[fit.max_half]
    amp = snap / np.sqrt(big_d.norm(fd[:, None], half) * big_r.norm(fr[:, None], half))
    x = peaks._patches(rd, d, r, 6, (1, 2, 0, 3))                        # (K, J_d, C, J_r)
    m, n = rd.shape[1:]
    count = np.zeros(d.size, dtype=int)
    for a in range(d.size):
        for q in range(d.size):
            dd = (d[q] - d[a] + m // 2) % m - m // 2
            dr = (r[q] - r[a] + n // 2) % n - n // 2
            if q == a or max(abs(dd), abs(dr)) > 6 + peaks.REFIT_REACH:
                continue
            count[a] += 1
            wd = axis_d.response(np.array([dd + fd[q]]))[0] * np.exp(1j * np.pi * dd * (m - 1) / m)
            wr = axis_r.response(np.array([dr + fr[q]]))[0] * np.exp(1j * np.pi * dr * (n - 1) / n)
            x[a] -= wd[:, None, None] * amp[q][None, :, None] * wr[None, None, :]
    ref = fit._fit_patches(x, fd, fr, wider, axis_d, axis_r, fit.REFIT_ROUNDS)
    assert np.max(np.abs(got[0] - ref[0])) < 1e-12 and np.max(np.abs(got[1] - ref[1])) < 1e-12
    assert np.max(np.abs(got[2] - ref[2])) < 1e-12 * np.max(np.abs(ref[2]))
    assert np.unique(count).size >= 3 and count.min() >= 1, count
    # the tones matter: the same fit without taking them out lands elsewhere
    plain = fit._fit_patches(peaks._patches(rd, d, r, 6, (1, 2, 0, 3)), fd, fr, wider, axis_d, axis_r,
                             fit.REFIT_ROUNDS)
    assert np.max(np.abs(plain[1] - ref[1])) > 1e-3


@pytest.mark.parametrize("preset", ["mimo12", "fast_chirp"])
@pytest.mark.parametrize("bins_from_edge", [-0.6, -0.3, -0.05, 0.05, 0.3])
def test_a_return_at_the_doppler_wrap_is_reported_inside_the_span_as_the_detection_level_reports_it(preset,
                                                                                                  bins_from_edge):
    """A strong return ``bins_from_edge`` Doppler bins from +v_a (below: inside the span; above: aliased) and at
    twice the span further: the signal level's speed lies in [−v_a, v_a) and is the detection level's alias of the
    truth, and its range is not moved by the wrong alias' coupling. A peak in the span's last bin interpolated
    across the wrap came out beyond −v_a (+32.25 m/s on mimo12 as −32.41 m/s, 0.40 m further: an independent
    tester's finding)."""
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS[preset]
    chain = DspChain(p)
    v_a = p.alias_speed_mps
    snr_sample = 35.0 - 10.0 * math.log10(num_range_samples(p) * p.num_chirps * p.num_virtual)
    rng = np.random.default_rng(5)
    for v in (v_a + bins_from_edge * p.doppler_bin_mps, v_a + bins_from_edge * p.doppler_bin_mps + 4.0 * v_a):
        scat = point_targets([30.0], [5.0], [v], 0.0)
        expected = detection_model.apparent_positions(p, scat)[1][0] * p.doppler_bin_mps
        for _ in range(4):
            det = chain.process_rd(synthesize_rd(p, scat, rng, snr_db=snr_sample))
            k = int(np.argmax(det.snr_db))
            assert -v_a <= det.range_rate_mps[k] < v_a, (v, det.range_rate_mps[k])
            # (within a quarter bin of it, across the wrap: a return 0.05 bin from the edge is drawn to either side)
            off = (det.range_rate_mps[k] - expected + v_a) % (2.0 * v_a) - v_a
            assert abs(off) < 0.25 * p.doppler_bin_mps, (v, det.range_rate_mps[k], expected)
            coupled = 30.0 + (v - det.range_rate_mps[k]) * p.range_rate_coupling_s     # the chain's own alias error
            assert abs(det.range_m[k] - coupled) < 0.25 * p.range_resolution_m, (v, det.range_m[k], coupled)


@pytest.mark.parametrize("rcs_dbsm", [200.0, 300.0])
def test_an_absurdly_strong_scatterer_is_refused_by_the_rd_synthesis_for_its_strength_not_its_migration(rcs_dbsm):
    """A return some 200 dB over the noise would need more series terms than the range–Doppler synthesis allows;
    the error says so and names the scatterer's peak-to-noise ratio (it used to blame a range migration of 0.0 bins).
    150 dBsm still synthesises."""
    from radarnode.errors import ConfigError
    from radarnode.radar.signal_model import synthesize_rd
    p = PRESETS["mimo12"]
    with pytest.raises(ConfigError, match=r"scatterer 0: peak-to-noise value \d+ dB .*rcs_dbsm"):
        synthesize_rd(p, point_targets([40.0], [0.0], [3.0], [rcs_dbsm]), np.random.default_rng(1))
    cube = synthesize_rd(p, point_targets([40.0], [0.0], [3.0], [150.0]), np.random.default_rng(1))
    assert np.all(np.isfinite(cube))


def test_the_refit_is_on_for_complex128_spectra_off_for_complex64_and_refused_for_other_values():
    """``signal.dsp.refit``: auto (the default) refits on complex128 spectra only (complex64 is the fast setting:
    the same detections as refit off); true and false force it; anything else, or true without range_ml, is an
    error naming the field."""
    from radarnode.errors import FieldError
    from radarnode.radar.chain import DspConfig
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS["ars408_like"]
    r = [40.3, 40.3 + 3.0 * p.range_resolution_m]
    scat = point_targets(r, [0.0, 4.0], [0.7, 0.7 + 0.4 * p.doppler_bin_mps], [0.0, 40.0 * math.log10(r[1] / r[0])])
    snr = 30.0 - 10.0 * math.log10(num_range_samples(p) * p.num_chirps * p.num_virtual)
    for dtype in (np.complex128, np.complex64):
        rd = synthesize_rd(p, scat, np.random.default_rng(3), snr_db=snr, dtype=dtype)
        auto, on, off = (DspChain(p, DspConfig(refit=mode)).process_rd(rd) for mode in ("auto", True, False))
        same_as = on if dtype == np.complex128 else off
        assert np.array_equal(auto.range_m, same_as.range_m)
        assert not np.array_equal(on.range_m, off.range_m)
    for bad in ("yes", 1, None):
        with pytest.raises(FieldError, match="refit"):
            DspConfig(refit=bad)
    with pytest.raises(FieldError, match="refit"):
        DspConfig(refit=True, range_ml=False)
