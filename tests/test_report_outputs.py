"""``report --junit`` (JUnit XML, read back with xml.etree) and ``report --plots``; the pictures' scales and units."""

from __future__ import annotations

import dataclasses
import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest

from tests.conftest import ROOT, SCENARIOS

CLI = [sys.executable, "-m", "radarnode"]
UNIT = re.compile(r", (m|m/s|s|m/s²|°)( \(.*\))?$")


def run(*args, timeout=300, **kw):
    return subprocess.run([*CLI, *args], capture_output=True, text=True, timeout=timeout, cwd=ROOT, **kw)


@pytest.fixture(scope="module")
def strict(tmp_path_factory):
    """nhtsa_lead_stopped with an impossible TTC limit: a scenario that fails for a known reason."""
    text = (SCENARIOS / "nhtsa_lead_stopped.yaml").read_text()
    assert "fcw_ttc_min_s: 2.1" in text
    path = tmp_path_factory.mktemp("strict") / "strict.yaml"
    path.write_text(text.replace("fcw_ttc_min_s: 2.1", "fcw_ttc_min_s: 9.0").replace(
        "name: nhtsa_lead_stopped", "name: strict_lead_stopped"))
    return path


def test_junit_has_a_case_per_scenario_and_seed_and_the_failed_expectation(tmp_path, strict):
    junit = tmp_path / "ci" / "report.xml"
    junit.parent.mkdir()
    plots = tmp_path / "plots"
    r = run("report", str(SCENARIOS / "nhtsa_lead_stopped.yaml"), str(strict), "--seeds", "2", "--min-passes", "1",
            "--junit", str(junit), "--plots", str(plots))
    assert r.returncode == 1, r.stderr                     # strict passes in 0 of 2 seeds
    root = ET.parse(junit).getroot()
    assert root.tag == "testsuites" and root.get("tests") == "4" and root.get("failures") == "2"
    suites = {s.get("name"): s for s in root.findall("testsuite")}
    assert set(suites) == {"nhtsa_lead_stopped", "strict_lead_stopped"}
    good, bad = suites["nhtsa_lead_stopped"], suites["strict_lead_stopped"]
    assert [c.get("name") for c in good.findall("testcase")] == ["nhtsa_lead_stopped seed 1",
                                                                 "nhtsa_lead_stopped seed 2"]
    assert good.get("failures") == "0" and not good.findall("testcase/failure")
    failures = bad.findall("testcase/failure")
    assert len(failures) == 2 and bad.get("failures") == "2"
    # the message is what the table says failed, for the same seed
    for case in bad.findall("testcase"):
        seed = case.get("name").rsplit(" ", 1)[1]
        row = next(line for line in r.stdout.splitlines() if line.startswith(f"| strict_lead_stopped | {seed} |"))
        reason = row.split("FAIL: ")[1].rstrip(" |")
        assert case.find("failure").get("message") == reason
        assert re.fullmatch(r"warning at TTC \d+\.\d\d s < 9\.0 s", reason)
        assert float(case.get("time")) > 0 and case.get("classname") == "radarnode.report.strict_lead_stopped"
    props = {p.get("name"): p.get("value") for p in bad.findall("properties/property")}
    assert props["passes"] == "0" and props["min_passes"] == "1" and props["scenario_file"] == str(strict)
    # one picture per scenario and seed, and nothing half-written
    pngs = sorted(p.name for p in plots.iterdir())
    assert pngs == ["nhtsa_lead_stopped_seed1.png", "nhtsa_lead_stopped_seed2.png",
                    "strict_lead_stopped_seed1.png", "strict_lead_stopped_seed2.png"]
    for p in plots.iterdir():
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and p.stat().st_size > 30_000
    assert sorted(x.name for x in junit.parent.iterdir()) == ["report.xml"]
    assert "wrote 4 plots" in r.stderr and "4 test cases" in r.stderr


def test_report_output_options_are_checked_before_any_run(tmp_path):
    afile = tmp_path / "afile"
    afile.write_text("x")
    r = run("report", str(SCENARIOS / "nhtsa_lead_stopped.yaml"), "--plots", str(afile))
    assert r.returncode == 1 and r.stderr.startswith("error: option --plots: value") and "| nhtsa" not in r.stdout
    r = run("report", str(SCENARIOS / "nhtsa_lead_stopped.yaml"), "--junit", str(tmp_path))
    assert r.returncode == 1 and r.stderr.startswith("error: option --junit: value")
    r = run("report", str(SCENARIOS / "nhtsa_lead_stopped.yaml"), "--junit", str(tmp_path / "no" / "dir.xml"))
    assert r.returncode == 1 and "error: option --junit: cannot write" in r.stderr
    assert sorted(x.name for x in tmp_path.iterdir()) == ["afile"]


