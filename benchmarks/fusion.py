"""Several radars fused: how well the consumer's track-to-track fusion keeps one fused object per actor.

Per shipped multi-radar scenario, level and seed, every frame the radars send goes through the consumer
(:class:`radarnode.consumer.fusion.FusingConsumer`, mounts from the scenario) and each fused list is compared with
the truth in the vehicle frame: an actor inside some radar's field of view is *covered* when a fused object lies
within 2.5 m of the actor's outline (its box; every radar reports some point of it); *split* counts the fused
objects beyond the first within that distance (one actor, two fused tracks), beside the same count in the single
radar's own list that has most (a radar that splits a near car gives the fusion two objects of it); *IDs per actor* is how many fused
IDs covered it over the run (1: one track from the first look to the last, through every hand-over between
radars); *by several* is the share of covered actor-rounds seen by more than one radar. Position error: the
distance of the nearest fused object from the outline (0 on it), median and 90th percentile, beside the same
for the best single radar's object of that round (the one nearest the outline, from its own list).

Run: ``python benchmarks/fusion.py [--seeds 1,2,3] [--levels object,detection]`` (about a minute).
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.consumer.fusion import FusingConsumer, to_vehicle  # noqa: E402
from radarnode.consumer.path import SensorMount  # noqa: E402
from radarnode.radar.object_model import in_fov  # noqa: E402
from radarnode.radar.setup import load_scenario  # noqa: E402
from radarnode.wire.group import ego_motion_for, make_node  # noqa: E402
from radarnode.wire.runner import SimulatedClock, run_node  # noqa: E402

SCENARIOS = ("front_and_corners", "intersection_crossing")
GATE_M = 2.5


def outline_distance(px, py, cx, cy, heading, length, width):
    """Distance of points (px, py) from the outline of a box (centre, heading, length, width); 0 on or inside."""
    c, s = math.cos(heading), math.sin(heading)
    dx, dy = px - cx, py - cy
    u, v = c * dx + s * dy, -s * dx + c * dy
    ou, ov = np.maximum(np.abs(u) - length / 2, 0.0), np.maximum(np.abs(v) - width / 2, 0.0)
    return np.hypot(ou, ov)


def run(name: str, level: str, seed: int) -> dict:
    import dataclasses
    sc = dataclasses.replace(load_scenario(ROOT / "scenarios" / f"{name}.yaml"), seed=seed)
    node = make_node(sc, fidelity=level)
    frames, outs = [], []
    run_node(node, clock=SimulatedClock(), sinks=[frames.append], vehicle=ego_motion_for(node), on_cycle=outs.append)
    mounts = {r.sensor_id: SensorMount.of(r.mount) for r in sc.sensors}
    fc = FusingConsumer(mounts)
    rounds = [f for batch in fc.feed(frames) for f in [batch]]
    fc.flush()
    rounds += fc.drain()
    m0 = mounts[sc.radars[0].sensor_id]
    covered = trials = split = several = own_split = 0
    err_f, err_s = [], []
    ids: dict[int, set] = {}
    scene = node.nodes[0].scene
    for (cycles, fused), out in zip(rounds, outs):
        view = out.view                                  # the first radar's view (sensor frame) of the truth
        cx, cy = m0.to_vehicle(view.centre_x_m, view.centre_y_m)
        heading = view.orientation_rad + math.radians(m0.yaw_deg)
        seen = np.zeros(scene.n, dtype=bool)
        for n in node.nodes:                               # inside any radar's field of view
            v = n.scene.view(out.t_s)
            seen |= in_fov(n.preset, v.range_m, v.azimuth_rad)
        singles = [to_vehicle(sid, c.timestamp, c.objects, mounts[sid]) for sid, c in cycles.items()]
        for i in np.flatnonzero(seen & ~scene.is_guardrail):
            trials += 1
            d = outline_distance(fused.x_m, fused.y_m, cx[i], cy[i], heading[i], scene.length_m[i], scene.width_m[i])
            near = np.flatnonzero(d <= GATE_M)
            if near.size == 0:
                continue
            covered += 1
            split += near.size - 1
            k = near[np.argmin(d[near])]
            ids.setdefault(int(i), set()).add(int(fused.id[k]))
            several += bin(int(fused.sensors[k])).count("1") > 1
            err_f.append(d[k])
            dists = [outline_distance(so.pos[:, 0], so.pos[:, 1], cx[i], cy[i], heading[i], scene.length_m[i],
                                      scene.width_m[i]) for so in singles if len(so.ids)]
            best = min((float(np.min(x)) for x in dists), default=math.inf)
            own_split += max((int(np.sum(x <= GATE_M)) - 1 for x in dists), default=0)
            if math.isfinite(best):
                err_s.append(best)
    return {"covered": covered / max(trials, 1), "split": split / max(covered, 1),
            "own_split": max(own_split, 0) / max(covered, 1),
            "ids": float(np.mean([len(v) for v in ids.values()])) if ids else math.nan,
            "several": several / max(covered, 1), "err_f": err_f, "err_s": err_s, "rounds": len(rounds),
            "cycles": len(outs)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--levels", default="object,detection")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    print(f"radarnode fusion benchmark, {time.strftime('%Y-%m-%d')}, `python benchmarks/fusion.py --seeds {args.seeds} "
          f"--levels {args.levels}`\n")
    print("| scenario | level | fused rounds / cycles | covered | split per covered: fused / one radar's own | fused IDs per actor | seen by several "
          "| fused error: median / p90 | best single radar: median / p90 |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for name in SCENARIOS:
        for level in args.levels.split(","):
            res = [run(name, level, s) for s in seeds]
            ef = np.concatenate([r["err_f"] for r in res])
            es = np.concatenate([r["err_s"] for r in res])
            mean = lambda k: float(np.mean([r[k] for r in res]))   # noqa: E731
            print(f"| {name} | {level} | {sum(r['rounds'] for r in res)} / {sum(r['cycles'] for r in res)} "
                  f"| {mean('covered'):.2f} | {mean('split'):.2f} / {mean('own_split'):.2f} | {mean('ids'):.2f} | {mean('several'):.2f} "
                  f"| {np.median(ef):.2f} / {np.percentile(ef, 90):.2f} m "
                  f"| {np.median(es):.2f} / {np.percentile(es, 90):.2f} m |", flush=True)


if __name__ == "__main__":
    main()
