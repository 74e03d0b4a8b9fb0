"""Fidelity levels behind the node: every level gives frames the consumer decodes; auto picks by content."""

from __future__ import annotations

import numpy as np
import pytest

from radarnode.consumer.assembler import CycleAssembler
from radarnode.errors import ConfigError
from radarnode.radar.setup import radar_config
from radarnode.radar.models import GLINT_SPAN_BEAMS, AutoModel, conflicting_actors, extended_actors, make_model
from radarnode.radar.object_model import RuntimeConfig
from radarnode.perception.tracker import GROUP_EPS_LONG_M, GROUP_EPS_M
from radarnode.radar.presets import PRESETS
from radarnode.radar.scatterers import point_targets
from radarnode.scene.world import Scene
from radarnode.wire.node import EgoMotionSender, RadarNode
from radarnode.wire.runner import SimulatedClock, run_node
from tests.conftest import SCENARIOS
from tests.helpers import scenario

TRAFFIC = """
  - {id: a, class: car, x_m: 30.0, lane: 1, speed_mps: 22.0}
  - {id: b, class: truck, x_m: 60.0, lane: 0, speed_mps: 18.0}
"""


@pytest.mark.parametrize("level", ["object", "detection", "signal", "auto"])
@pytest.mark.parametrize("output", ["objects", "clusters"])
def test_every_level_feeds_the_same_wire_and_consumer(level, output):
    sc = scenario(TRAFFIC, radar=f"{{preset: mimo12, output: {output}}}", duration=1.5)
    node = RadarNode(sc, fidelity=level)
    frames, outs = [], []
    run_node(node, clock=SimulatedClock(), sinks=[frames.append], on_cycle=outs.append,
             vehicle=EgoMotionSender(node.scene))
    assembler = CycleAssembler()
    cycles = list(assembler.feed(frames))
    assert len(cycles) == len(outs) == 20 and assembler.stats.dropped() == 0
    last = cycles[-1]
    if output == "objects":
        ol = last.objects
        near = np.argmin(np.abs(ol.dist_long_m - outs[-1].view.x_m[0]) + np.abs(ol.dist_lat_m))
        assert abs(ol.dist_long_m[near] - outs[-1].view.x_m[0]) < 1.0      # the car 26 m ahead
        assert abs(ol.vrel_long_mps[near] - 2.0) < 0.6
    else:
        assert len(last.clusters) >= 2


_POSTS = "guardrails: {left_offset_m: 1.0, right_offset_m: 1.0, post_spacing_m: 4.0}"
_CLUTTER = "clutter_density_per_m2: 0.001"


# (the object level renders no road clutter, as the README's level table says: no clutter case for it)
@pytest.mark.parametrize("level, what", [(level, _POSTS) for level in ("object", "detection", "signal", "auto")]
                         + [(level, _CLUTTER) for level in ("detection", "signal", "auto")])
def test_every_level_reports_posts_and_clutter_in_a_scene_without_actors(level, what):
    """No actors, only posts or clutter: ``auto`` indexed its (empty) per-actor table with the posts' actor index
    -1 and raised IndexError (an independent tester's finding); every level now sends their clusters."""
    road = "{lanes: 2, lane_width_m: 3.5, ego_lane: 0" + ("}" if what.startswith("clutter") else f", {what}}}")
    sc = scenario("", ego="{speed_mps: 36.11}", road=road, radar="{preset: ars408_like, output: clusters}",
                  duration=0.5, extra=f"signal: {{{what}}}" if what.startswith("clutter") else "")
    node = RadarNode(sc, fidelity=level)
    outs = []
    run_node(node, clock=SimulatedClock(), sinks=[lambda m: None], on_cycle=outs.append,
             vehicle=EgoMotionSender(node.scene))
    assert len(outs) == 6
    assert sum(len(o.frame.clusters) for o in outs) > 0


def test_conflicting_actors_are_those_within_the_chains_resolution():
    p = PRESETS["mimo12"]
    apart = point_targets([20.0, 40.0], [0.0, 10.0], [1.0, 2.0])
    together = point_targets([40.0, 40.45], [10.0, 10.3], [2.0, 2.0])       # pedestrians 0.45 m apart
    assert not conflicting_actors(p, apart, 2).any()
    assert conflicting_actors(p, together, 2).all()
    # same range and angle but 10 Doppler bins apart: resolved, no conflict
    moving = point_targets([40.0, 40.0], [10.0, 10.0], [2.0, 2.0 + 10 * p.speed_resolution_mps])
    assert not conflicting_actors(p, moving, 2).any()


@pytest.mark.parametrize("preset", ["ars408_like", "mimo12"])
def test_extended_actors_spread_across_the_beam_within_one_resolution_cell(preset):
    # one actor's reflectors at one range and speed, spread in d·sinθ by just below, at, above and twice
    # GLINT_SPAN_BEAMS beams: extended from the limit on; the same spread over ranges the chain resolves is not
    p = PRESETS[preset]
    beam = 1.0 / p.num_virtual
    r0 = 40.3 * p.range_resolution_m        # inside one cell of the grid, wherever it starts
    for span, extended in ((0.95, False), (1.001, True), (1.2, True), (2.0, True)):
        u = np.array([0.1, 0.1 + span * GLINT_SPAN_BEAMS * beam])
        az = np.degrees(np.arcsin(u / p.element_spacing_wl))
        scat = point_targets([r0, r0], az, [5.0, 5.0])
        scat.actor_index[:] = 0
        assert extended_actors(p, scat, 1)[0] == extended, span
        apart = point_targets([r0, r0 + 3.0 * p.range_resolution_m], az, [5.0, 5.0])
        apart.actor_index[:] = 0
        assert not extended_actors(p, apart, 1)[0]
        # two actors so placed are conflicting_actors' matter, not this
        two = point_targets([r0, r0], az, [5.0, 5.0])
        assert not extended_actors(p, two, 2).any()
    assert not extended_actors(p, point_targets([r0], [3.0], [5.0]), 1).any()     # one reflector


@pytest.mark.parametrize("name, actor, extended", [("bridge_90", "bridge", True), ("gantry_130", "gantry", True),
                                                   ("ncap_ccrs", "target", False), ("acc_follow_90", "lead", False)])
def test_auto_renders_a_deck_at_the_detection_level_and_a_car_ahead_at_the_object_level(name, actor, extended):
    # a structure across the road is 25–40 reflectors in one range cell over about a beam: the chain glints and
    # splits it (BENCHMARKS.md, "auto on every shipped scenario"); a car ahead is one point to it
    from radarnode.radar.setup import load_scenario
    sc = load_scenario(SCENARIOS / f"{name}.yaml")
    rc = radar_config(sc)
    model = AutoModel(Scene(sc), rc.preset, np.random.default_rng(0), rc.signal)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
    t = {"bridge_90": 6.0, "gantry_130": 4.0, "ncap_ccrs": 3.0, "acc_follow_90": 3.0}[name]
    model.step(t, cfg)
    assert (model.choices["detection"] == 1) == extended
    k = [a.id for a in sc.actors].index(actor)
    assert model.info.scatterers is not None and np.any(model.info.scatterers.actor_index == k)


