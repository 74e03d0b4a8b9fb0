"""The road boundaries in a second process (``radarnode.wire.pipeline``): `radarnode log` writes the same frames as in
one process, whole cycles in order, at every batch size and edge, and an error or a lost process is an error.

The reference is the same command with the pipeline turned off (``pipeline_for`` returning None): the cycle-by-cycle
path every other command takes.
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import can
import numpy as np
import pytest
import yaml

import radarnode.cli.log as cli_log
import radarnode.wire.pipeline as pl
from radarnode.cli.main import main
from radarnode.radar.setup import load_scenario
from radarnode.wire.group import ego_motion_for, make_node
from radarnode.wire.runner import SimulatedClock, run_node

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ROOT / "scenarios"
CUT_IN = SCENARIOS / "highway_cut_in.yaml"
CYCLE_S = 0.072            # highway_cut_in's radar cycle

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the pipeline forks: Linux only")


def _frames(path: Path) -> list[tuple[int, float, bytes]]:
    return [(m.arbitration_id, m.timestamp, bytes(m.data)) for m in can.BLFReader(str(path))]


def _both(tmp_path: Path, monkeypatch, capsys, *args: str) -> tuple[list, list, str]:
    """The log of ``args`` with the pipeline and without: their frames, and what the piped run printed."""
    piped, single = tmp_path / "piped.blf", tmp_path / "single.blf"
    started = []
    real = cli_log.pipeline_for

    def spy(node, cycles=None):
        p = real(node)          # (at any length: the batch edges below MIN_CYCLES too)
        started.append(p)
        return p

    monkeypatch.setattr(cli_log, "pipeline_for", spy)
    assert main(["log", *args, "-o", str(piped)]) == 0
    err = capsys.readouterr().err
    assert started and started[0] is not None          # the pipeline ran
    monkeypatch.setattr(cli_log, "pipeline_for", lambda node, cycles=None: None)
    assert main(["log", *args, "-o", str(single)]) == 0
    capsys.readouterr()
    return _frames(piped), _frames(single), err


def _same(a: list, b: list) -> None:
    assert len(a) == len(b), (len(a), len(b))
    for k, (x, y) in enumerate(zip(a, b)):
        assert x == y, f"frame {k}: {x} piped, {y} in one process"


def _boundary_frames(frames: list) -> list:
    return [f for f in frames if f[0] in (0x680, 0x681)]


@pytest.mark.parametrize("cycles", [1, pl.BATCH - 1, pl.BATCH, pl.BATCH + 1, 2 * pl.BATCH,
                                    pl.BATCH * pl.MAX_IN_FLIGHT + 1])
def test_the_log_is_the_one_process_log_byte_for_byte_across_the_batch_edges(cycles, tmp_path, monkeypatch, capsys):
    """One cycle, a batch less one, a batch, one more, two, and more than the batches allowed in flight: the same
    frames, stamps and bytes, and the boundary frames are the estimator's (valid ones among them, filled in)."""
    a, b, err = _both(tmp_path, monkeypatch, capsys, str(CUT_IN), "--fidelity", "object",
                      "--duration", f"{cycles * CYCLE_S + 0.001:.3f}")
    assert f"in {cycles} complete cycles" in err
    _same(a, b)
    bounds = _boundary_frames(a)
    assert len(bounds) == 2 * cycles
    if cycles > 20:        # (the estimator needs a few cycles of posts): found, so the frames carry its numbers
        assert any(data[6] != 0 or data[7] != 0 for _, _, data in bounds[-20:])


@pytest.mark.parametrize("cycles", [pl.MIN_CYCLES - 1, pl.MIN_CYCLES, pl.MIN_CYCLES + 1, 2 * pl.MIN_CYCLES])
def test_the_second_process_from_min_cycles_on_and_the_same_log_either_side(cycles, tmp_path, monkeypatch, capsys):
    """A run shorter than MIN_CYCLES is computed in one process (the second one would cost more than it saves);
    from MIN_CYCLES on in two: the same frames either side of the switch."""
    real = cli_log.pipeline_for
    made = []

    def spy(node, n=None):
        made.append(real(node, n))
        return made[-1]

    monkeypatch.setattr(cli_log, "pipeline_for", spy)
    args = [str(CUT_IN), "--fidelity", "object", "--duration", f"{cycles * CYCLE_S + 0.001:.3f}"]
    assert main(["log", *args, "-o", str(tmp_path / "a.blf")]) == 0
    assert (made[0] is not None) == (cycles >= pl.MIN_CYCLES)
    monkeypatch.setattr(cli_log, "pipeline_for", lambda node, n=None: None)
    assert main(["log", *args, "-o", str(tmp_path / "b.blf")]) == 0
    assert f"in {cycles} complete cycles" in capsys.readouterr().err
    _same(_frames(tmp_path / "a.blf"), _frames(tmp_path / "b.blf"))


