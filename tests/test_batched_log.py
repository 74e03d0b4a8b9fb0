"""The batched paths against the cycle-by-cycle one: `radarnode log` writes the same frames either way.

The object level computes its physics, the guardrail posts and the lists' field tables for chunks of up to
``CHUNK_CYCLES`` cycles at once, the scene the ego's states for ``EGO_BLOCK`` cycles (issue 13 item 10, issue 9
item 7). With both 1 every cycle is computed on its own — the reference path. Each shipped scenario here is logged both ways and the logs must hold
the same frames, byte for byte and stamp for stamp: an object list with road boundaries (highway_cut_in), a
cluster list beside guardrails on a bend (guardrail_traffic), a closed loop with the consumer ECU on a bend
(acc_follow_bend_250, whose ego is computed one cycle at a time in both paths).
"""

from __future__ import annotations

from pathlib import Path

import can
import numpy as np
import pytest

from radarnode.cli.main import main

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
CASES = {
    "objects+boundaries": ["highway_cut_in.yaml", "--fidelity", "object", "--duration", "20"],
    "clusters+guardrails+bend": ["guardrail_traffic.yaml", "--fidelity", "object"],
    "closed loop+ecu+bend": ["acc_follow_bend_250.yaml", "--fidelity", "object", "--ecu", "--duration", "15"],
}


def _frames(path: Path) -> list[tuple[int, float, bytes]]:
    return [(m.arbitration_id, m.timestamp, bytes(m.data)) for m in can.BLFReader(str(path))]


@pytest.mark.parametrize("case", list(CASES))
def test_a_log_is_the_same_computed_in_chunks_and_cycle_by_cycle(case, tmp_path, monkeypatch, capsys):
    import radarnode.radar.object_model as om
    import radarnode.scene.world as world
    name, *args = CASES[case]
    batched, single = tmp_path / "batched.blf", tmp_path / "single.blf"
    assert main(["log", str(SCENARIOS / name), *args, "-o", str(batched)]) == 0
    monkeypatch.setattr(om, "CHUNK_CYCLES", 1)
    monkeypatch.setattr(world, "EGO_BLOCK", 1)
    assert main(["log", str(SCENARIOS / name), *args, "-o", str(single)]) == 0
    a, b = _frames(batched), _frames(single)
    assert len(a) > 100
    assert len(a) == len(b)
    for k, (x, y) in enumerate(zip(a, b)):
        assert x == y, f"frame {k}: {x} batched, {y} cycle by cycle"


@pytest.mark.parametrize("name", ["lane_change_to_stopped.yaml", "clothoid_stopped_own_lane.yaml", "acc_stop_and_go.yaml"])
def test_the_ego_on_the_cycle_grid_is_the_ego_computed_on_its_own(name):
    """Scene.ego_state takes a scripted ego's states on the cycle grid from blocks computed in one pass: each is
    the state computed for its time alone (a lane change, a clothoid, speed changes), and off the grid too."""
    from radarnode.radar.setup import load_scenario
    from radarnode.scene.world import EGO_BLOCK, EgoState, Scene
    sc = load_scenario(SCENARIOS / name)
    scene = Scene(sc)

    def alone(t):
        x, y, heading, _, _, speed, accel, yaw = scene._ego_pose(scene._ego.state(t))
        return EgoState(*(float(v[0]) for v in (x, y, heading, speed, accel, yaw)))

    for k in list(range(0, 2 * EGO_BLOCK + 3, 7)) + [EGO_BLOCK - 1, EGO_BLOCK]:
        t = k * sc.period_s
        assert scene.ego_state(t) == alone(t), k
    assert scene.ego_state(0.5 * sc.period_s) == alone(0.5 * sc.period_s)


