"""Velocity ambiguity as the real radar has it, at every level (issue 9 items 3 and 4): staggered ramps on
ars408_like, stationary candidates, AmbigState filled truthfully, never a silent wrap."""

from __future__ import annotations

import math

import numpy as np
import pytest

from radarnode.radar.setup import radar_config
from radarnode.radar.chain import DspChain
from radarnode.perception.types import (AMBIG_AMBIGUOUS, AMBIG_STAGGERED, AMBIG_STATIONARY, DYN_CROSSING_MOVING,
                                        DYN_MOVING, DYN_ONCOMING, Detections)
from radarnode.radar import ambiguity, detection_model
from radarnode.radar.models import make_model
from radarnode.radar.object_model import RuntimeConfig
from radarnode.radar.presets import PRESETS
from radarnode.radar.scatterers import point_targets
from radarnode.scene.world import Scene
from tests.helpers import scenario

ARS = PRESETS["ars408_like"]
LEVELS = ("object", "detection", "signal")


def _det(v, az=0.0, r=50.0):
    v = np.atleast_1d(np.asarray(v, dtype=np.float64))
    return Detections(np.full(v.size, r), v, np.full(v.size, az), np.zeros(v.size), np.full(v.size, 30.0),
                      np.zeros(v.size, dtype=np.int64))


def test_ars408_like_unambiguous_span_reaches_the_data_sheet():
    lo, hi = ARS.range_rate_span_mps
    assert (lo, hi) == pytest.approx((-400 / 3.6, 200 / 3.6))
    vmax1 = ARS.max_unambiguous_speed_mps
    vmax2 = ARS.second_sequence().max_unambiguous_speed_mps
    assert vmax1 == pytest.approx(19.47, abs=0.01) and vmax2 < vmax1
    # the two lattices of 2·v_max coincide again only after 7 wraps of the first: 273 m/s > the span
    assert 7 * 2 * vmax1 == pytest.approx(8 * 2 * vmax2, rel=1e-9)
    assert 7 * 2 * vmax1 > hi - lo


@pytest.mark.parametrize("v", [-111.0, -80.0, -45.0, -19.5, -19.4, 0.0, 19.4, 19.5, 38.9, 55.5])
def test_staggered_ramps_recover_every_speed_of_the_span(v):
    """Just below, at and above ±v_max and 2·v_max, and the span's ends: the pair gives the true speed."""
    seq2 = ARS.second_sequence()
    alias = [np.mod(v + p.alias_speed_mps, 2 * p.alias_speed_mps) - p.alias_speed_mps
             for p in (ARS, seq2)]
    out = ambiguity.resolve_staggered(_det(alias[0] + 0.02), _det(alias[1] - 0.03), ARS)
    assert out.ambig_state[0] == AMBIG_STAGGERED
    assert out.range_rate_mps[0] == pytest.approx(v, abs=0.05)


@pytest.mark.parametrize("v", [-125.0, 60.0, 2 * 55.6])
def test_speeds_beyond_the_span_are_flagged_not_wrapped_silently(v):
    seq2 = ARS.second_sequence()
    alias = [np.mod(v + p.alias_speed_mps, 2 * p.alias_speed_mps) - p.alias_speed_mps
             for p in (ARS, seq2)]
    out = ambiguity.resolve(ARS, [_det(alias[0]), _det(alias[1])], (0.0, 0.0))
    assert out.ambig_state[0] != AMBIG_STAGGERED
    rep, state = ambiguity.apparent_range_rate(ARS, np.array([v]), np.array([0.0]), (0.0, 0.0))
    assert state[0] == AMBIG_AMBIGUOUS


def _alias(v, p):
    return np.mod(v + p.alias_speed_mps, 2 * p.alias_speed_mps) - p.alias_speed_mps


def test_a_reflector_the_second_sequence_missed_does_not_borrow_its_neighbours_speed():
    """Two reflectors in one cell, the second sequence detects only A: B stays ambiguous (it used to pair with A's
    second detection and come out "resolved" at a speed neither has in about one trial in five — an independent
    tester's finding); A, paired with its own, keeps its true speed. Either order of the first sequence's list.
    B takes A's wrap of its own measurement where its first-sequence speed is A's within a Doppler bin modulo
    2·v_max (``ambiguity.resolve_by_neighbours``: a car's reflector the second sequence missed, which left an
    oncoming convoy listed as receding): only there, and as often as that happens (2 bins in 2·v_max, 1.6 %)."""
    seq2 = ARS.second_sequence()
    rng = np.random.default_rng(0)
    wrong = took_a = missed_a = trials = 0
    for _ in range(2000):
        va, vb = rng.uniform(-45.0, 30.0, 2)
        if abs(va - vb) < 2.0:
            continue
        trials += 1
        order = [0, 1] if rng.integers(2) else [1, 0]
        v1 = np.array([_alias(va, ARS), _alias(vb, ARS)])[order] + rng.normal(0.0, 0.05, 2)
        out = ambiguity.resolve(ARS, [_det(v1), _det(_alias(va, seq2) + rng.normal(0.0, 0.05))], (0.0, 0.0))
        a, b = order.index(0), order.index(1)
        if out.ambig_state[b] == AMBIG_STAGGERED and abs(out.range_rate_mps[b] - vb) > 1.0:
            # B's first-sequence speed is A's within a bin modulo 2·v_max: the neighbour's wrap, counted apart
            if abs(_alias(v1[b] - v1[a], ARS)) <= ARS.doppler_bin_mps and abs(out.range_rate_mps[b] - va) < 1.0:
                took_a += 1
            else:
                wrong += 1
        missed_a += not (out.ambig_state[a] == AMBIG_STAGGERED and abs(out.range_rate_mps[a] - va) < 0.2)
    # what is left: B's lattice meets A's second detection more closely than A's own (measured 1.0 %)
    assert wrong / trials < 0.02 and missed_a / trials < 0.02
    assert 0.005 < took_a / trials < 0.03, took_a / trials        # 2·0.304 / 38.9 = 1.6 %


def test_single_ramp_stationary_candidates_unwrap_and_the_rest_is_ambiguous():
    p = PRESETS["mimo12"]
    vmax = p.alias_speed_mps
    ego = 36.1                                   # 130 km/h: a post ahead closes faster than v_max
    post = -ego * np.cos(0.2)
    alias = np.mod(post + vmax, 2 * vmax) - vmax
    out = ambiguity.resolve(p, [_det([alias, 10.0], az=0.2)], (ego, 0.0))
    assert out.ambig_state.tolist() == [AMBIG_STATIONARY, AMBIG_AMBIGUOUS]
    assert out.range_rate_mps[0] == pytest.approx(post, abs=1e-9)
    assert out.range_rate_mps[1] == 10.0         # measured, flagged, not guessed


def _guardrail_road(ego_mps, actors="", preset="ars408_like"):
    return scenario(actors, ego=f"{{speed_mps: {ego_mps}}}", radar=f"{{preset: {preset}, output: clusters}}",
                    road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0, guardrails: {left_offset_m: 1.0, "
                         "right_offset_m: 1.0, post_spacing_m: 4.0, rcs_dbsm: -5.0}}", duration=2.0, seed=3)


@pytest.mark.parametrize("preset", ["ars408_like", "mimo12"])
@pytest.mark.parametrize("level", LEVELS)
def test_motorway_speed_on_a_guardrail_road_gives_no_moving_object(level, preset):
    """Ego at 130 km/h (36.1 m/s, beyond ars408_like's single-ramp ±19.5 m/s and mimo12's ±32.3 m/s): posts stay
    stationary, in the cluster list and in the object list. (At the signal level the TDM wrap test once kept "no
    wrap" for most posts at this speed: their angles went wrong, and mimo12 made 55 moving objects of them in 10
    frames.)"""
    sc = _guardrail_road(130 / 3.6, preset=preset)
    model = make_model(level, Scene(sc), radar_config(sc).preset, np.random.default_rng(5), radar_config(sc).signal, clusters_wanted=True)
    cfg = RuntimeConfig(max_distance_m=250.0)
    moving = seen = 0
    for k in range(12):
        frame, _ = model.step(k * sc.period_s, cfg)
        cl = frame.clusters
        # posts stand 1 m beyond the road edges (y = −2.75 and +6.25 m); false alarms fall anywhere
        on_rail = (np.abs(cl.dist_lat_m + 2.75) < 1.0) | (np.abs(cl.dist_lat_m - 6.25) < 1.0)
        seen += int(on_rail.sum())
        # (a false alarm in the band has a random speed: flagged ambiguous, it is not a post taken for moving)
        moving += int((on_rail & np.isin(cl.dyn_prop, (DYN_MOVING, DYN_ONCOMING))
                       & (cl.ambig_state != AMBIG_AMBIGUOUS)).sum())
        moving += int(np.isin(frame.objects.dyn_prop, (DYN_MOVING, DYN_ONCOMING)).sum())
    assert seen > 50
    assert moving == 0


@pytest.mark.parametrize("preset, level, seeds", [("ars408_like", "detection", (1, 2, 3, 4)),
                                                  ("mimo12", "detection", (1, 2, 3, 4)),
                                                  # 26 s: -m slow (CI's 20 minutes; the detection level's run in CI)
                                                  pytest.param("ars408_like", "signal", (1, 5, 6),
                                                               marks=pytest.mark.slow)])
def test_posts_at_motorway_speed_never_become_crossing_objects(preset, level, seeds):
    """Tracks hopping from post to post — and across the rails, which merge into one detection at long range — took
    each jump for motion: 153 crossing-moving objects in 160 frames on ars408_like at the detection level, 401 at
    the signal level, some in the ego lane (an independent tester's finding). No moving, oncoming or crossing
    object now, over 40 frames a seed. (Signal seeds 5 and 6 had one each — a standing track back from a coast
    took 1 m/s from where it found its post — until such a track was re-anchored like a hop.)"""
    from radarnode.perception.types import DYN_CROSSING_MOVING
    moving = 0
    for seed in seeds:
        sc = scenario("", ego="{speed_mps: 36.11}", radar=f"{{preset: {preset}}}",
                      road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0, guardrails: {left_offset_m: 1.0, "
                           "right_offset_m: 1.0, post_spacing_m: 4.0}}", duration=4.0, seed=seed)
        cfg = radar_config(sc)
        model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(seed), cfg.signal)
        for k in range(40):
            frame, _ = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
            moving += int(np.isin(frame.objects.dyn_prop, (DYN_MOVING, DYN_ONCOMING, DYN_CROSSING_MOVING)).sum())
    assert moving == 0


@pytest.mark.parametrize("ego_mps, level, seeds, limit", [(36.11, "detection", range(1, 9), 8),
                                                           (55.6, "detection", range(1, 9), 6),
                                                           # the suite's longest test (about 2–4 minutes): run
                                                           # with -m slow, to keep CI within its 20 minutes
                                                           # a known limit (README: the merged rails' walk, seed
                                                           # 4): strict, so that it fails once the limit is gone
                                                           pytest.param(36.11, "signal", (1, 2, 3, 4), 8,
                                                                        marks=[pytest.mark.slow, pytest.mark.xfail(
                                                                            strict=True, reason="known limit: the "
                                                                            "merged rails' azimuth walks a standing "
                                                                            "track across the road at 70-98 m, seed 4 "
                                                                            "(README)")])])
def test_posts_two_metres_apart_passing_the_sensor_stay_standing(ego_mps, level, seeds, limit):
    """Posts 2 m apart (highway_cut_in's spacing), 130 and 200 km/h: a standing track near the sensor (50–57°) that
    missed its own post took the next one, 1.4 m across the line of sight (under HOP_M), read it as 20 m/s across for
    one cycle, and coasted out of the field of view as a crossing-moving object. 23 and 12 non-standing reports over
    8 seeds at the detection level (of 19,000), 17 over 4 seeds × 40 frames at the signal level (an independent
    tester's finding). Now a track never seen moving within 20 m is reported moving only once two of its last three
    measured cycles show it (at once where its radial speed is not the standing world's): 5, 2 and 6 (a track or two
    still hops along the posts for two cycles before it leaves the field of view, or a group of two posts with their
    mean radial speed is born moving: a known limit)."""
    from radarnode.perception.types import DYN_STATIONARY
    moving = reports = 0
    for seed in seeds:
        sc = scenario("", ego=f"{{speed_mps: {ego_mps}}}", radar="{preset: ars408_like}",
                      road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0, guardrails: {left_offset_m: 1.0, "
                           "right_offset_m: 1.0, post_spacing_m: 2.0}}", duration=4.0, seed=seed)
        cfg = radar_config(sc)
        model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(seed), cfg.signal)
        for k in range(56 if level == "detection" else 40):
            frame, _ = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
            moving += int(np.count_nonzero(frame.objects.dyn_prop != DYN_STATIONARY))
            reports += len(frame.objects)
    assert reports > 300 * len(seeds)
    assert moving <= limit, (moving, reports)


@pytest.mark.parametrize("level", LEVELS)
def test_oncoming_car_at_45_mps_is_reported_at_its_true_speed(level):
    sc = _guardrail_road(20.0, "  - {id: car, class: car, x_m: 120.0, y_m: 3.5, speed_mps: 45.0, "
                               "heading_deg: 180.0}")
    model = make_model(level, Scene(sc), radar_config(sc).preset, np.random.default_rng(6), radar_config(sc).signal, clusters_wanted=True)
    cfg = RuntimeConfig(max_distance_m=250.0)
    found = []
    for k in range(10):
        frame, view = model.step(k * sc.period_s, cfg)
        det = model.info.detections
        truth = view.vx_mps[0] * np.cos(view.azimuth_rad[0]) + view.vy_mps[0] * np.sin(view.azimuth_rad[0])
        near = det.take(np.abs(det.range_m - view.range_m[0]) < 3.0)
        hit = near.take(np.abs(near.range_rate_mps - truth) < 1.0)
        found.append(len(hit) > 0 and bool(np.all(hit.ambig_state == AMBIG_STAGGERED)))
        # a detection near the car at a wrapped speed of it (one to four wraps of the first ramp) is never
        # passed off as resolved: it carries AmbigState "ambiguous"
        for k_wrap in (1, 2, 3, 4):
            wrapped = truth + 2 * k_wrap * ARS.alias_speed_mps
            at = np.abs(near.range_rate_mps - wrapped) < 1.0
            assert np.all(near.ambig_state[at] == AMBIG_AMBIGUOUS)
    assert sum(found) >= 7          # Pd of a car at 120 m; every detection of it at its true speed
    assert truth < -2 * ARS.max_unambiguous_speed_mps      # −65 m/s: beyond two wraps of one ramp


@pytest.mark.parametrize("axis", ["range", "speed", "angle"])
@pytest.mark.parametrize("factor,taken", [(0.5, True), (1.0 - 1e-9, True), (1.02, False), (2.0, False)])
def test_a_resolved_neighbour_lends_its_wrap_only_within_its_reach(axis, factor, taken):
    """``ambiguity.resolve_by_neighbours``' three bounds, each alone, below, at, just above and at twice its limit:
    5 m in range (``NEIGHBOUR_REACH_M``), a Doppler bin of speed mismatch modulo 2·v_max, a beamwidth in angle. A
    resolved detection at −34.05 m/s, 50 m, boresight; an ambiguous one measured at its first-sequence alias."""
    vmax = ARS.alias_speed_mps
    r, v, az = 50.0, -34.05 + 2 * vmax, 0.0
    if axis == "range":
        r += factor * ambiguity.NEIGHBOUR_REACH_M
    elif axis == "speed":
        v += factor * ARS.doppler_bin_mps
    else:
        az = math.asin(factor * ARS.angular_resolution_rad)
    det = Detections(np.array([50.0, r]), np.array([-34.05, v]), np.array([0.0, az]), np.zeros(2),
                     np.full(2, 30.0), np.zeros(2, dtype=np.int64),
                     ambig_state=np.array([AMBIG_STAGGERED, AMBIG_AMBIGUOUS]))
    out = ambiguity.resolve_by_neighbours(det, ARS, (20.0, 0.0))
    if taken:
        assert out.ambig_state[1] == AMBIG_STAGGERED and abs(out.range_rate_mps[1] - (v - 2 * vmax)) < 1e-9
    else:
        assert out.ambig_state[1] == AMBIG_AMBIGUOUS and out.range_rate_mps[1] == v
    assert out.ambig_state[0] == AMBIG_STAGGERED and out.range_rate_mps[0] == -34.05


@pytest.mark.parametrize("level", ["object", "detection"])
def test_an_oncoming_convoy_whose_speed_the_second_sequence_aliases_to_zero_is_never_listed_receding(level):
    """Cars closing at −34.05 m/s past ``ars408_like`` (ego 20 m/s): the second sequence sees them at 0 m/s and
    its detections of a car's several reflectors often fewer than the first's. The one left unpaired kept its
    first-sequence alias (+4.86 m/s) and the trackers listed a car receding: in 13 and 26 of 144 cycles at the
    detection level (seeds 1, 2), 33 and 40 at the signal level, never at the object level (an independent
    tester's finding). A reflector within a car's length and a beamwidth of a resolved one, at its speed modulo
    2·v_max, now takes its wrap (``ambiguity.resolve_by_neighbours``): no cycle lists a receding object, and the
    cluster list's ambiguous detections of the cars are fewer than a quarter of the time before."""
    cars = "".join(f"  - {{id: c{i}, class: car, x_m: {150.0 + 30.0 * i}, lane: 0, speed_mps: 14.05, "
                   "heading_deg: 180.0}\n" for i in range(5))
    sc = scenario(cars, duration=5.0)
    rc = radar_config(sc)
    receding = ambiguous = clusters = 0
    for seed in (1, 2):
        model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal, clusters_wanted=True)
        cfg = RuntimeConfig(max_distance_m=250.0, clusters=True)
        for k in range(sc.num_cycles):
            frame, view = model.step(k * sc.period_s, cfg)
            receding += int(np.any(frame.objects.vrel_long_mps > 0.0))
            ambiguous += int(np.sum(frame.clusters.ambig_state == AMBIG_AMBIGUOUS))
            clusters += len(frame.clusters)
    assert receding == 0
    assert clusters > 300 and ambiguous / clusters < 0.04, (ambiguous, clusters)


