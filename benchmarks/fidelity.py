"""The speed–accuracy trade of the three fidelity levels, measured.

Two scenes:

* ``scenarios/point_targets_mimo12.yaml`` — eight point reflectors; per level:
  range, range-rate and azimuth RMSE against ground truth (each reflector's
  point the radar can see: its nearest point inside the field of view), the same RMSE over
  the Cramér–Rao bound at each target's SNR, probability of detection, false
  alarms per frame. The object level is scored on its object list, the
  detection and signal levels on their detections (before the tracker).
* ``scenarios/highway_mimo12.yaml`` — a dense highway frame (~260
  scatterers); per level: frame time (median of the frames after the first two, and the mean of all frames: the
  object level computes its cycles in chunks, which the mean includes and the median does not), frames per
  second and real-time factor against the 72 ms cycle from the mean; and what ``auto`` chose and saved.

Run: ``python benchmarks/fidelity.py [--frames N] [--object-only | --detection-only | --speed-only]``. Prints
Markdown tables; ``--object-only`` prints only the object level's speed figures (its row of the highway_mimo12 table
and the highway_cut_in line, issue 9 item 7), in seconds instead of minutes; ``--detection-only`` the detection
level's line on highway_cut_in (the same item's ≥ 200×) and the frame's parts by the model's own timers (scene, radar,
perception).
"""

from __future__ import annotations

import argparse
import math
import statistics
import time
from pathlib import Path

import numpy as np

import machine  # noqa: E402  (the day's machine speed, printed beside the figures)
from tree import ROOT, use_tree  # --root DIR: radarnode from another tree

use_tree()

from radarnode.radar import equation  # noqa: E402
try:
    from radarnode.radar import tables  # noqa: E402
except ImportError:        # a tree from before the table cache
    tables = None
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig, nearest_in_fov  # noqa: E402
from radarnode.radar.setup import load_scenario, radar_config, with_signal  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

GATE_RANGE_M, GATE_SPEED_MPS, GATE_AZ_DEG = 1.5, 1.5, 5.0


def _estimates(level: str, model, frame):
    """(range, range rate, azimuth) of what the level reports, and the actor it came from where known."""
    if level == "object":
        ol = frame.objects
        r = np.hypot(ol.dist_long_m, ol.dist_lat_m)
        az = np.arctan2(ol.dist_lat_m, ol.dist_long_m)
        vr = ol.vrel_long_mps * np.cos(az) + ol.vrel_lat_mps * np.sin(az)
        return r, vr, az
    det = model.info.detections
    return det.range_m, det.range_rate_mps, det.azimuth_rad


def accuracy(path: Path, level: str, frames: int, dtype: str = "complex128") -> dict:
    sc = load_scenario(path)
    sc = with_signal(sc, dtype=dtype)
    scene = Scene(sc)
    p = radar_config(sc).preset
    model = make_model(level, scene, p, np.random.default_rng(sc.seed), radar_config(sc).signal)
    cfg = RuntimeConfig(max_distance_m=p.max_range_m)
    err, crb, hits, trials, false = [], [], 0, 0, 0
    for k in range(frames):
        t = k * sc.period_s
        frame, view = model.step(t, cfg)
        if k < 3:          # let the object level's tracker confirm its objects
            continue
        r, vr, az = _estimates(level, model, frame)
        # each reflector's point the radar can see: its outline's nearest point inside the field of view (as
        # benchmarks/auto.py judges; a 0.3-m reflector passing the ±60° edge a metre or two ahead is seen there)
        x_in, y_in = nearest_in_fov(p, view, scene.length_m, scene.width_m)
        tr, taz = np.hypot(x_in, y_in), np.arctan2(y_in, x_in)
        tvr = view.vx_mps * np.cos(taz) + view.vy_mps * np.sin(taz)
        snr = equation.snr_db(p, tr, scene.rcs_dbsm)
        used = np.zeros(r.size, dtype=bool)
        for i in range(scene.n):
            trials += 1
            d = (np.abs(r - tr[i]) / GATE_RANGE_M + np.abs(vr - tvr[i]) / GATE_SPEED_MPS
                 + np.abs(np.degrees(az - taz[i])) / GATE_AZ_DEG)
            if d.size == 0 or d.min() > 1.0:
                continue
            j = int(np.argmin(d))
            used[j] = True
            hits += 1
            err.append((r[j] - tr[i], vr[j] - tvr[i], az[j] - taz[i]))
            crb.append((equation.crb_range_m(p, snr[i]), equation.crb_speed_mps(p, snr[i]),
                        equation.crb_azimuth_rad(p, snr[i], taz[i])))
        false += int((~used).sum())
    e = np.array(err)
    c = np.array(crb)
    rmse = np.sqrt(np.mean(e ** 2, axis=0))
    bound = np.sqrt(np.mean(c ** 2, axis=0))
    return {"rmse": rmse, "ratio": rmse / bound, "pd": hits / max(trials, 1),
            "fa": false / max(frames - 3, 1), "crb": bound}


