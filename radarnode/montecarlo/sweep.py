"""The sweeps of ``radarnode montecarlo``: which points, run where, and seed 001's figures from their trials.

Three experiments (seed 001 §3), every estimator of :mod:`radarnode.montecarlo.seed001` on the same draws:

* ``snr`` — one target at ``azimuth_deg`` (7°, seed 001 fig. 6–7) against SNR: eq. 11–13 per point, the
  stochastic CRB per radar and for both arrays together, and the SNR at which each RMSE reaches 0.1°;
* ``table2`` — one target at ``table2_snr_db`` (15 dB) over several azimuths, eq. 11–13 averaged over them
  (seed 001: "averaged metrics for different angles of arrival"; RMSE and bias at every azimuth whatever p,
  with a flag saying whether p > 0.8 held at all of them) and eq. 14 against ``lcacm``;
* ``resolution`` — two equal targets ``separation`` apart around ``azimuth_deg`` at ``resolution_snr_db``: the
  probability that an estimator finds exactly two, each within half the separation.

"Correct number of targets" (eq. 11) here also asks each estimate to lie within half the array's Rayleigh
width (4.8°) of its target (:func:`gate_deg`): the subspace estimators are told the number of sources, so
without a gate their deep-fade trials — one peak anywhere — would enter the RMSE while a beam scan's show as a
wrong count and do not.
"""

from __future__ import annotations

import functools
import math
from dataclasses import asdict, dataclass

import numpy as np

from radarnode.errors import ConfigError
from radarnode.montecarlo import metrics as mx
from radarnode.montecarlo.executor import run_tasks
from radarnode.montecarlo.seed001 import Point, PointResult, Setup, crb_deg, estimator_names, resolved, run_point

ALL_EXPERIMENTS = ("snr", "table2", "resolution")
#: seed 001's crossing level
RMSE_LEVEL_DEG = 0.1


@dataclass(frozen=True)
class Sweep:
    """What to run (defaults: seed 001's 500 trials a point)."""

    trials: int = 500
    seed: int = 0
    experiments: tuple[str, ...] = ALL_EXPERIMENTS
    snr_db: tuple[float, ...] = tuple(float(v) for v in np.arange(0.0, 35.01, 2.5))
    azimuth_deg: float = 7.0
    table2_snr_db: float = 15.0
    table2_azimuth_deg: tuple[float, ...] = (-20.0, -10.0, 0.0, 7.0, 10.0, 20.0)
    separation_deg: tuple[float, ...] = (1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0, 10.0, 12.0, 15.0)
    resolution_snr_db: float = 20.0

    def __post_init__(self) -> None:
        if not (isinstance(self.trials, int) and 2 <= self.trials <= 1_000_000):
            raise ConfigError(f"sweep trials: value {self.trials!r} is not allowed; expected an integer 2 … 1000000")
        bad = [e for e in self.experiments if e not in ALL_EXPERIMENTS]
        if bad or not self.experiments:
            raise ConfigError(f"sweep experiments: value {bad[0] if bad else self.experiments!r} is not allowed; "
                              f"expected one or more of {', '.join(ALL_EXPERIMENTS)}")
        if list(self.snr_db) != sorted(self.snr_db) or len(set(self.snr_db)) != len(self.snr_db):
            raise ConfigError(f"sweep snr_db: value {self.snr_db!r} is not allowed; expected ascending distinct SNRs")

    def points(self) -> list[Point]:
        """Every point, experiment by experiment; a point's index is its place in its experiment."""
        out: list[Point] = []
        if "snr" in self.experiments:
            out += [Point("snr", i, s, (self.azimuth_deg,)) for i, s in enumerate(self.snr_db)]
        if "table2" in self.experiments:
            out += [Point("table2", i, self.table2_snr_db, (a,)) for i, a in enumerate(self.table2_azimuth_deg)]
        if "resolution" in self.experiments:
            out += [Point("resolution", i, self.resolution_snr_db,
                          (self.azimuth_deg - 0.5 * s, self.azimuth_deg + 0.5 * s))
                    for i, s in enumerate(self.separation_deg)]
        return out


def run(setup: Setup, sweep: Sweep, *, workers: int = 1, scheduler: str | None = None,
        dask_local: int | None = None, on_done=None) -> list[PointResult]:
    """Every point of the sweep, in :meth:`Sweep.points` order, wherever asked (:func:`run_tasks`)."""
    fn = functools.partial(run_point, setup, sweep.trials, sweep.seed)
    return run_tasks(fn, sweep.points(), workers=workers, scheduler=scheduler, dask_local=dask_local,
                     on_done=on_done)


