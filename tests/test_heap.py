"""The command line's garbage collector (radarnode.cli.heap): off while the modules load, on while the command runs,
and as it was once the command returns. Each test runs in a new process, as a user's command does (and so that the
entry point is :func:`radarnode.cli.main`, the function, before ``radarnode.cli.main`` the module shadows it)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: a command whose work is replaced by the test's ``work(args)``: what the collector is while it runs, and after
SCRIPT = '''
import gc, sys, json
from radarnode.cli import main as entry
from radarnode.cli import heap
import importlib
seen = {}
%s
command = sys.argv[2]
importlib.import_module("radarnode.cli." + command).cmd = work
log = sys.argv[1]
open(log, "w").write("(0.000000) can0 200#0000000000000000\\n")
before = (gc.isenabled(), gc.get_threshold())
%s
status = entry([command, "scenarios/highway_cut_in.yaml" if command in ("node", "run") else log])
after = (gc.isenabled(), gc.get_threshold())
print(json.dumps({"status": status, "seen": seen, "before": before, "after": after, "frozen": gc.get_freeze_count(),
                  "gen0": heap.GEN0_THRESHOLD}))
'''

SPY = '''
def work(args):
    seen.update(enabled=gc.isenabled(), threshold=gc.get_threshold(), frozen=gc.get_freeze_count())
    return 0
'''


def run(work: str, tmp_path: Path, before: str = "", command: str = "decode") -> dict:
    import json
    out = subprocess.run([sys.executable, "-c", SCRIPT % (work, before), str(tmp_path / "x.log"), command], cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])


def test_a_command_runs_with_the_collector_on_and_returns_it_as_it_was(tmp_path):
    r = run(SPY, tmp_path)
    assert r["status"] == 0
    # during the command: on, the larger threshold, the loaded modules frozen
    assert r["seen"]["enabled"] is True
    assert r["seen"]["threshold"][0] == r["gen0"]
    assert r["seen"]["frozen"] > 10_000
    # after it: as before, nothing left frozen
    assert r["after"] == r["before"]
    assert r["frozen"] == 0


@pytest.mark.parametrize("command", ["node", "run"])
def test_a_real_time_command_keeps_pythons_thresholds_with_the_heap_frozen(command, tmp_path):
    """On a bus in real time a collection of 10,000 young objects can make a frame late: those commands keep the
    thresholds they had; their start's objects frozen all the same (no full collection over the modules)."""
    r = run(SPY, tmp_path, command=command)
    assert r["seen"]["enabled"] is True
    assert r["seen"]["threshold"] == r["before"][1]
    assert r["seen"]["frozen"] > 10_000
    assert r["after"] == r["before"] and r["frozen"] == 0


def test_a_collector_turned_off_by_the_caller_stays_off(tmp_path):
    r = run(SPY, tmp_path, before="gc.disable()")
    assert r["seen"]["enabled"] is False
    assert r["after"][0] is False
    assert r["frozen"] == 0


def test_cyclic_garbage_made_by_a_command_is_still_collected(tmp_path):
    """With the larger threshold, a command that makes reference cycles does not keep them: they go at the next
    collections (a weak reference to one of them dies while the command still runs)."""
    work = '''
import weakref
class Node:
    pass
def work(args):
    first = Node()
    first.me = first
    ref = weakref.ref(first)
    del first
    for _ in range(5 * heap.GEN0_THRESHOLD):        # containers that live on, each in a cycle of its own
        junk = [Node() for _ in range(10)]
        junk.append(junk)
    seen["alive"] = ref() is not None
    return 0
'''
    r = run(work, tmp_path)
    assert r["seen"]["alive"] is False


