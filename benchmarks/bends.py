"""ACC and FCW on bends, curve exits and guardrail roads: an independent tester's scenes (session 18).

Three tables, each row a scene built here, run through node, consumer and ECU as ``radarnode report`` runs it:

1. ACC behind a lead at the ego's speed on a constant bend, closed loop, set time gap 1.5 s (2.0 s where stated):
   the final time gap along the lane (the truth's) at each level, and the lead's velocity relative to the sensor
   as each level reports it against the truth (mean over the second half of an open-loop run);
2. a car stopped in the inner lane beyond a curve's exit (R 250 m into a 30-m clothoid, guardrails on both sides,
   and R 400 m into a 60-m clothoid without): FCW must stay silent;
3. an empty straight road with guardrails on both sides: FCW must stay silent (README, "Known limit, guardrails
   both sides": it does not at the detection level);
4. (``--only neighbours``, new 2026-12-05, session 69) a car or a truck in the lane inside or outside a constant
   bend from the run's first cycle, 40 m ahead, 2 m/s slower or faster than the ego (25 m/s), closed loop ACC: it
   must never be ACC's target and FCW must stay silent (an independent tester's scene: a truck 2 m/s slower inside
   R 250 m was ACC's target at the detection level in every seed);
5. (``--only exit_at_start``, new 2026-12-05, session 69) the run starts 4, 8 or 15 m before a bend's exit (R 150 m
   at 20 m/s, R 250 m at 25 m/s, left and right), a car 45 m ahead in the lane inside the bend, 1 m/s slower and
   already on the straight: it must never be ACC's target and FCW must stay silent (the radar's tracker takes the
   ego's bend for the road ahead from its first cycle, and this car is where that is wrong).

Run: ``.venv/bin/python benchmarks/bends.py [--seeds 3] [--levels object,detection] [--only follow,exit,neighbours,exit_at_start]``
(the first two tables, the default: about 2 minutes; the neighbours: about 4 minutes a level with 3 seeds, 25 at the
signal level; the exits at the start: about 2 minutes a level).
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.consumer.evaluate import simulate  # noqa: E402
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.setup import parse_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

FOLLOW = """
name: follow_R{radius:.0f}_v{speed:.0f}
duration_s: 30.0
seed: 1
radar: {{preset: ars408_like}}
ego: {{speed_mps: {speed}}}
road: {{lanes: 2, lane_width_m: 3.5, ego_lane: 0, curvature_1pm: {curv}}}
ecu:
  acc_enabled: true
  set_speed_mps: {speed}
  time_gap_s: {gap}
  closed_loop: true
  expect: {{lead: lead, gap_settle_s: 12.0, gap_tolerance: 0.15, acc_follows: lead}}
actors:
  - {{id: lead, class: car, x_m: {lead_x}, lane: 0, speed_mps: {speed}}}
"""
FOLLOWS = [(150.0, 20.0, 1.5), (100.0, 15.0, 1.5), (100.0, 20.0, 1.5), (250.0, 25.0, 2.0), (500.0, 25.0, 2.0)]

EXIT = """
name: {name}
duration_s: 9.0
seed: 1
radar: {{preset: ars408_like}}
ego: {{speed_mps: 25.0}}
road:
  lanes: 3
  lane_width_m: 3.5
  ego_lane: 1
  segments:
    - {{type: arc, length_m: {arc}, curvature_1pm: {curv}}}
    - {{type: clothoid, length_m: {clothoid}, curvature_start_1pm: {curv}, curvature_end_1pm: 0.0}}
    - {{type: straight, length_m: 600}}
{guardrails}ecu: {{acc_enabled: false, expect: {{lead: stopped, no_fcw: true, never_target: [stopped]}}}}
actors:
  - {{id: stopped, class: car, x_m: 200.0, lane: 2, speed_mps: 0.0}}
"""
EXITS = [("exit_R250_30_guardrails", 160.0, 0.004, 30.0, True), ("exit_R400_60_none", 130.0, 0.0025, 60.0, False)]

EMPTY = """
name: empty_guardrails_25
duration_s: 10.0
seed: 1
radar: {preset: ars408_like}
ego: {speed_mps: 25.0}
road:
  lanes: 3
  lane_width_m: 3.5
  ego_lane: 1
  guardrails: {left_offset_m: 1.0, right_offset_m: 1.0}
ecu: {acc_enabled: false, expect: {no_fcw: true}}
"""

NEIGHBOUR = """
name: {cls}_{side}_R{radius:+.0f}_v{speed:.0f}
duration_s: 27.5
seed: 1
radar: {{preset: ars408_like}}
ego: {{speed_mps: 25.0}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1, curvature_1pm: {curv}}}
ecu:
  acc_enabled: true
  set_speed_mps: 25.0
  time_gap_s: 2.0
  closed_loop: true
  expect: {{no_fcw: true, never_target: [other]}}
