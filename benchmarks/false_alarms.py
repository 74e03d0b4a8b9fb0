"""False alarms a frame at the three levels, noise only (no actors, the ego standing), against the set Pfa.

The chain reports one detection per local maximum of the range–Doppler map over its CA-CFAR threshold; its cells'
exceedances clump (the Hann windows correlate neighbouring cells) and a clump counts once, more so as the threshold
falls. The detection and object levels draw Poisson false alarms at Pfa × cells × F(Pfa), uniform over the map and
cut to what the chain reports (range, sectors), with F(Pfa) = 1 − c·Pfa^β (``radarnode.radar.calibration``,
``FALSE_ALARM_CLUMP``). Prints, per preset and Pfa: the reported false alarms a frame at each level, their ratios to
the signal level's, and the F the signal level implies (F used × signal / detection). The detection and signal
levels' detections are counted; the object level's false alarms are in its cluster list only, which holds 250 a cycle
at most (a point where it is full has no object figure).

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/false_alarms.py [--frames N]`` (150 frames: about 8 minutes; the
signal level at Pfa 1e-2 is most of it).
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.radar.calibration import false_alarms_per_pfa_cell  # noqa: E402
from radarnode.radar.levels import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.setup import parse_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

LEVELS = ("object", "detection", "signal")


def per_frame(preset: str, pfa: float, level: str, frames: int, seed: int) -> float:
    sc = parse_scenario(f"name: fa\nduration_s: {frames * 0.1 + 1.0}\nseed: {seed}\nradar: {{preset: {preset}}}\n"
                        f"ego: {{speed_mps: 0.0}}\nroad: {{lanes: 1, ego_lane: 0}}\nsignal: {{dsp: {{pfa: {pfa!r}}}}}\n"
                        "actors: []\n")
    cfg = radar_config(sc)
    model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(seed), cfg.signal, clusters_wanted=True)
    run = RuntimeConfig(max_distance_m=cfg.preset.max_range_m, clusters=True)
    counts = []
    for k in range(frames):
        frame, _ = model.step(k * sc.period_s, run)
        # the object level's false alarms are in its cluster list only (capped at 250 a cycle: then no figure)
        counts.append(len(frame.clusters) if level == "object" else len(model.info.detections))
        if level == "object" and counts[-1] >= 250:
            return math.nan
    return float(np.mean(counts))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=150, help="signal-level frames a point (4× at the other levels)")
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    print("| preset | Pfa | object | detection | signal | object / signal | detection / signal | F used | F the "
          "signal level implies |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for preset in ("mimo12", "ars408_like"):
        for pfa in (1e-2, 1e-3, 1e-4):
            n = {lv: per_frame(preset, pfa, lv, args.frames if lv == "signal" else 4 * args.frames, args.seed)
                 for lv in LEVELS}
            f = false_alarms_per_pfa_cell(pfa)
            print(f"| {preset} | {pfa:g} | {n['object']:.2f} | {n['detection']:.2f} | {n['signal']:.2f} | "
                  f"{n['object'] / n['signal']:.2f} | {n['detection'] / n['signal']:.2f} | {f:.3f} | "
                  f"{f * n['signal'] / n['detection']:.3f} |", flush=True)


if __name__ == "__main__":
    main()
