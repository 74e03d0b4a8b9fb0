"""Direction of arrival over a uniform linear (virtual) array.

One base class, one subclass per algorithm, steering computed once;
``DOA_METHODS`` is the registry. Snapshots have shape (n_detections, n_elements).
"""

from __future__ import annotations

import numpy as np
import scipy.fft

from radarnode.errors import ConfigError


class Doa:
    """Base: a ULA of ``num_elements`` at ``spacing_wl`` wavelengths; estimates sin(azimuth)."""

    name = ""

    def __init__(self, num_elements: int, spacing_wl: float = 0.5) -> None:
        if num_elements < 1:
            raise ConfigError(f"doa num_elements: value {num_elements!r} is not allowed; expected >= 1")
        if not spacing_wl > 0:
            raise ConfigError(f"doa spacing_wl: value {spacing_wl!r} is not allowed; expected > 0")
        self.num_elements = num_elements
        self.spacing_wl = spacing_wl

    def estimate(self, snapshots: np.ndarray) -> np.ndarray:  # pragma: no cover - abstract
        raise NotImplementedError


class FftBeamformer(Doa):
    """Zero-padded FFT beamforming with a log-parabola peak interpolation.

    The spatial frequency of element k is d·sinθ per wavelength, so the FFT
    bin u maps to sinθ = u / (n_fft · d). A Taylor-free (uniform) taper keeps
    the narrowest main lobe, which matters for 4 to 12 elements.
    """

    name = "fft"

    def __init__(self, num_elements: int, spacing_wl: float = 0.5, n_fft: int = 256) -> None:
        super().__init__(num_elements, spacing_wl)
        if n_fft < num_elements:
            raise ConfigError(f"doa n_fft: value {n_fft!r} is not allowed; expected >= num_elements")
        self.n_fft = n_fft
        u = scipy.fft.fftfreq(n_fft)                       # cycles per element
        self.sin_grid = u / spacing_wl
        self.valid = np.abs(self.sin_grid) <= 1.0

    def spectrum(self, snapshots: np.ndarray) -> np.ndarray:
        """|FFT|² of the snapshots along elements: shape (n, n_fft), in FFT bin order."""
        # a source at sinθ has element phase +2π·d·k·sinθ; Σ_k x_k e^{-j2πku/n} peaks at u/n = d·sinθ
        spec = scipy.fft.fft(snapshots, n=self.n_fft, axis=-1)
        return (spec.real ** 2 + spec.imag ** 2)

    def estimate(self, snapshots: np.ndarray) -> np.ndarray:
        snapshots = np.atleast_2d(snapshots)
        p = np.where(self.valid[None, :], self.spectrum(snapshots), 0.0)
        k = np.argmax(p, axis=1)
        return self._refine(p, np.arange(p.shape[0]), k)

    def estimate_peaks(self, snapshots: np.ndarray, floor_db: float = 9.0, noise_power: float | None = None,
                       secondary_snr_db: float = 12.0, max_sources: int = 4
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The sources of each snapshot, strongest first, found one at a time (CLEAN).

        Several sources in one range–Doppler cell (two guardrails at the same
        range, a car beside a truck) come out as several peaks. The strongest
        beam peak is a source; its steering vector, scaled by its least-squares
        amplitude, is taken out of the snapshot and the residual's strongest
        peak is the next candidate: a source when it lies within ``floor_db`` of
        the first and, with ``noise_power`` (per element), ``secondary_snr_db``
        above the beam's noise (K·noise_power). Taking each source out first
        keeps its sidelobes (−13 dB for the uniform taper) and its noise from
        becoming sources of their own, however strong it is; a second source's
        angle is measured on the residual, free of the first one's lobe.

        Returns (row, sin_azimuth, relative_power_db), each of shape (n_peaks,), rows in order.
        """
        x = np.atleast_2d(snapshots).astype(np.complex128)
        n, k_el = x.shape
        elements = np.arange(k_el)
        resid = x.copy()
        idx = np.arange(n)
        top = np.zeros(n)
        rows, sins, pows = [], [], []
        for step in range(max_sources):                       # a loop over sources, not over snapshots
            if idx.size == 0:
                break
            p = np.where(self.valid[None, :], self.spectrum(resid[idx]), 0.0)
            k = np.argmax(p, axis=1)
            pk = p[np.arange(idx.size), k]
            if step == 0:
                top[idx] = pk
                ok = pk > 0
            else:
                ok = (pk >= top[idx] * 10.0 ** (-floor_db / 10.0)) & (pk > 0)
                if noise_power is not None:
                    ok &= pk >= k_el * noise_power * 10.0 ** (secondary_snr_db / 10.0)
            idx, p, k, pk = idx[ok], p[ok], k[ok], pk[ok]
            if idx.size == 0:
                break
            sin_t = self._refine(p, np.arange(idx.size), k)
            steer = np.exp(2j * np.pi * self.spacing_wl * sin_t[:, None] * elements[None, :])
            amp = (steer.conj() * resid[idx]).sum(axis=1) / k_el
            resid[idx] -= amp[:, None] * steer
            rows.append(idx)
            sins.append(sin_t)
            pows.append(pk)
        if not rows:
            return np.zeros(0, dtype=np.int64), np.zeros(0), np.zeros(0)
        row, sin_t, pk = np.concatenate(rows), np.concatenate(sins), np.concatenate(pows)
        order = np.argsort(row, kind="stable")
        row, sin_t, pk = row[order], sin_t[order], pk[order]
        return row, sin_t, 10.0 * np.log10(pk / top[row])

    def _refine(self, p: np.ndarray, rows: np.ndarray, k: np.ndarray) -> np.ndarray:
        n = self.n_fft
        lp = np.log(np.maximum(p, np.finfo(np.float64).tiny))
        a_m, a_0, a_p = lp[rows, (k - 1) % n], lp[rows, k], lp[rows, (k + 1) % n]
        den = a_m - 2 * a_0 + a_p
        with np.errstate(divide="ignore", invalid="ignore"):
            delta = np.clip(np.where(den < 0, 0.5 * (a_m - a_p) / den, 0.0), -0.5, 0.5)
        # spatial frequency is circular: a peak refined past ±½ cycle belongs to the other end (a source at
        # +85° whose peak falls on the −½ bin is still at +85°, never at −90°)
        u = np.mod((k + delta) / n + 0.5, 1.0) - 0.5
        return np.clip(u / self.spacing_wl, -1.0, 1.0)


DOA_METHODS: dict[str, type[Doa]] = {"fft": FftBeamformer}


def make_doa(name: str, num_elements: int, spacing_wl: float = 0.5, **kwargs) -> Doa:
    if name not in DOA_METHODS:
        raise ConfigError(f"doa method: value {name!r} is not allowed; expected one of {', '.join(DOA_METHODS)}")
    return DOA_METHODS[name](num_elements, spacing_wl, **kwargs)
