"""The radar tracker's speed across the line of sight from one cycle's detections, against the truth.

A detection group narrower than ``RIGID_MIN_SPAN_RAD`` (10°) with three detections or more whose radial speeds one
rigid velocity explains measures its velocity across the line of sight by that least-squares fit, where the fit's σ
across is at most ``ACROSS_FIT_MAX_SIGMA_MPS`` (``radarnode/perception/tracker.py``, ``_across_fits``; the tracker
takes only its part across, with the σ the fit states, as a Kalman update). This benchmark checks that σ against the
truth: every such group of every shipped scenario, and of the 18 crossing cars of ``crossing.py --only fcw`` (seed
1; marked 'crossing'), at the detection (or signal) level (its first ``--seconds`` seconds, its own seed) whose
detections all come from one actor — or all from none, the guardrail posts, standing — is compared with that actor's
relative velocity (``SensorView.vx_mps``, ``vy_mps``; a post's: minus the sensor's velocity over ground) across the
line of sight to the group's point. Printed per kind: groups, the median and 95th percentile of the error across,
the RMS of the error over the stated σ (1 where the σ is right, below 1 where it is conservative), the share beyond
3σ, and the share more than 2 m/s off (the road prior's σ, which the fit replaces where it is better). A group of
one actor on a bend turns with it: its reflectors' speeds are not one translation, and the fit's residuals (hence
its σ) carry that.

Run: ``python benchmarks/across_fit.py [--seconds S] [--level detection|signal] [--only NAME ...] [--root DIR]``
(the 58 scenarios at 6 s: about half a minute at the detection level, minutes at the signal level; prints a
Markdown table).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from tree import ROOT, use_tree  # --root DIR: radarnode from another tree

TREE = use_tree()

from radarnode.perception import tracker as tracker_module  # noqa: E402
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.setup import load_scenario, parse_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402


def crossing_scenes() -> list:
    """The crossing cars of ``benchmarks/crossing.py --only fcw`` (seed 1): ego 10 / 15 / 20 m/s, the car 10 / 15 / 20
    m/s from 12 and 40 m to the left, clear of the ego's lane 1.5 s before the ego gets there."""
    out = []
    for from_m in (12.0, 40.0):
        for ego in (10.0, 15.0, 20.0):
            for car in (10.0, 15.0, 20.0):
                t_arrive = (from_m + 4.0) / car + 1.5
                out.append(parse_scenario(f"""
name: crossing_{ego:g}_{car:g}_{from_m:g}
duration_s: {round(t_arrive + 0.5, 2)}
seed: 1
radar: {{preset: ars408_like}}
ego: {{speed_mps: {ego}}}
road: {{lanes: 2, lane_width_m: 3.6, ego_lane: 0}}
actors:
  - {{id: x, class: car, x_m: {3.7 + ego * t_arrive:.1f}, y_m: {from_m}, speed_mps: {car}, heading_deg: -90}}
"""))
    return out


def collect(sc, seconds: float, level: str = "detection") -> list[tuple[str, float, float]]:
    """(kind, error across (m/s), stated σ across (m/s)) of every fitted group of one scenario."""
    cfg = radar_config(sc)
    scene = Scene(sc)
    model = make_model(level, scene, cfg.preset, np.random.default_rng(sc.seed), cfg.signal)
    captured: list = []
    inner = tracker_module.group_detections

    def spy(det, *args, **kw):
        groups = inner(det, *args, **kw)
        if groups.across is not None and len(groups):
            captured.append((det, groups))
        return groups

    classes = [a.object_class for a in sc.actors]
    out = []
    tracker_module.group_detections = spy
    try:
        for k in range(min(sc.num_cycles, int(round(seconds / sc.period_s)))):
            captured.clear()
            _, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
            for det, g in captured:
                for j in np.flatnonzero(np.isfinite(g.across[:, 0])):
                    tags = det.actor_index[g.labels == j]
                    if not np.all(tags == tags[0]):
                        continue                                   # several actors (or an actor and posts)
                    a = int(tags[0])
                    if a >= 0:
                        truth, kind = np.array([view.vx_mps[a], view.vy_mps[a]]), classes[a]
                    else:
                        truth, kind = -np.array([view.sensor_vx_mps, view.sensor_vy_mps]), "standing (posts)"
                    r = max(float(np.hypot(g.x_m[j], g.y_m[j])), 1e-6)
                    t = np.array([-g.y_m[j] / r, g.x_m[j] / r])
                    out.append((kind, float(t @ (g.across[j] - truth)), float(np.sqrt(t @ g.across_cov[j] @ t))))
    finally:
        tracker_module.group_detections = inner
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=6.0, help="seconds of each scenario (default 6)")
    ap.add_argument("--only", nargs="*", default=None,
                    help="scenario names (default: every shipped one and the crossing cars, 'crossing')")
    ap.add_argument("--level", default="detection", choices=("detection", "signal"), help="default: detection")
    ap.add_argument("--root", default=None, help="import radarnode from this tree")
    args = ap.parse_args()
    t0 = time.perf_counter()
    scenes = [load_scenario(p) for p in sorted((ROOT / "scenarios").glob("*.yaml"))] + crossing_scenes()
    if args.only:
        scenes = [sc for sc in scenes if sc.name in args.only or ("crossing" in args.only
                                                                  and sc.name.startswith("crossing_"))]
    rows: list[tuple[str, float, float]] = []
    for sc in scenes:
        got = collect(sc, args.seconds, args.level)
        rows += [(k + " (crossing)" if sc.name.startswith("crossing_") else k, e, sd) for k, e, sd in got]
        print(f"{sc.name}: {len(got)} groups", file=sys.stderr, flush=True)
    print(f"## Across-the-line-of-sight fits of narrower groups, {args.level} level, {len(scenes)} scenes, first "
          f"{args.seconds:g} s each (radarnode from {TREE})\n")
    print("| kind | groups | median abs error | p95 abs error | RMS error/σ | beyond 3σ | beyond 2 m/s |")
    print("|---|---:|---:|---:|---:|---:|---:|")
    kinds = sorted({k for k, _, _ in rows})
    for kind in kinds + ["all"]:
        sel = [(e, s) for k, e, s in rows if kind in ("all", k)]
        if not sel:
            continue
        e, s = np.array(sel).T
        z = e / s
        print(f"| {kind} | {e.size} | {np.median(np.abs(e)):.2f} m/s | {np.percentile(np.abs(e), 95):.2f} m/s "
              f"| {np.sqrt(np.mean(z ** 2)):.2f} | {np.mean(np.abs(z) > 3):.3f} | {np.mean(np.abs(e) > 2):.3f} |")
    print(f"\n(run time {time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