def test_detection_level_aliases_like_the_signal_level():
    """One ramp: +32.3 m/s beyond mimo12's ±32.4? no — v_max + 5 folds to −v_max + 5 at both levels."""
    p = PRESETS["mimo12"]
    vmax = p.alias_speed_mps
    det = detection_model.detect(p, point_targets([60.0], [0.0], [vmax + 5.0], 20.0), np.random.default_rng(1),
                                 DspChain(p).statistic)
    j = int(np.argmin(np.abs(det.range_m - 60.0)))
    assert det.range_rate_mps[j] == pytest.approx(-vmax + 5.0, abs=2 * p.speed_resolution_mps)


def _both_levels(p, scat, seed=2):
    from radarnode.radar.signal_model import synthesize
    chain = DspChain(p)
    sig = chain.process(synthesize(p, scat, np.random.default_rng(seed)))
    ana = detection_model.detect(p, scat, np.random.default_rng(seed), chain.statistic)
    return sig, ana


def test_range_just_inside_and_past_the_unambiguous_range_is_never_negative():
    p = PRESETS["mimo12"]
    r_max = p.unambiguous_range_m                                   # 112.5 m
    scat = point_targets([r_max - 0.2, r_max + 0.1, r_max + 30.0, 2 * r_max - 0.3], [0.0, 20.0, -20.0, 40.0],
                         [0.0, 3.0, -3.0, 6.0], 30.0)
    for det in _both_levels(p, scat):
        assert np.all(det.range_m >= 0.0) and np.all(det.range_m < r_max)
        # each alias where the radar puts it: R mod R_max, within a bin (bins 255.5 and 0.2 are neighbours)
        for r, v in ((r_max - 0.2, 0.0), (r_max + 0.1, 3.0), (30.0, -3.0), (r_max - 0.3, 6.0)):
            d = np.abs(np.mod(det.range_m - np.mod(r, r_max) + r_max / 2, r_max) - r_max / 2)
            assert np.any((d < p.range_resolution_m) & (np.abs(det.range_rate_mps - v) < 0.5)), (r, v)


def test_angle_ambiguity_of_a_sparse_array_at_both_levels():
    """Element spacing λ (grating lobes): a target at 40° (d·sinθ = 0.643) is seen at asin(−0.357) = −20.9°."""
    p = PRESETS["mimo12"].with_overrides({"element_spacing_wl": 1.0})
    scat = point_targets([40.0], [40.0], [2.0], 30.0)
    for det in _both_levels(p, scat):
        j = int(np.argmin(np.abs(det.range_m - 40.0)))
        assert np.degrees(det.azimuth_rad[j]) == pytest.approx(np.degrees(np.arcsin(0.643 - 1.0)), abs=0.5)


@pytest.mark.parametrize("v, az", [(33.0, 0.0), (-33.0, 0.0), (45.0, 20.0), (64.8, 0.0), (-40.0, 10.0)])
def test_three_transmitter_array_keeps_the_angle_of_an_aliased_target(v, az):
    """mimo12 (3 Tx in TDM): an aliased speed leaves a phase staircase across the sub-arrays; the chain's
    wrap-count hypotheses restore the array — one detection at the true angle, as at the detection level."""
    from radarnode.radar import equation
    from radarnode.radar.signal_model import synthesize
    p = PRESETS["mimo12"]
    rcs = 35.0 - float(equation.snr_db(p, 50.0, 0.0, azimuth_rad=np.radians(az)))
    chain = DspChain(p)
    for seed in range(3):
        det = chain.process(synthesize(p, point_targets([50.0], [az], [v], rcs), np.random.default_rng(seed)))
        near = det.take(np.abs(det.range_m - 50.0) < 3.0)
        assert len(near) == 1, np.degrees(near.azimuth_rad)
        assert np.degrees(near.azimuth_rad[0]) == pytest.approx(az, abs=1.0)


def test_a_one_channel_radar_reports_its_targets():
    """scanning_ka has one channel: no DOA, the detection at boresight (its scan supplies the angle)."""
    from radarnode.radar import equation
    from radarnode.radar.signal_model import synthesize
    p = PRESETS["scanning_ka"]
    for r in (50.0, 150.0, 240.0):
        rcs = 35.0 - float(equation.snr_db(p, r, 0.0, azimuth_rad=0.0))
        det = DspChain(p).process(synthesize(p, point_targets([r], [0.0], [3.0], rcs), np.random.default_rng(1)))
        assert np.any(np.abs(det.range_m - r) < p.range_resolution_m), (r, det.range_m)


@pytest.mark.parametrize("r", [470.0, 500.0, 917.0])
def test_real_sampling_rejects_what_lies_past_nyquist(r):
    """ars408_like samples real: past R_unamb (458 m) the anti-alias filter rejects the echo, so nothing folds or
    wraps into the near range at either level."""
    sig, ana = _both_levels(ARS, point_targets([r], [0.0], [0.0], 60.0))
    for det in (sig, ana):
        assert not np.any(det.snr_db > 20.0), det.range_m


def test_models_report_nothing_outside_the_field_of_view():
    from radarnode.radar.models import reportable
    p = PRESETS["mimo12"]                                     # ±60° to 112.5 m
    det = _det([0.0, 0.0, 0.0, 0.0], az=0.0)
    det.azimuth_rad = np.radians([59.0, 61.0, -89.0, 0.0])
    det.range_m = np.array([50.0, 50.0, 50.0, 0.1])
    keep = reportable(p, det, RuntimeConfig(max_distance_m=100.0))
    assert keep.tolist() == [True, False, False, False]       # 0.1 m is below the minimum range


def test_bad_inputs_to_the_chain_and_the_detection_level_name_the_problem():
    from radarnode.errors import ConfigError, FieldError
    p = PRESETS["mimo12"]
    chain = DspChain(p)
    with pytest.raises(ConfigError, match="NaN or infinite"):
        chain.process(np.full((12, 256, 256), np.nan + 0j))
    with pytest.raises(ConfigError, match="12 channels"):
        chain.process(np.zeros((5, 256, 256), dtype=complex))
    for kw in ({"snr_db": np.nan}, {"power_reduction_db": np.inf}):
        with pytest.raises(ConfigError, match=next(iter(kw))):
            detection_model.detect(p, point_targets([50.0], [0.0], [0.0]), np.random.default_rng(0), chain.statistic,
                                   **kw)
    with pytest.raises(FieldError, match="num_chirps.*even"):
        p.with_overrides({"num_chirps": 1})


@pytest.mark.parametrize("overrides, field", [
    (dict(stagger_chirp_period_s=2 * ARS.chirp_period_s), "stagger_chirp_period_s"),   # lattices coincide: T₂ = 2T₁
    (dict(min_range_rate_mps=50.0, max_range_rate_mps=-50.0), "min_range_rate_mps"),    # an inverted span
    (dict(min_range_rate_mps=-300.0, max_range_rate_mps=300.0), "min_range_rate_mps"),  # beyond the wraps searched
])
def test_a_staggered_pair_that_cannot_resolve_its_span_is_refused(overrides, field):
    """An independent tester's finding: T₂ = 2·T₁ was accepted, and the detection level then reported −10 m/s
    as −87.8 m/s, "resolved". The preset now refuses it, naming the field."""
    import dataclasses
    from radarnode.errors import FieldError
    with pytest.raises(FieldError, match=field):
        dataclasses.replace(ARS, **overrides)


@pytest.mark.parametrize("field, bad, good", [("system_loss_db", 1e308, 100.0), ("system_loss_db", 100.1, 0.0),
                                             ("noise_figure_db", 1e3, 40.0), ("bandwidth_hz", 1e-300, 1e6),
                                             ("bandwidth_hz", 999e3, 4e9), ("chirp_period_s", 1e-300, 1e-7),
                                             ("chirp_period_s", 0.011, 0.01), ("carrier_hz", 1e300, 3e11),
                                             ("carrier_hz", 9.99e8, 24e9), ("element_spacing_wl", 1e300, 100.0),
                                             ("element_spacing_wl", 100.1, 57.5)])
def test_a_radar_no_hardware_can_be_is_refused_by_name(field, bad, good):
    """A loss of 1e308 dB, a 1e-300-Hz sweep or a 1e-300-s chirp passed the loader, turned into NaN inside (numpy's
    RuntimeWarnings) and the car ahead vanished from every cycle; a carrier of 1e300 Hz was refused naming a field
    the user never set (an independent tester's finding), and an element spacing of 1e300 wavelengths (a later
    tester's: a target at 20° came out at 0°). Each is refused by its own name just beyond its bound;
    the bound itself and a common value pass (on mimo12, one chirp sequence: a staggered pair's span check has its
    own say on the period and the carrier)."""
    import dataclasses
    from radarnode.errors import FieldError
    for preset in (ARS, PRESETS["mimo12"]):
        with pytest.raises(FieldError, match=field):
            dataclasses.replace(preset, **{field: bad})
    dataclasses.replace(PRESETS["mimo12"], **{field: good})