def speed(path: Path, level: str, frames: int, dtype: str = "complex128") -> dict:
    sc = load_scenario(path)
    sc = with_signal(sc, dtype=dtype)
    p = radar_config(sc).preset
    model = make_model(level, Scene(sc), p, np.random.default_rng(sc.seed), radar_config(sc).signal,
                       clusters_wanted=sc.radar.output == "clusters")
    cfg = RuntimeConfig(max_distance_m=p.max_range_m, clusters=sc.radar.output == "clusters")
    if hasattr(model, "planned_cycles"):    # as the runner tells it: the object level's chunks end with the run
        model.planned_cycles = frames
    times, scat = [], []
    parts: dict[str, float] = {}           # the model's own timers (StepInfo.seconds), summed over the frames
    for k in range(frames):
        t0 = time.perf_counter()
        model.step(k * sc.period_s, cfg)
        times.append(time.perf_counter() - t0)
        info = getattr(model, "info", None)
        if info is not None and info.scatterers is not None:
            scat.append(len(info.scatterers))
        for name, sec in (getattr(info, "seconds", None) or {}).items():
            parts[name] = parts.get(name, 0.0) + sec
    med = statistics.median(times[2:])
    mean = statistics.fmean(times)
    return {"median_s": med, "mean_s": mean, "rtf_mean": sc.period_s / mean,
            "scatterers": statistics.median(scat) if scat else float("nan"),
            "choices": getattr(model, "choices", None), "parts_s": {k: v / frames for k, v in parts.items()}}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--object-only", action="store_true", help="only the object level's speed figures")
    ap.add_argument("--speed-only", action="store_true", help="only the speed table (every level) and the object "
                    "level's highway_cut_in line")
    ap.add_argument("--detection-only", action="store_true", help="only the detection level's highway_cut_in line "
                    "(issue 9 item 7's ≥ 200× real time)")
    ap.add_argument("--root", type=Path, help="import radarnode from this tree (another version) instead")
    args = ap.parse_args()
    where = tables.cache_dir() if tables is not None else None
    print(f"(radarnode from {Path(equation.__file__).parents[2]}; the detection statistic's table cache: "
          f"{where if where is not None else 'off'}; the object level's mean includes computing the tables it "
          "does not hold)")
    print(machine.line() + "\n")
    points = ROOT / "scenarios" / "point_targets_mimo12.yaml"
    highway = ROOT / "scenarios" / "highway_mimo12.yaml"
    if args.detection_only:
        _detection_line(args.frames)
        return
    if args.object_only:
        print(f"### Speed, object level: {highway.name}, {args.frames} frames, cycle 72 ms\n")
        print("| level | scatterers/frame | frame time (median) | frame time (mean, all frames) | frames/s | "
              "real-time factor |")
        print("|---|---:|---:|---:|---:|---:|")
        s = speed(highway, "object", args.frames)
        print(f"| object | - | {s['median_s'] * 1e3:.2f} ms | {s['mean_s'] * 1e3:.2f} ms | {1.0 / s['mean_s']:.0f} | "
              f"{s['rtf_mean']:.1f}× |\n")
        _object_list_line(args.frames)
        return
    rows = [("object", "complex128"), ("detection", "complex128"), ("signal", "complex128"),
            ("signal", "complex64")]
    if not args.speed_only:
        print(f"### Accuracy: {points.name}, {args.frames} frames, mimo12\n")
        print("| level | range RMSE | range-rate RMSE | azimuth RMSE | range RMSE/CRB | range-rate RMSE/CRB | "
              "azimuth RMSE/CRB | Pd | false alarms/frame |")
        print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
        for level, dtype in rows:
            a = accuracy(points, level, args.frames, dtype)
            name = level if level != "signal" else f"signal ({dtype})"
            print(f"| {name} | {a['rmse'][0] * 100:.1f} cm | {a['rmse'][1] * 100:.1f} cm/s | "
                  f"{math.degrees(a['rmse'][2]):.3f}° | {a['ratio'][0]:.2f} | {a['ratio'][1]:.2f} | {a['ratio'][2]:.2f} | "
                  f"{a['pd']:.3f} | {a['fa']:.2f} |", flush=True)
        print(f"\n(CRB at the targets' SNR: range {a['crb'][0] * 100:.2f} cm, range rate {a['crb'][1] * 100:.2f} cm/s, "
              f"azimuth {math.degrees(a['crb'][2]):.3f}°)\n")
    print(f"### Speed: {highway.name}, {args.frames} frames, cycle 72 ms\n")
    print("| level | scatterers/frame | frame time (median) | frame time (mean, all frames) | frames/s | "
          "real-time factor |")
    print("|---|---:|---:|---:|---:|---:|")
    base = None
    for level, dtype in rows + [("auto", "complex128")]:
        s = speed(highway, level, args.frames, dtype)
        name = level if level != "signal" else f"signal ({dtype})"
        extra = ""
        if s["choices"]:
            extra = " — chose " + ", ".join(f"{k} {v}" for k, v in s["choices"].items() if v)
        print(f"| {name}{extra} | {s['scatterers']:.0f} | {s['median_s'] * 1e3:.2f} ms | {s['mean_s'] * 1e3:.2f} ms | "
              f"{1.0 / s['mean_s']:.0f} | {s['rtf_mean']:.1f}× |", flush=True)
        if level == "signal" and dtype == "complex128":
            base = s["mean_s"]
    s_obj = speed(highway, "object", args.frames)
    print(f"\nobject level against signal level (complex128), means of the same run: {base / s_obj['mean_s']:.0f}× "
          "faster")
    _object_list_line(args.frames)
    _detection_line(args.frames)


