"""Shortcuts that compute the same bits with less work, each held against the path it shortens.

The object level's guardrail posts take the Cramér–Rao bounds with one SNR power ratio for the three of them
(``equation.crbs``), the window response without its masking passes where every offset lies inside its table,
the staggered look's probability without the steady Pd that an all-Swerling-1 input never reads, and the lobe
test's offsets without a stack of temporaries; a cluster block holds only the rows a reader of rows needs until a
cluster list is built from it; a node looks its frames' CAN IDs up per sensor ID. None of these may move a bit: each
test below compares with the long way written out or forced.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from helpers import scenario
from radarnode.radar import equation
from radarnode.radar.models import make_model
from radarnode.radar.object_model import RuntimeConfig, _lobe_offsets
from radarnode.radar.presets import PRESETS
from radarnode.radar.setup import radar_config
from radarnode.scene.world import Scene
from radarnode.wire import ars408 as P
from radarnode.wire import ids
from radarnode.wire.node import RadarNode


def _rho(snr_db):
    return 10.0 ** (np.asarray(snr_db, dtype=np.float64) / 10.0)


@pytest.mark.parametrize("name", ["ars408_like", "mimo12"])
@pytest.mark.parametrize("virtual", [None, 1])
def test_the_bounds_at_once_are_the_three_bounds(name, virtual):
    p = PRESETS[name] if virtual is None else dataclasses.replace(PRESETS[name], num_tx=1, num_rx=virtual)
    rng = np.random.default_rng(5)
    snr = np.concatenate([rng.uniform(-20.0, 70.0, 500), [0.0, -0.0, 13.0, 1e-300, 300.0]])
    az = np.concatenate([rng.uniform(-1.6, 1.6, 500), [0.0, np.pi / 2, -np.pi / 2, 1.5, -1e-9]])
    r, v, a = equation.crbs(p, snr, az)
    for got, want in ((r, equation.crb_range_m(p, snr)), (v, equation.crb_speed_mps(p, snr)),
                      (a, equation.crb_azimuth_rad(p, snr, az))):
        assert got.dtype == want.dtype and np.array_equal(got, want)
    # and the bounds themselves, written out (the formulas the functions were before they shared ρ)
    rho = _rho(snr)
    assert np.array_equal(r, p.range_resolution_m * np.sqrt(6.0) / (2.0 * np.pi * np.sqrt(rho)))
    assert np.array_equal(v, p.speed_resolution_mps * np.sqrt(6.0) / (2.0 * np.pi * np.sqrt(rho)))
    k = p.num_virtual
    cos_t = np.maximum(np.cos(az), np.cos(np.radians(85.0)))
    if k < 2:
        want = p.angular_resolution_rad / np.sqrt(2.0 * (rho / k)) / cos_t
    else:
        want = (1.0 / (2.0 * np.pi * p.element_spacing_wl * cos_t)) * np.sqrt(6.0 / ((rho / k) * k * (k * k - 1)))
    assert np.array_equal(a, want)
    # scalars stay scalars' shape
    assert np.shape(equation.crbs(p, 20.0, 0.1)[2]) == ()


def _statistic():
    sc = scenario("  - {id: lead, class: car, x_m: 40.0, lane: 0, speed_mps: 20.0}")
    rc = radar_config(sc)
    return make_model("object", Scene(sc), rc.preset, np.random.default_rng(0), rc.signal).statistic


@pytest.mark.parametrize("axis", ["r", "d"])
def test_the_window_response_inside_its_table_is_the_masked_path(axis):
    stat = _statistic()
    reach = stat.RESPONSE_REACH
    rng = np.random.default_rng(11)
    inside = np.concatenate([rng.uniform(-reach, reach, 4000), [-reach, reach, 0.0, -0.0, reach - 1e-12,
                                                                np.nextafter(-reach, 0.0)]])
    fast = stat.response(axis, inside)
    # one value outside (or NaN) sends the whole call through the masked path: the inside values must not move
    for extra in (reach + 1e-9, -reach - 3.0, np.nan, np.inf):
        slow = stat.response(axis, np.append(inside, extra))
        assert np.array_equal(slow[:-1], fast)
        assert slow[-1] == 0.0 or (np.isnan(extra) and np.isnan(slow[-1]))
    # 2-D input (the lobe test's rows) the same, element by element
    assert np.array_equal(stat.response(axis, inside[:4000].reshape(4, 1000)), fast[:4000].reshape(4, 1000))
    # and against np.interp on the table's grid (what the tabulated response is): to its interpolation's rounding
    grid, table, _ = stat.__dict__["_response_tables"][axis]
    assert fast == pytest.approx(np.interp(inside, grid, table), rel=1e-12, abs=1e-15)


def test_the_second_look_of_swerling_1_alone_skips_nothing_it_reads():
    stat = _statistic()
    rng = np.random.default_rng(2)
    rho = np.concatenate([rng.uniform(-15.0, 55.0, 3000), [-10.0, 50.0, 49.99, np.nan]])
    fast = stat.pd_second_look(rho, 0.58, 1)
    # a Swerling 0 entry appended sends the call through np.where with the steady Pd: the rest the same bits
    slow = stat.pd_second_look(np.append(rho, 20.0), 0.58, np.append(np.ones(rho.size, dtype=int), 0))
    assert fast.shape == rho.shape and fast.dtype == np.float64
    assert np.array_equal(slow[:-1], fast, equal_nan=True)
    assert slow[-1] == stat.pd_of_snr(20.0 + 0.58, 0)
    # a 0-d input stays an array, as np.where gave it; an empty one is the steady Pd's empty array
    assert isinstance(stat.pd_second_look(np.float64(20.0), 0.58, 1), np.ndarray)
    assert stat.pd_second_look(np.zeros(0), 0.58, 1).shape == (0,)


def test_the_lobe_offsets_are_the_four_expressions():
    rng = np.random.default_rng(4)
    x = rng.uniform(0.0, 300.0, 2000)
    cell = np.rint(x)
    other = rng.uniform(-4.0, 4.0, 2000)
    step = np.sign(other)
    out = _lobe_offsets(x, cell, other, step)
    assert np.array_equal(out, np.stack([cell - x, step + cell - x, -other, step - other]))
    assert out.dtype == np.float64
    assert _lobe_offsets(x.astype(np.float32), cell.astype(np.float32), other.astype(np.float32),
                         step.astype(np.float32)).dtype == np.float32


GUARDRAILS = ("{lanes: 2, lane_width_m: 3.5, ego_lane: 0, guardrails: {left_offset_m: 1.0, right_offset_m: 1.0, "
              "post_spacing_m: 2.0, rcs_dbsm: 5.0}}")


def test_a_block_read_as_rows_first_builds_the_same_cluster_lists():
    """Rows first (the log's road-boundary process), then cluster lists from the same blocks, against a model that
    built every cycle's cluster list: the same lists, field by field, and rows equal to their positions and speeds."""
    sc = scenario("  - {id: lead, class: car, x_m: 40.0, lane: 0, speed_mps: 20.0}", ego="{speed_mps: 25.0}",
                  road=GUARDRAILS, duration=12.0, seed=4)
    rc = radar_config(sc)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=True)

    def model():
        m = make_model("object", Scene(sc), rc.preset, np.random.default_rng(3), rc.signal, clusters_wanted=True)
        m.planned_cycles = 150
        return m

    listed, rows_first = model(), model()
    for k in range(150):
        t = k * sc.period_s
        want = listed.step(t, cfg)[0].clusters
        if k % 3:                          # rows only (as the pipeline reads them), a list now and then
            rows_first.step(t, cfg, cluster_list=False)
            rows, a, b = rows_first.cluster_rows()
            assert not rows.flags.writeable
            for j, name in enumerate(("dist_long_m", "dist_lat_m", "vrel_long_mps", "vrel_lat_mps")):
                assert np.array_equal(rows[j, a:b], getattr(want, name))
        else:
            got = rows_first.step(t, cfg)[0].clusters
            assert len(got) == len(want) > 0
            for f in dataclasses.fields(want):
                assert np.array_equal(getattr(got, f.name), getattr(want, f.name), equal_nan=True), (k, f.name)