def _node_frames(text: str, cycles: int, reconfigure_at: tuple[int, ...] = ()) -> list[tuple[int, bytes]]:
    """A node's frames over ``cycles`` cycles (simulated time, no vehicle), with MaxDistance changed by 0x200 before
    each cycle of ``reconfigure_at`` (alternately 120 m and back to 250 m). ``text``: the actors, or a shipped
    scenario's file name."""
    from radarnode.radar.setup import load_scenario
    from radarnode.wire import ars408 as P
    from radarnode.wire.dbc import load_database
    from radarnode.wire.node import RadarNode
    from tests.helpers import scenario
    db = load_database()
    msg = db.get_message_by_frame_id(P.RADAR_CFG)
    node = RadarNode(load_scenario(SCENARIOS / text) if text.endswith(".yaml") else
                     scenario(text, ego="{speed_mps: 25.0}", duration=cycles * 0.072 + 0.1))
    out = []
    for k in range(cycles):
        if k in reconfigure_at:
            values = {s.name: 0 for s in msg.signals}
            values.update(RadarCfg_MaxDistance_valid=1,
                          RadarCfg_MaxDistance=120 if reconfigure_at.index(k) % 2 == 0 else 250)
            node.receive(can.Message(arbitration_id=P.RADAR_CFG, data=msg.encode(values), is_extended_id=False),
                         k * node.period_s)
        out += [(m.arbitration_id, bytes(m.data)) for m in node.cycle(k * node.period_s).messages]
    return out


PASSING = """
  - {id: slow, class: car, x_m: 40.0, lane: 1, speed_mps: 15.0}
  - {id: fast, class: car, x_m: 60.0, lane: 2, speed_mps: 33.0}
  - {id: oncoming, class: car, x_m: 240.0, lane: 0, speed_mps: 20.0, heading_deg: 180.0}
"""


@pytest.mark.parametrize("scene", [PASSING, "bridge_stopped_car_50.yaml"], ids=["road", "bridge"])
def test_configuration_changes_restart_the_chunks_without_changing_a_frame(scene, monkeypatch):
    """A 0x200 that changes MaxDistance makes the object level compute a new chunk from that cycle (the chunks
    grow again from FIRST_CHUNK_CYCLES): the frames are those computed one cycle at a time. Under a bridge too,
    whose averaged elevation factor the tracker carries across the restart."""
    import radarnode.radar.object_model as om
    changes = (5, 40, 41, 60, 200)
    batched = _node_frames(scene, 260, changes)
    monkeypatch.setattr(om, "CHUNK_CYCLES", 1)
    single = _node_frames(scene, 260, changes)
    assert len(batched) == len(single) > 260
    assert batched == single


def _model_rows(steps: list[int], chunk: int | None, monkeypatch) -> list[np.ndarray]:
    """The object lists of highway_cut_in's object level stepped at the cycles ``steps`` (in that order)."""
    import radarnode.radar.object_model as om
    from radarnode.radar.setup import load_scenario, radar_config
    from radarnode.scene.world import Scene
    if chunk is not None:
        monkeypatch.setattr(om, "CHUNK_CYCLES", chunk)
    sc = load_scenario(SCENARIOS / "highway_cut_in.yaml")
    preset = radar_config(sc).preset
    model = om.ObjectModel(Scene(sc), preset, np.random.default_rng(sc.seed))
    model.planned_cycles = 208
    cfg = om.RuntimeConfig(max_distance_m=preset.max_range_m, clusters=True)
    out = []
    for k in steps:
        frame, _ = model.step(k * sc.period_s, cfg, (27.8, 0.0))
        ol = frame.objects
        out.append(np.concatenate([ol.id, ol.dist_long_m, ol.dist_lat_m, ol.vrel_long_mps, ol.vrel_lat_mps,
                                   ol.dyn_prop, ol.meas_state, [len(frame.clusters)]]))
    return out


@pytest.mark.parametrize("steps", [[*range(10), 12, 13, 14, *range(20, 60, 3)],     # cycles skipped, as when late
                                   [*range(150), 100, 101, 102, 3, 4],              # steps back, within and before
                                   [*range(20), 19, 19, 20, 21]],                    # a cycle repeated
                         ids=["skipped", "back", "repeated"])
def test_steps_off_the_sequence_give_what_the_cycle_by_cycle_tracker_gives(steps, monkeypatch):
    """A step that is not the chunk's next cycle starts a chunk there from the tracker's state after the last step,
    as the cycle-by-cycle tracker continues: the real-time runner skips the cycles it cannot compute in time, and a
    library user may step back (the draws of a block let go are drawn again from where it began)."""
    batched = _model_rows(steps, None, monkeypatch)
    single = _model_rows(steps, 1, monkeypatch)
    assert len(batched) == len(steps)
    for k, (a, b) in enumerate(zip(batched, single)):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12, err_msg=f"step {k} (cycle {steps[k]})")


