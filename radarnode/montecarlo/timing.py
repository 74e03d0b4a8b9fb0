"""The cost of one estimate, in µs (medians), measured in this process on seed 001's data (one snapshot of a
12-element radar, one target at 20 dB).

* Subspace estimators (``radarnode.dsp.subspace``): one ``subspace.estimate`` call — validation, covariance,
  smoothing (Q = 8), forward–backward averaging, estimator — with the number of sources given; plus complex
  MUSIC *without* forward–backward averaging (``music_nofb``) for reference, and ``music_core`` /
  ``unitary_music_core``: the estimator functions alone on covariances prepared beforehand.
* Seed 001's estimators (``radarnode.dsp.lcacm``) take a batch of trials: one call on a batch of one
  (``single``) and the per-trial cost in a batch of ``batch`` trials (``batched``).

Every repeat times every estimator once, in turn, so that load from other work on the machine falls on all of
them alike; the unitary/complex MUSIC ratio is the median of the per-repeat ratios (seed 004 claims the unitary
transform makes MUSIC cheaper; both give the same angles, checked here on the same draws).
"""

from __future__ import annotations

import time

import numpy as np

from radarnode.dsp import lcacm as lc
from radarnode.dsp import subspace as ss
from radarnode.montecarlo.seed001 import Setup

SNR_DB = 20.0
DRAWS = 32


def _draws(setup: Setup, rng: np.random.Generator, trials: int) -> tuple[list[np.ndarray], np.ndarray]:
    geo = setup.geometry
    x, y = lc.polar_to_xy(setup.range_m, np.radians([7.0]))
    rng_k, th = lc.seen_from(x, y, geo)
    ys = [lc.snapshots(rng, np.broadcast_to(th[k], (trials, 1)), SNR_DB, setup.n_elements, setup.spacing_wl)
          for k in range(2)]
    return ys, rng_k[:, 0]


def measure(setup: Setup, *, repeats: int = 15, calls: int = 100, batch: int = 500, seed: int = 0,
            on_repeat=None) -> dict:
    """``{"us": {name: {"single": µs, "batched": µs or None}}, "complex_over_unitary_music": {...}, ...}``;
    ``on_repeat`` is called after each repeat (a progress bar)."""
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(99,)))
    small, r = _draws(setup, rng, DRAWS)
    big, _ = _draws(setup, rng, batch)
    d, q = setup.spacing_wl, setup.subarray
    geo = setup.geometry
    rr = [np.full(DRAWS, r[0]), np.full(DRAWS, r[1])]
    rb = [np.full(batch, r[0]), np.full(batch, r[1])]

    def subspace_case(method, fb):
        def go(i):
            return ss.estimate(method, small[0][i % DRAWS], 1, d, fb=fb, subarray=q)
        return go

    single = {m: subspace_case(m, True) for m in ss.ESTIMATORS}
    single["music_nofb"] = subspace_case("music", False)
    # the two estimators alone, on covariances prepared beforehand (smoothed; forward–backward for the complex
    # one, as unitary MUSIC's real covariance Re(Qᴴ R Q) is the FB covariance's): what seed 004's claim is about
    covs = [ss.spatial_smoothing(ss.sample_covariance(small[0][i]), q) for i in range(DRAWS)]
    covs_fb = [ss.forward_backward(c) for c in covs]
    single["music_core"] = lambda i: ss.music(covs_fb[i % DRAWS], 1, d)
    single["unitary_music_core"] = lambda i: ss.unitary_music(covs[i % DRAWS], 1, d)
    seed001 = {
        "seed001_bs": (lambda i: lc.beam_scan(small[0][i % DRAWS][None], 2, d), lambda: lc.beam_scan(big[0], 2, d)),
        "seed001_capon": (lambda i: lc.capon_scan(small[0][i % DRAWS][None], 2, d, q),
                          lambda: lc.capon_scan(big[0], 2, d, q)),
        "lcacm": (lambda i: lc.lcacm(small[0][i % DRAWS][None], small[1][i % DRAWS][None], rr[0][:1], rr[1][:1], geo,
                                     d=d, q=q),
                  lambda: lc.lcacm(big[0], big[1], rb[0], rb[1], geo, d=d, q=q)),
    }
    for fn in list(single.values()) + [f for f, _ in seed001.values()]:      # warm the caches
        for i in range(4):
            fn(i)
    times: dict[str, list[float]] = {n: [] for n in list(single) + list(seed001)}
    batched: dict[str, list[float]] = {n: [] for n in seed001}
    for _ in range(repeats):
        for name, fn in single.items():
            t0 = time.perf_counter()
            for i in range(calls):
                fn(i)
            times[name].append((time.perf_counter() - t0) / calls * 1e6)
        for name, (one, many) in seed001.items():
            n_one = max(1, calls // 4)
            t0 = time.perf_counter()
            for i in range(n_one):
                one(i)
            times[name].append((time.perf_counter() - t0) / n_one * 1e6)
            t0 = time.perf_counter()
            many()
            batched[name].append((time.perf_counter() - t0) / batch * 1e6)
        if on_repeat:
            on_repeat()
    ratio = np.array(times["music"]) / np.array(times["unitary_music"])
    ratio_core = np.array(times["music_core"]) / np.array(times["unitary_music_core"])
    same = max(float(np.max(np.abs(ss.estimate("music", small[0][i], 1, d, fb=True, subarray=q).sin_theta
                                   - ss.estimate("unitary_music", small[0][i], 1, d, fb=True, subarray=q).sin_theta)))
               for i in range(DRAWS))
    return {
        "snr_db": SNR_DB, "repeats": repeats, "calls": calls, "batch": batch,
        "us": {n: {"single": float(np.median(times[n])),
                   "batched": float(np.median(batched[n])) if n in batched else None} for n in times},
        "complex_over_unitary_music": {"median": float(np.median(ratio)),
                                       "quartiles": [float(v) for v in np.percentile(ratio, [25, 75])]},
        "complex_over_unitary_music_core": {"median": float(np.median(ratio_core)),
                                            "quartiles": [float(v) for v in np.percentile(ratio_core, [25, 75])]},
        "max_abs_sin_difference_music_vs_unitary": same,
    }


__all__ = ["measure", "SNR_DB"]