#: fresh object models run one after another for the object level's line: one run of 1024 cycles times only about
#: 15 ms of work, and its mean moved by ±7 % from run to run on the quiet machine (2026-12-06)
OBJECT_RUNS = 9


def _object_list_line(frames: int, runs: int = OBJECT_RUNS) -> None:
    """The object level's line on highway_cut_in: the first fresh model's figures (which pay for what a process
    computes once), then the median and the range of the means of ``runs`` fresh models (the first among them)."""
    obj_only = ROOT / "scenarios" / "highway_cut_in.yaml"
    cycles = max(frames, 1024)
    runs_s = [speed(obj_only, "object", cycles) for _ in range(max(runs, 1))]
    s_list = runs_s[0]
    period = s_list["mean_s"] * s_list["rtf_mean"]
    means = sorted(r["mean_s"] for r in runs_s)
    mid = statistics.median(means)
    print(f"object level on {obj_only.name} (object list only, no cluster list, {cycles} frames): "
          f"median {s_list['median_s'] * 1e6:.0f} µs per frame, mean {s_list['mean_s'] * 1e6:.0f} µs with the "
          f"chunk computations included: {s_list['rtf_mean']:.0f}× real time; over {len(means)} fresh models in "
          f"this process, the mean a frame {mid * 1e6:.1f} µs by the median ({means[0] * 1e6:.1f}–"
          f"{means[-1] * 1e6:.1f}): {period / mid:.0f}× real time ({period / means[-1]:.0f}–{period / means[0]:.0f}×)")


#: frames of the detection level's line: its first frame imports scipy's k-d tree and assignment (0.1–0.2 s, once
#: a process), which 60 frames' mean counted as 2–3 ms a frame; a run of 300 (22 s of the scene) spreads it as a log
#: of that length does
DETECTION_FRAMES = 300


def _detection_line(frames: int) -> None:
    """The detection level on the scene issue 9 item 7 names (guardrail posts on both sides, four cars), and what
    its lobe test (``detection_model._inside_lobes``, timed around each call) takes of it."""
    from radarnode.radar import detection_model
    scene = ROOT / "scenarios" / "highway_cut_in.yaml"
    lobes = [0.0, 0]
    inner = detection_model._inside_lobes

    def timed(*args, **kw):
        t0 = time.perf_counter()
        try:
            return inner(*args, **kw)
        finally:
            lobes[0] += time.perf_counter() - t0
            lobes[1] += 1

    detection_model._inside_lobes = timed
    try:
        s = speed(scene, "detection", max(frames, DETECTION_FRAMES))
    finally:
        detection_model._inside_lobes = inner
    n = max(frames, DETECTION_FRAMES)
    print(f"detection level on {scene.name} (object list, {n} frames): median {s['median_s'] * 1e3:.2f} "
          f"ms per frame, mean {s['mean_s'] * 1e3:.2f} ms, {s['scatterers']:.0f} scatterers a frame: "
          f"{s['rtf_mean']:.0f}× real time; the lobe test {lobes[0] / max(lobes[1], 1) * 1e3:.2f} ms a call, "
          f"{lobes[1] / n:.0f} a frame, {100 * lobes[0] / (s['mean_s'] * n):.0f} % of the frames' time")
    print("the frame's parts by the model's own timers (mean a frame): " + ", ".join(
        f"{name} {sec * 1e3:.2f} ms" for name, sec in s["parts_s"].items())
          + " (scene: its view and scatterers; radar: the detection model's chirp sequences, the ego motion and the "
          "velocity ambiguity; perception: the cluster list and the tracker)")


if __name__ == "__main__":
    main()
