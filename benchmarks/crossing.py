"""Crossing cars at the detection level: how often the radar reports them moving.

A car crosses the ego's road (``ars408_like``, the ego standing) at 150 m and 20 m/s, at 100 m and 10 m/s and at
60 m and 3 m/s, 4 s each, seeds 1–6. Printed per case: the cycles in which an object lies within 5 m of the car
(seen), and of those the cycles in which such an object is reported moving, oncoming or crossing. Far out a
crossing car's speed is across the line of sight, where only position differences measure it, and the radar
tracker's rules for standing reflectors (a hop, a coast: ``radarnode/perception/tracker.py``) cost it some cycles.

Run: ``python benchmarks/crossing.py [--root DIR]`` (a few seconds; ``--root`` imports radarnode from another tree,
e.g. ``git archive REV | tar -x -C DIR``, to compare two versions with one script).
"""

from __future__ import annotations

import argparse

import numpy as np

from tree import use_tree  # --root DIR: radarnode from another tree

TREE = use_tree()

from radarnode.perception.types import DYN_CROSSING_MOVING, DYN_MOVING, DYN_ONCOMING  # noqa: E402
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.setup import parse_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

CASES = ((150.0, 20.0), (100.0, 10.0), (60.0, 3.0))
SEEDS = (1, 2, 3, 4, 5, 6)


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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", help="import radarnode from this tree (read before radarnode is imported)")
    ap.parse_args()
    print(f"radarnode from {TREE}; detection level, ars408_like, seeds {SEEDS[0]}–{SEEDS[-1]}\n")
    print("| crossing car | cycles seen | reported moving | fraction |")
    print("|---|---:|---:|---:|")
    for x_m, v in CASES:
        seen = moving = 0
        for seed in SEEDS:
            s, m = crossing(x_m, v, seed)
            seen, moving = seen + s, moving + m
        print(f"| {x_m:.0f} m ahead, {v:.0f} m/s | {seen} | {moving} | {moving / max(seen, 1):.2f} |", flush=True)


if __name__ == "__main__":
    main()