def test_the_shipped_staggered_pair_tells_its_span_apart():
    """ars408_like's pair (T₂/T₁ = 8/7) passes the same check: the nearest beat within its span is 4.9 m/s."""
    v1, v2 = ARS.alias_speed_mps, ARS.second_sequence().alias_speed_mps
    lo, hi = ARS.range_rate_span_mps
    beats = [abs(n * 2 * v1 - round(n * v1 / v2) * 2 * v2) for n in range(1, int((hi - lo) // (2 * v1)) + 1)]
    assert min(beats) == pytest.approx(2 * v1 / 8, rel=1e-6) and min(beats) > 2.0


@pytest.mark.parametrize("level", LEVELS)
def test_a_single_ramp_that_cannot_alias_a_road_user_says_unambiguous(level):
    """acc_lrr (one ramp, v_max 132.7 m/s, beyond the data sheet's 400 km/h closing): every cluster is
    "unambiguous" (AmbigState 3), at every level — an independent tester found it flagged "ambiguous"; a preset
    that aliases within road speeds (mimo12) never says so."""
    from radarnode.perception.types import AMBIG_UNAMBIGUOUS
    assert ambiguity.unambiguous(PRESETS["acc_lrr"]) and not ambiguity.unambiguous(PRESETS["mimo12"])
    assert not ambiguity.unambiguous(ARS)
    sc = scenario("  - {id: a, class: car, x_m: 60.0, lane: 1, speed_mps: 40.0, heading_deg: 180.0}\n",
                  radar="{preset: acc_lrr, output: clusters}", duration=1.0)
    p = radar_config(sc).preset
    model = make_model(level, Scene(sc), p, np.random.default_rng(1), radar_config(sc).signal,
                       clusters_wanted=True)
    states = []
    for k in range(5):
        frame, _ = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=p.max_range_m))
        states += frame.clusters.ambig_state.tolist()
    assert states and set(states) == {AMBIG_UNAMBIGUOUS}


@pytest.mark.parametrize("preset, r, az", [("srr_corner", 15.0, 74.9), ("srr_corner", 15.0, 75.1),
                                            ("mimo12", 40.0, 60.2)])
def test_a_small_body_on_a_sector_edge_is_seen_alike_at_every_level(preset, r, az):
    """A point-sized body whose centre lies just inside or just outside a sector's edge: every level measures it
    at its nearest point inside the field of view and reports only what it measured inside, so the levels see it
    about as often, never beyond the edge (an independent tester found the object level at 30 of 30 frames with
    azimuths beyond the edge where the detection and signal levels had 0 of 30)."""
    x, y = r * np.cos(np.radians(az)) + 3.7, r * np.sin(np.radians(az))     # the sensor sits 3.7 m ahead
    sc = scenario(f"  - {{id: p, class: point, x_m: {x:.3f}, y_m: {y:.3f}, rcs_dbsm: 0.0}}\n", ego="{speed_mps: 0.0}",
                  radar=f"{{preset: {preset}, output: clusters}}", duration=3.0)
    p = radar_config(sc).preset
    edge = max(s.half_angle_deg for s in p.fov)
    seen = {}
    for level in LEVELS:
        model = make_model(level, Scene(sc), p, np.random.default_rng(4), radar_config(sc).signal,
                           clusters_wanted=True)
        hits = 0
        for k in range(30):
            model.step(k * sc.period_s, RuntimeConfig(max_distance_m=p.max_range_m))
            det = model.info.detections
            near = np.abs(det.range_m - r) < 2.0
            assert np.all(np.abs(np.degrees(det.azimuth_rad)) <= edge + 1e-6)
            hits += bool(near.any())
        seen[level] = hits
    assert min(seen.values()) >= 8 and max(seen.values()) - min(seen.values()) <= 8, seen


@pytest.mark.parametrize("level", LEVELS)
def test_a_sparse_array_folds_the_angle_alike_at_every_level(level):
    """Element spacing λ (an override of mimo12): a target at 39.6° is seen in its grating lobe at −21°, at the
    object level as at the others (an independent tester found the object level at +39.6°, and auto switching
    between the two then dropped the track and made a ghost 40 m away)."""
    az = math.radians(39.58)
    x, y = 40.1 * math.cos(az) + 3.7, 40.1 * math.sin(az)
    sc = scenario(f"  - {{id: p, class: point, x_m: {x:.3f}, y_m: {y:.3f}, rcs_dbsm: 10.0}}\n", ego="{speed_mps: 0.0}",
                  radar="{preset: mimo12, overrides: {element_spacing_wl: 1.0}}", duration=1.0)
    p = radar_config(sc).preset
    model = make_model(level, Scene(sc), p, np.random.default_rng(2), radar_config(sc).signal)
    seen = []
    for k in range(4):
        model.step(k * sc.period_s, RuntimeConfig(max_distance_m=p.max_range_m))
        seen += np.degrees(model.info.detections.azimuth_rad).tolist()
    folded = math.degrees(math.asin((math.sin(az) + 0.5) % 1.0 - 0.5))          # d·sinθ modulo 1, d = λ
    assert float(np.degrees(ambiguity.apparent_azimuth(p, az))) == pytest.approx(folded, abs=1e-9)
    assert folded < -20.0 and seen and all(abs(a - folded) < 1.0 for a in seen), seen


def test_auto_is_refused_on_a_one_channel_radar():
    from radarnode.errors import ConfigError
    sc = scenario("  - {id: a, class: car, x_m: 60.0, lane: 1, speed_mps: 20.0}\n", radar="{preset: scanning_ka}")
    p = radar_config(sc).preset
    with pytest.raises(ConfigError, match="'auto' is not allowed with preset scanning_ka"):
        make_model("auto", Scene(sc), p, np.random.default_rng(1), radar_config(sc).signal)


@pytest.mark.parametrize("factor, expected", [(1 - 1e-6, False), (1.0, True), (1 + 1e-6, True), (2.0, True)])
def test_unambiguous_switches_at_400_kmh(factor, expected):
    """Just below, at, just above and at twice the 400-km/h alias speed (the chirp period scaled to put it there)."""
    import dataclasses
    base = PRESETS["fast_chirp"]
    p = dataclasses.replace(base, chirp_period_s=base.chirp_period_s * base.alias_speed_mps
                            / (ambiguity.UNAMBIGUOUS_SPEED_MPS * factor))
    assert p.alias_speed_mps == pytest.approx(ambiguity.UNAMBIGUOUS_SPEED_MPS * factor, rel=1e-9)
    assert ambiguity.unambiguous(p) is expected
    _, state = ambiguity.apparent_range_rate(p, np.array([-30.0]), np.array([0.1]), (20.0, 0.0))
    from radarnode.perception.types import AMBIG_UNAMBIGUOUS
    assert bool(state[0] == AMBIG_UNAMBIGUOUS) == expected


@pytest.mark.parametrize("preset, factor", [("mimo12", -1.5), ("mimo12", -2.2), ("ars408_like", -1.5),
                                            ("ars408_like", -2.2), ("mimo12", 2.2)])
def test_the_wrap_of_a_20_db_target_is_found_and_its_angle_kept(preset, factor):
    """At ρ = 20 dB beyond the alias speed the TDM wrap hypothesis must win over "no wrap" (the likelier one of
    models with the same parameters, by a margin of noise): with a margin proportional to the beam's power the
    chain kept no wrap in 80–100 % of these frames and reported the target degrees off its angle."""
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS[preset]
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    v, vmax = factor * p.alias_speed_mps, p.alias_speed_mps
    chain, right, seen = DspChain(p), 0, 0
    for seed in range(30):
        det = chain.process_rd(synthesize_rd(p, point_targets([40.0], [10.0], [v], 0.0), np.random.default_rng(seed),
                                             snr_db=20.0 - 10.0 * math.log10(n * m * c)))
        dv = (det.range_rate_mps - v + vmax) % (2 * vmax) - vmax
        near = np.flatnonzero((np.abs(dv) < 0.5) & (np.abs(det.range_m - 40.0) < 2.0))
        if near.size:
            seen += 1
            right += bool(np.any(np.abs(np.degrees(det.azimuth_rad[near]) - 10.0) < 2.0))
    assert seen >= 20 and right >= 0.9 * seen, (right, seen)


@pytest.mark.parametrize("preset", ["mimo12", "ars408_like"])
def test_weak_unaliased_targets_are_not_wrapped_by_noise(preset):
    """ρ = 17 dB, unaliased: no detection of the target is taken for a wrapped one (its angle stays)."""
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS[preset]
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    chain, wrong, seen = DspChain(p), 0, 0
    for seed in range(80):
        for v in (0.0, -0.5 * p.alias_speed_mps):
            det = chain.process_rd(synthesize_rd(p, point_targets([40.0], [10.0], [v], 0.0),
                                                 np.random.default_rng(100 + seed),
                                                 snr_db=17.0 - 10.0 * math.log10(n * m * c)))
            near = np.flatnonzero((np.abs(det.range_rate_mps - v) < 0.5) & (np.abs(det.range_m - 40.0) < 2.0))
            if near.size:
                seen += 1
                wrong += not np.any(np.abs(np.degrees(det.azimuth_rad[near]) - 10.0) < 3.0)
    assert seen >= 30 and wrong <= 0.05 * seen, (wrong, seen)


def test_the_migration_fit_brings_the_signal_level_to_the_bound_beyond_the_alias_speed():
    """The default chain (complex128: migration_fit auto, the fit on) on mimo12 at −70 m/s, 1.2 range bins of
    migration over the frame, ρ = 20 dB: range-rate RMSE, range standard deviation and azimuth RMSE (over the frames
    whose TDM wrap was found, at most 2 missed) within 1.3× the CRB (the still fit: about 1.7–1.9× in range and
    range rate, 8 wraps missed in 191 frames); at rest the fit changes nothing."""
    from radarnode.radar import equation
    from radarnode.radar.chain import DspConfig
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS["mimo12"]
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    vmax = p.alias_speed_mps
    rho = 20.0
    chain = DspChain(p)                                          # the default: auto, the fit on for complex128
    for v in (-70.0, 0.0):
        errs, same = [], True
        for seed in range(150):
            rd = synthesize_rd(p, point_targets([50.0], [10.0], [v], 0.0), np.random.default_rng(1000 + seed),
                               snr_db=rho - 10.0 * math.log10(n * m * c))
            det = chain.process_rd(rd)
            if v == 0.0 and seed < 10:
                plain = DspChain(p, DspConfig(migration_fit=False)).process_rd(rd)
                same &= np.array_equal(plain.range_rate_mps, det.range_rate_mps)
            dv = (det.range_rate_mps - v + vmax) % (2 * vmax) - vmax
            cost = np.abs(det.range_m - 50.0) / 1.0 + np.abs(dv) / 0.5
            if len(det) and cost.min() <= 1.0:
                j = int(np.argmin(cost))
                errs.append((det.range_m[j], dv[j], det.azimuth_rad[j] - math.radians(10.0)))
        e = np.array(errs)
        assert len(e) >= 120
        assert e[:, 0].std() <= 1.3 * float(equation.crb_range_m(p, rho)), v
        assert np.sqrt(np.mean(e[:, 1] ** 2)) <= 1.3 * float(equation.crb_speed_mps(p, rho)), v
        found = np.abs(np.degrees(e[:, 2])) <= 2.0              # a missed wrap: the angle of a broken array
        assert np.count_nonzero(~found) <= 2, v
        crb_az = float(equation.crb_azimuth_rad(p, rho, math.radians(10.0)))
        assert np.sqrt(np.mean(e[found, 2] ** 2)) <= 1.3 * crb_az, v
    assert same


@pytest.mark.parametrize("preset, sep", [("mimo12", 2.0), ("mimo12", 3.0), ("ars408_like", 1.5), ("ars408_like", 2.0)])
def test_two_sources_in_one_cell_are_not_taken_for_a_wrap(preset, sep):
    """Two unaliased targets in one range–Doppler cell, ``sep`` beamwidths apart, ρ = 30 dB each: under a wrong
    wrap hypothesis their ghost lobes can add up to a higher beam peak than either has. Judged by what one plane
    wave, or two, explain, no wrap is taken and every angle reported lies at one of the two (the beam-peak rule
    with a margin proportional to the power gave an angle off both in 29–42 % of the frames; with a noise margin,
    up to 83 %)."""
    from radarnode.radar import equation
    from radarnode.radar.signal_model import synthesize_rd
    p = PRESETS[preset]
    chain, rng = DspChain(p), np.random.default_rng(7)
    off = seen = 0
    for _ in range(40):
        r0, v0, a0 = rng.uniform(30, 80), rng.uniform(-0.8, 0.8) * p.alias_speed_mps, rng.uniform(-0.2, 0.2)
        a1 = a0 + sep * p.angular_resolution_rad
        az = np.degrees(np.arcsin([a0, a1]))
        rcs = [30.0 - float(equation.snr_db(p, r0, 0.0, azimuth_rad=math.radians(a))) for a in az]
        det = chain.process_rd(synthesize_rd(p, point_targets([r0, r0], az, [v0, v0], rcs), rng))
        near = (np.abs(det.range_m - r0) < 2 * p.range_resolution_m) \
            & (np.abs(det.range_rate_mps - v0) < 2 * p.speed_resolution_mps)
        if near.any():
            seen += 1
            s = np.sin(det.azimuth_rad[near])
            off += bool(np.any(np.minimum(np.abs(s - a0), np.abs(s - a1)) > 0.5 * p.angular_resolution_rad))
    assert seen >= 35 and off <= 0.05 * seen, (off, seen)


def test_the_migration_fit_is_refused_where_it_cannot_work():
    """One transmitter: no TDM wrap count, so no true speed to fit with; without the patch fit, nothing to refine.
    Both are errors that name the field, not options that silently do nothing."""
    from radarnode.errors import ConfigError, FieldError
    from radarnode.radar.chain import DspConfig
    with pytest.raises(ConfigError, match="migration_fit.*fast_chirp.*1 transmitter"):
        DspChain(PRESETS["fast_chirp"], DspConfig(migration_fit=True))
    with pytest.raises(FieldError, match="migration_fit.*range_ml"):
        DspConfig(migration_fit=True, range_ml=False)
    DspChain(PRESETS["ars408_like"], DspConfig(migration_fit=True))        # two transmitters: allowed
    # "auto" (the default) asks for nothing it cannot do: off there, without an error
    assert not DspChain(PRESETS["fast_chirp"]).migrates(np.complex128)
    assert not DspChain(PRESETS["mimo12"], DspConfig(range_ml=False)).migrates(np.complex128)


def test_auto_fits_the_migration_of_complex128_spectra_and_not_of_complex64_ones():
    """migration_fit: auto (the default) — a complex128 spectrum (the default dtype) gets the migration fit beyond
    the alias speed, exactly as with migration_fit: true; a complex64 one (the fast setting) the still fit, exactly
    as with false; at rest the three agree."""
    from radarnode.radar.chain import DspConfig
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS["mimo12"]
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    chains = {mode: DspChain(p, DspConfig(migration_fit=mode)) for mode in (True, False, "auto")}
    assert DspChain(p).config.migration_fit == "auto"
    for v in (-70.0, 45.0, 0.0):
        for dtype, same_as in ((np.complex128, True), (np.complex64, False)):
            moved = 0
            for seed in range(3):
                rd = synthesize_rd(p, point_targets([50.0, 80.0], [10.0, -20.0], [v, v], 0.0),
                                   np.random.default_rng(seed), snr_db=30.0 - 10.0 * math.log10(n * m * c),
                                   dtype=dtype)
                got = {mode: chain.process_rd(rd) for mode, chain in chains.items()}
                for f in ("range_m", "range_rate_mps", "azimuth_rad"):
                    assert np.array_equal(getattr(got["auto"], f), getattr(got[same_as], f)), (v, dtype, f)
                moved += not np.array_equal(got[True].range_m, got[False].range_m)
            # beyond the alias the two fits differ, so the comparison above can tell them apart; at rest they agree
            assert (moved == 3) if v else (moved == 0), (v, dtype, moved)


@pytest.mark.parametrize("v", [-70.0, -50.0, 40.0, 70.0])
def test_the_migration_fit_measures_the_speed_of_the_exact_cube(v):
    """The time-domain cube (every phase term of the target, no noise), mimo12 beyond the alias speed: the migration
    fit's range rate is the true one (wrapped) within 2e-5 m/s (the fit's Doppler is that of the phase at the chirp's
    middle in time, where the chain takes λ; taken at the window's centre, sample (N − 1)/2, it was off by μ/2N bins,
    6e-4 m/s at 70 m/s, 6× the CRB at ρ = 60 dB)."""
    from radarnode.dsp.spectra import range_doppler
    from radarnode.radar.chain import DspConfig
    from radarnode.radar.signal_model import num_range_samples, synthesize
    p = PRESETS["mimo12"]
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    cube = synthesize(p, point_targets([50.0], [10.0], [v], 0.0), np.random.default_rng(0),
                      snr_db=60.0 - 10.0 * math.log10(n * m * c), noise=False)
    det = DspChain(p, DspConfig(migration_fit=True)).process_rd(range_doppler(cube))
    vmax = p.alias_speed_mps
    dv = (det.range_rate_mps - v + vmax) % (2 * vmax) - vmax
    j = int(np.argmin(np.abs(dv) + np.abs(det.range_m - 50.0)))
    assert abs(math.degrees(det.azimuth_rad[j]) - 10.0) < 0.01           # the wrap found
    assert abs(dv[j]) < 2e-5, dv[j]


@pytest.mark.parametrize("threshold, fits", [(0.12, True), (0.14, True), (0.16, False), (0.30, False)])
def test_auto_fits_only_peaks_that_migrate_enough(monkeypatch, threshold, fits):
    """migration_fit: auto skips the peaks whose alias numbers all migrate less than MIGRATION_AUTO_MIN_BINS (0.3
    bin; below it the fit moves the estimates by a few hundredths of the CRB, BENCHMARKS.md). ars408_like at
    −36 m/s: the wrap's two alias numbers give −36 and +41.8 m/s, 0.129 and 0.149 bin over the frame. With the
    threshold just below both, between them, just above both, and at twice the latter (the default), auto's
    detections equal those of migration_fit: true, true, false and false."""
    from radarnode.radar import chain as chain_module
    from radarnode.radar.chain import DspConfig
    from radarnode.radar.signal_model import num_range_samples, synthesize_rd
    p = PRESETS["ars408_like"]
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    mus = [abs(v) * p.integration_time_s / p.range_resolution_m for v in (-36.0, -36.0 + 4 * p.alias_speed_mps)]
    assert 0.12 < min(mus) < 0.14 < max(mus) < 0.16
    monkeypatch.setattr(chain_module, "MIGRATION_AUTO_MIN_BINS", threshold)
    chains = {mode: DspChain(p, DspConfig(migration_fit=mode)) for mode in (True, False, "auto")}
    differ = 0
    for seed in range(6):
        rd = synthesize_rd(p, point_targets([50.0], [10.0], [-36.0], 0.0), np.random.default_rng(seed),
                           snr_db=25.0 - 10.0 * math.log10(n * m * c))
        got = {mode: ch.process_rd(rd) for mode, ch in chains.items()}
        if np.array_equal(got[True].range_m, got[False].range_m):
            continue
        differ += 1
        for f in ("range_m", "range_rate_mps", "azimuth_rad"):
            assert np.array_equal(getattr(got["auto"], f), getattr(got[fits], f)), (threshold, seed, f)
    assert differ >= 3          # frames where the two fits differ: the comparison can tell which one auto ran


@pytest.mark.parametrize("preset, dsp, said", [
    ("fast_chirp", "{migration_fit: true}", "value true is not allowed; expected false or auto with preset fast_chirp"),
    ("scanning_ka", "{doa: capon}", "value 'capon' is not allowed; expected 'fft' with preset scanning_ka")])
def test_a_scenario_whose_preset_cannot_run_its_dsp_option_is_refused_with_file_and_line(tmp_path, preset, dsp, said):
    """An option the preset cannot run is refused when the scenario is loaded, with the file, the line, the field,
    the value and what is allowed — not when the first signal-level cycle builds the chain (an error without the
    file, an independent tester found). "auto" is what migration_fit may be there."""
    from radarnode.errors import ScenarioError
    from radarnode.radar.setup import load_scenario
    f = tmp_path / "s.yaml"
    f.write_text(f"name: t\nduration_s: 1.0\nseed: 1\nradar: {{preset: {preset}}}\nsignal:\n  dsp: {dsp}\nactors: []\n")
    with pytest.raises(ScenarioError) as err:
        load_scenario(f)
    field = "signal.dsp." + dsp.strip("{}").split(":")[0]
    assert f"{f}:6" in str(err.value) and field in str(err.value) and said in str(err.value), str(err.value)
    f.write_text(f"name: t\nduration_s: 1.0\nseed: 1\nradar: {{preset: {preset}}}\nsignal:\n  dsp: {{}}\nactors: []\n")
    load_scenario(f)                        # the defaults (auto, fft) are what every preset can run


@pytest.mark.parametrize("order, where", [(("fast_chirp", "mimo12"), "radars[0]"), (("mimo12", "fast_chirp"), "radars[1]")])
def test_a_radar_list_whose_preset_cannot_run_the_fit_names_that_radar(tmp_path, order, where):
    """With several radars the refusal names the one whose preset cannot run the option, the first included (it was
    named 'radar', the scenario's own, when it came first: an independent tester's find)."""
    from radarnode.errors import ScenarioError
    from radarnode.radar.setup import load_scenario
    f = tmp_path / "s.yaml"
    f.write_text(f"name: t\nduration_s: 1.0\nseed: 1\nradars:\n  - {{preset: {order[0]}, sensor_id: 0}}\n"
                 f"  - {{preset: {order[1]}, sensor_id: 1}}\nsignal: {{dsp: {{migration_fit: true}}}}\nactors: []\n")
    with pytest.raises(ScenarioError) as err:
        load_scenario(f)
    assert f"preset fast_chirp of {where} " in str(err.value), str(err.value)


@pytest.mark.parametrize("dsp, said", [("{migration_fit: maybe}", "value 'maybe' is not allowed; expected true, "
                                                                  "false or auto"),
                                       ("{migration_fit: 1}", "expected true, false or auto"),
                                       ("{migration_fit: true, range_ml: false}", "while range_ml is false")])
def test_a_scenario_with_a_bad_migration_fit_says_the_file_field_and_value(tmp_path, dsp, said):
    from radarnode.errors import ScenarioError
    from radarnode.radar.setup import load_scenario
    f = tmp_path / "s.yaml"
    f.write_text(f"name: t\nduration_s: 1.0\nseed: 1\nradar: {{preset: mimo12}}\nsignal: {{dsp: {dsp}}}\nactors: []\n")
    with pytest.raises(ScenarioError) as err:
        radar_config(load_scenario(f))
    assert str(f) in str(err.value) and "signal.dsp.migration_fit" in str(err.value) and said in str(err.value)


@pytest.mark.parametrize("preset, rate", [("fast_chirp", -45.0), ("fast_chirp", 25.0), ("mimo12", 40.0),
                                          ("ars408_like", -115.0), ("ars408_like", 60.0), ("ars408_like", 30.0)])
def test_an_aliased_speed_leaves_its_range_doppler_coupling_in_the_range_at_every_level(preset, rate):
    """The chain takes the range–Doppler coupling out with the speed it reports: an aliased speed leaves
    (true − reported) × the coupling in the range (0.87 m on fast_chirp at −45 m/s). The object level put the target
    at its true range (an independent tester's finding: 0.4–3 m, 0.9–1.7 bins from the other levels). ars408_like
    at 30 m/s is inside its staggered span: resolved, no shift at any level."""
    p = PRESETS[preset]
    heading, x0 = (0.0, 40.0) if rate >= 0 else (180.0, 90.0)
    sc = scenario(f"  - {{id: p, class: point, rcs_dbsm: 15.0, x_m: {x0}, y_m: 0.0, speed_mps: {abs(rate)}, "
                  f"heading_deg: {heading}}}", ego="{speed_mps: 0.0}", radar=f"{{preset: {preset}}}",
                  road="{lanes: 1, ego_lane: 0}", duration=2.0)
    cfg = radar_config(sc)
    reported, ambig = ambiguity.apparent_range_rate(p, np.array([rate]), np.zeros(1), (0.0, 0.0))
    expected = (rate - reported[0]) * p.range_rate_coupling_s          # the closed form
    assert (abs(expected) > 0.3) == (ambig[0] == AMBIG_AMBIGUOUS)
    errors = {}
    for level in LEVELS:
        model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(1), cfg.signal)
        errs = []
        for k in range(6):
            model.step(0.072 * k, RuntimeConfig(max_distance_m=p.max_range_m))
            det, view = model.info.detections, model.scene.view(0.072 * k)
            if len(det):
                i = int(np.argmin(np.abs(det.range_m - view.range_m[0] - expected)))
                errs.append(det.range_m[i] - view.range_m[0])
        errors[level] = float(np.median(errs))
        assert errors[level] == pytest.approx(expected, abs=0.25 * p.range_resolution_m), (level, errors)


