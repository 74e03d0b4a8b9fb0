"""Which bodies the chain lists as two objects, against their reflectors' diameter in the trackers' metric.

``auto`` renders a body at the detection level where its reflectors in view lie further apart than
``LONG_DIAMETER`` in the trackers' grouping metric, sqrt((Δx/4.5 m)² + (Δy/2.8 m)²) (``radarnode.radar.models.
long_actors``): where the detection level lists the body as two objects in some cycles, the object level's one
point per actor never does. The threshold is measured here, not derived. Per scene (cars, a 5.1-m SUV, 5.0-m,
5.5-m and 6.0-m vans in the next lane, in the ego's lane on bends of 100–500 m, a car turned 10–30° across the road,
bodies broadside), per cycle and seed: the diameter, whether the detection level and ``auto`` list more than one
object on the body's box grown by 1 m, and whether the rule (or the rule before session 55, each axis alone against
its own scale) renders it at the detection level. Printed: a row per scene, the detection level's split rate by
diameter, and for thresholds 1.0–1.3 the share of actor-cycles rendered at the detection level against the share of
the detection level's splits they hold.

``--cost``: instead, the cost of the rule on the bodies with most reflectors (a convoy of 50 trucks, a 300-m body
alongside, at the scatterer spacings 1 m and 0.1 m, the finest a scenario may ask): the median time of an ``auto``
and a detection-level cycle and of ``long_actors`` on ``auto``'s scatterers of each cycle.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/long_bodies.py [--preset ars408_like] [--seeds 4] [--only TEXT]
[--cost]`` (about 2 minutes a preset on the project's machine, alone).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.perception.tracker import GROUP_EPS_LONG_M, GROUP_EPS_M  # noqa: E402
from radarnode.radar.models import LONG_DIAMETER, long_actors, make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig, in_fov  # noqa: E402
from radarnode.radar.scatterers import scene_scatterers  # noqa: E402
from radarnode.radar.setup import parse_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

BODIES = {"car": "class: car", "suv5.1": "class: car, length_m: 5.1, width_m: 1.95",
          "car5.0": "class: car, length_m: 5.0, width_m: 1.9", "van5.5": "class: car, length_m: 5.5, width_m: 2.0",
          "van6.0": "class: car, length_m: 6.0, width_m: 2.0"}
LANES = "lanes: 3, lane_width_m: 3.5, ego_lane: 1"


def scenes():
    """(label, actor line, road, ego speed) of every scene: the body is the first and only actor."""
    for name, spec in BODIES.items():
        for x in (20.0, 40.0, 80.0):
            yield (f"{name} next lane {x:g} m", f"{{id: v, {spec}, x_m: {x + 3.7}, lane: 2, speed_mps: 25.0}}",
                   f"{{{LANES}}}", 25.0)
        for radius in (100, 250, 500):
            for x in (25.0, 50.0):
                yield (f"{name} own lane R{radius} {x:g} m", f"{{id: v, {spec}, x_m: {x}, lane: 1, speed_mps: 25.0}}",
                       f"{{{LANES}, curvature_1pm: {1.0 / radius}}}", 25.0)
    for heading in (10, 15, 20, 30):
        for x in (20.0, 40.0):
            yield (f"car turned {heading} deg {x:g} m",
                   f"{{id: v, class: car, x_m: {x}, y_m: 0.0, speed_mps: 0.0, heading_deg: {heading}}}",
                   f"{{{LANES}}}", 5.0)
    for length in (3.5, 3.8, 4.0, 4.5):
        yield (f"body {length} m broadside 30 m",
               f"{{id: v, class: car, length_m: {length}, width_m: 1.8, x_m: 30.0, y_m: 0.0, speed_mps: 0.0, "
               "heading_deg: 90}", f"{{{LANES}}}", 5.0)


def diameter(preset, scat) -> float:
    """The largest distance between two of actor 0's reflectors in view, in the trackers' grouping metric."""
    m = (scat.actor_index == 0) & in_fov(preset, scat.range_m, scat.azimuth_rad)
    if np.count_nonzero(m) < 2:
        return 0.0
    u, v = scat.x_m[m] / GROUP_EPS_LONG_M, scat.y_m[m] / GROUP_EPS_M
    return float(np.sqrt(((u[:, None] - u) ** 2 + (v[:, None] - v) ** 2).max()))


def axis_rule(preset, scat) -> bool:
    """The rule before session 55: actor 0's reflectors in view span more than 4.5 m along x or 2.8 m along y."""
    m = (scat.actor_index == 0) & in_fov(preset, scat.range_m, scat.azimuth_rad)
    return bool(m.any() and (np.ptp(scat.x_m[m]) > GROUP_EPS_LONG_M or np.ptp(scat.y_m[m]) > GROUP_EPS_M))


def run(level: str, actor: str, road: str, ego: float, preset: str, seed: int, duration: float):
    """Per cycle: (more than one object on the body's box, its diameter, the rule, the rule before)."""
    sc = parse_scenario(f"name: long_bodies\nduration_s: {duration}\nseed: {seed}\nradar: {{preset: {preset}}}\n"
                        f"ego: {{speed_mps: {ego}}}\nroad: {road}\nactors:\n  - {actor}\n")
    rc = radar_config(sc)
    scene = Scene(sc)
    p = rc.preset
    model = make_model(level, scene, p, np.random.default_rng(seed), rc.signal)
    cfg = RuntimeConfig(max_distance_m=p.max_range_m, clusters=False)
    half_l, half_w = scene.length_m[0] / 2 + 1.0, scene.width_m[0] / 2 + 1.0
    out = []
    for k in range(sc.num_cycles):
        t = k * sc.period_s
        frame, view = model.step(t, cfg)
        ol = frame.objects
        c, s = np.cos(view.orientation_rad[0]), np.sin(view.orientation_rad[0])
        dx, dy = ol.dist_long_m - view.centre_x_m[0], ol.dist_lat_m - view.centre_y_m[0]
        on = int(((np.abs(c * dx + s * dy) <= half_l) & (np.abs(-s * dx + c * dy) <= half_w)).sum())
        scat = scene_scatterers(scene, t, view, p, p.max_range_m)
        out.append((on > 1, diameter(p, scat), bool(long_actors(p, scat, 1)[0]), axis_rule(p, scat)))
    return np.array(out)


