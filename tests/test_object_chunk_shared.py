"""The object level's chunk computes each body's outline once and its gains without logarithms: the same numbers.

The masking's outline interference and the centroid across (``visible_centre_y``) read the outlines of mostly the
same bodies; a :class:`SharedOutline` computes them once for both. The element pattern enters those sums as a power
ratio (``equation.pattern_gain``) instead of ``10 ** (pattern_db / 10)``, and the masking table is read by flat index.
These tests hold the shared and the direct computations to the same bits, and the gain to rounding of the dB form.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from helpers import masking_inputs, scenario
from radarnode.radar import equation
from radarnode.radar.models import make_model
from radarnode.radar.object_model import SharedOutline, in_fov, visible_centre_y, visible_outline
from radarnode.radar.presets import PRESETS
from radarnode.radar.setup import radar_config
from radarnode.scene.world import Scene


@pytest.mark.parametrize("exponent", [0.0, 0.5, 1.0, 1.5, 3.0])
def test_the_pattern_gain_is_the_pattern_in_db_as_a_power_ratio(exponent):
    p = dataclasses.replace(PRESETS["ars408_like"], element_pattern_exponent=exponent)
    az = np.radians(np.array([-180.0, -95.0, -90.0, -89.9999, -60.0, -9.0, 0.0, 1e-9, 30.0, 85.0, 89.99, 90.0, 120.0]))
    gain = equation.pattern_gain(p, az)
    assert gain == pytest.approx(10.0 ** (equation.pattern_db(p, az) / 10.0), rel=1e-12, abs=0.0)
    assert gain[6] == 1.0                                   # boresight: exactly 1
    where = np.arange(az.size) % 2 == 0
    part = equation.pattern_gain(p, az, where)
    assert np.array_equal(part[where], gain[where]) and np.all(part[~where] == 1.0)
    # at and beyond ±90° the floor of cos θ at 1e-6, as in dB (−120·q dB)
    assert np.all(gain[[0, 1, 2, 11, 12]] == pytest.approx(1e-6 ** (2.0 * exponent), rel=1e-12))


def _traffic(seed: int = 3):
    # a truck and cars abreast and crossing the beam's edge: bodies whose outlines the masking and the centroid read
    return scenario("""  - {id: lead, class: car, x_m: 14.0, lane: 1, speed_mps: 15.0}
  - {id: truck, class: truck, x_m: 30.0, lane: 0, speed_mps: 12.0}
  - {id: near, class: car, x_m: 4.0, lane: 2, speed_mps: 18.0}
  - {id: far, class: car, x_m: 90.0, lane: 1, speed_mps: 25.0}""",
                    ego="{speed_mps: 16.0}", road="{lanes: 3, ego_lane: 1}", duration=6.0, seed=seed)


def _view_of(sc):
    rc = radar_config(sc)
    p, scene = rc.preset, Scene(sc)
    _, view, _, _, observable, snr = masking_inputs(p, scene, np.arange(80) * sc.period_s)
    return p, scene, view, observable & (scene.length_m > 0.5), observable, snr


def test_a_shared_outline_gives_each_subset_the_bits_it_gives_computed_alone():
    p, scene, view, rows, observable, snr = _view_of(_traffic())
    shared = SharedOutline(p, view, scene.length_m, scene.width_m, rows, p.max_range_m)
    t_all, j_all = np.nonzero(rows)
    assert t_all.size > 100
    px, py, _, az, share, reflects = visible_outline(p, view, t_all, j_all, scene.length_m, scene.width_m,
                                                     p.max_range_m)
    facing = share > 0.0
    # the azimuth of every point on a facing edge, exactly; the others never reflect
    assert np.array_equal(az[facing], np.arctan2(py, px)[facing]) and not reflects[~facing].any()
    assert facing.any() and (~facing).any()
    every = np.arange(t_all.size)
    for pick in (every, every[::3], every[every % 7 == 2], every[:0]):
        alone = visible_outline(p, view, t_all[pick], j_all[pick], scene.length_m, scene.width_m, p.max_range_m)
        got = shared.of(t_all[pick], j_all[pick])
        assert len(got) == len(alone)
        for a, b in zip(got, alone):
            assert a.shape == b.shape and np.array_equal(a, b)
    # a body outside the shared rows is computed on its own, the same as alone
    t_out, j_out = np.nonzero(~rows & (np.arange(scene.n) >= 0))
    if t_out.size:
        alone = visible_outline(p, view, t_out[:5], j_out[:5], scene.length_m, scene.width_m, p.max_range_m)
        for a, b in zip(shared.of(t_out[:5], j_out[:5]), alone):
            assert np.array_equal(a, b)


def test_the_centroid_and_the_masking_are_the_same_with_the_outline_shared():
    sc = _traffic()
    p, scene, view, rows, observable, snr = _view_of(sc)
    rc = radar_config(sc)
    model = make_model("object", scene, p, np.random.default_rng(1), rc.signal)
    rng_m = view.range_m
    crossing = np.zeros(rng_m.shape, dtype=bool)
    extended = observable & model.extended
    direct_y = visible_centre_y(p, view, scene.length_m, scene.width_m, extended, p.max_range_m)
    direct_m = model._masking(view, rng_m, snr, observable, crossing, p.max_range_m)
    shared = SharedOutline(p, view, scene.length_m, scene.width_m, extended, p.max_range_m)
    shared_m = model._masking(view, rng_m, snr, observable, crossing, p.max_range_m, shared)
    shared_y = visible_centre_y(p, view, scene.length_m, scene.width_m, extended, p.max_range_m, shared)
    assert np.array_equal(direct_y, shared_y) and np.array_equal(direct_m, shared_m)
    assert (direct_m < 1.0).any() and (direct_y != view.y_m).any()        # the case reaches both paths


def test_the_masking_table_is_read_bilinearly_as_its_corners_say():
    sc = _traffic()
    stat = make_model("object", Scene(sc), radar_config(sc).preset, np.random.default_rng(1),
                      radar_config(sc).signal).statistic
    rng = np.random.default_rng(5)
    rho = rng.uniform(-15.0, 95.0, 4000)
    rel = 10.0 ** rng.uniform(-2.5, 7.5, 4000)
    mean_z = stat.n_channels * stat.eigenvalues.sum()
    for sw in (0, 1):
        got = stat.masking_factor(rho, rel * mean_z, sw)
        table = stat._mask_table(sw)
        rel_in = rel * mean_z / mean_z                     # as the function reads it back
        # the same rule written out with 2-D indices
        over = np.maximum(rho - stat.MASK_RHO_DB[-1], 0.0)
        x = np.clip(rho - over, stat.MASK_RHO_DB[0], stat.MASK_RHO_DB[-1])
        y = np.clip(np.log10(rel_in) - over / 10.0, stat.MASK_LOG_I[0], stat.MASK_LOG_I[-1])
        fx = (x - stat.MASK_RHO_DB[0]) / (stat.MASK_RHO_DB[1] - stat.MASK_RHO_DB[0])
        fy = (y - stat.MASK_LOG_I[0]) / (stat.MASK_LOG_I[1] - stat.MASK_LOG_I[0])
        i0 = np.minimum(np.floor(fx).astype(int), table.shape[0] - 2)
        j0 = np.minimum(np.floor(fy).astype(int), table.shape[1] - 2)
        ax, ay = fx - i0, fy - j0
        want = ((1 - ax) * (1 - ay) * table[i0, j0] + ax * (1 - ay) * table[i0 + 1, j0]
                + (1 - ax) * ay * table[i0, j0 + 1] + ax * ay * table[i0 + 1, j0 + 1])
        want = np.where(rel_in < 0.01, 1.0, want)
        assert np.array_equal(got, want)
        assert got.min() < 0.5 and got.max() == 1.0


# --- the new formulas against the old ones (978e87d's, written out here), on bodies crossing the beam's edge too ---

def _old_centre_y(p, view, length_m, width_m, rows, max_distance_m):
    """visible_centre_y as it was: the pattern through dB, r⁻⁴ by pow, every outline point's arctangent."""
    from radarnode.radar.object_model import outline_points
    y = view.y_m.copy()
    t_i, j_i = np.nonzero(rows)
    px, py, share = outline_points(view.centre_x_m[t_i, j_i], view.centre_y_m[t_i, j_i],
                                   view.orientation_rad[t_i, j_i], length_m[j_i], width_m[j_i])
    z = 0.0 if view.z_m is None else np.asarray(view.z_m, dtype=np.float64)[t_i, j_i][:, None, None]
    r_s = np.sqrt(px ** 2 + py ** 2 + z ** 2)
    az_s = np.arctan2(py, px)
    inside = (share > 0.0) & in_fov(p, r_s, az_s) & (r_s <= max_distance_m)
    power = np.where(inside, share * np.maximum(r_s, 0.1) ** -4 * 10.0 ** (equation.pattern_db(p, az_s) / 10.0), 0.0)
    total = power.sum(axis=(1, 2))
    seen = total > 0.0
    t_i, j_i, total = t_i[seen], j_i[seen], total[seen]
    yc = (power * py).sum(axis=(1, 2))[seen] / total
    z0 = 0.0 if view.z_m is None else np.asarray(view.z_m, dtype=np.float64)[t_i, j_i]
    r3 = np.sqrt(view.x_m[t_i, j_i] ** 2 + yc * yc + z0 * z0)
    ok = in_fov(p, r3, np.arctan2(yc, view.x_m[t_i, j_i])) & (r3 <= max_distance_m)
    y[t_i[ok], j_i[ok]] = yc[ok]
    return y