def test_report_figure_has_units_limits_and_the_instants(strict):
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from radarnode.cli.plots import instants, report_figure
    from radarnode.consumer.evaluate import simulate
    from radarnode.radar.setup import load_scenario
    sc = load_scenario(strict)
    res = simulate(sc)
    fig = report_figure(sc, res, plt)
    try:
        axes = fig.axes
        assert [a.get_ylabel().split(",")[0] for a in axes] == ["gap", "relative speed", "TTC", "ego speed",
                                                                "acceleration"]
        for a in axes:
            assert UNIT.search(a.get_ylabel()), a.get_ylabel()
        assert axes[-1].get_xlabel() == "time, s"
        ttc_labels = [line.get_label() for line in axes[2].get_lines()]
        assert "limit: warn at TTC ≥ 9.0 s" in ttc_labels
        assert f"TTC at warning {res.ttc_at_warning_s:.2f} s" in ttc_labels
        marks = instants(res)
        assert marks["FCW warning"] == res.warning_time_s is not None
        assert marks["lead braking"] is None and marks["braking"] is None     # a stopped lead, open loop
        vlines = [line.get_xdata()[0] for line in axes[0].get_lines() if line.get_label().startswith("FCW warning")]
        assert vlines == [pytest.approx(res.warning_time_s)]
        assert "FAIL: warning at TTC" in fig._suptitle.get_text()
    finally:
        plt.close(fig)


def test_image_views_carry_colour_bars_in_db_and_units():
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from radarnode.cli.image import Renderer
    from radarnode.radar.setup import load_scenario
    r = Renderer(load_scenario(SCENARIOS / "point_targets_mimo12.yaml"), 2.5)
    frame, bnd = r.step(0.0)
    fig = plt.figure(figsize=(22, 6))
    try:
        r.draw(fig, 0.0, frame, bnd)
        views = [a for a in fig.axes if a.get_title()]
        bars = [a for a in fig.axes if not a.get_title()]
        assert [a.get_title().split(" ")[0] for a in views] == ["range–Doppler", "range–azimuth", "bird's",
                                                              "direct"]
        assert len(bars) == 4 and all("dB" in b.get_ylabel() for b in bars)
        for a in views:
            assert UNIT.search(a.get_xlabel()) and UNIT.search(a.get_ylabel()), (a.get_xlabel(), a.get_ylabel())
            assert a.get_legend() is not None and "detections" in [t.get_text() for t in a.get_legend().get_texts()]
    finally:
        plt.close(fig)


def test_nothing_to_check_is_said_and_skipped_not_passed(tmp_path, capsys):
    import xml.etree.ElementTree as ET
    from radarnode.cli.main import main
    scen = SCENARIOS / "highway_cut_in.yaml"
    junit = tmp_path / "r.xml"
    assert main(["report", str(scen), "--junit", str(junit)]) == 0
    assert "nothing to check" in capsys.readouterr().out
    case = ET.parse(junit).getroot().find(".//testcase")
    assert case.find("skipped") is not None and case.find("failure") is None
    # the suite's pass count says so too (an independent tester: it counted the skipped runs as passes)
    props = {p.get("name"): p.get("value") for p in ET.parse(junit).getroot().iter("property")}
    assert props["passes"] == "0", props



def test_nothing_to_check_is_the_plot_title_too():
    pytest.importorskip("matplotlib")
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from radarnode.cli.plots import report_figure
    from radarnode.consumer.evaluate import simulate
    from radarnode.radar.setup import load_scenario
    sc = load_scenario(SCENARIOS / "highway_cut_in.yaml")
    res = simulate(dataclasses.replace(sc, duration_s=0.5))
    assert not res.checked
    fig = report_figure(sc, res, plt)
    try:
        assert fig._suptitle.get_text().endswith(": nothing to check"), fig._suptitle.get_text()
    finally:
        plt.close(fig)


