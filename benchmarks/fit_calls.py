"""What one call of the signal level's patch fits costs: its fixed part against its part per peak and patch cell.

The chain fits its peaks in patch-size buckets (``radarnode.dsp.peaks``: half-widths 3, 6, 12), one batched call
a bucket. A call has a fixed cost (its searches' and Newton steps' numpy calls, whatever the number of peaks) and a
cost per peak that grows with the patch's (2b + 1)² cells. A few peaks in a bucket of their own then cost nearly a
whole call; in the next larger bucket, where the patch is exact too (R⁻¹ is zero outside a peak's own cells), they
cost only their larger patches. ``_call_buckets`` joins them where that is cheaper, with each fit's ``CALL_CELLS``:
the fixed cost in cells. This benchmark measures it.

For each fit (``PatchFit._fit_patches``, the three search rounds, no neighbours' tones; ``MigrationFit._fit``,
μ = 1.5 bins, the patch projected on the peak's channel vector, as the chain calls it), each bucket b and
K = 1, 8, 32, 64 peaks at random cells of a noise map (mimo12's shape, 12 × 256 × 256, complex128): the median
time of a call. Then a least-squares fit of time = call + K·(a + κ·(2b + 1)²) over all of them, and call/κ, the
fixed cost in cells, beside the fit's ``CALL_CELLS``. Prints Markdown tables.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/fit_calls.py [--repeats N]`` (about 20 s).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import sys  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import machine  # noqa: E402
import signal_speed  # noqa: E402  (its median timer)

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from radarnode.dsp import peaks  # noqa: E402
from radarnode.dsp.spectra import window  # noqa: E402

SHAPE = (12, 256, 256)
BUCKETS = (3, 6, 12)
PEAKS = (1, 8, 32, 64)


def _median_ms(fn, repeats: int) -> float:
    """Median ms of ``repeats`` calls of ``fn()`` after a warm-up (``signal_speed._median_ms``)."""
    return signal_speed._median_ms(lambda _: fn(), list(range(repeats)))


def measure(repeats: int) -> dict[str, dict[tuple[int, int], float]]:
    """{fit: {(bucket, peaks): ms}}."""
    rng = np.random.default_rng(0)
    c, m, n = SHAPE
    rd = rng.standard_normal(SHAPE) + 1j * rng.standard_normal(SHAPE)
    fit = peaks.PatchFit(window("hann", m), window("hann", n), 12)
    mig = peaks.MigrationFit(window("hann", m), window("hann", n), 12)
    out: dict[str, dict[tuple[int, int], float]] = {"PatchFit": {}, "MigrationFit": {}}
    for b in BUCKETS:
        for k in PEAKS:
            d, r = rng.integers(0, m, k), rng.integers(0, n, k)
            fd, fr = rng.uniform(-0.4, 0.4, k), rng.uniform(-0.4, 0.4, k)
            halves = np.full(k, b)
            x = peaks._patches(rd, d, r, b, (1, 2, 0, 3))
            out["PatchFit"][(b, k)] = _median_ms(lambda: fit._fit_patches(x, fd, fr, halves, *fit.axes[b]), repeats)
            mu = np.full((k, 1), 1.5)
            snap = rd[:, d, r].T
            out["MigrationFit"][(b, k)] = _median_ms(
                lambda: mig._fit(rd, d, r, fd, fr, mu, halves, *mig.axes[b], snap), repeats)
    return out


def model(times: dict[tuple[int, int], float]) -> tuple[float, float, float]:
    """Least squares of ms = call + K·(a + κ·(2b + 1)²): (call ms, a µs, κ µs)."""
    keys = sorted(times)
    rows = np.array([[1.0, k, k * (2 * b + 1) ** 2] for b, k in keys])
    coef, *_ = np.linalg.lstsq(rows, np.array([times[key] for key in keys]), rcond=None)
    return float(coef[0]), 1e3 * float(coef[1]), 1e3 * float(coef[2])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()
    print(machine.line())
    got = measure(args.repeats)
    for name, times in got.items():
        print(f"\n{name}: ms a call\n")
        print("| bucket b | (2b+1)² | " + " | ".join(f"K = {k}" for k in PEAKS) + " |")
        print("|---:|---:|" + "---:|" * len(PEAKS))
        for b in BUCKETS:
            print(f"| {b} | {(2 * b + 1) ** 2} | " + " | ".join(f"{times[(b, k)]:.3f}" for k in PEAKS) + " |")
        call, a, kappa = model(times)
        worst = max(abs(times[(b, k)] - (call + k * (a + kappa * (2 * b + 1) ** 2) / 1e3)) / times[(b, k)]
                    for b, k in times)
        print(f"\nfit: a call {call:.3f} ms + a peak {a:.1f} µs + {kappa:.4f} µs a cell (worst misfit "
              f"{100 * worst:.0f} %): a call is {1e3 * call / kappa:,.0f} cells; CALL_CELLS "
              f"{getattr(peaks, name).CALL_CELLS:,.0f}")


if __name__ == "__main__":
    main()
