"""The signal level's first frames: what a new process pays before its frames cost what the speed table says.

A signal-level chain builds tables when it first needs them: the patch fit's noise correlation and norm tables (each
window and patch size), CA-CFAR's threshold for each ring the range edges cut, and — at the first frame whose peaks
migrate, past the alias speed — the migration fit's tone tables. A real-time node pays them before its schedule starts
(its first cycle) and in the cycle where the ego first passes the alias speed; a test or a `report` worker pays them
once in every new process.

Each run is a fresh Python process (the tables are shared within a process), on `scenarios/highway_mimo12.yaml`'s
frames (12 × 256 × 256, complex128), which it times one by one: a new chain's first frame at ego 20 m/s, its second
and third (steady), then the same chain's first frame at 50 m/s (past mimo12's 32.3 m/s alias speed: its peaks take
the migration fit, as a node's do when the ego passes it) and its next, and last a new chain's first frame at 50 m/s
(what a new scene of the same preset pays in the process). The spectra are synthesised before the clock starts (the
synthesis builds nothing). Medians over ``--runs`` processes; with ``--before DIR`` the same runs of another tree
(``git archive REV``), alternated with this one's, side by side.

Run: ``OPENBLAS_NUM_THREADS=1 python benchmarks/first_frame.py [--runs 5] [--before DIR]``. Markdown.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COLUMNS = ("first frame, 20 m/s", "second frame", "third frame", "the same chain's first frame at 50 m/s",
           "its next", "a new chain's first frame at 50 m/s")


def child(tree: str) -> None:
    """One process's timings, as JSON on stdout (ms, in COLUMNS' order)."""
    sys.path.insert(0, tree)
    sys.path.insert(0, str(ROOT / "benchmarks"))
    import numpy as np

    from radarnode.radar.chain import DspChain
    from radarnode.radar.signal_model import synthesize_rd
    from signal_speed import highway_frames

    spectra = {}
    for ego, frames in ((20.0, 3), (50.0, 3)):
        p, scats = highway_frames(ego, frames)
        rng = np.random.default_rng(1)
        spectra[ego] = [synthesize_rd(p, s, rng, dtype=np.complex128) for s in scats]
    out = []
    t0 = time.perf_counter()
    chain = DspChain(p)                    # a node's chain: three frames at 20 m/s, then the ego past the alias speed
    for rd in spectra[20.0] + spectra[50.0][:2]:
        chain.process_rd(rd)
        t1 = time.perf_counter()
        out.append(1e3 * (t1 - t0))
        t0 = t1
    DspChain(p).process_rd(spectra[50.0][2])          # a new chain (a new scene, a worker's next run)
    out.append(1e3 * (time.perf_counter() - t0))
    print(json.dumps(out))


def run(tree: Path) -> list[float]:
    env = dict(os.environ, OPENBLAS_NUM_THREADS=os.environ.get("OPENBLAS_NUM_THREADS", "1"))
    res = subprocess.run([sys.executable, __file__, "--child", str(tree)], capture_output=True, text=True, env=env,
                         check=True)
    return json.loads(res.stdout.strip().splitlines()[-1])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=5, help="fresh processes a tree (median)")
    ap.add_argument("--before", help="another tree (e.g. git archive REV | tar -x -C DIR), alternated with this one")
    ap.add_argument("--child", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.child:
        child(args.child)
        return
    trees = [("before", Path(args.before).resolve())] if args.before else []
    trees.append(("this tree", ROOT))
    times: dict[str, list[list[float]]] = {name: [] for name, _ in trees}
    for _ in range(args.runs):
        for name, tree in trees:
            times[name].append(run(tree))
    print(f"`python benchmarks/first_frame.py --runs {args.runs}"
          f"{' --before DIR' if args.before else ''}`: highway_mimo12 frames, complex128, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', '1')}, medians of {args.runs} processes\n")
    print("| tree | " + " | ".join(COLUMNS) + " |")
    print("|---|" + "---:|" * len(COLUMNS))
    for name, _ in trees:
        med = [statistics.median(col) for col in zip(*times[name])]
        print(f"| {name} | " + " | ".join(f"{v:.0f} ms" for v in med) + " |")


if __name__ == "__main__":
    main()
