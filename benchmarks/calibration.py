"""Calibration of the three fidelity levels against theory and against each other (issue 9, items 1 and 2).

SNR is defined once: ρ, the integrated SNR of :func:`radarnode.radar.equation.snr_db` (matched filter over
every sample, chirp and channel, no window, target on the bin centres); the Cramér–Rao bounds take the same ρ.

Prints Markdown tables:

1. false-alarm probability of the chain's CFAR on noise-only mimo12 cubes against the set value;
2. Pd against ρ for point targets, Swerling 0 and 1, level by level, with the exact theory (CA-CFAR on the
   non-coherent sum of 12 channels, straddle averaged) and theory at the trials that ran (each target's SNR and
   position in its cell in each frame, :class:`TrialTheory`): the ρ at Pd 0.5 and 0.9 of each;
2b. (``--only cells``) Pd of targets at a fixed position in their cell (on the bin centre, a quarter, half a bin
   in range, in Doppler, both), level by level, against the one-cell test the analytic levels draw from;
3. RMSE over the CRB of range, range rate and azimuth, and false alarms per frame, per level;
4. resolution: probability that two equal point targets come out as two, against their separation in range
   bins, Doppler bins and beamwidths, signal against detection level, and the 50 % point of each;
5. a weaker target behind a stronger one at another angle: how often each level reports it, against the range
   separation and the power ratio (the chain's range–Doppler peak test is blind to the angle);
6. the same in one beam, apart in range or in Doppler only;
7. the same behind several stronger returns in one cell, or beside a companion in its own cell;
8. the same near the map's first range bins, where the CA-CFAR ring is cut (ars408_like);
9. (``--only pairs``) two reflectors of one body within the resolution, inside one cell and astride a cell's edge,
   and a car's reflectors: how often each level sees them and the SNR and RCS it reports;
10. (``--only rcs``) two reflectors sharing one range–Doppler cell, apart in angle: each one's reported SNR against
   its own ρ and the cell's sum against the pair's;
11. (``--only posts``) guardrail posts on a straight road: the clusters each level reports a frame, by range band;
12. (``--only spacing``) the same with both rails against the posts' spacing, across the object level's 1.7-bin box
   and the windows' 2-bin main lobe, on ars408_like and mimo12, and at walking pace and motorway speed;
13. (``--only triples``) three equal reflectors in one range–Doppler cell, apart in angle, standing and beyond the
   alias speed: the frames in which a level reports a detection at none of their angles (a ghost);
14. (``--only abreast``) two returns at two angles (two cars abreast, one a little ahead) across a cell's edge,
   less than a bin to a bin and a half apart in range or in Doppler, equal or 6 dB apart: the detections each level
   reports a frame (the chain: one maximum of its channel-summed map and both angles in its snapshot up to about
   0.8 bins, one from 1.1);
15. (``--only layouts``) 70 random layouts of 2–5 point returns within two bins in range and Doppler at random
   angles and powers (ars408_like, mimo12, srr_corner; seed 4141, 16 frames each): the detection level's count a frame
   against the chain's, signed and absolute, by preset and over all;
16. (``--only secondary``) a weaker return in a stronger one's range–Doppler cell, 3 beamwidths apart, near the
   chain's angle-search thresholds (its second source within DOA_FLOOR_DB of the first and DOA_SECONDARY_SNR_DB above
   the beam noise): how often each level reports the weaker one;
17. (``--only neighbours``) accuracy beside a neighbour: two equal returns 2–6 bins apart at ρ = 30 dB and 6–24
   bins apart at 45 dB and 9–14 at 70–80 dB, a 25-dB return 12–26 bins from a 60-dB one, a 45-dB return 6–10 bins
   from a 55-dB one, rows of 3 and 4 equal returns: the resolved
   frames and the worst return's RMSE over its CRB, detection against signal level;
18. (``--only reading``) the RCS each level's clusters read of the point targets it detects, over the truth, from
   Pd ≈ 0.05 to 0.95, Swerling 0 and 1: the quartiles (a return detected near the threshold reads high: it faded
   up, or its noise took it over), and the Pd.
19. (``--only masked``, ``--preset``) the reading of a Swerling 1 return whose CA-CFAR ring holds a steady neighbour's
   energy I, at the statistic: the detection level's own law (``DetectionStatistic.draw`` with I, the position
   uniform in the cell, 400,000 draws) against ``DetectionStatistic.reading`` with the equivalent SNR loss the object
   level derives (``snr_of_pd`` of the Pd alone less that of the masked Pd): the masked Pd and the quartiles' offsets.

Run: ``python benchmarks/calibration.py [--quick] [--only PART] [--trials N]`` (about 12 minutes; ``--quick`` about 3).
"""

from __future__ import annotations

import argparse
import math
import shlex
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from radarnode.radar.chain import DspChain, DspConfig  # noqa: E402
from radarnode.dsp.spectra import noncoherent_power, range_doppler  # noqa: E402
from radarnode.radar import detection_model, equation  # noqa: E402
from radarnode.radar.models import make_model  # noqa: E402
from radarnode.radar.object_model import RuntimeConfig  # noqa: E402
from radarnode.radar.presets import PRESETS  # noqa: E402
from radarnode.radar.scatterers import actor_scatterers, point_targets, scene_scatterers  # noqa: E402
from radarnode.radar.signal_model import synthesize, synthesize_rd  # noqa: E402
from radarnode.radar.setup import parse_scenario, radar_config  # noqa: E402
from radarnode.scene.world import Scene  # noqa: E402

P = PRESETS["mimo12"]
LEVELS = ("object", "detection", "signal")
RESOLUTION_TRIALS = 40
PD_FRAMES: int | None = None        # --frames: frames per point of the Pd tables (None: 80, or 12 with --quick)
PD_SWERLING = (0, 1)
CELL_FRAMES = 100                   # frames per offset of the in-cell table (10 targets a frame)


def pfa_table(quick: bool) -> None:
    print("### False-alarm probability, noise-only mimo12 cubes (12 channels, Hann × Hann)\n")
    print("| CFAR | set Pfa | cells | false alarms | measured Pfa | measured / set |")
    print("|---|---:|---:|---:|---:|---:|")
    rows = [("ca", 1e-3, 1e7), ("ca", 1e-4, 1e7), ("ca", 1e-6, 1e7 if quick else 1e8), ("os", 1e-3, 2e6),
            ("os", 1e-4, 2e6 if quick else 1e7)]
    rng = np.random.default_rng(2026)
    c, m, n = P.num_virtual, P.num_chirps, P.num_samples
    for kind, pfa, want in rows:
        cfar = DspChain(P, DspConfig(cfar=kind, pfa=pfa)).cfar
        hits = cells = 0
        while cells < want:
            cube = (rng.standard_normal((c, m, n)) + 1j * rng.standard_normal((c, m, n))) * math.sqrt(0.5)
            hits += int(cfar(noncoherent_power(range_doppler(cube))).mask.sum())
            cells += m * n
        print(f"| {kind.upper()} | {pfa:.0e} | {cells:,} | {hits} | {hits / cells:.3e} | {hits / cells / pfa:.2f} |",
              flush=True)
    print()


def _in_view(r: float, az_deg: float) -> float:
    """``az_deg`` (within ±40°) scaled into the preset's sectors at range ``r`` — to within 2° of the edge of the
    widest sector that reaches 5 m past it — where it lies outside them; unchanged where every azimuth of the
    scene's lies inside (mimo12's every target). ``ars408_like``'s far sector, ±9° beyond 70 m, had left three of
    the ten targets out of view, and every Pd printed was 0.7× the targets' own (an independent tester's finding);
    scaled, not clamped: two targets clamped to one azimuth stood behind each other, the farther one hidden."""
    half = max((s.half_angle_deg for s in P.fov if r <= s.max_range_m - 5.0), default=None)
    if half is None or 40.0 <= half - 2.0:
        return az_deg
    return az_deg * (half - 2.0) / 40.0


def point_scene(rho_db: float, swerling: int, seed: int, n_targets: int = 10, rcs_fix: np.ndarray | None = None
                ) -> str:
    """Point targets at one integrated SNR, spread so that none shares a cell; Doppler offsets cover a bin.

    The RCS is set from the position relative to the ego's origin first, then corrected by what the
    sensor (mounted ahead of it) sees at t = 0 (``rcs_fix``, dB per target): see :func:`calibrated`.
    """
    rng = np.random.default_rng(seed)
    lines = []
    for k in range(n_targets):
        # 30–102 m and under 0.75 m/s: over a run a target drifts less than 2 m, 0.6 dB of SNR at 30 m;
        # the Doppler offsets still cover a bin
        r = 30.0 + 8.0 * k
        az = math.radians(_in_view(r, -40.0 + 80.0 * ((k * 7) % n_targets) / n_targets))
        v = (-2 + k % 5 + (k + 0.5) / n_targets) * P.speed_resolution_mps
        rcs = rho_db - float(equation.snr_db(P, r, 0.0, azimuth_rad=az))
        if rcs_fix is not None:
            rcs += float(rcs_fix[k])
        x, y = r * math.cos(az), r * math.sin(az)
        heading = math.degrees(math.atan2(y, x)) if v >= 0 else math.degrees(math.atan2(-y, -x))
        lines.append(f"  - {{id: p{k}, class: point, swerling: {swerling}, rcs_dbsm: {rcs:.3f}, x_m: {x:.3f}, "
                     f"y_m: {y:.3f}, speed_mps: {abs(v):.4f}, heading_deg: {heading:.3f}}}")
    del rng
    return f"""
name: calibration
duration_s: 30
seed: {seed}
radar: {{preset: {P.name}, output: clusters}}
ego: {{speed_mps: 0.0}}
road: {{lanes: 1, ego_lane: 0}}
actors:
""" + "\n".join(lines) + "\n"


def calibrated(rho_db: float, swerling: int, seed: int):
    """The point scene with every target at integrated SNR ``rho_db`` as the sensor sees it at t = 0."""
    sc = parse_scenario(point_scene(rho_db, swerling, seed))
    scene = Scene(sc)
    v = scene.view(0.0)
    fix = rho_db - equation.snr_db(P, v.range_m, scene.rcs_dbsm, azimuth_rad=v.azimuth_rad)
    return parse_scenario(point_scene(rho_db, swerling, seed, rcs_fix=fix))


