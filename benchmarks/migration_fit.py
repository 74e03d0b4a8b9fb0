"""What range migration costs the chain's estimates, and what the chain's migration fit wins back.

The patch fit of the chain (``radarnode.dsp.peaks.PatchFit``) models a peak as one
window response in Doppler times one in range: a target that does not move
between chirps. On the mimo12 preset (TDM, 7.7 ms of chirps) a target moves
v·7.7 ms during the frame, 1.23 range bins at 70 m/s, and its peak is smeared
across range bins along slow time. ``signal.dsp.migration_fit`` fits the wrapped
peaks again with the migrating target's response (``radarnode.dsp.peaks.MigrationFit``;
the true speed, and so the migration, from the TDM wrap count). Its default, ``auto``,
fits complex128 spectra (the default dtype; every table here is complex128 but
for the cost table's complex64 columns) and not complex64 ones; the tables compare
``migration_fit: false`` (the still fit) with ``true``.

Table 1, accuracy: a point target at ρ = 20 dB, 50 m, 10°, per radial speed, the
chain without and with the option — range-rate RMSE, range standard deviation
(the chain's range carries the coupling of the aliased speed beyond v_max, a
bias of about 40 cm that neither fit removes) and azimuth RMSE, each over its
Cramér–Rao bound (``radarnode.radar.equation``), ``--trials`` noise draws a row.
The azimuth RMSE is given twice: over every frame with a detection of the target, and over those whose TDM
wrap was found (angle within 2° of the truth). A missed wrap is a gross error (the angle of a broken array,
several degrees off), which the CRB, a bound on local errors, does not describe: it is counted in its own
column.

Table 2, cost: the mimo12 highway frame (``scenarios/highway_mimo12.yaml``, as in
``benchmarks/signal_speed.py``: synthesize_rd + process_rd, median of ``--frames``
frames, OpenBLAS on one thread) at ego speeds 0–70 m/s, without and with the option.

``--exact-trials N`` adds the independent reference of the previous runs: a fit on
the same 25 × 25-cell patch whose template is the exact noise-free response of
the target (``synthesize_rd`` without noise, so migration, coupling and the
in-chirp term are all in it) at the true alias number, Nelder–Mead from the
chain's estimate (slow: about 3 minutes for 20 trials at one speed).

Table 3, the TDM wrap: how often the wrap of a point target beyond the alias speed is found (its angle kept)
at ρ = 17–20 dB and up to 4× the alias speed, without and with the option.

Table 4, where ``auto`` fits (``--threshold-trials``): the still fit against the migration fit around
``MIGRATION_AUTO_MIN_BINS``. Table 5, high SNR (``--high-snr-trials``): the default chain at ρ = 40–60 dB on the
exact time-domain cube and on the range–Doppler synthesis.

Run: ``.venv/bin/python benchmarks/migration_fit.py [--speeds -70,-60,-50,-40,-32,0,50] [--trials 200]
[--wrap-trials 60] [--threshold-trials 60] [--high-snr-trials 30] [--frames 9] [--exact-trials 0]``. Prints
Markdown tables.
"""

from __future__ import annotations

import argparse
import dataclasses
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
from radarnode.radar.chain import DspChain, DspConfig  # noqa: E402
from radarnode.radar.scatterers import point_targets  # noqa: E402
from radarnode.radar.setup import load_scenario, radar_config  # noqa: E402
from radarnode.radar.signal_model import num_range_samples, synthesize_rd  # noqa: E402
from benchmarks.signal_speed import _median_ms, highway_frames  # noqa: E402

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


def _nearest_error(det, speed_mps: float, vmax: float, gate_m: float = 1.5):
    """(range, wrapped range-rate, azimuth) error of the detection nearest the point target at R0_M, AZ_DEG, or None
    when none lies within the gate (``gate_m`` in range, 1 m/s in wrapped range rate)."""
    dv = (det.range_rate_mps - speed_mps + vmax) % (2.0 * vmax) - vmax
    cost = np.abs(det.range_m - R0_M) / gate_m + np.abs(dv) / 1.0
    if not len(det) or cost.min() > 1.0:
        return None
    j = int(np.argmin(cost))
    return np.array([det.range_m[j] - R0_M, dv[j], det.azimuth_rad[j] - math.radians(AZ_DEG)])


