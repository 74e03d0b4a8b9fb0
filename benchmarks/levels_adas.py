"""The same ADAS verdicts at every fidelity level (issue 15 item 3).

Runs every shipped scenario with an ``ecu.expect`` (ACC and FCW cases) through node, consumer and ECU — as
``radarnode report`` does — at object, detection and signal level, over seeds 1…N, and prints per scenario
and level: how many seeds pass, the median warning time and TTC at the warning, and the largest difference
of the TTC at warning from the object level's (same seed). Target (issue 15): every NHTSA and Euro NCAP-style
scenario passes at all three levels in every seed, TTC at warning at detection and signal level within 0.3 s
of the object level's.

Run: ``.venv/bin/python benchmarks/levels_adas.py [--seeds N] [--levels object,detection,signal]
[--only SUBSTRING]``. Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.consumer.evaluate import simulate  # noqa: E402
from radarnode.radar.setup import load_scenario  # noqa: E402


def _med(xs: list[float]) -> str:
    xs = [x for x in xs if x is not None and math.isfinite(x)]
    return f"{statistics.median(xs):.2f} s" if xs else "-"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--levels", default="object,detection,signal")
    ap.add_argument("--only", default="", help="run only scenarios whose name contains this")
    args = ap.parse_args()
    levels = args.levels.split(",")
    paths = [p for p in sorted((ROOT / "scenarios").glob("*.yaml")) if args.only in p.stem]
    scenarios = [sc for sc in (load_scenario(p) for p in paths) if sc.ecu.expect != type(sc.ecu.expect)()]
    print(f"### ADAS verdicts per level: {len(scenarios)} scenarios × seeds 1–{args.seeds}\n")
    # (the bars of |Δ| escaped: bare, Markdown takes them for column edges)
    print("| scenario | level | passes | warning at (median) | TTC at warning (median) | max \\|Δ warning time\\| | "
          "max \\|ΔTTC at warning\\| | failures |")
    print("|---|---|---:|---:|---:|---:|---:|---|")
    all_pass, worst, worst_t = True, 0.0, 0.0
    t0 = time.perf_counter()
    for sc in scenarios:
        ref: dict[int, float | None] = {}
        ref_t: dict[int, float | None] = {}
        for level in levels:
            res = [simulate(dataclasses.replace(sc, seed=s), fidelity=level) for s in range(1, args.seeds + 1)]
            passes = sum(r.passed for r in res)
            all_pass &= passes == len(res)
            if level == levels[0]:
                ref = {s: r.ttc_at_warning_s for s, r in zip(range(1, args.seeds + 1), res)}
                ref_t = {s: r.warning_time_s for s, r in zip(range(1, args.seeds + 1), res)}
                delta = delta_t = "-"
            else:
                d = [abs(r.ttc_at_warning_s - ref[s]) for s, r in zip(range(1, args.seeds + 1), res)
                     if r.ttc_at_warning_s is not None and ref.get(s) is not None]
                delta = f"{max(d):.2f} s" if d else "-"
                if d:
                    worst = max(worst, max(d))
                dt = [abs(r.warning_time_s - ref_t[s]) for s, r in zip(range(1, args.seeds + 1), res)
                      if r.warning_time_s is not None and ref_t.get(s) is not None]
                delta_t = f"{max(dt):.2f} s" if dt else "-"
                if dt:
                    worst_t = max(worst_t, max(dt))
            fails = sorted({"; ".join(r.reasons) for r in res if not r.passed})
            print(f"| {sc.name} | {level} | {passes}/{len(res)} | {_med([r.warning_time_s for r in res])} | "
                  f"{_med([r.ttc_at_warning_s for r in res])} | {delta_t} | {delta} | {', '.join(fails)} |", flush=True)
    print(f"\nall pass at every level: {'yes' if all_pass else 'NO'}; against the {levels[0]} level (same seed): "
          f"largest |Δ warning time| {worst_t:.2f} s, largest |ΔTTC at warning| {worst:.2f} s; "
          f"wall time {time.perf_counter() - t0:.0f} s")


if __name__ == "__main__":
    main()
