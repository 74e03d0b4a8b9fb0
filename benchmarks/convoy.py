"""An oncoming convoy whose closing speed the staggered pair's second sequence aliases to zero, at every level.

Five cars 30 m apart oncoming in the next lane at 14.05 m/s past ``ars408_like`` (ego 20 m/s): a range rate of
−34.05 m/s, two wraps of the second sequence (2·17.02 m/s), one of the first plus +4.86 m/s. A car has several
reflectors; where the first sequence detects more of them than the second, the staggered pair cannot pair the rest
(``radarnode.radar.ambiguity``). Printed per level and seed, over 10.4 s (144 cycles): the cycles whose object list
holds an object receding (every car closes), and the cluster list's ambiguous detections (AmbigState 1) of all.

Run: ``python benchmarks/convoy.py [--levels object,detection,signal] [--seeds 1,2] [--root DIR]`` (about 4
minutes, most of it the signal level; ``--root`` imports radarnode from another tree, e.g. ``git archive REV | tar
-x -C DIR``, to compare two versions with one script).
"""

from __future__ import annotations

import argparse

import numpy as np

from tree import use_tree  # --root DIR: radarnode from another tree

TREE = use_tree()

from radarnode.perception.types import AMBIG_AMBIGUOUS  # noqa: E402
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.setup import parse_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

CARS = "".join(f"  - {{id: c{i}, class: car, x_m: {150.0 + 30.0 * i}, lane: 0, speed_mps: 14.05, "
               "heading_deg: 180.0}\n" for i in range(5))


def run(level: str, seed: int) -> tuple[int, int, int, int]:
    """(cycles, cycles listing a receding object, ambiguous clusters, clusters) of one run."""
    sc = parse_scenario(f"""
name: convoy
duration_s: 10.4
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: 20.0}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1}}
actors:
{CARS}""")
    rc = radar_config(sc)
    model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal, clusters_wanted=True)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=True)
    receding = ambiguous = clusters = 0
    for k in range(sc.num_cycles):
        frame, _ = model.step(k * sc.period_s, cfg)
        receding += int(np.any(frame.objects.vrel_long_mps > 0.0))
        ambiguous += int(np.sum(frame.clusters.ambig_state == AMBIG_AMBIGUOUS))
        clusters += len(frame.clusters)
    return sc.num_cycles, receding, ambiguous, clusters


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--levels", default="object,detection,signal")
    ap.add_argument("--seeds", default="1,2")
    ap.add_argument("--root", help="import radarnode from this tree")
    args = ap.parse_args()
    print(f"radarnode from {TREE}; ars408_like, an oncoming convoy at −34.05 m/s range rate\n")
    print("| level | seed | cycles | cycles listing a receding object | ambiguous clusters / clusters |")
    print("|---|---:|---:|---:|---:|")
    for level in args.levels.split(","):
        for seed in (int(s) for s in args.seeds.split(",")):
            n, rec, amb, cl = run(level, seed)
            print(f"| {level} | {seed} | {n} | {rec} | {amb} / {cl} |", flush=True)


if __name__ == "__main__":
    main()