@pytest.mark.parametrize("preset, v, listed", [
    ("mimo12", -39.9, False),           # one wrap (64.7 m/s) puts the next detection 4.7 m off: never confirmed
    ("ars408_like", 60.0, False),       # beyond the staggered span, two wraps of the first sequence: 5.6 m
    ("ars408_like", 56.0, False),       # beyond the span every detection is ambiguous: a track no unambiguous one
                                        # measured is never listed (one wrap, 2.8 m, was inside the gate: listed)
    ("fast_chirp", -30.0, True),        # one wrap: 1.9 m, and the range the track walks resolves it
])
def test_an_aliased_target_is_an_object_at_the_object_level_where_the_tracker_follows_it(preset, v, listed):
    """A target reported at an aliased speed moves (true − aliased) × the cycle away from where a track at that
    speed predicts it. The detection and signal levels' tracker follows it where that is inside its gate, and never
    confirms it beyond; the object level listed it every cycle at the aliased speed whatever the preset (an oncoming
    car on mimo12 as a car receding at +24.6 m/s where the other levels listed nothing; an independent tester's
    finding). Now both levels list it, or neither. Where they list it (a single ramp whose one wrap lies inside the
    gate) the range the track walks resolved the wrap: at its true speed (it was listed at the aliased one until
    2026-12-05). With staggered ramps a track whose speed only ambiguous detections measured is not listed at all
    (the tracker's ``alias_span_mps``)."""
    x = 40.0 if v >= 0 else 120.0
    heading = "" if v >= 0 else ", heading_deg: 180"
    sc = scenario(f"  - {{id: a, class: point, x_m: {x}, y_m: 0.0, speed_mps: {abs(v)}{heading}, rcs_dbsm: 25}}\n",
                  ego="{speed_mps: 0}", radar=f"{{preset: {preset}, output: clusters}}", duration=2.0)
    p = radar_config(sc).preset
    alias = _alias(v, p)
    found = {}
    for level in ("object", "detection"):
        model = make_model(level, Scene(sc), p, np.random.default_rng(1), radar_config(sc).signal,
                           clusters_wanted=True)
        listed_at = []
        for k in range(10):
            frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=p.max_range_m))
            o = frame.objects
            near = np.abs(o.dist_long_m - view.range_m[0]) < 6.0
            if k >= 3:
                listed_at.append(bool(near.any()))
                if near.any():
                    assert abs(o.vrel_long_mps[near][0] - v) < 1.5, (level, o.vrel_long_mps[near], v, alias)
        found[level] = np.mean(listed_at)
    if listed:
        assert found["object"] >= 0.8 and found["detection"] >= 0.5, found
    else:
        assert found["object"] == 0.0 and found["detection"] == 0.0, found


