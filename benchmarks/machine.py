"""How fast the machine is today, in three small reference workloads, printed beside a speed benchmark's table.

The project's machine is a virtual machine on a shared host, and which host, and how busy it is, changes from day to
day: on 2026-12-06 (session 72) the same code ran the object level 1.6–2.7× and the detection level 1.5–2.0×
slower than in session 71's runs a few hours before (``fidelity.py --object-only`` and ``--detection-only``; no such
line was printed then, so the host is the inferred cause: the same commit, and numpy 2.3.5 against 2.4.6 moved the
detection level by about 3 %). A table of milliseconds is only comparable with another day's beside these three
figures (each the median of several runs):

* ``python``: ``sum(range(1_000_000))``, ms — the interpreter alone (the object and detection levels' frames are
  thousands of short calls);
* ``numpy call``: ``np.add`` of two 256-element float64 arrays into a third, µs a call — the cost of one short numpy
  call (the detection level makes some 6,400 Python-level calls a frame, most of them into numpy);
* ``BLAS``: a complex128 matrix product of the signal level's floor's shape, (3072 × 321)·(321 × 256), GFlop/s (8
  real flops a complex multiply-add), on as many threads as ``OPENBLAS_NUM_THREADS`` allows (the line says how many
  it was set to; the benchmarks' commands set 1).

The figures are only as steady as the machine: other work on it moves them (an independent tester's 11 runs within
20 minutes beside other processes: 17.3–26.5 ms, 0.40–0.85 µs, 45.8–71.3 GFlop/s). Compare quiet runs, several.
Instructions (``benchmarks/instructions.py``) do not move with the machine at all; these say how fast the day's
machine runs them.

Run alone: ``OPENBLAS_NUM_THREADS=1 python benchmarks/machine.py`` (about 2 s).
"""

from __future__ import annotations

import os
import statistics
import time

import numpy as np


def _median_s(fn, repeats: int) -> float:
    fn()                                    # warm-up
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        runs.append(time.perf_counter() - t0)
    return statistics.median(runs)


def reference() -> dict[str, float]:
    """The three figures: python (ms), numpy call (µs), BLAS (GFlop/s)."""
    py = _median_s(lambda: sum(range(1_000_000)), 7)
    a, b, out = np.ones(256), np.ones(256), np.empty(256)

    def calls():
        for _ in range(10_000):
            np.add(a, b, out=out)
    call = _median_s(calls, 7) / 10_000
    rng = np.random.default_rng(0)
    left = rng.standard_normal((3072, 321)) + 1j * rng.standard_normal((3072, 321))
    right = rng.standard_normal((321, 256)) + 1j * rng.standard_normal((321, 256))
    blas = _median_s(lambda: left @ right, 7)
    return {"python_ms": py * 1e3, "numpy_call_us": call * 1e6,
            "blas_gflops": 8.0 * 3072 * 321 * 256 / blas / 1e9}


def line() -> str:
    """One line for a benchmark's output."""
    r = reference()
    return (f"machine today: python sum(range(10⁶)) {r['python_ms']:.1f} ms, numpy call {r['numpy_call_us']:.2f} "
            f"µs, BLAS complex128 {r['blas_gflops']:.1f} GFlop/s with OPENBLAS_NUM_THREADS="
            f"{os.environ.get('OPENBLAS_NUM_THREADS', 'unset')} (benchmarks/machine.py: compare quiet days by these)")


if __name__ == "__main__":
    print(line())
