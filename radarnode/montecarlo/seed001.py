"""Seed 001's numerical experiment: the trials of one point (an SNR, a target layout), every estimator on the
same data.

Scene (seed 001 §3): two ``srr_corner`` radars (12-element ULAs at λ/2), 1.46 m apart, each turned 45°
outwards; one snapshot per radar; each target's amplitude is complex Gaussian, independent per radar (the
radars are incoherent) and per trial; unit noise per element; ``snr_db`` is the mean per-element SNR of each
target. The paper does not give the target's range; here 10 m from the middle of the baseline (a third of the
30 m the preset reaches; the two radars then see a target ±4° apart). The range of the cell each radar measures
is the true range of the targets' mean position from that radar plus Gaussian noise of the range CRB of
DESIGN.md §8, ``σ_R = ΔR·√6 / (2π·√(N·ρ))`` (all N channels of the cell, ΔR = 0.2 m), unless given.

Estimators, all on the same draws:

* ``lcacm`` — LC-ACM over both radars (:func:`radarnode.dsp.lcacm.lcacm`, centre on the two-circle point,
  offsets converted to angle); ``lcacm_sine`` — the same with eq. 10 as printed (offset added in the sine
  domain); ``lcacm_scan`` — centred on each radar's beam-scan peak, eq. 10 as printed (the literal reading).
  Angles from the middle of the baseline.
* ``bs_srr1``/``bs_srr2`` — beam scanning on one radar's full array; ``capon_srr1``/``capon_srr2`` — Capon with
  spatial smoothing (Q = 8), as seed 001 compares. Angles from that radar's position.
* ``<method>_srr1``/``_srr2`` for every estimator of :mod:`radarnode.dsp.subspace` (bartlett, capon, music,
  unitary_music, root_music, esprit), through ``subspace.estimate`` with forward–backward averaging and spatial
  smoothing (Q = 8) — one snapshot needs both — given the true number of sources J (as
  ``benchmarks/doa_estimators.py``: their MDL count is a separate question, and with one snapshot and Q = 8 it
  says 2 for one source about half the time), so their "correct number" is J peaks found and flagged
  resolved. They are called trial by trial (they take one covariance each); the seed-001 ones run on all
  trials at once.
* ``circles`` — the direction φ of the two-circle point alone (eq. 4–5, from the two measured ranges): one
  target per trial, the "centre of mass" LC-ACM shifts its offsets by.

Reproducibility: a point's draws come from ``SeedSequence(seed, spawn_key=(experiment, index))`` — the point's
place in its experiment, never the worker that runs it — so a sweep gives bit-identical results on one
process, a pool or a Dask cluster.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from radarnode.dsp import lcacm as lc
from radarnode.dsp import subspace as ss
from radarnode.errors import ConfigError

#: experiment name → the first element of the spawn key (never renumber: it would change every result)
EXPERIMENTS = {"snr": 0, "table2": 1, "resolution": 2}
#: LC-ACM variants: name → (centre, offset)
LCACM_VARIANTS = {"lcacm": ("circle", "angle"), "lcacm_sine": ("circle", "sine"), "lcacm_scan": ("scan", "sine")}
SUBSPACE_METHODS = tuple(ss.ESTIMATORS)
RADARS = ("srr1", "srr2")


def estimator_names() -> tuple[str, ...]:
    """Every estimator a point runs, in table order."""
    names = list(LCACM_VARIANTS) + ["circles"]
    names += [f"{m}_{r}" for m in ("bs", "capon") for r in RADARS]
    names += [f"ss_{m}_{r}" if m in ("bartlett", "capon") else f"{m}_{r}" for m in SUBSPACE_METHODS for r in RADARS]
    return tuple(names)


@dataclass(frozen=True)
class Setup:
    """The scene and the arrays (defaults: seed 001 with the ``srr_corner`` preset's array).

    n_elements, spacing_wl : the virtual ULA (3 Tx × 4 Rx = 12 at λ/2).
    range_resolution_m : ΔR of the preset (c/2B = 0.2 m), for the range noise.
    baseline_m, yaw_deg : seed 001's mounts.
    range_m : targets' range from the middle of the baseline.
    subarray : Q for smoothing (round(0.7·N) = 8).
    range_sigma_m : the range noise's σ, m; None: the range CRB at each point's SNR.
    """

    n_elements: int = 12
    spacing_wl: float = 0.5
    range_resolution_m: float = 0.2
    baseline_m: float = lc.SEED001_BASELINE_M
    yaw_deg: float = lc.SEED001_YAW_DEG
    range_m: float = 10.0
    subarray: int = 8
    range_sigma_m: float | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.n_elements, int) and 4 <= self.n_elements <= 256):
            raise ConfigError(f"setup n_elements: value {self.n_elements!r} is not allowed; expected 4 … 256")
        if not 2 <= self.subarray <= self.n_elements:
            raise ConfigError(f"setup subarray: value {self.subarray!r} is not allowed; expected 2 … "
                              f"{self.n_elements}")
        for name in ("spacing_wl", "range_resolution_m", "baseline_m", "range_m"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise ConfigError(f"setup {name}: value {v!r} is not allowed; expected a finite number > 0")
        if self.range_m <= self.baseline_m:
            raise ConfigError(f"setup range_m: value {self.range_m!r} is not allowed; expected more than the "
                              f"baseline ({self.baseline_m} m)")
        if self.range_sigma_m is not None and not (math.isfinite(self.range_sigma_m) and self.range_sigma_m >= 0):
            raise ConfigError(f"setup range_sigma_m: value {self.range_sigma_m!r} is not allowed; expected a "
                              "finite σ >= 0 m or None (the range CRB)")

    @classmethod
    def from_preset(cls, name: str = "srr_corner", **changes) -> "Setup":
        """The array of a radar preset (``srr_corner``: seed 001's sensor), the rest seed 001's."""
        from radarnode.radar.presets import get_preset
        p = get_preset(name)
        n = p.num_virtual
        return cls(n_elements=n, spacing_wl=p.element_spacing_wl, range_resolution_m=p.range_resolution_m,
                   subarray=ss.default_subarray(n), **changes)

    @property
    def geometry(self) -> lc.PairGeometry:
        yaw = math.radians(self.yaw_deg)
        return lc.PairGeometry(self.baseline_m, (-yaw, yaw))

    def range_sigma(self, snr_db: float) -> float:
        """σ of each radar's range, m: given, or ``ΔR·√6 / (2π·√(N·ρ))`` (DESIGN.md §8, N channels)."""
        if self.range_sigma_m is not None:
            return self.range_sigma_m
        rho = self.n_elements * 10.0 ** (snr_db / 10.0)
        return self.range_resolution_m * math.sqrt(6.0) / (2.0 * math.pi * math.sqrt(rho))


@dataclass(frozen=True)
class Point:
    """One point of a sweep: experiment name, its index in the experiment, SNR and the targets' azimuths."""

    experiment: str
    index: int
    snr_db: float
    azimuth_deg: tuple[float, ...]

    def __post_init__(self) -> None:
        if self.experiment not in EXPERIMENTS:
            raise ConfigError(f"point experiment: value {self.experiment!r} is not allowed; expected one of "
                              f"{', '.join(EXPERIMENTS)}")
        if not (-60.0 <= self.snr_db <= 100.0):
            raise ConfigError(f"point snr_db: value {self.snr_db!r} is not allowed; expected -60 … 100 dB")
        if not 1 <= len(self.azimuth_deg) <= 2:
            raise ConfigError(f"point azimuth_deg: value {self.azimuth_deg!r} is not allowed; expected 1 or 2 "
                              "targets")

    @property
    def seed_key(self) -> tuple[int, int]:
        return EXPERIMENTS[self.experiment], self.index


@dataclass
class PointResult:
    """Every estimator's output at one point.

    count : name → (T,) int, targets found per trial.
    est_deg : name → (T, J) float64 azimuths, each row ascending (rows with the wrong count hold what was found,
        padded; metrics ignore them).
    truth_deg : name → (J,) the true azimuths in that estimator's frame (from the baseline's middle for LC-ACM,
        from the radar for a single radar).
    local_deg : (2, J) the targets' local angles at radar 1 and 2 (for the CRB).
    """

    point: Point
    count: dict[str, np.ndarray] = field(default_factory=dict)
    est_deg: dict[str, np.ndarray] = field(default_factory=dict)
    truth_deg: dict[str, np.ndarray] = field(default_factory=dict)
    local_deg: np.ndarray | None = None


def _sorted_first(values: np.ndarray, j: int) -> np.ndarray:
    return np.sort(values[:, :j], axis=1)


def run_point(setup: Setup, trials: int, seed: int, point: Point,
              methods: tuple[str, ...] | None = None) -> PointResult:
    """All trials of one point (module docstring); ``methods`` restricts the estimators (default all)."""
    names = estimator_names()
    methods = names if methods is None else tuple(methods)
    unknown = [m for m in methods if m not in names]
    if unknown:
        raise ConfigError(f"montecarlo estimator: value {unknown[0]!r} is not allowed; expected one of "
                          f"{', '.join(names)}")
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=point.seed_key))
    geo = setup.geometry
    n, d, q = setup.n_elements, setup.spacing_wl, setup.subarray
    az = np.radians(np.asarray(point.azimuth_deg, dtype=float))
    j = az.size
    x, y = lc.polar_to_xy(setup.range_m, az)
    rng_k, theta_k = lc.seen_from(x, y, geo)                                      # (2, J)
    ys = [lc.snapshots(rng, np.broadcast_to(theta_k[k], (trials, j)), point.snr_db, n, d) for k in range(2)]
    # the cell's range at each radar: the targets' mean position, plus the range noise
    xc, yc = float(np.mean(x)), float(np.mean(y))
    r_true, _ = lc.seen_from(np.array(xc), np.array(yc), geo)
    r_meas = r_true[:, None] + setup.range_sigma(point.snr_db) * rng.standard_normal((2, trials))
    r_meas = np.maximum(r_meas, 1e-3)
    out = PointResult(point, local_deg=np.degrees(theta_k))
    truth_origin = np.sort(np.degrees(az))
    truth_radar = [np.sort(np.degrees(theta_k[k] + geo.yaw_rad[k])) for k in range(2)]
    n_max = max(2, j + 1)
    for name, (centre, offset) in LCACM_VARIANTS.items():
        if name in methods:
            est = lc.lcacm(ys[0], ys[1], r_meas[0], r_meas[1], geo, n_max=n_max, d=d, q=q, centre=centre,
                           offset=offset)
            out.count[name] = est.count
            out.est_deg[name] = _sorted_first(np.degrees(est.azimuth_rad), j)
            out.truth_deg[name] = truth_origin
    if "circles" in methods:
        xm, ym, _ = lc.two_circle_intersection(r_meas[0], r_meas[1], geo.baseline_m)
        out.count["circles"] = np.ones(trials, dtype=np.int64)
        out.est_deg["circles"] = np.repeat(np.degrees(np.arctan2(xm, ym))[:, None], j, axis=1)
        out.truth_deg["circles"] = truth_origin
    for k, radar in enumerate(RADARS):
        yaw_deg = math.degrees(geo.yaw_rad[k])
        for name, fn in ((f"bs_{radar}", lambda v: lc.beam_scan(v, n_max, d)),
                         (f"capon_{radar}", lambda v: lc.capon_scan(v, n_max, d, q))):
            if name in methods:
                u, ok = fn(ys[k])
                out.count[name] = ok.sum(axis=1)
                out.est_deg[name] = _sorted_first(np.degrees(np.arcsin(np.clip(u, -1.0, 1.0))) + yaw_deg, j)
                out.truth_deg[name] = truth_radar[k]
        for m in SUBSPACE_METHODS:
            name = f"ss_{m}_{radar}" if m in ("bartlett", "capon") else f"{m}_{radar}"
            if name not in methods:
                continue
            count = np.zeros(trials, dtype=np.int64)
            est = np.zeros((trials, j))
            for t in range(trials):                     # subspace estimators take one covariance per call
                e = ss.estimate(m, ys[k][t], j, d, fb=True, subarray=q)
                found = e.sin_theta[e.resolved]
                count[t] = found.size
                if found.size:
                    est[t, :min(j, found.size)] = found[:j]
            out.count[name] = count
            out.est_deg[name] = np.sort(np.degrees(np.arcsin(np.clip(est, -1.0, 1.0))) + yaw_deg, axis=1)
            out.truth_deg[name] = truth_radar[k]
    return out


