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

from helpers import scenario
from radarnode.radar import equation
from radarnode.radar.models import make_model
from radarnode.radar.object_model import SharedOutline, in_fov, nearest_in_fov, visible_centre_y, visible_outline
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
    truth = scene.views(np.arange(80) * sc.period_s)
    x_in, y_in = nearest_in_fov(p, truth, scene.length_m, scene.width_m)
    view = dataclasses.replace(truth, x_m=x_in, y_m=y_in)
    rows = in_fov(p, view.range_m, view.azimuth_rad) & (scene.length_m > 0.5)
    return p, scene, view, rows


def test_a_shared_outline_gives_each_subset_the_bits_it_gives_computed_alone():
    p, scene, view, rows = _view_of(_traffic())
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
    p, scene, view, rows = _view_of(sc)
    rc = radar_config(sc)
    model = make_model("object", scene, p, np.random.default_rng(1), rc.signal)
    rng_m, az = view.range_m, view.azimuth_rad
    observable = in_fov(p, rng_m, az)
    snr = equation.snr_db(p, rng_m, scene.rcs_dbsm + np.zeros(rng_m.shape), 0.0, az)
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
