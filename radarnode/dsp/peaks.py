"""Peak grouping and sub-bin interpolation on a range–Doppler power map."""

from __future__ import annotations

import numpy as np
import scipy.ndimage


def local_maxima(power: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cells of ``mask`` that are the maximum of their 3×3 neighbourhood (Doppler wraps).

    Returns (doppler_index, range_index), each of shape (n,).
    """
    peak = power >= scipy.ndimage.maximum_filter(power, size=3, mode=("wrap", "nearest"))
    return np.nonzero(mask & peak)


def interpolate(power: np.ndarray, d: np.ndarray, r: np.ndarray, window: str = "hann"
                ) -> tuple[np.ndarray, np.ndarray]:
    """Sub-bin offsets of peaks from the peak cell and its two neighbours along each axis.

    For the Hann window the magnitude ratio of the larger neighbour to the
    peak, α = |X_{k±1}|/|X_k|, gives the offset exactly for one tone:
    δ = (2α − 1)/(α + 1) (from W(δ) ∝ sinc δ / (1 − δ²)). Other windows use a
    parabola through the log-power (bias up to a few hundredths of a bin).
    Returns (delta_doppler, delta_range) in bins, each in [-0.5, 0.5].
    """
    nd, nr = power.shape
    rm, rp = np.maximum(r - 1, 0), np.minimum(r + 1, nr - 1)
    est = _hann_ratio if window == "hann" else _log_parabola
    dd = est(power[(d - 1) % nd, r], power[d, r], power[(d + 1) % nd, r])
    dr = est(power[d, rm], power[d, r], power[d, rp])
    dr = np.where((r == 0) | (r == nr - 1), 0.0, dr)
    return dd, dr


def _hann_ratio(p_m, p_0, p_p):
    tiny = np.finfo(np.float64).tiny
    right = p_p >= p_m
    alpha = np.sqrt(np.where(right, p_p, p_m) / np.maximum(p_0, tiny))
    delta = np.clip((2.0 * alpha - 1.0) / (alpha + 1.0), 0.0, 0.5)
    return np.where(right, delta, -delta)


def _log_parabola(p_m, p_0, p_p):
    tiny = np.finfo(np.float64).tiny
    a_m, a_0, a_p = (np.log(np.maximum(x, tiny)) for x in (p_m, p_0, p_p))
    den = a_m - 2.0 * a_0 + a_p
    with np.errstate(divide="ignore", invalid="ignore"):
        delta = np.where(den < 0, 0.5 * (a_m - a_p) / den, 0.0)
    return np.clip(delta, -0.5, 0.5)