def _old_outline_interference(self, view, rng_m, on_bin, cell_d, cell_r, max_distance_m, outline=None):
    """ObjectModel._outline_interference as it was: gains through dB, (r/r)⁴ by pow, a bincount per actor."""
    p, stat, sc = self.preset, self.statistic, self.scene
    m, n_r = p.num_chirps, p.num_range_bins
    t_i, j_i = np.nonzero(on_bin > 0.0)
    from radarnode.radar.object_model import outline_points
    px, py, weight = outline_points(view.centre_x_m[t_i, j_i], view.centre_y_m[t_i, j_i],
                                    view.orientation_rad[t_i, j_i], sc.length_m[j_i], sc.width_m[j_i])
    z = 0.0 if view.z_m is None else np.asarray(view.z_m, dtype=np.float64)[t_i, j_i][:, None, None]
    r_s = np.sqrt(px ** 2 + py ** 2 + z ** 2)
    az_s = np.arctan2(py, px)
    keep = (weight > 0.0) & in_fov(p, r_s, az_s) & (r_s <= max_distance_m)
    row = np.broadcast_to(np.arange(t_i.size)[:, None, None], keep.shape)[keep]
    px, py, r_s, az_s, weight = px[keep], py[keep], r_s[keep], az_s[keep], weight[keep]
    t_k, j_k = t_i[row], j_i[row]
    gain = 10.0 ** ((equation.pattern_db(p, az_s) - equation.pattern_db(p, view.azimuth_rad[t_k, j_k])) / 10.0)
    e_s = on_bin[t_k, j_k] * weight * (np.maximum(rng_m[t_k, j_k], 0.1) / np.maximum(r_s, 0.1)) ** 4 * gain
    v_s = (view.vx_mps[t_k, j_k] * px + view.vy_mps[t_k, j_k] * py) / np.maximum(r_s, 1e-9)
    pos_d, pos_r = np.mod(v_s / p.doppler_bin_mps, m), np.mod(r_s / p.range_resolution_m, n_r)
    dd = np.mod(pos_d[:, None] - cell_d[t_k] + m / 2.0, m) - m / 2.0
    dr = np.mod(pos_r[:, None] - cell_r[t_k] + n_r / 2.0, n_r) - n_r / 2.0
    put = stat.ring_kernel(dd, dr) * e_s[:, None]
    t_n = on_bin.shape[0]
    return np.stack([np.bincount(t_k, weights=put[:, i], minlength=t_n) for i in range(put.shape[1])], axis=1)


