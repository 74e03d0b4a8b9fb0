"""radarnode.montecarlo and ``radarnode montecarlo``: seed 001's metrics (eq. 11–14) on hand-made inputs, the
same results on 1 or 2 local processes and on a Dask LocalCluster, no NaN at −20…+60 dB, the CLI's outputs and
its errors."""

from __future__ import annotations

import csv
import json
import math
import sys

import numpy as np
import pytest

from radarnode.errors import UsageError
from radarnode.montecarlo import metrics as mx
from radarnode.montecarlo import sweep as sw
from radarnode.montecarlo.executor import require_dask
from radarnode.montecarlo.seed001 import Point, Setup, estimator_names, run_point
from tests.helpers import cli

SETUP = Setup.from_preset()
#: a small sweep: two SNR points, one Table-2 azimuth, one separation, 12 trials each
SMALL = sw.Sweep(trials=12, seed=7, snr_db=(10.0, 30.0), table2_azimuth_deg=(0.0,), separation_deg=(10.0,))




# ---------------------------------------------------------------------------------------------------------
# metrics

def test_eq11_to_13_on_hand_made_trials():
    # 5 trials, 2 targets at 0° and 10°; trial 3 found only one
    count = np.array([2, 2, 1, 2, 2])
    est = np.array([[1.0, 10.0], [-1.0, 12.0], [50.0, 50.0], [0.0, 8.0], [2.0, 10.0]])
    m = mx.metrics(count, est, [0.0, 10.0])
    assert m.p == pytest.approx(0.8) and m.m == 4
    assert m.rmse_deg is None and m.bias_deg is None            # p must exceed 0.8
    # the figures themselves, without the p rule: target 1 mean 0.5, var (0.25+2.25+0.25+2.25)/3;
    # target 2 mean 10, var (0+4+4+0)/3
    rmse, bias = mx.rmse_bias(est[count == 2], [0.0, 10.0])
    assert rmse == pytest.approx(math.sqrt((5.0 / 3.0 + 8.0 / 3.0) / 2.0))
    assert bias == pytest.approx(math.sqrt((0.5 ** 2 + 0.0) / 2.0))
    assert m.rmse_any_deg == pytest.approx(rmse)
    m = mx.metrics(np.append(count, [2, 2]), np.vstack((est, [[0.5, 10.0], [0.5, 10.0]])), [0.0, 10.0])
    assert m.p == pytest.approx(6 / 7) and m.rmse_deg is not None


def test_gate_counts_far_estimates_as_misses():
    count = np.ones(4, dtype=int)
    est = np.array([[0.1], [-0.2], [30.0], [0.0]])
    assert mx.metrics(count, est, [0.0]).p == 1.0
    assert mx.metrics(count, est, [0.0], gate_deg=5.0).p == 0.75


def test_eq14_and_the_crossing():
    assert mx.normalised(0.3, 0.1) == pytest.approx(3.0)
    assert mx.normalised(None, 0.1) is None and mx.normalised(0.3, 0.0) is None
    # RMSE halves every 6 dB: 0.4, 0.2, 0.1 at 0, 6, 12 dB → 0.1 reached at 12; with a missing first point
    x = np.array([0.0, 6.0, 12.0, 18.0])
    assert mx.crossing(x, [0.4, 0.2, 0.1, 0.05], 0.1) == pytest.approx(12.0)
    assert mx.crossing(x, [0.4, 0.2, 0.1 * math.sqrt(2), 0.1 / math.sqrt(2)], 0.1) == pytest.approx(15.0)
    assert mx.crossing(x, [None, 0.2, 0.15, 0.12], 0.1) is None
    assert mx.crossing(x, [0.05, 0.2, 0.05, 0.05], 0.1) == pytest.approx(6.0 + 6.0 * math.log(2) / math.log(4))


# ---------------------------------------------------------------------------------------------------------
# the experiment