#: at most this many frames of one scene: its targets drift less than 2 m (0.6 dB of SNR at 30 m) over them; more
#: frames are further runs of the scene, each with its own seed
RUN_FRAMES = 80


def run_points(level: str, rho_db: float, swerling: int, frames: int, seed: int) -> dict:
    hits = trials = false = 0
    err, energy = [], []
    for run in range(-(-frames // RUN_FRAMES)):
        n = min(RUN_FRAMES, frames - run * RUN_FRAMES)
        h, t, f, e, w = _run_points(level, rho_db, swerling, n, seed + 100_003 * run)
        hits, trials, false = hits + h, trials + t, false + f
        err += e
        energy.append(w)
    e = np.array(err) if err else np.zeros((0, 3))
    return {"pd": hits / trials, "fa": false / frames, "ratio": np.sqrt(np.mean(e ** 2, axis=0)) if len(e) else None,
            "energy_db": np.concatenate(energy)}


def _run_points(level: str, rho_db: float, swerling: int, frames: int, seed: int
                ) -> tuple[int, int, int, list, np.ndarray]:
    """One run of the point scene: hits, trials, false alarms, the hits' errors over the CRB and every trial's
    windowed energy in dB (:class:`TrialTheory`; the same for every level: it depends on the scene alone)."""
    sc = calibrated(rho_db, swerling, seed)
    scene = Scene(sc)
    model = make_model(level, scene, P, np.random.default_rng(seed), radar_config(sc).signal, clusters_wanted=True)
    cfg = RuntimeConfig(max_distance_m=P.max_range_m)
    hits = trials = false = 0
    err, energy = [], []
    for k in range(frames):
        _, view = model.step(k * sc.period_s, cfg)
        det = model.info.detections
        energy.append(_trial_energy_db(scene, view))
        tr, taz = view.range_m, view.azimuth_rad
        tvr = view.vx_mps * np.cos(taz) + view.vy_mps * np.sin(taz)
        used = np.zeros(len(det), dtype=bool)
        for i in range(scene.n):
            trials += 1
            d = (np.abs(det.range_m - tr[i]) / (1.5 * P.range_resolution_m)
                 + np.abs(det.range_rate_mps - tvr[i]) / (1.5 * P.speed_resolution_mps)
                 + np.abs(np.sin(det.azimuth_rad) - np.sin(taz[i])) / (2.0 * P.angular_resolution_rad))
            if d.size == 0 or d.min() > 1.0:
                continue
            j = int(np.argmin(d))
            used[j] = True
            hits += 1
            crb = (equation.crb_range_m(P, rho_db), equation.crb_speed_mps(P, rho_db),
                   equation.crb_azimuth_rad(P, rho_db, taz[i]))
            err.append(((det.range_m[j] - tr[i]) / crb[0], (det.range_rate_mps[j] - tvr[i]) / crb[1],
                        (det.azimuth_rad[j] - taz[i]) / crb[2]))
        false += int((~used).sum())
    return hits, trials, false, err, np.concatenate(energy)


def _trial_energy_db(scene: Scene, view) -> np.ndarray:
    """Each point target's windowed energy in this frame (dB over σ², summed over channels), as the analytic levels
    compute it from its scatterer: its integrated SNR where it is and its straddle where it sits in its cell."""
    stat = _statistic()
    scat = actor_scatterers(scene, view)
    if not np.array_equal(scat.actor_index, np.arange(scene.n)):
        raise RuntimeError("the Pd scene's point targets are expected to give one scatterer each")
    rho = 10.0 ** (equation.snr_db(P, scat.range_m, scat.rcs_dbsm, azimuth_rad=scat.azimuth_rad) / 10.0)
    rb, vb, _ = detection_model.apparent_positions(P, scat)
    return 10.0 * np.log10(stat.energy(rho, rb - np.rint(rb), vb - np.rint(vb)))


_STAT = []


def _statistic():
    """The mimo12 chain's detection statistic, made once."""
    if not _STAT:
        _STAT.append(DspChain(P).statistic)
    return _STAT[0]


def snr_at(pd: np.ndarray, grid: np.ndarray, target: float) -> float:
    """The ρ at which a (noisy, mostly increasing) Pd curve crosses ``target``: linear interpolation."""
    above = np.flatnonzero(pd >= target)
    if above.size == 0 or above[0] == 0:
        return float("nan")
    i = above[0]
    return float(grid[i - 1] + (target - pd[i - 1]) / (pd[i] - pd[i - 1]) * (grid[i] - grid[i - 1]))


def fitted_offset(stat, pd: np.ndarray, grid: np.ndarray, swerling: int, target: float, samples: int,
                  curve=None) -> tuple[float, float, int]:
    """The shift Δ (dB) that fits theory's Pd curve, pd_of_snr(ρ − Δ), best to a measured curve over its rows whose
    theoretical Pd is within 0.15 of ``target`` (and below 0.98, where a row tells little) and the two rows either side
    of it: weighted least
    squares with each row's binomial variance (``samples`` trials a row). Returns (Δ, its standard error, the
    number of rows used). Several rows at once: near Pd 0.9 a Swerling 1 curve rises about 0.02 per dB, so the
    crossing of one pair of rows (:func:`snr_at`) moves by about ±0.5 dB with 800 trials a row.

    ``curve(deltas, rows)``: the reference instead of theory's uniform curve, the Pd of the rows ``rows`` (indices
    into ``grid``) with every trial's SNR lowered by each of ``deltas`` (D,), shape (D, rows) (:class:`TrialTheory`).
    """
    if curve is None:
        def curve(deltas, rows):
            return stat.pd_of_snr(grid[rows][None, :] - np.asarray(deltas)[:, None], swerling)
    theory = curve(np.zeros(1), np.arange(grid.size))[0]
    use = (np.abs(theory - target) <= 0.15) & (theory < 0.98)
    above = np.flatnonzero(theory >= target)
    if above.size and above[0] > 0:                 # and always the two rows either side of the target
        use[above[0] - 1:above[0] + 1] = True
    if not use.any():
        return float("nan"), float("nan"), 0
    rows = np.flatnonzero(use)
    meas = pd[rows]
    d = 0.0
    for step, half in ((0.05, 4.0), (0.002, 0.06)):            # a coarse search, then a fine one around its best
        deltas = d + np.arange(-half, half + step / 2, step)
        t = curve(deltas, rows)
        var = np.maximum(t * (1.0 - t), 0.01) / samples
        d = float(deltas[int(np.argmin(np.sum((meas - t) ** 2 / var, axis=1)))])
    t3 = curve(np.array([d + 0.01, d - 0.01, d]), rows)
    slope, t = (t3[0] - t3[1]) / 0.02, t3[2]
    info = float(np.sum(slope ** 2 / (np.maximum(t * (1.0 - t), 0.01) / samples)))
    return d, (1.0 / math.sqrt(info) if info > 0.0 else float("inf")), int(use.sum())


class TrialTheory:
    """Theory at the trials a Pd table ran: each row's Pd as the mean, over its trials, of the exact Pd of the test
    for that trial's own windowed energy — the target's integrated SNR at its range and azimuth in that frame and
    its straddle at its position in its cell (the analytic levels' draws use the same energy). The targets of the
    Pd scene drift (their Doppler offsets need a speed) and sit where they sit in their range cells, so their SNR
    spreads about the row's ρ (about ±0.5 dB over a run of 80 frames) and their straddle is not a uniform average:
    theory's uniform curve at ρ is then not what those trials should give (the spread lowers Pd where the curve bends
    down, near 0.9). ``energies_db``: per row, the trials' windowed energies in dB."""

    def __init__(self, stat, swerling: int, energies_db: list[np.ndarray]) -> None:
        self.e_grid = np.arange(-40.0, 70.0001, 0.01)
        self.pd_e = stat.pd(10.0 ** (self.e_grid / 10.0), swerling)
        self.energies_db = energies_db

    def __call__(self, deltas, rows) -> np.ndarray:
        deltas = np.asarray(deltas, dtype=np.float64)
        return np.stack([np.interp(self.energies_db[j][None, :] - deltas[:, None], self.e_grid, self.pd_e).mean(axis=1)
                         for j in rows], axis=1)


def pd_tables(quick: bool) -> None:
    stat = DspChain(P).statistic
    frames = PD_FRAMES or (80 if not quick else 12)
    for swerling in PD_SWERLING:
        top = 24.0 if swerling == 0 else 32.0
        grid = np.arange(12.0, top + 0.01, 1.0) if not quick else np.arange(12.0, top + 0.01, 2.0)
        print(f"### Pd against integrated SNR ρ, point targets, Swerling {swerling} ({frames} frames × 10 targets "
              "per point)\n")
        print("| ρ dB | theory | theory, the trials | " + " | ".join(LEVELS) + " |")
        print("|---:|---:|---:|" + "---:|" * len(LEVELS))
        curves = {lv: [] for lv in LEVELS}
        energies = []
        for rho in grid:
            for lv in LEVELS:
                r = run_points(lv, float(rho), swerling, frames, seed=int(rho * 10) + swerling)
                curves[lv].append(r["pd"])
            energies.append(r["energy_db"])
            trials = TrialTheory(stat, swerling, energies)(np.zeros(1), [len(energies) - 1])[0, 0]
            print(f"| {rho:.0f} | {float(stat.pd_of_snr(rho, swerling)):.3f} | {trials:.3f} | "
                  + " | ".join(f"{curves[lv][-1]:.3f}" for lv in LEVELS) + " |", flush=True)
        reference = TrialTheory(stat, swerling, energies)
        spread = np.concatenate([e - e.mean() for e in energies])
        print(f"\n(the trials' windowed energy about its row's mean: standard deviation {spread.std():.2f} dB)")
        fine = np.arange(0.0, 40.0, 0.01)
        theory = stat.pd_of_snr(fine, swerling)
        print("\n| Pd | theory ρ | " + " | ".join(f"{lv} ρ (Δ)" for lv in LEVELS) + " | "
              + " | ".join(f"{lv}: fitted Δ ± SE" for lv in LEVELS) + " | "
              + " | ".join(f"{lv}: Δ ± SE against the trials' theory" for lv in LEVELS) + " |")
        print("|---:|---:|" + "---:|" * (3 * len(LEVELS)))
        for target in (0.5, 0.9):
            t = snr_at(theory, fine, target)
            cells, fits, own = [], [], []
            for lv in LEVELS:
                s = snr_at(np.array(curves[lv]), grid, target)
                cells.append(f"{s:.2f} dB ({s - t:+.2f})")
                d, se, rows = fitted_offset(stat, np.array(curves[lv]), grid, swerling, target, frames * 10)
                fits.append(f"{d:+.2f} ± {se:.2f} dB ({rows} rows)")
                d, se, rows = fitted_offset(stat, np.array(curves[lv]), grid, swerling, target, frames * 10,
                                            curve=reference)
                own.append(f"{d:+.2f} ± {se:.2f} dB ({rows} rows)")
            print(f"| {target} | {t:.2f} dB | " + " | ".join(cells) + " | " + " | ".join(fits) + " | "
                  + " | ".join(own) + " |")
        print()


def _cell_scene(offset_range: float, offset_doppler: float, rho_db: float, seed: int, n: int = 10):
    """Ten Swerling 0 point targets (31–102 m, ±40°) at integrated SNR ``rho_db``, each at ``offset_range`` range
    bins and ``offset_doppler`` Doppler bins from its cell's centre at t = 0 (receding at that many Doppler bins;
    the range offset includes the range–Doppler coupling the chain sees): the scene and its targets' scatterers."""
    res, v = P.range_resolution_m, offset_doppler * P.doppler_bin_mps
    az = np.radians(-40.0 + 80.0 * ((np.arange(n) * 7) % n) / n)
    want = (70 + 18 * np.arange(n) + offset_range) * res - v * P.range_rate_coupling_s

    def scene_of(x, y, rcs):
        lines = [f"  - {{id: p{k}, class: point, swerling: 0, rcs_dbsm: {rcs[k]:.6f}, x_m: {x[k]:.6f}, "
                 f"y_m: {y[k]:.6f}, speed_mps: {v:.6f}, heading_deg: {math.degrees(math.atan2(y[k], x[k])):.6f}}}"
                 for k in range(n)]
        sc = parse_scenario(f"name: cells\nduration_s: 1\nseed: {seed}\nradar: {{preset: mimo12, output: clusters}}\n"
                            "ego: {speed_mps: 0.0}\nroad: {lanes: 1, ego_lane: 0}\nactors:\n" + "\n".join(lines))
        return sc, Scene(sc)

    x, y = want * np.cos(az), want * np.sin(az)
    _, scene = scene_of(x, y, np.zeros(n))
    view = scene.view(0.0)           # along each line of sight from the sensor (mounted ahead of the ego's origin)
    x, y = x + (want - view.range_m) * np.cos(view.azimuth_rad), y + (want - view.range_m) * np.sin(view.azimuth_rad)
    _, scene = scene_of(x, y, np.zeros(n))
    view = scene.view(0.0)
    return scene_of(x, y, rho_db - equation.snr_db(P, view.range_m, np.zeros(n), azimuth_rad=view.azimuth_rad))


def cells_table(quick: bool) -> None:
    """Pd of targets at a fixed position in their cell, level by level, against the one-cell test the analytic
    levels draw from (the target's energy with its straddle, in its nearest cell alone)."""
    stat = DspChain(P).statistic
    frames = 30 if quick else CELL_FRAMES
    rho = 19.0
    print(f"### Pd at a fixed position in the cell, Swerling 0, ρ = {rho:.0f} dB ({frames} frames × 10 targets, "
          "one frame a scene)\n")
    print("| offset (range, Doppler bins) | one cell | " + " | ".join(LEVELS) + " |")
    print("|---|---:|" + "---:|" * len(LEVELS))
    for off in ((0.0, 0.0), (0.25, 0.25), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)):
        expected, hits = [], {lv: 0 for lv in LEVELS}
        trials = 0
        for f in range(frames):
            sc, scene = _cell_scene(off[0], off[1], rho, 5000 + f)
            view = scene.view(0.0)
            expected.append(stat.pd(10.0 ** (_trial_energy_db(scene, view) / 10.0), 0))
            trials += scene.n
            for lv in LEVELS:
                model = make_model(lv, scene, P, np.random.default_rng(5000 + f), radar_config(sc).signal,
                                   clusters_wanted=True)
                _, v = model.step(0.0, RuntimeConfig(max_distance_m=P.max_range_m))
                det = model.info.detections
                tvr = v.vx_mps * np.cos(v.azimuth_rad) + v.vy_mps * np.sin(v.azimuth_rad)
                for i in range(scene.n):
                    d = (np.abs(det.range_m - v.range_m[i]) / (1.5 * P.range_resolution_m)
                         + np.abs(det.range_rate_mps - tvr[i]) / (1.5 * P.speed_resolution_mps)
                         + np.abs(np.sin(det.azimuth_rad) - np.sin(v.azimuth_rad[i])) / (2.0 * P.angular_resolution_rad))
                    hits[lv] += int(d.size > 0 and d.min() <= 1.0)
        se = lambda p: math.sqrt(max(p * (1.0 - p), 1e-12) / trials)  # noqa: E731
        print(f"| {off[0]:g}, {off[1]:g} | {np.concatenate(expected).mean():.3f} | "
              + " | ".join(f"{hits[lv] / trials:.3f} ± {se(hits[lv] / trials):.3f}" for lv in LEVELS) + " |",
              flush=True)
    print()


def accuracy_table(quick: bool) -> None:
    frames = 40 if not quick else 15
    print(f"### RMSE over the Cramér–Rao bound and false alarms, point targets, Swerling 0 ({frames} frames × 10)\n")
    print("| ρ | level | Pd | range RMSE/CRB | range-rate RMSE/CRB | azimuth RMSE/CRB | false alarms/frame |")
    print("|---:|---|---:|---:|---:|---:|---:|")
    for rho in (20.0, 30.0):
        for lv in LEVELS:
            a = run_points(lv, rho, 0, frames, seed=77)
            r = a["ratio"]
            print(f"| {rho:.0f} dB | {lv} | {a['pd']:.3f} | {r[0]:.2f} | {r[1]:.2f} | {r[2]:.2f} | {a['fa']:.2f} |",
                  flush=True)
    print()


def resolved(det, axis: str, sep: float, t0: tuple, t1: tuple) -> bool:
    """Two targets resolved: each has its own detection, within half the separation along ``axis`` and one
    cell along the others."""
    scale = np.array([P.range_resolution_m, P.speed_resolution_mps, P.angular_resolution_rad])
    pos = np.stack([det.range_m, det.range_rate_mps, np.sin(det.azimuth_rad)], axis=1) / scale
    tol = np.ones(3)
    tol[("range", "doppler", "angle").index(axis)] = sep / 2
    picks = []
    for t in (t0, t1):
        d = np.abs(pos - np.array(t) / scale)
        ok = np.flatnonzero(np.all(d <= tol, axis=1))
        if ok.size == 0:
            return False
        picks.append(ok[np.argmin(d[ok].sum(axis=1))])
    return picks[0] != picks[1]


def resolution_table(quick: bool) -> None:
    trials = RESOLUTION_TRIALS if not quick else 15
    chain = DspChain(P)
    stat = chain.statistic
    rho = 30.0
    seps = np.arange(0.25, 4.01, 0.25)
    print(f"### Resolution: two equal point targets at ρ = {rho:.0f} dB, random phases ({trials} trials per point)\n")
    print("| separation | range: signal | range: detection | Doppler: signal | Doppler: detection | "
          "angle: signal | angle: detection |")
    print("|---:|---:|---:|---:|---:|---:|---:|")
    curves = {}
    for axis in ("range", "doppler", "angle"):
        for lv in ("signal", "detection"):
            curves[(axis, lv)] = []
    for si, s in enumerate(seps):
        row = []
        for ai, axis in enumerate(("range", "doppler", "angle")):
            for li, lv in enumerate(("signal", "detection")):
                ok = 0
                for t in range(trials):
                    # the same pair of targets for both levels (a paired comparison), and each level's own noise
                    # stream: a change of one level's draws leaves the other's column as it was
                    geo = np.random.default_rng((99, si, ai, t))
                    rng = np.random.default_rng((99, si, ai, t, li))
                    r0 = geo.uniform(30, 80)
                    v0 = geo.uniform(-10, 10)
                    a0 = geo.uniform(-0.2, 0.2)           # sinθ
                    r1, v1, a1 = r0, v0, a0
                    if axis == "range":
                        r1 = r0 + s * P.range_resolution_m
                    elif axis == "doppler":
                        v1 = v0 + s * P.speed_resolution_mps
                    else:
                        a1 = a0 + s * P.angular_resolution_rad
                    az = np.degrees(np.arcsin([a0, a1]))
                    rcs = [rho - float(equation.snr_db(P, r, 0.0, azimuth_rad=math.radians(a)))
                           for r, a in zip((r0, r1), az)]
                    scat = point_targets([r0, r1], az, [v0, v1], rcs)
                    if lv == "signal":
                        det = chain.process(synthesize(P, scat, rng))
                    else:
                        det = detection_model.detect(P, scat, rng, stat)
                    ok += resolved(det, axis, s, (r0, v0, a0), (r1, v1, a1))
                curves[(axis, lv)].append(ok / trials)
                row.append(f"{ok / trials:.2f}")
        unit = "bins / beamwidths"
        print(f"| {s:.2f} {unit} | " + " | ".join(row) + " |", flush=True)
    print("\n| axis | 50 % point, signal | 50 % point, detection | difference |")
    print("|---|---:|---:|---:|")
    for axis in ("range", "doppler", "angle"):
        a = snr_at(np.array(curves[(axis, "signal")]), seps, 0.5)
        b = snr_at(np.array(curves[(axis, "detection")]), seps, 0.5)
        print(f"| {axis} | {a:.2f} | {b:.2f} | {b - a:+.2f} |")
    print()


def _weak_seen(preset, chain, ranges, az_deg, rho_db, seed: int) -> dict:
    """Whether the signal and detection levels report the second of two point targets (same speed, 0.3 m/s),
    within 2 range bins and 6° of it; the targets at ``ranges`` (m), ``az_deg`` and integrated SNR ``rho_db``."""
    scat = point_targets(list(ranges), list(az_deg), [0.3, 0.3])
    scat.rcs_dbsm = np.asarray(rho_db, dtype=np.float64) - equation.snr_db(preset, scat.range_m, 0.0, 0.0,
                                                                          scat.azimuth_rad)
    out = {}
    for lv in ("signal", "detection"):
        rng = np.random.default_rng(seed)
        det = chain.process_rd(synthesize_rd(preset, scat, rng)) if lv == "signal" \
            else detection_model.detect(preset, scat, rng, chain.statistic)
        out[lv] = bool(np.any((np.abs(det.range_m - ranges[1]) < 2.0 * preset.range_resolution_m)
                              & (np.abs(det.azimuth_rad - math.radians(az_deg[1])) < math.radians(6.0))))
    return out


def _fractions(trials: int, seen) -> str:
    """"signal / detection": the fraction of trials 0…trials−1 in which ``seen(t)`` says each level reports it."""
    hits = {"signal": 0, "detection": 0}
    for t in range(trials):
        out = seen(t)
        for lv in hits:
            hits[lv] += out[lv]
    return f"{hits['signal'] / trials:.2f} / {hits['detection'] / trials:.2f}"


def _beam_seen(chain, axis: str, sep: float, ratio: float, seed: int) -> dict:
    """Whether the signal and detection levels report the weaker of two boresight targets (ρ 50 and 50 − ratio dB)
    ``sep`` bins apart along ``axis`` ("range" or "Doppler"): within half a bin along it, a bin along the other."""
    rng0 = np.random.default_rng(seed)
    r0 = (40.0 + rng0.random()) * P.range_resolution_m
    v0 = (3.0 + rng0.random()) * P.doppler_bin_mps
    r, v = [r0, r0], [v0, v0]
    if axis == "range":
        r[1] += sep * P.range_resolution_m
    else:
        v[1] += sep * P.doppler_bin_mps
    scat = point_targets(r, [0.0, 0.0], v)
    scat.rcs_dbsm = np.array([50.0, 50.0 - ratio]) - equation.snr_db(P, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    tol_r = (0.5 if axis == "range" else 1.0) * P.range_resolution_m
    tol_v = (0.5 if axis == "Doppler" else 1.0) * P.doppler_bin_mps
    out = {}
    for lv in ("signal", "detection"):
        rng = np.random.default_rng(seed)
        det = chain.process_rd(synthesize_rd(P, scat, rng)) if lv == "signal" \
            else detection_model.detect(P, scat, rng, chain.statistic)
        out[lv] = bool(np.any((np.abs(det.range_m - r[1]) < tol_r) & (np.abs(det.range_rate_mps - v[1]) < tol_v)
                              & (np.abs(det.azimuth_rad) < math.radians(6.0))))
    return out


def lobe_table(quick: bool) -> None:
    trials = 40 if not quick else 15
    chain = DspChain(P)
    seps = (1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.5)
    ratios = (6.0, 12.0, 20.0)
    print(f"### A weaker target behind a stronger one at another angle ({trials} trials per point)\n")
    print("mimo12; the stronger at ρ = 60 dB and −20°, the weaker 40° away at +20°, the same speed, the range "
          "offset random within a bin; the fraction of frames in which each level reports the weaker one, "
          "signal / detection\n")
    print("| separation (range bins) | " + " | ".join(f"{r:.0f} dB weaker" for r in ratios) + " |")
    print("|---:|" + "---:|" * len(ratios))
    for sep in seps:
        row = []
        for ratio in ratios:
            def seen(t, sep=sep, ratio=ratio):
                base = 40.0 + np.random.default_rng(100 + t).random()
                return _weak_seen(P, chain, (base * P.range_resolution_m, (base + sep) * P.range_resolution_m),
                                  (-20.0, 20.0), (60.0, 60.0 - ratio), 5000 + t)
            row.append(_fractions(trials, seen))
        print(f"| {sep:.1f} | " + " | ".join(row) + " |", flush=True)
    print()


def beam_table(quick: bool) -> None:
    trials = 40 if not quick else 15
    chain = DspChain(P)
    seps = (1.5, 1.75, 2.0, 2.25, 2.5, 3.0)
    ratios = (0.0, 3.0, 6.0, 12.0, 20.0)
    print(f"### A weaker target in a stronger one's lobe, in the same beam ({trials} trials per point)\n")
    print("mimo12; the stronger at ρ = 50 dB, the weaker at the same angle (boresight), apart in range or in Doppler "
          "only, both positions random within a bin; the fraction of frames in which each level reports the "
          "weaker one (within half a bin along the axis, a bin along the other, 6° in angle), signal / detection\n")
    for axis in ("range", "Doppler"):
        print(f"| {axis} separation (bins) | " + " | ".join(f"{q:.0f} dB weaker" for q in ratios) + " |")
        print("|---:|" + "---:|" * len(ratios))
        for sep in seps:
            row = []
            for ratio in ratios:
                row.append(_fractions(trials, lambda t, sep=sep, ratio=ratio, axis=axis:
                                      _beam_seen(chain, axis, sep, ratio, 7000 + t)))
            print(f"| {sep:.2f} | " + " | ".join(row) + " |", flush=True)
        print()


def _crowd_seen(chain, config: str, ratio: float, seed: int) -> dict:
    """Whether each level reports a weak target at boresight, 2 range bins behind stronger returns at ρ 60 dB (the
    weak one ``ratio`` dB below), all at one speed: ``config`` "one" (a stronger one at −30°), "two" (at ±30°, one
    cell), "three" (at −45°, −25° and +30°, one cell), "companion" (one at −30°, and a return as strong as the weak
    one at +30° in the weak one's cell)."""
    base = 40.0 + np.random.default_rng(seed).random()
    rs, w = 60.0, 60.0 - ratio
    r, az, rho = {"one": ([base], [-30.0], [rs]), "two": ([base] * 2, [-30.0, 30.0], [rs] * 2),
                  "three": ([base] * 3, [-45.0, -25.0, 30.0], [rs] * 3),
                  "companion": ([base, base + 2.0], [-30.0, 30.0], [rs, w])}[config]
    r, az, rho = list(r) + [base + 2.0], list(az) + [0.0], list(rho) + [w]
    v = 3.4 * P.doppler_bin_mps
    scat = point_targets([x * P.range_resolution_m for x in r], az, [v] * len(r))
    scat.rcs_dbsm = np.array(rho) - equation.snr_db(P, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
    out = {}
    for lv in ("signal", "detection"):
        rng = np.random.default_rng(seed)
        det = chain.process_rd(synthesize_rd(P, scat, rng)) if lv == "signal" \
            else detection_model.detect(P, scat, rng, chain.statistic)
        out[lv] = bool(np.any((np.abs(det.range_m - scat.range_m[-1]) < P.range_resolution_m)
                              & (np.abs(det.range_rate_mps - v) < P.doppler_bin_mps)
                              & (np.abs(det.azimuth_rad) < math.radians(6.0))))
    return out


def crowd_table(quick: bool) -> None:
    trials = 40 if not quick else 15
    chain = DspChain(P)
    ratios = (3.0, 6.0, 9.0)
    configs = ("one", "two", "three", "companion")
    print(f"### A weaker target behind several stronger returns in one cell ({trials} trials per point)\n")
    print("mimo12; a target at boresight 2 range bins behind stronger returns at ρ = 60 dB and other angles, the same "
          "speed: one at −30°; two at ±30°; three at −45°, −25° and +30° (their range–Doppler cell is one); one at −30° "
          "and a companion as strong as the weak target at +30° in the weak target's cell; the fraction of frames in "
          "which each level reports the weak target, signal / detection\n")
    print("| weaker by | " + " | ".join(configs) + " |")
    print("|---:|" + "---:|" * len(configs))
    for ratio in ratios:
        row = [_fractions(trials, lambda t, c=c, ratio=ratio: _crowd_seen(chain, c, ratio, 100 + t)) for c in configs]
        print(f"| {ratio:.0f} dB | " + " | ".join(row) + " |", flush=True)
    print()


def edge_table(quick: bool) -> None:
    trials = 40 if not quick else 15
    p = PRESETS["ars408_like"]
    chain = DspChain(p)
    reach = chain.statistic.cfar.guard[1] + chain.statistic.cfar.train[1]
    print(f"### Masking where the CA-CFAR ring is cut by the first range bins ({trials} trials per point)\n")
    print(f"ars408_like (the ring reaches {reach} range bins); a 40 dB target 3 range bins behind a stronger one "
          "20° away, the same speed; the fraction of frames in which each level reports the weaker one, "
          "signal / detection\n")
    strong = (54.0, 55.0, 56.0, 57.0)
    print("| stronger target at range bin | " + " | ".join(f"{s:.0f} dB" for s in strong) + " |")
    print("|---:|" + "---:|" * len(strong))
    for base in (1.3, 4.3, 60.3):
        row = []
        for rs in strong:
            row.append(_fractions(trials, lambda t, base=base, rs=rs: _weak_seen(
                p, chain, (base * p.range_resolution_m, (base + 3.0) * p.range_resolution_m), (-20.0, 0.0),
                (rs, 40.0), 9000 + t)))
        print(f"| {base:.1f} | " + " | ".join(row) + " |", flush=True)
    print()


def _pair(p, axis: str, sep: float, centre: float, r0: float, v0: float):
    """Two equal reflectors of one body ``sep`` cells apart about ``centre`` cells from a cell's centre, along the
    range or Doppler bins or the beams (d·sinθ in 1/N); the others' at (r0, v0, boresight)."""
    off = np.array([centre - sep / 2, centre + sep / 2])
    if axis == "range":
        s = point_targets(r0 + off * p.range_resolution_m, 0.0, np.full(2, v0), 0.0)
    elif axis == "Doppler":       # the chain's peak sits at the coupled range: keep it on the range bin
        s = point_targets(r0 - off * p.doppler_bin_mps * p.range_rate_coupling_s, 0.0, v0 + off * p.doppler_bin_mps,
                          0.0)
    else:
        s = point_targets(np.full(2, r0), np.degrees(np.arcsin(off / p.num_virtual / p.element_spacing_wl)),
                          np.full(2, v0), 0.0)
    s.actor_index = np.zeros(2, dtype=np.int64)
    return s


def _pair_seen(level: str, p, chain, scat, snr: float, frames: int, seed: int, r_c: float, v_c: float):
    """Fraction of frames with a detection within 2 range and 2 Doppler bins of (r_c, v_c), and the strongest such
    detection's SNR (mean, sd)."""
    rng = np.random.default_rng(seed)
    got = []
    for _ in range(frames):
        det = (detection_model.detect(p, scat, rng, chain.statistic, snr_db=snr) if level == "detection"
               else chain.process_rd(synthesize_rd(p, scat, rng, snr_db=snr)))
        ok = (np.abs(det.range_m - r_c) < 2 * p.range_resolution_m) & (np.abs(det.range_rate_mps - v_c)
                                                                        < 2 * p.doppler_bin_mps)
        got.append(det.snr_db[ok].max() if ok.any() else np.nan)
    got = np.array(got)
    seen = got[np.isfinite(got)]
    return seen.size / frames, (seen.mean(), seen.std()) if seen.size else (np.nan, np.nan)


def pairs_table(quick: bool) -> None:
    frames = {"detection": 1200 if not quick else 300, "signal": 300 if not quick else 60}
    print(f"### Two reflectors of one body within the resolution ({frames['detection']} frames at the detection level, "
          f"{frames['signal']} at the signal level)\n")
    print("Two equal point reflectors of one body (random phases each frame), their power sum ρ dB above the "
          "CA-CFAR threshold's mean; 'centre' is where their middle sits from a cell's centre (0.5: astride the "
          "edge), in range or Doppler bins or beamwidths; Pd: frames with a detection within 2 range and 2 Doppler "
          "bins; SNR: the strongest such detection's, mean (sd), dB\n")
    print("| preset | axis | apart | centre | ρ over threshold | Pd detection | Pd signal | SNR detection | "
          "SNR signal |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    cases = [("ars408_like", axis, sep, centre, 4.0) for axis in ("range", "Doppler", "angle")
             for sep, centre in ((0.1, 0.0), (0.1, 0.5), (0.3, 0.5))]
    cases += [("ars408_like", "range", 0.5, 0.0, 10.0)]
    cases += [("mimo12", "range", sep, centre, 10.0) for sep, centre in ((1.0, 0.0), (1.0, 0.5), (1.5, 0.0))]
    for name, axis, sep, centre, margin in cases:
        p = PRESETS[name]
        chain = DspChain(p)
        stat = chain.statistic
        threshold_db = 10 * math.log10(stat.threshold_mean() / stat.window_gain)
        snr = threshold_db + margin - 3.0 - 10 * math.log10(p.num_range_bins * p.num_chirps * p.num_virtual)
        v0 = 10 * p.doppler_bin_mps
        r0 = 17 * p.range_resolution_m - v0 * p.range_rate_coupling_s
        scat = _pair(p, axis, sep, centre, r0, v0)
        r_c = r0 + (centre * p.range_resolution_m if axis == "range" else 0.0)
        v_c = v0 + (centre * p.doppler_bin_mps if axis == "Doppler" else 0.0)
        out = {lv: _pair_seen(lv, p, chain, scat, snr, frames[lv], 11, r_c, v_c) for lv in ("detection", "signal")}
        print(f"| {name} | {axis} | {sep:.1f} | {centre:.1f} | {margin:.0f} dB | {out['detection'][0]:.3f} | "
              f"{out['signal'][0]:.3f} | {out['detection'][1][0]:.2f} ({out['detection'][1][1]:.2f}) | "
              f"{out['signal'][1][0]:.2f} ({out['signal'][1][1]:.2f}) |", flush=True)
    print()
    bodies_table(quick)


def rcs_table(quick: bool) -> None:
    """Two steady reflectors at one range and speed, apart in angle (one range–Doppler cell, two angle peaks): the
    SNR each level reports for each against its own ρ, and the power sum of the cell's detections against the
    pair's (the peaks share the cell's energy in proportion to their powers)."""
    frames = {"detection": 120 if not quick else 30, "signal": 60 if not quick else 15}
    print(f"### Reflectors sharing one range–Doppler cell ({frames['detection']} frames at the detection level, "
          f"{frames['signal']} at the signal level)\n")
    print("Two steady point reflectors at one range and speed, `apart` beamwidths (1/N in d·sinθ) about boresight; "
          "the stronger at ρ 30 dB, the other `ratio` dB below; random phases each frame. Reported SNR minus the "
          "reflector's own ρ (median over the frames in which the cell gave exactly two detections, dB), and the "
          "power sum of those two minus the pair's (mean in power, dB); 'found': frames with exactly two\n")
    print("| preset | apart | ratio | level | found | stronger | weaker | sum |")
    print("|---|---:|---:|---|---:|---:|---:|---:|")
    cases = [("ars408_like", sep, ratio) for sep in (1.5, 2.0, 3.0) for ratio in (0.0, 3.0, 6.0)]
    cases += [("mimo12", 2.0, 0.0), ("mimo12", 2.0, 6.0), ("srr_corner", 2.0, 0.0), ("srr_corner", 2.0, 6.0)]
    for name, sep, ratio in cases:
        p = PRESETS[name]
        chain = DspChain(p)
        v0 = 10 * p.doppler_bin_mps
        r0 = 17 * p.range_resolution_m - v0 * p.range_rate_coupling_s
        az = np.degrees(np.arcsin(np.array([-sep / 2, sep / 2]) / p.num_virtual / p.element_spacing_wl))
        rho = np.array([30.0, 30.0 - ratio])
        rcs = rho - equation.snr_db(p, np.full(2, r0), np.zeros(2), 0.0, np.radians(az))
        scat = point_targets(np.full(2, r0), az, np.full(2, v0), rcs)
        scat.actor_index = np.zeros(2, dtype=np.int64)
        want_sum = 10 * np.log10(np.sum(10 ** (rho / 10)))
        for level in ("detection", "signal"):
            rng = np.random.default_rng(5)
            strong, weak, total = [], [], []
            for _ in range(frames[level]):
                det = (detection_model.detect(p, scat, rng, chain.statistic) if level == "detection"
                       else chain.process_rd(synthesize_rd(p, scat, rng)))
                near = (np.abs(det.range_m - r0) < 2 * p.range_resolution_m) & (np.abs(det.range_rate_mps - v0)
                                                                                  < 2 * p.doppler_bin_mps)
                if np.count_nonzero(near) != 2:
                    continue
                a = det.azimuth_rad[near]
                snr = det.snr_db[near][np.argsort(a)]          # the reflector at −θ first, as ``az``
                strong.append(snr[0] - rho[0])
                weak.append(snr[1] - rho[1])
                total.append(np.sum(10 ** (snr / 10)))
            found = len(total) / frames[level]
            cell = (f"{np.median(strong):+.2f} | {np.median(weak):+.2f} | "
                    f"{10 * np.log10(np.mean(total)) - want_sum:+.2f}") if total else "- | - | -"
            print(f"| {name} | {sep:.1f} | {ratio:.0f} dB | {level} | {found:.2f} | {cell} |", flush=True)
    print()


def posts_table(quick: bool) -> None:
    """Guardrail posts (2 m apart, −5 dBsm) on a straight road at 25 m/s: the clusters each level reports a frame, by
    range band, with one guardrail and with both."""
    frames = 30 if quick else 120
    bands = ((0.0, 70.0), (70.0, 150.0), (150.0, 250.0))
    print(f"### Guardrail posts: clusters a frame at each level ({frames} frames a row, seeds 1–2)\n")
    print("A straight three-lane road, the ego in the middle lane at 25 m/s, ars408_like; guardrails 1 m beyond the "
          "left edge (one) or both edges, posts 2 m apart (1.1 range bins) at −5 dBsm, Swerling 1; no other actor. "
          "Clusters a frame (mean) in each range band: what the cluster list carries\n")
    print("| guardrails | level | " + " | ".join(f"{a:.0f}–{b:.0f} m" for a, b in bands) + " | all |")
    print("|---|---|" + "---:|" * (len(bands) + 1))
    for rails in ("left", "both"):
        g = "{left_offset_m: 1.0}" if rails == "left" else "{left_offset_m: 1.0, right_offset_m: 1.0}"
        sc = parse_scenario(f"""
name: posts
duration_s: {frames * 0.072 + 0.01}
seed: 1
radar: {{preset: ars408_like}}
ego: {{speed_mps: 25.0}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1, guardrails: {g}}}
""")
        rc = radar_config(sc)
        for level in LEVELS:
            counts = np.zeros(len(bands) + 1)
            for seed in (1, 2):
                model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal)
                cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m)
                for k in range(frames):
                    cl = model.step(k * sc.period_s, cfg)[0].clusters
                    r = np.hypot(cl.dist_long_m, cl.dist_lat_m)
                    counts[:-1] += [np.count_nonzero((r >= a) & (r < b)) for a, b in bands]
                    counts[-1] += r.size
            counts /= 2 * frames
            print(f"| {rails} | {level} | " + " | ".join(f"{c:.1f}" for c in counts) + " |", flush=True)
    print()


def spacing_table(quick: bool) -> None:
    """Clusters a frame with guardrails on both edges against the posts' spacing, level by level: where the object
    level's resolution box (1.7 range bins) ends and the windows' main lobe (2 bins) still hides a weaker post."""
    frames = 15 if quick else 40
    print(f"### Guardrail posts against their spacing: clusters a frame ({frames} frames a row, seeds 1–2)\n")
    print("A straight three-lane road, the ego in the middle lane, guardrails 1 m beyond both edges, posts at −5 dBsm, "
          "Swerling 1; no other actor. Clusters a frame (mean) at each level, and each analytic level over the "
          "chain's\n")
    print("| preset | ego speed | post spacing | range bins | object | detection | signal | object / signal | "
          "detection / signal |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    rows = [("ars408_like", 25.0, sp) for sp in (2.0, 2.5, 3.0, 3.1, 3.5, 4.0, 5.0)]
    rows += [("ars408_like", v, sp) for v in (2.0, 36.0) for sp in (2.0, 4.0)]
    rows += [("mimo12", 25.0, sp) for sp in (0.5, 1.0, 2.0)]
    for name, speed, spacing in rows:
        counts = {}
        for level in ("object", "detection", "signal"):
            total = 0
            for seed in (1, 2):
                sc = parse_scenario(f"""
name: spacing
duration_s: {frames * 0.1 + 0.01}
seed: 1
radar: {{preset: {name}}}
ego: {{speed_mps: {speed}}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1, guardrails: {{left_offset_m: 1.0, right_offset_m: 1.0, post_spacing_m: {spacing}}}}}
""")
                rc = radar_config(sc)
                model = make_model(level, Scene(sc), rc.preset, np.random.default_rng(seed), rc.signal)
                cfg = RuntimeConfig(max_distance_m=rc.preset.max_range_m)
                total += sum(len(model.step(k * sc.period_s, cfg)[0].clusters) for k in range(frames))
            counts[level] = total / (2 * frames)
        sig = counts["signal"]
        print(f"| {name} | {speed:.0f} m/s | {spacing:.1f} m | {spacing / PRESETS[name].range_resolution_m:.2f} | "
              f"{counts['object']:.1f} | {counts['detection']:.1f} | {sig:.1f} | {counts['object'] / sig:.2f} | "
              f"{counts['detection'] / sig:.2f} |", flush=True)
    print()


def triples_table(quick: bool) -> None:
    """Three equal point reflectors in one range–Doppler cell (one range, one radial speed) at three angles: the
    frames in which a level reports a detection more than 6° from every reflector, and how often each is seen."""
    frames = 10 if quick else 30
    print(f"### Three reflectors in one range–Doppler cell ({frames} frames a row)\n")
    print("Three 10-dBsm point reflectors 30 m ahead at one radial speed (0, or 1.3× / 2.2× the alias speed: wrapped "
          "once, the second migrating over the frame), Swerling 0; detections within 3 m of 30 m. Ghost frames: a "
          "detection more than 6° from every reflector; seen: the frames in which the least-seen reflector has a "
          "detection within 6°\n")
    print("| preset | angles | speed / alias speed | level | ghost frames | seen (least) | detections a frame |")
    print("|---|---|---:|---|---:|---:|---:|")
    for name in ("ars408_like", "mimo12", "srr_corner"):
        p = PRESETS[name]
        chain = DspChain(p)
        for truth in ((-30.0, 0.0, 30.0), (-20.0, 0.0, 20.0)):
            for ratio in (0.0, -1.3, -2.2):
                s = point_targets([30.0] * 3, list(truth), ratio * p.max_unambiguous_speed_mps, 10.0)
                for level in ("detection", "signal"):
                    rng = np.random.default_rng(4)
                    ghosts, seen, count = 0, np.zeros(3, dtype=int), 0
                    for _ in range(frames):
                        det = (chain.process_rd(synthesize_rd(p, s, rng)) if level == "signal"
                               else detection_model.detect(p, s, rng, chain.statistic))
                        az = np.degrees(det.azimuth_rad[np.abs(det.range_m - 30.0) < 3.0])
                        off = np.abs(az[:, None] - np.array(truth)[None, :])
                        ghosts += int(np.any(off.min(axis=1) > 6.0))
                        seen += np.any(off <= 6.0, axis=0)
                        count += az.size
                    print(f"| {name} | {', '.join(f'{a:.0f}°' for a in truth)} | {ratio:.1f} | {level} | "
                          f"{ghosts} / {frames} | {seen.min()} / {frames} | {count / frames:.2f} |", flush=True)
    print()


def bodies_table(quick: bool) -> None:
    frames = 150 if not quick else 40
    print(f"### A car's reflectors ({frames} frames a row, each level)\n")
    print("One standing car, the ego standing; each frame the car moved along its line of sight by U(−1, 1) range "
          "bins; detections within 3 m + 2 range bins, 2 Doppler bins and 15° of its reflectors' mean; detections a "
          "frame, the strongest one's RCS and the RCS power sum of all (mean (sd), dBsm)\n")
    print("| preset | car at (x, y), heading | level | detections a frame | strongest RCS | RCS sum |")
    print("|---|---|---|---:|---:|---:|")
    for name, x, y, heading in (("mimo12", 15.0, 0.0, 60.0), ("mimo12", 16.0, 0.0, 80.0), ("mimo12", 36.0, -3.0, 10.0),
                                ("ars408_like", 11.0, 2.0, 60.0)):
        p = PRESETS[name]
        chain = DspChain(p)
        sc = parse_scenario(f"""
name: body
duration_s: 1.0
seed: 1
radar: {{preset: {name}}}
ego: {{speed_mps: 0.0}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1}}
actors:
  - {{id: car, class: car, x_m: {x}, y_m: {y}, speed_mps: 0.0, heading_deg: {heading}}}
""")
        scene = Scene(sc)
        base = scene_scatterers(scene, 0.0, scene.view(0.0), p, p.max_range_m)
        r_c, az_c = float(np.mean(base.range_m)), float(np.mean(base.azimuth_rad))
        for level in ("detection", "signal"):
            rng = np.random.default_rng(7)
            count, top, total = [], [], []
            for _ in range(frames):
                s = base.take(np.arange(len(base)))
                d = rng.uniform(-1.0, 1.0) * p.range_resolution_m
                s.x_m, s.y_m = s.x_m + d * math.cos(az_c), s.y_m + d * math.sin(az_c)
                det = (detection_model.detect(p, s, rng, chain.statistic) if level == "detection"
                       else chain.process_rd(synthesize_rd(p, s, rng)))
                ok = ((np.abs(det.range_m - r_c) < 3.0 + 2 * p.range_resolution_m)
                      & (np.abs(det.range_rate_mps) < 2 * p.doppler_bin_mps)
                      & (np.abs(det.azimuth_rad - az_c) < math.radians(15.0)))
                count.append(int(ok.sum()))
                if ok.any():
                    top.append(det.rcs_dbsm[ok].max())
                    total.append(10 * math.log10(np.sum(10 ** (det.rcs_dbsm[ok] / 10))))
            print(f"| {name} | ({x:.0f}, {y:.0f}) m, {heading:.0f}° | {level} | {np.mean(count):.2f} | "
                  f"{np.mean(top):.2f} ({np.std(top):.2f}) | {np.mean(total):.2f} ({np.std(total):.2f}) |", flush=True)
    print()


def abreast_table(quick: bool) -> None:
    positions = 16 if not quick else 6
    seps = (0.3, 0.5, 0.7, 0.8, 0.9, 1.0, 1.1, 1.5)
    cases = (("ars408_like", "range", (-10.0, 10.0), 0.0), ("ars408_like", "range", (-10.0, 10.0), 6.0),
             ("ars408_like", "Doppler", (-10.0, 10.0), 0.0), ("mimo12", "range", (-20.0, 20.0), 0.0),
             ("mimo12", "Doppler", (-20.0, 20.0), 6.0))
    print(f"### Two returns abreast at two angles ({positions} positions a point)\n")
    print("ρ 35 dB (the second one 0 or 6 dB weaker), the pair's middle at a random point of a cell along the axis "
          "they are apart in (40–41 range bins, 5–6 Doppler bins), each frame its own seed; detections within 2 bins "
          "of the pair a frame (mean), signal / detection\n")
    print("| preset | angles | axis | weaker by | " + " | ".join(f"{x:.1f} bins" for x in seps) + " |")
    print("|---|---|---|---:|" + "---:|" * len(seps))
    for name, axis, az, ratio in cases:
        p = PRESETS[name]
        chain = DspChain(p)
        row = []
        for sep in seps:
            count = {"signal": 0, "detection": 0}
            for t in range(positions):
                g = np.random.default_rng(300 + t)
                r0, v0 = 40.0 + g.random(), 5.0 + g.random()
                rb, vb = (np.array([r0, r0 + sep]), np.full(2, v0)) if axis == "range" else \
                    (np.full(2, r0), np.array([v0, v0 + sep]))
                r, v = rb * p.range_resolution_m, vb * p.doppler_bin_mps
                scat = point_targets(r, list(az), v)
                scat.rcs_dbsm = np.array([35.0, 35.0 - ratio]) - equation.snr_db(p, scat.range_m, 0.0, 0.0,
                                                                                 scat.azimuth_rad)
                for level in count:
                    count[level] += _near_count(level, p, chain, scat, 700 + t, r, v)
            row.append(f"{count['signal'] / positions:.2f} / {count['detection'] / positions:.2f}")
        print(f"| {name} | ±{abs(az[0]):.0f}° | {axis} | {ratio:.0f} dB | " + " | ".join(row) + " |", flush=True)
    print()


def layouts_table(quick: bool) -> None:
    layouts, frames = (70, 16) if not quick else (21, 6)
    rs = np.random.default_rng(4141)
    names = ("ars408_like", "mimo12", "srr_corner")
    diff = {name: [] for name in names}
    for i in range(layouts):
        name = names[i % 3]
        p = PRESETS[name]
        k = int(rs.integers(2, 6))
        rb, vb = 40.0 + rs.uniform(0.0, 2.0, k), 5.0 + rs.uniform(0.0, 2.0, k)
        if rs.random() < 0.5:
            vb[:] = vb[0]                                   # one speed: bodies abreast
        az = rs.uniform(-60.0, 60.0, k)
        rho = 35.0 - rs.choice([0.0, 0.0, 3.0, 6.0, 10.0], k)
        actor = rs.integers(0, 2, k) if rs.random() < 0.3 else np.arange(k)
        r, v = rb * p.range_resolution_m, vb * p.doppler_bin_mps
        scat = point_targets(r, list(az), v)
        scat.actor_index = np.asarray(actor, dtype=np.int64)
        scat.rcs_dbsm = rho - equation.snr_db(p, scat.range_m, 0.0, 0.0, scat.azimuth_rad)
        chain = _chain_of(name)
        count = {"signal": 0, "detection": 0}
        for t in range(frames):
            for level in count:
                count[level] += _near_count(level, p, chain, scat, 900 + 16 * i + t, r, v)
        diff[name].append((count["detection"] - count["signal"]) / frames)
    print(f"### Random layouts of returns within two bins ({layouts} layouts, {frames} frames each)\n")
    print("2–5 point returns at 40–42 range bins and 5–7 Doppler bins (half the layouts at one speed), azimuths uniform "
          "in ±60°, ρ 35 dB less 0, 3, 6 or 10 dB, some of one body; detections within 2 bins of a layout a frame, the "
          "detection level less the chain\n")
    print("| preset | layouts | mean signed | mean absolute | layouts over by > 0.5 | under by > 0.5 |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, d in list(diff.items()) + [("all", sum(diff.values(), []))]:
        d = np.array(d)
        print(f"| {name} | {d.size} | {d.mean():+.3f} | {np.abs(d).mean():.3f} | {int((d > 0.5).sum())} | "
              f"{int((d < -0.5).sum())} |", flush=True)
    print()


def secondary_table(quick: bool) -> None:
    frames = 48 if not quick else 12
    drops = (3.0, 5.0, 7.0, 8.5, 10.0)
    print(f"### A weaker return in a stronger one's cell, near the angle search's thresholds ({frames} frames a point)\n")
    print("Two point returns in one range–Doppler cell (both at one random point of cells 40 and 5), 3 beamwidths apart "
          "about a random direction within ±0.2 in sin θ; the stronger at ρ (dB), the weaker so many dB below it; each "
          "frame its own seed. The fraction of frames with a detection within 2 bins and 3° of the weaker one, "
          "signal / detection\n")
    print("| preset | ρ of the stronger | " + " | ".join(f"{d:g} dB weaker" for d in drops) + " |")
    print("|---|---:|" + "---:|" * len(drops))
    gaps = []
    for name in ("mimo12", "ars408_like", "srr_corner"):
        p = PRESETS[name]
        chain = _chain_of(name)
        for rho in (18.0, 22.0, 30.0):
            row = []
            for drop in drops:
                seen = {"signal": 0, "detection": 0}
                for t in range(frames):
                    g = np.random.default_rng((61, t))
                    rb, vb, centre = 40.0 + g.uniform(-0.5, 0.5), 5.0 + g.uniform(-0.5, 0.5), g.uniform(-0.2, 0.2)
                    u = centre + np.array([-1.5, 1.5]) / p.num_virtual
                    az = np.degrees(np.arcsin(u / p.element_spacing_wl))
                    r, v = np.full(2, rb * p.range_resolution_m), np.full(2, vb * p.doppler_bin_mps)
                    scat = point_targets(r, list(az), v)
                    scat.rcs_dbsm = np.array([rho, rho - drop]) - equation.snr_db(p, scat.range_m, 0.0, 0.0,
                                                                                  scat.azimuth_rad)
                    for level in seen:
                        rng = np.random.default_rng((62, t))
                        det = (detection_model.detect(p, scat, rng, chain.statistic) if level == "detection"
                               else chain.process_rd(synthesize_rd(p, scat, rng)))
                        seen[level] += bool(np.any((np.abs(det.range_m - r[1]) < 2 * p.range_resolution_m)
                                                   & (np.abs(det.range_rate_mps - v[1]) < 2 * p.doppler_bin_mps)
                                                   & (np.abs(np.degrees(det.azimuth_rad) - az[1]) < 3.0)))
                gaps.append((seen["detection"] - seen["signal"]) / frames)
                row.append(f"{seen['signal'] / frames:.2f} / {seen['detection'] / frames:.2f}")
            print(f"| {name} | {rho:.0f} dB | " + " | ".join(row) + " |", flush=True)
    gaps = np.array(gaps)
    print(f"\nDetection − signal over the {gaps.size} points: mean {gaps.mean():+.3f}, mean |Δ| "
          f"{np.abs(gaps).mean():.3f}, largest |Δ| {np.abs(gaps).max():.2f}\n")


def _near_count(level: str, p, chain, scat, seed: int, r: np.ndarray, v: np.ndarray) -> int:
    """How many detections one frame of ``scat`` gives at ``level`` (the detection level, or the chain on the
    range–Doppler synthesis) within 2 bins of the returns' extent in range ``r`` and speed ``v``, drawn from ``seed``."""
    rng = np.random.default_rng(seed)
    det = (detection_model.detect(p, scat, rng, chain.statistic) if level == "detection"
           else chain.process_rd(synthesize_rd(p, scat, rng)))
    near = ((det.range_m > r.min() - 2 * p.range_resolution_m) & (det.range_m < r.max() + 2 * p.range_resolution_m)
            & (det.range_rate_mps > v.min() - 2 * p.doppler_bin_mps)
            & (det.range_rate_mps < v.max() + 2 * p.doppler_bin_mps))
    return int(near.sum())


def _neighbour_errors(level: str, p, chain, r, az, v, rho, frames: int, seed: int):
    """Frames in which ``level`` resolves every one of the point returns (range ``r``, azimuth ``az`` deg, speed ``v``,
    integrated SNR ``rho`` dB each, set through their RCS), and those frames' errors, shape (frame, return, 3)."""
    rcs = np.asarray(rho, dtype=np.float64) - equation.snr_db(p, r, np.zeros(r.size), azimuth_rad=np.radians(az))
    scat = point_targets(r, az, v, rcs)
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(frames):
        det = (detection_model.detect(p, scat, rng, chain.statistic) if level == "detection"
               else chain.process_rd(synthesize_rd(p, scat, rng)))
        if det.range_m.size < r.size:
            continue
        cost = (np.abs(det.range_m[None] - r[:, None]) / p.range_resolution_m
                + np.abs(det.range_rate_mps[None] - v[:, None]) / p.doppler_bin_mps)
        j = np.argmin(cost, axis=1)
        if np.unique(j).size < r.size or np.any(cost[np.arange(r.size), j] > 1.0):
            continue
        out.append(np.c_[det.range_m[j] - r, det.range_rate_mps[j] - v, np.degrees(det.azimuth_rad[j]) - az])
    return len(out), (np.stack(out) if out else np.full((1, r.size, 3), np.nan))


def neighbours_table(quick: bool) -> None:
    frames = 60 if not quick else 15
    print(f"### Accuracy beside a neighbour: point returns a few to 24 range bins apart ({frames} frames a row)\n")
    print("Returns in a row along range (the same speed, 4° apart in azimuth; equal ρ, or a weaker one beside a "
          "stronger), set through their RCS so that both levels see one scene; 'resolved': frames in which a level "
          "reports every return within one bin; RMSE over each return's own single-return CRB, the worst return's, "
          "over the resolved frames (range / range rate / azimuth). The chain's patch fit ends 3 bins short of the "
          "nearest other peak and refits a patch a neighbour cut short, or a loud neighbour's sidelobes reach "
          "(DspChain.process_rd)\n")
    print("| preset | ρ of the returns | apart (bins) | resolved detection | resolved signal | "
          "RMSE/CRB detection | RMSE/CRB signal |")
    print("|---|---|---:|---:|---:|---|---|")
    cases = [(name, (30.0, 30.0), s) for name in ("mimo12", "ars408_like") for s in (2.0, 2.1, 2.5, 3.0, 4.0, 6.0)]
    cases += [(name, (45.0, 45.0), s) for name in ("mimo12", "ars408_like") for s in (9.0, 11.0, 14.0, 16.0, 18.0,
                                                                                      20.0, 24.0)]
    cases += [("mimo12", (60.0, 25.0), s) for s in (12.0, 13.0, 14.0, 16.0, 20.0, 26.0)]
    # 6–10 bins at 45–55 dB: patches cut to half-width 3–5 below 9 bins, 6 and 7 above (refitted where the louder
    # one's sidelobes reach them, from the three-bin interpolation)
    cases += [("mimo12", (45.0, 45.0), s) for s in (6.0, 7.0, 8.0)]
    cases += [("ars408_like", (55.0, 45.0), s) for s in (6.0, 7.0, 8.0, 9.0, 10.0)]
    cases += [("mimo12", (70.0, 70.0), s) for s in (9.0, 11.0, 14.0)]
    cases += [("ars408_like", (80.0, 80.0), s) for s in (9.0, 11.0, 14.0)]
    cases += [("mimo12", (30.0,) * k, s) for k in (3, 4) for s in (2.1, 2.5)]          # rows: an open case
    for name, rho, sep in cases:
        p = PRESETS[name]
        chain = _chain_of(name)
        k = len(rho)
        r = 40.3 + sep * p.range_resolution_m * np.arange(k)
        az, v = 4.0 * np.arange(k), np.full(k, 0.7)
        rho_a = np.asarray(rho)
        crb = np.stack([equation.crb_range_m(p, rho_a), equation.crb_speed_mps(p, rho_a),
                        np.degrees(equation.crb_azimuth_rad(p, rho_a, np.radians(az)))], axis=1)    # (return, 3)
        cells = []
        for lv in ("detection", "signal"):
            n, err = _neighbour_errors(lv, p, chain, r, az, v, rho_a, frames, seed=23)
            worst = np.max(np.sqrt(np.mean(err ** 2, axis=0)) / crb, axis=0)                           # (3,)
            cells.append((n / frames, " / ".join(f"{x:.2f}" for x in worst) if n else "–"))
        label = " / ".join(f"{x:.0f}" for x in rho) + " dB"
        print(f"| {name} | {label} | {sep:.1f} | {cells[0][0]:.2f} | {cells[1][0]:.2f} | {cells[0][1]} | "
              f"{cells[1][1]} |", flush=True)
    print()


_CHAINS: dict = {}


def _readings(level: str, rho_db: float, swerling: int, frames: int, seed: int) -> tuple[list[float], int, int]:
    """The cluster RCS over the truth of the point targets one run of :func:`calibrated`'s scene detects, at
    ``level``; the hits and trials (a cluster within 1.5 range bins and 2 beamwidths of a target is its own)."""
    sc = calibrated(rho_db, swerling, seed)
    scene = Scene(sc)
    model = make_model(level, scene, P, np.random.default_rng(seed), radar_config(sc).signal, clusters_wanted=True)
    return read_errors(model, scene, P, frames, sc.period_s, range(scene.n))


def read_errors(model, scene, p, frames: int, period_s: float, targets) -> tuple[list[float], int, int]:
    """Step ``model`` ``frames`` times: the cluster RCS over the truth of each of ``targets`` (actor indices) a
    frame detects, and the hits and trials (a cluster within 1.5 range bins and 2 beamwidths of a target is its
    own; the nearest such)."""
    cfg = RuntimeConfig(max_distance_m=p.max_range_m)
    err, hits, trials = [], 0, 0
    for k in range(frames):
        frame, view = model.step(k * period_s, cfg)
        cl = frame.clusters
        caz = np.arctan2(cl.dist_lat_m, cl.dist_long_m)
        for i in targets:
            trials += 1
            d = (np.abs(cl.range_m - view.range_m[i]) / (1.5 * p.range_resolution_m)
                 + np.abs(np.sin(caz) - np.sin(view.azimuth_rad[i])) / (2.0 * p.angular_resolution_rad))
            if d.size and d.min() <= 1.0:
                hits += 1
                err.append(float(cl.rcs_dbsm[int(np.argmin(d))] - scene.rcs_dbsm[i]))
    return err, hits, trials


def reading_table(quick: bool) -> None:
    frames = 20 if quick else 40
    seeds = (11, 12) if quick else (11, 12, 13, 14)
    print(f"### The RCS read of detected point targets, {P.name} ({len(seeds)} runs × {frames} frames × 10 targets "
          "a point)\n")
    print("Reported cluster RCS − true RCS (dB) of the targets each level detects: 25th / 50th / 75th percentile, "
          "and the Pd. Near the threshold a detected return reads high (it faded up, or its noise took it over); "
          "the object level draws its reading with its detection (`DetectionStatistic.reading`).\n")
    print("| Swerling | ρ (dB) | " + " | ".join(f"{lv}: Pd | {lv}: quartiles" for lv in LEVELS) + " |")
    print("|---|---:|" + "---:|---|" * len(LEVELS))
    for swerling, rhos in ((1, (11.0, 14.0, 17.0, 20.0, 30.0)), (0, (15.0, 16.5, 18.0, 20.0, 30.0))):
        for rho in rhos:
            cells = []
            for level in LEVELS:
                err, hits, trials = [], 0, 0
                for seed in seeds:
                    e, h, t = _readings(level, rho, swerling, frames, seed)
                    err, hits, trials = err + e, hits + h, trials + t
                q = np.percentile(err, [25, 50, 75]) if err else [math.nan] * 3
                cells.append(f"{hits / trials:.2f} | {q[0]:+.1f} / {q[1]:+.1f} / {q[2]:+.1f}")
            print(f"| {swerling} | {rho:.1f} | " + " | ".join(cells) + " |", flush=True)
    print()


def masked_table(quick: bool) -> None:
    """The reading under a steady ring interference: the statistic's own draw against the object level's reading."""
    from radarnode.dsp.detection_stats import straddle_gain
    st = _chain_of(P.name).statistic
    draws = 100_000 if quick else 400_000
    rng = np.random.default_rng(19)
    mean_z = st.n_channels * st.eigenvalues.sum()
    print(f"### The reading of a masked Swerling 1 return, {P.name} ({draws:,} draws a row)\n")
    print("I: a steady neighbour's energy in the CA-CFAR ring over the noise's mean training sum. Reading − ρ (dB, "
          "the SNR the chain reads over the return's mean) of the detected draws: the detection level's law "
          "(`DetectionStatistic.draw` with I) and the object level's (`DetectionStatistic.reading` with the equivalent "
          "loss L, `snr_of_pd` of the Pd alone less that of the masked Pd): 25th / 50th / 75th percentile.\n")
    print("| ρ (dB) | I | Pd alone | Pd masked | L (dB) | detection level's law | object level's reading | "
          "object − detection |")
    print("|---:|---:|---:|---:|---:|---|---|---|")
    for rho in (15.0, 20.0, 25.0, 30.0):
        for rel in (0.3, 1.0, 3.0):
            pos = (straddle_gain(st.range_window, rng.uniform(-0.5, 0.5, draws))
                   * straddle_gain(st.doppler_window, rng.uniform(-0.5, 0.5, draws)))
            energy = 10.0 ** (rho / 10.0) * st.window_gain * pos * rng.exponential(1.0, draws)
            det, x = st.draw(energy, rng, interference=rel * mean_z)
            k = int(det.sum())
            alone = float(st.pd_of_snr(rho, 1))
            loss = float(st.snr_of_pd(alone, 1) - st.snr_of_pd(det.mean(), 1))
            if k < 50:
                print(f"| {rho:.0f} | {rel:g} | {alone:.3f} | {det.mean():.5f} | {loss:.2f} | ({k} detections) | | |")
                continue
            mean = 10.0 ** (rho / 10.0) * st.window_gain * st.straddle_mean
            law = np.percentile(10.0 * np.log10(np.maximum(x[det] - st.n_channels, 1e-30) / mean), [25, 50, 75])
            read = st.reading(np.full(k, rho), rng.uniform(0.0, 1.0, k), rng.uniform(0.0, 1.0, k),
                              np.ones(k, dtype=bool), loss)
            obj = np.percentile(10.0 * np.log10(read), [25, 50, 75])
            cell = lambda q: " / ".join(f"{v:+.2f}" for v in q)      # noqa: E731
            print(f"| {rho:.0f} | {rel:g} | {alone:.3f} | {det.mean():.5f} | {loss:.2f} | {cell(law)} | {cell(obj)} | "
                  f"{cell(obj - law)} |", flush=True)
    print()


def _chain_of(name: str) -> DspChain:
    """One DspChain a preset (its statistic's tables are built once)."""
    if name not in _CHAINS:
        _CHAINS[name] = DspChain(PRESETS[name])
    return _CHAINS[name]


def main() -> None:
    global LEVELS, RESOLUTION_TRIALS, PD_FRAMES, PD_SWERLING, P
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", choices=("pfa", "pd", "cells", "accuracy", "resolution", "lobe", "beam", "crowd", "edge",
                                       "pairs", "rcs", "posts", "spacing", "triples", "abreast", "layouts",
                                       "secondary", "neighbours", "reading", "masked"))
    ap.add_argument("--levels", default="object,detection,signal", help="comma-separated subset of object,detection,signal")
    ap.add_argument("--trials", type=int, default=40, help="trials per point of the resolution table (its 50 %% "
                    "points move by about ±0.1 bin at 40)")
    ap.add_argument("--frames", type=int, default=None, help="frames per point of the Pd tables (default 80, "
                    "12 with --quick; 10 targets a frame: at 320 the ρ at Pd 0.9 of Swerling 1 is known to about "
                    "±0.25 dB)")
    ap.add_argument("--swerling", default="0,1", help="the Pd tables' Swerling cases: 0, 1 or 0,1")
    ap.add_argument("--preset", default="mimo12", help="the radar of the reading tables (--only reading, masked; every other "
                    "table is mimo12's or names its own)")
    args = ap.parse_args()
    if args.preset not in PRESETS:
        ap.error(f"--preset: value {args.preset!r} is not allowed; expected one of {', '.join(sorted(PRESETS))}")
    if args.preset != "mimo12" and args.only not in ("reading", "masked"):
        ap.error(f"--preset: value {args.preset!r} is allowed with --only reading or masked only (the other tables "
                 "are built "
                 "for mimo12 or name their radars)")
    if args.trials < 1:
        ap.error(f"--trials: value {args.trials} is not allowed; expected an integer ≥ 1")
    if args.frames is not None and args.frames < 2:
        ap.error(f"--frames: value {args.frames} is not allowed; expected an integer ≥ 2")
    cases = [c.strip() for c in args.swerling.split(",")]
    if not cases or any(c not in ("0", "1") for c in cases) or len(set(cases)) != len(cases):
        ap.error(f"--swerling: value {args.swerling!r} is not allowed; expected 0, 1 or 0,1")
    RESOLUTION_TRIALS = args.trials
    PD_FRAMES, PD_SWERLING = args.frames, tuple(int(c) for c in cases)
    LEVELS = tuple(lv for lv in args.levels.split(",") if lv)
    P = PRESETS[args.preset]
    t0 = time.perf_counter()
    # the command as given (its options, not a generic line), so that a table pasted from this output says what made it
    print(f"radarnode calibration, {time.strftime('%Y-%m-%d')}, "
          f"`python benchmarks/calibration.py{''.join(' ' + shlex.quote(a) for a in sys.argv[1:])}`\n")
    for name, fn in (("pfa", pfa_table), ("pd", pd_tables), ("cells", cells_table), ("accuracy", accuracy_table),
                     ("resolution", resolution_table), ("lobe", lobe_table), ("beam", beam_table),
                     ("crowd", crowd_table), ("edge", edge_table), ("pairs", pairs_table),
                     ("rcs", rcs_table), ("posts", posts_table), ("spacing", spacing_table),
                     ("triples", triples_table), ("abreast", abreast_table),
                     ("layouts", layouts_table), ("secondary", secondary_table),
                     ("neighbours", neighbours_table), ("reading", reading_table), ("masked", masked_table)):
        if args.only in (None, name):
            fn(args.quick)
    print(f"(total {time.perf_counter() - t0:.0f} s)")


if __name__ == "__main__":
    main()