def test_auto_counts_its_choices_and_uses_signal_for_impairments():
    import dataclasses
    sc = scenario(TRAFFIC, radar="{preset: mimo12}", duration=1.0)
    cfg = RuntimeConfig(max_distance_m=100.0, clusters=False)
    rc = radar_config(sc)
    model = AutoModel(Scene(sc), rc.preset, np.random.default_rng(0), rc.signal)
    for k in range(5):
        model.step(k * 0.072, cfg)
    # the truck in the next lane shows its side (long_actors): the detection level renders it, the car stays
    assert model.choices == {"object": 0, "detection": 5, "signal": 0}
    assert model.actor_frames == {"object": 5, "detection": 5}
    car = scenario(TRAFFIC.split("  - {id: b")[0], radar="{preset: mimo12}", duration=1.0)
    only_car = AutoModel(Scene(car), rc.preset, np.random.default_rng(0), rc.signal)
    for k in range(5):
        only_car.step(k * 0.072, cfg)
    assert only_car.choices["object"] == 5 and only_car.actor_frames == {"object": 5, "detection": 0}
    imp = dataclasses.replace(rc.signal, impairments=dataclasses.replace(rc.signal.impairments, adc_bits=10))
    model = AutoModel(Scene(sc), rc.preset, np.random.default_rng(0), imp)
    model.step(0.0, cfg)
    assert model.choices["signal"] == 1


def test_a_stated_snr_is_refused_at_the_object_level_and_auto_renders_every_actor_for_it(tmp_path, capsys):
    """signal.snr_db (every scatterer's per-sample SNR) was taken and ignored at the object level, the default, and
    by auto's object part: a lead at 40 m listed in 40 of 41 cycles at 61 dB, where the detection and signal levels
    at the stated −45 dB listed it in none (an independent tester's finding). The object level refuses it now, and
    auto renders every actor at the detection level; RF impairments, which only the signal level has, are refused
    at the object and detection levels likewise."""
    import dataclasses

    from radarnode.cli.main import main
    from radarnode.errors import ConfigError
    sc = scenario("  - {id: lead, class: car, x_m: 40.0, lane: 1, speed_mps: 20.0}", duration=2.0)
    rc = radar_config(sc)
    stated = dataclasses.replace(rc.signal, snr_db=-45.0)
    with pytest.raises(ConfigError, match="field 'signal.snr_db': value -45 is not allowed at fidelity 'object'"):
        make_model("object", Scene(sc), rc.preset, np.random.default_rng(0), stated)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
    listed = {}
    for level in ("auto", "detection"):
        model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(1), stated)
        listed[level] = sum(len(model.step(k * 0.072, cfg)[0].objects) for k in range(20))
        if level == "auto":
            assert model.choices == {"object": 0, "detection": 20, "signal": 0}
            assert model.actor_frames == {"object": 0, "detection": 20}
    assert listed == {"auto": 0, "detection": 0}            # −45 dB a sample: far below the threshold, at both
    # the same scene without it: auto at the object level, the lead listed
    model = make_model("auto", Scene(sc), rc.preset, np.random.default_rng(1), rc.signal)
    assert sum(len(model.step(k * 0.072, cfg)[0].objects) for k in range(20)) >= 15
    assert model.choices["object"] == 20
    imp = dataclasses.replace(rc.signal, impairments=dataclasses.replace(rc.signal.impairments, adc_bits=10))
    for level in ("object", "detection"):
        with pytest.raises(ConfigError, match=f"RF impairments are not allowed at fidelity '{level}'"):
            make_model(level, Scene(sc), rc.preset, np.random.default_rng(0), imp)
    # from a file: its line
    path = tmp_path / "snr.yaml"
    path.write_text("name: snr\nduration_s: 1.0\nseed: 1\nradar: {preset: ars408_like}\nego: {speed_mps: 20.0}\n"
                    "road: {lanes: 3, lane_width_m: 3.5, ego_lane: 1}\nsignal: {snr_db: -45}\nactors:\n"
                    "  - {id: lead, class: car, x_m: 40.0, lane: 1, speed_mps: 20.0}\n")
    capsys.readouterr()
    assert main(["log", str(path), "-o", str(tmp_path / "x.asc")]) == 1
    err = capsys.readouterr().err
    assert f"{path}:7: field 'signal.snr_db': value -45 is not allowed at fidelity 'object'" in err, err
    assert not (tmp_path / "x.asc").exists()
    assert main(["log", str(path), "-o", str(tmp_path / "x.asc"), "--fidelity", "detection"]) == 0


def _auto_and(level, text, radar, frames, seed=3, ego="{speed_mps: 0.0}"):
    """Run ``auto`` and ``level`` on the same scene: per level the model and, per frame, (frame, view, detections)."""
    sc = scenario(text, radar=radar, ego=ego, duration=frames * 0.072 + 1, seed=seed)
    cfg = RuntimeConfig(max_distance_m=radar_config(sc).preset.max_range_m, clusters=False)
    out = {}
    for name in ("auto", level):
        rc = radar_config(sc)
        model = make_model(name, Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal)
        rows = []
        for k in range(frames):
            frame, view = model.step(k * sc.period_s, cfg)
            rows.append((frame, view, model.info.detections))
        out[name] = (model, rows)
    return out


def test_auto_renders_two_pedestrians_side_by_side_as_the_chain_does():
    """0.45 m apart at 30 m: one peak for the chain; auto sends them through the detection level, which merges
    them, and reports one object as the signal level does."""
    text = """
  - {id: a, class: pedestrian, x_m: 30.0, y_m: 0.0, speed_mps: 0.0}
  - {id: b, class: pedestrian, x_m: 30.0, y_m: 0.45, speed_mps: 0.0}
"""
    out = _auto_and("signal", text, "{preset: mimo12}", 12)
    auto, rows = out["auto"]
    assert auto.choices["detection"] == 12 and auto.choices["object"] == 0
    near = [int(np.sum(np.abs(d.range_m - 30.0) < 1.0)) for _, _, d in rows]
    near_sig = [int(np.sum(np.abs(d.range_m - 30.0) < 1.0)) for _, _, d in out["signal"][1]]
    assert max(near) <= 1 and max(near_sig) <= 1
    assert len(rows[-1][0].objects) == len(out["signal"][1][-1][0].objects) == 1


def test_auto_switching_levels_keeps_ids_and_never_empties_a_frame():
    """Two cars side by side, then one pulls away: auto moves them from the detection to the object level
    mid-run; the one tracker keeps the IDs and reports objects in every frame after confirmation."""
    text = """
  - {id: a, class: car, x_m: 40.0, y_m: -1.2, speed_mps: 2.0}
  - {id: b, class: car, x_m: 40.0, y_m: 1.2, speed_mps: 2.0, accel: [{t_s: 1.5, accel_mps2: 2.0}]}
"""
    sc = scenario(text, radar="{preset: mimo12}", ego="{speed_mps: 0.0}", duration=6.0, seed=4)
    cfg = RuntimeConfig(max_distance_m=100.0, clusters=False)
    rc = radar_config(sc)
    model = AutoModel(Scene(sc), rc.preset, np.random.default_rng(4), rc.signal)
    levels, ids = [], []
    for k in range(70):
        frame, _ = model.step(k * sc.period_s, cfg)
        levels.append(model.info.level)
        ids.append(set(frame.objects.id.tolist()))
    assert "detection" in levels and "object" in levels                 # the switch happened
    first = next(i for i, s in enumerate(ids) if s)
    assert all(ids[i] for i in range(first, len(ids)))                  # never an empty frame
    switch = levels.index("object", levels.index("detection"))
    assert ids[switch - 1] <= ids[switch]                               # the IDs before survive the switch


