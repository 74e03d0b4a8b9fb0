"""What the detection level's ≥ 200× real time (issue 9 item 7) would need: the cost of its parts when batched.

The detection level costs about 6.5 ms a frame on ``highway_cut_in`` (``fidelity.py --detection-only``), flat over
some 6,400 Python-level calls a frame; 200× real time is 0.36 ms a frame. This script asks how far numpy alone could
go if the model were computed for many cycles at once, as the object level computes its chunks:

* ``detection_model.detect`` on the scatterers of 1, 4, 16 and 64 consecutive frames concatenated into one call (their
  cells collide across frames, so there are fewer cells than a batched model would have: a lower bound on its
  cost), per frame and chirp sequence (``ars408_like`` runs two, the staggered pair);
* the radar tracker and the cluster list of one frame (``ObjectTracker.step``, ``clusters_from_detections``), which
  run in order: a frame's tracks are the last frame's, updated.

Nothing here is a product path: it only times the model's own functions on the scenario's frames. The random draws of
the batched calls are not those of the frames (``rng`` is this script's).

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/detection_floor.py [--frames N] [--repeats R] [--root DIR]``.
Prints a Markdown table (medians of R repeats).
"""

from __future__ import annotations

import argparse
import dataclasses
import statistics
import time
from pathlib import Path

import numpy as np

import machine  # noqa: E402  (the day's machine speed, printed beside the figures)
from tree import ROOT, use_tree  # --root DIR: radarnode from another tree

use_tree()

from radarnode.perception.tracker import clusters_from_detections  # noqa: E402
from radarnode.radar import detection_model  # noqa: E402
from radarnode.radar.models import ego_motion, make_model, tracker_for  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.scatterers import Scatterers  # noqa: E402
from radarnode.radar.setup import load_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

BUDGET_S = 0.072 / 200        # 200× real time at the ARS 408's 72-ms cycle


def _concat(parts: list[Scatterers]) -> Scatterers:
    return Scatterers(**{f.name: np.concatenate([getattr(s, f.name) for s in parts])
                         for f in dataclasses.fields(Scatterers)})


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=64, help="frames of the scene timed (a multiple of 64)")
    ap.add_argument("--repeats", type=int, default=5, help="repeats; the table gives their medians")
    ap.add_argument("--root", type=Path, help="import radarnode from this tree (another version) instead")
    args = ap.parse_args()
    path = ROOT / "scenarios" / "highway_cut_in.yaml"
    sc = load_scenario(path)
    p = radar_config(sc).preset
    model = make_model("detection", Scene(sc), p, np.random.default_rng(sc.seed), radar_config(sc).signal)
    cfg = RuntimeConfig(max_distance_m=p.max_range_m)
    # the scene's own frames, stepped through the model (its tracker, its detections), with their scatterers kept
    scats, dets, motion = [], [], []
    for k in range(args.frames):
        frame, view = model.step(k * sc.period_s, cfg)
        scats.append(model.info.scatterers)
        dets.append(model.info.detections)
        motion.append(ego_motion(model.scene, k * sc.period_s, view, None))      # as the model gives the tracker
    rng = np.random.default_rng(1)
    rows = []
    for batch in (1, 4, 16, 64):
        if args.frames % batch:
            continue
        groups = [_concat(scats[i:i + batch]) for i in range(0, args.frames, batch)]
        runs = []
        for _ in range(args.repeats):
            t0 = time.perf_counter()
            for g in groups:
                detection_model.detect(p, g, rng, model.statistic)
            runs.append((time.perf_counter() - t0) / args.frames)
        rows.append((f"detect, {batch} frame{'s' if batch > 1 else ''} a call", statistics.median(runs),
                     len(groups[0]) / batch))
    # the tracker and the cluster list, frame by frame as they run (a fresh tracker over the same detections)
    runs_t, runs_c = [], []
    for _ in range(args.repeats):
        tracker = tracker_for(p, sc.period_s)
        t_track = t_clus = 0.0
        for k, det in enumerate(dets):
            sv, yaw = motion[k]
            t0 = time.perf_counter()
            clusters_from_detections(det, p.near_range_m, sv)
            t1 = time.perf_counter()
            tracker.step(k * sc.period_s, det, sv, yaw)
            t_track += time.perf_counter() - t1
            t_clus += t1 - t0
        runs_t.append(t_track / len(dets))
        runs_c.append(t_clus / len(dets))
    print(f"highway_cut_in.yaml, preset {p.name} ({'two chirp sequences' if p.stagger_chirp_period_s else 'one'} a "
          f"cycle), {args.frames} frames, medians of {args.repeats} repeats; 200× real time is "
          f"{BUDGET_S * 1e3:.2f} ms a frame")
    print(machine.line() + "\n")
    print("| part | ms a frame | scatterers a frame | of the 200× budget |")
    print("|---|---:|---:|---:|")
    for name, sec, n in rows:
        print(f"| {name} (one chirp sequence) | {sec * 1e3:.3f} | {n:.0f} | {sec / BUDGET_S:.1f}× |")
    for name, sec in (("radar tracker (ObjectTracker.step)", statistics.median(runs_t)),
                      ("cluster list", statistics.median(runs_c))):
        print(f"| {name} | {sec * 1e3:.3f} | | {sec / BUDGET_S:.1f}× |")


if __name__ == "__main__":
    main()
