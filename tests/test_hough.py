"""The Hough transform on synthetic points with known lines (issue 5, item 4)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.dsp.hough import HoughGrid, accumulate, refine, strongest_lines
from radarnode.errors import ConfigError

GRID = HoughGrid.make(rho_max_m=60.0, rho_step_m=0.25, theta_step_deg=0.5)


def _lines(x, y, **kw):
    return strongest_lines(accumulate(np.asarray(x, float), np.asarray(y, float), GRID), GRID, **kw)


def test_vertical_line_x_equals_12():
    y = np.linspace(-20, 20, 41)
    (line,) = _lines(np.full_like(y, 12.0), y, max_lines=1)
    assert math.degrees(line.theta_rad) == pytest.approx(0.0, abs=0.5) and line.rho_m == pytest.approx(12.0, abs=0.25)


def test_horizontal_line_a_guardrail_3_5_m_to_the_right():
    x = np.linspace(5, 80, 76)
    (line,) = _lines(x, np.full_like(x, -3.5), max_lines=1)
    assert abs(math.degrees(line.theta_rad)) == pytest.approx(90.0, abs=0.5)
    assert line.rho_m * math.sin(line.theta_rad) == pytest.approx(-3.5, abs=0.25)
    assert line.votes == pytest.approx(76)


def test_two_parallel_lines_a_road_apart():
    x = np.linspace(5, 80, 60)
    lines = _lines(np.concatenate([x, x]), np.concatenate([np.full_like(x, 6.0), np.full_like(x, -5.0)]))
    offsets = sorted(ln.rho_m * math.sin(ln.theta_rad) for ln in lines)
    assert offsets == pytest.approx([-5.0, 6.0], abs=0.25)


def test_no_points_and_one_point():
    assert _lines([], []) == []
    # one point votes once per θ: below any sensible min_votes, so no line
    assert _lines([10.0], [2.0], min_votes=2.0) == []
    acc = accumulate(np.array([10.0]), np.array([2.0]), GRID)
    assert acc.sum() == pytest.approx(GRID.theta_rad.size)


def test_noise_only_gives_no_line():
    rng = np.random.default_rng(0)
    x, y = rng.uniform(0, 60, 40), rng.uniform(-20, 20, 40)
    assert _lines(x, y, min_votes=12) == []


def test_outliers_do_not_move_the_refined_line():
    rng = np.random.default_rng(1)
    x = np.linspace(5, 80, 50)
    y = 0.02 * x + 4.0 + rng.normal(0, 0.1, x.size)          # a slightly slanted boundary
    ox, oy = rng.uniform(5, 80, 30), rng.uniform(-15, 15, 30)  # clutter
    xs, ys = np.concatenate([x, ox]), np.concatenate([y, oy])
    (line,) = _lines(xs, ys, max_lines=1, min_votes=20)
    fit, inliers = refine(line, xs, ys, band_m=0.6)
    assert inliers[:50].mean() > 0.95 and inliers[50:].mean() < 0.2
    slope = -1.0 / math.tan(fit.theta_rad)
    assert slope == pytest.approx(0.02, abs=0.005)
    assert fit.rho_m / math.sin(fit.theta_rad) == pytest.approx(4.0, abs=0.1)


def test_weights_and_bad_input():
    x = np.linspace(5, 50, 10)
    acc = accumulate(x, np.zeros_like(x), GRID, weights=2.0)
    assert acc.max() == pytest.approx(20.0)
    with pytest.raises(ConfigError, match="hough points"):
        accumulate(np.zeros(3), np.zeros(4), GRID)
    with pytest.raises(ConfigError, match="hough grid"):
        HoughGrid.make(rho_max_m=-1.0)


def test_the_accumulator_votes_exactly_as_the_plain_formula():
    """accumulate works in place on one array; every cell and every (weighted) vote is the plain formula's:
    ρ = x·cosθ + y·sinθ rounded to a cell, points beyond the ρ range voting nowhere."""
    rng = np.random.default_rng(7)
    x = rng.uniform(-5.0, 120.0, 900)
    y = rng.uniform(-60.0, 60.0, 900)        # many beyond ±ρ_max: they must vote nowhere
    w = rng.uniform(0.5, 2.0, 900)
    for weights in (None, w):
        rho = x[:, None] * np.cos(GRID.theta_rad)[None, :] + y[:, None] * np.sin(GRID.theta_rad)[None, :]
        idx = np.rint((rho - GRID.rho_m[0]) / (GRID.rho_m[1] - GRID.rho_m[0])).astype(np.int64)
        ok = (idx >= 0) & (idx < GRID.rho_m.size)
        flat = (np.arange(GRID.theta_rad.size)[None, :] * GRID.rho_m.size + idx)[ok]
        votes = np.broadcast_to((np.ones_like(x) if weights is None else weights)[:, None], rho.shape)[ok]
        plain = np.bincount(flat, weights=votes, minlength=GRID.theta_rad.size * GRID.rho_m.size)
        np.testing.assert_array_equal(accumulate(x, y, GRID, weights=weights), plain.reshape(GRID.theta_rad.size, -1))


@pytest.mark.parametrize("half", [(0, 0), (1, 0), (0, 3), (10, 4), (2, 7), (13, 1)])
def test_the_max_filter_is_scipys_with_edges_extended(half):
    import scipy.ndimage

    from radarnode.dsp.hough import max_filter
    rng = np.random.default_rng(sum(half))
    a = np.floor(rng.random((40, 57)) * 6.0)          # plateaus of equal values, as an accumulator has
    want = scipy.ndimage.maximum_filter(a, size=(2 * half[0] + 1, 2 * half[1] + 1), mode="nearest")
    np.testing.assert_array_equal(max_filter(a, half), want)


def test_peaks_on_plateaus_are_taken_strongest_first_and_each_strikes_its_neighbourhood():
    """Candidate cells on the plateaus of three lines: the lines found are the loop's over every candidate
    (strongest first, stable; skipped when near a line already taken)."""
    rng = np.random.default_rng(11)
    x = np.concatenate([np.linspace(5, 150, 60)] * 3)
    y = np.concatenate([np.full(60, 3.5), np.full(60, 7.0), 0.02 * np.linspace(5, 150, 60) - 4.0])
    x, y = x + rng.normal(0, 0.05, x.size), y + rng.normal(0, 0.05, y.size)
    acc = accumulate(x, y, GRID)
    got = strongest_lines(acc, GRID, max_lines=3, min_votes=4.0)
    # the plain loop, as it was written before
    import scipy.ndimage
    local = acc >= scipy.ndimage.maximum_filter(acc, size=(21, 9), mode="nearest")
    ti, ri = np.nonzero(local & (acc >= 4.0))
    plain = []
    for k in np.argsort(-acc[ti, ri], kind="stable"):
        t, r = ti[k], ri[k]
        if any(abs(np.degrees(GRID.theta_rad[t] - ln.theta_rad)) <= 5.0 and abs(GRID.rho_m[r] - ln.rho_m) <= 1.0
               for ln in plain):
            continue
        plain.append(type(got[0])(float(GRID.theta_rad[t]), float(GRID.rho_m[r]), float(acc[t, r])))
        if len(plain) == 3:
            break
    assert ti.size > 3 * len(plain)                 # candidates were skipped
    assert got == plain and len(got) == 3


@pytest.mark.parametrize("fraction", [0.3, 0.5, 0.9])
def test_a_minimum_fraction_keeps_the_strong_peaks_of_the_full_search(fraction):
    """min_fraction looks only around the strong cells: the lines are the full search's, less those below the
    fraction of the strongest (three lines of 60, 45 and 25 points and scattered clutter)."""
    rng = np.random.default_rng(5)
    x = np.concatenate([np.linspace(5, 150, 60), np.linspace(5, 110, 45), np.linspace(5, 60, 25),
                        rng.uniform(0, 150, 200)])
    y = np.concatenate([np.full(60, 3.5), np.full(45, -7.0), 0.05 * np.linspace(5, 60, 25) + 12.0,
                        rng.uniform(-30, 30, 200)])
    acc = accumulate(x + rng.normal(0, 0.05, x.size), y + rng.normal(0, 0.05, y.size), GRID)
    full = strongest_lines(acc, GRID, max_lines=6, min_votes=4.0)
    part = strongest_lines(acc, GRID, max_lines=6, min_votes=4.0, min_fraction=fraction)
    assert len(full) >= 3
    assert part == [ln for ln in full if ln.votes >= fraction * full[0].votes]
    assert 0 < len(part) < len(full)


def test_scratch_reused_across_point_sets_gives_the_same_accumulator():
    # one Scratch for point sets that grow and shrink (its arrays grown, then views of them reused): every
    # accumulator equals the one computed with fresh arrays, weighted or not
    from radarnode.dsp.hough import Scratch
    rng = np.random.default_rng(5)
    scratch = Scratch()
    for n in (3, 400, 50, 401, 1, 1200, 7):
        x, y = rng.uniform(0.0, 60.0, n), rng.uniform(-8.0, 8.0, n)
        w = rng.uniform(0.1, 3.0, n)
        assert np.array_equal(accumulate(x, y, GRID, scratch=scratch), accumulate(x, y, GRID))
        assert np.array_equal(accumulate(x, y, GRID, weights=w, scratch=scratch), accumulate(x, y, GRID, weights=w))


def test_the_votes_are_integer_counts_of_each_cell_and_a_scratch_accumulator_lasts_until_its_next_call():
    """The unweighted accumulator (votes added one by one into the scratch's memory) against the cell counts
    computed independently (ρ of each point and θ, rounded to the nearest cell, outside ones dropped); with a
    scratch that shares its result, the result is its memory: the next call with it replaces it, a copy keeps it."""
    from radarnode.dsp.hough import Scratch
    rng = np.random.default_rng(8)
    scratch = Scratch(share_result=True)
    step = GRID.rho_m[1] - GRID.rho_m[0]
    for n in (1, 5, 300, 2000):
        x, y = rng.uniform(0.0, 80.0, n), rng.uniform(-40.0, 40.0, n)     # many beyond the ρ range
        acc = accumulate(x, y, GRID, scratch=scratch)
        rho = np.outer(x, np.cos(GRID.theta_rad)) + np.outer(y, np.sin(GRID.theta_rad))
        cell = np.floor((rho - GRID.rho_m[0]) / step + 0.5).astype(int)
        want = np.zeros((GRID.theta_rad.size, GRID.rho_m.size))
        t = np.broadcast_to(np.arange(GRID.theta_rad.size), cell.shape)
        inside = (cell >= 0) & (cell < GRID.rho_m.size)
        np.add.at(want, (t[inside], cell[inside]), 1.0)
        # (a point within rounding of a cell edge may fall either side: at most a handful of such votes)
        assert acc.dtype == np.float64 and np.all(acc == np.round(acc)) and np.abs(acc - want).sum() <= 4
        kept = acc.copy()
        accumulate(x[:1], y[:1], GRID, scratch=scratch)
        assert np.array_equal(kept, accumulate(x, y, GRID))
    assert accumulate(x[:1], y[:1], GRID, scratch=scratch).sum() <= GRID.theta_rad.size
    # a scratch that does not share its result (the default): every accumulator is the caller's own
    own = Scratch()
    first = accumulate(x, y, GRID, scratch=own)
    second = accumulate(x[:1], y[:1], GRID, scratch=own)
    assert np.array_equal(first, accumulate(x, y, GRID)) and not np.shares_memory(first, second)


def _plain_peaks(acc, half, min_votes):
    """Every cell of at least ``min_votes`` that no cell of its window exceeds (the window cut by the array's edge;
    a NaN in it, the maximum of any comparison, leaves none), in row-major order: the definition, written out."""
    out = []
    for t, r in zip(*np.nonzero(acc >= min_votes)):
        win = acc[max(t - half[0], 0):t + half[0] + 1, max(r - half[1], 0):r + half[1] + 1]
        if acc[t, r] >= win.max():
            out.append((t, r))
    return out


@pytest.mark.parametrize("count", [1, 3, 15, 16, 17, 32, 200])
def test_few_and_many_candidates_give_the_same_peaks(count, monkeypatch):
    """strongest_lines tests up to FEW_CANDIDATES candidate cells each against its own window and more by the
    maximum filter over their box: both ways, just below, at, just above and at twice the threshold and far beyond
    (a plateau), with candidates at the accumulator's edges and a NaN cell, the lines are those of the peaks the
    definition gives."""
    from radarnode.dsp import hough
    rng = np.random.default_rng(count)
    grid = HoughGrid(np.radians(np.arange(60.0, 120.0, 0.5)), np.arange(-140, 141) * 0.25)
    acc = np.floor(rng.random((grid.theta_rad.size, grid.rho_m.size)) * 3.0)
    cells = rng.choice(acc.size, size=count, replace=False)
    cells[:min(count, 2)] = [0, acc.size - 1][:min(count, 2)]           # corners: the window cut by the edge
    acc.flat[cells] = 4.0 + np.floor(rng.random(count) * 3.0)          # the candidates (≥ min_votes 4)
    if count > 3:
        acc.flat[cells[3]] = np.nan                                     # a NaN cell is no candidate, nor a peak
    half = (10, 4)                                                      # 5° and 1 m in cells of 0.5° and 0.25 m
    peaks = _plain_peaks(acc, half, 4.0)            # (a window holding the NaN has a NaN maximum: no peak there)
    want = []                                       # strongest first (stable); one near a line taken is that line
    for k in np.argsort([-acc[t, r] for t, r in peaks], kind="stable"):
        t, r = peaks[k]
        if not any(abs(np.degrees(grid.theta_rad[t] - th)) <= 5.0 and abs(grid.rho_m[r] - rho) <= 1.0
                   for th, rho, _ in want):
            want.append((grid.theta_rad[t], grid.rho_m[r], acc[t, r]))
    assert len(want) >= min(count, 10) - 2
    assert hough.FEW_CANDIDATES == 16
    for few in (hough.FEW_CANDIDATES, 0, 10 ** 6):                      # as shipped, always the filter, never it
        monkeypatch.setattr(hough, "FEW_CANDIDATES", few)
        got = strongest_lines(acc, grid, max_lines=10 ** 6, min_votes=4.0)    # ±5° and ±1 m: half (10, 4) cells
        assert [(ln.theta_rad, ln.rho_m, ln.votes) for ln in got] == want


def test_one_scratch_serves_two_grids_in_turn():
    """The scratch keeps one grid's tables (its coefficients and row offsets): accumulating on another grid with it,
    and back, gives each grid's own accumulator."""
    from radarnode.dsp.hough import Scratch
    other = HoughGrid.make(rho_max_m=20.0, rho_step_m=0.3, theta_step_deg=1.0)
    rng = np.random.default_rng(4)
    scratch = Scratch()
    for grid in (GRID, other, GRID, other):
        x, y = rng.uniform(0.0, 60.0, 50), rng.uniform(-25.0, 25.0, 50)
        assert np.array_equal(accumulate(x, y, grid, scratch=scratch), accumulate(x, y, grid))
