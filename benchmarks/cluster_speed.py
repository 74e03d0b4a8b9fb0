"""DBSCAN's cost against the number of detections, on the worst layout for its connected-components pass.

A row of guardrail posts 2 m apart (one chain of neighbours), the detections numbered in random order, as a
radar cycle lists them; ``radarnode.dsp.cluster.dbscan`` with eps 2.5 m, median of 5 runs per size.

Run: ``python benchmarks/cluster_speed.py [--root DIR]``. ``--root DIR`` imports radarnode from another tree
(e.g. ``git archive REV | tar -x -C DIR``) so that two versions are timed with the same script. Prints a Markdown
table.
"""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import numpy as np

from tree import ROOT, use_tree  # --root DIR: radarnode from another tree

use_tree()

from radarnode.dsp.cluster import dbscan  # noqa: E402

SIZES = (100, 300, 1000, 3000, 10_000, 100_000)


def main() -> None:
    import radarnode
    print(f"dbscan, radarnode from {Path(radarnode.__file__).parents[1]}\n")
    print("| detections | median time |")
    print("|---:|---:|")
    rng = np.random.default_rng(1)
    for n in SIZES:
        x = 2.0 * rng.permutation(n).astype(np.float64)
        pts = np.stack([x, np.full(n, 4.0)], axis=1) / 2.5
        times = []
        for _ in range(5):
            t0 = time.perf_counter()
            labels = dbscan(pts, 1.0, 1)
            times.append(time.perf_counter() - t0)
        assert np.all(labels == 0)
        print(f"| {n} | {statistics.median(times) * 1e3:.2f} ms |", flush=True)


if __name__ == "__main__":
    main()
