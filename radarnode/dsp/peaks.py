"""Peak grouping and sub-bin interpolation on a range–Doppler power map."""

from __future__ import annotations

import numpy as np
import scipy.ndimage


def local_maxima(power: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cells of ``mask`` that are the maximum of their 3×3 neighbourhood (both axes wrap: both FFTs are circular).

    Returns (doppler_index, range_index), each of shape (n,).
    """
    peak = power >= scipy.ndimage.maximum_filter(power, size=3, mode="wrap")
    return np.nonzero(mask & peak)


def interpolate(power: np.ndarray, d: np.ndarray, r: np.ndarray, window: str = "hann"
                ) -> tuple[np.ndarray, np.ndarray]:
    """Sub-bin offsets of peaks from the peak cell and its two neighbours along each axis.

    For the Hann window the magnitude ratio of the larger neighbour to the
    peak, α = |X_{k±1}|/|X_k|, gives the offset exactly for one tone:
    δ = (2α − 1)/(α + 1) (from W(δ) ∝ sinc δ / (1 − δ²)). Other windows use a
    parabola through the log-power (bias up to a few hundredths of a bin).
    Both axes wrap (a beat frequency past the last range bin is the first bins').
    Returns (delta_doppler, delta_range) in bins, each in [-0.5, 0.5].
    """
    nd, nr = power.shape
    rm, rp = (r - 1) % nr, (r + 1) % nr
    est = _hann_ratio if window == "hann" else _log_parabola
    dd = est(power[(d - 1) % nd, r], power[d, r], power[(d + 1) % nd, r])
    dr = est(power[d, rm], power[d, r], power[d, rp])
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


def refine_ml(spectra: np.ndarray, bins: np.ndarray, window: np.ndarray, half_width: float = 0.15,
              points: int = 13) -> np.ndarray:
    """Maximum-likelihood refinement of peak positions along the last axis of windowed spectra.

    The three-bin interpolators lose a factor of about 2 against the
    Cramér–Rao bound because the window widens the main lobe. The window can
    be taken out exactly: the inverse FFT of a windowed spectrum is w[n]·x[n],
    and x[n] = (w[n]·x[n]) / w[n] carries the same white noise as before the
    window. The periodogram of x (rectangular, efficient at high SNR) is then
    evaluated on a fine grid of ``points`` within ±``half_width`` bins of the
    coarse estimate and summed over the channels; a parabola through its peak
    gives the estimate.

    Parameters
    ----------
    spectra : complex array, shape (n_peaks, n_channels, n_bins)
        The windowed spectrum of each peak's channels (e.g. ``rd[:, d, :]``).
    bins : array, shape (n_peaks,)
        Coarse peak positions in bins (integer plus interpolated offset).
    window : array, shape (n_bins,)
        The window that was applied before the FFT.

    Returns
    -------
    array, shape (n_peaks,): refined positions in bins.
    """
    if spectra.shape[0] == 0:
        return np.asarray(bins, dtype=np.float64)
    n = spectra.shape[-1]
    x = np.fft.ifft(spectra, axis=-1)
    keep = window > 1e-3 * window.max()              # samples the window zeroed carry nothing
    x = x[..., keep] / window[keep]
    idx = np.flatnonzero(keep).astype(np.float64)
    offsets = np.linspace(-half_width, half_width, points)
    coarse = np.asarray(bins, dtype=np.float64)
    f = coarse[:, None] + offsets[None, :]                                          # (peaks, points)
    # demodulate every peak to its coarse position; then one steering matrix serves all peaks
    x = x * np.exp(-2j * np.pi * coarse[:, None, None] * idx[None, None, :] / n)
    steer = np.exp(-2j * np.pi * idx[:, None] * offsets[None, :] / n)               # (samples, points)
    p_, c_, s_ = x.shape
    power = (np.abs(x.reshape(p_ * c_, s_) @ steer) ** 2).reshape(p_, c_, points).sum(axis=1)   # (peaks, points)
    k = np.clip(np.argmax(power, axis=1), 1, points - 2)
    rows = np.arange(power.shape[0])
    p_m, p_0, p_p = power[rows, k - 1], power[rows, k], power[rows, k + 1]
    den = p_m - 2.0 * p_0 + p_p
    with np.errstate(divide="ignore", invalid="ignore"):
        delta = np.where(den < 0, 0.5 * (p_m - p_p) / den, 0.0)
    step = offsets[1] - offsets[0]
    return f[rows, k] + np.clip(delta, -1.0, 1.0) * step