def test_auto_renders_a_body_a_sector_s_edge_crosses_at_the_detection_level():
    """:func:`across_an_edge`: a car whose nearest point lies outside the field of view while part of it is inside
    (half in the beam at its edge), not one wholly inside, wholly outside, or a point at the edge."""
    from radarnode.radar.models import across_an_edge
    p = PRESETS["ars408_like"]
    edge = np.radians(max(s.half_angle_deg for s in p.fov if s.max_range_m >= 10.0))
    text = f"""
  - {{id: across, class: car, x_m: {3.7 + 10.0 * np.cos(edge) + 1.0:.3f}, y_m: {10.0 * np.sin(edge) + 0.5:.3f}, speed_mps: 0.0}}
  - {{id: inside, class: car, x_m: 33.7, y_m: 0.0, speed_mps: 0.0}}
  - {{id: behind, class: car, x_m: -20.0, y_m: 3.5, speed_mps: 0.0}}
  - {{id: point, class: point, x_m: {3.7 + 10.0 * np.cos(edge):.3f}, y_m: {10.0 * np.sin(edge) + 0.3:.3f}, speed_mps: 0.0}}
"""
    sc = scenario(text, ego="{speed_mps: 0.0}")
    view = Scene(sc).view(0.0)
    np.testing.assert_array_equal(across_an_edge(p, view, Scene(sc).length_m, Scene(sc).width_m),
                                  [True, False, False, False])


def test_auto_renders_a_body_wider_than_two_beams_at_the_detection_level():
    """:func:`wide_actors`: a car beside the ego seen by a corner radar spans more than two beamwidths, a car 30 m
    ahead of a front radar less than one; the threshold is the beams given."""
    from radarnode.radar.models import WIDE_BEAMS, wide_actors
    sc = scenario("  - {id: beside, class: car, x_m: 1.0, lane: 2, speed_mps: 25.0}\n"
                  "  - {id: ahead, class: car, x_m: 33.7, lane: 1, speed_mps: 25.0}",
                  radar="{preset: srr_corner, mount: {x_m: 3.5, y_m: 0.73, yaw_deg: 45.0}}", ego="{speed_mps: 25.0}")
    view = Scene(sc).view(0.0)
    p = PRESETS["srr_corner"]
    span = (view.az_hi_rad - view.az_lo_rad) / p.angular_resolution_rad
    assert span[0] > WIDE_BEAMS > 1.0 > span[1]
    np.testing.assert_array_equal(wide_actors(p, view), [True, False])
    np.testing.assert_array_equal(wide_actors(p, view, beams=float(span[0]) + 0.1), [False, False])


def test_wide_actors_counts_only_the_span_inside_the_field_of_view():
    """:func:`span_in_view`: a car behind a front radar (its corners' azimuths either side of ±180°: 356° between
    them) and cars beside it, outside its ±60° view, span nothing in view and are not wide; a truck close ahead is,
    by the part of it within the sector's reach; the same span for the corner radar's car beside it."""
    from radarnode.radar.models import span_in_view, wide_actors
    text = ("  - {id: behind, class: car, x_m: -20.0, lane: 1, speed_mps: 25.0}\n"
            "  - {id: beside, class: car, x_m: 1.0, lane: 2, speed_mps: 25.0}\n"
            "  - {id: beside_r, class: car, x_m: 1.0, lane: 0, speed_mps: 25.0}\n"
            "  - {id: close, class: truck, x_m: 12.0, lane: 1, speed_mps: 25.0}")
    sc = scenario(text, ego="{speed_mps: 25.0}")
    view = Scene(sc).view(0.0)
    p = PRESETS["ars408_like"]
    assert view.az_hi_rad[0] - view.az_lo_rad[0] > np.radians(350.0)         # the seam
    in_view = span_in_view(p, view)
    np.testing.assert_array_equal(in_view[:3], 0.0)
    assert in_view[3] == pytest.approx(view.az_hi_rad[3] - view.az_lo_rad[3])     # wholly inside
    np.testing.assert_array_equal(wide_actors(p, view), [False, False, False, True])
    # the near sector's ±60° reaches 20 m: the same truck 40 m ahead is in the ±45° one, and narrower
    far = Scene(scenario(text.replace("x_m: 12.0", "x_m: 40.0"), ego="{speed_mps: 25.0}")).view(0.0)
    assert 0.0 < span_in_view(p, far)[3] < 2.0 * p.angular_resolution_rad
    # a corner radar yawed 45°: the car beside it is in view (wide), the one behind and the one on the right are not
    corner = Scene(scenario(text, ego="{speed_mps: 25.0}",
                            radar="{preset: srr_corner, mount: {x_m: 3.5, y_m: 0.73, yaw_deg: 45.0}}")).view(0.0)
    pc = PRESETS["srr_corner"]
    np.testing.assert_array_equal(wide_actors(pc, corner)[:3], [False, True, False])
    half = np.radians(pc.fov[0].half_angle_deg)
    assert span_in_view(pc, corner)[1] == pytest.approx(min(corner.az_hi_rad[1], half) - corner.az_lo_rad[1])


def _ars408_scatterers(actors: str, ego_mps: float, t_s: float):
    """(``ars408_like``, the scatterers the detection level makes of ``actors`` at ``t_s``, the ego at ``ego_mps``)."""
    from radarnode.radar.scatterers import scene_scatterers
    scene = Scene(scenario(actors, ego=f"{{speed_mps: {ego_mps}}}"))
    p = PRESETS["ars408_like"]
    return p, scene_scatterers(scene, t_s, scene.view(t_s), p, p.max_range_m)


def test_long_actors_are_bodies_whose_reflectors_in_view_span_more_than_the_grouping_scale():
    """:func:`long_actors`: a truck in the next lane (its side in view: reflectors over 11 m of x) is long; a car
    there (4 m of x, 1.5 m across: a diameter just over 1 in the trackers' metric), a truck straight ahead in the
    ego's lane (its rear face only) and a truck wholly behind the sensor are not; the diameter is the one given."""
    from radarnode.radar.models import LONG_DIAMETER, long_actors
    p, scat = _ars408_scatterers("  - {id: truck, class: truck, x_m: 30.0, lane: 2, speed_mps: 22.0}\n"
                                 "  - {id: car, class: car, x_m: 30.0, lane: 0, speed_mps: 22.0}\n"
                                 "  - {id: ahead, class: truck, x_m: 60.0, lane: 1, speed_mps: 30.0}\n"
                                 "  - {id: behind, class: truck, x_m: -30.0, lane: 2, speed_mps: 30.0}", 30.0, 0.5)
    x = {a: scat.x_m[scat.actor_index == a] for a in range(4)}
    y = {a: scat.y_m[scat.actor_index == a] for a in range(4)}
    assert np.ptp(x[0]) > 2 * GROUP_EPS_LONG_M and np.ptp(x[1]) < GROUP_EPS_LONG_M
    assert 1.0 < np.hypot(np.ptp(x[1]) / GROUP_EPS_LONG_M, np.ptp(y[1]) / GROUP_EPS_M) < LONG_DIAMETER
    np.testing.assert_array_equal(long_actors(p, scat, 4), [True, False, False, False])
    truck = np.hypot(np.ptp(x[0]) / GROUP_EPS_LONG_M, np.ptp(y[0]) / GROUP_EPS_M)      # its bounding box's diagonal
    np.testing.assert_array_equal(long_actors(p, scat, 4, diameter=float(truck) + 0.01), [False] * 4)