def test_frame_ids_follow_a_sensor_id_changed_between_cycles(db):
    """The node's table of CAN IDs per sensor ID: a change of SensorID between cycles (and back) moves every
    frame at the next cycle, ARS 408 messages by 0x10 and own messages by their plan (radarnode.wire.ids)."""
    from tests.test_node import TRAFFIC, _cfg_frame
    node = RadarNode(scenario(TRAFFIC))
    for k, sensor in enumerate((0, 0, 3, 3, 0, 7, 7)):
        if sensor != node.config.sensor_id:
            node.receive(_cfg_frame(db, node.config.sensor_id, RadarCfg_SensorID_valid=1, RadarCfg_SensorID=sensor),
                         k * 0.072)
        out = node.cycle(k * 0.072)
        assert node.config.sensor_id == sensor
        for m in out.messages:
            own = ids.split_own_id(m.arbitration_id)
            if own is not None:
                assert own[1] in (sensor, None)
            else:
                assert P.unshifted(m.arbitration_id)[1] == sensor or m.arbitration_id == P.COLL_DET_RELAY


def test_a_few_frames_encoded_in_python_numbers_are_the_arrays_frames(db):
    """MessageCodec.encode of a few frames (frames × signals ≤ FEW_VALUES) goes frame by frame in Python numbers:
    the same payloads and the same saturation counts as its array path (forced here with FEW_VALUES = 0), for values
    inside, at and beyond every signal's range, ints, bools, float32, a 0-d array and a scalar for every frame; a NaN
    or a column of another length is refused as the array path refuses it."""
    from collections import Counter

    from radarnode.wire import codec as codec_module
    from radarnode.wire.codec import MessageCodec
    from radarnode.errors import WireError
    rng = np.random.default_rng(8)
    for frame_id in (P.OBJ_GENERAL, P.OBJ_QUALITY, P.OBJ_EXTENDED, P.CLUSTER_GENERAL, P.OBJ_WARNING):
        fast, slow = (MessageCodec(db.get_message_by_frame_id(frame_id), Counter()) for _ in range(2))
        for n in (1, 2, 3, 4, 6):         # below, at and above FEW_VALUES (7 signals: 3 frames), and twice it
            for trial in range(40):
                values = {}
                for k, (name, f) in enumerate(zip(fast.signal_names, fast.fields)):
                    span = f.maximum - f.minimum
                    col = rng.uniform(f.minimum - 0.1 * span - 1.0, f.maximum + 0.1 * span + 1.0, n)
                    col[rng.random(n) < 0.2] = f.minimum
                    col[rng.random(n) < 0.2] = f.maximum
                    col[rng.random(n) < 0.1] = f.maximum + 0.4e-6 * f.scale        # within the tolerance
                    kind = (trial + k) % 6
                    values[name] = (col if kind == 0 else col.astype(np.float32) if kind == 1
                                    else np.rint(col).astype(np.int64) if kind == 2 and f.minimum >= 0
                                    else float(col[0]) if kind == 3 else np.array(col[0]) if kind == 4
                                    else col)
                    if trial == 7:
                        values[name] = rng.random(n) < 0.5                          # bools
                got = fast.encode(values)
                saved = codec_module.FEW_VALUES
                codec_module.FEW_VALUES = 0
                try:
                    want = slow.encode(values)
                finally:
                    codec_module.FEW_VALUES = saved
                assert got.dtype == want.dtype and np.array_equal(got, want), (frame_id, n, trial)
                assert fast.saturated == slow.saturated
        assert sum(fast.saturated.values()) > 0           # the test reached beyond the ranges
    c = MessageCodec(db.get_message_by_frame_id(P.OBJ_GENERAL), Counter())
    values = {name: np.array([1.0, 2.0]) for name in c.signal_names}
    values[c.signal_names[3]] = np.array([1.0, np.nan])
    with pytest.raises(WireError, match=f"signal {c.signal_names[3]} got NaN"):
        c.encode(values)
    assert not c.saturated
    values[c.signal_names[3]] = np.array([1.0, 2.0, 3.0])
    with pytest.raises(ValueError):
        c.encode(values)


