"""Signal level: synthesis + processing time and accuracy at every ego speed, time domain against RD domain.

Scene: ``scenarios/highway_mimo12.yaml`` (mimo12, 12 channels × 256 chirps × 256
samples; at its own 25 m/s 240–290 scatterers a frame over its 5 s, 250–253 in these frames: cars, trucks,
guardrail posts moving at −ego speed, road clutter), scatterers built as the signal level builds them
(``scene_scatterers``), the ego speed set to each value of the table.

* Speed: per ego speed, per dtype, the median over ``--frames`` frames of
  ``synthesize`` + ``DspChain.process`` (time domain) and ``synthesize_rd`` +
  ``DspChain.process_rd`` (range–Doppler domain), and, measured in the same
  run, the floor: numpy's matrix product of the shape the old single-product
  synthesis had, (channel·chirp × scatterer)·(scatterer × sample), plus
  ``range_doppler`` of a cube of that size. The ratio column is row / floor.
* Accuracy: a point target at an integrated SNR ρ = 20 dB (the convention of
  ``radarnode.radar.equation.snr_db``: the matched filter over every sample,
  chirp and channel; per sample and channel that is ρ − 10·log10(N·M·C)),
  radial speed −(ego speed) like the guardrail posts, 50 m, 10° azimuth;
  ``--trials`` noise draws per path. Range error is against the truth at the
  frame's start (the chain takes coupling and migration out, with the speed it
  measured: beyond the alias speed that is the aliased one, hence −40 cm);
  range-rate error is wrapped to ±``alias_speed_mps`` (beyond it the speed
  aliases, as on the real radar). Bias, standard deviation and RMSE over the
  Cramér–Rao bound (``equation.crb_range_m``/``crb_speed_mps`` at ρ); misses
  are trials without a detection within the gate.

Run: ``.venv/bin/python benchmarks/signal_speed.py [--frames N] [--trials N] [--blas-threads N]
[--traffic scenario|relative] [--ego-lane 0-3]``. ``--ego-lane 3`` puts the ego in the fast lane, beside the left
guardrail: its posts pass 2.75 m from the sensor and the frame holds about twice the peaks (150–180).
``--traffic relative`` (the default since 2026-12-06): the other actors keep the places and relative speeds they
have at the scenario's 25 m/s at every faster ego speed, so that every row from 25 m/s on is the same highway frame
and only the ego's speed over ground (the posts' and the clutter's speed, their wrap and migration) changes.
``--traffic scenario`` keeps their speeds: from about 55 m/s on the ego drives into the lead car within the frames
(the scene has no collisions; the car's body is then around the sensor, 0.6–2.7 m away, and the frame holds about
twice the peaks), which is not a highway frame (:func:`highway_frames`).
OpenBLAS is limited to ``--blas-threads`` threads (default 1, set before numpy
is imported; ``default`` leaves OpenBLAS its own choice): on a shared two-core
machine its idle worker threads spin after every threaded product and take the
core the noise thread needs. Measured, median over the 12 speeds, 1 thread →
OpenBLAS's choice: RD path 39 → 40 ms (complex64), 41 → 50 ms (complex128);
time-domain path 96 → 109 ms (complex64); only the floor's single large
product gains (complex64 28 → 16 ms). Prints Markdown tables.
"""

from __future__ import annotations

import os
import sys


def _blas_threads(argv: list[str]) -> str:
    for i, a in enumerate(argv):
        if a == "--blas-threads" and i + 1 < len(argv):
            return argv[i + 1]
        if a.startswith("--blas-threads="):
            return a.split("=", 1)[1]
    return "1"


# before numpy is imported anywhere ("default": leave OpenBLAS to choose)
if _blas_threads(sys.argv) != "default":
    os.environ["OPENBLAS_NUM_THREADS"] = _blas_threads(sys.argv)

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import math  # noqa: E402
import statistics  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

import machine  # noqa: E402  (the day's machine speed, printed beside the figures)

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.dsp.spectra import range_doppler  # noqa: E402
from radarnode.radar import equation  # noqa: E402
from radarnode.radar.chain import DspChain  # noqa: E402
from radarnode.radar.scatterers import point_targets, scene_scatterers  # noqa: E402
from radarnode.radar.signal_model import num_range_samples, synthesize, synthesize_rd  # noqa: E402
from radarnode.radar.setup import load_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

EGO_SPEEDS_MPS = (0.0, 10.0, 20.0, 28.0, 28.6, 29.0, 30.0, 32.0, 40.0, 50.0, 60.0, 70.0)
DTYPES = (("complex64", np.complex64), ("complex128", np.complex128))
RHO_DB = 20.0
GATE_RANGE_M, GATE_RATE_MPS = 1.5, 1.0      # beyond v_max the chain's coupling correction shifts the range ~0.4 m


