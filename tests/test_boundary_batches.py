"""The road-boundary process's batch path (``RadarNode.boundary_payloads_many``, ``MessageCodec.encode_values``) and
the estimator's gap rule and result type written for speed: each gives what the plain path gives, bit for bit."""

from __future__ import annotations

import dataclasses
import math
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from radarnode.errors import WireError
from radarnode.perception.boundaries import Boundary, RoadBoundaryEstimator
from radarnode.radar.setup import load_scenario
from radarnode.wire.dbc import load_own_database
from radarnode.wire.codec import MessageCodec
from radarnode.wire.group import make_node


ROOT = Path(__file__).resolve().parents[1]


def _old_gap_rule(xs: np.ndarray, sections: int, section_m: float, max_missing: int) -> tuple[int, int, bool]:
    """Seed 002's rule as _fit computed it before it was written with nonzero(): (reach, seen, ok)."""
    xs = xs - xs.min()
    row = np.bincount((xs / section_m).astype(np.intp), minlength=sections)[:sections].tolist()
    reach = sections - next((j for j in range(sections) if row[sections - 1 - j]), sections)
    seen = sum(1 for j in range(reach) if row[j])
    missing = (reach - seen) + max(0, sections - reach - max_missing)
    return reach, seen, missing <= max_missing and reach >= 2


def test_the_gap_rule_is_the_old_one_for_every_pattern_of_filled_sections():
    """Every pattern of filled sections among the first 12 (gaps at the start, in the middle, at the end, points
    past the last section, all, one): the same validity and confidence as the rule written with Python loops."""
    est = RoadBoundaryEstimator()
    rng = np.random.default_rng(1)
    checked = 0
    for pattern in range(1, 1 << 12):
        cells = [j for j in range(12) if pattern >> j & 1]
        if cells[0] != 0:                     # the nearest inlier starts the first section
            continue
        x = np.concatenate([10.0 + est.section_m * (j + rng.uniform(0.05, 0.95, 3)) for j in cells])
        y = 2.0 + 0.01 * x
        x[np.argmin(x)] = 10.0
        reach, seen, ok = _old_gap_rule(x, est.sections, est.section_m, est.max_missing)
        b = est._fit(x, y, np.ones((1, x.size), dtype=bool), np.ones(1, dtype=bool), kappa=0.0)[0]
        assert b.valid == ok, cells
        if ok:
            assert b.confidence == seen / est.sections and b.range_start_m == 10.0 and b.range_end_m == x.max()
        checked += 1
    assert checked == 1 << 11


def test_a_found_boundary_is_the_dataclass_built_the_usual_way():
    fast = Boundary.found(1.5, 0.01, 2e-4, 4.0, 120.0, 0.7)
    plain = Boundary(True, 1.5, 0.01, 2e-4, 4.0, 120.0, 0.7)
    assert fast == plain and hash(fast) == hash(plain) and repr(fast) == repr(plain)
    assert dataclasses.astuple(fast) == dataclasses.astuple(plain)
    with pytest.raises(dataclasses.FrozenInstanceError):
        fast.offset_m = 0.0


def _twins():
    sc = load_scenario(ROOT / "scenarios" / "highway_cut_in.yaml")
    return make_node(sc, fidelity="object"), make_node(sc, fidelity="object")


