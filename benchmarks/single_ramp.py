"""Targets beyond a single ramp's unambiguous speed: what each level lists, against the truth.

``fast_chirp`` (±18.99 m/s, cycle 50 ms: one wrap moves a target 1.9 m a cycle, within the trackers' 2.85-m gate)
measures a target closing faster than 18.99 m/s at an aliased speed, one wrap (38 m/s) away. Three scenes, seeds
1–3: a car closing at 25 m/s from 120 m, the ego standing; a mixed road (ego 20 m/s, a car oncoming at 5 m/s: −25
m/s, besides a lead, a slower truck and a pedestrian inside the span); ``guardrail_traffic`` with ``fast_chirp``
(ego 22 m/s on a bend between guardrails, a truck and a car oncoming at −42 and −46 m/s); ``highway_cut_in`` with
``fast_chirp`` (every road user inside the span: a truck at −4.8 m/s whose reflectors step along its side, guardrail
posts); a car ahead pulling away at 38 m/s over ground from an ego at 25 m/s (+13 m/s relative, inside the span, but
one wrap from the posts' rate: its detections are stationary candidates, README "Known limits"). Printed per scene and
level, for the actors beyond the span and for those inside it: the object rows listed for them, those within 3 m/s
of the true longitudinal relative speed, those more than 15 m/s off (an aliased speed), and the IDs they took.

Run: ``python benchmarks/single_ramp.py [--root DIR]`` (about a minute; ``--root`` imports radarnode from another
tree, e.g. ``git archive REV | tar -x -C DIR``, to compare two versions with one script).
"""

from __future__ import annotations

import argparse

import numpy as np

from tree import ROOT, use_tree  # --root DIR: radarnode from another tree

TREE = use_tree()

from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.setup import parse_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

SEEDS = (1, 2, 3)

def scene(name: str, duration_s: float, ego_mps: float, road: str, actors: list[str], seed: int) -> str:
    """A ``fast_chirp`` scenario's YAML: object output, these actors (flow mappings) on this road."""
    lines = "\n".join(f"  - {a}" for a in actors)
    return (f"name: {name}\nduration_s: {duration_s}\nseed: {seed}\nradar: {{preset: fast_chirp, output: objects}}\n"
            f"ego: {{speed_mps: {ego_mps}}}\nroad: {road}\nactors:\n{lines}\n")


def oncoming(seed: int) -> str:
    return scene("fc_oncoming", 3.0, 0.0, "{lanes: 2, lane_width_m: 3.5, ego_lane: 0}",
                 ["{id: onc, class: car, x_m: 120.0, lane: 0, speed_mps: 25.0, heading_deg: 180.0}"], seed)


def mixed(seed: int) -> str:
    return scene("fc_mixed", 8.0, 20.0, "{lanes: 3, lane_width_m: 3.5, ego_lane: 1}",
                 ["{id: lead, class: car, x_m: 40.0, lane: 1, speed_mps: 25.0}",
                  "{id: slow, class: truck, x_m: 90.0, lane: 0, speed_mps: 12.0}",
                  "{id: onc_slow, class: car, x_m: 150.0, lane: 2, speed_mps: 5.0, heading_deg: 180.0}",
                  "{id: ped, class: pedestrian, x_m: 30.0, y_m: -8.0, speed_mps: 1.5, heading_deg: 90.0}"], seed)


def guardrail(seed: int) -> str:
    text = (ROOT / "scenarios" / "guardrail_traffic.yaml").read_text()
    text = text.replace("preset: ars408_like, output: clusters, send_quality: true", "preset: fast_chirp, output: objects")
    return text.replace("seed: 5", f"seed: {seed}")


def cut_in(seed: int) -> str:
    text = (ROOT / "scenarios" / "highway_cut_in.yaml").read_text()
    text = text.replace("preset: ars408_like", "preset: fast_chirp")
    return text.replace("seed: 7", f"seed: {seed}")


def one_wrap(seed: int) -> str:
    return scene("fc_one_wrap", 5.0, 25.0, "{lanes: 3, lane_width_m: 3.5, ego_lane: 1}",
                 ["{id: away, class: car, x_m: 40.0, lane: 1, speed_mps: 38.0}"], seed)


SCENES = (("car closing at 25 m/s", oncoming, ("object", "detection", "signal")),
          ("mixed road", mixed, ("object", "detection")),
          ("guardrail_traffic", guardrail, ("object", "detection")),
          ("highway_cut_in", cut_in, ("object", "detection")),
          ("car one wrap from the posts' rate", one_wrap, ("object", "detection")))


def run(text: str, level: str) -> dict:
    """Per group (beyond, inside the span): [rows, within 3 m/s, off > 15 m/s, IDs]."""
    sc = parse_scenario(text)
    cfg = radar_config(sc)
    p = cfg.preset
    model = make_model(level, Scene(sc), p, np.random.default_rng(sc.seed), cfg.signal)
    out = {"beyond": [0, 0, 0, set()], "inside": [0, 0, 0, set()]}
    for k in range(sc.num_cycles):
        frame, view = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=p.max_range_m))
        o = frame.objects
        for j in np.flatnonzero(o.actor_index >= 0):
            a = int(o.actor_index[j])
            beyond = abs(float(view.vx_mps[a])) > p.alias_speed_mps
            err = abs(float(o.vrel_long_mps[j] - view.vx_mps[a]))
            s = out["beyond" if beyond else "inside"]
            s[0] += 1
            s[1] += err < 3.0
            s[2] += err > 15.0
            s[3].add((a, int(o.id[j])))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--root", help="import radarnode from this tree (read before radarnode is imported)")
    ap.parse_args()
    print(f"radarnode from {TREE}; fast_chirp, seeds {SEEDS[0]}–{SEEDS[-1]}\n")
    print("| scene | level | beyond ±v_max: rows | within 3 m/s | off > 15 m/s | IDs | inside: rows | within 3 m/s "
          "| off > 15 m/s |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    for name, make, levels in SCENES:
        for level in levels:
            tot = {"beyond": [0, 0, 0, 0], "inside": [0, 0, 0, 0]}
            for seed in SEEDS:
                for key, s in run(make(seed), level).items():
                    tot[key] = [tot[key][0] + s[0], tot[key][1] + s[1], tot[key][2] + s[2], tot[key][3] + len(s[3])]
            b, i = tot["beyond"], tot["inside"]
            print(f"| {name} | {level} | {b[0]} | {b[1]} | {b[2]} | {b[3]} | {i[0]} | {i[1]} | {i[2]} |", flush=True)


if __name__ == "__main__":
    main()