def chain_errors(p, speed_mps: float, trials: int, migration: bool) -> dict:
    """The chain's (range, wrapped range-rate, azimuth) errors of the detection nearest the truth, per trial."""
    chain = DspChain(p, DspConfig(migration_fit=migration))
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    vmax = p.alias_speed_mps
    errs = []
    for t in range(trials):
        rd = synthesize_rd(p, point_targets([R0_M], [AZ_DEG], [speed_mps], 0.0), np.random.default_rng(1000 + t),
                           snr_db=RHO_DB - 10.0 * math.log10(n * m * c))
        err = _nearest_error(chain.process_rd(rd), speed_mps, vmax)
        if err is not None:
            errs.append(err)
    e = np.array(errs).reshape(-1, 3)
    crb_r, crb_v = float(equation.crb_range_m(p, RHO_DB)), float(equation.crb_speed_mps(p, RHO_DB))
    crb_a = float(equation.crb_azimuth_rad(p, RHO_DB, math.radians(AZ_DEG)))
    missed = np.abs(np.degrees(e[:, 2])) > 2.0                  # the wrap missed: a gross error of the angle
    return {"found": len(e), "rate": np.sqrt(np.mean(e[:, 1] ** 2)) / crb_v, "range": e[:, 0].std() / crb_r,
            "az": np.sqrt(np.mean(e[:, 2] ** 2)) / crb_a, "missed": int(missed.sum()),
            "az_found": np.sqrt(np.mean(e[~missed, 2] ** 2)) / crb_a}


def wrap_right(p, factor: float, rho_db: float, trials: int, migration: bool) -> tuple[int, int]:
    """(frames whose detection of a point target at 40 m, 10°, radial speed ``factor``·v_alias, ρ = ``rho_db``
    is at the right angle (within 2°, i.e. its TDM wrap was found), frames with a detection of it)."""
    chain = DspChain(p, DspConfig(migration_fit=migration))
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    v, vmax = factor * p.alias_speed_mps, p.alias_speed_mps
    right = seen = 0
    for seed in range(trials):
        det = chain.process_rd(synthesize_rd(p, point_targets([40.0], [10.0], [v], 0.0), np.random.default_rng(seed),
                                             snr_db=rho_db - 10.0 * math.log10(n * m * c)))
        dv = (det.range_rate_mps - v + vmax) % (2 * vmax) - vmax
        near = np.flatnonzero((np.abs(dv) < 0.5) & (np.abs(det.range_m - 40.0) < 2.0))
        if near.size:
            seen += 1
            right += bool(np.any(np.abs(np.degrees(det.azimuth_rad[near]) - 10.0) < 2.0))
    return right, seen