def test_a_shorter_run_is_the_start_of_a_longer_one_at_every_level(tmp_path):
    """The object level's chunks end with the run (``planned_cycles``), so their schedule depends on its length; what
    they draw must not: ``auto``, which runs the object and detection levels side by side, gives a 1.5-s run's frames
    as the first of a 3-s run's."""
    logs = []
    for duration in ("1.5", "3"):
        out = tmp_path / f"auto_{duration}.blf"
        assert main(["log", str(SCENARIOS / "pedestrian_crossing.yaml"), "--fidelity", "auto", "--duration", duration,
                     "-o", str(out)]) == 0
        logs.append(_frames(out))
    short, long_ = logs
    assert 100 < len(short) < len(long_)
    assert long_[:len(short)] == short


def test_a_chunk_of_many_actors_is_short():
    """A chunk's cost grows with its cycles × actors: a real-time node computes it within one cycle, so a scene of
    40 cars gets chunks of at most CHUNK_ACTOR_CYCLES // 40 cycles."""
    import radarnode.radar.object_model as om
    from radarnode.radar.setup import radar_config
    from radarnode.scene.world import Scene
    from tests.helpers import scenario
    cars = "\n".join(f"  - {{id: c{i}, class: car, x_m: {20 + 6 * i}, lane: {i % 3}, speed_mps: 25.0}}"
                     for i in range(40))
    sc = scenario(cars, ego="{speed_mps: 25.0}", road="{lanes: 3, ego_lane: 1}", duration=60.0)
    preset = radar_config(sc).preset
    model = om.ObjectModel(Scene(sc), preset, np.random.default_rng(1))
    cfg = om.RuntimeConfig(max_distance_m=preset.max_range_m, clusters=False)
    sizes = set()
    for k in range(400):
        model.step(k * sc.period_s, cfg)
        sizes.add(model._cache["times"].size)
    assert max(sizes) == om.CHUNK_ACTOR_CYCLES // 40


@pytest.mark.parametrize("planned", [1023, 1024, 1025, 2048])
def test_a_run_starts_with_a_full_chunk_and_grows_again_only_after_a_restart(planned):
    """The chunks of a run of ``planned`` cycles, just below, at and just above CHUNK_CYCLES and at twice it: the
    first is full (the run's length bounds it), the next takes what is left up to CHUNK_CYCLES; a configuration
    change restarts at FIRST_CHUNK_CYCLES and grows CHUNK_GROWTH-fold while the configuration holds."""
    import dataclasses

    import radarnode.radar.object_model as om
    from radarnode.radar.setup import load_scenario, radar_config
    from radarnode.scene.world import Scene
    sc = load_scenario(SCENARIOS / "highway_cut_in.yaml")
    preset = radar_config(sc).preset
    model = om.ObjectModel(Scene(sc), preset, np.random.default_rng(1))
    model.planned_cycles = planned
    cfg = om.RuntimeConfig(max_distance_m=preset.max_range_m, clusters=False)
    starts = {}
    for k in range(planned):
        model.step(k * sc.period_s, cfg)
        starts.setdefault(model._cache["k0"], model._cache["times"].size)
    full = om.CHUNK_CYCLES
    assert starts == ({0: planned} if planned <= full else {0: full, full: min(planned - full, full)})
    # a 0x200 MaxDistance change restarts the chunks short and lets them grow
    model = om.ObjectModel(Scene(sc), preset, np.random.default_rng(1))
    model.planned_cycles = 2000
    near = dataclasses.replace(cfg, max_distance_m=150.0)
    starts = {}
    for k in range(2000):
        model.step(k * sc.period_s, cfg if k < 10 else near)
        starts.setdefault(model._cache["k0"], model._cache["times"].size)
    first, growth = om.FIRST_CHUNK_CYCLES, om.CHUNK_GROWTH
    grown = 10 + first + first * growth
    assert starts == {0: full, 10: first, 10 + first: first * growth, grown: full, grown + full: 2000 - grown - full}