@pytest.mark.parametrize("batch,in_flight", [(1, 1), (1, 4), (7, 1), (64, 2)])
def test_every_batch_size_and_depth_gives_the_same_log(batch, in_flight, tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(pl, "BATCH", batch)
    monkeypatch.setattr(pl, "MAX_IN_FLIGHT", in_flight)
    a, b, _ = _both(tmp_path, monkeypatch, capsys, str(CUT_IN), "--fidelity", "object", "--duration", "12")
    _same(a, b)


@pytest.mark.parametrize("case", ["bend, clusters", "no ego motion", "three radars, guardrails", "detection level"])
def test_the_same_log_on_a_bend_without_ego_frames_with_several_radars_and_at_detection_level(case, tmp_path,
                                                                                             monkeypatch, capsys):
    if case == "bend, clusters":
        args = [str(SCENARIOS / "guardrail_traffic.yaml"), "--fidelity", "object"]
    elif case == "no ego motion":          # the estimator sees a standing sensor: the frames say so, the same
        args = [str(CUT_IN), "--fidelity", "object", "--duration", "6", "--no-ego-motion"]
    elif case == "detection level":
        args = [str(CUT_IN), "--fidelity", "detection", "--duration", "2"]
    else:      # each radar its own estimator, sensor IDs 0–2: one process answers for all, in the radars' order
        doc = yaml.safe_load((SCENARIOS / "front_and_corners.yaml").read_text())
        doc["road"]["guardrails"] = {"left_offset_m": 1.0, "right_offset_m": 1.0, "post_spacing_m": 2.0}
        doc.pop("ecu", None)
        path = tmp_path / "corners_guardrails.yaml"
        path.write_text(yaml.safe_dump(doc))
        args = [str(path), "--fidelity", "object"]
    a, b, _ = _both(tmp_path, monkeypatch, capsys, *args)
    _same(a, b)
    from radarnode.wire import ids as wire_ids
    sensors = (0, 1, 2) if case == "three radars, guardrails" else (0,)
    own = {wire_ids.own_id(base, s) for s in sensors for base in (wire_ids.ROAD_BOUNDARY_LEFT,
                                                                  wire_ids.ROAD_BOUNDARY_RIGHT)}
    assert own <= {f[0] for f in a}, "every radar's boundary frames"


def _run(scenario: Path, cycles: int, pipeline: bool, stop_after: int | None = None, saturate: bool = False,
         received: dict | None = None):
    """run_node on the scenario: the frames sent, the stats, the node's saturated counts. ``received``: frames
    the node receives, by the poll (one a cycle) they arrive at."""
    sc = load_scenario(scenario)
    node = make_node(sc, fidelity="object")
    if saturate:      # a boundary far outside its signal's range: saturated and counted, wherever it is encoded
        est = node.boundaries
        estimate = est._estimate         # (a cycle's estimate, whether updated one cycle or a batch at a time)

        def far(*a, **k):
            left, right = estimate(*a, **k)
            return left.__class__(True, 1e4, 0.0, 0.0, 0.0, 1e4, 1.0), right
        est._estimate = far
    pipe = pl.pipeline_for(node) if pipeline else None
    sent: list[can.Message] = []
    stop = None
    if stop_after is not None:
        import threading
        stop = threading.Event()
    cycles_seen = [0]

    def on_cycle(out):
        cycles_seen[0] += 1
        if stop is not None and cycles_seen[0] >= stop_after:
            stop.set()
    calls = [0]

    def recv(timeout):
        calls[0] += 1
        return (received or {}).pop(calls[0], None)
    try:
        stats = run_node(node, clock=SimulatedClock(), sinks=[sent.append], vehicle=ego_motion_for(node),
                         duration_s=cycles * CYCLE_S + 1e-3, on_cycle=on_cycle, stop=stop, pipeline=pipe,
                         recv=recv if received is not None else None)
    finally:
        if pipe is not None:
            pipe.close()
    return [(m.arbitration_id, m.timestamp, bytes(m.data)) for m in sent], stats, dict(node.saturated)


def test_a_stopped_run_sends_every_cycle_it_computed_whole_and_the_same():
    """A stop (Ctrl-C) while cycles wait for their boundaries: they all go out, whole, as in one process (the
    stop comes from on_cycle, which with the pipeline runs only when a held cycle is sent: later cycles)."""
    a, sa, _ = _run(CUT_IN, 200, True, stop_after=70)
    b, sb, _ = _run(CUT_IN, 200, False, stop_after=sa.cycles)
    assert 70 <= sa.cycles < 200
    assert sa.cycles == sb.cycles and sa.frames == sb.frames
    _same(a, b)


def test_a_sensor_id_changed_mid_run_moves_the_boundary_frames_as_in_one_process():
    """A RadarConfiguration that moves the node to sensor ID 3 at cycle 40 (library use: run_node with a receiver):
    the boundary frames computed in the other process carry the new ID and its E2E key from that cycle on."""
    from radarnode.wire import ars408 as P
    from radarnode.wire import ids as wire_ids
    from radarnode.wire.dbc import load_database
    m = load_database().get_message_by_name("RadarConfiguration")
    values = {**{sig.name: 0 for sig in m.signals}, "RadarCfg_SensorID_valid": 1, "RadarCfg_SensorID": 3}
    cfg = can.Message(arbitration_id=P.shifted(m.frame_id, 0), data=m.encode(values), is_extended_id=False)
    a, _, _ = _run(CUT_IN, 90, True, received={40: cfg})
    b, _, _ = _run(CUT_IN, 90, False, received={40: cfg})
    _same(a, b)
    moved = {wire_ids.own_id(base, 3) for base in (wire_ids.ROAD_BOUNDARY_LEFT, wire_ids.ROAD_BOUNDARY_RIGHT)}
    assert sum(f[0] in moved for f in a) >= 2 * 45
    assert sum(f[0] in (0x680, 0x681) for f in a) >= 2 * 35


def _radar_cfg(**signals) -> can.Message:
    """A RadarConfiguration (0x200) for sensor 0 setting ``signals`` (each with its _valid bit)."""
    from radarnode.wire import ars408 as P
    from radarnode.wire.dbc import load_database
    m = load_database().get_message_by_name("RadarConfiguration")
    values = {sig.name: 0 for sig in m.signals}
    for name, value in signals.items():
        values[f"RadarCfg_{name}"] = value
        values[f"RadarCfg_{name}_valid"] = 1
    return can.Message(arbitration_id=P.shifted(m.frame_id, 0), data=m.encode(values), is_extended_id=False)


def test_the_object_level_hands_its_cluster_rows_over_only_while_objects_are_sent(monkeypatch):
    """While the node sends objects, the object level's clusters go to the boundary process as its blocks' rows
    (no list object here); a switch to clusters (the list sent: built here, handed over as columns) and back, and a
    MaxDistance that restarts the chunk in the middle of a block of rows (the cluster streams rewound), give the
    frames of one process, byte for byte, across blocks that straddle batches."""
    from radarnode.radar import object_model as om
    kinds = []
    for name in ("submit", "submit_rows"):
        real = getattr(pl.BoundaryPipeline, name)

        def spy(self, *a, _real=real, _name=name, **k):
            kinds.append(_name)
            return _real(self, *a, **k)
        monkeypatch.setattr(pl.BoundaryPipeline, name, spy)
    cycles = 3 * om.CLUSTER_BLOCK + 10
    changes = {30: _radar_cfg(OutputType=2), 60: _radar_cfg(OutputType=1), 100: _radar_cfg(MaxDistance=120)}
    a, _, _ = _run(CUT_IN, cycles, True, received=dict(changes))
    b, _, _ = _run(CUT_IN, cycles, False, received=dict(changes))
    _same(a, b)
    assert len(kinds) == cycles
    # rows, then the cluster list's columns for the cycles it was sent (from the poll that took the change on; one
    # poll a cycle from the second), then rows again
    first, count = kinds.index("submit"), kinds.count("submit")
    assert 25 <= first <= 31 and 28 <= count <= 30 and kinds[first:first + count] == ["submit"] * count
    assert set(kinds[:first]) == set(kinds[first + count:]) == {"submit_rows"}
    assert sum(f[0] == 0x600 for f in a) >= 25, "the cluster list was sent while asked for"


def test_cluster_rows_are_the_cluster_lists_columns():
    """ObjectModel.cluster_rows: the rows of the block a cycle's cluster list is cut from, the same numbers as the
    list step builds (position and speed), one array per block; refused where the step computed no clusters."""
    import radarnode.radar.object_model as om
    from radarnode.radar.setup import radar_config
    from radarnode.scene.world import Scene
    sc = load_scenario(CUT_IN)
    rc = radar_config(sc)
    twins = [om.ObjectModel(Scene(sc), rc.preset, np.random.default_rng(sc.seed)) for _ in range(2)]
    cfg = om.RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=True)
    blocks = set()
    with pytest.raises(ValueError, match="no step yet"):
        twins[1].cluster_rows()
    for k in range(2 * om.CLUSTER_BLOCK + 3):
        frame, _ = twins[0].step(k * sc.period_s, cfg)
        bare, _ = twins[1].step(k * sc.period_s, cfg, cluster_list=False)
        rows, a, b = twins[1].cluster_rows()
        cl = frame.clusters
        assert len(bare.clusters) == 0 and len(cl) == b - a
        for row, col in zip(rows[:, a:b], (cl.dist_long_m, cl.dist_lat_m, cl.vrel_long_mps, cl.vrel_lat_mps)):
            assert np.array_equal(row, col)
        np.testing.assert_array_equal(bare.objects.dist_long_m, frame.objects.dist_long_m)
        blocks.add(id(rows))
        assert not rows.flags.writeable
        if k == 40:
            assert len(cl) > 20          # the guardrail posts
    assert len(blocks) == 3
    plain, _ = twins[1].step((2 * om.CLUSTER_BLOCK + 3) * sc.period_s, om.RuntimeConfig(
        max_distance_m=rc.preset.max_range_m, clusters=False))
    with pytest.raises(ValueError, match="clusters=False"):
        twins[1].cluster_rows()