def test_a_weak_target_beyond_one_wrap_is_resolved_as_often_as_the_second_sequence_detects_it():
    """ars408_like's speed is resolved only where its second chirp sequence detects the target too. The object level
    resolved every detection it drew (0.50 at the true speed and never an alias at 18 dB, where the detection and
    signal levels gave 0.32–0.38 and 0.14–0.16; an independent tester's finding). Now it draws the second look given
    the first (its own noise, 0.58 dB more SNR): P(resolved | detected) is that theory's, and the detection level's
    within its own ~0.3 dB of sensitivity (P1 0.47 against 0.53 in this scene)."""
    from radarnode.radar import equation
    rho, n_t = 18.0, 8
    p = ARS

    def scene(seed, fix=None):
        lines = []
        for k in range(n_t):
            r, az = 40.0 + 12.0 * k, math.radians(-8.0 + 16.0 * ((3 * k) % n_t) / (n_t - 1))
            rcs = rho - float(equation.snr_db(p, r, 0.0, azimuth_rad=az)) + (0.0 if fix is None else float(fix[k]))
            x, y = r * math.cos(az), r * math.sin(az)
            lines.append(f"  - {{id: p{k}, class: point, swerling: 0, rcs_dbsm: {rcs:.3f}, x_m: {x + 3.7:.3f}, "
                         f"y_m: {y:.3f}, speed_mps: 30.0, heading_deg: {math.degrees(math.atan2(-y, -x)):.3f}}}")
        return scenario("\n".join(lines) + "\n", ego="{speed_mps: 0.0}",
                        radar="{preset: ars408_like, output: clusters}", road="{lanes: 1, ego_lane: 0}",
                        duration=5.0, seed=seed)

    s0 = Scene(scene(1))
    v0 = s0.view(0.0)
    fix = rho - equation.snr_db(p, v0.range_m, s0.rcs_dbsm, azimuth_rad=v0.azimuth_rad)
    counts = {}
    for level, runs in (("object", 80), ("detection", 40)):
        first = resolved = aliased = 0
        for seed in range(runs):
            sc = scene(seed, fix)
            model = make_model(level, Scene(sc), p, np.random.default_rng(seed), radar_config(sc).signal,
                               clusters_wanted=True)
            frame, view = model.step(0.0, RuntimeConfig(max_distance_m=p.max_range_m, clusters=True))
            det = model.info.detections
            for i in range(n_t):
                mine = np.abs(det.range_m - view.range_m[i]) < 2.5 * p.range_resolution_m
                if mine.any():
                    first += 1
                    resolved += bool((det.ambig_state[mine] == AMBIG_STAGGERED).any())
                    aliased += bool((det.ambig_state[mine] == AMBIG_AMBIGUOUS).any())
        counts[level] = (first, resolved / first, aliased / first)
    q = float(model.statistic.pd_second_look(np.array([rho]), 0.58, 0)[0])      # 0.68
    f_obj, r_obj, a_obj = counts["object"]
    assert f_obj >= 250 and abs(r_obj - q) < 0.07 and abs(a_obj - (1.0 - q)) < 0.07, (counts, q)
    assert abs(counts["detection"][1] - r_obj) < 0.12 and counts["detection"][2] > 0.15, counts


# three sources in one range–Doppler cell: the TDM wrap hypothesis that breaks the array into sub-arrays explained
# them better with two plane waves between the sources than the true hypothesis did, and the chain reported ghosts


@pytest.mark.parametrize("preset", ["ars408_like", "mimo12"])
@pytest.mark.parametrize("speed_over_vmax", [0.0, -1.3, -2.5])
def test_three_reflectors_in_one_cell_come_out_at_their_own_angles_at_both_levels(preset, speed_over_vmax):
    """Three equal 10-dBsm reflectors at 30 m, −30°, 0°, 30° (two of ars408_like's beams and 2.5 of mimo12's apart),
    one range and radial speed: standing, wrapped once beyond the alias speed, and at 2.5× it, where the migration fit
    refits the peaks (mimo12, complex128). The chain reported ghosts between them (ars408_like at ±14° and ±47° in 33
    of 40 frames; mimo12 in 30 of 30; judged again on the migration fit's snapshot for one hypothesis and the still
    one for the others, mimo12 at 2.5× still in 14–16 of 30); now a detection more than 6° from every reflector comes
    in at most 2 of 20 frames, and each reflector is seen in at least 16 — as the detection level sees them."""
    from radarnode.radar import detection_model
    from radarnode.radar.chain import DspChain
    from radarnode.radar.scatterers import point_targets
    from radarnode.radar.signal_model import synthesize_rd
    p = PRESETS[preset]
    chain = DspChain(p)
    truth = np.array([-30.0, 0.0, 30.0])
    s = point_targets([30.0] * 3, truth, speed_over_vmax * p.max_unambiguous_speed_mps, 10.0)
    rng = np.random.default_rng(4)
    for level in ("signal", "detection"):
        ghosts, seen = 0, np.zeros(3, dtype=int)
        for _ in range(20):
            det = chain.process_rd(synthesize_rd(p, s, rng)) if level == "signal" else \
                detection_model.detect(p, s, rng, chain.statistic)
            az = np.degrees(det.azimuth_rad[np.abs(det.range_m - 30.0) < 3.0])
            off = np.abs(az[:, None] - truth[None, :])
            ghosts += int(np.any(off.min(axis=1) > 6.0))
            seen += np.any(off <= 6.0, axis=0)
        assert ghosts <= 2 and seen.min() >= 16, (level, ghosts, seen)


@pytest.mark.parametrize("third_db", [-14.0, -10.0, -8.0, -6.0, -4.0, 0.0])
def test_a_weaker_third_reflector_in_the_cell_makes_no_ghost_and_the_gate_changes_no_detection(monkeypatch, third_db):
    """Two equal 10-dBsm reflectors at −30° and 0° and a third at 30°, 14 dB weaker to as strong, 30 m ahead on mimo12
    at −1.3× the alias speed: a sweep across where two plane waves stop explaining the cell. A second gate, two waves
    explaining less than 93 % of it, let the third source through 4–10 dB down: 3–5 of 20 frames had a ghost and lost
    the true pair. Now no more than 1 ghost frame, the strong pair seen in every frame but one, the third wherever it is
    within 6 dB; and the remaining gate (what two waves leave must exceed two penalties and the noise) changes no
    detection: judging every cell again gives the same frames, bit for bit."""
    from radarnode.radar.chain import DspChain
    from radarnode.radar.scatterers import point_targets
    from radarnode.radar.signal_model import synthesize_rd
    p = PRESETS["mimo12"]
    chain = DspChain(p)
    truth = np.array([-30.0, 0.0, 30.0])
    s = point_targets([30.0] * 3, truth, -1.3 * p.max_unambiguous_speed_mps, [10.0, 10.0, 10.0 + third_db])
    frames = {}
    for mode in ("gate", "every cell"):
        if mode == "every cell":
            monkeypatch.setattr(DspChain, "_fine_gate", lambda self, channels, sigma2: -np.inf)
        rng = np.random.default_rng(4)
        frames[mode] = [chain.process_rd(synthesize_rd(p, s, rng)) for _ in range(20)]
    ghosts, seen = 0, np.zeros(3, dtype=int)
    for det in frames["gate"]:
        az = np.degrees(det.azimuth_rad[np.abs(det.range_m - 30.0) < 3.0])
        off = np.abs(az[:, None] - truth[None, :])
        ghosts += int(np.any(off.min(axis=1) > 6.0))
        seen += np.any(off <= 6.0, axis=0)
    assert ghosts <= 1 and seen[:2].min() >= 19 and (third_db < -6.0 or seen[2] >= 18), (ghosts, seen)
    for a, b in zip(frames["gate"], frames["every cell"]):
        assert np.array_equal(a.azimuth_rad, b.azimuth_rad) and np.array_equal(a.range_rate_mps, b.range_rate_mps)


def test_plane_waves_fitted_jointly_explain_a_field_of_as_many_sources():
    """Noise-free snapshots of three on-grid plane waves two beams apart (8 elements, the FFT grid's bins): the greedy
    search's three waves leave part of the energy unexplained (its first peak lands between sources); refined by
    alternating projection, three waves explain it all, and one or two fewer than that."""
    from radarnode.dsp.doa import FftBeamformer
    doa = FftBeamformer(8, 0.5, n_fft=64)
    k = np.arange(8)
    rng = np.random.default_rng(3)
    short = []
    for _ in range(20):
        bins = np.array([-16, 0, 16]) + rng.integers(-3, 4)
        amp = np.exp(2j * np.pi * rng.random(3))
        x = (np.exp(2j * np.pi * np.outer(k, bins) / 64) @ amp)[None, :]
        total = float(np.sum(np.abs(x) ** 2))
        fine = doa.explained(x, 3, refine=2)[0]
        assert abs(fine[2] - total) < 1e-7 * total          # (the joint solve is regularised by 1e-9 of a wave)
        assert fine[1] < 0.9 * total and fine[0] < fine[1]
        short.append(1.0 - doa.explained(x, 3)[0][2] / total)
    assert np.mean(short) > 0.01 and min(short) > 0.0      # the greedy search's three: 1.6–6.5 % short


def test_a_72_channel_array_keeps_two_wrapped_sources_at_their_angles():
    """ars408_like with 36 receivers (72 virtual channels): two 30-dB sources two beams apart, wrapped (−1.3× the
    alias speed). Two plane waves leave about 70 σ² of noise unexplained there, more than the two penalties the
    re-judgement first asked for, and on the beamformer's 256-point grid (3.6 points a beam) a wave half a step off
    lost 6 % of a source: judged again, 3 of 40 frames put a ghost between the sources (an independent tester's
    finding). The re-judgement now asks for more than the noise leaves and fits on a grid of 16 points a beam."""
    import dataclasses

    from radarnode.radar import equation
    from radarnode.radar.chain import DspChain
    from radarnode.radar.scatterers import point_targets
    from radarnode.radar.signal_model import synthesize_rd
    p = dataclasses.replace(PRESETS["ars408_like"], num_rx=36, tx_power_dbm=3.65)
    chain = DspChain(p)
    u = np.array([0.05, 0.05 + 2.0 * 2.0 / 72])
    az = np.degrees(np.arcsin(u))
    rcs = [30.0 - float(equation.snr_db(p, 40.0, 0.0, azimuth_rad=math.radians(a))) for a in az]
    s = point_targets([40.0, 40.0], az, -1.3 * p.alias_speed_mps, rcs)
    rng = np.random.default_rng(25)
    half_beam = 0.5 * math.degrees(p.angular_resolution_rad)
    astray = 0
    for _ in range(40):
        det = chain.process_rd(synthesize_rd(p, s, rng))
        a = np.degrees(det.azimuth_rad[np.abs(det.range_m - 40.0) < 3.0])
        astray += int(np.any(np.abs(a[:, None] - az[None, :]).min(axis=1) > half_beam))
    assert astray <= 1, astray