def highway_frames(ego_mps: float, frames: int, traffic: str = "scenario", ego_lane: int | None = None):
    """(preset, [Scatterers per frame]) of the highway scene at one ego speed.

    ``traffic``: ``"scenario"`` keeps the actors' speeds as the scenario gives them (21–31 m/s): an ego much faster
    than them closes on them within the frames (at 70 m/s the lead car's rear is 0.55 m from the sensor in the first
    frame and the ego overlaps it or has driven through it in the other four: the scene has no collisions);
    ``"relative"`` adds the ego's speed beyond the scenario's own (25 m/s) to every actor, so that the traffic keeps
    the places and relative speeds it has at 25 m/s and only the ego's speed over ground changes (rows at or below
    25 m/s the same as ``"scenario"``). ``ego_lane``: the ego's lane (0–3; default the scenario's, 1); in lane 3,
    the fast lane, the left guardrail's posts pass 2.75 m beside the sensor and the frame holds about twice the
    peaks (an independent tester's frame, 2026-12-06)."""
    if traffic not in ("scenario", "relative"):
        raise ValueError(f"traffic: value {traffic!r} is not allowed; expected 'scenario' or 'relative'")
    sc = load_scenario(ROOT / "scenarios" / "highway_mimo12.yaml")
    if ego_lane is not None:
        if not (isinstance(ego_lane, int) and 0 <= ego_lane < sc.road.lanes):
            raise ValueError(f"ego_lane: value {ego_lane!r} is not allowed; expected a lane 0…{sc.road.lanes - 1}")
        sc = dataclasses.replace(sc, road=dataclasses.replace(sc.road, ego_lane=ego_lane))
    if traffic == "relative":
        shift = max(0.0, ego_mps - sc.ego.speed_mps)
        sc = dataclasses.replace(sc, actors=tuple(dataclasses.replace(a, speed_mps=a.speed_mps + shift)
                                                  for a in sc.actors))
    sc = dataclasses.replace(sc, ego=dataclasses.replace(sc.ego, speed_mps=ego_mps))
    scene = Scene(sc)
    p = radar_config(sc).preset
    o = radar_config(sc).signal
    rng = np.random.default_rng(sc.seed)
    out = []
    for k in range(frames):
        t = 0.5 + k * sc.period_s
        out.append(scene_scatterers(scene, t, scene.view(t), p, p.max_range_m, o.scatterer_spacing_m, rng,
                                    o.clutter_density_per_m2, o.clutter_rcs_dbsm))
    return p, out


def _median_ms(fn, runs) -> float:
    fn(runs[0])                                   # warm-up: caches, allocator
    times = []
    for arg in runs:
        t0 = time.perf_counter()
        fn(arg)
        times.append(time.perf_counter() - t0)
    return 1e3 * statistics.median(times)


def floor_ms(p, k: int, dtype, reps: int = 7) -> float:
    """Old single product (C·M × K)·(K × N) plus range_doppler of a cube of that size, median."""
    rng = np.random.default_rng(0)
    c, m, n = p.num_virtual, p.num_chirps, num_range_samples(p)
    left = (rng.standard_normal((c * m, k)) + 1j * rng.standard_normal((c * m, k))).astype(dtype)
    right = (rng.standard_normal((k, n)) + 1j * rng.standard_normal((k, n))).astype(dtype)

    def run(_):
        cube = (left @ right).reshape(c, m, n)
        range_doppler(cube)
    return _median_ms(run, list(range(reps)))


def speed_table(frames: int, traffic: str = "relative", ego_lane: int | None = None) -> list[str]:
    """The speed table's Markdown lines. ``nearest``: the nearest actor's scatterer in any frame (not the posts' or
    the clutter's; an ego that drives into another car has one within a metre or two, the body around the sensor);
    ``peaks``: the median count of detections the RD path's chain reports a frame (complex128), which the frame's
    time follows more than the scatterers' count (the fits are per peak)."""
    lines = ["| ego speed | scatterers | nearest | peaks | dtype | floor: product + FFTs | time domain: synthesize + "
             "process | ratio | RD domain: synthesize_rd + process_rd | ratio |",
             "|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|"]
    for ego in EGO_SPEEDS_MPS:
        p, scats = highway_frames(ego, frames, traffic, ego_lane)
        chain = DspChain(p)
        k = int(statistics.median(len(s) for s in scats))
        nearest = min((float(s.range_m[s.actor_index >= 0].min()) for s in scats if np.any(s.actor_index >= 0)),
                      default=math.inf)
        peaks = int(statistics.median(len(chain.process_rd(synthesize_rd(p, s, np.random.default_rng(1))).range_m)
                                      for s in scats))
        for name, dt in DTYPES:
            rng = np.random.default_rng(1)
            fl = floor_ms(p, k, dt)
            td = _median_ms(lambda s: chain.process(synthesize(p, s, rng, dtype=dt)), scats)
            rd = _median_ms(lambda s: chain.process_rd(synthesize_rd(p, s, rng, dtype=dt)), scats)
            lines.append(f"| {ego:g} m/s | {k} | {nearest:.1f} m | {peaks} | {name} | {fl:.1f} ms | {td:.1f} ms | "
                         f"{td / fl:.2f} | {rd:.1f} ms | {rd / fl:.2f} |")
        print(lines[-2], lines[-1], sep="\n", file=sys.stderr, flush=True)
    return lines


