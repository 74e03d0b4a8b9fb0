"""Do the object list's σ fields say how far off the objects are? The reported σ against the measured error, level by
level.

Each object of the list carries σ for its distances and relative velocities (0x60C's DistLong_rms … VrelLat_rms,
from the tracker's own covariance at the detection and signal levels, from the chain's accuracy at the object
level). A consumer weighs the object by them (the ECU's Kalman filter takes them as its measurement noise): an
object whose σ is too small pulls the consumer's track off by its error at full weight.

The scenes' truth: every reported object tagged with its actor (the model's tag; guardrail actors left out), each
cycle after the first ``WARM_UP`` of its track. The relative velocity is the actor's (its velocity over ground minus the
sensor's, sensor axes: the convention of the list). The distances are compared with the box's span along and across
(inside it counts as no error: the radar reports a point of the body — a truck's rear, or its side as an object of
its own — and which one is the reference point's business, not the noise's), so the distance rows are lower bounds
of the error, and only where the whole box is in the field of view.

For each level and field, split into objects reported moving and standing (DynProp), it prints the number of
object-cycles, the share of them whose error is within 1σ and 2σ (68.3 % and 95.4 % for errors the σ describes;
a share well below says σ is too small) and the root mean square of error/σ (1 where σ is right). A second table
says where the objects sit on their bodies: how many objects an actor has in a cycle (one body split into several),
and how far its nearest object lies beyond the nearest point of its box along the sensor's axis (the box's least x:
its rear face, or its nearest corner where it is turned; what ACC and FCW take for the gap; every object, its
track's first cycles too), and how far across that object's lateral distance lies from the box's point nearest to
the sensor (the point the object level reports; a car in the next lane reported at its rear face's middle lies half
a width from it).

Run: ``python benchmarks/object_sigma.py [--levels object,detection] [--seeds 3] [--root DIR]``. Markdown.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from collections import defaultdict

import numpy as np

from tree import ROOT, use_tree  # --root DIR: radarnode from another tree

use_tree()

from radarnode.perception.types import DYN_STOPPED, DYN_STATIONARY  # noqa: E402
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig, in_fov  # noqa: E402
from radarnode.radar.setup import load_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

#: straight roads, bends, a curve entry, lane changes, a crossing pedestrian, stopped cars under and beside things
SCENARIOS = ("highway_cut_in", "nhtsa_lead_stopped", "acc_follow_bend_250", "clothoid_stopped_outer_lane",
             "clothoid_stopped_own_lane", "bend_r250_left_stopped_outer_lane", "lane_change_to_stopped",
             "pedestrian_crossing", "no_fcw_adjacent_stopped", "bridge_stopped_car_50")
FIELDS = ("dist_long", "dist_lat", "vrel_long", "vrel_lat")
WARM_UP = 3      # cycles of a track's object left out (its first velocity is a prior)


def box(view, scene: Scene, a: int) -> tuple[np.ndarray, np.ndarray]:
    """The corners (x, y) of actor a's box, sensor frame."""
    c, s = math.cos(view.orientation_rad[a]), math.sin(view.orientation_rad[a])
    hl, hw = scene.length_m[a] / 2.0, scene.width_m[a] / 2.0
    u = np.array([hl, hl, -hl, -hl])
    w = np.array([hw, -hw, -hw, hw])
    return view.centre_x_m[a] + c * u - s * w, view.centre_y_m[a] + s * u + c * w


