"""Errors, not tracebacks: every subcommand, fed bad option values and bad files, prints one ``error: …`` line
naming the option or file, the value and what is allowed, exits 2 for a usage error (the command line alone
is wrong) and 1 for the rest (a file, a scenario, a bus), and leaves no partial file.

The commands run in-process through ``radarnode.cli.main.main`` (the console entry point), so the matrix of
some 400 cases takes seconds; ``tests/test_cli.py`` runs the real executable.
"""

from __future__ import annotations

import os
import random
import shutil
import subprocess
import sys
import tempfile
import uuid
from pathlib import Path

import pytest

from radarnode.cli.main import build_parser, main
from tests.helpers import cli
from tests.conftest import ROOT, SCENARIOS

SCENARIO = str(SCENARIOS / "stopped_vehicle.yaml")          # 15 s, one stopped car ahead




def one_error_line(err: str) -> str:
    lines = [x for x in err.splitlines() if x.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("error: ") and "Traceback" not in err, err
    return lines[0]


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    """A small log of each kind the file cases need: a BLF and a candump log of 1 s."""
    d = tmp_path_factory.mktemp("logs")
    out = {}
    for suffix in (".blf", ".log"):
        out[suffix] = d / f"small{suffix}"
        assert main(["log", SCENARIO, "-o", str(out[suffix]), "--duration", "1"]) == 0
    return out


# --- option values ---------------------------------------------------------------------------------------

VALUES = ("nan", "inf", "-inf", "-1", "0", "1e300", "99999999999999999999", "1.5", "abc", "")
INF = float("inf")


def _options(logs_dir: str) -> list[tuple[list[str], str, type, float, float, bool]]:
    """(the command before the option, option, int or float, lowest, highest, lowest excluded)."""
    log, mcap, png, out = f"{logs_dir}/small.blf", f"{logs_dir}/x.mcap", f"{logs_dir}/x.png", f"{logs_dir}/x.blf"
    scenario_opts = [("--seed", int, 0, 2**63 - 1, False), ("--duration", float, 0, 86_400, True)]
    table = {
        ("run", SCENARIO, "--fast"): scenario_opts + [("--every", int, 1, INF, False),
                                                      ("--foxglove-port", int, 0, 65_535, False)],
        ("node", SCENARIO, "-i", "virtual", "-c", "matrix", "--fast"):
            scenario_opts + [("-b", int, 10_000, 1_000_000, False), ("--foxglove-port", int, 0, 65_535, False)],
        ("consume", "-i", "virtual", "-c", "matrix"): [("--sensor-id", int, 0, 7, False), ("--count", int, 0, INF, False),
                                                       ("--timeout", float, 0, 86_400, False),
                                                       ("-b", int, 10_000, 1_000_000, False)],
        ("log", SCENARIO, "-o", out): scenario_opts + [("--start-time", float, 0, 1e10, False),
                                                       ("-b", int, 10_000, 1_000_000, False)],
        ("decode", log): [("--sensor-id", int, 0, 7, False), ("--max-cycles", int, 0, INF, False)],
        ("export", log, "-o", mcap): [("--start-time", float, 0, 1e10, False), ("--sensor-id", int, 0, 7, False)],
        ("image", SCENARIO, "-o", png): scenario_opts + [("--time", float, 0, 15.0, False),
                                                         ("--k", float, 1, 10, False),
                                                         ("--every", int, 1, INF, False)],
        ("report", SCENARIO): [("--seeds", int, 1, 10_000, False), ("--min-passes", int, 1, 1, False),
                               ("--fcw-ttc-warn", float, 0.5, 10, False), ("--fcw-decel-warn", float, 1, 10, False),
                               ("--acc-min-speed", float, 0, 30, False), ("--path-half-width", float, 0.5, 5, False),
                               ("--ecu-latency", float, 0, 0.5, False)],
    }
    return [(list(cmd), opt, kind, lo, hi, lo_open) for cmd, opts in table.items() for opt, kind, lo, hi, lo_open in opts]


def _allowed(text: str, kind: type, lo: float, hi: float, lo_open: bool) -> bool:
    try:
        v = int(text, 10) if kind is int else float(text)
    except ValueError:
        return False
    if v != v or v in (INF, -INF):
        return False
    return (v > lo if lo_open else v >= lo) and v <= hi


CASES = [(cmd, opt, kind, lo, hi, lo_open, value) for cmd, opt, kind, lo, hi, lo_open in _options("LOGS")
         for value in VALUES]


@pytest.mark.parametrize("cmd,option,kind,lo,hi,lo_open,value", CASES,
                         ids=[f"{c[0]}-{o}-{v or 'empty'}" for c, o, _, _, _, _, v in CASES])
def test_every_numeric_option_refuses_what_it_does_not_allow(capsys, logs, cmd, option, kind, lo, hi, lo_open,
                                                             value):
    d = str(logs[".blf"].parent)
    cmd = [c.replace("LOGS", d) for c in cmd]
    argv = [*cmd, f"{option}={value}"]          # "--x=-inf": a value that starts with a dash is a value
    if _allowed(value, kind, lo, hi, lo_open):
        build_parser().parse_args(argv)      # parses; not run (a run is not what this test is about)
        return
    before = sorted(os.listdir(d))
    rc, _, err = cli(capsys, *argv)
    line = one_error_line(err)
    assert rc == 2, err
    # the option, the value as typed, and what is allowed
    name = option.lstrip("-")
    assert f"option {option}" in line or f"/--{name}" in line or f"option -{name}" in line, line
    assert "is not allowed" in line and "expected" in line, line
    shown = repr(value) if value in ("abc", "") else None
    assert shown is None or shown in line, line
    assert sorted(os.listdir(d)) == before             # nothing written


@pytest.mark.parametrize("argv,needle", [
    (["run", SCENARIO, "--fidelity", "best"], "option --fidelity: value 'best' is not allowed; expected one of object"),
    (["decode", "LOGS/small.blf", "--format", "xml"], "option --format: value 'xml' is not allowed; expected one of"),
    (["log", SCENARIO, "-o", "LOGS/x.log", "--channel", ""], "option --channel: value '' is not allowed"),
    (["log", SCENARIO, "-o", "LOGS/x.log", "--channel", "can 0"], "option --channel: value 'can 0' is not allowed"),
    # BLF stores the channel in 16 bits: a struct.error traceback after the run had started (a tester's finding)
    (["log", SCENARIO, "-o", "LOGS/x.blf", "--channel", "65536"],
     "option --channel: value '65536' is not allowed for a .blf log: BLF stores the channel as a 16-bit number"),
    (["log", SCENARIO, "-o", "LOGS/x.blf", "--channel", "can99999999999999999999"],
     "option --channel: value 'can99999999999999999999' is not allowed for a .blf log"),
    (["log", SCENARIO, "-o", "LOGS/x.txt"], "option --output: value 'LOGS/x.txt' is not allowed: .txt is"),
    (["log", SCENARIO, "-o", "LOGS/x.unknown"], "option --output: value 'LOGS/x.unknown' is not allowed"),
    # '.blf' alone is a hidden file's name without a suffix to pathlib: "the suffix '(none)'" puzzled a tester, and
    # decode wrote text into '.blf' and JSON into '.csv'
    (["log", SCENARIO, "-o", "LOGS/.blf"], "option --output: value 'LOGS/.blf' is not allowed: '.blf' is a name "
                                           "without a stem (a hidden file's); expected a name before the suffix, "
                                           "such as run.blf"),
    (["log", SCENARIO, "-o", "LOGS/.log.gz"], "option --output: value 'LOGS/.log.gz' is not allowed: '.log.gz' is a "
                                              "name without a stem"),
    (["export", "LOGS/small.blf", "-o", "LOGS/.mcap"], "option --output: value 'LOGS/.mcap' is not allowed: '.mcap' is"
                                                       " a name without a stem"),
    (["image", SCENARIO, "-o", "LOGS/.png"], "option --output: value 'LOGS/.png' is not allowed: '.png' is a name "
                                             "without a stem"),
    (["decode", "LOGS/small.blf", "-o", "LOGS/.blf"], "option --output: value 'LOGS/.blf' is not allowed: '.blf' is a "
                                                      "name without a stem"),
    (["decode", "LOGS/small.blf", "--format", "json", "-o", "LOGS/.csv"], "option --output: value 'LOGS/.csv' is not "
                                                                          "allowed: '.csv' is a name without a stem"),
    (["log", SCENARIO, "-o", "LOGS/.gz"], "option --output: value 'LOGS/.gz' is not allowed: '.gz' has no suffix"),
    # decode wrote plain text under a .gz name
    (["decode", "LOGS/small.blf", "--format", "json", "-o", "LOGS/x.json.gz"],
     "option --output: value 'LOGS/x.json.gz' is not allowed: decode writes no compressed output"),
    (["log", SCENARIO, "-o", "LOGS/x.blf.gz"], "option --output: value 'LOGS/x.blf.gz' is not allowed"),
    (["export", "LOGS/small.blf", "-o", "LOGS/x.blf"], "option --output: value 'LOGS/x.blf' is not allowed"),
    (["image", SCENARIO, "-o", "LOGS/x.xyz"], "option --output: value 'LOGS/x.xyz' is not allowed"),
    (["image", SCENARIO, "-o", "LOGS/x.png", "--animate"], "option --output: value 'LOGS/x.png' is not allowed"),
    (["image", SCENARIO, "-o", "LOGS/x.png", "--time", "20"], "option --time: value 20.0 is not allowed"),
    (["decode", "LOGS/small.txt"], "argument FILE: value 'LOGS/small.txt' is not allowed"),
    (["decode", "LOGS/small.blf", "-o", "LOGS/small.blf"], "option --output: value 'LOGS/small.blf' is not allowed"),
    (["node", SCENARIO, "-i", "virtual", "-c", "x", "--bus-kwargs", "novalue"], "option --bus-kwargs: value 'novalue'"),
    # a value that begins with "-" and is no plain negative number was taken by argparse for an option ("expected
    # one argument", no value named), and Python read 0.1_5 as 0.15 (a tester's finding)
    (["log", SCENARIO, "-o", "LOGS/x.blf", "--duration", "-1e3"], "option --duration: value -1e3 is not allowed"),
    (["log", SCENARIO, "-o", "LOGS/x.blf", "--start-time", "-inf"], "option --start-time: value -inf is not allowed"),
    (["log", SCENARIO, "-o", "LOGS/x.blf", "--duration", "0.1_5"], "option --duration: value 0.1_5 is not allowed"),
    (["report", SCENARIO, "--seeds", "1_0"], "option --seeds: value 1_0 is not allowed"),
    # an integer bound in full, not 9.22337e+18 (a tester's finding)
    (["run", SCENARIO, "--seed", "-1"], "option --seed: value -1 is not allowed; expected an integer in "
                                        "[0, 9223372036854775807]"),
    # a list or a range that starts below zero is a value too (the next option's check is reached)
    (["montecarlo", "--snr-db", "-10:20:2", "--trials", "0"], "option --trials: value 0 is not allowed"),
    (["montecarlo", "--snr-db", "-5,0,5", "--trials", "0"], "option --trials: value 0 is not allowed"),
    # an empty key, a non-finite number, a truth value that is none, and a bit rate the bus-load budget would not
    # know (the bus opened at 250 kbit/s, the budget planned for 500; a tester's finding) were taken
    (["node", SCENARIO, "-i", "virtual", "-c", "x", "--bus-kwargs", "=1"], "option --bus-kwargs: value '=1'"),
    (["node", SCENARIO, "-i", "virtual", "-c", "x", "--bus-kwargs", "x=nan"], "option --bus-kwargs: value 'x=nan'"),
    (["node", SCENARIO, "-i", "virtual", "-c", "x", "--bus-kwargs", "receive_own_messages=maybe"],
     "option --bus-kwargs: value 'receive_own_messages=maybe' is not allowed; expected receive_own_messages=True"),
    (["node", SCENARIO, "-i", "virtual", "-c", "x", "--bus-kwargs", "bitrate=250000"],
     "option --bus-kwargs: key 'bitrate' ('250000') is not allowed; expected -b/--bitrate"),
    # a key the bus does not read was dropped without a word: a misspelt receive_own_messages ran the node with its
    # default; fd on the virtual bus (which takes protocol) likewise
    (["node", SCENARIO, "-i", "virtual", "-c", "x", "--bus-kwargs", "receive_own_messagez=True"],
     "option --bus-kwargs: key 'receive_own_messagez' is not allowed for interface 'virtual'"),
    (["consume", "-i", "virtual", "-c", "x", "--bus-kwargs", "receive_own_messages=True", "fd=True"],
     "option --bus-kwargs: key 'fd' is not allowed for interface 'virtual': python-can's VirtualBus does not read it "
     "(it would be dropped without a word); expected one of channel, config_context, ignore_config, interface, "
     "preserve_timestamps, protocol, receive_own_messages, rx_queue_size"),
    # a key that -i or -c overrode was dropped without a word: the node ran on the virtual bus, channel a (a tester's
    # finding)
    (["node", SCENARIO, "-i", "virtual", "-c", "a", "--bus-kwargs", "interface=udp_multicast"],
     "option --bus-kwargs: key 'interface' ('udp_multicast') is not allowed with -i/--interface 'virtual'; expected "
     "one of them"),
    (["consume", "-i", "virtual", "-c", "a", "--bus-kwargs", "channel=b"],
     "option --bus-kwargs: key 'channel' ('b') is not allowed with -c/--channel 'a'; expected one of them"),
    (["node", SCENARIO, "-c", "a", "--bus-kwargs", "bustype=bogus"],
     "option --bus-kwargs bustype: interface 'bogus' cannot be used here"),
    # a filter list cannot be given as KEY=VALUE: its text failed on every frame, status 0 (a tester's finding)
    (["consume", "-i", "virtual", "-c", "x", "--bus-kwargs", "can_filters=x"],
     "option --bus-kwargs: key 'can_filters' ('x') is not allowed: it takes a list of {can_id, can_mask} entries"),
    (["node", SCENARIO, "-i", "no_such_interface", "-c", "x"], "option -i/--interface: interface 'no_such_interface'"),
    (["consume", "-i", "no_such_interface", "-c", "x"], "option -i/--interface: interface 'no_such_interface'"),
    # consume took --sensor-id 1 with --fuse, ignored it and exited 0 (decode refused the pair; a tester's finding)
    (["consume", "-i", "virtual", "-c", "x", "--sensor-id", "1", "--fuse", "scenarios/front_and_corners.yaml"],
     "option --fuse: not allowed with --sensor-id"),
    (["report", SCENARIO, "--seeds", "2", "--min-passes", "3"], "option --min-passes: value 3 is not allowed"),
    # the ECU options named no interval for NaN and ±inf (a tester's finding)
    (["report", SCENARIO, "--fcw-ttc-warn", "nan"], "option --fcw-ttc-warn: value nan is not allowed; expected a "
                                                     "finite number in [0.5, 10]"),
    (["report", SCENARIO, "--ecu-latency", "inf"], "option --ecu-latency: value inf is not allowed; expected a "
                                                    "finite number in [0, 0.5]"),
    (["log", SCENARIO], "the following arguments are required: -o/--output"),
    (["log", SCENARIO, "-o", "LOGS/x.log", "--no-such-option"], "unrecognized arguments: --no-such-option"),
    # options are never abbreviated (report --seed 7 was taken for --seeds 7: seeds 1–7); the full name is offered
    (["report", SCENARIO, "--seed", "7"], "unrecognized arguments: --seed 7; did you mean --seeds?"),
    (["log", SCENARIO, "-o", "LOGS/x.log", "--dur", "3"], "unrecognized arguments: --dur 3; did you mean --duration?"),
    # the global options were offered twice ("--debug or --debug"; a tester's finding)
    (["log", SCENARIO, "-o", "LOGS/x.log", "--deb"], "unrecognized arguments: --deb; did you mean --debug?"),
    (["frobnicate"], "argument COMMAND: value 'frobnicate' is not allowed; expected one of run, node"),
    # an option that the rest of the command line leaves unused is refused, not ignored: both named
    (["image", SCENARIO, "-o", "LOGS/x.png", "--every", "3"],
     "option --every: value 3 is not allowed without --animate"),
    (["image", SCENARIO, "-o", "LOGS/x.gif", "--animate", "--time", "2"],
     "option --time: value 2 is not allowed with --animate"),
    (["run", SCENARIO, "--fast", "--foxglove-port", "9000"],
     "option --foxglove-port: value 9000 is not allowed without --foxglove"),
    (["node", SCENARIO, "-i", "virtual", "-c", "x", "--fast", "--foxglove-port", "9000"],
     "option --foxglove-port: value 9000 is not allowed without --foxglove"),
    (["export", "LOGS/small.blf", "-o", "LOGS/y.mcap", "--start-time", "5"],
     "option --start-time: value 5 is not allowed without --scenario"),
    # … the same for options that only another mode or experiment reads (an independent tester's findings, 2026-12-07)
    (["run", SCENARIO, "--fast", "--quiet", "--every", "3"], "option --every: value 3 is not allowed with --quiet"),
    (["image", SCENARIO, "-o", "LOGS/x.png", "--fidelity", "object"],
     "option --fidelity: value 'object' is not allowed with image"),
    (["montecarlo", "--experiment", "table2", "--snr-db", "5"],
     "option --snr-db: value 5 is not allowed with --experiment table2"),
    (["montecarlo", "--experiment", "snr", "--resolution-snr-db", "5"],
     "option --resolution-snr-db: value 5 is not allowed with --experiment snr"),
    (["montecarlo", "--experiment", "timing", "--trials", "20"],
     "option --trials: value 20 is not allowed with --experiment timing"),
    (["run", SCENARIO, "--duration", "0.01"], "option --duration: value 0.01 is not allowed; expected at least one"),
])
def test_other_usage_errors_are_one_line_and_exit_2(capsys, logs, argv, needle):
    d = str(logs[".blf"].parent)
    before = sorted(os.listdir(d))
    rc, _, err = cli(capsys, *[a.replace("LOGS", d) for a in argv])
    line = one_error_line(err)
    assert rc == 2 and needle.replace("LOGS", d) in line, line
    assert sorted(os.listdir(d)) == before


def test_an_mf4_or_mcap_output_without_its_extra_is_refused_before_the_run(capsys, logs, monkeypatch):
    import builtins

    from can.io import mf4
    monkeypatch.setattr(mf4, "asammdf", None)
    d = logs[".blf"].parent
    rc, _, err = cli(capsys, "log", SCENARIO, "-o", d / "x.mf4")
    assert rc == 2 and "needs python-can's MF4 support (asammdf), which is not installed: pip install " \
                       "'radarnode[mf4]'" in one_error_line(err)
    rc, _, err = cli(capsys, "decode", d / "x.mf4")
    assert rc == 2 and "radarnode[mf4]" in one_error_line(err)
    real_import = builtins.__import__

    def no_foxglove(name, *a, **kw):
        if name == "foxglove" or name.startswith("foxglove."):
            raise ImportError(name)
        return real_import(name, *a, **kw)

    monkeypatch.setattr(builtins, "__import__", no_foxglove)
    rc, _, err = cli(capsys, "log", SCENARIO, "-o", d / "x.mcap")
    assert rc == 2 and "needs foxglove-sdk, which is not installed" in one_error_line(err)
    assert not list(d.glob("x.*")) and not list(d.glob(".x*"))


# --- files -------------------------------------------------------------------------------------------------

FILE_KINDS = ("missing", "directory", "unreadable", "empty", "truncated", "corrupted", "not-utf8", "wrong-format")


def _bad_scenario(d: Path, kind: str) -> Path:
    text = (SCENARIOS / "highway_cut_in.yaml").read_text()
    p = d / f"{kind}.yaml"
    if kind == "missing":
        return p
    if kind == "directory":
        p.mkdir()
    elif kind == "empty":
        p.write_text("")
    elif kind == "truncated":                         # cut in the middle of a waypoint
        cut = text.index("{t_s: 4.0") + 12
        p.write_text(text[:cut])
    elif kind == "corrupted":
        rnd = random.Random(7)
        data = bytearray(text.encode())
        for k in range(len(data) // 3, len(data) // 3 + 64):
            data[k] = rnd.randrange(256)
        p.write_bytes(bytes(data))
    elif kind == "not-utf8":
        p.write_bytes(text.replace("Three-lane", "Dreispurige Autobahn, Überholer").encode("latin-1"))
    elif kind == "wrong-format":
        shutil.copy(ROOT / "dbc" / "ars408.dbc", p)     # a text file of another kind
    elif kind == "recursive-alias":                   # a RecursionError traceback before (an independent tester)
        p.write_text(text + "extra: &a [*a]\n")
    elif kind == "deep-nesting":
        p.write_text(text + "extra: " + "[" * 5000 + "]" * 5000 + "\n")
    elif kind == "many-values":                       # minutes and gigabytes before its error (16 MB of them)
        p.write_text(text + "extra: [" + ", ".join(["1"] * 250_000) + "]\n")
    elif kind == "huge":                              # read whole before (800 MB, or /dev/zero until killed)
        p.write_text(text + "# " + "x" * (17 << 20) + "\n")
    elif kind == "alias-bomb":                        # ran for minutes before
        bomb = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
            f"a{k}: &a{k} [" + ", ".join([f"*a{k - 1}"] * 10) + "]\n" for k in range(1, 9))
        p.write_text(text + bomb)
    elif kind == "unreadable":
        p.write_text(text)
        p.chmod(0)
    return p


def _bad_log(d: Path, kind: str, good: Path, suffix: str) -> Path:
    p = d / f"{kind}{suffix}"
    data = good.read_bytes()
    if kind == "missing":
        return p
    if kind == "directory":
        p.mkdir()
    elif kind == "empty":
        p.write_bytes(b"")
    elif kind == "truncated":
        p.write_bytes(data[: len(data) * 2 // 3])
    elif kind == "corrupted":
        rnd = random.Random(11)
        bad = bytearray(data)
        for k in range(len(bad) // 3, len(bad) // 3 + 48):
            bad[k] = rnd.randrange(256)
        p.write_bytes(bytes(bad))
    elif kind == "not-utf8":
        p.write_bytes(data.replace(b"60B#", b"\xe9\xe90B#", 5) if suffix == ".log" else b"\xff\xfe" + data)
    elif kind == "wrong-format":
        p.write_bytes((SCENARIOS / "highway_cut_in.yaml").read_bytes())
    elif kind == "unreadable":
        p.write_bytes(data)
        p.chmod(0)
    return p


def _drop_to_nobody() -> None:
    os.setgroups([])
    os.setgid(65534)
    os.setuid(65534)


def _interpreters() -> list[str]:
    """This interpreter, and the system's of the same version (a virtual environment's may live where only root
    can go, e.g. under /root)."""
    v = f"{sys.version_info.major}.{sys.version_info.minor}"
    return [sys.executable] + [p for p in (f"/usr/bin/python{v}", f"/usr/local/bin/python{v}") if os.path.isfile(p)]


_UNPRIVILEGED: list = []


def _unprivileged_python():
    """(interpreter, environment) with which user nobody runs radarnode, or None."""
    if _UNPRIVILEGED:
        return _UNPRIVILEGED[0]
    import site
    path = os.pathsep.join([str(ROOT), *site.getsitepackages()])
    found = None
    for exe in _interpreters():
        env = {**os.environ, "PYTHONPATH": path}
        try:
            r = subprocess.run([exe, "-c", "import radarnode.cli.main"], preexec_fn=_drop_to_nobody, cwd="/",
                               capture_output=True, env=env, timeout=60)
        except OSError:
            continue
        if r.returncode == 0:
            found = (exe, env)
            break
    _UNPRIVILEGED.append(found)
    return found


def _run_unprivileged(argv: list[str], home: Path) -> tuple[int, str]:
    """Run as a user that file permissions apply to (root reads any file): as nobody when we are root."""
    exe, env = _unprivileged_python()
    env = {**env, "HOME": str(home), "MPLCONFIGDIR": str(home)}
    r = subprocess.run([exe, "-m", "radarnode", *argv], preexec_fn=_drop_to_nobody, cwd="/",
                       capture_output=True, text=True, timeout=120, env=env)
    return r.returncode, r.stderr


@pytest.fixture(scope="module")
def shared_dir():
    """A directory every user can enter (pytest's tmp_path is root's alone), for the unprivileged runs."""
    d = Path(tempfile.mkdtemp(prefix="radarnode-errors-"))
    d.chmod(0o755)
    yield d
    for p in d.rglob("*"):
        p.chmod(0o755 if p.is_dir() else 0o644)
    shutil.rmtree(d, ignore_errors=True)


def _run_case(capsys, argv: list[str], unprivileged: bool) -> tuple[int, str]:
    if unprivileged and os.geteuid() == 0:
        if _unprivileged_python() is None:
            pytest.skip("as root every file is readable, and user nobody cannot run this interpreter")
        home = Path(tempfile.mkdtemp(prefix="radarnode-home-"))
        home.chmod(0o777)
        try:
            return _run_unprivileged(argv, home)
        finally:
            shutil.rmtree(home, ignore_errors=True)
    rc, _, err = cli(capsys, *argv)
    return rc, err


SCENARIO_COMMANDS = {
    "run": lambda sc, d: ["run", sc, "--fast", "--duration", "0.1", "--quiet"],
    "node": lambda sc, d: ["node", sc, "-i", "virtual", "-c", f"errors-{uuid.uuid4().hex}", "--fast", "--duration", "0.1"],
    "log": lambda sc, d: ["log", sc, "-o", f"{d}/out.blf", "--duration", "0.1"],
    "image": lambda sc, d: ["image", sc, "-o", f"{d}/out.png"],
    "report": lambda sc, d: ["report", sc, "--junit", f"{d}/out.xml"],
    "export": lambda sc, d: ["export", f"{d}/good.blf", "-o", f"{d}/out.mcap", "--scenario", sc],
}


@pytest.mark.parametrize("command,kind", [(c, k) for c in sorted(SCENARIO_COMMANDS) for k in FILE_KINDS]
                         # (the scenario reader's own limits: through two commands, every command reads it alike)
                         + [(c, k) for c in ("log", "run") for k in ("recursive-alias", "deep-nesting", "alias-bomb",
                                                                    "huge", "many-values")])
def test_a_bad_scenario_file_is_one_line_naming_it_exit_1(capsys, logs, shared_dir, command, kind):
    if command in ("image", "export"):
        pytest.importorskip("matplotlib" if command == "image" else "foxglove")
    d = shared_dir / f"sc-{command}-{kind}"
    d.mkdir()
    d.chmod(0o777)                  # the outputs' directory is writable for the unprivileged runs too
    shutil.copy(logs[".blf"], d / "good.blf")
    (d / "good.blf").chmod(0o644)
    path = _bad_scenario(d, kind)
    before = sorted(x.name for x in d.iterdir())
    rc, err = _run_case(capsys, SCENARIO_COMMANDS[command](str(path), d), kind == "unreadable")
    line = one_error_line(err)
    assert rc == 1, err
    assert line.startswith(f"error: {path}"), line
    assert sorted(x.name for x in d.iterdir()) == before          # no output, not even a temporary one


LOG_COMMANDS = {
    "decode": (lambda log, d: ["decode", log, "-o", f"{d}/out.jsonl", "--format", "json"], "out.jsonl"),
    "export": (lambda log, d: ["export", log, "-o", f"{d}/out.mcap"], "out.mcap"),
}


@pytest.mark.parametrize("suffix", [".blf", ".log"])
@pytest.mark.parametrize("kind", FILE_KINDS)
@pytest.mark.parametrize("command", sorted(LOG_COMMANDS))
def test_a_bad_log_file_is_one_line_naming_it_exit_1(capsys, logs, shared_dir, command, kind, suffix):
    if command == "export":
        pytest.importorskip("foxglove")
    d = shared_dir / f"log-{command}-{kind}{suffix}"
    d.mkdir()
    d.chmod(0o777)
    path = _bad_log(d, kind, logs[suffix], suffix)
    before = sorted(x.name for x in d.iterdir())
    make, output = LOG_COMMANDS[command]
    rc, err = _run_case(capsys, make(str(path), d), kind == "unreadable")
    errors = [x for x in err.splitlines() if x.startswith("error:")]
    assert "Traceback" not in err and len(errors) == 1 and err.strip().splitlines()[-1] == errors[0], err
    line = errors[0]
    assert rc == 1 and line.startswith("error: argument ") and repr(str(path)) in line, err
    after = sorted(x.name for x in d.iterdir())
    if "is damaged" in line:
        # what was readable is decoded and written, complete; the error says where the damage starts
        assert kind in ("truncated", "corrupted", "not-utf8") and "first bad record at" in line, line
        assert after == sorted(before + [output]), (line, after)
    else:
        assert after == before and len(err.strip().splitlines()) == 1, (line, after)


OUTPUT_COMMANDS = {
    "log": (lambda out: ["log", SCENARIO, "-o", out, "--duration", "0.1"], "out.blf", "--output"),
    "decode": (lambda out: ["decode", "LOG", "-o", out], "out.txt", "--output"),
    "export": (lambda out: ["export", "LOG", "-o", out], "out.mcap", "--output"),
    "image": (lambda out: ["image", SCENARIO, "-o", out], "out.png", "--output"),
    "report-junit": (lambda out: ["report", SCENARIO, "--junit", out], "out.xml", "--junit"),
    "report-plots": (lambda out: ["report", SCENARIO, "--plots", out], "plots", "--plots"),
}


@pytest.mark.parametrize("kind", ["missing-directory", "a-directory", "unwritable-directory", "a-file"])
@pytest.mark.parametrize("command", sorted(OUTPUT_COMMANDS))
def test_an_output_that_cannot_be_written_is_one_line_exit_1_before_the_work(capsys, logs, shared_dir, command,
                                                                             kind):
    if command == "export":
        pytest.importorskip("foxglove")
    if command.startswith("image") or command == "report-plots":
        pytest.importorskip("matplotlib")
    make, name, option = OUTPUT_COMMANDS[command]
    if kind == "a-file" and command != "report-plots":
        pytest.skip("only --plots wants a directory")
    if kind == "missing-directory" and command == "report-plots":
        pytest.skip("--plots creates the directory it is given")
    d = shared_dir / f"out-{command}-{kind}"
    d.mkdir()
    d.chmod(0o755)
    shutil.copy(logs[".blf"], d / "in.blf")
    (d / "in.blf").chmod(0o644)
    if kind == "missing-directory":
        out = d / "no" / "such" / name
    elif kind == "a-directory":
        out = d / name
        out.mkdir()
        if command == "report-plots":
            pytest.skip("--plots wants a directory")
    elif kind == "unwritable-directory":
        sub = d / "ro"
        sub.mkdir()
        sub.chmod(0o555)
        out = sub / name
    else:
        out = d / name
        out.write_text("a file")
    argv = [str(d / "in.blf") if a == "LOG" else a for a in make(str(out))]
    before = sorted(str(x.relative_to(d)) for x in d.rglob("*"))
    rc, err = _run_case(capsys, argv, kind == "unwritable-directory")
    line = one_error_line(err)
    assert rc == 1, err
    assert line.startswith(f"error: option {option}: ") and repr(str(out)) in line, line
    assert sorted(str(x.relative_to(d)) for x in d.rglob("*")) == before


@pytest.mark.parametrize("command", ["log", "decode"])
def test_an_output_through_a_symlink_replaces_the_file_it_points_to_not_the_link(capsys, logs, tmp_path, command):
    # an independent tester's finding: the temporary file was renamed over the link itself
    make, name, _ = OUTPUT_COMMANDS[command]
    target = tmp_path / f"real-{name}"
    target.write_text("old")
    link = tmp_path / name
    link.symlink_to(target.name)
    argv = [str(logs[".blf"]) if a == "LOG" else a for a in make(str(link))]
    assert main(argv) == 0, capsys.readouterr().err
    assert link.is_symlink() and os.readlink(link) == target.name
    assert target.read_bytes() != b"old" and target.stat().st_size > 100


def test_an_output_that_is_a_device_or_a_fifo_is_written_into_not_replaced(capsys, logs, tmp_path):
    # -o /dev/null (a device node) and -o FIFO (a reader at its other end) take the output; neither is replaced by a
    # regular file (an independent tester's finding: as root, -o /dev/full replaced the real /dev/full)
    import threading
    null_link = tmp_path / "devnull.txt"
    null_link.symlink_to("/dev/null")
    assert main(["decode", str(logs[".blf"]), "-o", str(null_link)]) == 0, capsys.readouterr().err
    assert null_link.is_symlink() and Path("/dev/null").is_char_device()
    fifo = tmp_path / "fifo.txt"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    assert main(["decode", str(logs[".blf"]), "-o", str(fifo)]) == 0, capsys.readouterr().err
    reader.join(10)
    assert fifo.is_fifo() and got and got[0].count(b"\n") > 10


@pytest.mark.skipif(not Path("/dev/full").is_char_device(), reason="needs /dev/full (Linux): a device that is always full")
def test_a_full_device_is_one_error_line_naming_the_option_and_file(capsys, logs):
    rc = main(["decode", str(logs[".blf"]), "-o", "/dev/full"])
    line = one_error_line(capsys.readouterr().err)
    assert rc == 1 and line.startswith("error: option --output: cannot write '/dev/full': ") and "space" in line
    assert Path("/dev/full").is_char_device()


def test_a_signal_level_cube_larger_than_memory_allows_is_refused_before_the_run(capsys, tmp_path):
    """mimo12 with 8192 chirps of 8192 samples (both within the loader's 1…65536) at the signal level: a 12-GiB
    cube, which failed with numpy's MemoryError and a 60-line traceback (an independent tester's finding). The cube's
    size is checked against the machine's memory (an eighth of it) before the run: one line naming the overrides
    and the size, exit 1, no file. Every shipped preset's cube passes, in both precisions."""
    from radarnode.radar.presets import PRESETS
    from radarnode.radar.signal_model import check_cube_memory
    for preset in PRESETS.values():
        for dtype in ("complex64", "complex128"):
            check_cube_memory(preset, dtype)
    sc = tmp_path / "big.yaml"
    # (a cycle of 0.3 s: the 8192 chirps take 246 ms, which a 72-ms cycle refuses first)
    sc.write_text("name: big\nduration_s: 0.4\nseed: 1\nfidelity: signal\n"
                  "radar: {preset: mimo12, overrides: {num_chirps: 8192, num_samples: 8192}}\n"
                  "cycle_period_s: 0.3\nego: {speed_mps: 20.0}\nactors: []\n")
    out = tmp_path / "x.blf"
    assert main(["log", str(sc), "-o", str(out)]) == 1
    line = one_error_line(capsys.readouterr().err)
    assert "radar.overrides" in line and "8192 chirps" in line and "12.0 GiB" in line
    assert not out.exists() and not list(tmp_path.glob("*.blf*"))
    # … naming the file and the line of its overrides, and in a report of several scenarios before any runs (it named
    # neither, after the rows of the scenarios before it: an independent tester's finding)
    assert line.startswith(f"error: {sc}:5: radar.overrides: a signal-level frame"), line
    assert main(["report", str(SCENARIOS / "stopped_vehicle.yaml"), str(sc)]) == 1
    got = capsys.readouterr()
    assert got.out == "" and one_error_line(got.err).startswith(f"error: {sc}:5: radar.overrides"), got


def test_out_of_memory_during_a_run_is_one_line(capsys, tmp_path, monkeypatch):
    """What the checks before a run cannot foresee (the machine's memory taken by something else meanwhile): numpy's
    MemoryError is one line naming the command, exit 1, no partial file."""
    from radarnode.radar import models

    def starved(*args, **kwargs):
        raise MemoryError("Unable to allocate 12.0 GiB")
    monkeypatch.setattr(models.ObjectModel, "step", starved)
    out = tmp_path / "x.blf"
    assert main(["log", SCENARIO, "-o", str(out), "--duration", "1"]) == 1
    line = one_error_line(capsys.readouterr().err)
    assert line.startswith("error: log: out of memory") and not out.exists() and not list(tmp_path.glob("*.blf*"))


@pytest.mark.parametrize("share, refused", [(0.99, False), (1.0, False), (1.01, True), (2.0, True)])
def test_the_cube_memory_check_refuses_just_above_its_share(monkeypatch, share, refused):
    """CUBE_MEMORY_SHARE = 1/8 of the machine's memory: a cube just below and at it passes, just above and at twice
    it is refused (the machine's memory set so that mimo12's complex128 cube is ``share`` of the allowed size)."""
    from radarnode.errors import ConfigError
    from radarnode.radar.presets import PRESETS
    from radarnode.radar import signal_model
    p = PRESETS["mimo12"]
    need = p.num_virtual * p.num_chirps * signal_model.num_range_samples(p) * 16
    total = need / (share * signal_model.CUBE_MEMORY_SHARE)
    monkeypatch.setattr(os, "sysconf", lambda name: 1 if name == "SC_PAGE_SIZE" else int(round(total)))
    if refused:
        with pytest.raises(ConfigError, match="radar.overrides"):
            signal_model.check_cube_memory(p, "complex128")
    else:
        signal_model.check_cube_memory(p, "complex128")


def test_fidelity_auto_on_a_one_channel_radar_names_the_option_or_the_field(capsys, tmp_path):
    """``auto`` cannot render a scanning radar of one channel: ``--fidelity auto`` names the option and the radar;
    ``fidelity: auto`` in the file names its line, whatever the command line asks (it named neither: an independent
    tester's finding)."""
    sc = tmp_path / "ka.yaml"
    sc.write_text("name: ka\nduration_s: 1.0\nseed: 1\nradar: {preset: scanning_ka}\n"
                  "actors:\n  - {id: a, class: car, x_m: 40.0}\n", encoding="utf-8")
    for cmd in (["run", sc, "--fast"], ["report", sc]):
        rc, _, err = cli(capsys, *cmd, "--fidelity", "auto")
        assert rc == 2 and "option --fidelity: value 'auto' is not allowed with preset scanning_ka of radar" \
            in one_error_line(err), cmd
    sc.write_text(sc.read_text(encoding="utf-8") + "fidelity: auto\n", encoding="utf-8")
    rc, _, err = cli(capsys, "run", sc, "--fast")
    assert rc != 0 and "ka.yaml:7: field 'fidelity': value 'auto' is not allowed" in one_error_line(err)
    sc.write_text(sc.read_text(encoding="utf-8").replace("fidelity: auto", "fidelity: object"), encoding="utf-8")
    rc, _, err = cli(capsys, "run", sc, "--fast", "--duration", "0.2")
    assert rc == 0, err


def test_plots_below_a_file_names_the_file(tmp_path, capsys):
    # "(it is a file)" was said of a name that did not exist, whose parent was the file (a tester's finding)
    pytest.importorskip("matplotlib")
    (tmp_path / "afile").write_text("x")
    rc = main(["report", SCENARIO, "--plots", str(tmp_path / "afile" / "sub")])
    err = capsys.readouterr().err.strip()
    assert rc == 1 and err == (f"error: option --plots: value {str(tmp_path / 'afile' / 'sub')!r} is not allowed; "
                               f"expected a directory ({str(tmp_path / 'afile')!r} above it is a file)"), err


@pytest.mark.skipif(not Path("/proc/self").is_dir(), reason="needs /proc (Linux): a directory that takes no file")
def test_junit_into_a_directory_that_takes_no_file_fails_before_the_runs(capsys):
    # /proc passed the permission check and failed after every run (a tester's finding)
    import time
    t0 = time.monotonic()
    rc = main(["report", SCENARIO, "--junit", "/proc/x.xml"])
    err = capsys.readouterr().err.strip()
    assert rc == 1 and err.startswith("error: option --junit: cannot write '/proc/x.xml': "), err
    assert time.monotonic() - t0 < 5.0


def test_every_radars_cube_is_checked_before_a_report_runs_and_image_names_the_file(capsys, tmp_path):
    # the second radar's too-large cube was found after the first scenario's runs (rows printed), and image's refusal
    # named no file (a tester's findings)
    ok = SCENARIOS / "stopped_vehicle.yaml"
    big = tmp_path / "bigm.yaml"
    big.write_text("name: bigm\nduration_s: 0.6\nseed: 1\ncycle_period_s: 0.3\nfidelity: signal\nradars:\n"
                   "  - {preset: srr_corner, sensor_id: 0}\n  - preset: mimo12\n    sensor_id: 1\n"
                   "    overrides: {num_chirps: 8192, num_samples: 8192}\nactors:\n  - {id: lead, class: car, x_m: 20}\n")
    assert main(["report", str(ok), str(big)]) == 1
    got = capsys.readouterr()
    assert got.out == "" and one_error_line(got.err).startswith(f"error: {big}:10: radars[1].overrides: a signal-level "
                                                                "frame of 12 channels × 8192 chirps"), got
    one = tmp_path / "big.yaml"
    one.write_text("name: big\nduration_s: 0.4\nseed: 1\nfidelity: signal\n"
                   "radar: {preset: mimo12, overrides: {num_chirps: 8192, num_samples: 8192}}\n"
                   "cycle_period_s: 0.3\nego: {speed_mps: 20.0}\nactors: []\n")
    assert main(["image", str(one), "-o", str(tmp_path / "big.png")]) == 1
    assert one_error_line(capsys.readouterr().err).startswith(f"error: {one}:5: radar.overrides: a signal-level frame")
    assert not (tmp_path / "big.png").exists()