def threshold_row(p, speed_mps: float, trials: int) -> dict:
    """The still fit against the migration fit on the same frames (point target at ρ = 20 dB, 50 m, 10°): each one's
    range std, range-rate RMSE and azimuth RMSE over the frames whose wrap it found, over the CRB; the median and
    90th percentile of |migration fit − still fit| over the CRB per axis; and whether ``auto`` fits this target
    (complex128) — its detections equal the migration fit's, or the still fit's."""
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    vmax = p.alias_speed_mps
    crb = np.array([float(equation.crb_range_m(p, RHO_DB)), float(equation.crb_speed_mps(p, RHO_DB)),
                    float(equation.crb_azimuth_rad(p, RHO_DB, math.radians(AZ_DEG)))])
    chains = {mode: DspChain(p, DspConfig(migration_fit=mode)) for mode in (False, True, "auto")}
    errs, diff, auto_fits, auto_still = {False: [], True: []}, [], 0, 0
    for t in range(trials):
        rd = synthesize_rd(p, point_targets([R0_M], [AZ_DEG], [speed_mps], 0.0), np.random.default_rng(3000 + t),
                           snr_db=RHO_DB - 10.0 * math.log10(n * m * c))
        got = {}
        for mode, chain in chains.items():
            err = _nearest_error(chain.process_rd(rd), speed_mps, vmax, gate_m=3.0)
            if err is not None:
                got[mode] = err
        for mode in (False, True):
            if mode in got:
                errs[mode].append(got[mode])
        if False in got and True in got and "auto" in got:
            diff.append(np.abs(got[True] - got[False]) / crb)
            if not np.array_equal(got[True], got[False]):       # frames where the two fits differ tell auto's choice
                auto_fits += np.array_equal(got["auto"], got[True])
                auto_still += np.array_equal(got["auto"], got[False])
    out = {"mu": abs(speed_mps) * p.integration_time_s / p.range_resolution_m, "auto": (auto_fits, auto_still)}
    for mode in (False, True):
        e = np.array(errs[mode]).reshape(-1, 3)
        found = np.abs(np.degrees(e[:, 2])) <= 2.0
        out[mode] = (e[:, 0].std() / crb[0], np.sqrt(np.mean(e[:, 1] ** 2)) / crb[1],
                     np.sqrt(np.mean(e[found, 2] ** 2)) / crb[2], int((~found).sum()), len(e))
    d = np.array(diff).reshape(-1, 3)
    out["median"], out["p90"] = np.median(d, axis=0), np.percentile(d, 90, axis=0)
    return out


def high_snr_row(p, speed_mps: float, rho_db: float, path: str, trials: int) -> dict:
    """The default chain (complex128: the migration fit beyond the alias) at high SNR, on the exact time-domain cube
    ("td": synthesize + range_doppler) or the range–Doppler synthesis ("rd"): range-rate RMSE and bias, range
    standard deviation and azimuth RMSE over their CRBs, point target at 50 m, 10°."""
    from radarnode.dsp.spectra import range_doppler
    from radarnode.radar.signal_model import synthesize
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    vmax = p.alias_speed_mps
    crb = np.array([float(equation.crb_range_m(p, rho_db)), float(equation.crb_speed_mps(p, rho_db)),
                    float(equation.crb_azimuth_rad(p, rho_db, math.radians(AZ_DEG)))])
    chain = DspChain(p)
    scat = point_targets([R0_M], [AZ_DEG], [speed_mps], 0.0)
    per_sample = rho_db - 10.0 * math.log10(n * m * c)
    errs = []
    for t in range(trials):
        rng = np.random.default_rng(4000 + t)
        rd = range_doppler(synthesize(p, scat, rng, snr_db=per_sample)) if path == "td" \
            else synthesize_rd(p, scat, rng, snr_db=per_sample)
        err = _nearest_error(chain.process_rd(rd), speed_mps, vmax)
        if err is not None:
            errs.append(err)
    e = np.array(errs).reshape(-1, 3) / crb
    return {"found": len(e), "rate": float(np.sqrt(np.mean(e[:, 1] ** 2))), "rate_bias": float(e[:, 1].mean()),
            "range": float(e[:, 0].std()), "az": float(np.sqrt(np.mean(e[:, 2] ** 2)))}