#: two reflectors ``span`` apart in the trackers' metric: along x, along y, and on a diagonal (1.2 · 3/5 of the scale
#: along x, 1.2 · 4/5 along y: neither axis beyond its own scale)
DIRECTIONS = {"x": (1.0, 0.0), "y": (0.0, 1.0), "diagonal": (0.6, 0.8)}


@pytest.mark.parametrize("direction", list(DIRECTIONS))
@pytest.mark.parametrize("step, long", [(-0.001, False), (0.0, False), (0.001, True), (None, True)])
def test_long_actors_switches_just_above_its_diameter_counting_only_reflectors_in_view(direction, step, long):
    """:func:`long_actors` at its threshold: one actor's two reflectors in view (20 m ahead, 4 m to the side of a
    front radar, ``ars408_like``) apart by just below, at, just above and twice :data:`LONG_DIAMETER` in the
    trackers' metric, along x, along y or on a diagonal where neither axis reaches its own scale (a van on a bend)
    — long only above it. A third reflector of the same actor behind the sensor, 20 m further along, and one beyond
    the maximum range do not count; neither does a guardrail post (actor −1) in view 30 m away."""
    from radarnode.radar.models import LONG_DIAMETER, long_actors
    from radarnode.radar.scatterers import Scatterers
    p = PRESETS["ars408_like"]
    span = 2 * LONG_DIAMETER if step is None else LONG_DIAMETER * (1.0 + step)
    ux, uy = DIRECTIONS[direction]
    dx, dy = span * ux * GROUP_EPS_LONG_M, span * uy * GROUP_EPS_M
    x = np.array([20.0, 20.0 + dx, -5.0, p.max_range_m + 10.0, 50.0])
    y = np.array([4.0 - dy / 2, 4.0 + dy / 2, 20.0, 0.0, 0.0])
    if direction == "diagonal":
        assert dx < GROUP_EPS_LONG_M and dy < GROUP_EPS_M or step is None
    zeros = np.zeros_like(x)
    scat = Scatterers(x_m=x, y_m=y, z_m=zeros, vx_mps=zeros, vy_mps=zeros, rcs_dbsm=zeros + 10.0,
                      actor_index=np.array([0, 0, 0, 0, -1]))
    np.testing.assert_array_equal(long_actors(p, scat, 2), [long, False])
    # the same with the first reflector out of view: one reflector in view spans nothing
    scat.x_m[0] = -5.0
    np.testing.assert_array_equal(long_actors(p, scat, 2), [False, False])


def test_long_actors_takes_a_truck_crossing_in_front_and_leaves_a_car_seen_from_behind():
    """:func:`long_actors` across the line of sight: a truck crossing 26 m ahead, 10 m to the right (its side broadside, reflectors
    over more than twice GROUP_EPS_M of y) is long; a car in the next lane and a truck straight ahead in the ego's
    lane (seen from behind: 1.8 and 2.5 m wide) are not."""
    from radarnode.radar.models import long_actors
    # at 1 s the crossing truck is 10 m to the right: the others in sight
    p, scat = _ars408_scatterers("  - {id: cross, class: truck, waypoints: [{t_s: 0.0, x_m: 26.0, y_m: -20.0}, "
                                 "{t_s: 4.0, x_m: 26.0, y_m: 20.0}]}\n"
                                 "  - {id: car, class: car, x_m: 60.0, lane: 2, speed_mps: 20.0}\n"
                                 "  - {id: truck, class: truck, x_m: 90.0, lane: 1, speed_mps: 20.0}", 0.0, 1.0)
    x = {a: scat.x_m[scat.actor_index == a] for a in range(3)}
    y = {a: scat.y_m[scat.actor_index == a] for a in range(3)}
    assert np.ptp(y[0]) > 2 * GROUP_EPS_M and np.ptp(y[1]) < GROUP_EPS_M and np.ptp(y[2]) < GROUP_EPS_M
    np.testing.assert_array_equal(long_actors(p, scat, 3), [True, False, False])
    cross = np.hypot(np.ptp(x[0]) / GROUP_EPS_LONG_M, np.ptp(y[0]) / GROUP_EPS_M)
    np.testing.assert_array_equal(long_actors(p, scat, 3, diameter=float(cross) + 0.01), [False] * 3)


def test_long_actors_is_the_largest_distance_between_two_reflectors_in_view():
    """:func:`long_actors` against every pair of each actor's reflectors in view, counted here one actor at a time:
    random bodies 0.5–7 m across around the threshold (most between its box's longer side and its diagonal, where
    it takes the pairs), posts among them, at three diameters. An actor index at or beyond ``n_actors`` is refused
    by name."""
    from radarnode.radar.models import long_actors
    from radarnode.radar.object_model import in_fov
    from radarnode.radar.scatterers import Scatterers
    p = PRESETS["ars408_like"]
    rng = np.random.default_rng(7)
    between = 0
    for _ in range(300):
        m, n = int(rng.integers(0, 60)), int(rng.integers(1, 8))
        a = rng.integers(-1, n, m)
        k = np.maximum(a, 0)
        cx, cy, ext = rng.uniform(5, 60, n), rng.uniform(-8, 8, n), rng.uniform(0.5, 7, n)
        x = np.where(a >= 0, cx[k] + rng.uniform(-0.5, 0.5, m) * ext[k], rng.uniform(1, 60, m))
        y = np.where(a >= 0, cy[k] + rng.uniform(-0.3, 0.3, m) * ext[k], rng.uniform(-10, 10, m))
        z = np.zeros(m)
        scat = Scatterers(x_m=x, y_m=y, z_m=z, vx_mps=z, vy_mps=z, rcs_dbsm=z, actor_index=a)
        seen = in_fov(p, scat.range_m, scat.azimuth_rad)
        widest = np.zeros(n)
        for b in range(n):
            u, v = x[(a == b) & seen] / GROUP_EPS_LONG_M, y[(a == b) & seen] / GROUP_EPS_M
            if u.size >= 2:
                widest[b] = np.sqrt(((u[:, None] - u) ** 2 + (v[:, None] - v) ** 2).max())
                between += max(np.ptp(u), np.ptp(v)) <= 1.2 < np.hypot(np.ptp(u), np.ptp(v))
        for d in (0.5, 1.2, 3.0):
            np.testing.assert_array_equal(long_actors(p, scat, n, diameter=d), widest > d)
    assert between > 50
    z = np.zeros(2)
    bad = Scatterers(x_m=z + 10.0, y_m=z, z_m=z, vx_mps=z, vy_mps=z, rcs_dbsm=z, actor_index=np.array([0, 3]))
    with pytest.raises(ValueError, match="actor_index holds 3, not below n_actors = 2"):
        long_actors(p, bad, 2)