def test_saturated_boundary_values_are_counted_in_the_node_as_in_one_process():
    a, _, sat_a = _run(CUT_IN, 40, True, saturate=True)
    b, _, sat_b = _run(CUT_IN, 40, False, saturate=True)
    _same(a, b)
    assert sat_a == sat_b and sat_a.get("RBL_LatOffset", 0) >= 30


def test_an_exception_in_the_boundary_process_is_raised_in_the_run_and_nothing_hangs():
    sc = load_scenario(CUT_IN)
    node = make_node(sc, fidelity="object")

    def broken(*a, **k):
        raise ZeroDivisionError("estimator failed")
    node.boundaries._estimate = broken     # (a cycle's estimate, however it is updated)
    pipe = pl.pipeline_for(node)
    try:
        with pytest.raises(ZeroDivisionError, match="estimator failed"):
            run_node(node, clock=SimulatedClock(), sinks=[lambda m: None], duration_s=5.0, pipeline=pipe)
    finally:
        pipe.close()
    assert not pipe._process.is_alive()


def test_a_killed_boundary_process_is_a_clear_error_and_log_leaves_no_file(tmp_path, monkeypatch, capsys):
    real = cli_log.pipeline_for

    def doomed(node, cycles=None):
        p = real(node)
        os.kill(p._process.pid, signal.SIGKILL)
        p._process.join()
        return p

    monkeypatch.setattr(cli_log, "pipeline_for", doomed)
    out = tmp_path / "x.blf"
    rc = main(["log", str(CUT_IN), "--fidelity", "object", "--duration", "10", "-o", str(out)])
    err = capsys.readouterr().err
    assert rc == 1, err
    line = err.strip().splitlines()[-1]
    assert re.fullmatch(r"error: the road-boundary process \(pid \d+\) ended without answering \(exit code -9\); "
                        r"the run stops here", line), err
    assert list(tmp_path.iterdir()) == []           # no partial file


