"""Seed 001's figures of merit over Monte Carlo trials (eq. 11–14), and where an RMSE curve crosses a level.

Axis order: counts ``count[trial]``; estimates ``est[trial, target]`` (each trial's estimates sorted ascending,
as the true angles ``truth[target]``), degrees.

Seed 001 reports RMSE and bias only where the probability of the correct number of targets exceeds 0.8; the
functions here return ``None`` there (and for fewer than two correct trials) instead of a number or NaN.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

#: seed 001: "RMSE and bias are considered only where p > 0.8"
P_MIN = 0.8


@dataclass(frozen=True)
class Metrics:
    """Eq. 11–13 of one estimator at one point.

    p : probability of the correct number of targets, ``m / n`` (eq. 11).
    rmse_deg : ``√(1/J Σ_k σ_k²)``, ``σ_k²`` the unbiased variance of target k's estimates over the m correct
        trials (eq. 12) — a spread about the mean, not about the truth; None where ``p ≤ 0.8`` or ``m < 2``.
    bias_deg : ``√(1/J Σ_k (φ̄_k − φ_k)²)`` (eq. 13); None as ``rmse_deg``.
    m, n : correct and all trials.
    rmse_any_deg, bias_any_deg : the same figures whatever ``p`` (None only for ``m < 2``), for tables that show
        them flagged rather than not at all.
    """

    p: float
    rmse_deg: float | None
    bias_deg: float | None
    m: int
    n: int
    rmse_any_deg: float | None = None
    bias_any_deg: float | None = None

    def as_dict(self) -> dict:
        return {"p": self.p, "rmse_deg": self.rmse_deg, "bias_deg": self.bias_deg, "m": self.m, "n": self.n}


def rmse_bias(est_deg: np.ndarray, truth_deg: np.ndarray) -> tuple[float, float]:
    """Eq. 12 and 13 over trials that found the right number of targets: ``est_deg`` (m, J), ``truth_deg`` (J,).

    Needs m ≥ 2 (the unbiased variance divides by m − 1).
    """
    est = np.asarray(est_deg, dtype=float)
    truth = np.asarray(truth_deg, dtype=float)
    if est.ndim != 2 or est.shape[0] < 2 or est.shape[1] != truth.size:
        raise ValueError(f"rmse_bias: shape {est.shape} is not allowed; expected (m >= 2, {truth.size})")
    mean = est.mean(axis=0)                                         # φ̄_k
    var = est.var(axis=0, ddof=1)                                   # σ_k²
    return math.sqrt(float(var.mean())), math.sqrt(float(np.mean((mean - truth) ** 2)))


def metrics(count: np.ndarray, est_deg: np.ndarray, truth_deg: np.ndarray, gate_deg: float | None = None) -> Metrics:
    """Eq. 11–13 for one estimator at one point: ``count`` (n,), ``est_deg`` (n, J) (rows of trials with the
    wrong count are ignored), ``truth_deg`` (J,).

    ``gate_deg``: a trial counts as correct only if, besides the count, every estimate lies within this of its
    target. Seed 001 counts targets only; but an estimator told the number of sources (the subspace ones) always
    "finds" it, and in a deep fade its one peak can be anywhere — a gate puts such trials on the same footing as
    a beam scan's, whose fade shows as a wrong count.
    """
    truth = np.atleast_1d(np.asarray(truth_deg, dtype=float))
    count = np.asarray(count)
    good = count == truth.size
    if gate_deg is not None:
        good &= np.all(np.abs(np.asarray(est_deg, dtype=float) - truth[None, :]) < gate_deg, axis=1)
    if count.size == 0:
        raise ValueError("metrics: no trial; expected at least one")
    p = float(np.mean(good))
    m = int(good.sum())
    if m < 2:
        return Metrics(p, None, None, m, int(count.size))
    rmse, bias = rmse_bias(np.asarray(est_deg, dtype=float)[good], truth)
    if p <= P_MIN:
        return Metrics(p, None, None, m, int(count.size), rmse, bias)
    return Metrics(p, rmse, bias, m, int(count.size), rmse, bias)


def normalised(value: float | None, reference: float | None) -> float | None:
    """Eq. 14: ``value / reference`` (an estimator's RMSE or bias over LC-ACM's); None when either is missing or
    the reference is 0."""
    if value is None or reference is None or reference <= 0.0:
        return None
    return value / reference


def crossing(x: np.ndarray, y: list[float | None], level: float) -> float | None:
    """The first ``x`` at which ``y`` comes down to ``level`` and stays there, interpolated linearly in
    ``log y`` between the two points around it; ``x`` ascending. Points where ``y`` is None (not reported) count
    as above the level. None when ``y`` never reaches the level or already starts below it (then the crossing
    is at or before ``x[0]``: returned as ``x[0]`` only when ``y[0]`` is exactly reported)."""
    x = np.asarray(x, dtype=float)
    below = np.array([v is not None and v <= level for v in y])
    if not below[-1]:
        return None
    # the last point above the level: everything after it is below
    above = np.flatnonzero(~below)
    if above.size == 0:
        return float(x[0])
    i = int(above[-1])
    j = i + 1
    if y[i] is None or y[i] <= 0 or y[j] <= 0:
        return float(x[j])
    l0, l1, lv = math.log(y[i]), math.log(y[j]), math.log(level)
    return float(x[i] + (x[j] - x[i]) * (l0 - lv) / (l0 - l1))


__all__ = ["Metrics", "P_MIN", "rmse_bias", "metrics", "normalised", "crossing"]
