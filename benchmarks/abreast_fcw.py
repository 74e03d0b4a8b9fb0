"""Two cars abreast ahead, one in each lane beside the ego's, the ego's lane free: does FCW warn, level by level?

Each row is a scene built here: a straight three-lane road, the ego in the middle lane at 30 m/s, FCW on, no ACC; two
cars side by side in the left and the right lane (or, as a control, the left one alone), ``dv`` m/s slower than the
ego, their rear 100 m ahead of the sensor at the start; the run ends when the ego has closed to about 5 m. Judged as
``radarnode report`` judges a scenario (``ecu.expect: {no_fcw: true}``), over seeds 1…N at each level.

Far ahead the two cars are closer in azimuth than the array resolves (``ars408_like``: 8 channels, a beam of 14.5°,
the cars ±3.5 m apart at 46 m are 0.61 beam apart; ``mimo12``: 12 channels, 9.6°). The chain then sees one return
between them, in some frames two (its resolution grows gradually with the separation: BENCHMARKS.md, "Resolution"),
and its tracker may hold an object in the ego's lane: a false FCW that a real radar of that array gives too. The
detection level resolves two returns 0.7 beam apart or more always, less never (a step at the chain's 50 % point;
until session 81 two returns in one angle cell never, which made the cars' near sides either side of boresight one
return between them), the object level keeps every body apart: this table measures what that does to the verdict.
``warned for`` counts what FCW's first warning was for (an actor's id, or ``no actor`` for a ghost).

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/abreast_fcw.py [--seeds 12] [--levels object,detection,signal]
[--presets ars408_like,mimo12] [--dvs 10,15,20] [--jobs 2] [--root DIR]`` (about 6 minutes with the defaults on two
cores, most of it the signal level). Prints a Markdown table, a row per scene.
``--bands`` instead prints, for the pair, what the radar reports as the gap closes, in 10-m bands of the distance to
the cars' rear (60 to 10 m): the share of frames with a detection between the cars (|y| < 1.5 m, within 4 m of
their rear along x), with detections of both cars apart (y > 2 m and y < −2 m), and with a radar object in the ego's
lane (|y| < 1.5 m, within 6 m): the radar's own output, before the ECU's path and tracks.
"""

from __future__ import annotations

import argparse
import collections
import itertools
import multiprocessing
import statistics
import sys
import time
from pathlib import Path

import machine  # noqa: E402  (the day's machine, printed beside the figures)
from tree import use_tree  # --root DIR: radarnode from another tree

use_tree()

import numpy as np  # noqa: E402

import radarnode  # noqa: E402
from radarnode.consumer.evaluate import simulate  # noqa: E402
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.setup import parse_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

EGO_MPS = 30.0
START_M = 100.0          # the cars' rear ahead of the sensor at t = 0
END_GAP_M = 5.0          # the run ends when the ego has closed to about this
SCENE = """
name: abreast
duration_s: {duration}
seed: {seed}
radar: {{preset: {preset}}}
ego: {{speed_mps: {ego}}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1}}
ecu: {{acc_enabled: false, expect: {{no_fcw: true}}}}
actors:
{actors}
"""


def scene_text(preset: str, dv: float, pair: bool, seed: int) -> str:
    """One row's scene for one seed: the cars' centres placed so that their rear is START_M ahead of the sensor."""
    speed = EGO_MPS - dv
    # x_m is the actor's centre from the ego's reference point; the sensor sits at the front of a 4.5-m car on the
    # ego's axis (radarnode.scene.world): the car's rear is x_m − 2.25, the sensor at about 3.7
    x = START_M + 3.7 + 2.25
    cars = [f"  - {{id: left, class: car, x_m: {x}, lane: 2, speed_mps: {speed}}}"]
    if pair:
        cars.append(f"  - {{id: right, class: car, x_m: {x}, lane: 0, speed_mps: {speed}}}")
    duration = round((START_M - END_GAP_M) / dv, 1)
    return SCENE.format(duration=duration, seed=seed, preset=preset, ego=EGO_MPS, actors="\n".join(cars))


def row_name(preset: str, dv: float, pair: bool) -> str:
    return f"{preset}, {'two cars abreast' if pair else 'one car, left lane'}, {dv:g} m/s slower"


def _one(job):
    preset, dv, pair, level, seed = job
    r = simulate(parse_scenario(scene_text(preset, dv, pair, seed)), fidelity=level)
    return (preset, dv, pair), level, seed, r.passed and r.checked, r.warning_time_s, r.warned_for


#: the distance bands (m, from the sensor to the cars' rear) of ``--bands``, nearest last
BANDS_M = ((60.0, 50.0), (50.0, 40.0), (40.0, 30.0), (30.0, 20.0), (20.0, 10.0))


