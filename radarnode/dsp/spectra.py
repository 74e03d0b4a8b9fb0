"""Windowed range and Doppler FFTs and non-coherent integration.

References
----------
Richards, *Fundamentals of Radar Signal Processing*, 2nd ed., ch. 5 (windows,
straddle loss), ch. 17 (FMCW range–Doppler processing).
"""

from __future__ import annotations

import functools

import numpy as np

from radarnode.errors import ConfigError

#: the windows, as cosine sums w[k] = Σ_j (−1)^j·a_j·cos(2πjk/n) (DFT-even: scipy's ``get_window(…, fftbins=True)``,
#: which tests/test_dsp.py compares them with); a few DFT terms each, which the patch fit uses
WINDOWS = ("hann", "hamming", "blackman", "boxcar", "blackmanharris")
_COSINE_SUMS = {"hann": (0.5, 0.5), "hamming": (0.54, 0.46), "blackman": (0.42, 0.5, 0.08), "boxcar": (1.0,),
                "blackmanharris": (0.35875, 0.48829, 0.14128, 0.01168)}


def circular(x: np.ndarray, period: float) -> np.ndarray:
    """``x`` (bins) wrapped into [−period/2, period/2): an offset on a circular FFT axis of ``period`` bins.

    ``np.mod(x + period/2, period) − period/2``, bit for bit, with the remainder taken only where x + period/2 lies
    outside [0, period): inside, it is that value itself (fmod is exact there, and a zero comes out +0), and numpy's
    floating remainder costs about 9 ns an element, most of the whole (the lobe tests wrap thousands of offsets that
    are already within a period, a few times a cycle)."""
    half = period / 2.0
    y = np.add(x, half)
    if y.size < 64:                           # (a few values: the test below costs more than it saves)
        return np.mod(y, period) - half
    outside = y < 0.0
    outside |= ~(y < period)                  # (NaN and ±inf too: their remainder is NaN, as np.mod gives)
    n = np.count_nonzero(outside)
    if 2 * n > y.size:                        # mostly outside: one pass over all of them is cheaper
        y = np.mod(y, period)
    elif n:
        np.mod(y, period, out=y, where=outside)
    y -= half
    return y


@functools.lru_cache(maxsize=64)
def window(name: str, n: int, dtype: str = "float64") -> np.ndarray:
    """A symmetric-free (DFT-even) window of length ``n``, computed once per (name, n)."""
    if name not in WINDOWS:
        raise ConfigError(f"window: value {name!r} is not allowed; expected one of {', '.join(WINDOWS)}")
    k = np.arange(n)
    w = sum((-1) ** j * a * np.cos(2.0 * np.pi * j * k / n) for j, a in enumerate(_COSINE_SUMS[name]))
    w = np.asarray(w, dtype=np.float64).astype(dtype)
    w.setflags(write=False)
    return w


def range_doppler(cube: np.ndarray, *, range_window: str = "hann", doppler_window: str = "hann",
                  num_range_bins: int | None = None, workers: int = -1) -> np.ndarray:
    """Range FFT over samples, then Doppler FFT over chirps.

    Parameters
    ----------
    cube : complex array, shape (channel, chirp, sample)
    num_range_bins : int, optional
        Keep only the first bins (the rest lie beyond the farthest range of interest).

    Returns
    -------
    complex array, shape (channel, doppler, range); Doppler fftshifted (bin M/2 is zero speed).
    """
    if cube.ndim != 3:
        raise ConfigError(f"cube: shape {cube.shape} is not allowed; expected (channel, chirp, sample)")
    c, m, n = cube.shape
    real = np.float32 if cube.dtype == np.complex64 else np.float64
    x = cube * window(range_window, n, np.dtype(real).name)[None, None, :]
    import scipy.fft  # imported when first needed: the object level never transforms a cube
    x = scipy.fft.fft(x, axis=2, workers=workers, overwrite_x=True)
    if num_range_bins is not None:
        x = x[:, :, :num_range_bins]
    x *= _doppler_weights(doppler_window, m, np.dtype(real).name)[None, :, None]
    return scipy.fft.fft(x, axis=1, workers=workers, overwrite_x=True)


@functools.lru_cache(maxsize=64)
def _doppler_weights(name: str, m: int, dtype: str) -> np.ndarray:
    """The Doppler window times (−1)^m: shifts zero speed to bin M/2 without an fftshift copy (M even)."""
    w = window(name, m, dtype) * np.where(np.arange(m) % 2, -1.0, 1.0).astype(dtype)
    if m % 2:
        raise ConfigError(f"num_chirps: value {m} is not allowed; expected an even number")
    w.setflags(write=False)
    return w


def noncoherent_power(rd: np.ndarray) -> np.ndarray:
    """Sum of |rd|² over channels: (channel, doppler, range) -> (doppler, range), float.

    The real and imaginary parts' squares summed over the channels in one product over the map's memory read as
    reals (contiguous: numpy's vectorised loop; the strided ``.real`` and ``.imag`` views took its scalar one, 2–3×
    the time), each cell's two sums then added: the same sums in the same order, the same values."""
    if not np.iscomplexobj(rd) or rd.ndim != 3:
        return np.einsum("cdr,cdr->dr", rd.real, rd.real) + np.einsum("cdr,cdr->dr", rd.imag, rd.imag)
    c, m, n = rd.shape
    flat = np.ascontiguousarray(rd).view(rd.real.dtype).reshape(c, 2 * m * n)
    parts = np.einsum("cx,cx->x", flat, flat).reshape(m, n, 2)
    return parts[..., 0] + parts[..., 1]
