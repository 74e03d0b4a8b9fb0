"""How much of a cell's array snapshot its plane waves leave unexplained, and the angular spread that implies.

A point reflector's snapshot across a uniform linear array is one steering vector: once the sources the angle
search found are fitted out (least squares), only noise is left. A cell holding a reflector that spans an angle —
a bridge deck across the road, a guardrail section, a truck's side — is a sum of many plane waves with random
phases; its apparent angle wanders from frame to frame (glint) over about that span, and part of its energy fits
no single steering vector. The unexplained fraction of the energy, less the noise's expected share, measures
the span: for scatterers spread uniformly over Δs in sin θ about the fitted direction, the expected unexplained
energy over the expected energy is

    1 − (1/N²) Σ_k Σ_l sinc(d·(k − l)·Δs)

(elements k, l at spacing d wavelengths; sinc(x) = sin(πx)/(πx)), which :func:`angular_spread` inverts. One
snapshot's fraction scatters around it: it is large in the fades of the coherent sum, where the apparent angle
wanders most, so the spread read from one snapshot is that snapshot's glint uncertainty. A tracker
uses the span as the measurement's uncertainty across the line of sight, so that one extended reflector stays
one object instead of a new one at every glint.

Pure array functions; shapes are given per function. The same estimator serves the signal chain (on the measured
snapshot) and the detection level (on the snapshot its scatterers sum to), so both levels report the same spread.
"""

from __future__ import annotations

import functools

import numpy as np

#: points of the tabulated expected fraction against the spread (up to its first maximum)
_TABLE_POINTS = 512


def unexplained_fraction(x: np.ndarray, row: np.ndarray, sin_t: np.ndarray, spacing_wl: float,
                         noise_power: float = 0.0) -> np.ndarray:
    """Per snapshot, the fraction of its energy no least-squares combination of its sources explains, less the
    noise's expected share, in [0, 1].

    ``x``: snapshots (n, N); ``row``/``sin_t``: the sources found, (m,) each (row of ``x``, sin θ); a snapshot with
    no source keeps all its energy unexplained. ``noise_power``: per element (the residual of p sources holds
    (N − p)·noise_power of noise on average). Returns shape (n,).
    """
    x = np.atleast_2d(np.asarray(x, dtype=np.complex128))
    n, k_el = x.shape
    row = np.asarray(row, dtype=np.int64)
    sin_t = np.asarray(sin_t, dtype=np.float64)
    total = np.sum(x.real ** 2 + x.imag ** 2, axis=1)
    resid = total.copy()
    count = np.bincount(row, minlength=n)
    elements = np.arange(k_el)
    order = np.argsort(row, kind="stable")
    first = np.concatenate([[0], np.cumsum(count)[:-1]])
    for p in np.unique(count[count > 0]):          # one batch per source count (1 … a handful), not per cell
        cells = np.flatnonzero(count == p)
        src = order[first[cells][:, None] + np.arange(p)[None, :]]                     # (c, p)
        a = np.exp(2j * np.pi * spacing_wl * sin_t[src][:, None, :] * elements[None, :, None])   # (c, N, p)
        if p == 1:        # one source (most cells): aᴴa = N, the residual is ‖x‖² − |aᴴx|²/N
            ax = np.einsum("cn,cn->c", np.conj(a[:, :, 0]), x[cells])
            left = total[cells] - (ax.real ** 2 + ax.imag ** 2) / k_el
        else:
            coef = np.linalg.pinv(a) @ x[cells][:, :, None]                              # (c, p, 1)
            r = x[cells] - (a @ coef)[:, :, 0]
            left = np.sum(r.real ** 2 + r.imag ** 2, axis=1)
        resid[cells] = left - (k_el - p) * noise_power
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where(total > 0.0, resid / np.where(total > 0.0, total, 1.0), 0.0)
    return np.clip(frac, 0.0, 1.0)


@functools.lru_cache(maxsize=16)
def _table(n_elements: int, spacing_wl: float) -> tuple[np.ndarray, np.ndarray]:
    """(spread in sin θ, expected unexplained fraction), ascending, up to the fraction's first maximum."""
    # ΣΣ_{k,l} sinc(d(k−l)Δs) as a sum over the lags, each counted N − |lag| times: O(N) a point (the (N, N) lag
    # matrix a point took 64 GiB for 4096 channels: an independent tester's finding)
    lag = np.arange(-(n_elements - 1), n_elements)
    count = (n_elements - np.abs(lag)).astype(np.float64)
    spread = np.linspace(0.0, 2.0 / (n_elements * spacing_wl), _TABLE_POINTS)
    frac = 1.0 - (np.sinc(spacing_wl * lag[None, :] * spread[:, None]) @ count) / n_elements ** 2
    top = int(np.argmax(frac))
    return spread[: top + 1], np.maximum.accumulate(frac[: top + 1])


def angular_spread(fraction: np.ndarray, n_elements: int, spacing_wl: float) -> np.ndarray:
    """The spread Δs (in sin θ) of a uniform incoherent reflector whose expected unexplained fraction is
    ``fraction`` (any shape; clipped to what an N-element array can tell: about 2/(N·d) at most)."""
    spread, frac = _table(int(n_elements), float(spacing_wl))
    return np.interp(np.asarray(fraction, dtype=np.float64), frac, spread)


def azimuth_spread(fraction: np.ndarray, n_elements: int, spacing_wl: float, azimuth_rad: np.ndarray) -> np.ndarray:
    """The spread of :func:`angular_spread` in azimuth (rad) at ``azimuth_rad``: Δθ ≈ Δs / cos θ (cos θ taken as at
    least 0.05, near endfire)."""
    return angular_spread(fraction, n_elements, spacing_wl) / np.maximum(np.cos(azimuth_rad), 0.05)


__all__ = ["angular_spread", "azimuth_spread", "unexplained_fraction"]