def test_ecu_settings_from_the_command_line_are_used_and_checked(capsys):
    from radarnode.cli.main import main
    scen = str(SCENARIOS / "nhtsa_lead_stopped.yaml")
    assert main(["report", scen]) == 0
    assert main(["report", scen, "--fcw-ttc-warn", "2.2", "--fcw-decel-warn", "9"]) == 1   # warns too late
    assert "warning at TTC" in capsys.readouterr().out
    assert main(["report", scen, "--fcw-ttc-warn", "20"]) == 2
    assert "option --fcw-ttc-warn: value 20.0 is not allowed" in capsys.readouterr().err


def test_the_stationary_speed_limit_from_the_command_line(capsys):
    from radarnode.cli.main import main
    scen = str(SCENARIOS / "nhtsa_lead_stopped.yaml")                 # 20.1 m/s towards a car never seen moving
    assert main(["report", scen, "--fcw-stationary-max-speed", "20"]) == 1
    assert "no FCW warning" in capsys.readouterr().out
    assert main(["report", scen, "--fcw-stationary-max-speed", "71"]) == 2
    assert "option --fcw-stationary-max-speed: value 71.0 is not allowed; expected a number in [0, 70]" in \
        capsys.readouterr().err


def test_report_runs_scale_out_with_the_same_table_in_the_same_order(capsys, tmp_path):
    """report --seeds on 2 local processes and on a Dask LocalCluster prints what one process prints, and the
    JUnit XML holds the same cases."""
    from radarnode.cli.main import main
    args = [str(SCENARIOS / "nhtsa_lead_stopped.yaml"), str(SCENARIOS / "no_fcw_adjacent_stopped.yaml"),
            "--seeds", "2"]
    tables = {}
    for name, extra in (("one", ["--workers", "1"]), ("two", ["--workers", "2"]), ("dask", ["--dask-local", "2"])):
        if name == "dask":
            pytest.importorskip("dask.distributed")
        junit = tmp_path / f"{name}.xml"
        assert main(["report", *args, *extra, "--junit", str(junit)]) == 0
        tables[name] = capsys.readouterr().out
        cases = [(c.get("classname"), c.get("name")) for c in ET.parse(junit).getroot().iter("testcase")]
        assert len(cases) == 4
    assert tables["one"].count("| pass |") == 4
    assert tables["one"] == tables["two"] == tables["dask"]


def test_report_scale_out_options_are_checked(capsys):
    from radarnode.cli.main import main
    sc = str(SCENARIOS / "nhtsa_lead_stopped.yaml")
    assert main(["report", sc, "--workers", "2", "--dask-local", "2"]) == 2
    assert "option --workers: value 2 is not allowed with --dask-local" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["report", sc, "--scheduler", "http://host:8786"])
    assert "expected a Dask scheduler address such as tcp://host:8786" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["report", sc, "--scheduler", "tcp://127.0.0.1:99999"])              # no such port
    assert "a port 1..65535" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        main(["report", sc, "--workers", "0"])
    assert "option --workers: value 0 is not allowed" in capsys.readouterr().err