@pytest.mark.parametrize("cls", ["car", "point"])
@pytest.mark.parametrize("speed_mps", [-60.0, 54.0, 60.0, 120.0])
def test_a_fast_cars_signal_level_detections_are_tagged_with_it(speed_mps, cls):
    """ars408_like, ego standing, a car (or a point target) 40 m ahead at −60 (resolved by the staggered pair), +54 (just inside the
    span), +60 (beyond it: AmbigState 1) and +120 m/s: every detection of it at the signal level carries its actor
    index, as the detection level's do. The chain's range of an aliased speed is off by the wrong alias' coupling
    (about 1 m a wrap), and the detections 2 m or more from the car went untagged (−1), so that a report lost what
    a warning was for (an independent tester's finding)."""
    heading = 0.0 if speed_mps > 0 else 180.0
    sc = scenario(f"  - {{id: car, class: {cls}, x_m: 43.7, y_m: 2.0, speed_mps: {abs(speed_mps)}, "
                  f"heading_deg: {heading}}}", ego="{speed_mps: 0.0}", radar="{preset: ars408_like}",
                  road="{lanes: 3, lane_width_m: 3.5, ego_lane: 1}", duration=1.0, seed=3)
    cfg = radar_config(sc)
    seen = 0
    for level in ("detection", "signal"):
        model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(3), cfg.signal)
        for k in range(4):
            model.step(k * sc.period_s, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
            det = model.info.detections
            strong = det.snr_db > 20.0              # the car's returns, not a false alarm
            seen += int(strong.sum())
            assert np.all(det.actor_index[strong] == 0), (level, det.range_m[strong], det.actor_index[strong])
    assert seen >= 8


def _cycle(r, v, state, az=0.0):
    d = _det([v], az=az, r=r)
    d.ambig_state = np.array([state], dtype=np.int64)
    return d


def test_the_tracker_takes_an_ambiguous_detection_at_its_tracks_wrap_and_lists_no_track_only_they_measured():
    """A car closing at −34.05 m/s, ego standing: ars408_like's first sequence aliases it to +4.87 m/s. (a) A track
    the staggered pair resolved takes the cycles the second sequence missed (ambiguous, +4.87) at its own wrap: it
    keeps −34.05 and is never listed receding. (b) A track started from ambiguous detections only is not listed;
    the first resolved detection moves it by whole spans to that speed and lists it. (c) Without ``alias_span_mps``
    (a single ramp) the old rule: an ambiguous detection is taken as measured."""
    from radarnode.radar.models import tracker_for
    span = 2 * ARS.alias_speed_mps
    v, alias = -34.05, _alias(-34.05, ARS)
    assert alias == pytest.approx(v + span)
    dt = 0.072

    def run(tracker, states):
        out = []
        for k, st in enumerate(states):
            r = 150.0 + v * dt * k
            out.append(tracker.step(k * dt, _cycle(r, v if st == AMBIG_STAGGERED else alias, st), (0.0, 0.0)))
        return out

    # (a): resolved, then every other cycle the second sequence misses it
    lists = run(tracker_for(ARS), [AMBIG_STAGGERED] * 3 + [AMBIG_AMBIGUOUS, AMBIG_STAGGERED] * 5)
    assert all(len(o) == 1 for o in lists[2:])
    assert all(o.vrel_long_mps[0] == pytest.approx(v, abs=0.5) for o in lists[2:])
    # (b): five ambiguous cycles list nothing; the resolved one lists it at the resolved speed
    lists = run(tracker_for(ARS), [AMBIG_AMBIGUOUS] * 5 + [AMBIG_STAGGERED] * 3)
    assert [len(o) for o in lists[:5]] == [0] * 5
    listed = [o for o in lists[5:] if len(o)]
    assert listed and all(o.vrel_long_mps[0] == pytest.approx(v, abs=1.0) for o in listed)
    # (c): a single ramp's tracker (no span) lists the alias as measured
    assert tracker_for(PRESETS["mimo12"]).alias_span_mps is None
    from radarnode.perception.tracker import ObjectTracker
    lists = run(ObjectTracker(), [AMBIG_AMBIGUOUS] * 5)
    assert len(lists[-1]) >= 1 and lists[-1].vrel_long_mps[0] > 0.0


def test_a_single_ramps_tracker_resolves_the_wrap_from_the_range_its_track_walks():
    """fast_chirp (±18.99 m/s, cycle 50 ms: one wrap moves a target 1.9 m a cycle, within the tracker's 2.85-m
    gate), ego standing. A car closing at −25 m/s is measured at +12.97 m/s (AmbigState 1) every cycle: the tracker
    ``tracker_for`` gives the preset at its cycle resolves the wrap from the ranges its track measured, and lists it
    from its third hit (RANGE_WALK_MIN_HITS), at −25 m/s (the tracker before, ``ObjectTracker()``, listed it receding
    at +12.97 from its second). A car at −10 m/s (inside ±v_max) keeps its speed, also with 0.15 m of noise on every
    range over 200 cycles; so does a truck at −8 m/s whose second detection lies 2 m beyond its first (another
    reflector: over two hits a wrap, which moved a track of it to +30 m/s and listed it there when two hits
    resolved). A single ramp whose wrap lies beyond the gate (mimo12 at 72 ms: 4.7 m) gets no range walk, nor does a
    tracker without a span."""
    from radarnode.perception.tracker import ObjectTracker
    from radarnode.radar.models import tracker_for
    p, dt = PRESETS["fast_chirp"], 0.05
    tracker = tracker_for(p, dt)
    assert tracker.range_walk and tracker.alias_span_mps == pytest.approx(2 * p.alias_speed_mps)
    assert not tracker_for(PRESETS["mimo12"], 0.072).range_walk and not tracker_for(p).range_walk
    with pytest.raises(ValueError, match="range_walk: True is not allowed without alias_span_mps"):
        ObjectTracker(range_walk=True)

    def run(tr, v, cycles=12, noise=0.0, step=0.0):
        rng = np.random.default_rng(3)
        out = []
        for k in range(cycles):
            r = 120.0 + v * dt * k + noise * rng.standard_normal() + (step if k else 0.0)
            out.append(tr.step(k * dt, _cycle(r, float(_alias(v, p)), AMBIG_AMBIGUOUS), (0.0, 0.0)))
        return out

    lists = run(tracker_for(p, dt), -25.0)
    listed = [o for o in lists if len(o)]
    assert [len(o) for o in lists[:2]] == [0, 0] and len(listed) == 10 and all(len(o) == 1 for o in listed)
    assert all(o.vrel_long_mps[0] == pytest.approx(-25.0, abs=0.5) for o in listed), [o.vrel_long_mps for o in listed]
    assert all(o.dyn_prop[0] == DYN_ONCOMING for o in listed)
    before = [o for o in run(ObjectTracker(), -25.0) if len(o)]
    assert before and all(o.vrel_long_mps[0] == pytest.approx(_alias(-25.0, p), abs=0.5) for o in before)
    for noise, cycles in ((0.0, 12), (0.15, 200)):
        listed = [o for o in run(tracker_for(p, dt), -10.0, cycles, noise) if len(o)]
        assert len(listed) >= cycles - 3 and all(np.all(np.abs(o.vrel_long_mps + 10.0) < 1.0) for o in listed)
    listed = [o for o in run(tracker_for(p, dt), -8.0, 12, step=2.0) if len(o)]
    assert all(np.all(np.abs(o.vrel_long_mps + 8.0) < 1.0) for o in listed), [o.vrel_long_mps for o in listed]


def _truck_cycles(stray_dy: float, cycles: int = 16, v: float = -8.0, dt: float = 0.05):
    """A truck closing at ``v`` in the next lane (y −3.4 m), ego standing, on fast_chirp (AmbigState 1 everywhere):
    its side's four reflectors 3.5 m apart (one group, 10.5 m long) for ten cycles, then its front and one reflector
    that steps 1.9 m nearer along it each cycle (one wrap's drift: 38 m/s × 50 ms) from 9.5 m behind the front,
    ``stray_dy`` across from the side; (x, y) of every detection per cycle."""
    out = []
    for k in range(cycles):
        front = 60.0 + v * dt * k
        if k < 10:
            xs, ys = front + np.array([0.0, 3.5, 7.0, 10.5]), np.full(4, -3.4)
        else:
            xs = np.array([front, front + 9.5 - 1.9 * (k - 10)])
            ys = np.array([-3.4, -3.4 + stray_dy])
        out.append((xs, ys))
    return out


def _run_truck(tracker, cycles, v=-8.0, dt=0.05, p=None):
    lists = []
    for k, (xs, ys) in enumerate(cycles):
        r, az = np.hypot(xs, ys), np.arctan2(ys, xs)
        d = Detections(r, _alias(v * xs / r, p), az, np.zeros(r.size), np.full(r.size, 30.0),
                       np.zeros(r.size, dtype=np.int64), ambig_state=np.full(r.size, AMBIG_AMBIGUOUS))
        lists.append(tracker.step(k * dt, d, (0.0, 0.0)))
    return lists


@pytest.mark.parametrize("stray_dy, on_body", [(0.0, True), (0.9, True), (1.2, False), (2.0, False),
                                               (3.5, False)])
def test_a_reflector_stepping_along_a_tracked_truck_is_not_walked_to_another_wrap(stray_dy, on_body):
    """helper-86's finding (fast_chirp, ``highway_cut_in`` at the detection level, seeds 1, 3, 5, 6): a new track of
    one of a truck's reflectors took the next ones along its side, 74.2, 72.0, 69.8 m, and the range walk moved it a
    wrap (−42.8 m/s where the truck closed at 4.8) and listed it `oncoming` beside the truck's own track. A track on
    the body of a confirmed one whose speed there gives its range rate modulo the span (within BODY_MARGIN_M of its
    extent: 1 m beside a body 0 m wide) now takes that body's wrap and is not walked nor listed
    (ObjectTracker._body_wrap): inside the margin nothing is listed off the truck's speed. Beyond it, and a lane
    away, the same detections are another target's, walked and listed one wrap off, as a single ramp must (a car
    there at −46 m/s would measure the same). The margin applies to the tracks' filtered positions, which lag the
    detections by a few tenths of a metre across: 0.9 and 1.2 m bracket it, not 0.99 and 1.01."""
    from radarnode.radar.models import tracker_for
    p, dt = PRESETS["fast_chirp"], 0.05
    lists = _run_truck(tracker_for(p, dt), _truck_cycles(stray_dy), p=p)
    rows = [(round(float(x), 1), round(float(v), 1)) for o in lists for x, v in zip(o.dist_long_m, o.vrel_long_mps)]
    off = [row for row in rows if abs(row[1] + 8.0) > 1.0]
    assert any(abs(v + 8.0) < 1.0 for _, v in rows)                  # the truck itself, listed throughout
    if on_body:
        assert not off, off
    else:
        assert off and all(abs(v + 8.0 - 2 * -p.alias_speed_mps) < 1.5 for _, v in off), off


@pytest.mark.parametrize("seed", [1, 3])
def test_the_default_scene_on_fast_chirp_lists_its_truck_at_its_speed_only(seed):
    """helper-86's scene itself: ``highway_cut_in`` with ``preset: fast_chirp`` at the detection level (the truck at
    −4.8 m/s in the right lane, guardrail posts on both sides). Before ObjectTracker._body_wrap a second track of the
    truck walked a wrap and was listed `oncoming` at −42.8 m/s for 6 cycles in seed 1 and 4 in seed 3. Now every row
    of the truck is within 3 m/s of its speed, it is listed in at least 290 of the 300 cycles, and at most 30 rows
    of guardrail posts (or of no truth) are listed moving, oncoming or crossing (11 and 9 here, as before the
    change)."""
    import re
    from pathlib import Path
    from radarnode.radar.setup import parse_scenario
    text = (Path(__file__).resolve().parents[1] / "scenarios" / "highway_cut_in.yaml").read_text()
    text = re.sub(r"preset: *\w+", "preset: fast_chirp", text)
    text = re.sub(r"^seed: *\d+", f"seed: {seed}", text, flags=re.M)
    sc = parse_scenario(text)
    cfg = radar_config(sc)
    model = make_model("detection", Scene(sc), cfg.preset, np.random.default_rng(sc.seed), cfg.signal)
    truck = [a.id for a in sc.actors].index("truck")
    rails = [-1] + [i for i, a in enumerate(sc.actors) if a.object_class == "guardrail"]    # and no truth at all
    rows = wrong = moving_posts = 0
    for k in range(sc.num_cycles):
        frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
        o = frame.objects
        mine = o.actor_index == truck
        rows += int(mine.any())
        wrong += int(np.sum(np.abs(o.vrel_long_mps[mine] - view.vx_mps[truck]) >= 3.0))
        moving_posts += int(np.sum(np.isin(o.actor_index, rails) & np.isin(o.dyn_prop, (DYN_MOVING, DYN_ONCOMING, DYN_CROSSING_MOVING))))
    assert wrong == 0 and rows >= 290 and moving_posts <= 30, (wrong, rows, moving_posts)


def test_a_car_closing_beyond_a_single_ramps_span_is_listed_at_its_true_speed_at_every_level():
    """fast_chirp, ego standing, a car closing at 25 m/s from 120 m (measured at +12.97 m/s, one wrap away): an
    independent tester found it listed as `moving` away at +13 m/s at every level, and split between two
    alternating IDs at the detection and signal levels. Now each level lists it in at least 55 of the 58 cycles from
    its third on (the hits that resolve the wrap), always within 0.5 m/s of its true range rate and as oncoming,
    under one ID; its clusters keep the aliased speed, flagged ambiguous."""
    sc = scenario("  - {id: onc, class: car, x_m: 120.0, lane: 0, speed_mps: 25.0, heading_deg: 180.0}\n",
                  ego="{speed_mps: 0.0}", radar="{preset: fast_chirp, output: objects}",
                  road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0}", duration=3.0, seed=4)
    p = radar_config(sc).preset
    for level in ("object", "detection", "signal"):
        model = make_model(level, Scene(sc), p, np.random.default_rng(sc.seed), radar_config(sc).signal)
        rows, ids, cluster_rates = 0, set(), []
        for k in range(60):
            frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=p.max_range_m, clusters=True))
            mine = np.flatnonzero(frame.objects.actor_index == 0)
            assert np.all(np.abs(frame.objects.vrel_long_mps[mine] - view.vx_mps[0]) < 0.5), (level, k)
            assert np.all(frame.objects.dyn_prop[mine] == DYN_ONCOMING), (level, k)
            rows += mine.size
            ids.update(frame.objects.id[mine].tolist())
            near = np.abs(frame.clusters.dist_long_m - view.x_m[0]) < 3.0
            cluster_rates += list(zip(frame.clusters.vrel_long_mps[near], frame.clusters.ambig_state[near]))
        assert rows >= 55 and len(ids) == 1, (level, rows, ids)
        assert cluster_rates and all(v > 0.0 and st == AMBIG_AMBIGUOUS for v, st in cluster_rates), level


@pytest.mark.parametrize("factor, listed", [(0.99, True), (1.0 - 1e-9, True), (1.01, False), (2.0, False)])
@pytest.mark.parametrize("level", ["object", "detection"])
def test_a_single_ramps_aliased_target_is_listed_at_its_true_speed_within_the_gate_and_not_beyond(level, factor,
                                                                                                   listed):
    """The switch of the range walk (models.tracker_for: one wrap's drift a cycle within ALIAS_GATE_M) and of the
    object level's listing of an aliased target swept across together: mimo12's one wrap (64.7 m/s) with the cycle
    set to 0.99, 1, 1.01 and 2 times the gate over it, a point closing at 39.9 m/s (measured at +24.8). Within the
    gate both levels list it, at its true speed in every cycle they do (never at the aliased one); beyond it neither
    lists it."""
    from radarnode.perception.tracker import ALIAS_GATE_M
    p0 = PRESETS["mimo12"]
    cycle = factor * ALIAS_GATE_M / (2.0 * p0.alias_speed_mps)
    sc = scenario("  - {id: a, class: point, x_m: 100.0, y_m: 0.0, speed_mps: 19.9, heading_deg: 180, rcs_dbsm: 25}\n",
                  ego="{speed_mps: 20.0}", radar=f"{{preset: mimo12, overrides: {{cycle_period_s: {cycle!r}}}}}",
                  duration=1.5)
    p = radar_config(sc).preset
    model = make_model(level, Scene(sc), p, np.random.default_rng(1), radar_config(sc).signal)
    seen = []
    for k in range(12):
        frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=p.max_range_m))
        at = np.abs(frame.objects.dist_long_m - view.range_m[0]) < 6.0
        assert np.all(np.abs(frame.objects.vrel_long_mps[at] - view.vx_mps[0]) < 1.0), (k, frame.objects.vrel_long_mps)
        if k >= 3:
            seen.append(bool(at.any()))
    assert (np.mean(seen) >= 0.8) if listed else not any(seen), (factor, seen)