def collect(level: str, seeds: int) -> tuple[dict, dict]:
    """{(field, 'moving' | 'standing'): list of (error, σ)} over the scenarios and seeds, and {actor class: list of
    (objects the actor has this cycle, the nearest one's x less the box's least x, how far across its y lies from
    the y of the box's point nearest to the sensor)} for the actor-cycles with an object whose whole box is in
    view."""
    out: dict = defaultdict(list)
    bodies: dict = defaultdict(list)
    for name in SCENARIOS:
        base = load_scenario(ROOT / "scenarios" / f"{name}.yaml")
        for seed in range(1, seeds + 1):
            sc = dataclasses.replace(base, seed=seed)
            rc = radar_config(sc)
            scene = Scene(sc)
            model = make_model(level, scene, rc.preset, np.random.default_rng(seed), rc.signal)
            cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m, clusters=False)
            age: dict[int, int] = {}
            guard = {i for i, a in enumerate(sc.actors) if a.object_class == "guardrail"}
            for k in range(sc.num_cycles):
                frame, view = model.step(k * sc.period_s, cfg)
                ol = frame.objects
                ids = set()
                for j in range(len(ol)):
                    oid = int(ol.id[j])
                    ids.add(oid)
                    age[oid] = age.get(oid, 0) + 1
                    a = int(ol.actor_index[j])
                    if a < 0 or a in guard or age[oid] <= WARM_UP:
                        continue
                    bx, by = box(view, scene, a)
                    x, y = float(ol.dist_long_m[j]), float(ol.dist_lat_m[j])
                    # distances only where the whole box is in view (a car beside the sensor shows the part in the
                    # field of view, and its least x is not what the radar can report)
                    whole = bool(in_fov(rc.preset, np.hypot(bx, by), np.arctan2(by, bx)).all())
                    lat = y - min(max(y, by.min()), by.max())
                    along = x - min(max(x, bx.min()), bx.max())
                    errs = (along if whole else math.nan, lat if whole else math.nan,
                            float(ol.vrel_long_mps[j] - view.vx_mps[a]), float(ol.vrel_lat_mps[j] - view.vy_mps[a]))
                    sigs = (ol.dist_long_sigma_m[j], ol.dist_lat_sigma_m[j], ol.vrel_long_sigma_mps[j],
                            ol.vrel_lat_sigma_mps[j])
                    kind = "standing" if int(ol.dyn_prop[j]) in (DYN_STATIONARY, DYN_STOPPED) else "moving"
                    for f, e, s in zip(FIELDS, errs, sigs):
                        out[(f, kind)].append((e, float(s)))
                for a in {int(i) for i in ol.actor_index} - guard - {-1}:
                    mine = np.flatnonzero(ol.actor_index == a)
                    bx, by = box(view, scene, a)
                    if in_fov(rc.preset, np.hypot(bx, by), np.arctan2(by, bx)).all():
                        first = mine[np.argmin(ol.dist_long_m[mine])]
                        bodies[sc.actors[a].object_class].append(
                            (mine.size, float(ol.dist_long_m[first]) - bx.min(),
                             abs(float(ol.dist_lat_m[first]) - float(view.y_m[a]))))
                for gone in set(age) - ids:
                    del age[gone]
    return out, bodies


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--levels", default="object,detection")
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--root", help="import radarnode from this tree (benchmarks/tree.py)")
    args = ap.parse_args()
    print(f"`python benchmarks/object_sigma.py --levels {args.levels} --seeds {args.seeds}`: "
          f"{len(SCENARIOS)} scenarios × seeds 1–{args.seeds}\n")
    print("| level | field | objects | object-cycles | within 1σ | within 2σ | rms(error/σ) | median |error| | "
          "median σ |")
    print("|---|---|---|---:|---:|---:|---:|---:|---:|")
    places = []
    for level in args.levels.split(","):
        rows, bodies = collect(level, args.seeds)
        places += [(level, cls, np.array(v, dtype=np.float64)) for cls, v in sorted(bodies.items())]
        for f in FIELDS:
            for kind in ("moving", "standing"):
                es = np.array(rows.get((f, kind), []), dtype=np.float64).reshape(-1, 2)
                ok = np.isfinite(es).all(axis=1) & (es[:, 1] > 0)
                es = es[ok]
                if not es.size:
                    print(f"| {level} | {f} | {kind} | 0 | | | | | |")
                    continue
                z = es[:, 0] / es[:, 1]
                print(f"| {level} | {f} | {kind} | {len(z)} | {np.mean(np.abs(z) <= 1):.1%} | "
                      f"{np.mean(np.abs(z) <= 2):.1%} | {np.sqrt(np.mean(z * z)):.2f} | "
                      f"{np.median(np.abs(es[:, 0])):.2f} | {np.median(es[:, 1]):.2f} |")
    print("\nWhere the objects sit: each actor-cycle with an object (the whole box in view), how many objects the "
          "actor has (a body split into several), how far the nearest one lies beyond the box's nearest point along "
          "the sensor's axis, and how far across from that point (|Δy|) (m)\n")
    print("| level | actor class | actor-cycles | objects each | split | nearest − box: median | p90 | > 1 m "
          "| across: median | p90 |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for level, cls, b in places:
        n, e, c = b[:, 0], b[:, 1], b[:, 2]
        print(f"| {level} | {cls} | {len(n)} | {n.mean():.3f} | {np.mean(n > 1):.1%} | {np.median(e):.2f} | "
              f"{np.percentile(e, 90):.2f} | {np.mean(e > 1.0):.1%} | {np.median(c):.2f} | "
              f"{np.percentile(c, 90):.2f} |")


if __name__ == "__main__":
    main()
