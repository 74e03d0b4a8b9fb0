"""Classification and size of the reported objects against the scene, level by level (issue 15 item 4).

Runs the shipped scenarios with vehicles and pedestrians through the radar model at each level and compares
every reported object that stems from an actor (the model's truth tag) with that actor: a confusion matrix
of reported ARS 408 class against the scene's class, and the median and 90th-percentile absolute length and
width error for cars, trucks and pedestrians in the range bands 0–50, 50–100 and 100–200 m. Targets (issue
15) at detection and signal level: cars classed as car or truck in ≥ 90 % of their reported cycles within
100 m; median width error ≤ 0.5 m for cars within 50 m.

Run: ``.venv/bin/python benchmarks/classes.py [--levels object,detection,signal] [--seeds N]``. Markdown.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.perception.types import CLASS_NAMES  # noqa: E402
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.setup import load_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

SCENARIOS = ("highway_cut_in", "guardrail_traffic", "stopped_vehicle", "pedestrian_crossing", "acc_cut_in",
             "no_fcw_adjacent_stopped", "ncap_ccrm", "nhtsa_lead_slower")
SCENE_CLASSES = ("car", "truck", "pedestrian", "motorcycle", "bicycle", "point", "sign")
BANDS = ((0.0, 50.0), (50.0, 100.0), (100.0, 200.0))


def collect(level: str, seeds: int):
    rows = []   # (scene class, reported class code, range, length error, width error)
    for name in SCENARIOS:
        base = load_scenario(ROOT / "scenarios" / f"{name}.yaml")
        for seed in range(1, seeds + 1):
            sc = dataclasses.replace(base, seed=seed)
            rc = radar_config(sc)
            model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal)
            cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
            for k in range(sc.num_cycles):
                frame, view = model.step(k * sc.period_s, cfg)
                ol = frame.objects
                for j in np.flatnonzero(ol.actor_index >= 0):
                    a = sc.actors[int(ol.actor_index[j])]
                    if a.object_class == "guardrail":
                        continue
                    r = float(np.hypot(ol.dist_long_m[j], ol.dist_lat_m[j]))
                    rows.append((a.object_class, int(ol.obj_class[j]), r, abs(ol.length_m[j] - a.length),
                                 abs(ol.width_m[j] - a.width)))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--levels", default="object,detection,signal")
    ap.add_argument("--seeds", type=int, default=2)
    args = ap.parse_args()
    print(f"### Class and size against the scene: {len(SCENARIOS)} scenarios × seeds 1–{args.seeds}\n")
    for level in args.levels.split(","):
        rows = collect(level, args.seeds)
        print(f"#### {level} level ({len(rows)} object-cycles)\n")
        print("| scene class \\ reported | " + " | ".join(CLASS_NAMES) + " | car or truck within 100 m |")
        print("|---|" + "---:|" * (len(CLASS_NAMES) + 1))
        for c in SCENE_CLASSES:
            sel = [r for r in rows if r[0] == c]
            if not sel:
                continue
            counts = np.bincount([r[1] for r in sel], minlength=len(CLASS_NAMES))
            near = [r for r in sel if r[2] <= 100.0]
            vt = f"{np.mean([r[1] in (1, 2) for r in near]):.0%}" if near else "-"
            print(f"| {c} | " + " | ".join(str(int(x)) for x in counts) + f" | {vt} |")
        print("\n| class | range | n | length error median / p90 | width error median / p90 |")
        print("|---|---|---:|---:|---:|")
        for c in ("car", "truck", "pedestrian"):
            for lo, hi in BANDS:
                sel = np.array([(r[3], r[4]) for r in rows if r[0] == c and lo <= r[2] < hi])
                if sel.size == 0:
                    continue
                med, p90 = np.median(sel, axis=0), np.percentile(sel, 90, axis=0)
                print(f"| {c} | {lo:.0f}–{hi:.0f} m | {len(sel)} | {med[0]:.2f} / {p90[0]:.2f} m | "
                      f"{med[1]:.2f} / {p90[1]:.2f} m |")
        print(flush=True)


if __name__ == "__main__":
    main()
