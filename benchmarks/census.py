"""How many detections each body gives a frame at the detection level and in the signal chain, on the same scatterers.

Issue 9 asks for levels that agree with each other. The calibration (``benchmarks/calibration.py``) checks it on point
targets; this checks it on the shipped scenarios' bodies — cars seen obliquely, trucks beside the ego, bridge decks and
gantries across the road — where a body is many scatterers and the count of its detections is what a cluster list and
the trackers see. For every shipped scenario (its first radar, its first chirp sequence), every ``--stride``-th cycle:
the scatterers the scatterer levels draw (the scenario's seed, each actor's fluctuation drawn anew each frame), then
``detection_model.detect`` and the signal chain on ``synthesize_rd`` of the very same scatterers, each with its own
noise (seeds (1, cycle) and (2, cycle)). A detection is counted for the actor of the nearest scatterer within 3 m
(x, y); farther from every scatterer it is `other` (noise false alarms, and the chain's angle glint of a near car: two
reflectors in anti-phase put peaks beyond the body's width, which the detection level does not report).

Prints one Markdown row per scenario and actor (detections a frame: detection level, signal level, difference), then
the mean absolute and the mean signed difference over the actors, overall and by kind (structures above the road,
vehicles, the rest).

Run: ``.venv/bin/python benchmarks/census.py [--stride 5] [--jobs 2] [--only NAME ...] [--root TREE]``.
"""

from __future__ import annotations

import argparse
import multiprocessing
import statistics
import sys
import time
from pathlib import Path

from tree import ROOT, use_tree  # --root DIR: radarnode from another tree

use_tree(sys.argv)

import numpy as np  # noqa: E402

from radarnode.radar import detection_model  # noqa: E402
from radarnode.radar.chain import DspChain  # noqa: E402
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.setup import load_scenario, radar_config, radar_scenarios  # noqa: E402
from radarnode.radar.signal_model import synthesize_rd  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

#: a detection farther than this from every scatterer (x, y) is counted as `other`
NEAREST_M = 3.0
VEHICLES = ("car", "truck", "motorcycle", "bicycle", "van", "bus")


def census(path: Path, stride: int) -> tuple[str, int, list[tuple[str, str, bool]], np.ndarray]:
    """(scenario name, frames, [(actor id, class, above the road)], counts (2, actors + 1): detection, signal)."""
    sc = radar_scenarios(load_scenario(path))[0]
    rc = radar_config(sc)
    p = rc.preset
    scene = Scene(sc)
    model = make_model("detection", scene, p, np.random.default_rng(sc.seed), rc.signal, clusters_wanted=False)
    cfg = RuntimeConfig(max_distance_m=p.max_range_m, clusters=False)
    chain = DspChain(p)
    n = len(sc.actors)
    counts = np.zeros((2, n + 1))
    frames = 0
    for k in range(0, sc.num_cycles, stride):
        t = k * sc.period_s
        scat = model.scatterers(t, scene.view(t), cfg)
        if len(scat) == 0:
            continue
        frames += 1
        det = detection_model.detect(p, scat, np.random.default_rng((1, k)), chain.statistic)
        sig = chain.process_rd(synthesize_rd(p, scat, np.random.default_rng((2, k))))
        for row, d in enumerate((det, sig)):
            if len(d) == 0:
                continue
            x, y = d.range_m * np.cos(d.azimuth_rad), d.range_m * np.sin(d.azimuth_rad)
            dist = np.hypot(x[:, None] - scat.x_m[None, :], y[:, None] - scat.y_m[None, :])
            j = np.argmin(dist, axis=1)
            actor = np.where(dist[np.arange(x.size), j] < NEAREST_M, scat.actor_index[j], -1)
            np.add.at(counts[row], np.where(actor >= 0, actor, n), 1.0)
    actors = [(a.id, a.object_class, bool(up)) for a, up in zip(sc.actors, scene.elevated)]
    return sc.name, frames, actors, counts


def _job(args: tuple[Path, int]):
    return census(*args)


def _positive(text: str) -> int:
    """A whole number ≥ 1 (argparse names the option and the value where it is not)."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"value {text!r} is not allowed; expected a whole number ≥ 1") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"value {text!r} is not allowed; expected a whole number ≥ 1")
    return value


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--stride", type=_positive, default=5, help="every this many cycles (default 5)")
    ap.add_argument("--jobs", type=_positive, default=2)
    ap.add_argument("--only", nargs="*", default=None, help="scenario file names without .yaml (default: all)")
    ap.add_argument("--root", default=None, help="import radarnode from this tree")
    args = ap.parse_args()
    t0 = time.perf_counter()
    paths = sorted((ROOT / "scenarios").glob("*.yaml"))
    if args.only:
        unknown = sorted(set(args.only) - {p.stem for p in paths})
        if unknown:
            ap.error(f"--only: value(s) {', '.join(unknown)} not allowed; expected names of scenarios/*.yaml "
                     "without .yaml")
        paths = [p for p in paths if p.stem in args.only]
    with multiprocessing.Pool(args.jobs) as pool:
        results = pool.map(_job, [(p, args.stride) for p in paths], chunksize=1)
    print(f"### Detections a frame per body, detection level against the signal chain on the same scatterers "
          f"(every {args.stride}th cycle of {len(paths)} scenarios)\n")
    print("| scenario | body | frames | detection | signal | difference |")
    print("|---|---|---:|---:|---:|---:|")
    kinds: dict[str, list[float]] = {"structure": [], "vehicle": [], "other body": []}
    for name, frames, actors, counts in results:
        if frames == 0:
            continue
        rate = counts / frames
        for i, (aid, cls, up) in enumerate(actors):
            if counts[:, i].sum() == 0:
                continue
            d = rate[0, i] - rate[1, i]
            kinds["structure" if up else "vehicle" if cls in VEHICLES else "other body"].append(d)
            print(f"| {name} | {aid} ({cls}) | {frames} | {rate[0, i]:.2f} | {rate[1, i]:.2f} | {d:+.2f} |")
        print(f"| {name} | other | {frames} | {rate[0, -1]:.2f} | {rate[1, -1]:.2f} | {rate[0, -1] - rate[1, -1]:+.2f} |")
    print("\n| bodies | count | mean abs. difference | mean difference (detection − signal) |")
    print("|---|---:|---:|---:|")
    every = [d for v in kinds.values() for d in v]
    for label, diffs in [("all", every)] + list(kinds.items()):
        if diffs:
            print(f"| {label} | {len(diffs)} | {statistics.fmean(abs(d) for d in diffs):.3f} | "
                  f"{statistics.fmean(diffs):+.3f} |")
    print(f"\n({time.perf_counter() - t0:.0f} s with {args.jobs} processes)")


if __name__ == "__main__":
    main()