def resolved(result: PointResult, name: str) -> np.ndarray:
    """(T,) bool: the estimator found exactly the J targets and each within half their separation of its truth
    (J = 2; for one target: within 1°)."""
    truth = result.truth_deg[name]
    half = 0.5 * float(np.min(np.diff(truth))) if truth.size > 1 else 1.0
    err = np.abs(result.est_deg[name] - truth[None, :])
    return (result.count[name] == truth.size) & np.all(err < half, axis=1)


def crb_deg(setup: Setup, local_deg: np.ndarray, snr_db: float) -> dict[str, float]:
    """Stochastic CRB (``subspace.crb_sin``, one snapshot) on each target's angle, in degrees, RMS over targets:
    one radar (``srr1``, ``srr2``: ``√CRB(sin θ)/cos θ``) and both radars' arrays together (``both``: Fisher
    information added, ranges not used)."""
    out = {}
    info = 0.0
    for k, radar in enumerate(RADARS):
        th = np.radians(np.asarray(local_deg[k], dtype=float))
        var_u = ss.crb_sin(np.sin(th), setup.n_elements, 1, snr_db, setup.spacing_wl)
        var_th = var_u / np.cos(th) ** 2
        out[radar] = math.degrees(math.sqrt(float(np.mean(var_th))))
        info = info + 1.0 / var_th
    out["both"] = math.degrees(math.sqrt(float(np.mean(1.0 / info))))
    return out


__all__ = ["EXPERIMENTS", "LCACM_VARIANTS", "SUBSPACE_METHODS", "Setup", "Point", "PointResult", "run_point",
           "estimator_names", "resolved", "crb_deg"]
