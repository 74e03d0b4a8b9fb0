"""``radarnode report SCENARIO…``: run scenarios through node, consumer and ECU and judge them.

Per scenario: warning time, TTC at the warning (constant-speed TTC to the
``ecu.expect.lead`` actor, as the NHTSA confirmation tests define it), the
minimum TTC and gap, peak deceleration and jerk of the ego (closed loop), the
final time gap, and pass or fail against the scenario's ``ecu.expect``.
``--seeds N`` repeats each scenario with seeds 1…N and counts the passes; without it, each scenario runs once,
with its own ``seed``.
``--junit FILE`` also writes JUnit XML (one test suite per scenario, one test
case per scenario and seed, the failed expectations as the failure message)
for a CI system to render; ``--plots DIR`` draws one PNG per scenario and seed
(gap, relative speed, TTC, ego speed and acceleration over time, with the FCW
and braking instants and the pass/fail limits; needs matplotlib). Files are
written under a temporary name and renamed when complete. The runs are
independent: they go to all local cores (``--workers``), or to a Dask cluster
(``--scheduler tcp://host:8786``, ``--dask-local N``), with the same results
in the same order wherever they run.
"""

from __future__ import annotations

import argparse
import collections
import contextlib
import dataclasses
import datetime
import math
import os
import socket
import sys
import time
import xml.etree.ElementTree as ET
from pathlib import Path

from radarnode.cli import options
from radarnode.cli.common import add_scale_out_arguments, atomic_output, atomic_path, check_scale_out, plot_dir, \
    plots_into, progress, require_matplotlib, with_doa
from radarnode.consumer.evaluate import simulate
from radarnode.errors import FieldError, FileError, Terminated, UsageError
from radarnode.radar.setup import load_scenario


def add_subparser(sub) -> None:
    p = sub.add_parser("report", help="judge scenarios against their ACC/FCW expectations", description=__doc__)
    p.add_argument("scenarios", nargs="+", help="scenario files")
    p.add_argument("--seeds", type=options.integer(lo=1, hi=10_000), default=None,
                   help="run each scenario with seeds 1..N, N up to 10000 (default: once, with the scenario's own "
                        "seed)")
    p.add_argument("--fidelity", choices=("object", "detection", "signal", "auto"), help="radar model level")
    p.add_argument("--doa", choices=options.DOA_CHOICES,
                   help="angle estimator of the signal chain (super-resolution other than fft: fidelity signal)")
    add_scale_out_arguments(p, "runs")
    p.add_argument("--min-passes", type=options.POSITIVE_COUNT, default=None,
                   help="exit 1 when a scenario passes in fewer seeds than this (default: all of them)")
    p.add_argument("--junit", metavar="FILE", help="also write JUnit XML for a CI system to FILE")
    p.add_argument("--plots", metavar="DIR",
                   help="draw one PNG per scenario and seed into DIR (created if missing; needs matplotlib)")
    for opt, field, what in ECU_OPTIONS:
        # any float here: the ECU settings' own check then names the interval, NaN and ±inf included
        p.add_argument(opt, type=_any_number, default=None, metavar="X",
                       help=f"{what} (overrides the scenario's ecu.{field})")
    p.set_defaults(func=cmd)


def _any_number(text: str) -> float:
    """An argparse type: any float, NaN and ±inf too (the ECU settings refuse them, naming their interval)."""
    try:
        return float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"value {text!r} is not allowed; expected a number") from None


#: report options that set the consumer ECU under test, and the scenario field each overrides
ECU_OPTIONS = (("--fcw-ttc-warn", "fcw_ttc_warn_s", "FCW warns at a TTC at or below X s (0.5–10)"),
               ("--fcw-decel-warn", "fcw_decel_warn_mps2", "FCW warns when avoiding needs X m/s² (1–10)"),
               ("--acc-min-speed", "acc_min_speed_mps", "ACC waits in standby below X m/s (0–30)"),
               ("--path-half-width", "path_half_width_m", "the predicted path's half-width, m (0.5–5)"),
               ("--ecu-latency", "processing_latency_s", "the ECU's processing latency, s (0–0.5)"),
               ("--fcw-stationary-max-speed", "fcw_stationary_max_speed_mps",
                "above X m/s a stationary object never seen moving draws no FCW (0–70)"))