def test_every_estimator_runs_and_nothing_is_nan_from_minus_20_to_60_db():
    names = estimator_names()
    for snr in (-20.0, 60.0):
        for az in ((7.0,), (5.0, 9.0)):
            r = run_point(SETUP, 6, 1, Point("snr", 0, snr, az))
            assert set(r.count) == set(names)
            for n in names:
                assert r.est_deg[n].shape == (6, len(az)) and np.all(np.isfinite(r.est_deg[n])), n
    summary = sw.summarise(SETUP, SMALL, sw.run(SETUP, SMALL))
    json.dumps(summary, allow_nan=False)                       # None where a figure is not given, never NaN


def test_a_point_depends_on_its_key_not_on_what_ran_before():
    p = Point("snr", 3, 15.0, (7.0,))
    a = run_point(SETUP, 8, 5, p, methods=("lcacm", "bs_srr1"))
    run_point(SETUP, 8, 5, Point("snr", 2, 15.0, (7.0,)))
    b = run_point(SETUP, 8, 5, p, methods=("lcacm", "bs_srr1"))
    assert np.array_equal(a.est_deg["lcacm"], b.est_deg["lcacm"])
    c = run_point(SETUP, 8, 5, Point("table2", 3, 15.0, (7.0,)), methods=("lcacm",))
    assert not np.array_equal(a.est_deg["lcacm"], c.est_deg["lcacm"])      # another experiment: another stream


def test_one_or_two_local_processes_give_identical_results():
    one = sw.run(SETUP, SMALL, workers=1)
    two = sw.run(SETUP, SMALL, workers=2)
    assert sw.results_equal(one, two)
    assert len(one) == 4 and sw.finite_everywhere(one)


def test_a_dask_local_cluster_gives_identical_results():
    dd = pytest.importorskip("dask.distributed")
    one = sw.run(SETUP, SMALL, workers=1)
    with dd.LocalCluster(processes=True, n_workers=2, threads_per_worker=1, dashboard_address=None) as cluster:
        # through the scheduler's address, as --scheduler tcp://… does (loopback only)
        on_cluster = sw.run(SETUP, SMALL, scheduler=cluster.scheduler_address)
    assert sw.results_equal(one, on_cluster)


def test_missing_dask_is_a_usage_error_naming_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "dask.distributed", None)
    with pytest.raises(UsageError, match=r"option --scheduler needs dask.distributed.*radarnode\[dask\]"):
        require_dask("--scheduler")


# ---------------------------------------------------------------------------------------------------------
# the command

def test_cli_writes_tables_json_csv_and_plots(capsys, tmp_path):
    pytest.importorskip("matplotlib")
    out_csv, plots = tmp_path / "mc.csv", tmp_path / "png"
    rc, out, err = cli(capsys, "montecarlo", "--experiment", "snr", "resolution", "--trials", "8",
                       "--snr-db", "10,30", "--workers", "1", "--quiet", "--csv", out_csv, "--plots", plots)
    assert rc == 0, err
    assert "### RMSE (eq. 12)" in out and "| lcacm |" in out and "CRB both" in out
    assert "Probability of resolving two targets" in out
    rows = list(csv.DictReader(out_csv.open()))
    assert {r["experiment"] for r in rows} == {"snr", "resolution"}
    assert sorted(p.name for p in plots.iterdir()) == ["montecarlo_bias.png", "montecarlo_p_correct.png",
                                                      "montecarlo_resolution.png", "montecarlo_rmse.png"]
    rc, out, err = cli(capsys, "montecarlo", "--experiment", "table2", "--trials", "4", "--workers", "1", "--json")
    assert rc == 0, err
    doc = json.loads(out)
    assert doc["table2"]["metrics"]["lcacm"]["norm_rmse"] == pytest.approx(1.0)
    assert doc["sweep"]["trials"] == 4


