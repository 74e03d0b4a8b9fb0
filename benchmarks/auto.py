"""``auto`` on every shipped scenario: its accuracy against the signal level and its cost against the object level.

Per scenario and seed (``--seeds``, default 1, 2, 3: one seed is not enough where a car stands at the edge of
the chain's resolution, beside guardrail posts), the first ``--frames`` cycles at four levels (object, detection,
signal, auto), the same seed at every level. Accuracy is judged on the object list each level sends: an actor with a part inside the field of view counts as
reported in a cycle when an object lies within 2.5 m of its point the radar can see — the nearest point of its outline
inside the field of view (``nearest_in_fov``) — after the levels' trackers have had 5 cycles to confirm; the rest of
the objects are extra (false or split). Fractions are means over the seeds; ``auto − signal`` is the difference of
the reported fractions, with its smallest and largest value over the seeds. Cost is the median time per cycle of
the radar model (scene, radar and perception, no wire) over every seed's cycles.

Run: ``python benchmarks/auto.py [--frames N] [--seeds 1,2,3] [--only NAME ...]`` (about 3 minutes a seed at
the default 40 frames).
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

from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig, in_fov, nearest_in_fov  # noqa: E402
from radarnode.radar.setup import load_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

LEVELS = ("object", "detection", "signal", "auto")
GATE_M = 2.5


def run(path: Path, level: str, frames: int, seed: int | None = None) -> dict:
    sc = load_scenario(path)
    if seed is not None:
        sc = dataclasses.replace(sc, seed=seed)
    scene = Scene(sc)
    p = radar_config(sc).preset
    clusters = sc.radar.output == "clusters"
    model = make_model(level, scene, p, np.random.default_rng(sc.seed), radar_config(sc).signal, clusters_wanted=clusters)
    cfg = RuntimeConfig(max_distance_m=p.max_range_m, clusters=clusters)
    times, reported, trials, extra = [], 0, 0, 0
    visible = ~scene.is_guardrail
    n = min(frames, int(sc.duration_s / sc.period_s))
    for k in range(n):
        t0 = time.perf_counter()
        frame, view = model.step(k * sc.period_s, cfg)
        times.append(time.perf_counter() - t0)
        if k < 5:
            continue
        ol = frame.objects
        # each actor's point the radar can see: its outline's nearest point inside the field of view (a car half in
        # a sector is seen at its part there, at every level)
        x_in, y_in = nearest_in_fov(p, view, scene.length_m, scene.width_m)
        r_in = np.hypot(x_in, y_in) if view.z_m is None else np.sqrt(x_in ** 2 + y_in ** 2 + view.z_m ** 2)
        seen = visible & in_fov(p, r_in, np.arctan2(y_in, x_in))
        used = np.zeros(len(ol), dtype=bool)
        for i in np.flatnonzero(seen):
            trials += 1
            d = np.hypot(ol.dist_long_m - x_in[i], ol.dist_lat_m - y_in[i])
            if d.size and d.min() <= GATE_M:
                reported += 1
                used[int(np.argmin(d))] = True
        extra += int((~used).sum())
    return {"times": times[1:], "median_ms": statistics.median(times[1:]) * 1e3, "reported": reported / max(trials, 1),
            "extra": extra / max(n - 5, 1), "choices": getattr(model, "choices", None),
            "actor_frames": getattr(model, "actor_frames", None)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--frames", type=int, default=40)
    ap.add_argument("--seeds", default="1,2,3", help="comma-separated seeds (default 1,2,3)")
    ap.add_argument("--only", nargs="*", default=None, help="scenario names (default: every shipped scenario)")
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    print(f"radarnode auto benchmark, {time.strftime('%Y-%m-%d')}, `python benchmarks/auto.py --frames {args.frames} "
          f"--seeds {args.seeds}`\n")
    print("| scenario | preset | reported: object / detection / signal / auto | auto − signal (min … max over seeds) | "
          "extra objects/cycle: object / detection / signal / auto | ms/cycle: object / detection / signal / auto | "
          "auto cost / object | auto's actor-cycles at detection level |")
    print("|---|---|---|---:|---|---|---:|---:|")
    paths = sorted((ROOT / "scenarios").glob("*.yaml"))
    if args.only:
        paths = [p for p in paths if p.stem in args.only]
    for path in paths:
        runs = {lv: [run(path, lv, args.frames, seed) for seed in seeds] for lv in LEVELS}
        rep = {lv: float(np.mean([r["reported"] for r in runs[lv]])) for lv in LEVELS}
        extra = {lv: float(np.mean([r["extra"] for r in runs[lv]])) for lv in LEVELS}
        ms = {lv: statistics.median([t for r in runs[lv] for t in r["times"]]) * 1e3 for lv in LEVELS}
        diff = [a["reported"] - s["reported"] for a, s in zip(runs["auto"], runs["signal"])]
        det = sum((r["actor_frames"] or {}).get("detection", 0) for r in runs["auto"])
        obj = sum((r["actor_frames"] or {}).get("object", 0) for r in runs["auto"])
        sc = load_scenario(path)
        print(f"| {path.stem} | {sc.radar.preset} | "
              + " / ".join(f"{rep[lv]:.2f}" for lv in LEVELS)
              + f" | {rep['auto'] - rep['signal']:+.2f} ({min(diff):+.2f} … {max(diff):+.2f}) | "
              + " / ".join(f"{extra[lv]:.2f}" for lv in LEVELS) + " | "
              + " / ".join(f"{ms[lv]:.2f}" for lv in LEVELS)
              + f" | {ms['auto'] / ms['object']:.1f}× | {det / max(det + obj, 1):.0%} |", flush=True)


if __name__ == "__main__":
    main()