def test_the_real_time_clock_refuses_a_pipeline():
    from radarnode.wire.runner import RealTimeClock
    sc = load_scenario(CUT_IN)
    node = make_node(sc, fidelity="object")
    pipe = pl.pipeline_for(node)
    try:
        with pytest.raises(ValueError, match="not in real time"):
            run_node(node, clock=RealTimeClock(), sinks=[], duration_s=1.0, pipeline=pipe)
    finally:
        pipe.close()


def test_no_process_without_a_boundary_estimator_nor_with_the_ecu(tmp_path, monkeypatch, capsys):
    sc = load_scenario(SCENARIOS / "front_and_corners.yaml")         # no guardrails: no estimator
    assert pl.pipeline_for(make_node(sc, fidelity="object")) is None
    made = []
    monkeypatch.setattr(cli_log, "pipeline_for", lambda node, cycles=None: made.append(node))
    assert main(["log", str(CUT_IN), "--fidelity", "object", "--duration", "1", "--ecu",
                 "-o", str(tmp_path / "e.blf")]) == 0
    assert made == []       # the ECU reads the boundaries back: one process


def test_ctrl_c_to_the_whole_process_group_closes_the_log_complete(tmp_path):
    """A terminal's Ctrl-C reaches every process of the group, the boundary process too: it ignores it, answers
    the cycles computed, and the log is complete (130); no process of the group is left."""
    out = tmp_path / "long.blf"
    p = subprocess.Popen([sys.executable, "-m", "radarnode", "log", str(CUT_IN), "--fidelity", "object",
                          "--duration", "80000", "-v", "-o", str(out)], cwd=ROOT, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        seen = ""
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            line = p.stderr.readline()
            seen += line
            if "logging highway_cut_in to" in line or not line:
                break
        assert "logging highway_cut_in to" in seen, seen
        while time.monotonic() < deadline and not any(f.stat().st_size > 30_000 for f in tmp_path.iterdir()):
            time.sleep(0.1)
        os.killpg(p.pid, signal.SIGINT)
        _, err = p.communicate(timeout=120)
    finally:
        if p.poll() is None:
            os.killpg(p.pid, signal.SIGKILL)
    assert p.returncode == 130, seen + err
    done = re.search(r"interrupted: wrote (\d+) frames in (\d+) complete cycles", err)
    assert done, err
    frames = _frames(out)
    assert len(frames) == int(done.group(1))
    assert len(_boundary_frames(frames)) == 2 * int(done.group(2))
    time.sleep(0.2)
    with pytest.raises(ProcessLookupError):      # nothing of the group left running
        os.killpg(p.pid, 0)


def test_a_pipeline_never_closed_does_not_hold_the_interpreter_at_exit(tmp_path):
    """A library user who forgets close(): the interpreter still exits (multiprocessing's exit handler would wait
    for the daemon, which ignores SIGTERM so that a Ctrl-C of the whole group cannot cut a log short)."""
    script = tmp_path / "forgot.py"
    script.write_text(
        "from radarnode.radar.setup import load_scenario\n"
        "from radarnode.wire.group import make_node\n"
        "from radarnode.wire.pipeline import pipeline_for\n"
        "from radarnode.wire.runner import SimulatedClock, run_node\n"
        f"node = make_node(load_scenario({str(CUT_IN)!r}), fidelity='object')\n"
        "pipe = pipeline_for(node)\n"
        "run_node(node, clock=SimulatedClock(), sinks=[], duration_s=3.0, pipeline=pipe)\n"
        "print('ran', pipe.done, pipe._process.pid)\n")
    done = subprocess.run([sys.executable, str(script)], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    ran, cycles, pid = done.stdout.split()
    assert int(cycles) == 41
    with pytest.raises(ProcessLookupError):      # the boundary process ended with it
        os.kill(int(pid), 0)


def _children(pid: int) -> list[int]:
    """The processes whose parent is ``pid`` (from /proc)."""
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(d.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_the_boundary_process_ends_when_the_run_is_killed_and_holds_no_pipe_of_the_caller(tmp_path):
    """SIGKILL (an OOM kill, a harness's timeout) to the run: its boundary process sees the end of its pipe and
    ends too, and the caller's stdout/stderr pipes close (a harness waiting for them is not held)."""
    p = subprocess.Popen([sys.executable, "-m", "radarnode", "log", str(CUT_IN), "--fidelity", "object",
                          "--duration", "80000", "-v", "-o", str(tmp_path / "long.blf")], cwd=ROOT,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        seen = ""
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and "logging highway_cut_in to" not in seen:
            line = p.stderr.readline()
            seen += line
            assert line, seen
        workers = _children(p.pid)
        assert len(workers) == 1, workers
        p.kill()
        p.communicate(timeout=30)            # the pipes close: nothing else holds them
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and _alive(workers[0]):
            time.sleep(0.05)
        assert not _alive(workers[0]), "the boundary process outlived the run"
    finally:
        try:                       # whatever is left of the run's session
            os.killpg(p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def test_a_ctrl_c_while_the_process_is_forked_stops_the_run_with_a_complete_log(tmp_path, monkeypatch, capsys):
    """The signal arrives inside pipeline_for (about 4 ms at the start of every log): caught as every Ctrl-C of
    the run is, so the run stops at once, 130, the file complete, no process left."""
    real = cli_log.pipeline_for
    made = []

    def interrupted(node, cycles=None):
        os.kill(os.getpid(), signal.SIGINT)
        made.append(real(node))
        return made[-1]

    monkeypatch.setattr(cli_log, "pipeline_for", interrupted)
    out = tmp_path / "x.blf"
    rc = main(["log", str(CUT_IN), "--fidelity", "object", "--duration", "10", "-o", str(out)])
    err = capsys.readouterr().err
    assert rc == 130, err
    # stopped before its first cycle: no frame, so no file (an empty log is not kept); or a complete short one
    if out.exists():
        assert re.search(r"interrupted: wrote [1-9]\d* frames in \d+ complete cycles", err), err
        assert 0 < len(_frames(out)) < 100
    else:
        assert "interrupted before the first frame: nothing written" in err, err
        assert not list(tmp_path.iterdir())
    assert not made[0]._process.is_alive()


def test_an_interrupt_inside_the_fork_leaves_no_process(monkeypatch):
    import multiprocessing.process as mpp
    started = []
    real = mpp.BaseProcess.start

    def start_then_interrupt(self):
        real(self)
        started.append(self.pid)
        raise KeyboardInterrupt
    monkeypatch.setattr(mpp.BaseProcess, "start", start_then_interrupt)
    node = make_node(load_scenario(CUT_IN), fidelity="object")
    with pytest.raises(KeyboardInterrupt):
        pl.pipeline_for(node)
    assert started and not _alive(started[0])
    monkeypatch.undo()
    out, _, _ = _run_direct(node, 0, 40)          # the node was never handed over: it runs in one process
    assert len(_boundary_frames(out)) == 80


def _run_direct(node, first: int, cycles: int):
    """Cycles first … first+cycles−1 of ``node`` called directly, each after the vehicle's frames (a library
    user's loop): frames, outputs."""
    vehicle = ego_motion_for(node)
    outs = []
    for k in range(first, first + cycles):
        for m in vehicle.frames(k * CYCLE_S):
            node.receive(m, k * CYCLE_S)
        outs.append(node.cycle(k * CYCLE_S))
    return [(m.arbitration_id, m.timestamp, bytes(m.data)) for o in outs for m in o.messages], outs, node


def test_a_closed_pipeline_gives_the_nodes_their_estimators_back_to_go_on_in_one_process():
    """Library use: 60 cycles with a pipeline, closed, then 40 more cycles of the same node in this process give
    the frames of 100 cycles in one process (the estimator, its E2E counters, its last estimate came back)."""
    piped = make_node(load_scenario(CUT_IN), fidelity="object")
    pipe = pl.pipeline_for(piped)
    run_node(piped, clock=SimulatedClock(), sinks=[], vehicle=ego_motion_for(piped), duration_s=60 * CYCLE_S + 1e-3,
             pipeline=pipe)
    pipe.close()
    assert not pipe._process.is_alive()
    single = make_node(load_scenario(CUT_IN), fidelity="object")
    run_node(single, clock=SimulatedClock(), sinks=[], vehicle=ego_motion_for(single), duration_s=60 * CYCLE_S + 1e-3)
    a, outs, _ = _run_direct(piped, 60, 40)
    b, _, _ = _run_direct(single, 60, 40)
    _same(a, b)
    assert sum(o.boundaries[0].valid or o.boundaries[1].valid for o in outs) >= 20     # found, and going on
    with pytest.raises(pl.PipelineError, match="is closed"):
        pipe.submit(0, (np.zeros(0),) * 5, (0.0, (0.0, 0.0), 0.0, 0))


def test_after_a_pipeline_that_could_not_answer_the_node_says_its_estimator_is_lost():
    node = make_node(load_scenario(CUT_IN), fidelity="object")
    pipe = pl.pipeline_for(node)
    run_node(node, clock=SimulatedClock(), sinks=[], duration_s=20 * CYCLE_S + 1e-3, pipeline=pipe)
    pipe.close(graceful=False)            # (an error, an interrupt): killed, the estimator not given back
    assert not pipe._process.is_alive()
    with pytest.raises(pl.PipelineError, match="estimator was in a BoundaryPipeline's process that ended"):
        node.cycle(20 * CYCLE_S)


def test_a_stopped_boundary_process_is_warned_of_and_waited_for(monkeypatch, caplog):
    """SIGSTOP (a debugger, a job control accident): the run says what it waits for, and goes on when the process
    is continued, to the same frames."""
    import threading
    monkeypatch.setattr(pl, "SLOW_ANSWER_S", 0.3)
    node = make_node(load_scenario(CUT_IN), fidelity="object")
    pipe = pl.pipeline_for(node)
    os.kill(pipe._process.pid, signal.SIGSTOP)
    threading.Timer(1.5, os.kill, (pipe._process.pid, signal.SIGCONT)).start()
    sent: list[can.Message] = []
    try:
        with caplog.at_level("WARNING", logger="radarnode.wire.pipeline"):
            run_node(node, clock=SimulatedClock(), sinks=[sent.append], vehicle=ego_motion_for(node),
                     duration_s=70 * CYCLE_S + 1e-3, pipeline=pipe)
    finally:
        pipe.close()
    assert any("has not answered for 0.3 s; waiting" in r.message for r in caplog.records), caplog.text
    b, _, _ = _run(CUT_IN, 70, False)
    _same([(m.arbitration_id, m.timestamp, bytes(m.data)) for m in sent], b)


def test_a_handed_over_node_is_not_run_without_its_pipeline_nor_handed_over_twice():
    node = make_node(load_scenario(CUT_IN), fidelity="object")
    pipe = pl.pipeline_for(node)
    try:
        with pytest.raises(ValueError, match="pass it as pipeline="):      # else its boundary frames go out blank
            run_node(node, clock=SimulatedClock(), sinks=[], duration_s=1.0)
        with pytest.raises(pl.PipelineError, match="cannot be handed to another"):
            pl.pipeline_for(node)
        run_node(node, clock=SimulatedClock(), sinks=[], duration_s=3.0, pipeline=pipe)
    finally:
        pipe.close(graceful=False)
    with pytest.raises(pl.PipelineError, match="cannot be handed to another"):      # its estimator was lost
        pl.pipeline_for(node)


def test_an_interrupt_while_the_nodes_are_handed_over_leaves_them_in_one_process(monkeypatch):
    from radarnode.wire.node import RadarNode
    real = RadarNode.defer_boundaries

    def interrupted(self, pipe, index):
        if pipe is not None:
            raise KeyboardInterrupt
        real(self, pipe, index)
    monkeypatch.setattr(RadarNode, "defer_boundaries", interrupted)
    node = make_node(load_scenario(CUT_IN), fidelity="object")
    with pytest.raises(KeyboardInterrupt):
        pl.pipeline_for(node)
    monkeypatch.undo()
    assert node.boundary_pipe is None
    a, _, _ = _run_direct(node, 0, 40)
    b, _, _ = _run_direct(make_node(load_scenario(CUT_IN), fidelity="object"), 0, 40)
    _same(a, b)
