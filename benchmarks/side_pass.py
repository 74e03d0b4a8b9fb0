"""Passing and being passed: a car or a truck in the next lane, beside the ego, must never draw FCW or become ACC's
target.

Each row is a scene built here: a straight three-lane road, the ego in the middle lane at 20, 30 or 36 m/s (36 with
guardrails on both sides, posts 2 m apart) under closed-loop ACC set to its speed, no lead; one car or truck in the
left or the right lane, ``dv`` m/s slower than the ego (it starts 40 m ahead and the ego passes it) or, negative,
faster (it starts 15 m behind and passes the ego). The scene runs until the pass is over. Judged as ``radarnode
report`` judges it (``ecu.expect``: no FCW, the other vehicle never ACC's target), over seeds 1…N at each level.

Beside the ego the forward radar's field of view cuts the passed body: its detections stay at the edge of the field
of view while the body moves on (the object level reports that point as well: its nearest point in the field of
view). The radar's tracker takes where along the body a detection lies for no motion there
(``radarnode.perception.tracker.along_body_cov``); before it, the track drifted across into the ego's lane.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/side_pass.py [--seeds 3] [--levels object,detection]
[--jobs 2] [--egos 20,30,36] [--dvs=-8,-3,-1,1,2,3,5,8] [--classes car,truck] [--root DIR]`` (about 9 minutes with
the defaults on two cores; ``--root DIR`` runs the radarnode of another tree). Prints a Markdown table, a row per
scene: the seeds that passed at each level, and the failures.
"""

from __future__ import annotations

import argparse
import itertools
import multiprocessing
import sys
import time
from pathlib import Path

from tree import use_tree  # --root DIR: radarnode from another tree

use_tree()

import radarnode  # noqa: E402
from radarnode.consumer.evaluate import simulate  # noqa: E402
from radarnode.radar.setup import parse_scenario  # noqa: E402

SCENE = """
name: {name}
duration_s: {duration}
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: {ego}}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1{rails}}}
ecu:
  acc_enabled: true
  set_speed_mps: {ego}
  time_gap_s: 2.0
  closed_loop: true
  expect: {{no_fcw: true, never_target: [other]}}
actors:
  - {{id: other, class: {cls}, x_m: {x0}, lane: {lane}, speed_mps: {speed}}}
"""
RAILS = ", guardrails: {left_offset_m: 0.8, right_offset_m: 0.8, post_spacing_m: 2.0}"
#: the other vehicle's speed below the ego's (m/s; negative: it is faster and passes the ego)
DVS = (-8, -3, -1, 1, 2, 3, 5, 8)
LANES = (0, 2)                     # right, left of the ego's lane 1
CLASSES = ("car", "truck")


def scene_text(ego: float, dv: int, lane: int, cls: str, seed: int) -> str:
    """The scene of one row, for one seed."""
    if dv > 0:        # the ego passes a slower one that starts ahead
        x0, duration = 40.0, min(50.0, 45.0 / dv + 5.0)
    else:             # a faster one starts behind and passes the ego
        x0, duration = -15.0, min(50.0, 40.0 / -dv + 5.0)
    return SCENE.format(name=row_name(ego, dv, lane, cls), duration=round(duration, 1), seed=seed, ego=ego,
                        rails=RAILS if ego >= 36.0 else "", cls=cls, x0=x0, lane=lane, speed=ego - dv)


def row_name(ego: float, dv: int, lane: int, cls: str) -> str:
    return f"ego {ego:g} m/s, {cls} {'left' if lane == 2 else 'right'}, dv {dv:+d} m/s"


def _one(job: tuple[float, int, int, str, str, int]) -> tuple[tuple, str, int, bool, str]:
    ego, dv, lane, cls, level, seed = job
    r = simulate(parse_scenario(scene_text(ego, dv, lane, cls, seed)), fidelity=level)
    return (ego, dv, lane, cls), level, seed, r.passed and r.checked, "; ".join(r.reasons)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--levels", default="object,detection")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--egos", default="20,30,36", help="ego speeds, m/s")
    ap.add_argument("--dvs", default=",".join(str(d) for d in DVS), help="the other's speed below the ego's, m/s")
    ap.add_argument("--classes", default=",".join(CLASSES))
    ap.add_argument("--root", help="import radarnode from this tree (another version) instead")
    args = ap.parse_args()
    levels = args.levels.split(",")
    rows = list(itertools.product([float(v) for v in args.egos.split(",")], [int(d) for d in args.dvs.split(",")],
                                  LANES, args.classes.split(",")))
    jobs = [row + (lv, s) for row in rows for lv in levels for s in range(1, args.seeds + 1)]
    t0 = time.perf_counter()
    with multiprocessing.Pool(args.jobs) as pool:
        results = pool.map(_one, jobs, chunksize=1)
    by: dict[tuple, list] = {}
    for row, lv, s, ok, why in results:
        by.setdefault((row, lv), []).append((s, ok, why))
    print(f"(radarnode from {Path(radarnode.__file__).parents[1]})\n")
    print(f"### Passing and being passed: {len(rows)} scenes × seeds 1–{args.seeds} × {', '.join(levels)}\n")
    print("| scene | " + " | ".join(f"{lv} passes" for lv in levels) + " | failures |")
    print("|---|" + "---:|" * len(levels) + "---|")
    total = {lv: 0 for lv in levels}
    for row in rows:
        counts = [sum(ok for _, ok, _ in by[(row, lv)]) for lv in levels]
        for lv, c in zip(levels, counts):
            total[lv] += c
        fails = "; ".join(f"{lv} seed {s}: {why}" for lv in levels for s, ok, why in by[(row, lv)] if not ok)
        print(f"| {row_name(*row)} | " + " | ".join(f"{c}/{args.seeds}" for c in counts) + f" | {fails} |")
    runs = len(rows) * args.seeds
    print("\n" + "; ".join(f"{lv}: {total[lv]} of {runs} runs pass" for lv in levels)
          + f" ({len(jobs)} runs in {time.perf_counter() - t0:.0f} s with {args.jobs} processes)")
    return 0 if all(total[lv] == runs for lv in levels) else 1


if __name__ == "__main__":
    sys.exit(main())