def _simulate_task(task) -> tuple:
    """One report run (a worker's task): the scenario's ECU figures and the seconds it took. The trace's live
    objects (the consumer, the ECU) stay in the worker; its arrays come back."""
    sc, fidelity = task
    t0 = time.perf_counter()
    r = simulate(sc, fidelity=fidelity)
    r.trace = {k: v for k, v in r.trace.items() if k not in ("assembler", "ecu")}
    return r, time.perf_counter() - t0


def _with_ecu_options(sc, args):
    """The scenario with the ECU settings given on the command line; a bad value names the option."""
    changes = {field: getattr(args, opt.lstrip("-").replace("-", "_")) for opt, field, _ in ECU_OPTIONS}
    changes = {k: v for k, v in changes.items() if v is not None}
    if not changes:
        return sc
    try:
        return dataclasses.replace(sc, ecu=dataclasses.replace(sc.ecu, **changes))
    except FieldError as exc:
        opt = next(o for o, f, _ in ECU_OPTIONS if f == exc.field)
        raise UsageError(f"option {opt}: value {exc.value!r} is not allowed; expected {exc.allowed}") from None


def _fmt(v, unit: str, digits: int = 2) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.{digits}f} {unit}"


def _figures(r) -> str:
    return (f"warning at {_fmt(r.warning_time_s, 's')}" + (f" for {r.warned_for}" if r.warned_for else "")
            + f", TTC at warning {_fmt(r.ttc_at_warning_s, 's')}, "
            f"min TTC {_fmt(r.min_ttc_s, 's')}, min gap {_fmt(r.min_gap_m, 'm', 1)}, "
            f"peak decel {_fmt(r.peak_decel_mps2, 'm/s²')}, peak jerk {_fmt(r.peak_jerk_mps3, 'm/s³')}, "
            f"final time gap {_fmt(r.final_time_gap_s, 's')}")


def junit_xml(suites: list[tuple[str, str, list[tuple[object, float]]]], min_passes: dict[str, int]) -> ET.ElementTree:
    """JUnit XML: ``suites`` is [(scenario name, scenario file, [(ScenarioResult, seconds)])]."""
    root = ET.Element("testsuites", name="radarnode report")
    total = failures = 0
    elapsed = 0.0
    stamp = datetime.datetime.now().isoformat(timespec="seconds")
    for name, path, runs in suites:
        n_fail = sum(not r.passed for r, _ in runs)
        n_skip = sum(not r.checked for r, _ in runs)
        secs = sum(s for _, s in runs)
        suite = ET.SubElement(root, "testsuite", name=name, tests=str(len(runs)), failures=str(n_fail),
                              errors="0", skipped=str(n_skip), time=f"{secs:.3f}", timestamp=stamp,
                              hostname=socket.gethostname())
        props = ET.SubElement(suite, "properties")
        ET.SubElement(props, "property", name="scenario_file", value=path)
        # (a run with nothing to check is skipped, not a pass)
        ET.SubElement(props, "property", name="passes", value=str(sum(r.checked and r.passed for r, _ in runs)))
        ET.SubElement(props, "property", name="min_passes", value=str(min_passes[name]))
        for r, s in runs:
            case = ET.SubElement(suite, "testcase", classname=f"radarnode.report.{name}", name=f"{name} seed {r.seed}",
                                 file=path, time=f"{s:.3f}")
            if not r.checked:
                ET.SubElement(case, "skipped", message="nothing to check: the scenario's ecu.expect states no "
                                                       "criterion")
            elif not r.passed:
                fail = ET.SubElement(case, "failure", message="; ".join(r.reasons), type="ExpectationNotMet")
                fail.text = "\n".join(r.reasons) + "\n" + _figures(r)
            ET.SubElement(case, "system-out").text = _figures(r)
        total += len(runs)
        failures += n_fail
        elapsed += secs
    root.set("tests", str(total))
    root.set("failures", str(failures))
    root.set("errors", "0")
    root.set("time", f"{elapsed:.3f}")
    ET.indent(root)
    return ET.ElementTree(root)


