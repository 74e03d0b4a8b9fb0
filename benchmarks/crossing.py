"""Crossing cars: how often the radar reports them moving (far), and how well each level follows them (near).

Far: a car crosses the ego's road (``ars408_like``, the ego standing) at 150 m and 20 m/s, at 100 m and 10 m/s and
at 60 m and 3 m/s, 4 s each, seeds 1–6, at the detection level. Printed per case: the cycles in which an object lies
within 5 m of the car (seen), and of those the cycles in which such an object is reported moving, oncoming or
crossing. Far out a crossing car's speed is across the line of sight, where only position differences measure it,
and the radar tracker's rules for standing reflectors (a hop, a coast: ``radarnode/perception/tracker.py``) cost it
some cycles.

Near: a car crosses 35 m ahead from the left at 10, 15, 20 and 30 m/s (the ego standing, ``ars408_like``), seeds
1–3, at the object, detection and signal levels. Printed per case and level: the cycles in which the car's nearest
point lies in the field of view, the cycles in which an object lies within the car's half diagonal + 1.5 m of its
centre, the cycles in which that object's velocity lies within 3 m/s of the car's, the IDs it was listed under,
and the objects near no actor (summed over the cycles). There the car's motion is almost all across the line of
sight: the object level's tracker starts from the measured velocity; the radar tracker's from the radial speed
and a prior across the line of sight (σ 2 m/s, ``TANGENTIAL_PRIOR_VAR``), which it corrects from the positions only.

FCW: a car crosses the ego's road from the left (``ars408_like``, two lanes of 3.6 m, the ego in the right one) and
clears the ego's lane 1.5 s before the ego gets there, so that no warning is due: ego 10, 15 and 20 m/s, car 10, 15
and 20 m/s, starting 12 m (first tracked within 20° of the ego's road) or 40 m to the left, seeds 1–10, at the object
and detection levels (``radarnode.consumer.evaluate.simulate``). Printed per case and level: the seeds in which the
consumer warned. The object level's warnings are the consumer's rule, not the radar's (at 15 m/s and below the
car is in the lane within the warning's reach while the ego is still far: a car in the lane is a threat whatever its
speed across); the detection level should warn where the object level warns.

Run: ``python benchmarks/crossing.py [--only far|near|fcw] [--root DIR]`` (far: a few seconds; near and fcw: about a
minute each;
``--root`` imports radarnode from another tree, e.g. ``git archive REV | tar -x -C DIR``, to compare two versions
with one script).
"""

from __future__ import annotations

import argparse

import numpy as np

from tree import use_tree  # --root DIR: radarnode from another tree

TREE = use_tree()

from radarnode.perception.types import DYN_CROSSING_MOVING, DYN_MOVING, DYN_ONCOMING  # noqa: E402
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig, in_fov  # noqa: E402
from radarnode.radar.setup import parse_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

CASES = ((150.0, 20.0), (100.0, 10.0), (60.0, 3.0))
SEEDS = (1, 2, 3, 4, 5, 6)
NEAR_X_M, NEAR_SPEEDS, NEAR_SEEDS, NEAR_LEVELS = 35.0, (10.0, 15.0, 20.0, 30.0), (1, 2, 3), ("object", "detection",
                                                                                         "signal")
#: an object's velocity within this of the car's counts as right (m/s)
NEAR_SPEED_OK_MPS = 3.0


def crossing(x_m: float, speed_mps: float, seed: int) -> tuple[int, int]:
    """(cycles seen, cycles reported moving) of one car crossing at ``x_m`` ahead."""
    sc = parse_scenario(f"""
name: crossing
duration_s: 4.0
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: 0.0}}
road: {{lanes: 1, ego_lane: 0}}
actors:
  - {{id: c, class: car, x_m: {x_m}, y_m: -20.0, speed_mps: {speed_mps}, heading_deg: 90.0}}
""")
    cfg = radar_config(sc)
    model = make_model("detection", Scene(sc), cfg.preset, np.random.default_rng(seed), cfg.signal)
    seen = moving = 0
    for k in range(sc.num_cycles):
        frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
        ol = frame.objects
        near = np.hypot(ol.dist_long_m - view.x_m[0], ol.dist_lat_m - view.y_m[0]) < 5.0
        if near.any():
            seen += 1
            moving += bool(np.isin(ol.dyn_prop[near], (DYN_MOVING, DYN_ONCOMING, DYN_CROSSING_MOVING)).any())
    return seen, moving