@pytest.mark.parametrize("length, long", [(5.05, False), (5.2, False), (5.6, True)])
def test_long_actors_leaves_a_body_just_over_five_metres_in_the_next_lane_to_the_object_level(length, long):
    """A body 20 m ahead in the next lane, its side seen edge-on (``ars408_like``): 5.05 m long its reflectors span
    4.6 m of x and 1.5 m across (1.16 in the trackers' metric), and the detection level listed it once in every
    cycle (an independent tester's scene, seeds 1–8); the axis-by-axis rule before rendered it at the detection level
    in every cycle for nothing. 5.6 m long (1.26) it is long, as a 5.5-m van there (1.24), which the detection level
    split in up to 6 % of its cycles (``benchmarks/long_bodies.py``)."""
    from radarnode.radar.models import long_actors
    p, scat = _ars408_scatterers(f"  - {{id: v, class: car, length_m: {length}, width_m: 2.0, x_m: 23.7, lane: 2, "
                                 "speed_mps: 25.0}", 25.0, 0.0)
    x, y = scat.x_m[scat.actor_index == 0], scat.y_m[scat.actor_index == 0]
    assert (np.ptp(x) > GROUP_EPS_LONG_M) == (length > 5.0)
    assert long_actors(p, scat, 1)[0] == long


#: the truck of :func:`_split_cycles`: overtaken in the next lane (the ego at 30 m/s, the truck at 22 m/s from 30 m
#: ahead), crossing 30 m ahead of a standing ego at 10 m/s (an independent tester's scene), or crossing at 45°
#: from 25 m ahead, 15 m to the right, to 55 m ahead, 15 m to the left (its side and its front both seen); and a
#: 5.1-m SUV 50 m ahead of the ego in its lane on a bend of 250 m radius, both at 25 m/s (its reflectors 4.5 m apart
#: along x and 2.4 m across: neither axis beyond its scale, 1.27 in the trackers' metric; an independent tester's scene)
TRUCKS = {"alongside": ("  - {id: truck, class: truck, x_m: 30.0, lane: 2, speed_mps: 22.0}", 30.0, 6.0, None),
          "crossing": ("  - {id: truck, class: truck, waypoints: [{t_s: 0.0, x_m: 30.0, y_m: -20.0}, "
                       "{t_s: 4.0, x_m: 30.0, y_m: 20.0}]}", 0.0, 4.0, None),
          "diagonal": ("  - {id: truck, class: truck, waypoints: [{t_s: 0.0, x_m: 25.0, y_m: -15.0}, "
                       "{t_s: 4.0, x_m: 55.0, y_m: 15.0}]}", 0.0, 4.0, None),
          "suv_on_bend": ("  - {id: suv, class: car, length_m: 5.1, width_m: 1.95, x_m: 50.0, lane: 1, speed_mps: 25.0}",
                          25.0, 6.0, "{lanes: 3, lane_width_m: 3.5, ego_lane: 1, curvature_1pm: 0.004}")}


def _split_cycles(level: str, seed: int, truck: str = "alongside") -> int:
    """The cycles with more than one object on a truck (its box grown by 1 m) of :data:`TRUCKS` (``ars408_like``)."""
    actor, ego, duration, road = TRUCKS[truck]
    kw = {} if road is None else {"road": road}
    sc = scenario(actor, ego=f"{{speed_mps: {ego}}}", duration=duration, seed=seed, **kw)
    rc = radar_config(sc)
    scene = Scene(sc)
    model = make_model(level, scene, rc.preset, np.random.default_rng(seed), rc.signal)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
    half_l, half_w = scene.length_m[0] / 2 + 1.0, scene.width_m[0] / 2 + 1.0
    split = 0
    for k in range(sc.num_cycles):
        frame, view = model.step(k * sc.period_s, cfg)
        ol = frame.objects
        c, s = np.cos(view.orientation_rad[0]), np.sin(view.orientation_rad[0])
        dx, dy = ol.dist_long_m - view.centre_x_m[0], ol.dist_lat_m - view.centre_y_m[0]
        on = (np.abs(c * dx + s * dy) <= half_l) & (np.abs(-s * dx + c * dy) <= half_w)
        split += int(on.sum() > 1)
    return split


@pytest.mark.parametrize("truck", list(TRUCKS))
def test_auto_splits_a_truck_whose_side_it_sees_as_the_detection_level_does(truck):
    """The chain lists a truck whose side it sees as two objects (its nearest corner and the strongest reflector of
    its side, 4–8 m along it) wherever those lie more than the trackers' grouping scale apart: alongside, 12–29 of
    83 cycles at the detection and signal levels in seeds 1–4, crossing, 190 and 215 of 216; never at the object
    level (one point per actor), and by auto in 4 of seeds 1–2 alongside, never crossing, before it rendered such a
    body at the detection level (:func:`long_actors` along x, then across: independent testers' findings); at 45°,
    100 of 110 cycles at the detection level and 99 by auto in seeds 1–2. The SUV on a bend: 24 of 166 at the
    detection level, by auto in none while it tested each axis alone, 29 since it measures the diameter in the
    trackers' metric. Seeds 1–2 together: auto within a factor 1.5 of the detection level, the object level none."""
    det = sum(_split_cycles("detection", s, truck) for s in (1, 2))
    auto = sum(_split_cycles("auto", s, truck) for s in (1, 2))
    assert _split_cycles("object", 1, truck) == 0
    assert det >= 20 and det / 1.5 <= auto <= det * 1.5, (det, auto)