def _seeds(args, sc) -> list[int]:
    """The seeds a scenario runs with: 1…N with ``--seeds N`` (``--seeds 1`` is seed 1: it ran the scenario's own
    seed, so a report of one seed and one of several did not share it, an independent tester's finding), else the
    scenario's own ``seed``, once."""
    return list(range(1, args.seeds + 1)) if args.seeds is not None else [sc.seed]


def _runs_each(args) -> int:
    """How many runs each scenario gets (:func:`_seeds`)."""
    return args.seeds if args.seeds is not None else 1


def cmd(args) -> int:
    check_scale_out(args)
    runs_each = _runs_each(args)
    need = runs_each if args.min_passes is None else args.min_passes
    if not 1 <= need <= runs_each:
        raise UsageError(f"option --min-passes: value {need} is not allowed; expected an integer in [1, {runs_each}] "
                         "(at most --seeds)")
    plt = require_matplotlib("option --plots") if args.plots else None
    if args.plots and Path(args.plots).is_file():
        plot_dir(args.plots)                                    # the error for a file, before anything is run
    if args.junit and Path(args.junit).is_dir():
        raise FileError(f"option --junit: value {args.junit!r} is not allowed; expected a file name (it is a "
                        "directory)")
    if args.junit and not Path(args.junit).parent.is_dir():     # fail now, not after the runs
        raise FileError(f"option --junit: cannot write {args.junit!r}: no such directory "
                        f"{str(Path(args.junit).parent)!r}")
    if args.junit and not os.access(Path(args.junit).parent, os.W_OK):
        raise FileError(f"option --junit: cannot write {args.junit!r}: permission denied")
    if args.junit:
        # a file made and removed there: a directory that takes no file whatever its permissions say (/proc, a
        # read-only mount) failed only after every run (an independent tester's finding)
        import tempfile
        try:
            with tempfile.NamedTemporaryFile(dir=Path(args.junit).parent, prefix=".radarnode-probe-"):
                pass
        except OSError as exc:
            raise FileError(f"option --junit: cannot write {args.junit!r}: {exc.strerror or exc}") from None
    scenarios = [(path, with_doa(_with_ecu_options(load_scenario(path), args), args.doa))
                 for path in args.scenarios]                                                    # checked first
    from radarnode.cli.common import check_auto_presets, check_doa_option, check_doa_presets
    from radarnode.radar.levels import check_level
    from radarnode.radar.setup import radar_config, radar_scenarios
    for _, sc in scenarios:
        if args.fidelity == "auto":
            check_auto_presets(sc)                # the option named, before any run (as run, log, node)
        if args.doa is not None:
            check_doa_option(args.doa, args.fidelity or sc.fidelity)
            check_doa_presets(sc, args.doa)
        for one in radar_scenarios(sc):          # every radar (its cube): the second radar's was found after a run
            check_level(args.fidelity or sc.fidelity, radar_config(one).signal, one)
    # the plots' directory is made once everything else is known good, and removed again if the runs fail first
    with plots_into(args.plots) if args.plots else contextlib.nullcontext() as out_dir:
        return _report(args, scenarios, need, plt, out_dir)


def plot_stems(names: list[str]) -> list[str]:
    """Each scenario's plot file stem (``DIR/<stem>_seed<N>.png``), in the order of ``names``: the name's ASCII letters,
    digits and ``._+-``, every other character an underscore, no leading dot, at most 100 characters, and a number
    added where two scenarios come to the same stem, the same name twice included (a name is free text — 'ego 30 m/s,
    truck left' — and a '/' in it wrote into another directory, '../' two levels up; two files of one name wrote one
    plot over the other: an independent tester's findings)."""
    out: list[str] = []
    taken: set[str] = set()
    for name in names:
        stem = "".join(c if c.isascii() and (c.isalnum() or c in "._+-") else "_" for c in name).lstrip(".")[:100]
        stem = stem or "scenario"
        k, unique = 1, stem
        while unique in taken:
            k += 1
            unique = f"{stem}_{k}"
        taken.add(unique)
        out.append(unique)
    return out


def _cell(text: str) -> str:
    """``text`` in a Markdown table cell: a '|' escaped, so that it does not end the cell."""
    return text.replace("|", "\\|")