def test_a_few_frames_come_back_writeable_and_counted_field_by_field(db):
    """The frame-by-frame path returns what the array path returns: a writeable (n, length) array, and its
    saturated values counted in the shared counter field by field, in the message's signal order, as the array
    path adds them (frame by frame, a later frame's earlier field went in after an earlier frame's later one: an
    independent tester's finding)."""
    from collections import Counter

    from radarnode.wire.codec import MessageCodec
    c = MessageCodec(db.get_message_by_frame_id(P.OBJ_GENERAL), Counter())
    out = c.encode({name: np.zeros(2) for name in c.signal_names})
    out[0, 0] = 1                                              # writeable, as the array path's
    one = c.encode({name: 0.0 for name in c.signal_names})     # (one frame of scalars: the same)
    one[0, 0] = 1
    values = {name: np.zeros(2) for name in c.signal_names}
    values["Obj_RCS"] = np.array([1e9, 0.0])                    # frame 1 saturates the later field …
    values["Obj_DistLong"] = np.array([0.0, 1e9])               # … frame 2 the earlier one
    c.encode(values)
    assert list(c.saturated) == [n for n in c.signal_names if n in ("Obj_DistLong", "Obj_RCS")]
    assert c.saturated["Obj_DistLong"] == c.saturated["Obj_RCS"] == 1


