"""The patch fit's search rounds: what each choice of grids costs in accuracy and in the highway frame's time.

``PatchFit`` (``radarnode.dsp.peaks``) searches range and Doppler alternately on grids around its estimate, round
after round, each grid finer; a parabola through the best point and its neighbours ends each search. Fewer rounds
cost less (each round collapses every patch twice, whatever its points), but the last round's step sets what the
parabola leaves, and each round is one more alternation of the two axes. The variants, (half-span, points) a round:

* ``three rounds`` — ((0.5, 9), (1/16, 5), (1/64, 5)): the fit until 2026-12-07 (last step 1/128 bin);
* ``two of 9`` — ((0.5, 9), (1/32, 9)): the default since (last step 1/128 bin, one alternation fewer);
* ``two, last of 17`` — ((0.5, 9), (1/16, 17)): the second round as wide as the old one's;
* ``two of 9 and 5`` — ((0.5, 9), (1/16, 5)): the old first two rounds alone (last step 1/32 bin).

Printed for each: the error on noise-free tones (rms and max over 200 tones, bins) and the RMSE over the CRB of
one tone's frequency, √6/(2π√ρ) bins, Doppler / range, at ρ = 16, 20, 30, 60 and 80 dB (``--trials`` noisy tones a
point, the same draws for every variant; a 64 × 64 Hann map, 4 channels, the tone anywhere within its cell, started
from the three-bin interpolation; the RMSE over the trials that every variant fitted on the tone's own peak,
within half a bin — a noise peak taken is a miss — so that the variants are compared on the same draws: "k out"
counts the trials left out, "its own" those this variant missed). Then, with ``--frames`` > 0, the complex128
chain's ``process_rd`` on the ``highway_mimo12`` frames of ``signal_speed.py`` at 0, 30, 50 and 70 m/s, median ms,
the variants alternated in one process (the first fit and the refit use the same variant's grids: the refit's
first round is ±0.25 bin of 5 points in every variant). Prints Markdown tables.

Run: ``OPENBLAS_NUM_THREADS=1 .venv/bin/python benchmarks/fit_rounds.py [--trials N] [--frames N]`` (about 4
minutes with the defaults; ``--frames 0`` the accuracy alone, ``--trials 0`` the timing alone).
"""

from __future__ import annotations

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import argparse  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import machine  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from radarnode.dsp.peaks import PatchFit, interpolate  # noqa: E402
from radarnode.dsp.spectra import noncoherent_power, window  # noqa: E402

VARIANTS = {
    "three rounds": (((0.5, 9), (1.0 / 16.0, 5), (1.0 / 64.0, 5)), ((0.25, 5), (1.0 / 16.0, 5), (1.0 / 64.0, 5))),
    "two of 9": (((0.5, 9), (1.0 / 32.0, 9)), ((0.25, 5), (1.0 / 32.0, 9))),
    "two, last of 17": (((0.5, 9), (1.0 / 16.0, 17)), ((0.25, 5), (1.0 / 16.0, 17))),
    "two of 9 and 5": (((0.5, 9), (1.0 / 16.0, 5)), ((0.25, 5), (1.0 / 16.0, 5))),
}
SNRS_DB = (16.0, 20.0, 30.0, 60.0, 80.0)
M = N = 64
CHANNELS = 4


def tone_map(xd: float, xr: float, amp: np.ndarray, rng: np.random.Generator | None, noise: float) -> np.ndarray:
    """Windowed range–Doppler spectra of one tone at (xd, xr) bins in every channel, white noise of variance
    ``noise`` a sample added first (``rng`` None: none)."""
    t_d, t_r = np.arange(M)[:, None], np.arange(N)[None, :]
    x = amp[:, None, None] * np.exp(2j * np.pi * (xd * t_d / M + xr * t_r / N))[None]
    if rng is not None:
        x = x + (rng.standard_normal(x.shape) + 1j * rng.standard_normal(x.shape)) * math.sqrt(noise / 2)
    x = x * window("hann", M)[None, :, None] * window("hann", N)[None, None, :]
    return np.fft.fft(np.fft.fft(x, axis=2), axis=1)


