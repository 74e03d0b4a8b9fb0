"""Overhead structures where the road is not a straight single crossing: a bridge on a bend, a gantry after a
bridge, two bridges in a row. Does the ECU stay quiet?

The layouts an independent tester found to draw false FCW warnings (2026-11-24, README "Known limits"), each at
50, 70 and 90 km/h with ACC on in closed loop and ``expect: {no_fcw, no_braking}``, run through node, wire,
consumer and ECU as ``radarnode report`` runs them, seeds 1…N, at object and detection level. A run passes when
the ECU neither warned nor braked. The structures stand 250 m ahead (the first one); the run ends 10 m before it
(bends) or 10 m before the last one.

* ``bend R500 left`` / ``bend R500 right`` / ``bend R1000 left`` / ``bend R333 left``: one bridge on a constant
  bend (its deck across the road where it stands, so obliquely in the sensor's beam; on the R 333 m bend it comes
  into view only about 115 m out, the car table's tightest bend);
* ``bridge + gantry 60 m``: a bridge, then a sign gantry 60 m after it (the deck hides it in elevation until
  about 180 m);
* ``two bridges 40 m``, ``two bridges 100 m``.

The second table is the other side of the same decision: a car stopped in the own lane under a bridge (its rear 0,
2 or 4 m past the deck's near edge) on the straight road and on R 500 m and R 333 m bends, ACC off, ``expect:
{lead: car, fcw_ttc_min_s: 2.1}``; a run counts when FCW warned at a TTC of 2.1 s or more. On a bend the car comes
into the far beam after the deck has been recognised, and the ECU must not file it as one of the deck's parts.

Run: ``.venv/bin/python benchmarks/overhead_layouts.py [--seeds 5] [--levels object,detection] [--speeds 50,70,90]
[--jobs 2] [--tables quiet,car]``. Prints Markdown tables.
"""

from __future__ import annotations

import argparse
import multiprocessing
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.consumer.evaluate import simulate  # noqa: E402
from radarnode.radar.setup import parse_scenario  # noqa: E402

#: layout -> (road curvature 1/m, [(class, distance along the road)])
LAYOUTS = {
    "bend R500 left": (0.002, [("bridge", 250.0)]),
    "bend R500 right": (-0.002, [("bridge", 250.0)]),
    "bend R1000 left": (0.001, [("bridge", 250.0)]),
    "bend R333 left": (0.003, [("bridge", 250.0)]),
    "bridge + gantry 60 m": (0.0, [("bridge", 250.0), ("gantry", 310.0)]),
    "two bridges 40 m": (0.0, [("bridge", 250.0), ("bridge", 290.0)]),
    "two bridges 100 m": (0.0, [("bridge", 250.0), ("bridge", 350.0)]),
}
#: a car stopped in the own lane under a bridge 250 m ahead: layout -> (road curvature 1/m, how far its rear stands
#: past the deck's near edge, m)
CAR_LAYOUTS = {
    "straight, rear 2 m under": (0.0, 2.0),
    "bend R500 left, rear 0 m under": (0.002, 0.0),
    "bend R500 left, rear 4 m under": (0.002, 4.0),
    "bend R500 right, rear 0 m under": (-0.002, 0.0),
    "bend R500 right, rear 4 m under": (-0.002, 4.0),
    "bend R333 left, rear 0 m under": (0.003, 0.0),
    "bend R333 left, rear 4 m under": (0.003, 4.0),
}
DECK_HALF_DEPTH_M, CAR_HALF_LENGTH_M = 6.0, 2.25     # radarnode.scene: a bridge's deck, a car
#: what both tables' scenarios share: the run, the radar, the ego and the road
HEADER = """duration_s: {dur}
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: {v}}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1, curvature_1pm: {kappa}}}
"""
CAR_TEMPLATE = "name: car_under_bridge\n" + HEADER + """ecu: {{acc_enabled: false, set_speed_mps: {v}, expect: {{lead: car, fcw_ttc_min_s: 2.1}}}}
actors:
  - {{id: bridge, class: bridge, x_m: 250.0, y_m: 0.0}}
  - {{id: car, class: car, x_m: {x_car}, lane: 1, speed_mps: 0.0}}
"""
TEMPLATE = "name: overhead_layout\n" + HEADER + """ecu:
  acc_enabled: true
  set_speed_mps: {v}
  closed_loop: true
  expect: {{no_fcw: true, no_braking: true}}
actors:
{actors}"""