@pytest.mark.parametrize("argv, needle", [
    (["--trials", "1"], "option --trials: value 1 is not allowed; expected an integer"),
    (["--snr-db", "0:10:-1"], "option --snr-db: value '0:10:-1' is not allowed; expected START:STOP:STEP"),
    (["--snr-db", "20,10"], "option --snr-db: value '20,10' is not allowed"),
    (["--snr-db", "nan"], "option --snr-db: value 'nan' is not allowed"),
    (["--snr-db", "0:1000:1"], "option --snr-db: value '0:1000:1' is not allowed"),
    (["--workers", "0"], "option --workers: value 0 is not allowed; expected an integer"),
    (["--azimuth-deg", "70"], "option --azimuth-deg: value 70 is not allowed"),
    (["--experiment", "table3"], "option --experiment: value 'table3' is not allowed; expected one of snr"),
    (["--scheduler", "http://host:8786"], "option --scheduler: value 'http://host:8786' is not allowed; expected "
                                          "a Dask scheduler address"),
    (["--scheduler", "tcp://h:8786", "--dask-local", "2"], "option --dask-local: value 2 is not allowed with "
                                                           "--scheduler"),
    (["--workers", "2", "--dask-local", "2"], "option --workers: value 2 is not allowed with --dask-local"),
])
def test_cli_errors_name_the_option_the_value_and_what_is_allowed(capsys, argv, needle):
    rc, out, err = cli(capsys, "montecarlo", *argv)
    lines = [x for x in err.splitlines() if x.strip()]
    assert rc == 2 and len(lines) == 1 and lines[0].startswith("error: "), err
    assert needle in lines[0], lines[0]
    assert out == ""


def test_cli_without_matplotlib_refuses_plots_before_running(capsys, monkeypatch, tmp_path):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    rc, out, err = cli(capsys, "montecarlo", "--plots", tmp_path / "png", "--trials", "2")
    assert rc == 2 and "option --plots needs matplotlib" in err and "radarnode[image]" in err and out == ""
    assert not (tmp_path / "png").exists()


@pytest.mark.slow
def test_cli_says_when_the_scheduler_cannot_be_reached(capsys):
    # port 1 on the loopback: refused; distributed retries until its 10 s timeout
    rc, out, err = cli(capsys, "montecarlo", "--scheduler", "tcp://127.0.0.1:1", "--trials", "2",
                       "--experiment", "snr", "--snr-db", "10")
    assert rc == 1 and err.startswith("error: option --scheduler: cannot reach the Dask scheduler"), err


def test_cli_refuses_a_directory_for_csv_before_running(capsys, tmp_path):
    rc, out, err = cli(capsys, "montecarlo", "--csv", tmp_path, "--trials", "2")
    assert rc == 1 and err.startswith("error: option --csv:") and "directory" in err and out == ""


#: montecarlo's numeric options: (option, int or float, lowest, highest)
NUMERIC = [("--trials", int, 2, 1_000_000), ("--seed", int, 0, 2**63 - 1), ("--azimuth-deg", float, -40, 40),
           ("--range-m", float, 2, 30), ("--range-sigma-m", float, 0, 1), ("--resolution-snr-db", float, -60, 100),
           ("--workers", int, 1, 1024), ("--dask-local", int, 1, 256)]
VALUES = ("nan", "inf", "-inf", "-1", "0", "1e300", "99999999999999999999", "1.5", "abc", "")


def _allowed(text, kind, lo, hi):
    try:
        v = int(text, 10) if kind is int else float(text)
    except ValueError:
        return False
    return math.isfinite(v) and lo <= v <= hi


@pytest.mark.parametrize("option, kind, lo, hi, value", [(*o, v) for o in NUMERIC for v in VALUES])
def test_every_numeric_option_refuses_what_it_does_not_allow(capsys, option, kind, lo, hi, value):
    from radarnode.cli.main import build_parser
    argv = ["montecarlo", f"{option}={value}"]
    if _allowed(value, kind, lo, hi):
        build_parser().parse_args(argv)                         # parses; a run is not what this test is about
        return
    rc, out, err = cli(capsys, *argv)
    lines = [x for x in err.splitlines() if x.strip()]
    assert rc == 2 and len(lines) == 1, err
    assert f"option {option}" in lines[0] and "is not allowed" in lines[0] and "expected" in lines[0], lines[0]
