"""Habits of the ecosystem: ``python -m radarnode``, global options on either side of the subcommand, a tqdm
progress bar only on a terminal, and the bit rate from python-can's configuration."""

from __future__ import annotations

import fcntl
import os
import pty
import select
import struct
import subprocess
import sys
import termios

import pytest

from radarnode.cli.common import Bitrate, resolve_bitrate
from radarnode.errors import ConfigError
from tests.conftest import ROOT, SCENARIOS

CLI = [sys.executable, "-m", "radarnode"]
SCENARIO = str(SCENARIOS / "stopped_vehicle.yaml")


def run(*args, timeout=120, **kw):
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=timeout, cwd=ROOT, **kw)


def test_python_dash_m_radarnode_is_the_command():
    r = run("--version")
    assert r.returncode == 0 and r.stdout.startswith("radarnode ")
    r = run("--help")
    assert r.returncode == 0 and "decode" in r.stdout and "report" in r.stdout


@pytest.fixture(scope="module")
def small_log(tmp_path_factory):
    out = tmp_path_factory.mktemp("habits") / "small.log"
    r = run("log", SCENARIO, "-o", str(out), "--duration", "0.5")
    assert r.returncode == 0, r.stderr
    return out


@pytest.mark.parametrize("where", ["before", "after"])
def test_verbose_before_and_after_the_subcommand(small_log, where):
    quiet = run("decode", str(small_log), "--summary")
    assert quiet.returncode == 0 and "INFO" not in quiet.stderr
    args = ["-v", "decode", str(small_log), "--summary"] if where == "before" else \
        ["decode", str(small_log), "--summary", "-v"]
    r = run(*args)
    assert r.returncode == 0, r.stderr
    assert "INFO radarnode.cli.main: radarnode" in r.stderr and "DEBUG" not in r.stderr
    args = ["-vv", "decode", str(small_log)] if where == "before" else ["decode", str(small_log), "-vv"]
    r = run(*args)
    assert "DEBUG radarnode.cli.main: options:" in r.stderr


def test_verbose_counts_add_up_across_the_subcommand(small_log):
    r = run("-v", "decode", str(small_log), "--summary", "-v")
    assert "DEBUG radarnode.cli.main: options:" in r.stderr


@pytest.mark.parametrize("where", ["before", "after"])
def test_debug_before_and_after_the_subcommand(where):
    plain = run("decode", "/nonexistent/file.blf")
    assert plain.returncode == 1 and plain.stderr.startswith("error: argument FILE") and "Traceback" not in plain.stderr
    args = ["--debug", "decode", "/nonexistent/file.blf"] if where == "before" else \
        ["decode", "/nonexistent/file.blf", "--debug"]
    r = run(*args)
    assert r.returncode != 0 and "Traceback" in r.stderr and "FileError: argument FILE" in r.stderr


def _run_on_a_terminal(tmp_path, *args, timeout=120, stdout_too=False):
    """Run with stderr on a pseudo-terminal (stdout to a file, or to the terminal too with ``stdout_too``) and
    return (rc, stdout, what the terminal showed)."""
    stdout = tmp_path / "stdout.txt"
    master, slave = pty.openpty()
    fcntl.ioctl(slave, termios.TIOCSWINSZ, struct.pack("HHHH", 24, 100, 0, 0))    # a 100-column terminal
    with stdout.open("wb") as f:
        p = subprocess.Popen([*CLI, *args], stdout=slave if stdout_too else f, stderr=slave, cwd=ROOT)
    os.close(slave)
    shown = b""
    while True:
        ready, _, _ = select.select([master], [], [], timeout)
        if not ready:
            p.kill()
            raise TimeoutError(shown)
        try:
            chunk = os.read(master, 4096)
        except OSError:              # the child closed the terminal
            break
        if not chunk:
            break
        shown += chunk
    p.wait(timeout=timeout)
    os.close(master)
    return p.returncode, stdout.read_text(), shown.decode(errors="replace")