def gate_deg(setup: Setup) -> float:
    """Half the array's Rayleigh width at broadside, ``arcsin(1/(2·N·d))`` (4.8° for 12 elements at λ/2): an
    estimate farther than this from its target is not counted as finding it (:func:`metrics.metrics`)."""
    return math.degrees(math.asin(min(1.0, 1.0 / (2.0 * setup.n_elements * setup.spacing_wl))))


def _mean_or_none(values: list[float | None]) -> float | None:
    return None if not values or any(v is None for v in values) else float(np.mean(values))


def summarise(setup: Setup, sweep: Sweep, results: list[PointResult]) -> dict:
    """Seed 001's figures from the trials, as plain JSON-able data (None where a figure is not given)."""
    names = [n for n in estimator_names() if results and n in results[0].count]
    gate = gate_deg(setup)
    out: dict = {"setup": asdict(setup), "sweep": asdict(sweep), "estimators": names, "gate_deg": gate}
    by = {e: [r for r in results if r.point.experiment == e] for e in ALL_EXPERIMENTS}
    if by["snr"]:
        rs = by["snr"]
        curves = {n: [mx.metrics(r.count[n], r.est_deg[n], r.truth_deg[n], gate).as_dict() for r in rs] for n in names}
        crb = {k: [crb_deg(setup, r.local_deg, r.point.snr_db)[k] for r in rs] for k in ("srr1", "srr2", "both")}
        snr = [r.point.snr_db for r in rs]
        out["snr"] = {
            "azimuth_deg": sweep.azimuth_deg, "snr_db": snr, "metrics": curves, "crb_deg": crb,
            "crossing_db": {n: mx.crossing(np.array(snr), [c["rmse_deg"] for c in curves[n]], RMSE_LEVEL_DEG)
                            for n in names},
            "crb_crossing_db": {k: mx.crossing(np.array(snr), v, RMSE_LEVEL_DEG) for k, v in crb.items()},
        }
    if by["table2"]:
        rs = by["table2"]
        per = {n: [mx.metrics(r.count[n], r.est_deg[n], r.truth_deg[n], gate) for r in rs] for n in names}
        # seed 001 gives Table 2 for every estimator: the means here take every azimuth's figure whatever its p,
        # and say whether p > 0.8 held at all of them
        table = {n: {"p": float(np.mean([m.p for m in per[n]])),
                     "p_above_0.8_everywhere": all(m.p > mx.P_MIN for m in per[n]),
                     "rmse_deg": _mean_or_none([m.rmse_any_deg for m in per[n]]),
                     "bias_deg": _mean_or_none([m.bias_any_deg for m in per[n]])} for n in names}
        ref = table.get("lcacm", {})
        for n in names:
            table[n]["norm_rmse"] = mx.normalised(table[n]["rmse_deg"], ref.get("rmse_deg"))
            table[n]["norm_bias"] = mx.normalised(table[n]["bias_deg"], ref.get("bias_deg"))
        out["table2"] = {"snr_db": sweep.table2_snr_db, "azimuth_deg": [r.point.azimuth_deg[0] for r in rs],
                         "metrics": table,
                         "crb_deg": {k: float(np.mean([crb_deg(setup, r.local_deg, r.point.snr_db)[k] for r in rs]))
                                     for k in ("srr1", "srr2", "both")}}
    if by["resolution"]:
        rs = by["resolution"]
        out["resolution"] = {"snr_db": sweep.resolution_snr_db, "centre_deg": sweep.azimuth_deg,
                             "separation_deg": [float(np.diff(r.point.azimuth_deg)[0]) for r in rs],
                             "probability": {n: [float(np.mean(resolved(r, n))) for r in rs] for n in names}}
    return out


def results_equal(a: list[PointResult], b: list[PointResult]) -> bool:
    """Bit for bit: the same points, estimators, counts and estimates."""
    if len(a) != len(b):
        return False
    for ra, rb in zip(a, b):
        if ra.point != rb.point or ra.count.keys() != rb.count.keys():
            return False
        for n in ra.count:
            if not (np.array_equal(ra.count[n], rb.count[n]) and np.array_equal(ra.est_deg[n], rb.est_deg[n])):
                return False
    return True


def finite_everywhere(results: list[PointResult]) -> bool:
    """No NaN or inf in any estimate."""
    return all(np.all(np.isfinite(v)) for r in results for v in r.est_deg.values())


__all__ = ["Sweep", "run", "summarise", "results_equal", "finite_everywhere", "ALL_EXPERIMENTS", "RMSE_LEVEL_DEG"]
