"""Issue 10's acceptance scenarios, every one over seeds 1…N at object and detection level.

Each scenario runs through node, wire, consumer and ECU as ``radarnode report`` runs it and is judged against its
``ecu.expect``; a scenario is accepted when it passes in at least ``--min-passes`` of the seeds (6 of 7) at every
level. The scenarios: bends of 250 and 500 m in both directions with a car stopped in the own, the inner and the
outer lane; ACC following on a bend at 1.5 and 2.0 s past a slower truck in the outer lane; a curve entered
through a clothoid with a car stopped after it (own and outer lane); the ego changing lane towards and away from
a stopped car; a bridge and a sign gantry at 50, 90 and 130 km/h; a car stopped under a bridge at 50 and 90 km/h
(with a driver who brakes after the warning); stop and go; a cut-in along waypoints that brakes.

Run: ``.venv/bin/python benchmarks/acceptance.py [--seeds 7] [--min-passes 6] [--levels object,detection]
[--jobs 2] [--only SUBSTRING]``. Prints a Markdown table; exit status 1 when a scenario is not accepted.
"""

from __future__ import annotations

import argparse
import dataclasses
import multiprocessing
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.consumer.evaluate import simulate  # noqa: E402
from radarnode.radar.setup import load_scenario  # noqa: E402

SCENARIOS = (
    [f"bend_r{r}_{d}_stopped_{lane}_lane" for r in (250, 500) for d in ("left", "right")
     for lane in ("own", "inner", "outer")]
    + ["acc_follow_bend_250", "acc_follow_bend_500_right", "clothoid_stopped_own_lane", "clothoid_stopped_outer_lane",
       "lane_change_to_stopped", "lane_change_past_stopped"]
    + [f"{k}_{v}" for k in ("bridge", "gantry") for v in (50, 90, 130)]
    + ["bridge_stopped_car_50", "bridge_stopped_car_90", "acc_stop_and_go", "cut_in_then_brake"])


def _one(job: tuple[str, str, int]) -> tuple[str, str, int, bool, str]:
    name, level, seed = job
    sc = dataclasses.replace(load_scenario(ROOT / "scenarios" / f"{name}.yaml"), seed=seed)
    r = simulate(sc, fidelity=level)
    return name, level, seed, r.passed and r.checked, "; ".join(r.reasons)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=7)
    ap.add_argument("--min-passes", type=int, default=6)
    ap.add_argument("--levels", default="object,detection")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--only", default="")
    args = ap.parse_args()
    levels = args.levels.split(",")
    names = [n for n in SCENARIOS if args.only in n]
    jobs = [(n, lv, s) for n in names for lv in levels for s in range(1, args.seeds + 1)]
    t0 = time.perf_counter()
    with multiprocessing.Pool(args.jobs) as pool:
        results = pool.map(_one, jobs, chunksize=1)
    by = {(n, lv): [] for n in names for lv in levels}
    for n, lv, s, ok, why in results:
        by[(n, lv)].append((s, ok, why))
    print(f"### Issue 10 acceptance: {len(names)} scenarios × seeds 1–{args.seeds} × {', '.join(levels)}\n")
    print("| scenario | " + " | ".join(f"{lv} passes" for lv in levels) + " | accepted | failures |")
    print("|---|" + "---:|" * len(levels) + "---|---|")
    short = 0
    for n in names:
        counts = [sum(ok for _, ok, _ in by[(n, lv)]) for lv in levels]
        accepted = all(c >= args.min_passes for c in counts)
        short += not accepted
        fails = "; ".join(f"{lv} seed {s}: {why}" for lv in levels for s, ok, why in by[(n, lv)] if not ok)
        print(f"| {n} | " + " | ".join(f"{c}/{args.seeds}" for c in counts) + f" | {'yes' if accepted else 'NO'} | "
              f"{fails} |")
    print(f"\n{len(names) - short} of {len(names)} scenarios accepted (≥ {args.min_passes} of {args.seeds} seeds at "
          f"every level); {len(jobs)} runs in {time.perf_counter() - t0:.0f} s with {args.jobs} processes")
    return 1 if short else 0


if __name__ == "__main__":
    sys.exit(main())
