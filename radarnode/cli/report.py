"""``radarnode report SCENARIO…``: run scenarios through node, consumer and ECU and judge them.

Per scenario: warning time, TTC at the warning (constant-speed TTC to the
``ecu.expect.lead`` actor, as the NHTSA confirmation tests define it), the
minimum TTC and gap, peak deceleration and jerk of the ego (closed loop), the
final time gap, and pass or fail against the scenario's ``ecu.expect``.
``--seeds N`` repeats each scenario with seeds 1…N and counts the passes.
"""

from __future__ import annotations

import dataclasses
import math

from radarnode.consumer.evaluate import simulate
from radarnode.errors import ConfigError
from radarnode.radar.setup import load_scenario


def add_subparser(sub) -> None:
    p = sub.add_parser("report", help="judge scenarios against their ACC/FCW expectations", description=__doc__)
    p.add_argument("scenarios", nargs="+", help="scenario files")
    p.add_argument("--seeds", type=int, default=1, help="run each scenario with seeds 1..N (default 1)")
    p.add_argument("--fidelity", choices=("object", "detection", "signal", "auto"), help="radar model level")
    p.add_argument("--min-passes", type=int, default=None,
                   help="exit 1 when a scenario passes in fewer seeds than this (default: all of them)")
    p.set_defaults(func=cmd)


def _fmt(v, unit: str, digits: int = 2) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    return f"{v:.{digits}f} {unit}"


def cmd(args) -> int:
    if args.seeds < 1:
        raise ConfigError(f"option --seeds: value {args.seeds} is not allowed; expected an integer >= 1")
    need = args.seeds if args.min_passes is None else args.min_passes
    if not 1 <= need <= args.seeds:
        raise ConfigError(f"option --min-passes: value {need} is not allowed; expected 1..{args.seeds}")
    short = 0
    print("| scenario | seed | warning at | TTC at warning | min TTC | min gap | peak decel | peak jerk | "
          "final time gap | result |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for path in args.scenarios:
        sc = load_scenario(path)
        passes = 0
        for seed in range(1, args.seeds + 1) if args.seeds > 1 else [sc.seed]:
            r = simulate(dataclasses.replace(sc, seed=seed), fidelity=args.fidelity)
            passes += r.passed
            verdict = "pass" if r.passed else "FAIL: " + "; ".join(r.reasons)
            print(f"| {sc.name} | {seed} | {_fmt(r.warning_time_s, 's')} | {_fmt(r.ttc_at_warning_s, 's')} | "
                  f"{_fmt(r.min_ttc_s, 's')} | {_fmt(r.min_gap_m, 'm', 1)} | {_fmt(r.peak_decel_mps2, 'm/s²')} | "
                  f"{_fmt(r.peak_jerk_mps3, 'm/s³')} | {_fmt(r.final_time_gap_s, 's')} | {verdict} |", flush=True)
        if args.seeds > 1:
            print(f"| {sc.name} | | | | | | | | | {passes} of {args.seeds} seeds pass |")
        short += passes < need
    return 1 if short else 0