def _objects_near_the_first_actor(sc, seed: int) -> tuple[int, int]:
    """``auto`` over the whole scenario: the cycles with an object within 6 m of the first actor's nearest point, and
    those with more than one."""
    rc = radar_config(sc)
    model = AutoModel(Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
    doubled = seen = 0
    for k in range(sc.num_cycles):
        frame, view = model.step(k * sc.period_s, cfg)
        ol = frame.objects
        near = np.hypot(ol.dist_long_m - view.x_m[0], ol.dist_lat_m - view.y_m[0]) < 6.0
        doubled += int(near.sum() > 1)
        seen += int(near.any())
    return seen, doubled


@pytest.mark.parametrize("seed", [1, 2])
def test_auto_lists_one_object_of_a_car_overtaking_beside_a_corner_radar(seed):
    """The left corner radar of front_and_corners.yaml (srr_corner yawed 45°), a car overtaking from 12 m behind at
    30 m/s against the ego's 25 m/s (an independent tester's scene): the object level's one point of the car beside
    the radar carries a radial speed near zero, and tracks started on it at the standing world's speed drifted off
    it by a metre a cycle: auto listed two objects of it in 7–16 of about 70 cycles (the signal level in none, the
    detection level in 2). Rendered at the detection level while it spans more than two beams: as the detection
    level, at most 2."""
    sc = scenario("  - {id: passer, class: car, x_m: -12.0, lane: 2, speed_mps: 30.0}", ego="{speed_mps: 25.0}",
                  radar="{preset: srr_corner, mount: {x_m: 3.5, y_m: 0.73, yaw_deg: 45.0}}", duration=6.0, seed=seed)
    seen, doubled = _objects_near_the_first_actor(sc, seed)
    assert seen > 50 and doubled <= 2, (seen, doubled)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_auto_lists_one_object_of_a_car_overtaking_into_the_view(seed):
    """The ego at 25 m/s, a car passing at 30 m/s from 12 m behind in the next lane (an independent tester's
    scene): as it came into view auto switched it between the object level (its point on the sector's edge, sliding
    along it: a track with a lateral speed of 12 m/s) and the detection level (its outline's inner points) and
    listed a second object of it in 1–2 cycles of each of seeds 1–6. Rendered at the detection level while the edge
    crosses it, never more than one object within 6 m of it, as at either level alone."""
    sc = scenario("  - {id: passer, class: car, x_m: -12.0, lane: 2, speed_mps: 30.0}", ego="{speed_mps: 25.0}",
                  duration=6.0, seed=seed)
    seen, doubled = _objects_near_the_first_actor(sc, seed)
    assert seen > 30 and doubled == 0, (seen, doubled)


def test_auto_pedestrian_near_the_range_limit_is_detected_as_often_as_at_signal_level():
    """A pedestrian at 92 m on mimo12, near the threshold: auto (object level here) and the signal level detect
    it with the same law, so their detection rates agree within sampling error."""
    text = "  - {id: p, class: pedestrian, x_m: 92.0, y_m: 0.0, speed_mps: 0.0}"
    frames = 150
    out = _auto_and("signal", text, "{preset: mimo12}", frames)
    rate = {}
    for name, (_, rows) in out.items():
        rate[name] = np.mean([bool(np.any(np.abs(d.range_m - v.range_m[0]) < 1.0)) for _, v, d in rows])
    assert out["auto"][0].choices["object"] == frames
    assert 0.05 < rate["signal"] < 0.95                                  # the interesting regime
    assert abs(rate["auto"] - rate["signal"]) < 3 * np.sqrt(0.25 / frames) * np.sqrt(2) + 0.05


def test_signal_options_in_scenario_files_are_validated(tmp_path):
    from radarnode.errors import ScenarioError
    from radarnode.radar.setup import load_scenario
    base = (SCENARIOS / "highway_mimo12.yaml").read_text()
    for bad, fragment in [
        ("signal: {dtype: complex32}", "signal.dtype"),
        ("signal: {domain: frequency}", "signal.domain"),
        ("signal: {impairments: {adc_bits: 40}}", "signal.impairments.adc_bits"),
        ("signal: {dsp: {cfar: gocfar}}", "signal.dsp.cfar"),
        ("signal: {scatterer_spacing_m: .nan}", "signal.scatterer_spacing_m"),
        ("signal: {colour: 1}", "unknown field 'signal.colour'"),
        ("fidelity: raytrace", "fidelity"),
    ]:
        key = bad.split(":")[0]
        lines = [ln for ln in base.splitlines() if not ln.startswith(key + ":")]
        path = tmp_path / "s.yaml"
        path.write_text("\n".join(lines) + "\n" + bad + "\n")
        with pytest.raises(ScenarioError, match=fragment):
            load_scenario(path)


@pytest.mark.slow      # (about 40 s: 12 seeds at two levels; on request, pytest -m slow; benchmarks/auto.py's row)
def test_auto_on_a_curve_entry_beside_guardrail_posts_reports_the_car_as_the_detection_level_does():
    """clothoid_stopped_own_lane: the stopped car 127 m ahead stands within the chain's resolution of the guardrail
    posts (8 channels: ~30 m of cross range there), so auto renders it at the detection level in every cycle and
    must report it as that level does. One seed is not enough to judge (a seed's fraction ranges from 0.2 to 1.0 at
    every level, the signal level's too, so a mean over 12 seeds still moves by about ±0.05): over seeds 1–12 the
    reported fractions agree (measured with the range–Doppler lobe test: detection 0.82, auto 0.86, the signal
    level 0.91; before it 0.88, 0.95 and 0.91)."""
    from radarnode.radar.setup import load_scenario
    from radarnode.radar.object_model import in_fov
    import dataclasses
    base = load_scenario(SCENARIOS / "clothoid_stopped_own_lane.yaml")
    reported = {"detection": [], "auto": []}
    for seed in range(1, 13):
        sc = dataclasses.replace(base, seed=seed)
        rc = radar_config(sc)
        cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
        for level in reported:
            scene = Scene(sc)
            car = int(np.flatnonzero(~scene.is_guardrail)[0])
            model = make_model(level, scene, rc.preset, np.random.default_rng(seed), rc.signal)
            hits = []
            for k in range(40):
                frame, view = model.step(k * sc.period_s, cfg)
                if k >= 5 and in_fov(rc.preset, view.range_m[car:car + 1], view.azimuth_rad[car:car + 1])[0]:
                    ol = frame.objects
                    d = np.hypot(ol.dist_long_m - view.x_m[car], ol.dist_lat_m - view.y_m[car])
                    hits.append(bool(d.size and d.min() <= 2.5))
            reported[level].append(np.mean(hits))
            if level == "auto":
                assert model.actor_frames["object"] == 0           # the car at the detection level throughout
    assert np.mean(reported["detection"]) > 0.7
    assert abs(np.mean(reported["auto"]) - np.mean(reported["detection"])) < 0.15


@pytest.mark.slow          # (about 2 min: 24 seeds of the signal chain; on request, pytest -m slow)
def test_cars_side_by_side_at_close_range_are_reported_by_the_detection_level_as_the_chain_reports_them():
    """Three cars at close range in 3.5 m lanes (a jam). The chain (signal level) loses the cars ahead in the beside
    car's range–Doppler lobe in some cycles: 0.74 / 0.62 / 0.91 of the cycles over these seeds. The detection level
    hides a weaker cell in stronger ones' lobes at any angle as the chain's local-maximum test does (0.69 / 0.73 /
    0.90 over seeds 1–12, the chain 0.77 / 0.53 / 0.95; 0.94 / 0.87 / 0.92 without it). The object level does not model the lobe (README, known limits):
    it must not mask the cars ahead more than the detection level does (taken whole at its nearest point, the car
    beside had hidden them in 26 and 40 of 55 cycles). Rates are means over 24 seeds: one seed's varies by ±0.15, and
    a few detections changed in one cell of one frame move the tracker's hits of a car by up to 18 of 55 cycles (the
    chain's re-judgement of cells on three plane waves, 2026-11-30, changed 9 of 1,320 frames here, all close-range
    cells of the cars: car b 0.588 → 0.561 over 12 seeds, 0.645 → 0.564 over 4, every change in seed 3). Over 12
    seeds the detection and signal levels' difference for car b was 0.18 in seeds 1–12 and 0.00 in seeds 13–24 with
    the radar tracker's spread single groups (session 33; 0.14 and −0.05 before them): too noisy a measure, hence 24
    (then: detection 0.75 / 0.70 / 0.98, signal 0.76 / 0.61 / 0.97)."""
    from radarnode.radar.setup import parse_scenario
    sc = parse_scenario("""
name: side
duration_s: 4.0
seed: 1
radar: {preset: ars408_like}
ego: {speed_mps: 20.0}
road: {lanes: 3, lane_width_m: 3.5, ego_lane: 1}
actors:
  - {id: a, class: car, x_m: 14.0, lane: 1, speed_mps: 20.5}
  - {id: b, class: car, x_m: 14.0, lane: 2, speed_mps: 20.5}
  - {id: c, class: car, x_m: 8.0, lane: 0, speed_mps: 20.5}
""")
    rc = radar_config(sc)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
    rate = {}
    for level in ("object", "detection", "signal"):
        hits = np.zeros(3)
        for seed in range(1, 25):
            model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal)
            for k in range(sc.num_cycles):
                frame, v = model.step(k * sc.period_s, cfg)
                ol = frame.objects
                for i in range(3):
                    d = np.hypot(ol.dist_long_m - v.x_m[i], ol.dist_lat_m - v.y_m[i])
                    hits[i] += d.size > 0 and d.min() < 2.5
        rate[level] = hits / (24 * sc.num_cycles)
    assert np.all(np.abs(rate["detection"] - rate["signal"]) < 0.15), rate
    assert np.all(rate["object"] > 0.7) and np.all(rate["object"] > rate["detection"] - 0.1), rate


