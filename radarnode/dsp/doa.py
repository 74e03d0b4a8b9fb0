"""Direction of arrival over a uniform linear (virtual) array.

One base class, one subclass per algorithm, steering computed once;
``DOA_METHODS`` is the registry. Snapshots have shape (n_detections, n_elements).

``fft`` is zero-padded beamforming with CLEAN (every angle peak of a cell, strongest first). The other
methods (``capon``, ``music``, ``unitary_music``, ``root_music``, ``esprit``: :mod:`radarnode.dsp.subspace`)
are super-resolution run only where it can change the answer: on the cells whose snapshot one plane wave
does not explain (:class:`SuperResolution`); every other cell keeps the beamformer's estimate.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from radarnode.errors import ConfigError


#: the grid of :meth:`FftBeamformer.explained`'s refined fit: at least this many points a beamwidth (1/N cycles an
#: element)
REFINE_POINTS_PER_BEAM = 16


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


@functools.lru_cache(maxsize=8)
def _steering_table(n_el: int, n_fft: int) -> np.ndarray:
    """e^{2πi·k·b/n_fft} for elements k < ``n_el`` and FFT bins b < ``n_fft``: shape (n_fft, n_el), read only. The
    same expression, element for element, as one evaluated at given bins (bit for bit), made once instead of an
    exponential a wave, element and snapshot at every step of the joint fit."""
    k = np.arange(n_el)
    table = np.exp(2j * np.pi * k[None, :] * np.arange(n_fft)[:, None] / n_fft)
    table.flags.writeable = False
    return table


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
        u = np.fft.fftfreq(n_fft)                          # cycles per element
        self.sin_grid = u / spacing_wl
        self.valid = np.abs(self.sin_grid) <= 1.0

    def spectrum(self, snapshots: np.ndarray, n_fft: int | None = None) -> np.ndarray:
        """|FFT|² of the snapshots along elements: shape (n, n_fft), in FFT bin order (``n_fft``: another grid than
        the beamformer's)."""
        # a source at sinθ has element phase +2π·d·k·sinθ; Σ_k x_k e^{-j2πku/n} peaks at u/n = d·sinθ
        import scipy.fft  # imported when first needed: the object level builds a chain but never beamforms
        spec = scipy.fft.fft(snapshots, n=self.n_fft if n_fft is None else n_fft, axis=-1)
        return (spec.real ** 2 + spec.imag ** 2)

    def explained(self, snapshots: np.ndarray, sources: int = 2, refine: int = 0) -> np.ndarray:
        """The energy of each snapshot that 1, 2, … ``sources`` plane waves explain, found one after another (the
        beam's peak on the FFT grid, its projection taken out, the residual searched again): shape
        snapshots.shape[:-1] + (sources,), cumulative.

        With ``refine`` > 0 each new set of q plane waves is refined by that many passes of alternating projection
        (each wave searched again on what the others, fitted jointly, leave) and its energy is the snapshot's
        projection on them all: the greedy search's first peak sits between sources a beamwidth or two apart and
        its energies fall short by what its misplaced waves miss (three equal sources two beams apart: a third
        short); refined, they are the least-squares fit's on the FFT grid."""
        x = np.array(snapshots, dtype=np.complex128)
        if refine > 0:
            shape = x.shape[:-1]
            return self._explained_refined(x.reshape(-1, x.shape[-1]), sources, refine).reshape(shape + (sources,))
        n_el = x.shape[-1]
        steer = _steering_table(n_el, self.n_fft)
        out = np.zeros(x.shape[:-1] + (sources,))
        total = np.zeros(x.shape[:-1])
        for q in range(sources):
            spec = self.spectrum(x)
            b = np.argmax(spec, axis=-1)
            total = total + np.take_along_axis(spec, b[..., None], axis=-1)[..., 0] / n_el
            out[..., q] = total
            a = steer[b]                                                            # the peak's steering vector
            x = x - a * (np.sum(a.conj() * x, axis=-1, keepdims=True) / n_el)
        return out

    def _explained_refined(self, x: np.ndarray, sources: int, passes: int) -> np.ndarray:
        """:meth:`explained` with alternating projection, snapshots (n, elements): (n, sources). The waves are sought
        on a grid of at least 16 points a beamwidth (:data:`REFINE_POINTS_PER_BEAM`), whatever the array: on the
        beamformer's 256 points a 72-element array has 3.6 a beam, and a wave half a step off loses 6 % of a strong
        source's energy — more than the penalty of a wave, which then decided between hypotheses."""
        n, n_el = x.shape
        rows = np.arange(n)
        n_fft = max(self.n_fft, 1 << int(math.ceil(math.log2(REFINE_POINTS_PER_BEAM * n_el))))
        steer = _steering_table(n_el, n_fft)                                               # (n_fft, elements)

        def fit(bins: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            """The waves at FFT bins ``bins`` (n, q) fitted jointly: the explained energy (n,) and the residual."""
            a = np.ascontiguousarray(steer[bins].transpose(0, 2, 1))                      # (n, elements, q)
            ah = a.conj().transpose(0, 2, 1)
            gram = ah @ a + 1e-9 * n_el * np.eye(bins.shape[1])     # two waves on one bin: a regularised solve
            y = ah @ x[:, :, None]
            c = np.linalg.solve(gram, y)
            return np.real(y.conj().transpose(0, 2, 1) @ c)[:, 0, 0], x - (a @ c)[:, :, 0]

        out = np.zeros((n, sources))
        bins = np.zeros((n, 0), dtype=np.int64)
        resid = x
        for q in range(sources):
            bins = np.concatenate([bins, np.argmax(self.spectrum(resid, n_fft), axis=1)[:, None]], axis=1)
            for _ in range(passes if q else 0):
                for j in range(q + 1):
                    others = np.delete(bins, j, axis=1)
                    bins[rows, j] = np.argmax(self.spectrum(fit(others)[1], n_fft), axis=1)
            out[:, q], resid = fit(bins)
        return out

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


class SuperResolution(FftBeamformer):
    """Beamforming everywhere, a subspace estimator on the cells where more than one source is likely.

    A cell gets super-resolution when its snapshot x is not one plane wave: after the beamformer's
    strongest source is fitted and taken out (its angle refined to the maximum-likelihood one), the
    residual energy ‖r‖² exceeds what noise leaves, ``σ²·χ²₂₍N−1₎/2`` at a false-alarm rate of
    :attr:`GATE_PFA`, and a fraction :attr:`GATE_MIN_FRACTION` of ‖x‖² (the fit's numerical floor at
    very high SNR). Cells where CLEAN already found two or more sources qualify too. There, from the
    one snapshot: spatial smoothing over sub-arrays of Q = round(0.7·N) elements (seed 001) and
    forward–backward averaging (2·(N−Q+1) looks, enough to decorrelate coherent sources), the number
    of sources by MDL (at most :attr:`MAX_SOURCES`), then the estimator; each source's power is its
    least-squares amplitude over the full array. A cell whose count is below two, or whose estimate
    is not resolved, keeps the beamformer's answer: super-resolution never loses a detection.

    ``stats`` counts, over the instance's life, the cells seen and the cells that went through the
    estimator (what gating saves: the estimator costs 0.1–0.4 ms a cell, ``BENCHMARKS.md``).
    ``gate=False`` runs it on every cell (for that comparison).
    """

    GATE_PFA = 1e-3
    GATE_MIN_FRACTION = 1e-3
    MAX_SOURCES = 3

    def __init__(self, num_elements: int, spacing_wl: float = 0.5, n_fft: int = 256, method: str = "music",
                 gate: bool = True) -> None:
        from radarnode.dsp import subspace  # the estimators only where they run: a faster start
        super().__init__(num_elements, spacing_wl, n_fft)
        if method not in subspace.ESTIMATORS:
            raise ConfigError(f"doa method: value {method!r} is not allowed; expected one of "
                              f"{', '.join(['fft', *sorted(subspace.ESTIMATORS)])}")
        if num_elements < 3:
            raise ConfigError(f"doa num_elements: value {num_elements!r} is not allowed for {method}; expected "
                              ">= 3 (super-resolution needs a sub-array of two elements and more)")
        self.name = method
        self.gate = gate
        self.subarray = subspace.default_subarray(num_elements)
        # the residual's energy over σ² is χ² with 2(N−1) degrees of freedom, halved (complex noise)
        import scipy.special  # the super-resolution stage only: a faster start
        self.gate_ratio = float(scipy.special.gammainccinv(num_elements - 1, self.GATE_PFA))
        self.stats = {"cells": 0, "super": 0}

    def _ml_refine(self, x: np.ndarray, sin_t: np.ndarray) -> np.ndarray:
        """Newton steps on |aᴴx|² from the beamformer's interpolated peak (the single-source ML angle)."""
        k = np.arange(self.num_elements)
        u = sin_t.copy()
        for _ in range(3):                                     # a loop over iterations, not over cells
            ph = np.exp(-2j * np.pi * self.spacing_wl * u[:, None] * k[None, :])
            w = 2j * np.pi * self.spacing_wl * k[None, :]
            s0 = (ph * x).sum(axis=1)
            s1 = (-w * ph * x).sum(axis=1)
            s2 = (w * w * ph * x).sum(axis=1)
            g = 2.0 * np.real(np.conj(s0) * s1)                # d|s0|²/du
            h = 2.0 * (np.abs(s1) ** 2 + np.real(np.conj(s0) * s2))
            step = np.where(h < 0, -g / np.where(h < 0, h, -1.0), 0.0)
            u = np.clip(u + np.clip(step, -0.5 / (self.num_elements * self.spacing_wl),
                                    0.5 / (self.num_elements * self.spacing_wl)), -1.0, 1.0)
        return u

    def multi_source(self, snapshots: np.ndarray, noise_power: float | None) -> np.ndarray:
        """(n,) bool: cells whose snapshot one plane wave does not explain (see the class docstring)."""
        from radarnode.dsp import subspace  # the estimators only where they run: a faster start
        x = np.atleast_2d(snapshots).astype(np.complex128)
        if x.shape[0] == 0:
            return np.zeros(0, dtype=bool)
        p = np.where(self.valid[None, :], self.spectrum(x), 0.0)
        u = self._ml_refine(x, self._refine(p, np.arange(x.shape[0]), np.argmax(p, axis=1)))
        a = subspace.steering(self.num_elements, u, self.spacing_wl).T                   # (n, N)
        amp = (np.conj(a) * x).sum(axis=1) / self.num_elements
        resid = np.sum(np.abs(x - amp[:, None] * a) ** 2, axis=1)
        total = np.sum(np.abs(x) ** 2, axis=1)
        floor = self.GATE_MIN_FRACTION * total
        if noise_power is not None and math.isfinite(noise_power) and noise_power > 0:
            floor = np.maximum(floor, self.gate_ratio * noise_power)
        return resid > floor

    def estimate_peaks(self, snapshots: np.ndarray, floor_db: float = 9.0, noise_power: float | None = None,
                       secondary_snr_db: float = 12.0, max_sources: int = 4
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        from radarnode.dsp import subspace  # the estimators only where they run: a faster start
        x = np.atleast_2d(snapshots).astype(np.complex128)
        row, sin_t, rel = super().estimate_peaks(x, floor_db, noise_power, secondary_snr_db, max_sources)
        n = x.shape[0]
        self.stats["cells"] += n
        if n == 0:
            return row, sin_t, rel
        cand = np.ones(n, dtype=bool) if not self.gate else (
            self.multi_source(x, noise_power) | (np.bincount(row, minlength=n) >= 2))
        cells = np.flatnonzero(cand)
        self.stats["super"] += int(cells.size)
        if cells.size == 0:
            return row, sin_t, rel
        k_eff = 2 * (self.num_elements - self.subarray + 1)
        keep = np.ones(row.size, dtype=bool)
        add_rows, add_sin, add_rel = [], [], []
        for c in cells:          # only the gated cells (a few per frame), not every cell
            r = subspace.forward_backward(subspace.spatial_smoothing(subspace.sample_covariance(x[c][:, None]),
                                                                     self.subarray))
            count = min(subspace.mdl(subspace._eigvals_desc(r), k_eff), self.MAX_SOURCES, self.subarray - 1)
            if count < 2:
                continue
            est = subspace.estimate(self.name, x[c], count, self.spacing_wl, fb=True, subarray=self.subarray)
            if not est.all_resolved:
                continue
            a = subspace.steering(self.num_elements, est.sin_theta, self.spacing_wl)          # (N, M)
            amp = np.linalg.lstsq(a, x[c], rcond=None)[0]
            pw = np.abs(amp) ** 2
            ok = pw >= pw.max() * 10.0 ** (-floor_db / 10.0)
            keep &= row != c
            add_rows.append(np.full(int(ok.sum()), c))
            add_sin.append(est.sin_theta[ok])
            add_rel.append(10.0 * np.log10(np.maximum(pw[ok] / pw.max(), 1e-30)))
        if not add_rows:
            return row, sin_t, rel
        row = np.concatenate([row[keep], *add_rows])
        sin_t = np.concatenate([sin_t[keep], *add_sin])
        rel = np.concatenate([rel[keep], *add_rel])
        order = np.argsort(row, kind="stable")
        return row[order], sin_t[order], rel[order]


#: "fft" is beam scanning (Bartlett); the rest are the subspace estimators, as super-resolution
#: (written out, so that importing this module does not import the estimators and scipy.linalg;
#: tests/test_doa_chain.py checks it against radarnode.dsp.subspace.ESTIMATORS)
DOA_METHODS: tuple[str, ...] = ("fft", "capon", "esprit", "music", "root_music", "unitary_music")


def make_doa(name: str, num_elements: int, spacing_wl: float = 0.5, **kwargs) -> Doa:
    """The DOA stage ``name`` (a key of :data:`DOA_METHODS`): ``fft``, or super-resolution with that estimator."""
    if name not in DOA_METHODS:
        raise ConfigError(f"doa method: value {name!r} is not allowed; expected one of {', '.join(DOA_METHODS)}")
    if name == "fft":
        return FftBeamformer(num_elements, spacing_wl, **kwargs)
    return SuperResolution(num_elements, spacing_wl, method=name, **kwargs)