def _starts(rd: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    p = noncoherent_power(rd)
    sub = p[28:36, 28:36]
    d, r = np.unravel_index(np.argmax(sub), sub.shape)
    d, r = np.array([d + 28]), np.array([r + 28])
    dd, dr = interpolate(p, d, r)
    return d, r, dd, dr


def accuracy(trials: int) -> list[str]:
    fit = PatchFit(window("hann", M), window("hann", N), 12)
    rng = np.random.default_rng(0)
    clean = []
    for _ in range(200):
        xd, xr = 30.0 + rng.random(), 30.0 + rng.random()
        clean.append((tone_map(xd, xr, np.exp(2j * np.pi * rng.random(CHANNELS)), None, 0.0), xd, xr))
    noisy = {}
    for rho_db in SNRS_DB:
        rho = 10.0 ** (rho_db / 10.0)
        rng = np.random.default_rng(7)
        noisy[rho_db] = []
        for _ in range(trials):
            xd, xr = 30.0 + rng.random(), 30.0 + rng.random()
            amp = np.exp(2j * np.pi * rng.random(CHANNELS))
            noisy[rho_db].append((tone_map(xd, xr, amp, rng, M * N * CHANNELS / rho), xd, xr))
    lines = ["| variant | noise-free error, rms / max | " + " | ".join(f"RMSE/CRB at {r:g} dB" for r in SNRS_DB)
             + " |", "|---|---:|" + "---:|" * len(SNRS_DB)]
    saved = PatchFit.ROUNDS
    clean_err, noisy_err = {}, {}
    try:
        for name, (rounds, _) in VARIANTS.items():
            PatchFit.ROUNDS = rounds

            def errors(maps):
                out = []
                for rd, xd, xr in maps:
                    d, r, dd, dr = _starts(rd)
                    fd, fr, _ = fit(rd, d, r, dd, dr)
                    out.append(((d + fd)[0] - xd, (r + fr)[0] - xr))
                return np.array(out)
            clean_err[name] = np.abs(errors(clean))
            noisy_err[name] = {rho_db: errors(noisy[rho_db]) for rho_db in SNRS_DB}
            print(f"({name}: fitted)", file=sys.stderr, flush=True)
    finally:
        PatchFit.ROUNDS = saved
    # the RMSE over the trials every variant fitted on the tone's own peak (within half a bin in both axes; a noise
    # peak is a miss), so that the variants are compared on the same draws; "out": the trials left out, and in
    # brackets those this variant itself missed
    common = {rho_db: np.logical_and.reduce([np.all(np.abs(noisy_err[name][rho_db]) < 0.5, axis=1)
                                             for name in VARIANTS]) for rho_db in SNRS_DB}
    for name in VARIANTS:
        e = clean_err[name]
        cells = [f"{math.sqrt(np.mean(e ** 2)):.1e} / {e.max():.1e} bin"]
        for rho_db in SNRS_DB:
            err, inlier = noisy_err[name][rho_db], common[rho_db]
            own = int(np.sum(~np.all(np.abs(err) < 0.5, axis=1)))
            crb = math.sqrt(6.0) / (2.0 * math.pi * math.sqrt(10.0 ** (rho_db / 10.0)))
            rmse = np.sqrt(np.mean(err[inlier] ** 2, axis=0)) / crb
            cells.append(f"{rmse[0]:.3f} / {rmse[1]:.3f}"
                         + ("" if inlier.all() else f" ({np.sum(~inlier)} out; {own} its own)"))
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--trials", type=int, default=1000, help="noisy tones a point (default 1000; 0: no accuracy table)")
    ap.add_argument("--frames", type=int, default=9, help="highway frames a speed for the timing (0: none)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    print(machine.line())
    if args.trials > 0:
        print(f"\n### The patch fit's search rounds: accuracy ({args.trials} noisy tones a point)\n")
        print("\n".join(accuracy(args.trials)))
    if args.frames > 0:
        print(f"\n### process_rd of the highway_mimo12 frame, complex128, median of {3 * args.frames} runs\n")
        print("\n".join(timing(args.frames)))
    print(f"\n(run time {time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