@pytest.mark.parametrize("yaw", [0.0, 45.0])
@pytest.mark.parametrize("level", ["object", "detection", "signal"])
def test_length_and_width_are_reported_along_the_moving_object_at_every_mount_yaw(level, yaw):
    """A corner radar turned 45° sees a car driving beside the ego at 45° to its axes: the ARS 408 reports length
    and width along the object, so it is a car of about 4.5 × 1.8 m, not a 4.4 × 4.6 m 'wide' object (which the
    sensor-axes spans gave at every level)."""
    sc = scenario("  - {id: a, class: car, x_m: 16.0, lane: 2, speed_mps: 18.0}\n",
                  radar=f"{{preset: srr_corner, mount: {{x_m: 3.5, y_m: 0.73, yaw_deg: {yaw}}}}}", duration=2.0)
    node = RadarNode(sc, fidelity=level)
    outs = []
    run_node(node, clock=SimulatedClock(), sinks=[lambda m: None], on_cycle=outs.append,
             vehicle=EgoMotionSender(node.scene))
    length, width, cls = [], [], []
    for o in outs[10:]:      # once the track's velocity, hence its heading, is known (0.7 s)
        ol = o.frame.objects
        k = np.flatnonzero(ol.actor_index == 0)
        if k.size:
            length.append(ol.length_m[k[0]])
            width.append(ol.width_m[k[0]])
            cls.append(int(ol.obj_class[k[0]]))
    assert len(cls) >= 20
    assert np.mean(np.array(cls) == 1) >= 0.9, np.bincount(cls, minlength=7)          # 1: car, 6: wide
    assert 3.5 <= np.median(length) <= 5.5 and np.median(width) <= 2.5, (np.median(length), np.median(width))


def test_false_alarms_a_frame_agree_across_the_levels_at_a_high_pfa():
    """Noise only, Pfa 1e-3 on mimo12: the chain reports one false alarm per clump of neighbouring exceedances, 0.85
    of Pfa × cells here; the detection and object levels drew 1.0 of it (1.2× the chain's) and the object level over
    the reported area instead of the map (1.4×; independent tester's findings). Now all three within 12 % (the
    counts' own spread about 3 %; ``benchmarks/false_alarms.py`` for the curve)."""
    sc = scenario("", ego="{speed_mps: 0.0}", radar="{preset: mimo12}", road="{lanes: 1, ego_lane: 0}",
                  duration=20.0, seed=7, extra="signal: {dsp: {pfa: 1.0e-3}}")
    cfg = radar_config(sc)
    run = RuntimeConfig(max_distance_m=cfg.preset.max_range_m, clusters=True)
    n = {}
    for level in ("object", "detection", "signal"):
        model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(7), cfg.signal, clusters_wanted=True)
        frames = 40 if level == "signal" else 160
        n[level] = np.mean([len(model.step(0.072 * k, run)[0].clusters) for k in range(frames)])
    assert abs(n["detection"] / n["signal"] - 1.0) < 0.12 and abs(n["object"] / n["signal"] - 1.0) < 0.12, n


@pytest.mark.parametrize("yaw", [0.0, -50.0])
@pytest.mark.parametrize("level", ["object", "detection"])
def test_a_clusters_velocity_is_its_range_rate_along_its_azimuth_at_every_level(level, yaw):
    """A cluster is one detection, which measures one radial speed: its VrelLong/VrelLat are that speed split along
    its azimuth, as the ARS 408 and the detection and signal levels give them. The object level gave clusters the
    actor's whole relative velocity (a standing point 15 m out at 40°, ego at 25 m/s: VrelLong −25.25 against
    −14.7 at the other levels; an independent tester's finding)."""
    import math
    th = math.radians(yaw + 40.0)
    x, y = 3.7 + 15.0 * math.cos(th), -0.8 + 15.0 * math.sin(th)
    sc = scenario(f"  - {{id: p, class: point, x_m: {x:.3f}, y_m: {y:.3f}, speed_mps: 0, rcs_dbsm: 10}}\n",
                  ego="{speed_mps: 25.0}", duration=1.0,
                  radar=f"{{preset: ars408_like, output: clusters, mount: {{x_m: 3.7, y_m: -0.8, yaw_deg: {yaw}}}}}",
                  road="{lanes: 10, lane_width_m: 6, ego_lane: 5}")
    cfg = radar_config(sc)
    model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(3), cfg.signal, clusters_wanted=True)
    run = RuntimeConfig(max_distance_m=cfg.preset.max_range_m, clusters=True)
    seen = 0
    for k in range(6):
        cl = model.step(k * sc.period_s, run)[0].clusters
        mine = np.flatnonzero(cl.actor_index == 0)
        for i in mine:
            seen += 1
            az = math.atan2(cl.dist_lat_m[i], cl.dist_long_m[i])
            rate = cl.vrel_long_mps[i] * math.cos(az) + cl.vrel_lat_mps[i] * math.sin(az)
            # no tangential part, and the radial part is the standing point's (−25 m/s·cos of its azimuth off the
            # ego's axis), within the measurement's noise
            assert abs(-cl.vrel_long_mps[i] * math.sin(az) + cl.vrel_lat_mps[i] * math.cos(az)) < 1e-6, (level, i)
            assert abs(rate + 25.0 * math.cos(az + math.radians(yaw))) < 0.5, (level, rate)
    assert seen >= 4


_TRUCK_AND_PEDESTRIANS = """
name: mask_gap
duration_s: 4.0
seed: 1
radar: {preset: ars408_like}
ego: {speed_mps: 0.0}
road: {lanes: 3, lane_width_m: 3.5, ego_lane: 1}
actors:
  - {id: truck, class: truck, x_m: 30.0, y_m: 0.0, speed_mps: 0.0, rcs_dbsm: 35.0}
  - {id: ped1, class: pedestrian, x_m: 37.0, y_m: 4.5, speed_mps: 0.0}
%s
"""
_BIKE_BY_THE_POSTS = """
name: posts_ring
duration_s: 4.0
seed: 1
radar: {preset: ars408_like}
ego: {speed_mps: 0.0}
road: {lanes: 2, lane_width_m: 3.5, ego_lane: 0%s}
actors:
  - {id: bike, class: bicycle, x_m: 30.0, y_m: 1.0, speed_mps: 1.7}
"""


def _reported(text: str, level: str, seeds=(1, 2, 3)) -> np.ndarray:
    """Per actor, the share of cycles (from the fifth on) with an object within 2.5 m of its visible point."""
    from radarnode.radar.setup import parse_scenario
    sc = parse_scenario(text)
    rc = radar_config(sc)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
    hits, count = np.zeros(len(sc.actors)), 0
    for seed in seeds:
        model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal)
        for k in range(sc.num_cycles):
            frame, v = model.step(k * sc.period_s, cfg)
            if k < 5:
                continue
            ol, count = frame.objects, count + 1
            for i in range(len(sc.actors)):
                hits[i] += ol.dist_long_m.size > 0 and np.hypot(ol.dist_long_m - v.x_m[i],
                                                                ol.dist_lat_m - v.y_m[i]).min() < 2.5
    return hits / count