def test_a_batch_of_boundary_frames_is_the_frames_of_its_cycles_one_by_one():
    """Cycles of guardrail-like points (found, lost, saturating offsets) with the sensor ID changed in the
    middle: the same payloads, saturation counts, E2E counters and last estimate as one cycle at a time."""
    one, many = _twins()
    again = _twins()[0]
    for node in (one, many, again):   # from cycle 30 a left boundary far beyond RBL_LatOffset's range: saturated
        estimate, calls = node.boundaries._estimate, [0]     # (a cycle's estimate, whichever way it is updated)

        def far(*a, _estimate=estimate, _calls=calls, **k):
            left, right = _estimate(*a, **k)
            _calls[0] += 1
            return (Boundary.found(1e4, 0.0, 0.0, 0.0, 1e4, 1.0) if _calls[0] > 30 else left), right
        node.boundaries._estimate = far
    rng = np.random.default_rng(4)
    cycles = []
    for k in range(40):
        x = np.concatenate([np.arange(5.0, 150.0, 2.0)] * 2) + rng.normal(0, 0.05, 146)
        y = np.concatenate([np.full(73, 3.0), np.full(73, -3.0)]) + rng.normal(0, 0.1, 146)
        if 12 <= k < 16:                            # a gap: nothing seen
            x, y = x[:0], y[:0]
        vx = np.full(x.size, -27.0)
        cols = (x, y, vx, np.zeros(x.size), np.hypot(x, y))
        cycles.append((cols, 0.072 if k else 0.0, (27.0, 0.0), 0.0, 0 if k < 20 else 5))
    want = [b"".join(p.tobytes() for _, p in one.boundary_payloads(*c)) for c in cycles]
    got = many.boundary_payloads_many(cycles[:7]) + many.boundary_payloads_many(cycles[7:])
    assert got == want
    assert any(w[2:] != b"\x00" * 6 for w in want[:12]), "boundaries were found"
    assert one.saturated == many.saturated and one.saturated["RBL_LatOffset"] > 0
    assert one._e2e._counter == many._e2e._counter and one.last_boundaries == many.last_boundaries
    assert many.boundary_payloads_many([]) == []
    # the road-boundary process's rows leave the range out: the same frames from the clusters' positions
    assert again.boundary_payloads_many([((*c[0][:4], None), *c[1:]) for c in cycles]) == want