def test_cycles_with_nothing_in_view_are_skipped_without_changing_a_frame(monkeypatch):
    """The object level computes its physics only at the cycles where some actor may be in a sector: here the slow
    car falls behind, the fast one drives out of range and the oncoming one passes, so most of the run has
    nothing in view. Computing every cycle gives the same frames."""
    import radarnode.radar.object_model as om
    seen = []
    original = om.ObjectModel._cycles_in_view

    def spy(self, truth):
        rows = original(self, truth)
        seen.append((rows.size, truth.t_s.size))
        return rows

    monkeypatch.setattr(om.ObjectModel, "_cycles_in_view", spy)
    skipped = _node_frames(PASSING, 700)
    assert sum(t - r for r, t in seen) > 300          # most cycles skipped
    monkeypatch.setattr(om.ObjectModel, "_cycles_in_view", lambda self, truth: np.arange(truth.t_s.size))
    every = _node_frames(PASSING, 700)
    assert len(skipped) == len(every) > 700
    assert skipped == every


def test_a_step_back_beyond_the_kept_random_state_is_refused(monkeypatch):
    """The object level keeps the random state where each of its last KEEP_DRAW_STATES blocks of draws began (a
    node running for days must not grow): a step back within them is drawn again, one beyond them is refused with
    a clear error, not a KeyError from inside."""
    import radarnode.radar.object_model as om
    monkeypatch.setattr(om, "KEEP_DRAW_STATES", 2)
    _model_rows([*range(5 * om.DRAW_BLOCK), 3 * om.DRAW_BLOCK + 1], None, monkeypatch)     # two blocks back: kept
    with pytest.raises(ValueError, match="cannot step back to cycle 10"):
        _model_rows([*range(5 * om.DRAW_BLOCK), 10], None, monkeypatch)


@pytest.mark.parametrize("name", sorted(p.name for p in SCENARIOS.glob("*.yaml")))
def test_the_movers_states_of_many_times_are_each_times_own(name):
    """MoverTable.state of an array of times finds each mover's knot by a binary search and gathers the knot's
    columns at once: every state is the one of its time alone (and the counting search's), for every shipped
    scenario's actors and ego, from before the start to beyond the end, at the knots' own times too (finite times:
    the state at an infinite time is NaN, as before)."""
    from radarnode.radar.setup import load_scenario
    from radarnode.scene.world import Scene
    sc = load_scenario(SCENARIOS / name)
    scene = Scene(sc)
    for table in (scene._movers, scene._ego):
        knots = table.t[np.isfinite(table.t)]
        t = np.concatenate([np.linspace(-1.0, sc.duration_s + 5.0, 257), knots])
        many = vars(table.state(t))
        for k in range(0, t.size, 7):
            alone = vars(table.state(float(t[k])))
            for field, value in alone.items():
                np.testing.assert_array_equal(many[field][k], value, err_msg=f"{field} at t={t[k]}")
        counted = table._sorted
        table._sorted = False                         # the counting search, (times, movers, knots) at once
        try:
            for field, value in vars(table.state(t)).items():
                np.testing.assert_array_equal(many[field], value, err_msg=field)
        finally:
            table._sorted = counted


def test_a_chunks_truth_row_is_a_sensor_view_filled_when_read():
    """The object level's step returns its cycle's truth as a row of the chunk's many-time view, whose arrays are
    indexed out when first read: every field the eager row's, and it prints, compares, copies, pickles and
    replaces as a SensorView does."""
    import copy
    import dataclasses
    import pickle

    from radarnode.scene.world import _VIEW_FIELDS, SensorView
    from radarnode.radar.setup import load_scenario
    from radarnode.scene.world import Scene
    sc = load_scenario(SCENARIOS / "highway_cut_in.yaml")
    scene = Scene(sc)
    times = np.arange(40) * sc.period_s
    many = scene.views(times)
    for k in (0, 17, 39):
        row = many.row(k)
        alone = scene.views(times[k:k + 1])
        assert isinstance(row, SensorView) and repr(row).startswith("SensorView(t_s=")
        for field in _VIEW_FIELDS:
            want = getattr(many, field)
            want = None if want is None else np.asarray(want)[k]
            np.testing.assert_array_equal(getattr(row, field), want, err_msg=field)
            if field not in ("t_s", "sensor_vx_mps", "sensor_vy_mps", "z_m"):
                np.testing.assert_array_equal(getattr(row, field), getattr(alone, field)[0], err_msg=field)
        assert row == copy.copy(row)
        back = pickle.loads(pickle.dumps(many.row(k)))
        assert type(back) is SensorView and np.array_equal(back.x_m, row.x_m)
        moved = dataclasses.replace(many.row(k), t_s=1.5)
        assert moved.t_s == 1.5 and np.array_equal(moved.vx_mps, row.vx_mps)
        with pytest.raises(AttributeError, match="no attribute 'nope'"):
            many.row(k).nope


