"""``auto`` on every shipped scenario: its accuracy against the signal level and its cost against the object level.

Per scenario, the first ``--frames`` cycles at four levels (object, detection, signal, auto), same seed. Accuracy
is judged on the object list each level sends: an actor-cycle counts as reported when an object lies within
2.5 m of the actor's reported point (after the levels' trackers have had 5 cycles to confirm); the rest of the
objects are extra (false or split). ``auto vs signal`` is the difference of the reported fractions. Cost is the
median time per cycle of the radar model (scene, radar and perception, no wire).

Run: ``python benchmarks/auto.py [--frames N]`` (about 3 minutes at the default 40).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig, in_fov  # noqa: E402
from radarnode.radar.setup import load_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

LEVELS = ("object", "detection", "signal", "auto")
GATE_M = 2.5


def run(path: Path, level: str, frames: int) -> dict:
    sc = load_scenario(path)
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
        seen = visible & in_fov(p, view.range_m, view.azimuth_rad)
        used = np.zeros(len(ol), dtype=bool)
        for i in np.flatnonzero(seen):
            trials += 1
            d = np.hypot(ol.dist_long_m - view.x_m[i], ol.dist_lat_m - view.y_m[i])
            if d.size and d.min() <= GATE_M:
                reported += 1
                used[int(np.argmin(d))] = True
        extra += int((~used).sum())
    return {"median_ms": statistics.median(times[1:]) * 1e3, "reported": reported / max(trials, 1),
            "extra": extra / max(n - 5, 1), "choices": getattr(model, "choices", None),
            "actor_frames": getattr(model, "actor_frames", None)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--frames", type=int, default=40)
    args = ap.parse_args()
    print(f"radarnode auto benchmark, {time.strftime('%Y-%m-%d')}, `python benchmarks/auto.py --frames {args.frames}`\n")
    print("| scenario | preset | reported: object / detection / signal / auto | auto − signal | extra objects/cycle: "
          "object / detection / signal / auto | ms/cycle: object / detection / signal / auto | auto cost / object | auto's actor-cycles at "
          "detection level |")
    print("|---|---|---|---:|---|---|---:|---:|")
    for path in sorted((ROOT / "scenarios").glob("*.yaml")):
        res = {lv: run(path, lv, args.frames) for lv in LEVELS}
        a = res["auto"]
        af = a["actor_frames"] or {}
        share = af.get("detection", 0) / max(af.get("detection", 0) + af.get("object", 0), 1)
        sc = load_scenario(path)
        print(f"| {path.stem} | {sc.radar.preset} | "
              + " / ".join(f"{res[lv]['reported']:.2f}" for lv in LEVELS)
              + f" | {a['reported'] - res['signal']['reported']:+.2f} | "
              + " / ".join(f"{res[lv]['extra']:.2f}" for lv in LEVELS) + " | "
              + " / ".join(f"{res[lv]['median_ms']:.2f}" for lv in LEVELS)
              + f" | {a['median_ms'] / res['object']['median_ms']:.1f}× | {share:.0%} |", flush=True)


if __name__ == "__main__":
    main()