actors:
  - {{id: other, class: {cls}, x_m: 40.0, lane: {lane}, speed_mps: {speed}}}
"""
#: (class, lane, curvature 1/m, speed m/s): lane 2 is left of the ego's (inside a left bend, κ > 0), lane 0 right
NEIGHBOURS = [(cls, lane, curv, speed) for cls in ("car", "truck") for lane in (2, 0)
              for curv in (0.004, -0.004, 0.002) for speed in (23.0, 27.0)]

EXIT_AT_START = """
name: exit_in_{arc:.0f}m_R{radius:+.0f}
duration_s: 12.0
seed: 1
radar: {{preset: ars408_like}}
ego: {{speed_mps: {speed}}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1, segments: [{{type: arc, length_m: {arc}, curvature_1pm: {curv}}},
        {{type: straight, length_m: 800.0}}]}}
ecu:
  acc_enabled: true
  set_speed_mps: {speed}
  time_gap_s: 2.0
  closed_loop: true
  expect: {{no_fcw: true, never_target: [nb]}}
actors:
  - {{id: nb, class: car, x_m: 45.0, lane: {lane}, speed_mps: {car_speed}}}
"""
#: (metres of arc left, curvature 1/m, ego speed m/s): a car 45 m ahead in the lane inside the bend, 1 m/s slower,
#: already on the straight beyond the exit (an independent tester's scenes, session 69)
EXITS_AT_START = [(arc, curv, speed) for arc in (4.0, 8.0, 15.0)
                  for curv, speed in ((-1.0 / 150.0, 20.0), (1.0 / 150.0, 20.0), (-0.004, 25.0), (0.004, 25.0))]


def _runs(sc, levels, seeds):
    return {lv: [simulate(dataclasses.replace(sc, seed=s), fidelity=lv) for s in range(1, seeds + 1)] for lv in levels}


def _velocity(sc, level: str, cycles: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """The lead's reported velocity relative to the sensor and the truth, means over the second half (open loop)."""
    cfg = radar_config(sc)
    model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(1), cfg.signal)
    rep, truth = [], []
    for k in range(cycles):
        frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=250.0))
        o = frame.objects
        mine = np.flatnonzero(o.actor_index == 0)
        if k >= cycles // 2 and mine.size:
            rep.append((o.vrel_long_mps[mine[0]], o.vrel_lat_mps[mine[0]]))
            truth.append((view.vx_mps[0], view.vy_mps[0]))
    return np.mean(rep, axis=0), np.mean(truth, axis=0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--levels", default="object,detection")
    ap.add_argument("--only", default="follow,exit", help="tables: follow, exit (with the empty road), neighbours, "
                    "exit_at_start")
    args = ap.parse_args()
    if args.seeds < 1:
        ap.error(f"--seeds: value {args.seeds} is not allowed; expected an integer ≥ 1")
    levels = [lv for lv in args.levels.split(",") if lv]
    only = [t for t in args.only.split(",") if t]
    bad = [t for t in only if t not in ("follow", "exit", "neighbours", "exit_at_start")]
    if bad or not only:
        ap.error(f"--only: value {args.only!r} is not allowed; expected a comma-separated list of follow, exit, "
                 "neighbours, exit_at_start")
    t0 = time.perf_counter()
    if "follow" in only:
        _follow_table(levels, args.seeds)
    if "exit" in only:
        _exit_table(levels, args.seeds)
    if "neighbours" in only:
        _neighbour_table(levels, args.seeds)
    if "exit_at_start" in only:
        _exit_at_start_table(levels, args.seeds)
    print(f"\n(total {time.perf_counter() - t0:.0f} s)")


def _verdict_table(levels, seeds: int, title: str, columns: str, aligns: str, scenes) -> None:
    """One row a scene (``scenes``: its first cells and its YAML): passes and failures at each level."""
    print(f"### {title} (seeds 1–{seeds}; never ACC's target, FCW silent)\n")
    print(f"| {columns} | " + " | ".join(f"{lv}: passes" for lv in levels) + " | "
          + " | ".join(f"{lv}: failures" for lv in levels) + " |")
    print(f"|{aligns}" + "---:|" * len(levels) + "---|" * len(levels))
    total = {lv: 0 for lv in levels}
    for cells, text in scenes:
        runs = _runs(parse_scenario(text), levels, seeds)
        for lv in levels:
            total[lv] += sum(r.passed for r in runs[lv])
        fails = ["; ".join(f"seed {i + 1}: {r.reasons[0]}" for i, r in enumerate(runs[lv]) if not r.passed) or "-"
                 for lv in levels]
        print(f"| {cells} | " + " | ".join(f"{sum(r.passed for r in runs[lv])}/{seeds}" for lv in levels) + " | "
              + " | ".join(fails) + " |", flush=True)
    print("\nall: " + ", ".join(f"{lv} {total[lv]} of {len(scenes) * seeds}" for lv in levels))


def _neighbour_table(levels, seeds: int) -> None:
    scenes = []
    for cls, lane, curv, speed in NEIGHBOURS:
        side = "left" if lane == 2 else "right"
        inner = (lane == 2) == (curv > 0)
        scenes.append((f"{cls} | {side} ({'inside' if inner else 'outside'}) | {curv:+.3f} 1/m | {speed:.0f} m/s",
                       NEIGHBOUR.format(cls=cls, side=side, radius=1.0 / curv, curv=curv, lane=lane, speed=speed)))
    _verdict_table(levels, seeds, "A vehicle in the next lane on a bend from the run's first cycle, 40 m ahead, ego 25 "
                   "m/s", "vehicle | lane | curvature | its speed", "---|---|---:|---:|", scenes)


def _exit_at_start_table(levels, seeds: int) -> None:
    scenes = [(f"{arc:.0f} m | {curv:+.5f} 1/m | {speed:.0f} m/s",
               EXIT_AT_START.format(arc=arc, radius=1.0 / curv, curv=curv, speed=speed, lane=2 if curv > 0 else 0,
                                    car_speed=speed - 1.0)) for arc, curv, speed in EXITS_AT_START]
    _verdict_table(levels, seeds, "The run starts just before a bend's exit, a car 45 m ahead in the lane inside the "
                   "bend on the straight", "arc left | curvature | ego speed", "---:|---:|---:|", scenes)


def _follow_table(levels, seeds: int) -> None:
    print(f"### ACC behind a lead at the ego's speed on a bend (seeds 1–{seeds}; time gap: median of the "
          "final time gaps along the lane)\n")
    print("| bend | speed | set gap | " + " | ".join(f"{lv}: final gap (passes)" for lv in levels) + " | truth v | "
          + " | ".join(f"{lv}: reported v" for lv in levels) + " |")
    print("|---|---:|---:|" + "---:|" * (2 * len(levels) + 1))
    for radius, speed, gap in FOLLOWS:
        sc = parse_scenario(FOLLOW.format(radius=radius, speed=speed, curv=1.0 / radius, gap=gap,
                                          lead_x=round(gap * speed + 5.7, 2)))
        runs = _runs(sc, levels, seeds)
        cells = [f"{statistics.median(r.final_time_gap_s for r in runs[lv]):.2f} s "
                 f"({sum(r.passed for r in runs[lv])}/{seeds})" for lv in levels]
        vel = [_velocity(sc, lv) for lv in levels]
        truth = vel[0][1]
        print(f"| R {radius:.0f} m | {speed:.0f} m/s | {gap:.1f} s | " + " | ".join(cells)
              + f" | ({truth[0]:+.2f}, {truth[1]:+.2f}) | "
              + " | ".join(f"({v[0][0]:+.2f}, {v[0][1]:+.2f})" for v in vel) + " |", flush=True)


def _exit_table(levels, seeds: int) -> None:
    print(f"\n### FCW: a car stopped in the inner lane beyond a curve's exit; an empty road with guardrails (seeds "
          f"1–{seeds}; must stay silent)\n")
    print("| scene | " + " | ".join(f"{lv}: silent in" for lv in levels) + " | " +
          " | ".join(f"{lv}: warnings at (s)" for lv in levels) + " |")
    print("|---|" + "---:|" * (2 * len(levels)))
    scenes = [EXIT.format(name=name, arc=arc, curv=curv, clothoid=cl,
                          guardrails="  guardrails: {left_offset_m: 1.0, right_offset_m: 1.0}\n" if rails else "")
              for name, arc, curv, cl, rails in EXITS] + [EMPTY]
    for text in scenes:
        sc = parse_scenario(text)
        runs = _runs(sc, levels, seeds)
        silent = [f"{sum(r.passed for r in runs[lv])}/{seeds}" for lv in levels]
        times = [", ".join(f"{r.warning_time_s:.2f}" if r.warning_time_s is not None else "-" for r in runs[lv])
                 for lv in levels]
        print(f"| {sc.name} | " + " | ".join(silent) + " | " + " | ".join(times) + " |", flush=True)


if __name__ == "__main__":
    main()
