"""What the signal chain's estimates lose to range migration: the chain against a fit that knows the migration.

The patch fit of the chain (``radarnode.dsp.peaks.PatchFit``) models a peak as one
window response in Doppler times one in range: a target that does not move
between chirps. On the mimo12 preset (TDM, 7.7 ms of chirps) a target moves
v·7.7 ms during the frame, 1.23 range bins at 70 m/s, and its peak is smeared
across range bins along slow time. This script measures how much of the gap to
the Cramér–Rao bound that costs: per radial speed, the chain's range-rate RMSE
and range standard deviation against the bound, beside those of a fit on the
same 25 × 25-cell patch whose template is the exact noise-free response of the
point target (``synthesize_rd`` without noise, so migration, coupling and the
in-chirp term are all in it) at the candidate range and speed, with the true
alias number (what a fit knows that has resolved the ambiguity), the channels'
amplitudes concentrated out and the windows' noise correlation whitened
(Nelder–Mead from the chain's estimate).

Scene as in ``benchmarks/signal_speed.py``: a point target at ρ = 20 dB, 50 m,
10°, radial speed as given. Slow (each template is a whole synthesis): about
3 minutes for 20 trials at one speed.

Run: ``.venv/bin/python benchmarks/migration_fit.py [--speeds -70,0] [--trials 20]``. Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from scipy.optimize import minimize  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.radar import equation  # noqa: E402
from radarnode.radar.chain import DspChain  # noqa: E402
from radarnode.radar.scatterers import point_targets  # noqa: E402
from radarnode.radar.setup import load_scenario, radar_config  # noqa: E402
from radarnode.radar.signal_model import num_range_samples, synthesize_rd  # noqa: E402

RHO_DB, R0_M, AZ_DEG, HALF = 20.0, 50.0, 10.0, 12


def run(p, speed_mps: float, trials: int) -> dict:
    chain = DspChain(p)
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    axis_d, axis_r = chain._patch_fit(m, n).axes[HALF]
    inv = np.kron(axis_d.inverse[HALF], axis_r.inverse[HALF])          # R⁻¹ of the patch (Hann × Hann)
    per_sample = RHO_DB - 10.0 * math.log10(n * m * c)

    def cube(r, v, rng, noise):
        return synthesize_rd(p, point_targets([r], [AZ_DEG], [v], 0.0), rng, snr_db=per_sample, noise=noise)

    peak = np.unravel_index(np.argmax(np.abs(cube(R0_M, speed_mps, np.random.default_rng(0), False)[0])), (m, n))
    di = (peak[0] + np.arange(-HALF, HALF + 1)) % m
    ri = (peak[1] + np.arange(-HALF, HALF + 1)) % n

    def patch(rd):
        return rd[:, di[:, None], ri[None, :]].reshape(c, -1)

    vmax = p.alias_speed_mps
    chain_err, fit_err = [], []
    for t in range(trials):
        rd = cube(R0_M, speed_mps, np.random.default_rng(1000 + t), True)
        det = chain.process_rd(rd)
        start = (0.0, 0.0)
        if len(det):
            dv = (det.range_rate_mps - speed_mps + vmax) % (2.0 * vmax) - vmax
            j = int(np.argmin(np.abs(dv)))
            if abs(dv[j]) < 1.0:
                dr = det.range_m[j] - R0_M
                chain_err.append((dr, dv[j]))
                # the chain's range carries the coupling of the aliased speed: start from its speed only
                start = (0.0, dv[j])
        x = patch(rd)

        def neg_likelihood(q):
            h = patch(cube(R0_M + q[0], speed_mps + q[1], np.random.default_rng(0), False))[0]
            g = inv @ h
            return -float(np.sum(np.abs(x @ g.conj()) ** 2) / np.real(h.conj() @ g))

        res = minimize(neg_likelihood, np.array(start), method="Nelder-Mead",
                       options={"xatol": 1e-4, "fatol": 1e-9, "initial_simplex":
                                np.array(start) + np.array([[0.0, 0.0], [0.02, 0.0], [0.0, 0.02]])})
        fit_err.append(res.x)
    ce, fe = np.array(chain_err), np.array(fit_err)
    crb_r, crb_v = float(equation.crb_range_m(p, RHO_DB)), float(equation.crb_speed_mps(p, RHO_DB))
    return {"mu": abs(speed_mps) * p.integration_time_s / p.range_resolution_m, "found": len(ce),
            "chain_v": np.sqrt(np.mean(ce[:, 1] ** 2)) / crb_v, "chain_r": ce[:, 0].std() / crb_r,
            "fit_v": np.sqrt(np.mean(fe[:, 1] ** 2)) / crb_v, "fit_r": np.sqrt(np.mean(fe[:, 0] ** 2)) / crb_r}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--speeds", default="-70,0", help="radial speeds, m/s, comma-separated (default -70,0)")
    ap.add_argument("--trials", type=int, default=20, help="noise draws per speed (default 20)")
    args = ap.parse_args()
    p = radar_config(load_scenario(ROOT / "scenarios" / "highway_mimo12.yaml")).preset
    print(f"Point target, ρ = {RHO_DB:g} dB, {R0_M:g} m, {AZ_DEG:g}°, preset {p.name}; {args.trials} trials a row; "
          "RMSE (range: standard deviation for the chain, whose range carries the aliased coupling) over the CRB.\n")
    print("| radial speed | migration over the frame | chain detected | chain: rate RMSE/CRB | chain: range std/CRB "
          "| exact-migration fit: rate RMSE/CRB | exact-migration fit: range RMSE/CRB |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    for v in (float(s) for s in args.speeds.split(",")):
        r = run(p, v, args.trials)
        print(f"| {v:g} m/s | {r['mu']:.2f} bins | {r['found']}/{args.trials} | {r['chain_v']:.2f} "
              f"| {r['chain_r']:.2f} | {r['fit_v']:.2f} | {r['fit_r']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