def cost() -> None:
    """The rule's cost on the bodies with most reflectors, against the cycle's."""
    convoy = [f"{{id: t{i}, class: truck, x_m: {20 + 14 * (i // 3) + 4 * (i % 3)}, lane: {i % 3}, speed_mps: 25.0}}"
              for i in range(50)]
    train = ["{id: train, class: truck, length_m: 300.0, width_m: 3.0, x_m: 160.0, lane: 2, speed_mps: 25.0}"]
    print(f"{'scene':10s} {'spacing':>7s} {'reflectors':>10s} {'auto ms':>8s} {'detection ms':>12s} "
          f"{'long_actors ms':>14s}")
    for label, actors in (("convoy 50", convoy), ("300-m body", train)):
        for spacing in (1.0, 0.1):
            text = (f"name: cost\nduration_s: 0.8\nseed: 1\nradar: {{preset: ars408_like}}\nego: {{speed_mps: 25.0}}\n"
                    f"road: {{{LANES}}}\nsignal: {{scatterer_spacing_m: {spacing}}}\nactors:\n"
                    + "".join(f"  - {a}\n" for a in actors))
            times, rule, count = {}, [], 0
            for level in ("auto", "detection"):
                sc = parse_scenario(text)
                rc = radar_config(sc)
                scene = Scene(sc)
                model = make_model(level, scene, rc.preset, np.random.default_rng(1), rc.signal)
                cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
                steps = []
                for k in range(sc.num_cycles):
                    t0 = time.perf_counter()
                    model.step(k * sc.period_s, cfg)
                    steps.append(time.perf_counter() - t0)
                    if level == "auto":
                        scat = model.info.scatterers
                        t0 = time.perf_counter()
                        long_actors(rc.preset, scat, scene.n)
                        rule.append(time.perf_counter() - t0)
                        count = int(np.count_nonzero(scat.actor_index >= 0))
                times[level] = 1e3 * float(np.median(steps))
            print(f"{label:10s} {spacing:7.1f} {count:10d} {times['auto']:8.1f} {times['detection']:12.1f} "
                  f"{1e3 * float(np.median(rule)):14.2f}", flush=True)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="ars408_like")
    ap.add_argument("--seeds", type=int, default=4, help="seeds 1..N (default 4)")
    ap.add_argument("--duration", type=float, default=3.0)
    ap.add_argument("--only", default=None, help="scenes whose label contains this text")
    ap.add_argument("--cost", action="store_true", help="the rule's cost on the bodies with most reflectors instead")
    args = ap.parse_args(argv)
    if args.cost:
        cost()
        return
    seeds = range(1, args.seeds + 1)
    print(f"preset {args.preset}, seeds 1-{args.seeds}, {args.duration:g} s a scene; LONG_DIAMETER {LONG_DIAMETER}")
    print(f"{'scene':30s} {'diameter':>8s} {'rule':>5s} {'before':>6s} {'det split':>9s} {'auto split':>10s}")
    rows = []
    for label, actor, road, ego in scenes():
        if args.only and args.only not in label:
            continue
        det = np.concatenate([run("detection", actor, road, ego, args.preset, s, args.duration) for s in seeds])
        auto = np.concatenate([run("auto", actor, road, ego, args.preset, s, args.duration)[:, 0] for s in seeds])
        rows.append((det, auto))
        print(f"{label:30s} {np.median(det[:, 1]):8.2f} {det[:, 2].mean():5.2f} {det[:, 3].mean():6.2f} "
              f"{det[:, 0].mean():9.3f} {auto.mean():10.3f}", flush=True)
    det = np.concatenate([r[0] for r in rows])
    auto = np.concatenate([r[1] for r in rows])
    split, diam, rule, before = det[:, 0].astype(bool), det[:, 1], det[:, 2].astype(bool), det[:, 3].astype(bool)
    print("\nthe detection level's split rate by diameter (actor-cycles)")
    for lo in np.arange(0.9, 1.75, 0.1):
        m = (diam >= lo) & (diam < lo + 0.1)
        if m.any():
            print(f"  [{lo:.1f}, {lo + 0.1:.1f}): {m.sum():5d} cycles, split in {split[m].mean():.3f}")
    total = max(int(split.sum()), 1)
    print(f"\n{split.sum()} of {split.size} actor-cycles split at the detection level; auto split {int(auto.sum())}")
    print(f"{'threshold':>12s} {'rendered':>9s} {'splits held':>11s} {'split rate left':>15s}")
    for th in (1.0, 1.05, 1.1, 1.15, 1.2, 1.25, 1.3):
        esc = diam > th
        print(f"{th:12.2f} {esc.mean():9.3f} {split[esc].sum() / total:11.2f} {split[~esc].mean():15.4f}")
    for name, esc in (("the rule", rule), ("before", before)):
        print(f"{name:>12s} {esc.mean():9.3f} {split[esc].sum() / total:11.2f} {split[~esc].mean():15.4f}")


if __name__ == "__main__":
    main()