def _one(job: tuple[str, float, str, int]) -> tuple[str, float, str, bool]:
    layout, kmh, level, seed = job
    kappa, structures = LAYOUTS[layout]
    v = kmh / 3.6
    last = max(x for _, x in structures)
    actors = "".join(f"  - {{id: s{i}, class: {c}, x_m: {x}, y_m: 0.0}}\n" for i, (c, x) in enumerate(structures))
    sc = parse_scenario(TEMPLATE.format(dur=round((last - 10.0) / v, 2), seed=seed, v=round(v, 3), kappa=kappa,
                                        actors=actors))
    r = simulate(sc, fidelity=level)
    return layout, kmh, level, r.passed and r.checked


def _car(job: tuple[str, float, str, int]) -> tuple[str, float, str, bool]:
    layout, kmh, level, seed = job
    kappa, under = CAR_LAYOUTS[layout]
    v = kmh / 3.6
    rear = 250.0 - DECK_HALF_DEPTH_M + under
    sc = parse_scenario(CAR_TEMPLATE.format(dur=round((rear - 3.7) / v + 1.0, 2), seed=seed, v=round(v, 3),
                                            kappa=kappa, x_car=round(rear + CAR_HALF_LENGTH_M, 3)))
    r = simulate(sc, fidelity=level)
    return layout, kmh, level, r.passed and r.checked


def _table(title: str, layouts: dict, fn, args, levels: list[str], speeds: list[float], what: str) -> None:
    jobs = [(lay, s, lv, seed) for lay in layouts for s in speeds for lv in levels
            for seed in range(1, args.seeds + 1)]
    t0 = time.perf_counter()
    with multiprocessing.Pool(args.jobs) as pool:
        results = pool.map(fn, jobs, chunksize=1)
    ok = {}
    for lay, s, lv, passed in results:
        ok[(lay, s, lv)] = ok.get((lay, s, lv), 0) + passed
    print(f"### {title}: seeds 1–{args.seeds} ({what})\n")
    print("| layout | " + " | ".join(f"{s:g} km/h {lv}" for s in speeds for lv in levels) + " |")
    print("|---|" + "---:|" * (len(speeds) * len(levels)))
    for lay in layouts:
        print(f"| {lay} | " + " | ".join(f"{ok[(lay, s, lv)]}/{args.seeds}" for s in speeds for lv in levels) + " |")
    total = {lv: sum(ok[(lay, s, lv)] for lay in layouts for s in speeds) for lv in levels}
    runs = len(layouts) * len(speeds) * args.seeds
    print("\n" + "; ".join(f"{lv}: {total[lv]} of {runs}" for lv in levels)
          + f" ({len(jobs)} runs in {time.perf_counter() - t0:.0f} s with {args.jobs} processes)\n")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--levels", default="object,detection")
    ap.add_argument("--speeds", default="50,70,90")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--tables", default="quiet,car", help="quiet (structures alone), car (a car under a bridge)")
    args = ap.parse_args()
    levels, speeds = args.levels.split(","), [float(s) for s in args.speeds.split(",")]
    tables = args.tables.split(",")
    unknown = sorted(set(tables) - {"quiet", "car"})
    if unknown:
        ap.error(f"--tables: value {args.tables!r} is not allowed ({', '.join(unknown)}); expected quiet, car or both, "
                 "comma-separated")
    if "quiet" in tables:
        _table("No warning, no braking under overhead structures", LAYOUTS, _one, args, levels, speeds,
               "runs without a warning")
    if "car" in tables:
        _table("A car stopped under a bridge: warned in time (TTC ≥ 2.1 s)", CAR_LAYOUTS, _car, args, levels,
               speeds, "runs warned in time")


if __name__ == "__main__":
    main()