def test_a_late_first_step_draws_the_cycles_it_skips_without_holding_them():
    """A first step far into a run draws the random numbers of every cycle before it (so that the generator stands
    where a run through them leaves it) but lets each skipped block go at once: a first step at 10⁶ s held 2.8 GB of
    them (an independent tester's finding). Its cycle's numbers are those of a run stepped up to it."""
    import tracemalloc

    import radarnode.radar.object_model as om
    from radarnode.radar.setup import load_scenario, radar_config
    from radarnode.scene.world import Scene
    sc = load_scenario(SCENARIOS / "highway_cut_in.yaml")
    preset = radar_config(sc).preset
    cfg = om.RuntimeConfig(max_distance_m=preset.max_range_m, clusters=False)
    peaks = {}
    for k in (1_000, 100_000):
        model = om.ObjectModel(Scene(sc), preset, np.random.default_rng(1))
        tracemalloc.start()
        try:
            model.step(k * sc.period_s, cfg)
            peaks[k] = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
    # 1,563 blocks skipped: ~38 MB held before; now their kept random states (KEEP_DRAW_STATES), under 1 MB
    assert peaks[100_000] < peaks[1_000] + 2e6, peaks
    late = om.ObjectModel(Scene(sc), preset, np.random.default_rng(1))
    walked = om.ObjectModel(Scene(sc), preset, np.random.default_rng(1))
    k = 5 * om.DRAW_BLOCK + 7
    for name, values in late._draws(k, 3).items():
        assert np.array_equal(values, walked._draws(0, k + 3)[name][k:])


@pytest.mark.parametrize("t_s", [1e12, -2e7, 1.0000001e7])
def test_a_step_beyond_the_longest_time_is_refused_at_every_level(t_s):
    """A step's time beyond ±MAX_STEP_TIME_S (about 116 days) is refused with the value and the limit, at every
    level: the object level draws every cycle's numbers up to it, and 10¹² s would have run for weeks."""
    import radarnode.radar.object_model as om
    from radarnode.errors import ConfigError
    from radarnode.radar.models import make_model
    from radarnode.radar.setup import load_scenario, radar_config
    from radarnode.scene.world import Scene
    sc = load_scenario(SCENARIOS / "highway_cut_in.yaml")
    rc = radar_config(sc)
    for level in ("object", "detection", "signal", "auto"):
        model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(1), rc.signal)
        with pytest.raises(ConfigError, match=rf"t_s: value {t_s!r} is not allowed; .*within ±1e\+07"):
            model.step(t_s, om.RuntimeConfig(max_distance_m=rc.preset.max_range_m))



@pytest.mark.parametrize("t_s", [9.999999e6, 1e7, -1e7])
def test_a_step_just_below_and_at_the_longest_time_is_taken(t_s):
    """Just below and at ±MAX_STEP_TIME_S a step is a step (at the detection level, which draws no cycle before it:
    the object level would draw 139 million cycles' numbers first, some 40 s)."""
    import radarnode.radar.object_model as om
    from radarnode.radar.models import make_model
    from radarnode.radar.setup import load_scenario, radar_config
    from radarnode.scene.world import Scene
    assert om.MAX_STEP_TIME_S == 1e7
    sc = load_scenario(SCENARIOS / "highway_cut_in.yaml")
    rc = radar_config(sc)
    model = make_model("detection", Scene(sc), rc.preset, np.random.default_rng(1), rc.signal)
    frame, view = model.step(t_s, om.RuntimeConfig(max_distance_m=rc.preset.max_range_m))
    assert frame.t_s == t_s and np.all(np.isfinite(view.x_m))