@pytest.mark.parametrize("v, listed", [
    (55.4, True), (55.7, False), (111.1, False),          # +200 km/h: just below, just above, twice
    (-110.9, True), (-111.3, False), (-222.2, False),     # −400 km/h: the same
])
def test_a_target_is_listed_inside_the_staggered_span_and_never_beyond_it_at_both_levels(v, listed):
    """ars408_like resolves −400…+200 km/h. Inside, a point target is listed (at its true speed); beyond, every
    detection is ambiguous and the trackers list nothing, at the object and detection levels alike."""
    lo, hi = ARS.range_rate_span_mps
    assert (lo <= v <= hi) == listed
    x, heading = (40.0, "") if v > 0 else (240.0, ", heading_deg: 180")
    ego = max(0.0, -v - 140.0)            # an actor drives at most 150 m/s: the ego closes the rest
    sc = scenario(f"  - {{id: a, class: point, x_m: {x}, y_m: 0.0, speed_mps: {abs(v) - ego:.2f}{heading}, "
                  "rcs_dbsm: 25}\n", ego=f"{{speed_mps: {ego:.2f}}}", radar="{preset: ars408_like}", duration=1.0)
    for level in ("object", "detection"):
        model = make_model(level, Scene(sc), ARS, np.random.default_rng(1), radar_config(sc).signal)
        shown = []
        for k in range(sc.num_cycles):
            frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=ARS.max_range_m))
            o = frame.objects
            if k >= 3:
                shown.append(len(o) > 0)
                assert np.all(np.abs(o.vrel_long_mps - v) < 1.0), (level, o.vrel_long_mps, v)
        assert (np.mean(shown) >= 0.8) if listed else not any(shown), (level, v, shown)


def _cluster_medians(sc, level: str, frames: int = 8) -> tuple[float, float, float, int]:
    """Median cluster (range, azimuth °, RCS) over ``frames`` cycles of ``sc`` at ``level``, and the count."""
    model = make_model(level, Scene(sc), radar_config(sc).preset, np.random.default_rng(3), radar_config(sc).signal,
                       clusters_wanted=True)
    cfg = RuntimeConfig(max_distance_m=radar_config(sc).preset.max_range_m, clusters=True)
    r, az, rcs = [], [], []
    for k in range(frames):
        cl = model.step(k * sc.period_s, cfg)[0].clusters
        r.extend(np.hypot(cl.dist_long_m, cl.dist_lat_m))
        az.extend(np.degrees(np.arctan2(cl.dist_lat_m, cl.dist_long_m)))
        rcs.extend(cl.rcs_dbsm)
    return float(np.median(r)), float(np.median(az)), float(np.median(rcs)), len(r)


@pytest.mark.parametrize("x_m", [100.0, 114.0, 115.0, 133.7, 2 * 114.56 + 5.0])
def test_a_target_beyond_the_unambiguous_range_folds_at_the_object_level_as_at_the_others(x_m):
    """64 complex samples: range bins end at 114.56 m inside ars408_like's 250-m sector. Beyond that the beat folds:
    the object level reported 131 m and the true RCS where the detection and signal levels report 16.4 m and the RCS
    the radar equation gives at that range (an independent tester's finding). Just below, at and past the fold, and
    past twice it: the same range (within 0.3 m) and RCS (within 1 dB) at the three levels (the signal level's
    raw-IQ chain held too since session 61: an independent tester saw it agree, no test had held it)."""
    sc = scenario(f"  - {{id: t, class: point, x_m: {x_m}, y_m: 0.0, speed_mps: 5.0, rcs_dbsm: 50, swerling: 0}}",
                  ego="{speed_mps: 0.0}", road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0}", duration=1.0,
                  radar="{preset: ars408_like, output: clusters, overrides: {num_samples: 64, complex_sampling: true, "
                        "tx_power_dbm: 30}}")
    unamb = radar_config(sc).preset.unambiguous_range_m
    assert unamb == pytest.approx(114.56, abs=0.01)
    obj, det, sig = (_cluster_medians(sc, level) for level in ("object", "detection", "signal"))
    assert obj[3] >= 6 and det[3] >= 6 and sig[3] >= 6
    assert obj[0] == pytest.approx(det[0], abs=0.3) and obj[2] == pytest.approx(det[2], abs=1.0), (obj, det)
    assert sig[0] == pytest.approx(det[0], abs=0.3) and sig[2] == pytest.approx(det[2], abs=1.0), (sig, det)
    # where the fold puts it: the range the default preset (458-m range bins) measures, modulo the 114.56 m
    plain = scenario(f"  - {{id: t, class: point, x_m: {x_m}, y_m: 0.0, speed_mps: 5.0, rcs_dbsm: 50, swerling: 0}}",
                     ego="{speed_mps: 0.0}", road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0}", duration=1.0,
                     radar="{preset: ars408_like, output: clusters, overrides: {tx_power_dbm: 30}}")
    assert obj[0] == pytest.approx(math.fmod(_cluster_medians(plain, "object")[0], unamb), abs=0.3)


@pytest.mark.parametrize("x_m, speed", [(54.2, 5.0), (60.0, 12.0), (100.0, 3.0)])
def test_a_folded_target_reads_the_rcs_at_its_folded_range_in_every_cycle_at_the_object_level(x_m, speed):
    """fast_chirp with 64 samples folds at 47.97 m. The object level read a folded target's RCS against its range
    after the fold wherever some range–Doppler coupling was left in it (a remainder of 1e-15 m/s of the speed
    taken out was enough): 30 dBsm at 2 m in two cycles of six, where the detection level read −25 (a tester's
    finding; the medians of the test above hid it). Every cycle now (the target beyond the fold throughout), at
    the object level as at the detection level."""
    sc = scenario(f"  - {{id: a, class: point, rcs_dbsm: 30.0, swerling: 0, x_m: {x_m}, y_m: 0.0, "
                  f"speed_mps: {speed}, heading_deg: 180}}", ego="{speed_mps: 0.0}", duration=0.4, seed=3,
                  road="{lanes: 1, ego_lane: 0}",
                  radar="{preset: fast_chirp, output: clusters, overrides: {num_samples: 64}}")
    p = radar_config(sc).preset
    assert p.unambiguous_range_m == pytest.approx(47.97, abs=0.01)
    cfg = RuntimeConfig(max_distance_m=p.max_range_m, clusters=True)
    seen = {}
    for level in ("object", "detection"):
        model = make_model(level, Scene(sc), p, np.random.default_rng(3), radar_config(sc).signal, clusters_wanted=True)
        seen[level] = []
        for k in range(sc.num_cycles):
            cl = model.step(k * sc.period_s, cfg)[0].clusters
            near = np.abs(cl.dist_lat_m) < 2.0
            seen[level].append((np.hypot(cl.dist_long_m, cl.dist_lat_m)[near], cl.rcs_dbsm[near]))
    both = 0
    for (r_o, rcs_o), (r_d, rcs_d) in zip(seen["object"], seen["detection"]):
        assert np.all(r_o < p.unambiguous_range_m) and np.all(rcs_o < 25.0), (r_o, rcs_o)
        if r_o.size == 1 and r_d.size == 1:
            both += 1
            assert r_o[0] == pytest.approx(r_d[0], abs=0.3) and rcs_o[0] == pytest.approx(rcs_d[0], abs=1.5), \
                (r_o, rcs_o, r_d, rcs_d)
    assert both >= sc.num_cycles // 2


def test_a_grating_lobe_reports_the_rcs_inferred_at_the_angle_measured_at_every_level():
    """mimo12 with its elements 0.7 λ apart: a target at 42.8° is measured at −41.5°. The radar divides the element
    pattern out at the angle it measures: the detection and signal levels report 1.5 dB less than the truth, the
    object level reported the truth (an independent tester's finding)."""
    sc = scenario("  - {id: p, class: point, x_m: 16.556, y_m: 15.321, speed_mps: 0.0, rcs_dbsm: 10, swerling: 0}",
                  ego="{speed_mps: 0.0}", duration=1.0,
                  radar="{preset: mimo12, output: clusters, overrides: {element_spacing_wl: 0.7}}")
    obj, det = _cluster_medians(sc, "object"), _cluster_medians(sc, "detection")
    assert obj[1] == pytest.approx(det[1], abs=0.5) and obj[1] < -40.0             # seen on the other side
    # (the sensor sits ahead of the ego's origin: from it the target is 50° off the axis, cos 50°/cos 41.5° = −1.3 dB)
    assert obj[2] == pytest.approx(det[2], abs=0.3) and obj[2] < 9.0, (obj, det)


@pytest.mark.parametrize("preset", ["ars408_like", "mimo12"])
@pytest.mark.parametrize("level, seed", [("detection", 3), ("detection", 6), ("auto", 3), ("auto", 6),
                                         ("signal", 1)])
def test_posts_passing_close_beside_the_sensor_at_motorway_speed_stay_standing(preset, level, seed):
    """An independent tester's road (2026-12-03): posts 2 m apart 0.8 m beyond both edges, the ego at 130 km/h for
    4 s, the object list every cycle. A standing track 0–7 m ahead at 45–60° took the next post two cycles running
    (the ego moves 2.6 m a cycle) and was listed crossing for its last 2–3 cycles (ars408_like and mimo12, in these
    seeds). Every object stays standing now (tracker.MOVING_EVIDENCE_CYCLES: three of three within 20 m)."""
    from radarnode.perception.types import DYN_STATIONARY, DYN_STOPPED
    sc = scenario("", ego="{speed_mps: 36.11}", radar=f"{{preset: {preset}}}", duration=4.0, seed=seed,
                  road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0, guardrails: {left_offset_m: 0.8, "
                       "right_offset_m: 0.8, post_spacing_m: 2.0, rcs_dbsm: 0.0}}")
    model = make_model(level, Scene(sc), radar_config(sc).preset, np.random.default_rng(seed), radar_config(sc).signal)
    cfg = RuntimeConfig(max_distance_m=radar_config(sc).preset.max_range_m)
    listed = moving = 0
    for k in range(sc.num_cycles):
        ol = model.step(k * sc.period_s, cfg)[0].objects
        listed += len(ol)
        moving += int((~np.isin(ol.dyn_prop, (DYN_STATIONARY, DYN_STOPPED))).sum())
    assert listed > 100 and moving == 0, (listed, moving)


@pytest.mark.parametrize("level", ["detection", "object"])
def test_a_rear_radar_at_motorway_speed_sees_the_posts_behind_standing_and_within_its_range(level):
    """A rear radar (yaw 180°) saw no guardrail post beyond 5 m behind the ego (the posts were made ahead only: a
    tester's finding), so the 130-km/h check had nothing to hold; and a standing track receding past the far sector
    coasted 26 m beyond it, listed out to 276 m. Now the posts behind are seen out to the range, none is reported
    moving, and nothing is listed beyond the range."""
    sc = scenario("", ego="{speed_mps: 36.11}", radar="{preset: ars408_like, output: clusters, mount: {x_m: -1.0, "
                  "y_m: 0.0, yaw_deg: 180}}", road="{lanes: 2, lane_width_m: 3.5, ego_lane: 0, guardrails: "
                  "{left_offset_m: 1.0, right_offset_m: 1.0, post_spacing_m: 4.0}}", duration=3.0, seed=1)
    cfg = radar_config(sc)
    model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(1), cfg.signal, clusters_wanted=True)
    run = RuntimeConfig(max_distance_m=cfg.preset.max_range_m, clusters=True)
    far_cluster = far_object = 0.0
    moving = listed = 0
    for k in range(30):
        frame = model.step(k * sc.period_s, run)[0]
        cl, ol = frame.clusters, frame.objects
        far_cluster = max(far_cluster, float(np.hypot(cl.dist_long_m, cl.dist_lat_m).max(initial=0.0)))
        if len(ol):
            far_object = max(far_object, float(np.hypot(ol.dist_long_m, ol.dist_lat_m).max()))
        listed += len(ol)
        moving += int(np.isin(ol.dyn_prop, (DYN_MOVING, DYN_ONCOMING, DYN_CROSSING_MOVING)).sum())
    assert far_cluster > 150.0, far_cluster
    assert moving == 0
    if level == "detection":          # (the object level lists no guardrail post as an object, ahead or behind)
        assert listed > 300 and 150.0 < far_object <= cfg.preset.max_range_m + 1.0, (listed, far_object)


@pytest.mark.parametrize("preset, speed", [("ars408_like", 30.0), ("ars408_like", 75.0), ("ars408_like", 100.0),
                                           ("mimo12", 75.0), ("mimo12", 100.0)])
def test_a_fast_target_reads_its_rcs_at_the_range_reported_at_every_level(preset, speed):
    """The radar infers the RCS at the range it reports. Where a speed is resolved after the RCS was read
    (staggered ramps), the range moves by the coupling of the wraps and the RCS must move with it: a 20-dBsm
    point closing at 75–100 m/s read 19.3–19.6 dBsm at the detection and signal levels of ars408_like where the
    object level read 20.0 (a tester's finding). A single ramp (mimo12) reports the aliased speed and the range its
    coupling moved: the object level read the RCS at the true range, 0.1–0.2 dB above the detection level."""
    sc = scenario(f"  - {{id: a, class: point, x_m: 110.0, y_m: 0.0, speed_mps: {speed}, heading_deg: 180, "
                  "rcs_dbsm: 20, swerling: 0}\n", ego="{speed_mps: 0.0}", radar=f"{{preset: {preset}, output: clusters}}",
                  duration=1.0)
    obj, det = _cluster_medians(sc, "object"), _cluster_medians(sc, "detection")
    assert obj[3] >= 6 and det[3] >= 6
    assert obj[2] == pytest.approx(det[2], abs=0.05), (obj, det)
    if preset == "ars408_like":         # resolved: the true range, the true RCS (the signal level's chain too)
        sig = _cluster_medians(sc, "signal")
        assert sig[3] >= 6
        for rcs in (obj[2], det[2], sig[2]):
            assert rcs == pytest.approx(20.0, abs=0.1), (obj, det, sig)