def test_radarnode_log_starts_without_a_full_collection(tmp_path):
    """``radarnode log`` as a user starts it: no collection of the whole heap, and at most one of the middle
    generation, over a 1-s log (before: one full and eleven middle ones while it loaded and set up)."""
    code = ("import gc, sys\n"
            "counts = []\n"
            "gc.callbacks.append(lambda phase, info: counts.append(info['generation']) if phase == 'start' else None)\n"
            "from radarnode.cli import main\n"
            f"status = main(['log', 'scenarios/highway_cut_in.yaml', '--duration', '1', '-o', {str(tmp_path / 'x.log')!r}])\n"
            "print(status, counts.count(1), counts.count(2))\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120)
    status, middle, full = (int(v) for v in out.stdout.split()[-3:])
    assert status == 0, out.stderr
    assert full == 0 and middle <= 1, out.stdout


def test_objects_the_caller_froze_stay_frozen(tmp_path):
    """A caller that froze its own heap (before a fork, say) finds it frozen after the command (an independent
    tester's finding: restore() had unfrozen everything)."""
    r = run(SPY, tmp_path, before="gc.freeze()")
    assert r["seen"]["enabled"] is True
    # (frozen objects that die leave the count: a few of the start's do)
    assert r["frozen"] > 0.9 * r["seen"]["frozen"] > 10_000


def test_the_program_ends_with_the_commands_status_and_its_start_still_frozen(tmp_path):
    """``radarnode`` as a program (the console script, ``python -m radarnode``: :func:`radarnode.cli.program`) leaves
    the start's objects frozen as the process ends, so that Python's last collection does not scan them again; the
    command's status is the process's, a failing command's too. :func:`main` (above) still gives them back."""
    code = SCRIPT.replace("from radarnode.cli import main as entry", "from radarnode.cli import program") \
        .replace("status = entry(", "sys.argv[1:] = (").replace(
            ' else log])\n', ' else log])\ntry:\n    program()\nexcept SystemExit as stop:\n    status = stop.code\n')
    for work, want in ((SPY, 0), (SPY.replace("return 0", "return 1"), 1)):
        out = subprocess.run([sys.executable, "-c", code % (work, ""), str(tmp_path / "x.log"), "decode"], cwd=ROOT,
                             capture_output=True, text=True, timeout=120)
        assert out.returncode == 0, out.stderr
        import json
        r = json.loads(out.stdout.strip().splitlines()[-1])
        assert r["status"] == want
        assert r["frozen"] > 0.9 * r["seen"]["frozen"] > 10_000
    for args, want in ((["--version"], 0), (["decode", str(tmp_path / "missing.log")], 1)):
        done = subprocess.run([sys.executable, "-m", "radarnode", *args], cwd=ROOT, capture_output=True, text=True,
                              timeout=120)
        assert done.returncode == want, done.stderr


def test_the_program_runs_again_in_one_process_after_the_command_line_module_is_imported(tmp_path):
    """``radarnode.cli.main`` (the module) takes the package's name ``main`` once imported: :func:`program` calls the
    function under a name of its own, so a second program in one process, or one after that import, still runs
    (an independent tester: ``TypeError: 'module' object is not callable``)."""
    code = ("import sys\n"
            "import radarnode.cli as cli\n"
            "import radarnode.cli.main\n"
            "codes = []\n"
            "for _ in range(2):\n"
            "    sys.argv[1:] = ['decode', 'missing.log']\n"
            "    try:\n"
            "        cli.program()\n"
            "    except SystemExit as stop:\n"
            "        codes.append(stop.code)\n"
            "print(codes)\n")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=120,
                         env={**__import__("os").environ, "PYTHONPATH": str(ROOT)})
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip().splitlines()[-1] == "[1, 1]"


@pytest.mark.parametrize("unbuffered", [False, True])
@pytest.mark.parametrize("args", [["--version"], ["--help"], ["decode", "--max-cycles", "1", "LOG"]])
def test_small_output_to_a_closed_pipe_ends_quietly_and_to_a_full_disk_with_one_error(args, tmp_path, unbuffered):
    """Output small enough to wait in the buffer until the process ends (Python's own flush at exit met the closed
    pipe or the full disk there: status 120 and "Exception ignored"): a closed pipe ends with the command's status and
    nothing on stderr; /dev/full with one error line and status 1."""
    import os
    log = tmp_path / "x.log"
    log.write_text("(0.000000) can0 60A#0000000010000000\n")
    args = [str(log) if a == "LOG" else a for a in args]
    # unbuffered (PYTHONUNBUFFERED, as container images often set it) the write fails at once, and argparse drops a
    # failed write of its help: `--help > /dev/full` ended with status 0 and nothing said (an independent tester's
    # finding)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    if unbuffered:
        env["PYTHONUNBUFFERED"] = "1"
    reader, writer = os.pipe()
    os.close(reader)                                 # closed before the program writes anything
    try:
        done = subprocess.run([sys.executable, "-m", "radarnode", *args], cwd=ROOT, stdout=writer,
                              stderr=subprocess.PIPE, text=True, timeout=120, env=env)
    finally:
        os.close(writer)
    assert done.returncode == 0, done.stderr
    assert "Exception ignored" not in done.stderr and "Traceback" not in done.stderr
    with open("/dev/full", "w") as full:
        done = subprocess.run([sys.executable, "-m", "radarnode", *args], cwd=ROOT, stdout=full,
                              stderr=subprocess.PIPE, text=True, timeout=120, env=env)
    assert done.returncode == 1
    assert "error: standard output: No space left on device" in done.stderr
    assert "Exception ignored" not in done.stderr and "Traceback" not in done.stderr


@pytest.mark.skipif(not Path("/dev/full").is_char_device(),
                    reason="needs /dev/full (Linux): a device that is always full")
@pytest.mark.parametrize("args", [["decode", "LOG"], ["decode", "LOG", "--summary"],
                                  ["run", "scenarios/stopped_vehicle.yaml", "--fast", "--duration", "1"]])
def test_output_that_fails_while_the_command_runs_names_standard_output(args, tmp_path):
    """A command whose output fails to go out while it runs (a flush on the way, not the one at exit) said only
    "error: No space left on device", where the README promises "error: standard output: …" (an independent
    tester's finding)."""
    import os
    log = tmp_path / "x.log"
    made = subprocess.run([sys.executable, "-m", "radarnode", "log", "scenarios/stopped_vehicle.yaml", "--duration",
                           "10", "-o", str(log)], cwd=ROOT, capture_output=True, timeout=120)
    assert made.returncode == 0, made.stderr
    args = [str(log) if a == "LOG" else a for a in args]
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    with open("/dev/full", "w") as full:
        done = subprocess.run([sys.executable, "-m", "radarnode", *args], cwd=ROOT, stdout=full,
                              stderr=subprocess.PIPE, text=True, timeout=120, env=env)
    assert done.returncode == 1, done.stderr
    assert done.stderr.strip().splitlines()[-1] == "error: standard output: No space left on device", done.stderr
    assert done.stderr.count("error:") == 1 and "Traceback" not in done.stderr