def _bands_one(job):
    """One seed of the pair at one level: per band, [frames, a detection between the cars, both cars apart, a radar
    object in the ego's lane]."""
    preset, dv, level, seed = job
    sc = parse_scenario(scene_text(preset, dv, True, seed))
    rc = radar_config(sc)
    model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(sc.seed), rc.signal)
    cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
    counts = np.zeros((len(BANDS_M), 4), dtype=np.int64)
    for k in range(int(sc.duration_s / sc.period_s)):
        frame, _ = model.step(k * sc.period_s, cfg)
        gap = START_M - dv * k * sc.period_s
        band = [i for i, (hi, lo) in enumerate(BANDS_M) if lo <= gap < hi]
        if not band:
            continue
        d = model.info.detections
        x, y = d.range_m * np.cos(d.azimuth_rad), d.range_m * np.sin(d.azimuth_rad)
        near = np.abs(x - gap) < 4.0
        o = frame.objects
        counts[band[0]] += (1, np.any(near & (np.abs(y) < 1.5)), np.any(near & (y > 2.0)) and np.any(near & (y < -2.0)),
                            np.any((np.abs(o.dist_long_m - gap) < 6.0) & (np.abs(o.dist_lat_m) < 1.5)))
    return (preset, dv, level), counts


def bands(args) -> int:
    levels = args.levels.split(",")
    rows = list(itertools.product(args.presets.split(","), [float(v) for v in args.dvs.split(",")], levels))
    jobs = [row + (s,) for row in rows for s in range(1, args.seeds + 1)]
    t0 = time.perf_counter()
    with multiprocessing.Pool(args.jobs) as pool:
        results = pool.map(_bands_one, jobs, chunksize=1)
    total: dict[tuple, np.ndarray] = {}
    for row, c in results:
        total[row] = total.get(row, 0) + c
    print(f"(radarnode from {Path(radarnode.__file__).parents[1]})")
    print(machine.line() + "\n")
    print(f"### Two cars abreast as the gap closes: what the radar reports, ego {EGO_MPS:g} m/s, seeds 1–{args.seeds}\n")
    print("| scene | level | gap to the cars | frames | a detection between them | both apart | an object in the ego's "
          "lane |")
    print("|---|---|---|---:|---:|---:|---:|")
    for row in rows:
        for (hi, lo), (n, between, apart, lane) in zip(BANDS_M, total[row]):
            print(f"| {row_name(row[0], row[1], True)} | {row[2]} | {hi:.0f}–{lo:.0f} m | {n} | {between / n:.2f} | "
                  f"{apart / n:.2f} | {lane / n:.2f} |")
    print(f"\n({len(jobs)} runs in {time.perf_counter() - t0:.0f} s with {args.jobs} processes)")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, default=12)
    ap.add_argument("--levels", default="object,detection,signal")
    ap.add_argument("--presets", default="ars408_like,mimo12")
    ap.add_argument("--dvs", default="10,15,20", help="the cars' speed below the ego's, m/s")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--root", help="import radarnode from this tree (another version) instead")
    ap.add_argument("--bands", action="store_true", help="what the radar reports of the pair as the gap closes, "
                    "in 10-m bands (no ECU verdict)")
    args = ap.parse_args()
    if args.bands:
        return bands(args)
    levels = args.levels.split(",")
    rows = list(itertools.product(args.presets.split(","), [float(v) for v in args.dvs.split(",")], (True, False)))
    jobs = [row + (lv, s) for row in rows for lv in levels for s in range(1, args.seeds + 1)]
    t0 = time.perf_counter()
    with multiprocessing.Pool(args.jobs) as pool:
        results = pool.map(_one, jobs, chunksize=1)
    by: dict[tuple, list] = collections.defaultdict(list)
    for row, lv, s, ok, t_w, who in results:
        by[(row, lv)].append((ok, t_w, who))
    print(f"(radarnode from {Path(radarnode.__file__).parents[1]})")
    print(machine.line() + "\n")
    print(f"### Two cars abreast, the ego's lane free: FCW, ego {EGO_MPS:g} m/s, the cars' rear {START_M:g} m ahead "
          f"at the start, seeds 1–{args.seeds}\n")
    print("| scene | " + " | ".join(f"{lv}: no FCW" for lv in levels) + " | first warning, median (gap then) | "
          "warned for |")
    print("|---|" + "---:|" * len(levels) + "---|---|")
    for row in rows:
        cells, times, whom = [], [], collections.Counter()
        for lv in levels:
            res = by[(row, lv)]
            cells.append(f"{sum(ok for ok, _, _ in res)}/{len(res)}")
            for ok, t_w, who in res:
                if t_w is not None:
                    times.append((lv, t_w))
                    whom[f"{lv} {who}"] += 1
        warn = "; ".join(
            f"{lv} {statistics.median(t for l2, t in times if l2 == lv):.2f} s "
            f"({START_M - row[1] * statistics.median(t for l2, t in times if l2 == lv):.0f} m)"
            for lv in levels if any(l2 == lv for l2, _ in times)) or "-"
        print(f"| {row_name(*row)} | " + " | ".join(cells) + f" | {warn} | "
              + (", ".join(f"{k} ×{v}" for k, v in sorted(whom.items())) or "-") + " |")
    print(f"\n({len(jobs)} runs in {time.perf_counter() - t0:.0f} s with {args.jobs} processes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