@pytest.mark.parametrize("ego_mps", [19.0, 36.11, 55.6])
def test_a_standing_reflector_reads_its_rcs_at_the_range_reported_at_every_level(ego_mps):
    """A standing reflector passed at 130 and 200 km/h is aliased on ars408_like (±19.5 m/s) and resolved (by the
    staggered pair, or as a stationary candidate where the second sequence missed it); the wraps' coupling moves its
    range by about 1 m a wrap and its RCS must move with it: 19.83–19.87 dBsm before (the same finding as above;
    just below the alias speed nothing moves)."""
    sc = scenario("  - {id: a, class: point, x_m: 140.0, y_m: 2.0, speed_mps: 0.0, rcs_dbsm: 20, swerling: 0}\n",
                  ego=f"{{speed_mps: {ego_mps}}}", radar="{preset: ars408_like, output: clusters}", duration=1.0)
    got = [_cluster_medians(sc, level) for level in ("object", "detection", "signal")]
    for r, az, rcs, n in got:
        assert n >= 6 and rcs == pytest.approx(20.0, abs=0.1), got


@pytest.mark.parametrize("speed", [70.0, 100.0, -70.0])
def test_the_signal_level_divides_the_range_migration_out_of_a_fast_target_s_rcs(speed):
    """mimo12's frame is long enough for a target beyond its alias speed to migrate 1–2 range bins: the chain read
    the peak cell, which lacks the energy the migration spreads over its neighbours, and reported a 20-dBsm point
    0.25 dB low at 70 m/s and 0.6 dB at 100 m/s where the detection level reads the RCS at the range reported (two
    independent testers). The migrating fit's gain (MigrationFit.peak_gain) is divided out now."""
    heading = ", heading_deg: 180" if speed > 0 else ""
    sc = scenario(f"  - {{id: a, class: point, x_m: {60.0 if speed > 0 else 20.0}, y_m: 0.0, speed_mps: {abs(speed)}"
                  f"{heading}, rcs_dbsm: 20, swerling: 0}}\n", ego="{speed_mps: 0.0}",
                  radar="{preset: mimo12, output: clusters}", duration=0.6)
    det, sig = _cluster_medians(sc, "detection"), _cluster_medians(sc, "signal")
    assert det[3] >= 6 and sig[3] >= 6
    assert sig[2] == pytest.approx(det[2], abs=0.1), (det, sig)


@pytest.mark.parametrize("second", ["{id: b, class: point, x_m: 60.0, y_m: 0.0, speed_mps: 70.75, heading_deg: 180, "
                                    "rcs_dbsm: 17, swerling: 0}",
                                    "{id: b, class: point, x_m: 61.3, y_m: 1.75, speed_mps: 70.0, heading_deg: 180, "
                                    "rcs_dbsm: 20, swerling: 0}"])
def test_a_fast_target_beside_a_neighbour_has_the_migration_divided_out_too(second):
    """A neighbour 3 Doppler bins or 1.3 m away cuts a fast target's patch to 3 × 3 cells, where the still fit's beam
    beats the migrating one's: the migration's loss was not divided out there (−0.28 and −0.23 dB against the
    detection level at 70 m/s on mimo12: an independent tester's finding). It is wherever the peak is judged
    wrapped at the alias number the migrating fit chose."""
    y = "-1.75" if "61.3" in second else "0.0"
    sc = scenario(f"  - {{id: a, class: point, x_m: 60.0, y_m: {y}, speed_mps: 70.0, heading_deg: 180, rcs_dbsm: 20, "
                  f"swerling: 0}}\n  - {second}\n", ego="{speed_mps: 0.0}", radar="{preset: mimo12, output: clusters}",
                  duration=0.1 + 1e-6, extra="cycle_period_s: 0.01")
    got = {}
    for level in ("detection", "signal"):
        model = make_model(level, Scene(sc), radar_config(sc).preset, np.random.default_rng(3), radar_config(sc).signal)
        cfg = RuntimeConfig(max_distance_m=radar_config(sc).preset.max_range_m)
        strongest = []
        for k in range(sc.num_cycles):
            model.step(k * sc.period_s, cfg)
            det = model.info.detections
            if len(det):
                strongest.append(det.rcs_dbsm[np.argmax(det.snr_db)])
        assert len(strongest) >= 8
        got[level] = float(np.median(strongest))
    assert got["signal"] == pytest.approx(got["detection"], abs=0.1), got


def _wide_mimo12():
    """mimo12 with a field of view of ±90° (a user's preset: no shipped one sees beyond ±75°)."""
    import dataclasses
    from radarnode.radar.presets import FovSector
    return dataclasses.replace(PRESETS["mimo12"], fov=(FovSector(PRESETS["mimo12"].max_range_m, 90.0),))


def _angles_and_rcs(frames):
    """(azimuths in degrees, RCS) of the detections within 1.5 m of 15 m over ``frames`` (Detections)."""
    az, rcs = [], []
    for d in frames:
        near = np.abs(d.range_m - 15.0) < 1.5
        az.extend(np.degrees(d.azimuth_rad[near]))
        rcs.extend(d.rcs_dbsm[near])
    return np.array(az), np.array(rcs)


@pytest.mark.parametrize("az", [79.9, 80.1, 89.0, 89.5, -89.5])
def test_near_endfire_the_detection_level_reads_the_angle_as_the_chain_does(az):
    """A λ/2 array measures d·sinθ, which wraps at ±½: near ±90° noise puts a target on the other side in some
    frames. The detection level drew the noise in angle and clipped it at ±90°, where it divided out an element
    pattern of nil: a 20-dBsm point at +89.9° read 44.6 dBsm by the median (99 dBsm in one frame), never on the
    other side, where the signal level read it at −86° in 0.4 of the frames and −11.7 dBsm (an independent
    tester's finding; mimo12 with a ±90° field of view). Beyond 80° (ambiguity.ENDFIRE_RAD) it draws in d·sinθ;
    just below, in angle as before (the two agree there)."""
    from radarnode.radar.signal_model import synthesize_rd
    p = _wide_mimo12()
    chain = DspChain(p)
    scat = point_targets([15.0], [az], [0.0], 20.0)
    det_az, det_rcs = _angles_and_rcs(detection_model.detect(p, scat, np.random.default_rng(s), chain.statistic)
                                      for s in range(400))
    sig_az, sig_rcs = _angles_and_rcs(chain.process_rd(synthesize_rd(p, scat, np.random.default_rng(s)))
                                      for s in range(40))
    assert det_az.size >= 390 and sig_az.size >= 39
    assert np.all(np.abs(det_az) <= 90.0) and np.all(np.isfinite(det_rcs))
    other_det, other_sig = np.mean(np.sign(det_az) != np.sign(az)), np.mean(np.sign(sig_az) != np.sign(az))
    assert abs(other_det - other_sig) <= 0.2, (other_det, other_sig)
    if abs(az) < 85.0:                           # one side: the angle's spread as the chain's
        assert other_det == 0.0 and np.std(det_az) == pytest.approx(np.std(sig_az), rel=0.35)
    assert np.median(det_rcs) == pytest.approx(np.median(sig_rcs), abs=1.5)
    assert np.median(det_rcs) == pytest.approx(20.0, abs=0.2) if abs(az) < 85.0 else np.median(det_rcs) < 18.0


def test_the_detection_level_s_angle_noise_is_continuous_across_its_switch_to_d_sin_theta():
    """Just below and just above ambiguity.ENDFIRE_RAD (80°) the detection level's angles spread alike: the draw in
    angle and the draw in d·sinθ agree there to a tenth of σ (the arcsine's curvature)."""
    p = _wide_mimo12()
    chain = DspChain(p)
    edge = math.degrees(ambiguity.ENDFIRE_RAD)
    spread = {}
    for az in (edge - 0.01, edge, edge + 0.01):
        scat = point_targets([15.0], [az], [0.0], 0.0)     # 0 dBsm: σ of about 0.3° there
        got, _ = _angles_and_rcs(detection_model.detect(p, scat, np.random.default_rng(s), chain.statistic)
                                 for s in range(600))
        assert got.size >= 590
        spread[az] = (np.mean(got) - az, np.std(got))
    (b0, s0), (b1, s1), (b2, s2) = spread.values()
    assert s0 > 0.05 and s2 == pytest.approx(s0, rel=0.15) and s1 == pytest.approx(s0, rel=0.15)
    assert abs(b2 - b0) < 0.2 * s0 and abs(b1 - b0) < 0.2 * s0


@pytest.mark.parametrize("az", [89.0, 89.5, -89.5])
def test_near_endfire_the_object_level_reads_the_angle_and_rcs_as_the_detection_level(az):
    """The object level drew its angle in angle and reported it unclipped: beyond ±90° (behind the antenna) half
    the frames at ±89.5°, dropped as outside the field of view. It now draws where the array measures it and reads
    the RCS with the element pattern at the angle measured, as the other levels."""
    p = _wide_mimo12()
    x, y = 3.7 + 15.0 * math.cos(math.radians(az)), 15.0 * math.sin(math.radians(az))
    sc = scenario(f"  - {{id: p, class: point, x_m: {x:.6f}, y_m: {y:.6f}, speed_mps: 0.0, rcs_dbsm: 20.0, "
                  "swerling: 0}", ego="{speed_mps: 0.0}", radar="{preset: mimo12, output: clusters}", duration=20.0)
    got = {}
    for level in ("object", "detection"):
        model = make_model(level, Scene(sc), p, np.random.default_rng(5), radar_config(sc).signal,
                           clusters_wanted=True)
        cfg = RuntimeConfig(max_distance_m=p.max_range_m, clusters=True)
        frames = []
        for k in range(200):
            model.step(k * sc.period_s, cfg)
            frames.append(model.info.detections)
        got[level] = _angles_and_rcs(frames)
    (oa, orcs), (da, drcs) = got["object"], got["detection"]
    assert oa.size >= 190 and da.size >= 190 and np.all(np.abs(oa) <= 90.0)
    assert abs(np.mean(np.sign(oa) != np.sign(az)) - np.mean(np.sign(da) != np.sign(az))) <= 0.12
    assert np.median(orcs) == pytest.approx(np.median(drcs), abs=1.0)


@pytest.mark.parametrize("az, snr_db", [(79.9, 16.0), (80.1, 16.0), (75.0, 13.0), (70.0, 10.0)])
def test_near_the_wrap_the_angle_is_read_on_the_other_side_as_often_as_theory_gives(az, snr_db):
    """Where d·sinθ lies within ambiguity.WRAP_REACH_SIGMA of its σ from the wrap at ±½, the chain reads a return on
    the other side when the noise carries it across: P = Q(margin/σ_u), margin = ½ − d·sinθ. Drawn in angle, a
    draw wrapped only past 90°: at 79.9° and ρ ≈ 16 dB the detection level read the other side in 0.014 of the
    frames, six times less than at 80.1° (0.090), where the chain reads 0.044 and 0.095 (an independent tester's
    finding). Checked on ambiguity.measured_azimuth itself against the normal tail (mimo12, 200,000 draws)."""
    from scipy.stats import norm
    from radarnode.radar import equation
    from radarnode.radar.calibration import chain_efficiency
    p = PRESETS["mimo12"]
    rng = np.random.default_rng(7)
    n = rng.standard_normal(200_000)
    a = math.radians(az)
    snr = np.full(n.size, snr_db)
    ea = chain_efficiency(snr)[2]
    sigma = ea * equation.crb_azimuth_rad(p, snr, np.full(n.size, a))
    got, wide = ambiguity.measured_azimuth(p, np.full(n.size, a), sigma, n, snr, ea)
    assert wide.all()
    sigma_u = p.element_spacing_wl * ea[0] * float(equation.crb_azimuth_rad(p, np.array([snr_db]), np.zeros(1))[0])
    want = norm.sf((0.5 - p.element_spacing_wl * math.sin(a)) / sigma_u)
    other = np.mean(got < 0)
    assert want > 2e-5 and other == pytest.approx(want, abs=4 * math.sqrt(want / n.size) + 1e-4)
    assert np.all(np.abs(got) <= math.pi / 2)


def test_below_half_a_wavelength_the_analytic_levels_read_the_chain_s_beamformer_edge():
    """An array of elements 0.4 λ apart sees d·sinθ only within ±0.4: the chain's beamformer reads nothing beyond half
    a bin inside its last grid bin there (82.40° for a return at 85°, 88° or 89.5°), and divides the element pattern
    out there. The detection level read a draw past the visible edge at ±90°, where the pattern is nil: 98.5 dBsm by
    the median at 89.5° (an independent tester's finding). Now it reads where the chain reads, the same RCS."""
    import dataclasses
    from radarnode.radar.chain import DspConfig
    from radarnode.radar.signal_model import synthesize_rd
    assert ambiguity.CHAIN_DOA_BINS == DspConfig().doa_fft_size
    p = dataclasses.replace(_wide_mimo12(), element_spacing_wl=0.4)
    chain = DspChain(p)
    for az in (85.0, 89.5):
        scat = point_targets([15.0], [az], [0.0], 20.0)
        det_az, det_rcs = _angles_and_rcs(detection_model.detect(p, scat, np.random.default_rng(s), chain.statistic)
                                          for s in range(200))
        sig_az, sig_rcs = _angles_and_rcs(chain.process_rd(synthesize_rd(p, scat, np.random.default_rng(s)))
                                          for s in range(5))
        assert det_az.size >= 195 and sig_az.size == 5
        assert np.max(np.abs(det_az)) < 89.0 and np.median(det_az) == pytest.approx(np.median(sig_az), abs=0.05)
        assert np.median(det_rcs) == pytest.approx(np.median(sig_rcs), abs=0.3)