def _report_until(tmp_path, rows: int):
    """A report of six detection-level runs in one process, interrupted (SIGINT) once ``rows`` result rows are out."""
    import signal
    plots = tmp_path / "new" / "plots"
    p = subprocess.Popen([*CLI, "report", str(SCENARIOS / "nhtsa_lead_stopped.yaml"), "--seeds", "6", "--workers", "1",
                          "--fidelity", "detection", "--plots", str(plots)], cwd=ROOT, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    lines = [p.stdout.readline(), p.stdout.readline()]          # the table's header: printed before any run ends
    lines += [p.stdout.readline() for _ in range(rows)]
    p.send_signal(signal.SIGINT)
    rest, err = _rest(p, 120)
    return p.returncode, lines + rest.splitlines(), err, plots


def _rest(p: subprocess.Popen, timeout: float) -> tuple[str, str]:
    """What a process whose first lines were read with ``readline`` writes after them, and its stderr, once it ended:
    ``communicate`` reads the pipes' descriptors and would lose what ``readline`` had already buffered."""
    import threading
    err: list[str] = []
    reader = threading.Thread(target=lambda: err.append(p.stderr.read()), daemon=True)
    reader.start()
    rest = p.stdout.read()
    p.wait(timeout=timeout)
    reader.join(timeout=timeout)
    return rest, err[0] if err else ""


def test_report_interrupted_before_a_run_ends_leaves_no_plots_directory_and_says_so(tmp_path):
    status, lines, err, plots = _report_until(tmp_path, 0)
    assert status == 130, err
    assert lines[0].startswith("| scenario | seed |")
    assert "report: interrupted after 0 of 6 runs" in err and "kept" not in err, err
    # the directories --plots made are gone again (an empty one was left behind: an independent tester's finding)
    assert not plots.exists() and not plots.parent.exists()
    assert "Traceback" not in err


def test_report_interrupted_after_some_runs_has_shown_their_rows_and_kept_their_plots(tmp_path):
    status, lines, err, plots = _report_until(tmp_path, 2)
    assert status == 130, err
    rows = [ln for ln in lines if ln.startswith("| nhtsa_lead_stopped | ")]
    done = int(re.search(r"interrupted after (\d+) of 6 runs \(their rows above\)", err).group(1))
    assert 2 <= done < 6 and len(rows) == done, (rows, err)        # each row as its run ended, not all at the end
    pngs = sorted(x.name for x in plots.iterdir())
    assert 1 <= len(pngs) <= done and pngs[0] == "nhtsa_lead_stopped_seed1.png"
    # … and the line says so (it said nothing of them: a tester's finding)
    kept = f"; kept {len(pngs)} plot{'s' if len(pngs) != 1 else ''} in {plots}"
    assert kept in err, err


def test_plot_files_of_any_scenario_name_stay_in_the_plots_directory_and_rows_stay_whole(tmp_path):
    # a '/' in a name wrote the plot into another directory ('../../escaped' two levels above --plots) or failed after
    # the whole run ('a/b'); a '|' ended the row's first cell (an independent tester's findings)
    text = (SCENARIOS / "nhtsa_lead_stopped.yaml").read_text()
    # (a $…$ was TeX to matplotlib: a traceback; two files of one name wrote one plot)
    names = ["../../escaped", "a/b", "a_b", "x | y", "a $\\bad$ b", "a/b"]
    paths = []
    for i, name in enumerate(names):
        path = tmp_path / f"s{i}.yaml"
        path.write_text(text.replace("name: nhtsa_lead_stopped", f"name: '{name}'"))
        paths.append(str(path))
    plots = tmp_path / "deep" / "plots"
    r = run("report", *paths, "--plots", str(plots), "--workers", "1")
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in plots.iterdir()) == ["_.._escaped_seed1.png", "a___bad__b_seed1.png",
                                                         "a_b_2_seed1.png", "a_b_3_seed1.png", "a_b_seed1.png",
                                                         "x___y_seed1.png"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["deep", "s0.yaml", "s1.yaml", "s2.yaml", "s3.yaml",
                                                          "s4.yaml", "s5.yaml"]
    assert "wrote 6 plots" in r.stderr
    rows = [ln for ln in r.stdout.splitlines() if ln.startswith("| ") and "seed" not in ln and "---" not in ln]
    # (the two files named 'a/b' are labelled with their files since 2026-12-07)
    assert [ln.split(" | ")[0] for ln in rows] == ["| ../../escaped", f"| a/b ({paths[1]})", "| a_b", "| x \\| y",
                                                   "| a $\\bad$ b", f"| a/b ({paths[5]})"], rows
    assert all(ln.count(" | ") == 9 for ln in rows)


def test_ctrl_c_on_a_report_with_worker_processes_ends_it_at_once_and_leaves_no_worker(tmp_path):
    # a Ctrl-C reaches the whole process group: a worker that took it while holding the task queue's lock left the
    # command hanging at its exit (6 of 10 interrupted runs after rows came as runs ended, 2 of 10 before; an
    # independent tester's finding). The workers ignore SIGINT; the command stops them and ends with status 130
    import os
    import signal
    import time
    p = subprocess.Popen([*CLI, "report", str(SCENARIOS / "acc_cut_in.yaml"), str(SCENARIOS / "stopped_vehicle.yaml"),
                          "--seeds", "3", "--workers", "2"], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True, start_new_session=True)
    header = [p.stdout.readline(), p.stdout.readline()]
    assert header[0].startswith("| scenario |")
    assert p.stdout.readline().startswith("| acc_cut_in | 1 |")   # the first run is done: both workers are up
    children = [int(x) for x in open(f"/proc/{p.pid}/task/{p.pid}/children").read().split()]
    workers = [c for c in children if "spawn_main" in open(f"/proc/{c}/cmdline").read()]
    assert len(workers) == 2, children                       # the pool's two workers, running
    os.killpg(p.pid, signal.SIGINT)                          # as a terminal's Ctrl-C: every process of the group
    t0 = time.monotonic()
    _, err = _rest(p, 30)
    assert p.returncode == 130, err
    assert time.monotonic() - t0 < 10.0                      # no wait for the runs in progress (seconds each)
    assert "report: interrupted after" in err and "Traceback" not in err
    assert not [c for c in workers if os.path.exists(f"/proc/{c}")]


def _report_with_two_workers():
    """A report of six runs on a pool of two workers, once its first row is out: (process, the lines read so far,
    the two workers' pids)."""
    p = subprocess.Popen([*CLI, "report", str(SCENARIOS / "acc_cut_in.yaml"), str(SCENARIOS / "stopped_vehicle.yaml"),
                          "--seeds", "3", "--workers", "2"], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                         text=True)
    lines = [p.stdout.readline() for _ in range(3)]
    assert lines[2].startswith("| acc_cut_in | 1 |"), lines
    children = [int(x) for x in open(f"/proc/{p.pid}/task/{p.pid}/children").read().split()]
    workers = [c for c in children if "spawn_main" in open(f"/proc/{c}/cmdline").read()]
    assert len(workers) == 2, children
    return p, lines, workers


def test_report_workers_leave_sigint_to_the_command(tmp_path):
    # the pool's workers ignore SIGINT: the command alone decides what a Ctrl-C stops (a worker that took one while
    # holding the task queue's lock hung the command at its exit). SIGINT sent to the workers only changes nothing
    import os
    import signal
    p, lines, workers = _report_with_two_workers()

    def ignores_sigint(pid):        # the kernel's mask of ignored signals: bit SIGINT − 1
        mask = next(ln for ln in open(f"/proc/{pid}/status") if ln.startswith("SigIgn:")).split()[1]
        return bool(int(mask, 16) & (1 << (signal.SIGINT - 1)))

    import time
    deadline = time.monotonic() + 120.0          # a worker still starting (a loaded machine) has not set it yet
    while not all(ignores_sigint(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert all(ignores_sigint(w) for w in workers)
    for w in workers:
        os.kill(w, signal.SIGINT)
    rest, err = _rest(p, 300)
    assert p.returncode == 0, err
    rows = [ln for ln in lines + rest.splitlines() if re.match(r"^\| (acc_cut_in|stopped_vehicle) \| \d \|", ln)]
    assert len(rows) == 6 and "Traceback" not in err, (rows, err)


def test_a_worker_killed_from_outside_ends_the_report_with_one_error_line(tmp_path):
    # (the kernel's out-of-memory killer, a kill -9): concurrent.futures' BrokenProcessPool traceback before
    import os
    import signal
    p, lines, workers = _report_with_two_workers()
    os.kill(workers[0], signal.SIGKILL)
    _, err = _rest(p, 120)
    assert p.returncode == 1, err
    assert err.strip().splitlines()[-1] == ("error: a worker process ended abruptly (killed from outside, or out of "
                                            "memory); expected it to finish: try fewer --workers"), err
    assert "Traceback" not in err
    assert not [c for c in workers if os.path.exists(f"/proc/{c}")]


@pytest.mark.parametrize("sig,delay", [("SIGINT", 0.3), ("SIGINT", 0.8), ("SIGTERM", 0.3), ("SIGTERM", 0.8)])
def test_a_signal_to_the_group_while_the_workers_start_prints_no_traceback(sig, delay):
    # a Ctrl-C (or a SIGTERM to the group) while the pool's workers were starting printed their tracebacks:
    # KeyboardInterrupt in a worker still importing, EOFError in one whose start-up data was cut off (an independent
    # tester's finding); the signals are held while the workers start, and they leave them to the command
    import os
    import signal
    import time
    p = subprocess.Popen([*CLI, "report", str(SCENARIOS / "acc_cut_in.yaml"), "--seeds", "3", "--workers", "2"],
                         cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, start_new_session=True)
    time.sleep(delay)
    os.killpg(p.pid, getattr(signal, sig))
    _, err = p.communicate(timeout=60)
    assert p.returncode in (130, 143), err
    assert "Traceback" not in err and "Error" not in err and "Exception" not in err, err