def near_crossing(speed_mps: float, seed: int, level: str) -> tuple[int, int, int, dict, int]:
    """(cycles in view, cycles followed, cycles at the right velocity, {ID: cycles followed under it}, other objects)
    of a car crossing NEAR_X_M ahead from the left at ``speed_mps``, at ``level`` (also tests/test_track_start.py)."""
    sc = parse_scenario(f"""
name: near_crossing
duration_s: {2.0 * 70.0 / speed_mps:.3f}
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: 0.0}}
road: {{lanes: 2, lane_width_m: 3.6, ego_lane: 0}}
actors:
  - {{id: c, class: car, x_m: {NEAR_X_M}, y_m: 70.0, speed_mps: {speed_mps}, heading_deg: -90.0}}
""")
    cfg = radar_config(sc)
    p = cfg.preset
    scene = Scene(sc)
    model = make_model(level, scene, p, np.random.default_rng(seed), cfg.signal, clusters_wanted=False)
    reach = 0.5 * float(np.hypot(scene.length_m[0], scene.width_m[0])) + 1.5
    in_view = followed = right = others = 0
    ids: dict[int, int] = {}
    for k in range(sc.num_cycles):
        frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=p.max_range_m, clusters=False))
        ol = frame.objects
        d = np.hypot(ol.dist_long_m - view.centre_x_m[0], ol.dist_lat_m - view.centre_y_m[0])
        others += int(np.sum(d >= reach))
        if not in_fov(p, view.range_m[:1], view.azimuth_rad[:1])[0]:
            continue
        in_view += 1
        if len(ol) and d.min() < reach:
            i = int(np.argmin(d))
            followed += 1
            ids[int(ol.id[i])] = ids.get(int(ol.id[i]), 0) + 1
            right += bool(np.hypot(ol.vrel_long_mps[i] - view.vx_mps[0], ol.vrel_lat_mps[i] - view.vy_mps[0])
                          < NEAR_SPEED_OK_MPS)
    return in_view, followed, right, ids, others


FCW_EGO, FCW_CAR, FCW_FROM, FCW_SEEDS, FCW_LEVELS = (10.0, 15.0, 20.0), (10.0, 15.0, 20.0), (12.0, 40.0), \
    tuple(range(1, 11)), ("object", "detection")


def crossing_fcw(ego_mps: float, car_mps: float, from_m: float, seed: int, level: str) -> bool:
    """Whether the consumer warned (FCW) while a car crossed from ``from_m`` to the left, clearing the ego's lane
    1.5 s before the ego got there (tests/test_track_start.py has three of these cases)."""
    from radarnode.consumer.evaluate import simulate
    t_arrive = (from_m + 4.0) / car_mps + 1.5
    sc = parse_scenario(f"""
name: crossing_fcw
duration_s: {round(t_arrive + 0.5, 2)}
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: {ego_mps}}}
road: {{lanes: 2, lane_width_m: 3.6, ego_lane: 0}}
ecu: {{acc_enabled: false, expect: {{no_fcw: true}}}}
actors:
  - {{id: x, class: car, x_m: {3.7 + ego_mps * t_arrive:.1f}, y_m: {from_m}, speed_mps: {car_mps}, heading_deg: -90}}
""")
    return simulate(sc, fidelity=level).warning_time_s is not None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", choices=("far", "near", "fcw"), help="print one table only")
    ap.add_argument("--root", help="import radarnode from this tree (read before radarnode is imported)")
    args = ap.parse_args()
    if args.only in (None, "far"):
        print(f"radarnode from {TREE}; detection level, ars408_like, seeds {SEEDS[0]}–{SEEDS[-1]}\n")
        print("| crossing car | cycles seen | reported moving | fraction |")
        print("|---|---:|---:|---:|")
        for x_m, v in CASES:
            seen = moving = 0
            for seed in SEEDS:
                s, m = crossing(x_m, v, seed)
                seen, moving = seen + s, moving + m
            print(f"| {x_m:.0f} m ahead, {v:.0f} m/s | {seen} | {moving} | {moving / max(seen, 1):.2f} |", flush=True)
    if args.only in (None, "near"):
        print(f"\nradarnode from {TREE}; a car crossing {NEAR_X_M:.0f} m ahead, the ego standing, ars408_like, seeds "
              f"{NEAR_SEEDS[0]}–{NEAR_SEEDS[-1]} summed; velocity right: within {NEAR_SPEED_OK_MPS:g} m/s of the car's\n")
        print("| crossing speed | level | cycles in view | followed | velocity right | fraction right | IDs (per seed) "
              "| other objects |")
        print("|---|---|---:|---:|---:|---:|---|---:|")
        for v in NEAR_SPEEDS:
            for level in NEAR_LEVELS:
                total = [0, 0, 0, 0]
                per_seed = []
                for seed in NEAR_SEEDS:
                    a, b, c, ids, o = near_crossing(v, seed, level)
                    total = [total[0] + a, total[1] + b, total[2] + c, total[3] + o]
                    per_seed.append(str(len(ids)))
                print(f"| {v:.0f} m/s | {level} | {total[0]} | {total[1]} | {total[2]} | {total[2] / max(total[0], 1):.2f} "
                      f"| {', '.join(per_seed)} | {total[3]} |", flush=True)
    if args.only in (None, "fcw"):
        print(f"\nradarnode from {TREE}; a car crossing the ego's road from the left, clear of the ego's lane 1.5 s before "
              f"the ego gets there, ars408_like; seeds {FCW_SEEDS[0]}–{FCW_SEEDS[-1]} in which the consumer warned (FCW)\n")
        print("| ego | car | from | " + " | ".join(f"{lv} level" for lv in FCW_LEVELS) + " |")
        print("|---:|---:|---:|" + "---:|" * len(FCW_LEVELS))
        for from_m in FCW_FROM:
            for ego in FCW_EGO:
                for car in FCW_CAR:
                    cells = [sum(crossing_fcw(ego, car, from_m, seed, lv) for seed in FCW_SEEDS) for lv in FCW_LEVELS]
                    print(f"| {ego:.0f} m/s | {car:.0f} m/s | {from_m:.0f} m | "
                          + " | ".join(f"{c} of {len(FCW_SEEDS)}" for c in cells) + " |", flush=True)


if __name__ == "__main__":
    main()
