"""Super-resolution DOA estimators (``radarnode.dsp.subspace``): cost per estimate, RMSE against the stochastic
Cramér–Rao bound, and resolution probability against separation.

Array: 12-element ULA at d = λ/2 (seed 001's N = 12), two equal-power uncorrelated sources, unit noise power,
per-element SNR. Every estimate goes through ``subspace.estimate`` (validation, scaling, covariance, smoothing,
FB, estimator) with the source count given (2).

* Speed: µs per estimate, the median over ``--repeats`` timings of ``--calls`` calls each, cycling over 32
  snapshot draws, measured in this run; two cases: K = 1 with forward–backward averaging and spatial
  smoothing (Q = round(0.7·12) = 8), and K = 16 on the full array without preprocessing (except the
  ``music+fb`` row, complex MUSIC on the FB covariance; ``unitary_music`` is FB by construction). The
  complex-vs-unitary ratio compares ``music+fb`` with ``unitary_music``, which give the same angles.
* Accuracy: RMSE of sin θ over ``--trials`` trials (both sources, estimates sorted), divided by √CRB
  (``subspace.crb_sin``, Stoica & Nehorai's stochastic bound; for K = 1 it is the same formula at K = 1, an
  asymptotic bound that is not tight there). Sources at sin θ = −0.3 and 0.2 (3 Rayleigh widths apart).
  "res" is the fraction of trials with both sources resolved (flag set, each estimate within half the
  separation); each cell gives RMSE/√CRB over all trials / over the resolved trials only (res).
* Resolution: probability of resolving two sources at 20 dB centred on sin θ = 0.1, separated by
  0.25 … 1.0 Rayleigh widths (1 Rayleigh width = 1/(N·d) = 0.167 in sin θ).

Run: ``.venv/bin/python benchmarks/doa_estimators.py [--trials N] [--repeats N] [--calls N]``.
OpenBLAS is limited to one thread (set before numpy is imported): these are 8×8 to 22×22 problems.
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402

from radarnode.dsp import subspace as ss  # noqa: E402

N = 12
D = 0.5
RAYLEIGH = 1.0 / (N * D)
#: row name → (estimator, extra options on the K = 16 full-array case)
ROWS = {
    "bartlett": ("bartlett", {}),
    "capon": ("capon", {}),
    "music": ("music", {}),
    "music+fb": ("music", {"fb": True}),
    "unitary_music": ("unitary_music", {}),
    "root_music": ("root_music", {}),
    "esprit": ("esprit", {}),
}
SMOOTHED = {"fb": True, "subarray": True}


def draw(rng, u, snr_db, k):
    """(N, k) snapshots: two equal-power uncorrelated sources at ``u`` plus unit-power noise."""
    a = ss.steering(N, np.asarray(u, dtype=float), D)
    amp = 10.0 ** (snr_db / 20.0)
    s = (rng.standard_normal((len(u), k)) + 1j * rng.standard_normal((len(u), k))) / math.sqrt(2.0)
    w = (rng.standard_normal((N, k)) + 1j * rng.standard_normal((N, k))) / math.sqrt(2.0)
    return a @ (amp * s) + w


def options(row, k):
    method, extra = ROWS[row]
    return method, (SMOOTHED if k == 1 else extra)


def time_rows(repeats, calls):
    """{(row, K): [µs per call, one value per repeat]}; rows and K interleaved within each repeat so that
    load from other work on the machine falls on every row alike."""
    rng = np.random.default_rng(1)
    data = {k: [draw(rng, [-0.3, 0.2], 20.0, k) for _ in range(32)] for k in (1, 16)}
    cases = [(row, k) for row in ROWS for k in (1, 16)]
    for row, k in cases:                               # warm the grid and index caches
        method, opts = options(row, k)
        for x in data[k]:
            ss.estimate(method, x, 2, D, **opts)
    out = {case: [] for case in cases}
    for _ in range(repeats):
        for row, k in cases:
            method, opts = options(row, k)
            xs = data[k]
            t0 = time.perf_counter()
            for i in range(calls):
                ss.estimate(method, xs[i % 32], 2, D, **opts)
            out[row, k].append((time.perf_counter() - t0) / calls * 1e6)
    return out


def resolved(est, u0):
    sep = abs(u0[1] - u0[0])
    return est.all_resolved and float(np.max(np.abs(est.sin_theta - u0))) < sep / 2


def accuracy(row, k, snr_db, trials):
    method, opts = options(row, k)
    u0 = np.array([-0.3, 0.2])
    rng = np.random.default_rng(int(1000 + snr_db))
    err = np.empty((trials, 2))
    ok = np.zeros(trials, dtype=bool)
    for t in range(trials):
        est = ss.estimate(method, draw(rng, u0, snr_db, k), 2, D, **opts)
        err[t] = est.sin_theta - u0
        ok[t] = resolved(est, u0)
    crb = float(np.mean(ss.crb_sin(u0, N, k, snr_db, D)))
    res_only = math.sqrt(float(np.mean(err[ok] ** 2)) / crb) if ok.any() else float("nan")
    return math.sqrt(float(np.mean(err ** 2)) / crb), res_only, float(ok.mean())


def resolution(row, k, sep_rayleigh, trials):
    method, opts = options(row, k)
    sep = sep_rayleigh * RAYLEIGH
    u0 = np.array([0.1 - sep / 2, 0.1 + sep / 2])
    rng = np.random.default_rng(int(2000 + 100 * sep_rayleigh))
    hits = sum(resolved(ss.estimate(method, draw(rng, u0, 20.0, k), 2, D, **opts), u0) for _ in range(trials))
    return hits / trials


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=500)
    ap.add_argument("--repeats", type=int, default=15)
    ap.add_argument("--calls", type=int, default=200)
    args = ap.parse_args(argv)
    t_start = time.perf_counter()
    print(f"numpy {np.__version__}, Python {platform.python_version()}, {os.cpu_count()} cores, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}; N = {N}, d = {D} λ, 2 sources; "
          f"load average at start {os.getloadavg()[0]:.2f}\n")

    print(f"### Cost of one estimate (µs, median of {args.repeats} × {args.calls} calls)\n")
    print("| estimator | K = 1, FB + smoothing (Q = 8) | K = 16, full array | ≤ 100 µs (both medians)? "
          "| fastest repeat, K = 1 / K = 16 |")
    print("|---|---:|---:|---|---:|")
    runs = time_rows(args.repeats, args.calls)
    for row in ROWS:
        t1, t16 = np.median(runs[row, 1]), np.median(runs[row, 16])
        met = "yes" if max(t1, t16) <= 100.0 else "no"
        print(f"| {row} | {t1:.0f} | {t16:.0f} | {met} | {min(runs[row, 1]):.0f} / {min(runs[row, 16]):.0f} |")
    for k in (1, 16):
        ratio = np.array(runs["music+fb", k]) / np.array(runs["unitary_music", k])
        q25, q50, q75 = np.percentile(ratio, [25, 50, 75])
        print(f"\ncomplex FB-MUSIC / unitary MUSIC time, K = {k}: median of the per-repeat ratios {q50:.2f} "
              f"(quartiles {q25:.2f}–{q75:.2f}; > 1: unitary faster)")
    print()

    for k in (16, 1):
        label = "K = 16, full array" if k == 16 else "K = 1, FB + smoothing (Q = 8)"
        print(f"### RMSE / √CRB, sources at sin θ = −0.3, 0.2, {args.trials} trials, {label}\n")
        snrs = (0.0, 10.0, 20.0)
        print("| estimator | " + " | ".join(f"{s:.0f} dB: all / resolved (res)" for s in snrs) + " |")
        print("|---|" + "---:|" * len(snrs))
        for row in ROWS:
            cells = []
            for snr in snrs:
                ratio, ratio_res, res = accuracy(row, k, snr, args.trials)
                cells.append(f"{ratio:.2f} / {ratio_res:.2f} ({res:.2f})")
            print(f"| {row} | " + " | ".join(cells) + " |")
        print()

    seps = (0.25, 0.5, 0.75, 1.0)
    for k in (16, 1):
        label = "K = 16, full array" if k == 16 else "K = 1, FB + smoothing (Q = 8)"
        print(f"### Probability of resolving two sources at 20 dB, {args.trials} trials, {label}\n")
        print("| estimator | " + " | ".join(f"{s:.2f} BW" for s in seps) + " |")
        print("|---|" + "---:|" * len(seps))
        for row in ROWS:
            print(f"| {row} | " + " | ".join(f"{resolution(row, k, s, args.trials):.2f}" for s in seps) + " |")
        print()
    print(f"(run took {time.perf_counter() - t_start:.0f} s; load average at end {os.getloadavg()[0]:.2f})")


if __name__ == "__main__":
    main()