def frame_ms(ego_mps: float, frames: int, migration: bool, dtype) -> float:
    p, scats = highway_frames(ego_mps, frames)
    chain = DspChain(p, DspConfig(migration_fit=migration))
    rng = np.random.default_rng(1)
    return _median_ms(lambda s: chain.process_rd(synthesize_rd(p, s, rng, dtype=dtype)), scats)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--speeds", default="-70,-60,-50,-40,-32,0,50", help="radial speeds, m/s, comma-separated")
    ap.add_argument("--trials", type=int, default=200, help="noise draws per speed (default 200; 0: no table)")
    ap.add_argument("--frames", type=int, default=9, help="highway frames per ego speed for the cost (0: none)")
    ap.add_argument("--exact-trials", type=int, default=0, help="noise draws of the exact-template reference")
    ap.add_argument("--wrap-trials", type=int, default=60, help="noise draws a row of the wrap table (0: none)")
    ap.add_argument("--threshold-trials", type=int, default=60,
                    help="noise draws a row of the auto threshold table (0: none)")
    ap.add_argument("--high-snr-trials", type=int, default=30,
                    help="noise draws a row of the high-SNR table (0: none)")
    args = ap.parse_args()
    p = radar_config(load_scenario(ROOT / "scenarios" / "highway_mimo12.yaml")).preset
    speeds = [float(x) for x in args.speeds.split(",")]
    if args.trials:
        print(f"Point target, ρ = {RHO_DB:g} dB, {R0_M:g} m, {AZ_DEG:g}°, preset {p.name} (alias speed "
              f"{p.alias_speed_mps:.2f} m/s); {args.trials} trials a row; each figure over its CRB.\n")
        print("| radial speed | migration over the frame | detected | still fit: rate RMSE | range std "
              "| azimuth RMSE (wrap found) | wrap missed | migration fit: rate RMSE | range std "
              "| azimuth RMSE (wrap found) | wrap missed |")
        print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for v in speeds if args.trials else ():
        a, b = (chain_errors(p, v, args.trials, mig) for mig in (False, True))
        mu = abs(v) * p.integration_time_s / p.range_resolution_m
        print(f"| {v:g} m/s | {mu:.2f} bins | {a['found']}/{args.trials} | {a['rate']:.2f} | {a['range']:.2f} "
              f"| {a['az']:.2f} ({a['az_found']:.2f}) | {a['missed']} | {b['rate']:.2f} | {b['range']:.2f} "
              f"| {b['az']:.2f} ({b['az_found']:.2f}) | {b['missed']} |", flush=True)
    if args.wrap_trials:
        print(f"\nThe TDM wrap found (the angle within 2°), point target at 40 m, 10°, preset {p.name}, "
              f"{args.wrap_trials} trials a row (seeds 0 …); right / frames with a detection of it:\n")
        print("| radial speed | ρ | still fit | migration fit |")
        print("|---:|---:|---:|---:|")
        for factor, rho in ((-1.5, 17.0), (-1.5, 18.0), (-1.5, 19.0), (-1.5, 20.0), (-2.5, 20.0), (-3.0, 20.0),
                            (-4.0, 20.0), (2.2, 20.0)):
            a, b = (wrap_right(p, factor, rho, args.wrap_trials, mig) for mig in (False, True))
            print(f"| {factor:g} × v_alias | {rho:g} dB | {a[0]}/{a[1]} ({100 * a[0] / max(a[1], 1):.0f} %) "
                  f"| {b[0]}/{b[1]} ({100 * b[0] / max(b[1], 1):.0f} %) |", flush=True)
    if args.threshold_trials:
        from radarnode.radar.chain import MIGRATION_AUTO_MIN_BINS
        from radarnode.radar.presets import PRESETS
        m12 = PRESETS["mimo12"]
        half_bw = dataclasses.replace(m12, name="mimo12 at half bandwidth", bandwidth_hz=m12.bandwidth_hz / 2.0)
        print(f"\nWhere auto fits: {args.threshold_trials} trials a row (seeds 3000 …), ρ = {RHO_DB:g} dB, 50 m, "
              f"10°, complex128; auto fits a wrapped peak one of whose alias numbers migrates "
              f"≥ {MIGRATION_AUTO_MIN_BINS:g} bin. Still fit and migration fit: range std, range-rate RMSE, azimuth "
              "RMSE over the frames whose wrap was found, each over its CRB, (wrap missed / frames); "
              "|migration − still| over the CRB, median and 90th percentile per axis (range, rate, azimuth); "
              "auto: of the frames where the fits differ, how many equal the migration fit's / the still fit's:\n")
        print("| preset | radial speed | migration | still fit | migration fit | median \\|Δ\\| | p90 \\|Δ\\| | auto: fit / still |")
        print("|---|---:|---:|---|---|---|---|---:|")
        rows = [(PRESETS["ars408_like"], -36.0), (PRESETS["ars408_like"], -70.0)]
        rows += [(half_bw, -mu * half_bw.range_resolution_m / half_bw.integration_time_s) for mu in (0.3, 0.4, 0.5, 0.6)]
        for preset, v in rows:
            t = threshold_row(preset, v, args.threshold_trials)
            a, b = t[False], t[True]
            print(f"| {preset.name} | {v:.1f} m/s | {t['mu']:.2f} bins | {a[0]:.2f} / {a[1]:.2f} / {a[2]:.2f} "
                  f"({a[3]}/{a[4]}) | {b[0]:.2f} / {b[1]:.2f} / {b[2]:.2f} ({b[3]}/{b[4]}) "
                  f"| {' / '.join(f'{x:.2f}' for x in t['median'])} | {' / '.join(f'{x:.2f}' for x in t['p90'])} "
                  f"| {t['auto'][0]} / {t['auto'][1]} |", flush=True)
    if args.high_snr_trials:
        print(f"\nHigh SNR, the default chain (complex128), point target at 50 m, 10°, {args.high_snr_trials} trials a "
              "row (seeds 4000 …), time-domain cube (td) and range–Doppler synthesis (rd); each figure over its CRB:\n")
        print("| radial speed | ρ | path | detected | rate RMSE | rate bias | range std | azimuth RMSE |")
        print("|---:|---:|---|---:|---:|---:|---:|---:|")
        for v in (-70.0, -20.0, 50.0):
            for rho in (40.0, 50.0, 60.0):
                for path in ("td", "rd"):
                    h = high_snr_row(p, v, rho, path, args.high_snr_trials)
                    print(f"| {v:g} m/s | {rho:g} dB | {path} | {h['found']}/{args.high_snr_trials} | {h['rate']:.2f} "
                          f"| {h['rate_bias']:+.2f} | {h['range']:.2f} | {h['az']:.2f} |", flush=True)
    if args.frames:
        print(f"\nhighway_mimo12.yaml frame, synthesize_rd + process_rd, median of {args.frames} frames, "
              f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}:\n")
        print("| ego speed | complex64 | with migration_fit | ratio | complex128 | with migration_fit (its default) "
              "| ratio |")
        print("|---:|---:|---:|---:|---:|---:|---:|")
        for ego in (0.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0):
            t = [frame_ms(ego, args.frames, mig, dt) for dt in (np.complex64, np.complex128) for mig in (False, True)]
            print(f"| {ego:g} m/s | {t[0]:.1f} ms | {t[1]:.1f} ms | {t[1] / t[0]:.2f} | {t[2]:.1f} ms "
                  f"| {t[3]:.1f} ms | {t[3] / t[2]:.2f} |", flush=True)
    if args.exact_trials:
        print("\nThe exact-template reference (Nelder–Mead on the whole synthesis):\n")
        print("| radial speed | migration over the frame | chain detected | chain: rate RMSE/CRB "
              "| chain: range std/CRB | exact-migration fit: rate RMSE/CRB | exact-migration fit: range RMSE/CRB |")
        print("|---:|---:|---:|---:|---:|---:|---:|")
        for v in speeds:
            r = run(p, v, args.exact_trials)
            print(f"| {v:g} m/s | {r['mu']:.2f} bins | {r['found']}/{args.exact_trials} | {r['chain_v']:.2f} "
                  f"| {r['chain_r']:.2f} | {r['fit_v']:.2f} | {r['fit_r']:.2f} |", flush=True)


if __name__ == "__main__":
    main()