@pytest.mark.parametrize("second", ["  - {id: ped2, class: pedestrian, x_m: 37.5, y_m: -4.5, speed_mps: 0.0}", ""])
def test_auto_renders_what_is_in_a_rendered_actors_cfar_ring(second):
    """A standing truck (35 dBsm) 7 range bins before two standing pedestrians, the ego standing: the chain loses the
    pedestrians in the truck's CA-CFAR training ring (10 range bins, 6 Doppler bins; every level: 0 of the cycles).
    `auto` rendered the pedestrians (within 4 bins of each other) at the detection level without the truck (at the
    object level, 7 bins away), and reported them in every cycle (an independent tester's finding). Now the truck's
    reflectors in their ring come along for their energy; with one pedestrian both stay at the object level, whose
    masking counts every actor."""
    text = _TRUCK_AND_PEDESTRIANS % second
    auto, detection = _reported(text, "auto"), _reported(text, "detection")
    assert auto[0] > 0.95 and np.all(auto[1:] < 0.05) and np.all(detection[1:] < 0.05), (auto, detection)


@pytest.mark.parametrize("rails, masked", [(", guardrails: {left_offset_m: 0.5, right_offset_m: 0.5, post_spacing_m: 2.0, "
                                            "rcs_dbsm: 10.0}", True), ("", False)])
def test_auto_renders_an_actor_with_posts_in_its_cfar_ring(rails, masked):
    """A bicycle riding away at 1.7 m/s, 5.6 Doppler bins off a guardrail's posts (the ego standing): the chain loses
    it in the posts' CA-CFAR training ring (signal level 0–0.23 of the cycles, detection level 0–0.18, seeds 1–3).
    `auto` kept it at the object level (4-bin reach), whose masking counts actors only, and reported it in every
    cycle; now an actor with posts or clutter in its ring goes to the detection level. The object level itself still
    reports it (README, known limits); without the rails every level does."""
    text = _BIKE_BY_THE_POSTS % rails
    auto, detection, obj = _reported(text, "auto"), _reported(text, "detection"), _reported(text, "object")
    if masked:
        assert auto[0] < 0.3 and detection[0] < 0.3 and obj[0] > 0.95, (auto, detection, obj)
    else:
        assert auto[0] > 0.95 and detection[0] > 0.95, (auto, detection)


@pytest.mark.parametrize("field, value", [("max_distance_m", float("nan")), ("max_distance_m", float("inf")),
                                          ("max_distance_m", -5.0), ("max_distance_m", 0.0),
                                          ("power_reduction_db", float("inf")), ("power_reduction_db", float("nan")),
                                          ("power_reduction_db", -3.0), ("high_sensitivity", 1), ("clusters", "yes")])
def test_a_runtime_configuration_out_of_range_is_refused_by_name(field, value):
    """A NaN MaxDistance emptied the object level's lists silently and failed deep in numpy at the detection level
    ("negative dimensions are not allowed"); −5 m emptied every level's; an infinite power reduction gave the object
    level nothing with eleven RuntimeWarnings where the detection level refused it (an independent tester's finding).
    Each is refused where it is made, naming the field, the value and what is allowed; the edges pass (10 m, 0 dB)."""
    kw = {"max_distance_m": 250.0, field: value}
    with pytest.raises(ConfigError) as info:
        RuntimeConfig(**kw)
    assert f"RuntimeConfig.{field}" in str(info.value) and repr(value) in str(info.value)
    RuntimeConfig(max_distance_m=10.0, power_reduction_db=0.0, high_sensitivity=False, clusters=True)


@pytest.mark.parametrize("level", ["object", "detection", "signal", "auto"])
@pytest.mark.parametrize("t_s, sv, name", [(float("nan"), None, "t_s"), (float("inf"), None, "t_s"),
                                           (0.0, (float("nan"), 0.0), "sensor_velocity_est"),
                                           (0.0, (float("inf"), 0.0), "sensor_velocity_est"),
                                           (0.0, (20.0, 0.0, float("nan")), "sensor_velocity_est"),
                                           (0.0, (20.0,), "sensor_velocity_est")])
def test_a_step_at_a_non_finite_time_or_velocity_is_refused_by_name(level, t_s, sv, name):
    """``step(nan)`` failed in numpy's integer conversion ("cannot convert float NaN to integer") at every level; a
    NaN or infinite ego-motion estimate gave a frame. Each level refuses both, naming the argument; the model steps
    on after the refusal."""
    sc = scenario("  - {id: car, class: car, x_m: 50.0, lane: 1, speed_mps: 15.0}", duration=1.0)
    cfg = radar_config(sc)
    model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(1), cfg.signal, clusters_wanted=True)
    with pytest.raises(ConfigError, match=name):
        model.step(t_s, RuntimeConfig(max_distance_m=250.0), sv)
    frame, _ = model.step(0.072, RuntimeConfig(max_distance_m=250.0), (20.0, 0.0))
    assert np.all(np.isfinite(frame.objects.dist_long_m))


#: a car 35 m ahead and a motorcycle 11 m behind it, ``dy`` across (an independent tester's scene)
def _shadow_scene(dy: float, preset: str):
    return scenario(f"  - {{id: car, class: car, x_m: 35.0, y_m: 0.0, speed_mps: 10.0}}\n"
                    f"  - {{id: moto, class: motorcycle, x_m: 46.0, y_m: {dy}, speed_mps: 10.0}}",
                    ego="{speed_mps: 10.0}", radar=f"{{preset: {preset}}}", duration=3.0, seed=1)


@pytest.mark.parametrize("dy, shadowed", [(0.5, False), (1.1, True), (1.3, True), (2.2, False)])
def test_shadowed_actors_are_those_another_hides_in_part(dy, shadowed):
    """:func:`shadowed_actors` at its two edges: the motorcycle wholly behind the car (visible fraction 0: no level
    sees it), partly (0.3 m and 0.5 m of its 0.8 m in view) and wholly clear; the car, nearest, never."""
    from radarnode.radar.models import shadowed_actors
    from radarnode.radar.object_model import visible_fraction
    sc = _shadow_scene(dy, "mimo12")
    scene = Scene(sc)
    p = radar_config(sc).preset
    view = scene.view(0.0)
    frac = visible_fraction(view.range_m, view.az_lo_rad, view.az_hi_rad, np.ones(2, dtype=bool))
    assert frac[0] == 1.0 and (0.0 < frac[1] < 1.0) == shadowed
    np.testing.assert_array_equal(shadowed_actors(p, scene, view, p.max_range_m), [False, shadowed])


@pytest.mark.parametrize("preset", ["mimo12", "ars408_like"])
def test_auto_renders_a_body_another_partly_hides_as_the_chain_does(preset):
    """A motorcycle 1.1 m across, 11 m behind a car, a sliver of it in view: the object level scales its RCS by the
    fraction seen and listed it in 35 (mimo12) or 17 (ars408_like) of 35 cycles, and so did ``auto``, which kept it
    there; the detection and signal levels, whose scatterers in view are none of the motorcycle's, in none (an
    independent tester's finding). ``auto`` now renders it at the detection level."""
    sc = _shadow_scene(1.1, preset)
    listed = {}
    for level in ("detection", "auto", "object"):
        cfg = radar_config(sc)
        model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(1), cfg.signal)
        seen = 0
        for k in range(40):
            frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
            ob = frame.objects
            if k >= 5:
                seen += int(np.any((np.abs(ob.dist_long_m - view.x_m[1]) < 3.0)     # its nearest point, 10 m
                                   & (np.abs(ob.dist_lat_m - view.y_m[1]) < 2.0)))  # beyond the car's
        listed[level] = seen
    assert listed["object"] >= 10
    assert listed["auto"] == listed["detection"] == 0