@pytest.mark.parametrize("gain", [float("nan"), float("inf"), None, "0.58", np.array([0.5]), True])
def test_the_second_look_refuses_a_gain_that_is_not_a_finite_number(gain):
    """A NaN gain built a table named second_nan, which the table cache then could not read back (the whole file
    was computed again every start): refused, whatever the Swerling case, before anything is computed."""
    stat = _statistic()
    before = set(stat._second_tables)
    for swerling in (1, 0, np.array([0, 1])):
        with pytest.raises(ValueError, match="gain_db .* is not allowed; expected a finite number of dB"):
            stat.pd_second_look(np.array([10.0, 20.0]), gain, swerling)
    assert set(stat._second_tables) == before
    assert np.all(np.isfinite(stat.pd_second_look(np.array([10.0, 20.0]), np.float32(0.58), 1)))


def test_a_cycle_without_objects_gets_a_new_list_of_the_listed_fields_and_dtypes():
    # a car ahead pulls away past the sensor's range: cycles with an object, then cycles without (which build
    # their list as a copy of one dict of empty fields instead of 23 views, a fresh list every cycle)
    sc = scenario("  - {id: away, class: car, x_m: 40.0, lane: 1, speed_mps: 70.0}", duration=12.0)
    p = radar_config(sc).preset
    for estimate in (None, "off"):
        model = make_model("object", Scene(sc), p, np.random.default_rng(sc.seed), radar_config(sc).signal)
        cfg = RuntimeConfig(max_distance_m=p.max_range_m, clusters=False)
        frames = []
        for k in range(int(sc.duration_s / sc.period_s)):
            # an ego-motion estimate off the truth takes the cycle-by-cycle DynProp path, with or without objects
            sv = None if estimate is None else (19.0, 0.3)
            frames.append(model.step(k * sc.period_s, cfg, sv)[0].objects)
        full = [o for o in frames if len(o)]
        empty = [o for o in frames if not len(o)]
        assert full and len(empty) > 20
        assert len({id(o) for o in frames}) == len(frames)
        names = list(vars(full[0]))
        for o in empty:
            assert list(vars(o)) == names
            for name in names:
                got, listed = getattr(o, name), getattr(full[0], name)
                assert isinstance(got, np.ndarray) and got.shape == (0,) and got.dtype == listed.dtype, name
        empty[0].note = "mine"
        assert not hasattr(empty[1], "note")