def _road_cycles(seed: int, n: int) -> list[tuple]:
    """Cycles of a radar driving a bend between guardrails with cars among the posts: each cycle's detections
    (x, y, range rate, dt, sensor velocity, yaw rate, range), with gaps (nothing seen for long enough that the
    search restarts), cycles of one detection, a stop and a reversing sensor."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        speed = 0.0 if 50 <= k < 55 else (-3.0 if 55 <= k < 58 else 25.0 + 5.0 * math.sin(k / 9.0))
        yaw = 0.02 * math.sin(k / 17.0) if k > 20 else 0.0
        kappa = yaw / speed if abs(speed) > 1.0 else 0.0
        x = np.concatenate([np.arange(3.0, 160.0, 2.5)] * 2) + rng.normal(0, 0.05, 126)
        y = np.concatenate([np.full(63, 3.7), np.full(63, -4.1)]) + 0.5 * kappa * x * x + rng.normal(0, 0.1, 126)
        r = np.hypot(x, y)
        rate = -speed * x / r + rng.normal(0, 0.05, 126)
        cars = rng.uniform(10.0, 90.0, 3)
        x, y = np.append(x, cars), np.append(y, rng.uniform(-2.0, 2.0, 3))
        r = np.hypot(x, y)
        rate = np.append(rate, rng.uniform(-10.0, 10.0, 3))
        if 30 <= k < 45:                     # nothing seen: the search restarts
            x, y, rate, r = x[:0], y[:0], rate[:0], r[:0]
        elif k in (60, 61):                  # one detection
            x, y, rate, r = x[:1], y[:1], rate[:1], r[:1]
        out.append((x, y, rate, 0.072 if k else 0.0, (speed, 0.3 * yaw), yaw, np.maximum(r, 1e-6)))
    return out


@pytest.mark.parametrize("split", [1, 2, 7, 32, 200])
def test_update_many_is_update_cycle_by_cycle_bit_for_bit(split):
    """RoadBoundaryEstimator.update_many against update, in batches of 1 to 200 cycles: the same boundaries (every
    float the same bits), the same accumulated points and odometry pose, on a bend, through a stop, a reversing
    sensor and a restart of the search."""
    cycles = _road_cycles(3, 120)
    one, many = RoadBoundaryEstimator(), RoadBoundaryEstimator()
    want = [one.update(*c) for c in cycles]
    got = []
    for a in range(0, len(cycles), split):
        part = cycles[a:a + split]
        got += many.update_many(np.concatenate([c[0] for c in part]), np.concatenate([c[1] for c in part]),
                                np.concatenate([c[2] for c in part]), np.concatenate([c[6] for c in part]),
                                [c[0].size for c in part], [c[3:6] for c in part])
    assert sum(b.valid for pair in want for b in pair) > 100, "boundaries were found"
    assert any(not pair[0].valid and not pair[1].valid for pair in want[30:45]), "the search restarted"
    assert [dataclasses.astuple(b) for pair in got for b in pair] == \
        [dataclasses.astuple(b) for pair in want for b in pair]
    assert many._pose == one._pose and many._cycle == one._cycle
    assert len(many._points) == len(one._points)
    for p, q in zip(many._points, one._points):
        assert np.array_equal(p, q)


def test_update_many_refuses_counts_that_do_not_match():
    est = RoadBoundaryEstimator()
    x = np.arange(4.0)
    with pytest.raises(ValueError, match="counts"):
        est.update_many(x, x, x, x + 1.0, [2, 1], [(0.072, (20.0, 0.0), 0.0)] * 2)
    with pytest.raises(ValueError, match="motion"):
        est.update_many(x, x, x, x + 1.0, [4], [(0.072, (20.0, 0.0), 0.0)] * 2)


def test_encode_values_is_encode_for_one_frame_and_refuses_nan_counting_nothing():
    db = load_own_database()
    codec = MessageCodec(db.get_message_by_name("RoadBoundary_Left"), Counter())
    rng = np.random.default_rng(2)
    for _ in range(200):
        values = [float(rng.uniform(f.minimum - 0.2 * (f.maximum - f.minimum), f.maximum + 0.2 * (f.maximum -
                                                                                                   f.minimum)))
                  for f in codec.fields]
        assert codec.encode_values(values) == codec.encode(dict(zip(codec.signal_names, values)))[0].tobytes()
        assert codec.encode_values(values) == codec.encode(
            {n: np.array([v, v]) for n, v in zip(codec.signal_names, values)})[1].tobytes()
    before = Counter(codec.saturated)
    bad = [1e9] * len(codec.fields)
    bad[-1] = math.nan
    with pytest.raises(WireError, match=f"signal {codec.signal_names[-1]} got NaN"):
        codec.encode_values(bad)
    assert codec.saturated == before
    with pytest.raises(WireError, match="values for"):
        codec.encode_values([0.0])


def _batched(est, cycles, dtype=np.float64):
    cat = lambda k: np.concatenate([c[k] for c in cycles]).astype(dtype)  # noqa: E731
    return est.update_many(cat(0), cat(1), cat(2), cat(6), [c[0].size for c in cycles], [c[3:6] for c in cycles])


@pytest.mark.parametrize("dtype", [np.float32, np.longdouble])
def test_update_many_follows_other_dtypes_as_update_does(dtype):
    """Detections of another dtype than float64 (float32 within its rounding of the stationary threshold: an
    independent tester's case, where one float64 table kept 63 points and update 7), and a long-double velocity: the
    same estimates as update cycle by cycle in that dtype."""
    cycles = _road_cycles(8, 60)
    cycles = [(x, y, -np.float64(v[0]) * x / r * (1.0 + 1e-7), dt, v, yaw, r) for x, y, _, dt, v, yaw, r in cycles]
    one, many = RoadBoundaryEstimator(), RoadBoundaryEstimator()
    want = [one.update(*(np.asarray(a, dtype=dtype) if k in (0, 1, 2, 6) else a for k, a in enumerate(c)))
            for c in cycles]
    got = _batched(many, cycles, dtype)
    assert [dataclasses.astuple(b) for pair in got for b in pair] == \
        [dataclasses.astuple(b) for pair in want for b in pair]
    slow = [(x, y, rate, dt, (np.longdouble(v[0]), np.longdouble(v[1])), yaw, r) for x, y, rate, dt, v, yaw, r in cycles]
    one, many = RoadBoundaryEstimator(), RoadBoundaryEstimator()
    assert [dataclasses.astuple(b) for c in slow for b in one.update(*c)] == \
        [dataclasses.astuple(b) for pair in _batched(many, slow) for b in pair]


def test_update_many_refuses_columns_that_do_not_fit_and_changes_nothing():
    est = RoadBoundaryEstimator()
    _batched(est, _road_cycles(2, 12))
    pose, cycle, points = est._pose, est._cycle, len(est._points)
    x = np.arange(4.0)
    with pytest.raises(ValueError, match="four columns"):
        est.update_many(x, x, x, x[:3] + 1.0, [4], [(0.072, (20.0, 0.0), 0.0)])
    assert (est._pose, est._cycle, len(est._points)) == (pose, cycle, points)