def _errors(p, chain, path: str, v_mps: float, trials: int) -> np.ndarray:
    """(range error, wrapped range-rate error) of the detection nearest the truth, one row per trial; NaN when
    none lies within the gate (a miss: at ρ = 20 dB the chain detects the target in ~80 % of the frames)."""
    r0, az = 50.0, 10.0
    n, m, c = num_range_samples(p), p.num_chirps, p.num_virtual
    snr_sample = RHO_DB - 10.0 * math.log10(n * m * c)
    scat = point_targets([r0], [az], [v_mps], 0.0)
    vmax = p.alias_speed_mps                      # the chain's Doppler wraps at λ_c/(4T), λ_c at mid-sweep
    out = np.full((trials, 2), np.nan)
    for i in range(trials):
        rng = np.random.default_rng(1000 + i)
        if path == "td":
            det = chain.process(synthesize(p, scat, rng, snr_db=snr_sample))
        else:
            det = chain.process_rd(synthesize_rd(p, scat, rng, snr_db=snr_sample))
        if len(det):
            dv = (det.range_rate_mps - v_mps + vmax) % (2.0 * vmax) - vmax
            dr = det.range_m - r0
            cost = np.abs(dr) / GATE_RANGE_M + np.abs(dv) / GATE_RATE_MPS
            j = int(np.argmin(cost))
            if cost[j] <= 1.0:
                out[i] = dr[j], dv[j]
    return out


def accuracy_table(trials: int) -> list[str]:
    p = highway_frames(0.0, 1)[0]
    chain = DspChain(p)
    crb_r = float(equation.crb_range_m(p, RHO_DB))
    crb_v = float(equation.crb_speed_mps(p, RHO_DB))
    lines = [f"Point target, ρ = {RHO_DB:g} dB, 50 m, 10°, radial speed −(ego speed); {trials} trials a cell; "
             f"CRB: range {100 * crb_r:.2f} cm, range rate {100 * crb_v:.2f} cm/s.", "",
             "| radial speed | path | range bias | range std | range RMSE/CRB | rate bias | rate std "
             "| rate RMSE/CRB | missed |",
             "|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    for ego in EGO_SPEEDS_MPS:
        for path, label in (("td", "time domain"), ("rd", "RD domain")):
            e = _errors(p, chain, path, -ego, trials)
            ok = e[~np.isnan(e[:, 0])]
            bias, std = ok.mean(axis=0), ok.std(axis=0)
            rmse = np.sqrt(np.mean(ok ** 2, axis=0))
            lines.append(f"| {-ego:g} m/s | {label} | {100 * bias[0]:+.2f} cm | {100 * std[0]:.2f} cm "
                         f"| {rmse[0] / crb_r:.2f} | {100 * bias[1]:+.2f} cm/s | {100 * std[1]:.2f} cm/s "
                         f"| {rmse[1] / crb_v:.2f} | {trials - len(ok)} |")
        print(lines[-2], lines[-1], sep="\n", file=sys.stderr, flush=True)
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=5, help="frames per speed and path (median)")
    ap.add_argument("--trials", type=int, default=50, help="noise draws per speed and path (accuracy; 0: none)")
    ap.add_argument("--blas-threads", default="1",
                    help="OpenBLAS threads, set before numpy is imported ('default': OpenBLAS's own choice)")
    ap.add_argument("--traffic", choices=("scenario", "relative"), default="relative",
                    help="the other actors' speeds: the ego's speed beyond 25 m/s added to each (default), so that "
                    "every row from 25 m/s on is the scenario's own highway frame with only the ego's speed over "
                    "ground changed; or as the scenario gives them (an ego faster than ~55 m/s drives into the lead "
                    "car within the frames: the scene has no collisions) (highway_frames)")
    ap.add_argument("--ego-lane", type=int, choices=range(4), default=None, metavar="{0,1,2,3}",
                    help="the ego's lane (default the scenario's, 1; 3: the fast lane beside the left guardrail, "
                    "about twice the peaks a frame)")
    args = ap.parse_args()
    t0 = time.perf_counter()
    speed = speed_table(args.frames, args.traffic, args.ego_lane)
    acc = accuracy_table(args.trials) if args.trials > 0 else []
    lane = "the scenario's (1)" if args.ego_lane is None else str(args.ego_lane)
    print(f"## Signal level: synthesis + processing, highway_mimo12.yaml, median of {args.frames} frames, "
          f"traffic {args.traffic}, ego lane {lane}, "
          f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', 'unset')}\n")
    print(machine.line() + "\n")
    print("\n".join(speed))
    if acc:
        print("\n## Accuracy at every speed\n")
        print("\n".join(acc))
    print(f"\n(run time {time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
