"""``radarnode montecarlo``: seed 001's Monte Carlo evaluation of the direction-of-arrival estimators.

Two ``srr_corner`` radars 1.46 m apart, each turned 45° (seed 001); one snapshot per radar; LC-ACM over both
radars against beam scanning and Capon on each radar and every estimator of ``radarnode.dsp.subspace``.
Experiments: ``snr`` — probability of the correct number of targets (eq. 11), RMSE (eq. 12) and bias (eq. 13)
of one target at 7° against SNR, with the Cramér–Rao bound and the SNR where each RMSE reaches 0.1°;
``table2`` — seed 001's Table 2 at 15 dB, averaged over azimuths, normalised to LC-ACM (eq. 14);
``resolution`` — the probability of resolving two targets against their separation; ``timing`` — µs per
estimate (medians), unitary against complex MUSIC. 500 trials a point by default.

The points run on all local cores (``--workers``), or on a Dask cluster (``--scheduler tcp://host:8786``, or
``--dask-local N`` for a cluster of N processes on this machine); the results are bit-identical for the same
``--seed`` whatever runs them. Tables go to standard output (``--json``: one JSON document instead),
``--csv FILE`` writes every figure as a row, ``--plots DIR`` draws PNGs with the Cramér–Rao bound (needs
matplotlib: radarnode[image]).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from radarnode.cli import options
from radarnode.cli.common import add_scale_out_arguments, atomic_output, atomic_path, check_scale_out, plot_dir, \
    plots_into, progress, require_matplotlib
from radarnode.errors import FileError, UsageError

EXPERIMENT_CHOICES = ("snr", "table2", "resolution", "timing")
SNR_LIMITS = (-60.0, 100.0)


def snr_list(text: str) -> tuple[float, ...]:
    """``START:STOP:STEP`` (STOP included) or a comma list of SNRs in dB, each in [-60, 100], ascending."""
    allowed = ("START:STOP:STEP (dB, stop included, step > 0) or a comma list of ascending SNRs, each in "
               f"[{SNR_LIMITS[0]:g}, {SNR_LIMITS[1]:g}] dB, at most 200 points")
    shown = repr(text)
    try:
        if ":" in text:
            start, stop, step = (float(v) for v in text.split(":"))
            if not (math.isfinite(start) and math.isfinite(stop) and math.isfinite(step) and step > 0
                    and stop >= start and (stop - start) / step <= 199.0 + 1e-9):
                raise ValueError
            values = tuple(float(v) for v in np.round(start + step * np.arange(int((stop - start) / step + 1e-9) + 1),
                                                      9))
        else:
            values = tuple(float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"value {shown} is not allowed; expected {allowed}") from None
    ok = (0 < len(values) <= 200 and all(math.isfinite(v) and SNR_LIMITS[0] <= v <= SNR_LIMITS[1] for v in values)
          and all(b > a for a, b in zip(values, values[1:])))
    if not ok:
        raise argparse.ArgumentTypeError(f"value {shown} is not allowed; expected {allowed}")
    return values


def add_subparser(sub) -> None:
    p = sub.add_parser("montecarlo", help="seed 001's Monte Carlo: LC-ACM, beam scanning, Capon, subspace DOA",
                       description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--experiment", nargs="+", choices=EXPERIMENT_CHOICES, default=list(EXPERIMENT_CHOICES),
                   metavar="NAME", help="which to run: " + ", ".join(EXPERIMENT_CHOICES) + " (default: all)")
    p.add_argument("--trials", type=options.integer(lo=2, hi=1_000_000), default=None,
                   help="trials a point, 2..1000000 (default 500, as seed 001)")
    p.add_argument("--seed", type=options.SEED, default=0, help="seed of the whole sweep (an integer >= 0, default 0)")
    p.add_argument("--snr-db", type=snr_list, default=None, metavar="SNRS",
                   help="SNR points of the snr experiment: START:STOP:STEP or a comma list, dB per element "
                        "(default 0:35:2.5)")
    p.add_argument("--azimuth-deg", type=options.number(lo=-40.0, hi=40.0), default=7.0,
                   help="the target's azimuth for snr and the pair's centre for resolution, degrees from straight "
                        "ahead, [-40, 40] (default 7, seed 001)")
    p.add_argument("--range-m", type=options.number(lo=2.0, hi=30.0), default=10.0,
                   help="the targets' range from the middle of the bumper, m, [2, 30] (default 10)")
    p.add_argument("--range-sigma-m", type=options.number(lo=0.0, hi=1.0), default=None,
                   help="σ of each radar's range, m, [0, 1] (default: the range CRB at each SNR)")
    p.add_argument("--resolution-snr-db", type=options.number(lo=SNR_LIMITS[0], hi=SNR_LIMITS[1]), default=None,
                   help="SNR of the resolution experiment, dB (default 20)")
    add_scale_out_arguments(p, "points")
    p.add_argument("--json", action="store_true", help="one JSON document on standard output instead of tables")
    p.add_argument("--csv", metavar="FILE", help="also write every figure as one CSV row to FILE")
    p.add_argument("--plots", metavar="DIR", help="draw PNGs into DIR (created if missing; needs matplotlib)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=cmd)


def _check_args(args):
    check_scale_out(args)
    # an option only an experiment not chosen reads was ignored (an independent tester: --snr-db with table2 alone,
    # which runs at 15 dB): refused, naming both
    chosen = set(args.experiment)
    for option, value, needs in (("--snr-db", args.snr_db, {"snr"}),
                                 ("--resolution-snr-db", args.resolution_snr_db, {"resolution"}),
                                 ("--trials", args.trials, {"snr", "table2", "resolution"})):
        if value is not None and not chosen & needs:
            shown = ",".join(f"{float(v):g}" for v in value) if hasattr(value, "__len__") else f"{value:g}"
            raise UsageError(f"option {option}: value {shown} is not allowed with --experiment "
                             f"{' '.join(args.experiment)} (no experiment chosen reads it); expected --experiment "
                             f"{' or '.join(sorted(needs))} with it, or no {option}")
    if args.resolution_snr_db is None:
        args.resolution_snr_db = 20.0
    if args.trials is None:
        args.trials = 500
    plt = None
    if args.plots:
        plt = require_matplotlib("option --plots")
        if Path(args.plots).is_file():
            plot_dir(args.plots)
    if args.csv:
        target = Path(args.csv)
        if target.is_dir():
            raise FileError(f"option --csv: value {args.csv!r} is not allowed; expected a file name (it is a "
                            "directory)")
        if not target.parent.is_dir():
            raise FileError(f"option --csv: cannot write {args.csv!r}: no such directory {str(target.parent)!r}")
    return plt


def _fmt(v, digits: int = 3) -> str:
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else f"{v:.{digits}f}"


def _table(head: list[str], rows: list[list[str]]) -> str:
    lines = ["| " + " | ".join(head) + " |", "|---|" + "---:|" * (len(head) - 1)]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    return "\n".join(lines)


def format_tables(summary: dict) -> str:
    """The summary as markdown tables (the ones BENCHMARKS.md quotes)."""
    out = []
    names = summary.get("estimators", [])
    trials = summary["sweep"]["trials"]
    if "snr" in summary:
        s = summary["snr"]
        cols = [f"{v:g}" for v in s["snr_db"]]
        for key, title, digits in (("p", "probability of the correct number of targets (eq. 11)", 3),
                                   ("rmse_deg", "RMSE (eq. 12), degrees; '-' where p ≤ 0.8", 3),
                                   ("bias_deg", "bias (eq. 13), degrees; '-' where p ≤ 0.8", 4)):
            rows = [[n] + [_fmt(c[key], digits) for c in s["metrics"][n]] for n in names]
            if key == "rmse_deg":
                rows += [[f"CRB {k}"] + [_fmt(v, digits) for v in s["crb_deg"][k]] for k in ("srr1", "srr2", "both")]
            out.append(f"### {title}: one target at {s['azimuth_deg']:g}°, {trials} trials a point; columns: SNR dB\n\n"
                       + _table(["estimator"] + cols, rows))
        rows = [[n, _fmt(s["crossing_db"][n], 1)] for n in names]
        rows += [[f"CRB {k}", _fmt(v, 1)] for k, v in s["crb_crossing_db"].items()]
        out.append("### SNR (dB) at which the RMSE comes down to 0.1° ('-': not within the sweep)\n\n"
                   + _table(["estimator", "SNR at 0.1°"], rows))
    if "table2" in summary:
        t = summary["table2"]
        rows = [[n + ("" if m["p_above_0.8_everywhere"] else " *"), _fmt(m["p"], 3), _fmt(m["rmse_deg"], 4),
                 _fmt(m["norm_rmse"], 2), _fmt(m["bias_deg"], 4), _fmt(m["norm_bias"], 2)]
                for n, m in t["metrics"].items()]
        rows += [[f"CRB {k}", "", _fmt(v, 4), "", "", ""] for k, v in t["crb_deg"].items()]
        az = ", ".join(f"{a:g}" for a in t["azimuth_deg"])
        out.append(f"### Table 2 (seed 001) at {t['snr_db']:g} dB, averaged over azimuths {az}°, {trials} trials "
                   "each; normalised to lcacm (eq. 14); * p ≤ 0.8 at some azimuth (seed 001 would not report it)\n\n"
                   + _table(["estimator", "p", "RMSE °", "norm. RMSE", "bias °", "norm. bias"], rows))
    if "resolution" in summary:
        r = summary["resolution"]
        cols = [f"{v:g}°" for v in r["separation_deg"]]
        rows = [[n] + [_fmt(v, 2) for v in r["probability"][n]] for n in names]
        out.append(f"### Probability of resolving two targets around {r['centre_deg']:g}° at {r['snr_db']:g} dB "
                   f"against their separation, {trials} trials a point\n\n" + _table(["estimator"] + cols, rows))
    if "timing" in summary:
        t = summary["timing"]
        rows = [[n, _fmt(v["single"], 0), _fmt(v["batched"], 1)] for n, v in t["us"].items()]
        ratio, core = t["complex_over_unitary_music"], t["complex_over_unitary_music_core"]
        out.append(f"### µs per estimate (median of {t['repeats']} repeats; one snapshot, 12 elements, "
                   f"{t['snr_db']:g} dB)\n\n"
                   + _table(["estimator", "one estimate, µs", f"per trial in a batch of {t['batch']}, µs"], rows)
                   + f"\n\ncomplex FB-MUSIC / unitary MUSIC time: median of the per-repeat ratios "
                     f"{ratio['median']:.2f} (quartiles {ratio['quartiles'][0]:.2f}–{ratio['quartiles'][1]:.2f}; "
                     f"> 1: unitary faster); the estimators alone (music_core / unitary_music_core) "
                     f"{core['median']:.2f} ({core['quartiles'][0]:.2f}–{core['quartiles'][1]:.2f}); "
                     f"largest |Δ sin θ| between them on the same data "
                     f"{t['max_abs_sin_difference_music_vs_unitary']:.1e}")
    return "\n\n".join(out)


def csv_rows(summary: dict) -> list[list]:
    """Every figure as ``experiment, estimator, snr_db, azimuth_deg, separation_deg, metric, value``."""
    rows: list[list] = []
    if "snr" in summary:
        s = summary["snr"]
        for n, curve in s["metrics"].items():
            for snr, c in zip(s["snr_db"], curve):
                rows += [["snr", n, snr, s["azimuth_deg"], "", k, c[k]] for k in ("p", "rmse_deg", "bias_deg")]
            rows.append(["snr", n, "", s["azimuth_deg"], "", "snr_at_0.1deg_db", s["crossing_db"][n]])
        for k, curve in s["crb_deg"].items():
            rows += [["snr", f"crb_{k}", snr, s["azimuth_deg"], "", "rmse_deg", v]
                     for snr, v in zip(s["snr_db"], curve)]
    if "table2" in summary:
        t = summary["table2"]
        for n, m in t["metrics"].items():
            rows += [["table2", n, t["snr_db"], "mean", "", k, v] for k, v in m.items()]
    if "resolution" in summary:
        r = summary["resolution"]
        for n, probs in r["probability"].items():
            rows += [["resolution", n, r["snr_db"], r["centre_deg"], sep, "p_resolved", v]
                     for sep, v in zip(r["separation_deg"], probs)]
    if "timing" in summary:
        for n, v in summary["timing"]["us"].items():
            rows += [["timing", n, summary["timing"]["snr_db"], "", "", f"us_{k}", x] for k, x in v.items()]
    return [[("" if v is None else v) for v in row] for row in rows]


def cmd(args) -> int:
    from tqdm import tqdm

    from radarnode.montecarlo import sweep as sw
    from radarnode.montecarlo.executor import default_workers, limit_blas_threads
    from radarnode.montecarlo.seed001 import Setup
    plt = _check_args(args)
    limit_blas_threads(1)
    setup = Setup.from_preset("srr_corner", range_m=args.range_m, range_sigma_m=args.range_sigma_m)
    experiments = tuple(e for e in EXPERIMENT_CHOICES if e in args.experiment)
    sweep_kw = {"trials": args.trials, "seed": args.seed, "azimuth_deg": args.azimuth_deg,
                "resolution_snr_db": args.resolution_snr_db}
    if args.snr_db is not None:
        sweep_kw["snr_db"] = args.snr_db
    mc = [e for e in experiments if e != "timing"]
    t0 = time.perf_counter()
    if mc:
        sweep = sw.Sweep(experiments=tuple(mc), **sweep_kw)
        points = sweep.points()
        bar = tqdm(disable=True) if args.quiet else progress(len(points), "montecarlo", unit="point")
        try:
            results = sw.run(setup, sweep, workers=args.workers or default_workers(), scheduler=args.scheduler,
                             dask_local=args.dask_local, on_done=lambda: bar.update(1))
        finally:
            bar.close()
        if not sw.finite_everywhere(results):      # a guard on the contract, not an expected outcome
            raise FileError("montecarlo: an estimator returned a non-finite angle; this is a bug, please report it")
        summary = sw.summarise(setup, sweep, results)
    else:
        import dataclasses
        summary = {"setup": dataclasses.asdict(setup), "sweep": {"trials": args.trials}, "estimators": []}
    if "timing" in experiments:
        from radarnode.montecarlo import timing
        repeats = 15
        bar = tqdm(disable=True) if args.quiet else progress(repeats, "timing", unit="repeat")
        try:
            summary["timing"] = timing.measure(setup, repeats=repeats, seed=args.seed, on_repeat=lambda: bar.update(1))
        finally:
            bar.close()
    summary["elapsed_s"] = time.perf_counter() - t0
    if args.json:
        print(json.dumps(summary, indent=1))
    else:
        print(format_tables(summary))
        print(f"\n(took {summary['elapsed_s']:.0f} s)")
    if args.csv:
        with atomic_output(args.csv, "--csv", newline="") as f:
            w = csv.writer(f)
            w.writerow(["experiment", "estimator", "snr_db", "azimuth_deg", "separation_deg", "metric", "value"])
            w.writerows(csv_rows(summary))
        print(f"wrote {args.csv}", file=sys.stderr)
    if plt is not None and mc:
        from radarnode.cli.montecarlo_plots import figures
        written = []
        with plots_into(args.plots) as d:
            for name, fig in figures(summary, plt).items():
                target = d / name
                try:
                    with atomic_path(target, "--plots") as tmp:
                        fig.savefig(tmp, dpi=90)
                except OSError as exc:
                    raise FileError(f"option --plots: cannot write {str(target)!r}: {exc.strerror or exc}") from None
                finally:
                    plt.close(fig)
                written.append(target)
        print(f"wrote {len(written)} plots to {d}", file=sys.stderr)
    return 0