def _crossing_traffic():
    # a truck in the next lane the ego passes (the beam's edge crosses it), a car ahead, one far off: bodies whose
    # outlines reach the ring of another, some crossing the edge of the field of view
    return scenario("""  - {id: lead, class: car, x_m: 14.0, lane: 1, speed_mps: 6.0}
  - {id: truck, class: truck, x_m: 30.0, lane: 0, speed_mps: 0.0}
  - {id: far, class: car, x_m: 60.0, lane: 2, speed_mps: 9.0}""",
                    ego="{speed_mps: 6.0}", road="{lanes: 3, ego_lane: 1}", duration=9.0, seed=2)


@pytest.mark.parametrize("exponent", [1.0, 1.5])
def test_the_centroid_and_the_masking_agree_with_the_old_formulas(exponent, monkeypatch):
    sc = _crossing_traffic()
    rc = radar_config(sc)
    p = dataclasses.replace(rc.preset, element_pattern_exponent=exponent)
    scene = Scene(sc)
    model = make_model("object", scene, p, np.random.default_rng(1), rc.signal)
    truth, view, rng_m, az, observable, snr = masking_inputs(p, scene, np.arange(120) * sc.period_s)
    crossing = ((view.x_m != truth.x_m) | (view.y_m != truth.y_m)) & model.extended
    assert crossing.any()                                   # the edge-crossing path is taken
    rows = observable & model.extended
    shared = SharedOutline(p, view, scene.length_m, scene.width_m, rows, p.max_range_m)
    new_m = model._masking(view, rng_m, snr, observable, crossing, p.max_range_m, shared)
    new_y = visible_centre_y(p, view, scene.length_m, scene.width_m, rows, p.max_range_m, shared)
    old_y = _old_centre_y(p, view, scene.length_m, scene.width_m, rows, p.max_range_m)
    monkeypatch.setattr(type(model), "_outline_interference", _old_outline_interference)
    old_m = model._masking(view, rng_m, snr, observable, crossing, p.max_range_m)
    assert (old_m < 0.99).any() and (old_y != view.y_m).any()       # both formulas do something here
    np.testing.assert_allclose(new_y, old_y, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(new_m, old_m, rtol=1e-12, atol=1e-12)


def test_the_detected_and_resolved_posts_are_those_the_draws_and_the_resolution_select():
    """The cluster block's guardrail posts (their cycles, in order) against the selection replayed on its own: the
    block's hit stream drawn again from its recorded state, Pd and the resolution rule applied with boolean masks."""
    from radarnode.radar.object_model import RuntimeConfig, resolved_posts
    sc = scenario("  - {id: lead, class: car, x_m: 40.0, lane: 0, speed_mps: 20.0}", ego="{speed_mps: 25.0}",
                  road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0, guardrails: {left_offset_m: 1.0, "
                       "right_offset_m: 1.0, post_spacing_m: 2.0, rcs_dbsm: 5.0}}", duration=8.0, seed=4)
    rc = radar_config(sc)
    model = make_model("object", Scene(sc), rc.preset, np.random.default_rng(3), rc.signal, clusters_wanted=True)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=True)
    model.planned_cycles = 100
    for k in range(100):
        model.step(k * sc.period_s, cfg)
    ch = model._cache
    blocks = ch["cluster_blocks"]
    assert len(blocks) >= 2
    svx, svy = ch["view"].sensor_vx_mps, ch["view"].sensor_vy_mps
    for b, block in enumerate(blocks):
        lo = b * block["cycles"] if b == 0 else sum(x["cycles"] for x in blocks[:b])
        hi = lo + block["cycles"]
        g = model._posts(ch, lo, hi)
        rng = np.random.default_rng()
        rng.bit_generator.state = block["states"]["hit"]
        u = rng.random(g["range"].size)
        first = u < g["pd"]
        g1 = {key: val[first] for key, val in g.items()}
        g1["cos"], g1["sin"] = np.cos(g1["true_azimuth"]), np.sin(g1["true_azimuth"])
        kept = resolved_posts(rc.preset, g1, u[first], np.arange(int(first.sum())), svx, svy,
                              model.statistic.response)
        # None for every post (what the block passes): the same; a subset by index: the same as that subset's table
        assert np.array_equal(resolved_posts(rc.preset, g1, u[first], None, svx, svy, model.statistic.response), kept)
        some = np.flatnonzero(np.arange(int(first.sum())) % 3 != 1)
        g2 = {key: val[some] for key, val in g1.items()}
        assert np.array_equal(resolved_posts(rc.preset, g1, u[first], some, svx, svy, model.statistic.response),
                              resolved_posts(rc.preset, g2, u[first][some], None, svx, svy, model.statistic.response))
        assert 0 < kept.sum() < first.sum() < g["range"].size      # draws and resolution both drop some
        np.testing.assert_array_equal(block["hit_cycle"], g1["cycle"][kept] - lo)
        np.testing.assert_array_equal(block["post_cycle"], g["cycle"] - lo)
