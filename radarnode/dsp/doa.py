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
                       secondary_snr_db: float = 12.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Every spectral peak within ``floor_db`` of each snapshot's strongest.

        Several sources in one range–Doppler cell (two guardrails at the same
        range, a car beside a truck) come out as several peaks. The floor stays
        above the −13 dB sidelobes of the uniform taper. With ``noise_power``
        (per element), a peak other than the strongest must also stand
        ``secondary_snr_db`` above the beam's noise (K·noise_power): the angle
        spectrum of a noise cell has several peaks within 9 dB, and without
        this test one false alarm would become several detections.

        Returns (row, sin_azimuth, relative_power_db), each of shape (n_peaks,).
        """
        snapshots = np.atleast_2d(snapshots)
        p = np.where(self.valid[None, :], self.spectrum(snapshots), 0.0)
        peak = (p >= np.roll(p, 1, axis=1)) & (p > np.roll(p, -1, axis=1))
        top = p.max(axis=1, keepdims=True)
        strong = peak & (p >= top * 10.0 ** (-floor_db / 10.0)) & (p > 0)
        if noise_power is not None:
            loud = p >= self.num_elements * noise_power * 10.0 ** (secondary_snr_db / 10.0)
            strong &= loud | (p >= top)
        rows, k = np.nonzero(strong)
        rel = 10.0 * np.log10(p[rows, k] / top[rows, 0])
        return rows, self._refine(p, rows, k), rel

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