def _report(args, scenarios, need: int, plt, out_dir: Path | None) -> int:
    runs_each = _runs_each(args)
    bar = progress(len(scenarios) * runs_each, "report", unit="run")
    stems = plot_stems([sc.name for _, sc in scenarios])
    # two files of one scenario name are told apart by their file in the table and the JUnit suites, as the plots
    # are by their stems (two suites and test cases of one name: an independent tester's finding)
    names = collections.Counter(sc.name for _, sc in scenarios)
    labels = [sc.name if names[sc.name] == 1 else f"{sc.name} ({path})" for path, sc in scenarios]

    def out(line: str) -> None:
        bar.write(line, file=sys.stdout) if not bar.disable else print(line, flush=True)

    short = 0
    suites = []
    written = []
    # every (scenario, seed) run is independent: on all local cores, or a Dask cluster, results in this order
    from radarnode.montecarlo.executor import default_workers, iter_tasks
    tasks = [(dataclasses.replace(sc, seed=seed), args.fidelity) for _, sc in scenarios
             for seed in _seeds(args, sc)]
    reported = 0
    try:
        # each row as soon as its run and the runs before it are done: an interrupted report has shown those
        done = iter_tasks(_simulate_task, tasks, workers=args.workers or default_workers(), scheduler=args.scheduler,
                          dask_local=args.dask_local, on_done=lambda: bar.update(1))
        out("| scenario | seed | warning at | TTC at warning | min TTC | min gap | peak decel | peak jerk | "
            "final time gap | result |")
        out("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
        for (path, sc), stem, label in zip(scenarios, stems, labels):
            passes = unchecked = 0
            runs = []
            for seed in _seeds(args, sc):
                run_sc = dataclasses.replace(sc, seed=seed)
                r, seconds = next(done)
                reported += 1
                runs.append((r, seconds))
                passes += r.passed and r.checked
                unchecked += not r.checked
                verdict = ("nothing to check" if not r.checked else "pass" if r.passed
                           else "FAIL: " + "; ".join(r.reasons))
                out(f"| {_cell(label)} | {seed} | {_fmt(r.warning_time_s, 's')} | {_fmt(r.ttc_at_warning_s, 's')} | "
                    f"{_fmt(r.min_ttc_s, 's')} | {_fmt(r.min_gap_m, 'm', 1)} | {_fmt(r.peak_decel_mps2, 'm/s²')} | "
                    f"{_fmt(r.peak_jerk_mps3, 'm/s³')} | {_fmt(r.final_time_gap_s, 's')} | {verdict} |")
                if out_dir is not None:
                    from radarnode.cli.plots import report_figure
                    target = out_dir / f"{stem}_seed{seed}.png"
                    fig = report_figure(run_sc, r, plt)
                    try:
                        with atomic_path(target, "--plots") as tmp:
                            fig.savefig(tmp, dpi=90)
                    except OSError as exc:
                        raise FileError(f"option --plots: cannot write {str(target)!r}: {exc.strerror or exc}") \
                            from None
                    finally:
                        plt.close(fig)
                    written.append(target)
            if unchecked:
                out(f"| {_cell(label)} | | | | | | | | | nothing to check (no criterion in ecu.expect) |")
            elif runs_each > 1:
                out(f"| {_cell(label)} | | | | | | | | | {passes} of {runs_each} seeds pass |")
            short += passes < need and not unchecked
            suites.append((label, str(path), runs))
    except (KeyboardInterrupt, Terminated):
        bar.close()
        # (the plots written so far stay: the line said nothing of them, a tester's finding)
        print(f"report: interrupted after {reported} of {len(tasks)} runs" + (" (their rows above)" if reported else "")
              + (f"; kept {len(written)} plot{'s' if len(written) != 1 else ''} in {out_dir}" if written else "")
              + ("; no --junit file written" if args.junit else ""), file=sys.stderr)
        raise
    finally:
        bar.close()
    if args.junit:
        tree = junit_xml(suites, {name: need for name, _, _ in suites})
        with atomic_output(args.junit, "--junit", mode="wb") as f:
            tree.write(f, encoding="utf-8", xml_declaration=True)
        cases = sum(len(r) for _, _, r in suites)
        print(f"wrote {args.junit}: {cases} test case{'s' if cases != 1 else ''}", file=sys.stderr)
    if written:
        print(f"wrote {len(written)} plots to {out_dir}", file=sys.stderr)
    return 1 if short else 0
