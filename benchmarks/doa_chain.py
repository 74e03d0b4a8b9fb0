"""Super-resolution in the signal chain: what it resolves, and what running it only on multi-source cells saves.

* Resolution: two equal point targets in one range–Doppler cell (mimo12, 12 virtual elements, 40 m, 3 m/s,
  around 10° azimuth), each at an integrated SNR ρ of ``--rho`` dB, ``--trials`` noise draws per separation;
  the chain's DOA stage set to each estimator (``signal.dsp.doa``). A trial resolves the pair when the cell gives
  exactly two detections, each within 1.5° of its target; RMSE is over the resolved trials' angles.
* Cost: ``DspChain.process_rd`` on the range–Doppler maps of ``--frames`` highway_mimo12 frames (ego 30 m/s,
  ~300 scatterers, ~95 detection cells a frame), median per frame: the beamformer alone, each estimator gated
  (only the cells one plane wave does not explain: ``radarnode.dsp.doa.SuperResolution``) and on every cell.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/doa_chain.py [--trials 40] [--frames 8] [--rho 30]``
(about 2 minutes). Prints Markdown tables.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from radarnode.dsp.doa import DOA_METHODS, SuperResolution  # noqa: E402
from radarnode.radar.chain import DspChain, DspConfig  # noqa: E402
from radarnode.radar.presets import PRESETS  # noqa: E402
from radarnode.radar.scatterers import point_targets  # noqa: E402
from radarnode.radar.signal_model import num_range_samples, synthesize_rd  # noqa: E402

P = PRESETS["mimo12"]
SEPARATIONS_BW = (0.3, 0.5, 0.7, 1.0, 1.5)
TOL_DEG = 1.5


def resolution_row(doa: str, sep_bw: float, trials: int, rho_db: float) -> tuple[float, float]:
    n, m, c = num_range_samples(P), P.num_chirps, P.num_virtual
    sep = math.degrees(math.asin(sep_bw / (c * P.element_spacing_wl)))
    truth = np.array([10.0 - sep / 2, 10.0 + sep / 2])
    chain = DspChain(P, DspConfig(doa=doa))
    ok, err = 0, []
    for t in range(trials):
        scat = point_targets([40.0, 40.0], truth, [3.0, 3.0], 0.0)
        rd = synthesize_rd(P, scat, np.random.default_rng(t), snr_db=rho_db - 10.0 * math.log10(n * m * c))
        det = chain.process_rd(rd)
        near = (np.abs(det.range_m - 40.0) < 2.0) & (np.abs(det.range_rate_mps - 3.0) < 1.0)
        az = np.sort(np.degrees(det.azimuth_rad[near]))
        if az.size == 2 and np.max(np.abs(az - truth)) <= TOL_DEG:
            ok += 1
            err.extend((az - truth).tolist())
    return ok / trials, math.sqrt(float(np.mean(np.square(err)))) if err else math.nan


def cost_rows(frames: int) -> list[str]:
    from signal_speed import highway_frames
    p, scats = highway_frames(30.0, frames)
    rng = np.random.default_rng(1)
    rds = [synthesize_rd(p, s, rng) for s in scats]
    rows = []
    base = None
    for doa in DOA_METHODS:
        for gate in ((True,) if doa == "fft" else (True, False)):
            chain = DspChain(p, DspConfig(doa=doa))
            if isinstance(chain.doa, SuperResolution):
                chain.doa.gate = gate
            chain.process_rd(rds[0])                      # warm-up
            if isinstance(chain.doa, SuperResolution):
                chain.doa.stats = {"cells": 0, "super": 0}
            times = []
            for rd in rds:
                t0 = time.perf_counter()
                chain.process_rd(rd)
                times.append(time.perf_counter() - t0)
            ms = 1e3 * statistics.median(times)
            base = ms if doa == "fft" else base
            st = getattr(chain.doa, "stats", None)
            cells = f"{st['super']} of {st['cells']}" if st else "-"
            where = "every cell (beamformer only)" if doa == "fft" else "only multi-source cells" if gate else "every cell"
            rows.append(f"| {doa} | {where} | {cells} | {ms:.1f} ms "
                        f"| {ms / base:.2f} |")
            print(rows[-1], file=sys.stderr, flush=True)
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trials", type=int, default=40)
    ap.add_argument("--frames", type=int, default=8)
    ap.add_argument("--rho", type=float, default=30.0)
    args = ap.parse_args()
    print(f"radarnode DOA in the chain, {time.strftime('%Y-%m-%d')}, `benchmarks/doa_chain.py --trials {args.trials} "
          f"--frames {args.frames} --rho {args.rho:g}`\n")
    bw = [f"{s:g} bw ({math.degrees(math.asin(s / (P.num_virtual * P.element_spacing_wl))):.1f}°)"
          for s in SEPARATIONS_BW]
    print(f"#### Two equal targets in one cell, ρ = {args.rho:g} dB each: P(resolved within {TOL_DEG}°) / RMSE (deg)\n")
    print("| estimator | " + " | ".join(bw) + " |")
    print("|---|" + "---:|" * len(bw))
    for doa in DOA_METHODS:
        cells = [resolution_row(doa, s, args.trials, args.rho) for s in SEPARATIONS_BW]
        print(f"| {doa} | " + " | ".join(f"{p:.2f} / {r:.2f}" if p else "0.00 / -" for p, r in cells) + " |",
              flush=True)
    print(f"\n#### Cost per frame, highway_mimo12.yaml at 30 m/s, median of {args.frames} frames\n")
    print("| estimator | run on | cells through the estimator | process_rd | ratio to fft |")
    print("|---|---|---:|---:|---:|")
    print("\n".join(cost_rows(args.frames)))


if __name__ == "__main__":
    main()