def test_progress_bar_on_a_terminal_only(tmp_path):
    out = tmp_path / "bar.blf"
    rc, _, shown = _run_on_a_terminal(tmp_path, "log", SCENARIO, "-o", str(out), "--duration", "3")
    assert rc == 0, shown
    assert "logging stopped_vehicle" in shown and "cycle" in shown and "\r" in shown
    assert "/41 [" in shown             # the total (41 cycles of 72 ms) is known: a bar, not just a count
    piped = run("log", SCENARIO, "-o", str(tmp_path / "piped.blf"), "--duration", "3")
    assert piped.returncode == 0
    assert "logging stopped_vehicle" not in piped.stderr and "\r" not in piped.stderr
    # decode: the bar goes to the terminal, the JSON on stdout stays clean
    rc, stdout, shown = _run_on_a_terminal(tmp_path, "decode", str(out), "--format", "json")
    assert rc == 0 and "decoding" in shown and "frame" in shown
    assert stdout.startswith("{") and "decoding" not in stdout and "\r" not in stdout


@pytest.mark.parametrize("fmt", ["json", "csv", "text"])
def test_no_progress_bar_among_records_on_a_terminal_stdout(tmp_path, fmt):
    """decode writing its records to a terminal: no bar redrawn in the middle of them (they show the progress)."""
    out = tmp_path / "p.blf"
    assert run("log", SCENARIO, "-o", str(out), "--duration", "1").returncode == 0
    rc, _, shown = _run_on_a_terminal(tmp_path, "decode", str(out), "--format", fmt, stdout_too=True)
    assert rc == 0, shown
    assert "frame/s" not in shown and "decoding p.blf:" not in shown, shown[:2000]
    # with -o the records go to the file: the bar is back on the terminal
    rc, _, shown = _run_on_a_terminal(tmp_path, "decode", str(out), "--format", fmt, "-o",
                                      str(tmp_path / f"x.{fmt if fmt != 'text' else 'txt'}"), stdout_too=True)
    assert rc == 0 and "decoding" in shown, shown


def test_bit_rate_from_the_command_line_python_can_config_or_scenario(monkeypatch, tmp_path):
    for var in ("CAN_BITRATE", "CAN_CONFIG"):
        monkeypatch.delenv(var, raising=False)
    monkeypatch.setenv("HOME", str(tmp_path))              # ~/can.conf is python-can's user config file
    import can.util
    monkeypatch.setattr(can.util, "CONFIG_FILES", ["~/can.conf"])
    assert resolve_bitrate(None, 500_000) == Bitrate(500_000, "scenario radar.bitrate")
    (tmp_path / "can.conf").write_text("[default]\ninterface = virtual\nbitrate = 250000\n")
    assert resolve_bitrate(None, 500_000) == Bitrate(250_000, f"python-can config file {tmp_path}/can.conf")
    monkeypatch.setenv("CAN_CONFIG", '{"bitrate": 125000}')
    assert resolve_bitrate(None, 500_000) == Bitrate(125_000, "python-can environment CAN_CONFIG")
    monkeypatch.setenv("CAN_BITRATE", "1000000")
    b = resolve_bitrate(None, 500_000)
    assert b == Bitrate(1_000_000, "python-can environment CAN_BITRATE")
    assert str(b) == "1000000 bit/s (python-can environment CAN_BITRATE)"
    assert resolve_bitrate(83_333, 500_000) == Bitrate(83_333, "command line -b/--bitrate")
    assert resolve_bitrate(None, 500_000, use_can_config=False) == Bitrate(500_000, "scenario radar.bitrate")
    monkeypatch.setenv("CAN_BITRATE", "fast")
    with pytest.raises(ConfigError, match=r"python-can environment CAN_BITRATE: bit rate value 'fast' is not "
                                          r"allowed; expected an integer 10000\.\.1000000 bit/s"):
        resolve_bitrate(None, 500_000)


