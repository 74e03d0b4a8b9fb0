"""Overhead structures where the road is not a straight single crossing: a bridge on a bend, a gantry after a
bridge, two bridges in a row. Does the ECU stay quiet?

The layouts an independent tester found to draw false FCW warnings (2026-11-24, README "Known limits"), each at
50, 70 and 90 km/h with ACC on in closed loop and ``expect: {no_fcw, no_braking}``, run through node, wire,
consumer and ECU as ``radarnode report`` runs them, seeds 1…N, at object and detection level. A run passes when
the ECU neither warned nor braked. The structures stand 250 m ahead (the first one); the run ends 10 m before it
(bends) or 10 m before the last one.

* ``bend R500 left`` / ``bend R500 right`` / ``bend R1000 left``: one bridge on a constant bend (its deck across
  the road where it stands, so obliquely in the sensor's beam);
* ``bridge + gantry 60 m``: a bridge, then a sign gantry 60 m after it (the deck hides it in elevation until
  about 180 m);
* ``two bridges 40 m``, ``two bridges 100 m``.

Run: ``.venv/bin/python benchmarks/overhead_layouts.py [--seeds 5] [--levels object,detection] [--speeds 50,70,90]
[--jobs 2]``. Prints a Markdown table.
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
    "bridge + gantry 60 m": (0.0, [("bridge", 250.0), ("gantry", 310.0)]),
    "two bridges 40 m": (0.0, [("bridge", 250.0), ("bridge", 290.0)]),
    "two bridges 100 m": (0.0, [("bridge", 250.0), ("bridge", 350.0)]),
}
TEMPLATE = """name: overhead_layout
duration_s: {dur}
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: {v}}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1, curvature_1pm: {kappa}}}
ecu:
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--levels", default="object,detection")
    ap.add_argument("--speeds", default="50,70,90")
    ap.add_argument("--jobs", type=int, default=2)
    args = ap.parse_args()
    levels, speeds = args.levels.split(","), [float(s) for s in args.speeds.split(",")]
    jobs = [(lay, s, lv, seed) for lay in LAYOUTS for s in speeds for lv in levels
            for seed in range(1, args.seeds + 1)]
    t0 = time.perf_counter()
    with multiprocessing.Pool(args.jobs) as pool:
        results = pool.map(_one, jobs, chunksize=1)
    ok = {}
    for lay, s, lv, passed in results:
        ok[(lay, s, lv)] = ok.get((lay, s, lv), 0) + passed
    print(f"### No warning, no braking under overhead structures: seeds 1–{args.seeds} (runs without a warning)\n")
    print("| layout | " + " | ".join(f"{s:g} km/h {lv}" for s in speeds for lv in levels) + " |")
    print("|---|" + "---:|" * (len(speeds) * len(levels)))
    for lay in LAYOUTS:
        print(f"| {lay} | " + " | ".join(f"{ok[(lay, s, lv)]}/{args.seeds}" for s in speeds for lv in levels) + " |")
    total = {lv: sum(ok[(lay, s, lv)] for lay in LAYOUTS for s in speeds) for lv in levels}
    runs = len(LAYOUTS) * len(speeds) * args.seeds
    print("\n" + "; ".join(f"{lv}: {total[lv]} of {runs} runs quiet" for lv in levels)
          + f" ({len(jobs)} runs in {time.perf_counter() - t0:.0f} s with {args.jobs} processes)")


if __name__ == "__main__":
    main()