def test_log_says_which_bit_rate_its_budget_used(tmp_path):
    env = {**os.environ, "CAN_BITRATE": "250000"}
    r = run("log", SCENARIO, "-o", str(tmp_path / "a.log"), "--duration", "0.5", env=env)
    assert r.returncode == 0
    assert "bus-load budget 80 % of 500000 bit/s (scenario radar.bitrate)" in r.stderr   # log opens no bus
    r = run("log", SCENARIO, "-o", str(tmp_path / "b.log"), "--duration", "0.5", "-b", "125000")
    assert "bus-load budget 80 % of 125000 bit/s (command line -b/--bitrate)" in r.stderr
    r = run("log", SCENARIO, "-o", str(tmp_path / "c.log"), "--duration", "0.5", "-b", "5")
    assert r.returncode == 2
    assert r.stderr.strip() == ("error: option -b/--bitrate: value 5 is not allowed; expected an integer in "
                                "[10000, 1000000] bit/s")


def test_node_takes_its_budget_bit_rate_from_python_can_configuration(monkeypatch, capsys):
    from radarnode.cli.main import main
    monkeypatch.setenv("CAN_BITRATE", "250000")
    scen = str(SCENARIOS / "highway_cut_in.yaml")
    assert main(["node", scen, "-i", "virtual", "-c", "habits-bitrate", "--fast", "--duration", "0.3"]) == 0
    assert "of 250000 bit/s (python-can environment CAN_BITRATE)" in capsys.readouterr().err
    assert main(["node", scen, "-i", "virtual", "-c", "habits-bitrate", "--fast", "--duration", "0.3",
                 "-b", "125000"]) == 0
    assert "of 125000 bit/s (command line -b/--bitrate)" in capsys.readouterr().err


@pytest.mark.parametrize("args", [
    ["log", SCENARIO, "-o", "a.txt"],
    ["image", SCENARIO, "-o", "x.png", "--time", "99"],
    ["export", "nosuch.log", "-o", "x.blf"],
    ["consume", "-i", "nosuch", "-c", "x"],
])
def test_debug_keeps_the_exit_status_of_a_usage_error(tmp_path, args):
    plain = subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert plain.returncode == 2, plain.stderr
    r = subprocess.run([*CLI, *args, "--debug"], capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 2 and "Traceback" in r.stderr, r.stderr


def test_a_udp_multicast_bus_is_named_by_interface_and_group():
    """python-can leaves udp_multicast's channel_info at "unknown": node and consume say interface and group."""
    group = "239.74.163.2"
    r = run("node", SCENARIO, "-i", "udp_multicast", "-c", group, "--fast", "--duration", "0.2")
    assert r.returncode == 0, r.stderr
    assert f"on udp_multicast channel {group}," in r.stderr and "unknown" not in r.stderr
    r = run("consume", "-i", "udp_multicast", "-c", group, "--timeout", "0.2")
    assert r.returncode == 0 and f"listening on udp_multicast channel {group}" in r.stderr, r.stderr


def test_run_takes_its_bit_rate_as_node_does_and_names_the_source(monkeypatch):
    env = {k: v for k, v in os.environ.items() if k not in ("CAN_BITRATE", "CAN_CONFIG")}
    r = run("run", SCENARIO, "--fast", "--quiet", "--duration", "0.2", env={**env, "CAN_BITRATE": "250000"})
    assert r.returncode == 0, r.stderr
    assert "of 250000 bit/s (python-can environment CAN_BITRATE)" in r.stdout, r.stdout
    r = run("run", SCENARIO, "--fast", "--quiet", "--duration", "0.2", "-b", "125000", env=env)
    assert r.returncode == 0 and "of 125000 bit/s (command line -b/--bitrate)" in r.stdout, r.stderr + r.stdout
    r = run("run", SCENARIO, "--fast", "--quiet", "--duration", "0.2", "-b", "5", env=env)
    assert r.returncode == 2 and r.stderr.startswith("error: option -b/--bitrate: value 5 is not allowed"), r.stderr
