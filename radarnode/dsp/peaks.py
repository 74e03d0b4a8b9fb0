"""Peak grouping and sub-bin interpolation on a range–Doppler power map."""

from __future__ import annotations

import functools
import itertools
import math

import numpy as np


_TINY = np.finfo(np.float64).tiny


def _clamp(x, lo, hi):
    """``np.clip(x, lo, hi)`` for lo ≤ hi (NaN stays NaN), two ufuncs without np.clip's Python-level wrappers: the
    fits' loops clamp some 500 times a frame."""
    return np.minimum(np.maximum(x, lo), hi)


def local_maxima(power: np.ndarray, mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Cells of ``mask`` that are the maximum of their 3×3 neighbourhood (both axes wrap: both FFTs are circular).

    Only the masked cells (the CFAR's few hundred) are compared with their eight neighbours.
    Returns (doppler_index, range_index), each of shape (n,), in row-major order.
    """
    d, r = np.nonzero(mask)
    if d.size == 0:
        return d, r
    m, n = power.shape
    centre = power[d, r]
    peak = np.ones(d.size, dtype=bool)
    for dd in (-1, 0, 1):                      # eight neighbours, not a loop over cells
        for dr in (-1, 0, 1):
            if dd or dr:
                peak &= centre >= power[(d + dd) % m, (r + dr) % n]
    return d[peak], r[peak]


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
    tiny = _TINY
    right = p_p >= p_m
    alpha = np.sqrt(np.where(right, p_p, p_m) / np.maximum(p_0, tiny))
    delta = _clamp((2.0 * alpha - 1.0) / (alpha + 1.0), 0.0, 0.5)
    return np.where(right, delta, -delta)


def _log_parabola(p_m, p_0, p_p):
    tiny = _TINY
    a_m, a_0, a_p = (np.log(np.maximum(x, tiny)) for x in (p_m, p_0, p_p))
    den = a_m - 2.0 * a_0 + a_p
    with np.errstate(divide="ignore", invalid="ignore"):
        delta = np.where(den < 0, 0.5 * (a_m - a_p) / den, 0.0)
    return _clamp(delta, -0.5, 0.5)


class _PatchAxis:
    """One axis of :class:`PatchFit`: the window's spectrum in closed form and the noise's correlation."""

    def __init__(self, window: np.ndarray, max_half: int) -> None:
        from radarnode.dsp.detection_stats import noise_correlation

        w = np.asarray(window, dtype=np.float64)
        L = self.length = w.size
        spec = np.fft.fft(w)
        # W(u) = (1/L)·Σ_k ŵ[k]·D(u − k), D the Dirichlet kernel: a cosine-sum window (all of
        # radarnode.dsp.spectra.WINDOWS) has a few DFT terms ŵ[k]; any other window keeps all of them (exact, slower)
        keep = np.abs(spec) > 1e-12 * np.abs(spec).max()
        k = np.arange(L)
        self.terms_k = np.where(k > L // 2, k - L, k)[keep].astype(np.int64)
        self.terms_c = spec[keep] / L
        self.max_half = max_half
        self.reach = int(np.abs(self.terms_k).max())
        # D(q − δ) = e^{−iπ(q−δ)(L−1)/L}·sin(π(q−δ))/sin(π(q−δ)/L): the factor e^{iπδ(L−1)/L} is common to a
        # template and cancels in the fit; the rest of the phase depends on the integer q only
        q = np.arange(-max_half - self.reach, max_half + self.reach + 1)
        # with q an integer: sin(π(q−δ)) = −(−1)^q·sin(πδ) and sin(π(q−δ)/L) = sin(πq/L)cos(πδ/L) −
        # cos(πq/L)sin(πδ/L), so no transcendental function is evaluated per patch cell
        self._sign = -np.where(q % 2, -1.0, 1.0)
        self._den = np.stack((np.sin(np.pi * q / L), -np.cos(np.pi * q / L)))          # (2, Q)
        # W(i − δ) = Σ_k c_k·D(i − k − δ): term k reads the q = i − k, a slice of the q axis, times c_k·phase(q)
        phase = np.exp(-1j * np.pi * q * (L - 1) / L)
        self._slices = [slice(self.reach - int(t), self.reach - int(t) + 2 * max_half + 1) for t in self.terms_k]
        # the response is then one real product, ratio (…, Q) @ mix (Q, 2J), whose columns hold each patch offset's
        # real and imaginary coefficients side by side (so the product is the complex response's memory)
        mix = np.zeros((q.size, 2 * max_half + 1), dtype=np.complex128)
        cols = np.arange(2 * max_half + 1)
        for c, sl in zip(self.terms_c, self._slices):
            mix[np.arange(sl.start, sl.stop), cols] += c * self._sign[sl] * phase[sl]
        self._mix = np.ascontiguousarray(mix.view(np.float64).reshape(q.size, 2 * (2 * max_half + 1)))
        rho = noise_correlation(w)
        # R⁻¹ of each patch size m ≤ max_half, embedded in the largest patch (zero outside): one batch serves
        # patches of every size, the cells outside a peak's own patch get no weight
        size = 2 * max_half + 1
        self.inverse = np.zeros((max_half + 1, size, size), dtype=np.complex128)
        for m in range(1, max_half + 1):
            lag = np.arange(-m, m + 1)
            corr = rho[(lag[:, None] - lag[None, :]) % L]                        # E[X_i X_l*] / σ²
            sl = slice(max_half - m, max_half + m + 1)
            self.inverse[m, sl, sl] = np.linalg.inv(corr)
        # its real part in its own memory: the fits' products read it (a strided .real view is copied by every
        # product that reads it)
        self.inverse_real = np.ascontiguousarray(self.inverse.real)
        # h^H R⁻¹ h depends only on δ and m: tabulated on a fine grid (linear interpolation moves a fit by
        # < 1e-5 bin), so the search needs R⁻¹ only once per peak, on the data. One product per patch size on its
        # own block of R⁻¹ (a loop over the sizes, not the grid; one einsum over the blocks embedded in the largest
        # took 0.26 s for max_half 12): where R⁻¹ is real (a DFT-even window, every one radarnode.dsp.spectra makes)
        # h^H R⁻¹ h = Re(h)ᵀR⁻¹Re(h) + Im(h)ᵀR⁻¹Im(h), two real products; otherwise (numpy's symmetric np.hanning,
        # a Kaiser window: R Hermitian) the complex one
        self._norm_grid = np.linspace(-self.NORM_SPAN, self.NORM_SPAN, int(2 * self.NORM_SPAN * self.NORM_STEPS) + 1)
        h = self.response(self._norm_grid)                                               # (G, J)
        self._norm = np.zeros((max_half + 1, self._norm_grid.size))                     # (m, G); m = 0: no patch
        for m in range(1, max_half + 1):
            sl = slice(max_half - m, max_half + m + 1)
            block = self.inverse[m, sl, sl]
            if np.any(block.imag):
                self._norm[m] = np.sum((h[:, sl].conj() @ block) * h[:, sl], axis=1).real
                continue
            for part in (h.real[:, sl], h.imag[:, sl]):
                self._norm[m] += np.sum((part @ block.real) * part, axis=1)

    #: the norm table: δ within ±NORM_SPAN bins, NORM_STEPS points a bin
    NORM_SPAN, NORM_STEPS = 1.5, 2048

    def norm(self, delta: np.ndarray, halves: np.ndarray) -> np.ndarray:
        """h^H R⁻¹ h of tones at ``delta`` (shape (K, P)) for patch half-widths ``halves`` (shape (K,))."""
        pos = (np.asarray(delta) + self.NORM_SPAN) * self.NORM_STEPS
        i0 = _clamp(np.floor(pos).astype(np.int64), 0, self._norm.shape[1] - 2)
        frac = pos - i0
        row = self._norm[np.asarray(halves)[:, None], i0]
        nxt = self._norm[np.asarray(halves)[:, None], i0 + 1]
        return row + frac * (nxt - row)

    def response(self, delta: np.ndarray) -> np.ndarray:
        """W(i − δ)·e^{−iπδ(L−1)/L} for the patch offsets i = −max_half…max_half: shape delta.shape + (J,)."""
        L = self.length
        delta = np.asarray(delta, dtype=np.float64)[..., None]
        a = np.pi * delta / L
        # sin(πq/L)cos(a) − cos(πq/L)sin(a), one product (…, 2) @ (2, Q)
        den = (np.concatenate((np.cos(a), np.sin(a)), axis=-1).reshape(-1, 2) @ self._den
               ).reshape(delta.shape[:-1] + (self._den.shape[1],))                        # (..., Q)
        tiny = np.abs(den) < 1e-12
        if tiny.any():
            den[tiny] = 1.0
            ratio = np.sin(np.pi * delta) / den
            ratio[tiny] = float(L) * self._sign[np.nonzero(tiny)[-1]]                  # the limit at q = δ
        else:
            ratio = np.sin(np.pi * delta) / den
        flat = ratio.reshape(-1, ratio.shape[-1]) @ self._mix                            # one product, (…, 2J)
        return flat.view(np.complex128).reshape(ratio.shape[:-1] + (self._mix.shape[1] // 2,))   # (..., J)


#: patch sizes computed together: a peak's patch is embedded in the smallest of these that holds it
PATCH_BUCKETS = (3, 6, 12, 32)
#: PatchFit.refit takes out of a patch the tones of the peaks within this many bins of its edge (a Hann tone's
#: sidelobes 5 bins from its peak are 50 dB down)
REFIT_REACH = 5


@functools.lru_cache(maxsize=16)
def _grid(span: float, points: int) -> np.ndarray:
    """``np.linspace(-span, span, points)``, made once for each of the fits' few search grids (read only)."""
    grid = np.linspace(-span, span, points)
    grid.flags.writeable = False
    return grid


def _patch_axes(doppler_window: np.ndarray, range_window: np.ndarray, max_half: int):
    """(max_half, buckets, {bucket: (Doppler axis, range axis)}) of a patch fit of half-width up to ``max_half``."""
    if not (isinstance(max_half, (int, np.integer)) and 1 <= max_half <= 32):
        raise ValueError(f"max_half: value {max_half!r} is not allowed; expected an integer in 1…32")
    shortest = min(len(doppler_window), len(range_window))
    if 2 * max_half + 1 > shortest:         # a patch longer than the map repeats cells: its noise is singular
        raise ValueError(f"max_half: value {max_half!r} is not allowed for a map of {len(doppler_window)} × "
                         f"{len(range_window)} bins; expected at most {(shortest - 1) // 2} (a patch within the map)")
    buckets = sorted({b for b in PATCH_BUCKETS if b < max_half} | {int(max_half)})
    return int(max_half), buckets, {b: (_patch_axis(doppler_window, b), _patch_axis(range_window, b)) for b in buckets}


def _patch_axis(window: np.ndarray, max_half: int) -> _PatchAxis:
    """The :class:`_PatchAxis` of ``window`` and ``max_half``, built once per process for each window (by its
    values) and half-width: a chain's Doppler and range axes, its patch and migration fits and every chain of the same
    preset share it (it is read only after it is built)."""
    w = np.ascontiguousarray(window, dtype=np.float64)
    return _patch_axis_of(w.tobytes(), int(max_half))


@functools.lru_cache(maxsize=24)          # an axis holds 0.05–0.8 MB up to max_half 12, 3.7 MB at 32
def _patch_axis_of(window_bytes: bytes, max_half: int) -> _PatchAxis:
    return _read_only(_PatchAxis(np.frombuffer(window_bytes, dtype=np.float64), max_half))


def _read_only(obj):
    """``obj`` with its arrays (attributes, and arrays in its list and tuple attributes) made read only: a shared
    table written by mistake raises instead of changing every fit that shares it."""
    for value in vars(obj).values():
        for a in (value if isinstance(value, (list, tuple)) else (value,)):
            for x in (a if isinstance(a, (list, tuple)) else (a,)):
                if isinstance(x, np.ndarray):
                    x.flags.writeable = False
    return obj


def _checked(rd: np.ndarray, d, r, delta_d, delta_r, half, max_half: int):
    """The fits' common arguments as arrays, or a ValueError that names the argument: (d, r, δ_d, δ_r clipped to
    ±1 bin, half-widths (K,) at most ``max_half``)."""
    d, r = np.asarray(d), np.asarray(r)
    if rd.ndim != 3 or d.ndim != 1 or d.shape != r.shape or not (np.issubdtype(d.dtype, np.integer)
                                                                 and np.issubdtype(r.dtype, np.integer)):
        raise ValueError(f"rd, d, r: shapes {rd.shape}, {d.shape}, {r.shape} are not allowed; expected a (channel, "
                         "doppler, range) map and two (K,) integer arrays of peak cells")
    k = d.size
    fd, fr = (np.broadcast_to(np.asarray(x, dtype=np.float64), (k,)) for x in (delta_d, delta_r))
    if not (np.all(np.isfinite(fd)) and np.all(np.isfinite(fr))):
        raise ValueError("delta_d, delta_r: NaN or infinite offsets are not allowed; expected finite bins")
    halves = np.full(k, max_half) if half is None else np.broadcast_to(np.asarray(half), (k,))
    if not np.issubdtype(halves.dtype, np.integer) or np.any(halves < 1):
        raise ValueError(f"half: values {np.unique(halves)[:5]} are not allowed; expected integers of at least 1")
    return d, r, _clamp(fd, -1.0, 1.0), _clamp(fr, -1.0, 1.0), halves


def _call_buckets(buckets, halves: np.ndarray, call_cells: float) -> np.ndarray:
    """The bucket each peak is fitted in: the smallest that holds its patch (half-width ``halves``), or a larger one
    that other peaks' call runs anyway, where that costs less than a call of its own.

    A patch is exact in any larger bucket (R⁻¹ is zero outside its own cells): the fits of :meth:`PatchFit.__call__`,
    :meth:`PatchFit.snapshot` and :class:`MigrationFit` are the same to rounding; :meth:`PatchFit.refit` takes out of
    a joined patch the tones of the neighbours that reach its larger bucket, a few more (3e-7 m on the highway frames,
    up to 6e-4 bin on random maps with the chain's leak reach: an independent tester, 2026-12-07). The cost model,
    measured (``benchmarks/fit_calls.py``): a call costs a fixed ``call_cells`` patch cells' worth of arithmetic, and
    each peak (2b + 1)² cells in bucket b. Of the ways to run the buckets that hold peaks (each either in its own call
    or in the next larger one that runs; at most 2³ ways), the cheapest is taken. ``call_cells`` 0: every bucket in
    its own call; ``inf``: every peak in the largest bucket's call."""
    if not (isinstance(call_cells, (int, float, np.integer, np.floating)) and call_cells >= 0):
        raise ValueError(f"call_cells: value {call_cells!r} is not allowed; expected a number of cells >= 0 (or inf)")
    buckets = np.asarray(buckets)
    bucket = buckets[np.searchsorted(buckets, halves)]
    present, count = np.unique(bucket, return_counts=True)
    if present.size < 2 or call_cells == 0:
        return bucket
    if math.isinf(call_cells):
        return np.full(bucket.shape, present[-1])
    best, runs = math.inf, present
    for mask in itertools.product((False, True), repeat=present.size - 1):
        tried = np.append(present[:-1][list(mask)], present[-1])          # the buckets that run, ascending
        into = tried[np.searchsorted(tried, present)]                     # each present bucket's call
        cost = tried.size * call_cells + float(np.sum(count * (2 * into + 1) ** 2))
        if cost < best:
            best, runs = cost, tried
    return runs[np.searchsorted(runs, bucket)]


def _per_bucket(buckets, halves: np.ndarray, fd: np.ndarray, fr: np.ndarray, channels: int, fit,
                call_cells: float = 0.0):
    """Run ``fit(sel, bucket)`` -> (δ_d, δ_r, snapshot) on the peaks of each patch size bucket (a loop over a few
    sizes; small groups joined to a larger bucket where that is cheaper, :func:`_call_buckets`) and gather the
    results: (δ_d (K,), δ_r (K,), snapshots (K, channels))."""
    out_d, out_r = fd.copy(), fr.copy()
    snap = np.zeros((fd.size, channels), dtype=np.complex128)
    bucket = _call_buckets(buckets, halves, call_cells)
    for b in buckets:
        sel = np.flatnonzero(bucket == b)
        if sel.size:
            out_d[sel], out_r[sel], snap[sel] = fit(sel, b)
    return out_d, out_r, snap


class PatchFit:
    """Maximum-likelihood range and Doppler of single peaks from a patch of the windowed range–Doppler spectrum.

    A windowed FFT keeps every sample's information, but correlates the noise of
    neighbouring bins (Hann: −2/3 one bin apart) and widens the main lobe; the
    three-bin interpolator and a periodogram of one row lose 1.5–2× against the
    Cramér–Rao bound. Over a patch of (2m+1) × (2m+1) cells around the peak the
    fit uses the exact model of one tone in every channel, X_c[i, j] =
    a_c·W_d(i − δ_d)·W_r(j − δ_r), and the exact noise correlation R_d ⊗ R_r
    (the same in every channel): the likelihood, concentrated over the channel
    amplitudes a_c, is Σ_c |g_d^H X_c g_r*|² / (h_d^H g_d · h_r^H g_r) with
    g = R⁻¹h. It separates into one-dimensional searches, done alternately on
    finer grids. The information it leaves outside the patch keeps it above the
    bound: for Hann and m = 12, 1.06–1.09× in RMSE (on-bin worst), from the
    Fisher information of the patch against that of the whole record.

    The channels' complex amplitudes at the optimum, scaled to the noise
    variance of one cell, are the snapshot a beamformer wants: the target's
    energy from the whole patch, not from one windowed cell (which loses the
    window's 1.76 dB per axis and the straddle).

    Parameters
    ----------
    doppler_window, range_window : arrays
        The windows applied before the Doppler and range FFTs (any cosine-sum window is exact and fast).
    max_half : int
        The largest patch half-width m (bins).
    """

    #: alternate searches: (half-span, points) of each round's grid around the current estimate, bins. The last
    #: round's step (1/128 bin) sets what the parabola through the best point and its neighbours leaves: 3e-6 bin
    #: rms on a noise-free tone (a last step of 1/32 bin left 5e-5, 1.7× the bound at ρ = 80 dB); two rounds, the
    #: last of 9 points, cost less than three of 9, 5 and 5 (the fit until 2026-12-07) at the same last step, with
    #: one alternation of the axes fewer: the mimo12 highway frame's processing 6–11 % faster
    #: (``benchmarks/fit_rounds.py``). The price: the second round reaches ±0.04 bin where the old second and third
    #: reached ±0.09, and a fit whose first round ends further off (a start from the three-bin interpolation up to
    #: 0.35 bin away, at 20 dB) stops short — up to 0.047 bin, 1.2× the bound, in a few percent of the chain's fits
    #: (an independent tester): the chain's range 1.19 → 1.22× the bound at 20 dB (``calibration.py --only
    #: accuracy``); on starts near the tone the same RMSE within 0.1 % at 20–80 dB, at 16 dB 0.5 % worse in Doppler
    #: and 3.9 % in range (one common set of trials, ``fit_rounds.py``)
    ROUNDS = ((0.5, 9), (1.0 / 32.0, 9))
    #: … and :meth:`refit`'s, from the first fit's estimates (within a few of its σ: ±0.25 bin reaches 0.1-bin
    #: errors at ρ = 15 dB)
    REFIT_ROUNDS = ((0.25, 5), (1.0 / 32.0, 9))
    #: a call's fixed cost in patch cells (one peak in bucket b costs (2b + 1)², :func:`_call_buckets`): measured
    #: 8,400 (a call 0.31 ms, a cell 0.037 µs; ``benchmarks/fit_calls.py``, 2026-12-07)
    CALL_CELLS = 8000.0

    def __init__(self, doppler_window: np.ndarray, range_window: np.ndarray, max_half: int = 12) -> None:
        self.max_half, self.buckets, self.axes = _patch_axes(doppler_window, range_window, max_half)
        env_d, env_r = sidelobe_envelope(doppler_window), sidelobe_envelope(range_window)
        size = max(env_d.size, env_r.size)
        self.envelope = np.maximum(*(np.pad(e, (0, size - e.size), mode="edge") for e in (env_d, env_r)))

    def leak_reach(self, power: np.ndarray, level: float) -> np.ndarray:
        """How far, in whole bins, the tones of peaks whose cells hold ``power`` (shape (K,)) leak at ``level``
        (the same units) or above on either axis: the number of distances e = 0, 1, … from a peak's cell at which
        the windows' worst-case sidelobe (:func:`sidelobe_envelope`, the worse axis) times that power reaches the
        level. Shape (K,)."""
        cell = np.asarray(power, dtype=np.float64)
        return np.sum(self.envelope[None, :] * cell[:, None] >= level, axis=1).astype(np.int64)

    def __call__(self, rd: np.ndarray, d: np.ndarray, r: np.ndarray, delta_d: np.ndarray, delta_r: np.ndarray,
                 half: np.ndarray | int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fit the peaks at cells (d, r) of ``rd`` (shape (channel, doppler, range); both axes circular).

        Parameters
        ----------
        d, r : int arrays, shape (K,)
            The peak cells.
        delta_d, delta_r : arrays, shape (K,)
            Starting offsets from the peak cells (e.g. :func:`interpolate`), bins.
        half : int or int array of shape (K,), optional
            Patch half-width per peak (1…max_half; smaller where another peak is near). Default max_half.

        Returns
        -------
        (delta_d, delta_r, snapshot): offsets from the peak cells in bins (within ±1), shape (K,), and the
        channels' amplitudes, shape (K, channel), scaled so that the noise in each has the variance of one
        cell (their common phase is arbitrary).
        """
        d, r, fd, fr, halves = _checked(rd, d, r, delta_d, delta_r, half, self.max_half)
        k = d.size
        if k == 0:
            return fd, fr, np.zeros((0, rd.shape[0]), dtype=np.complex128)
        if np.any(halves > self.max_half):
            raise ValueError(f"half: values must lie in 1…{self.max_half}")
        return _per_bucket(self.buckets, halves, fd, fr, rd.shape[0],
                           lambda sel, b: self._fit(rd, d[sel], r[sel], fd[sel], fr[sel], halves[sel], *self.axes[b]),
                           self.CALL_CELLS)

    def refit(self, rd: np.ndarray, d: np.ndarray, r: np.ndarray, delta_d: np.ndarray, delta_r: np.ndarray,
              snapshot: np.ndarray, half: np.ndarray, which: np.ndarray, new_half: np.ndarray,
              reach: np.ndarray | None = None, rounds: tuple | None = None, store: PatchStore | None = None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fit the peaks ``which`` of a first fit again over larger patches, every other peak's fitted tone taken
        out of them.

        A patch that ends 3 bins short of the nearest other peak (:func:`patch_halves`) is small where peaks
        crowd: with a neighbour 3–6 bins away the fit keeps half-widths of 1–3 and loses 1.5–2.2× against the
        bound in range. Here each of the first fit's peaks — (``d``, ``r``) + (``delta_d``, ``delta_r``), its
        ``snapshot`` as :meth:`__call__` returned it for its patch half-width ``half`` — is a tone a_c·W_d·W_r
        whose channel amplitudes are the snapshot over √(h^H R⁻¹ h) of each axis; the tones of the other peaks
        within ``REFIT_REACH`` bins of a patch, or within their own ``reach`` (shape (K,), e.g. :meth:`leak_reach`:
        a strong tone's sidelobes reach further), are subtracted from it, and the peak is fitted on what is left
        with half-width ``new_half``, searched on ``rounds`` (default ``REFIT_ROUNDS``; ``ROUNDS``, the first fit's,
        for a start further off). ``store``: a :class:`PatchStore` of ``rd`` and these peaks, which cuts each patch
        once for every call that shares it (the same results). Returns (δ_d, δ_r, snapshot) of the peaks ``which``,
        as :meth:`__call__`.
        """
        d, r, fd, fr, halves = _checked(rd, d, r, delta_d, delta_r, half, self.max_half)
        if store is not None and not store.holds(rd, d, r):
            raise ValueError("store: a PatchStore of another map or other peaks is not allowed; expected one made "
                             "with this rd, d and r")
        which = np.asarray(which, dtype=np.int64)
        new = np.broadcast_to(np.asarray(new_half), which.shape)
        if which.size == 0:
            return np.zeros(0), np.zeros(0), np.zeros((0, rd.shape[0]), dtype=np.complex128)
        if np.any(new < 1) or np.any(new > self.max_half):
            raise ValueError(f"new_half: values must lie in 1…{self.max_half}")
        big_d, big_r = self.axes[self.max_half]
        amp = np.asarray(snapshot) / np.sqrt(big_d.norm(fd[:, None], halves) * big_r.norm(fr[:, None], halves))
        rows, cols = rd.shape[1], rd.shape[2]
        far = np.full(d.size, REFIT_REACH) if reach is None else np.maximum(np.broadcast_to(reach, d.shape),
                                                                              REFIT_REACH)

        def fit(sel, b):
            axis_d, axis_r = self.axes[b]
            p = which[sel]
            x = _patches(rd, d[p], r[p], b, (1, 2, 0, 3)) if store is None else store.take(p, b)   # (S, J_d, C, J_r)
            key = (b, p.tobytes(), far.tobytes())
            pairs = None if store is None else store.pairs.get(key)
            if pairs is None:
                # the other peaks near enough to reach the patch: pairs (patch, peak), circular distances in bins
                dd = (d[None, :] - d[p][:, None] + rows // 2) % rows - rows // 2
                dr = (r[None, :] - r[p][:, None] + cols // 2) % cols - cols // 2
                near = np.maximum(np.abs(dd), np.abs(dr)) <= b + far[None, :]
                near[np.arange(p.size), p] = False
                i, q = np.nonzero(near)
                # each patch's neighbours go in slots, padded with zeros to the most any patch of the call has
                count = np.bincount(i, minlength=p.size)
                slot = np.arange(i.size) - np.repeat(np.cumsum(count) - count, count)     # i is sorted
                pairs = (i, q, slot, dd[i, q], dr[i, q], int(count.max(initial=0)))
                if store is not None:
                    store.pairs[key] = pairs
            i, q, slot, dd, dr, most = pairs
            if i.size:
                # W(i − δ) at the patch's offsets from the patch's cell: the axes' response() carries the factor
                # e^{−iπδ(L−1)/L} of the tone's own offset, so a tone Δ whole bins away gets e^{iπΔ(L−1)/L}
                ld, lr = axis_d.length, axis_r.length
                wd = axis_d.response(dd + fd[q]) * np.exp(1j * np.pi * dd * (ld - 1) / ld)[:, None]
                wr = axis_r.response(dr + fr[q]) * np.exp(1j * np.pi * dr * (lr - 1) / lr)[:, None]
                # the patch's tones Σ_n wd_n ⊗ a_n ⊗ wr_n are not formed (J_d·C·J_r values a neighbour, the bulk of a
                # refit's arithmetic): the fit reads a patch only through its collapses on a template of one axis,
                # and a tone's collapse is its amplitudes times one inner product (PatchFit._fit_patches)
                shape = (p.size, most)
                w_pad = np.zeros(shape + (wd.shape[1],), dtype=np.complex128)
                a_pad = np.zeros(shape + (amp.shape[1],), dtype=np.complex128)
                r_pad = np.zeros(shape + (wr.shape[1],), dtype=np.complex128)
                w_pad[i, slot], a_pad[i, slot], r_pad[i, slot] = wd, amp[q], wr
                tones = (w_pad, a_pad, r_pad)
            else:
                tones = None
            return self._fit_patches(x, fd[p], fr[p], new[sel], axis_d, axis_r,
                                     self.REFIT_ROUNDS if rounds is None else rounds, tones)

        return _per_bucket(self.buckets, new, fd[which], fr[which], rd.shape[0], fit, self.CALL_CELLS)

    def snapshot(self, rd: np.ndarray, d: np.ndarray, r: np.ndarray, delta_d: np.ndarray, delta_r: np.ndarray,
                 half: np.ndarray | int | None = None) -> np.ndarray:
        """The channels' amplitudes of tones at (``d``, ``r``) + (``delta_d``, ``delta_r``), fitted over patches of
        half-width ``half`` without a search: the snapshot :meth:`__call__` returns for those offsets, shape
        (K, channel)."""
        d, r, fd, fr, halves = _checked(rd, d, r, delta_d, delta_r, half, self.max_half)
        if np.any(halves > self.max_half):
            raise ValueError(f"half: values must lie in 1…{self.max_half}")
        return _per_bucket(self.buckets, halves, fd, fr, rd.shape[0], lambda sel, b: self._fit_patches(
            _patches(rd, d[sel], r[sel], b, (1, 2, 0, 3)), fd[sel], fr[sel], halves[sel], *self.axes[b],
            rounds=()), self.CALL_CELLS)[2]

    def _fit(self, rd, d, r, fd, fr, halves, axis_d: _PatchAxis, axis_r: _PatchAxis):
        """:meth:`__call__` for peaks whose patches fit in the axes' size."""
        return self._fit_patches(_patches(rd, d, r, axis_d.max_half, (1, 2, 0, 3)), fd, fr, halves, axis_d, axis_r)

    def _fit_patches(self, x, fd, fr, halves, axis_d: _PatchAxis, axis_r: _PatchAxis, rounds=None, tones=None):
        """:meth:`_fit` on the peaks' patches ``x``, shape (K, J_d, C, J_r) (:func:`_patches`' axes (1, 2, 0, 3));
        ``rounds``: the searches' grids (default ``ROUNDS``); ``tones``: (wd, a, wr) of shapes (K, N, J_d), (K, N, C),
        (K, N, J_r), tones Σ_n wd_n ⊗ a_n ⊗ wr_n to take out of each patch (zeros in unused slots), or None."""
        m, k = axis_d.max_half, x.shape[0]
        c, j = x.shape[2], 2 * m + 1
        # one layout, two views: collapsing over Doppler is a (1 × J_d) @ (J_d × C·J_r) product per peak, over range
        # a (J_d·C × J_r) @ (J_r × 1) one
        by_d, by_r = x.reshape(k, j, c * j), x.reshape(k, j * c, j)
        # R⁻¹ is real: its products run on real and imaginary parts side by side (_real_left)
        inv_d, inv_r = axis_d.inverse_real[halves], axis_r.inverse_real[halves]          # (K, J, J)
        if tones is not None:
            t_d, t_a, t_r = tones
            t_a = t_a.transpose(0, 2, 1)                                                 # (K, C, N)

        def over_doppler(g):          # Σ_i conj(g_i)·X_c[i, j] for templates g (K, J_d): (K, C, J_r)
            out = (g[:, None, :].conj() @ by_d).reshape(k, c, j)
            if tones is not None:     # a tone's share: a_c·(g^H wd)·wr_j
                out -= (t_a * (t_d @ g.conj()[:, :, None]).transpose(0, 2, 1)) @ t_r
            return out

        def over_range(g):            # Σ_j conj(g_j)·X_c[i, j] for templates g (K, J_r): (K, C, J_d)
            out = (by_r @ g.conj()[:, :, None]).reshape(k, j, c).transpose(0, 2, 1)
            if tones is not None:     # a tone's share: a_c·(g^H wr)·wd_i
                out = out - (t_a * (t_r @ g.conj()[:, :, None]).transpose(0, 2, 1)) @ t_d
            return out

        gd = _real_left(inv_d, axis_d.response(fd)[:, :, None])[:, :, 0]                # R⁻¹h
        for span, points in self.ROUNDS if rounds is None else rounds:
            grid = _grid(span, points)
            # range with the Doppler template fixed (the patch collapsed over Doppler), then Doppler likewise;
            # u = R⁻¹v once, so each candidate costs its template and one product: Σ_c |h^H u_c|² / h^H R⁻¹ h.
            # Each collapse uses the other axis' best grid template (within half a step of its estimate)
            u = _real_left(inv_r, over_doppler(gd).transpose(0, 2, 1))                   # (K, J_r, C)
            fr, hr = self._search(axis_r, u.transpose(0, 2, 1), fr, grid, halves)
            v = _real_left(inv_d, over_range(_real_left(inv_r, hr[:, :, None])[:, :, 0]).transpose(0, 2, 1))
            fd, hd = self._search(axis_d, v.transpose(0, 2, 1), fd, grid, halves)
            gd = _real_left(inv_d, hd[:, :, None])[:, :, 0]
        # the snapshot with both templates at the final estimates
        v = over_range(_real_left(inv_r, axis_r.response(fr)[:, :, None])[:, :, 0])     # (K, C, J_d)
        gd = _real_left(inv_d, axis_d.response(fd)[:, :, None])[:, :, 0]
        s = (v @ gd[:, :, None].conj())[..., 0]                                          # (K, C)
        nd = axis_d.norm(fd[:, None], halves)
        nr = axis_r.norm(fr[:, None], halves)
        return fd, fr, s / np.sqrt(nd[:, :1] * nr[:, :1])

    @staticmethod
    def _search(axis: _PatchAxis, u: np.ndarray, start: np.ndarray, grid: np.ndarray, halves: np.ndarray
                ) -> np.ndarray:
        """The offset on ``start`` + ``grid`` that maximises Σ_c |h^H u_c|²/h^H R⁻¹ h (u = R⁻¹v), refined by a
        parabola through the best grid point and its neighbours; and the best grid point's template h."""
        cand = _clamp(start[:, None] + grid[None, :], -1.0, 1.0)                   # (K, P)
        h = axis.response(cand)                                                      # (K, P, J)
        s = (h.conj() @ np.swapaxes(u, 1, 2)).view(np.float64)                         # (K, P, 2C): h^H u_c side by side
        obj = np.einsum("kpc,kpc->kp", s, s) / np.maximum(axis.norm(cand, halves), _TINY)
        best = _clamp(np.argmax(obj, axis=1), 1, grid.size - 2)
        rows = np.arange(obj.shape[0])
        o_m, o_0, o_p = obj[rows, best - 1], obj[rows, best], obj[rows, best + 1]
        den = o_m - 2.0 * o_0 + o_p
        with np.errstate(divide="ignore", invalid="ignore"):
            frac = np.where(den < 0, 0.5 * (o_m - o_p) / den, 0.0)
        step = grid[1] - grid[0]
        return _clamp(cand[rows, best] + _clamp(frac, -1.0, 1.0) * step, -1.0, 1.0), h[rows, best]


def patch_halves(d: np.ndarray, r: np.ndarray, which: np.ndarray, shape: tuple[int, int], max_half: int,
                 among: np.ndarray | None = None) -> np.ndarray:
    """Patch half-width for the peaks ``which`` of all peaks (d, r): the patch ends 3 bins short of the
    nearest other peak (its main lobe, ±2 bins for Hann), at least 1 and at most ``max_half``. ``among``: only
    these peaks count as others (default all).

    Distances are Chebyshev, circular on both axes (map ``shape`` = (doppler, range)); shape (len(which),).
    """
    which = np.asarray(which)
    if which.size == 0:
        return np.zeros(0, dtype=np.int64)
    others = np.arange(d.size) if among is None else np.asarray(among, dtype=np.int64)
    if others.size == 0:
        return np.full(which.size, max_half, dtype=np.int64)
    return _clamp(nearest_peak(d, r, which, shape, others) - 3, 1, max_half).astype(np.int64)


def nearest_peak(d: np.ndarray, r: np.ndarray, which: np.ndarray, shape: tuple[int, int],
                 among: np.ndarray | None = None) -> np.ndarray:
    """Distance from each of the peaks ``which`` to the nearest other of the peaks (d, r) (cells or fractional
    positions, bins), Chebyshev, circular on both axes (map ``shape`` = (doppler, range)); ``among``: only these
    count as others (default all); inf where there is none. Shape (len(which),)."""
    others = np.arange(np.size(d)) if among is None else np.asarray(among, dtype=np.int64)
    return _distances(d, r, which, shape, others).min(axis=1, initial=np.inf)


def reached(d: np.ndarray, r: np.ndarray, which: np.ndarray, shape: tuple[int, int], half: np.ndarray,
            reach: np.ndarray, power: np.ndarray | None = None) -> np.ndarray:
    """Whether the patch of half-width ``half`` (shape (len(which),)) around each of the peaks ``which`` comes
    within ``reach`` (shape (len(d),), e.g. :meth:`PatchFit.leak_reach`) of another of the peaks (d, r): its
    nearest cell less than that peak's reach away (Chebyshev, circular). With ``power`` (shape (len(d),)) only the
    peaks of more power than the patch's own count. Shape (len(which),), bool."""
    which = np.asarray(which)
    gap = _distances(d, r, which, shape, np.arange(np.size(d))) - np.asarray(half)[:, None]
    hit = gap < np.asarray(reach)[None, :]
    if power is not None:
        power = np.asarray(power)
        hit &= power[None, :] > power[which][:, None]
    return np.any(hit, axis=1)


def _distances(d, r, which, shape, others) -> np.ndarray:
    """Chebyshev distances, circular on both axes, from the peaks ``which`` to ``others`` (inf to itself)."""
    which = np.asarray(which)
    d, r = np.asarray(d, dtype=np.float64), np.asarray(r, dtype=np.float64)
    m, n = shape
    dd = np.abs(d[which, None] - d[None, others])
    dr = np.abs(r[which, None] - r[None, others])
    dist = np.maximum(np.minimum(dd, m - dd), np.minimum(dr, n - dr))             # (len(which), others)
    dist[which[:, None] == others[None, :]] = np.inf                                 # not itself
    return dist


def sidelobe_envelope(window: np.ndarray, oversample: int = 16) -> np.ndarray:
    """The worst case over a tone's offset f ∈ [−½, ½] from its cell of |W(e + f)|² / |W(f)|², for whole bins
    e = 0 … L/2 from the cell (W the window's spectrum, L its length), made non-increasing in e: how much of a
    peak cell's power a tone leaks e bins away at most (Hann: −14 / −31 / −53 / −72 dB at 2 / 3 / 6 / 12)."""
    w = np.asarray(window, dtype=np.float64)
    size, half = w.size, w.size // 2
    spec = np.abs(np.fft.fft(w, size * oversample)) ** 2                          # |W(k / oversample)|²
    f = np.arange(-(oversample // 2), oversample // 2 + 1)                           # f·oversample
    e = np.arange(half + 1)
    ratio = spec[(e[:, None] * oversample + f[None, :]) % spec.size] / spec[f % spec.size][None, :]
    worst = ratio.max(axis=1)
    return np.maximum.accumulate(worst[::-1])[::-1]


def _tone_table(weights: np.ndarray, reach: float, steps: int) -> tuple[np.ndarray, float]:
    """G(u) = Σ_n weights[n]·e^{j2π·u·n/L} for u on a grid of ``steps`` points a bin over [−reach, reach] (L =
    len(weights); one zero-padded FFT); returns (table, −reach) for :class:`_ShiftTable`."""
    L = weights.size
    full = np.fft.ifft(weights, L * steps) * (L * steps)           # u = k/steps, k = 0 … L·steps − 1
    k = np.arange(-int(np.ceil(reach * steps)), int(np.ceil(reach * steps)) + 2)
    return full[k % full.size], k[0] / steps


class _ShiftTable:
    """A table from :func:`_tone_table` (or several side by side: (U, T)) read at u, u + 1, …, u + J − 1 at once,
    linearly interpolated (about 1e-6 of the peak off). The table is kept by the phase of u within a bin
    (``by_phase[f, k]`` = table[k·steps + f]), with each point's slope to the next, so that the J values of one
    read share one interpolation weight and lie side by side: a read gathers two rows instead of 2·J scattered
    values."""

    def __init__(self, table: np.ndarray, start: float, steps: int) -> None:
        self.start, self.steps = start, steps
        bins = (table.shape[0] - 1) // steps
        by_phase = table[np.arange(bins) * steps + np.arange(steps + 1)[:, None]]       # (steps + 1, bins, ...)
        self.value, self.slope = by_phase[:-1], np.diff(by_phase, axis=0)               # (steps, bins, ...)
        self._windows: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def read(self, u: np.ndarray, length: int) -> np.ndarray:
        """The table at u + 0, 1, …, length − 1 (u within its reach): shape u.shape + table.shape[1:] + (length,)."""
        win = self._windows.get(length)
        if win is None:                            # (steps, k, ..., J): views, made once per length
            win = self._windows[length] = tuple(np.lib.stride_tricks.sliding_window_view(t, length, axis=1)
                                                for t in (self.value, self.slope))
        pos = (u - self.start) * self.steps
        if pos.size and not (pos.min() >= 0.0 and pos.max() < win[0].shape[1] * self.steps):    # (NaN: refused)
            raise ValueError(f"u: values from {self.start:g} to {self.start + win[0].shape[1] - 1 / self.steps:g} "
                             f"are allowed for windows of {length}; got {np.min(u):g} … {np.max(u):g}")
        i0 = pos.astype(np.intp)
        frac = pos - i0
        k, f = np.divmod(i0, self.steps)
        out = win[1][f, k]
        out *= frac.reshape(frac.shape + (1,) * (win[0].ndim - 2))
        out += win[0][f, k]
        return out


class PatchStore:
    """The patches of peaks (``d``, ``r``) of one map ``rd``, cut once a size, and the pairs (patch, neighbour) of
    :meth:`PatchFit.refit`, found once: its passes fit the same peaks of the same map again, with the same
    neighbours (cutting the patches was a tenth of a refit on the post-lined highway, copying them for each pass
    another). The patches are handed out read only, the same array to every call that asks for the same peaks; the
    map must not change while the store is in use."""

    def __init__(self, rd: np.ndarray, d: np.ndarray, r: np.ndarray) -> None:
        self.rd, self.d, self.r = rd, np.asarray(d), np.asarray(r)
        self._cut: dict[int, tuple[np.ndarray, np.ndarray]] = {}      # half-width -> (patches, which are cut)
        self._given: dict[tuple, np.ndarray] = {}                     # (half-width, peaks) -> their patches
        self.pairs: dict[tuple, tuple] = {}                           # PatchFit.refit's pairs, by its key

    def holds(self, rd: np.ndarray, d: np.ndarray, r: np.ndarray) -> bool:
        """Whether this is the store of map ``rd`` and peaks (``d``, ``r``)."""
        return rd is self.rd and np.array_equal(d, self.d) and np.array_equal(r, self.r)

    def take(self, which: np.ndarray, m: int) -> np.ndarray:
        """The (2m + 1) × (2m + 1) patches of the peaks ``which``, as :func:`_patches` with axes (1, 2, 0, 3): shape
        (len(which), J_d, channel, J_r), read only (shared by every call for the same peaks and size)."""
        which = np.asarray(which, dtype=np.int64)
        key = (m, which.tobytes())
        given = self._given.get(key)
        if given is not None:
            return given
        got = self._cut.get(m)
        if got is None:                 # rows only written where a peak is cut: the rest of the memory stays untouched
            j = 2 * m + 1
            got = self._cut[m] = (np.empty((self.d.size, j, self.rd.shape[0], j), dtype=np.complex128),
                                  np.zeros(self.d.size, dtype=bool))
        cut, done = got
        need = np.unique(which[~done[which]])
        if need.size:
            cut[need] = _patches(self.rd, self.d[need], self.r[need], m, (1, 2, 0, 3))
            done[need] = True
        given = self._given[key] = cut[which]
        given.flags.writeable = False
        return given


def _patches(rd: np.ndarray, d: np.ndarray, r: np.ndarray, m: int, axes: tuple[int, ...] = (1, 0, 2, 3)
             ) -> np.ndarray:
    """The (2m + 1) × (2m + 1) cells around each peak (d, r) of ``rd`` (channel, doppler, range; both axes
    circular), complex128, with the axes (channel, peak, Doppler offset, range offset) in the order ``axes``
    (default (K, C, J_d, J_r)). One ``take`` over the flattened map, then one copy into place (a fancy index on
    the three axes costs several times more)."""
    c, rows, cols = rd.shape
    step = np.arange(-m, m + 1)
    di = (np.asarray(d)[:, None] + step) % rows
    ri = (np.asarray(r)[:, None] + step) % cols
    flat = (di[:, :, None] * cols + ri[:, None, :]).ravel()
    x = np.take(rd.reshape(c, rows * cols), flat, axis=1).reshape(c, d.size, 2 * m + 1, 2 * m + 1).transpose(axes)
    out = np.empty(x.shape, dtype=np.complex128)
    out[...] = x
    return out


def _real_left(m: np.ndarray, z: np.ndarray) -> np.ndarray:
    """``m @ z`` for a real ``m`` (..., J, J) and a complex ``z`` (..., J, P): one real product on z's real and
    imaginary parts side by side (a complex product would multiply m's zero imaginary part too)."""
    z = np.ascontiguousarray(z, dtype=np.complex128)
    return (m @ z.view(np.float64)).view(np.complex128)


@functools.lru_cache(maxsize=4)      # a pair of tables: 16 MB at max_half 12, 36 MB at 32; a few presets at once
def _migration_tables(doppler_bytes: bytes, range_bytes: bytes, max_half: int, order: int, steps: int,
                      max_migration: float) -> tuple[np.ndarray, _ShiftTable, _ShiftTable]:
    """:class:`MigrationFit`'s Chebyshev nodes and its Doppler and range tables, built once per process for each
    pair of windows (by their values) and half-width (eight FFTs of L·steps points: about 0.2 s; read only after)."""
    wd, wr = np.frombuffer(doppler_bytes, dtype=np.float64), np.frombuffer(range_bytes, dtype=np.float64)
    M = wd.size
    q = np.arange(order)
    nodes = 0.5 * np.cos(np.pi * (2 * q + 1) / (2 * order))                             # Chebyshev, in [−½, ½]
    s = (np.arange(M) - M / 2) / M
    # Lagrange basis L_q(s_m), shape (M, order)
    basis = np.ones((M, order))
    for a in range(order):
        for b in range(order):
            if a != b:
                basis[:, a] *= (s - nodes[b]) / (nodes[a] - nodes[b])
    reach = max_half + 2.0 + max_migration / 2.0
    # the Doppler tables side by side, (U, order): one lookup gathers every term of a cell
    tables = [_tone_table(wd * basis[:, a], reach, steps) for a in range(order)]
    doppler = _ShiftTable(np.stack([t for t, _ in tables], axis=1), tables[0][1], steps)
    nodes.flags.writeable = False
    return nodes, _read_only(doppler), _read_only(_ShiftTable(*_tone_table(wr, reach + max_migration / 2.0, steps),
                                                              steps))


class MigrationFit:
    """The patch fit for a target that moves across range bins during the frame (range migration).

    A target at radial speed v moves μ = v·T_frame/Δr range bins during a
    frame of M chirps: chirp m sees the beat at δ_r + μ·s_m bins from the peak
    cell, s_m = (m − M/2)/M (so δ_r is the beat at mid-frame, where the chain's
    coupling correction puts the range). The response on the patch is then
    X_c[i, j] = a_c·Σ_m w_d[m]·e^{j2π(δ_d − i)m/M}·G_r(δ_r − j + μ·s_m), no
    longer one Doppler response times one range response (δ_d: the Doppler of
    the chirps' phase at mid-chirp, as the separable fit and the chain's speed
    have it). Without its turning phase (a Doppler shift), G_r(δ_r − j + μ·s)
    is smooth over the frame (μ·s spans a bin or two), so Chebyshev
    interpolation at ``ORDER`` nodes s_q makes the response
    Σ_q A_q(δ_d − i)·G_r(δ_r − j + μ·s_q)·e^{−jπμ·s_q(N−1)/N}, with A_q the
    Doppler response of the window times the q-th Lagrange basis polynomial:
    a sum of ORDER separable terms, each tabulated once. Its error against the
    response computed sample by sample: 2e-7 of its norm at μ = 0.5 bin, 1e-5
    at 1.5, 1.3e-3 at 3 (MAX_MIGRATION). The fit maximises the same
    concentrated likelihood as :class:`PatchFit` (channel amplitudes out,
    noise correlation R_d ⊗ R_r whitened), by Newton steps on a 3 × 3 grid
    from the separable fit's estimate (:meth:`_newton`), at a μ the caller
    knows (the chain knows it beyond the alias speed from the TDM wrap count,
    up to two alias numbers, between which the fit chooses).

    Parameters
    ----------
    doppler_window, range_window : arrays
        The windows applied before the Doppler and range FFTs.
    max_half : int
        The largest patch half-width (bins): a patch of (2·max_half + 1)² cells; a larger one is cut to it.
    """

    ORDER = 7
    #: table points a bin
    STEPS = 2048
    #: the largest |μ| fitted (bins over the frame): 171 m/s on mimo12
    MAX_MIGRATION = 3.0
    #: Newton steps on a 3 × 3 grid (:meth:`_newton`): the grid step starts at NEWTON_STEP[0] bin and shrinks by
    #: NEWTON_SHRINK after each step within half of it, until it is below NEWTON_STEP[1], in at most
    #: NEWTON_ITERATIONS steps of at most NEWTON_REACH grid steps each (a peak that has converged costs nothing)
    NEWTON_STEP, NEWTON_SHRINK, NEWTON_ITERATIONS, NEWTON_REACH = (1.0 / 16.0, 1.0 / 512.0), 8.0, 12, 2.0
    #: the widest grid step (bins) a search far from the peak grows to
    NEWTON_WIDEST = 0.25
    #: a call's fixed cost in patch cells (:func:`_call_buckets`): measured 3,400–3,700 (a call 1.3 ms, its Newton
    #: loop's steps; a cell 0.34–0.37 µs; ``benchmarks/fit_calls.py``, 2026-12-07)
    CALL_CELLS = 3000.0

    def __init__(self, doppler_window: np.ndarray, range_window: np.ndarray, max_half: int = 12) -> None:
        # patches embedded in the smallest bucket that holds them, as PatchFit does
        self.max_half, self.buckets, self.axes = _patch_axes(doppler_window, range_window, max_half)
        wd = np.ascontiguousarray(doppler_window, dtype=np.float64)
        wr = np.ascontiguousarray(range_window, dtype=np.float64)
        self.nodes, self._doppler, self._range = _migration_tables(wd.tobytes(), wr.tobytes(), self.max_half,
                                                                   self.ORDER, self.STEPS, self.MAX_MIGRATION)
        # δ_d is the Doppler of the phase at the chirp's middle in time, sample N/2, where the chain's speed takes
        # λ (mid-sweep): the range terms carry the turning phase of the window's centre, sample (N − 1)/2, less
        # that of sample N/2 (taken at (N − 1)/2, δ_d was μ/2N bins off: 0.6 mm/s at 70 m/s on mimo12, against
        # the exact time-domain cube; 5e-6 bins now)
        self._centre = 0.5

    def _doppler_terms(self, fd: np.ndarray, off: np.ndarray) -> np.ndarray:
        """A_q(δ_d − i) for offsets ``fd`` (K,) or (K, I) and the patch offsets ``off`` (J,: −m … m): shape
        (K, J, ORDER) or (K, J, I, ORDER) (the patch axis second: each peak's product with R⁻¹ is then one matrix
        product)."""
        fd = np.asarray(fd)
        t = self._doppler.read(fd + off[0], off.size)[..., ::-1]          # (K, [I,] Q, J): δ_d − m … δ_d + m read
        return np.moveaxis(t, -1, 1)

    def _range_terms(self, fr: np.ndarray, mu: np.ndarray, off: np.ndarray) -> np.ndarray:
        """G_r(δ_r − j + μ·s_q)·e^{−jπμ·s_q} for ``fr`` (K,) or (K, P) and ``mu`` of the same shape (or (K, 1)),
        patch offsets ``off`` (J,: −m … m): shape (K, J, ORDER) or (K, J, P, ORDER). G_r(u) is e^{jπu(N−1)/N} times
        a smooth real kernel: the phase that turns with the migrating beat is a Doppler shift (the chirps' phase at
        their middle in time, sample N/2, runs μ/2 bins ahead of that at their first sample), so it is taken out of
        the terms the Chebyshev nodes interpolate over s (but for e^{−jπμ·s/N}, smooth), and δ_d is the Doppler at
        mid-chirp, which the separable fit and the chain's speed (λ at mid-sweep) measure."""
        fr = np.asarray(fr)
        mu = np.asarray(mu)[..., None]                                                   # (K, [P,] 1)
        t = self._range.read(fr[..., None] + off[0] + mu * self.nodes, off.size)       # (K, [P,] Q, J), a new array
        t *= np.exp(-2j * np.pi * self._centre * mu * self.nodes)[..., None]
        return np.moveaxis(t[..., ::-1], -1, 1)

    def __call__(self, rd: np.ndarray, d: np.ndarray, r: np.ndarray, delta_d: np.ndarray, delta_r: np.ndarray,
                 mu: np.ndarray, half: np.ndarray | int | None = None, channels: np.ndarray | None = None,
                 chosen: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fit the peaks at cells (d, r) of ``rd`` (channel, doppler, range) that migrate by ``mu`` bins over the
        frame (|μ| ≤ MAX_MIGRATION), from the offsets ``delta_d``, ``delta_r`` (e.g. the separable fit's), on
        patches of half-width ``half`` (at most ``max_half``). Returns (delta_d, delta_r, snapshot) as
        :meth:`PatchFit.__call__` does.

        ``mu``: shape (K,), each peak's migration; or (K, H), each peak's candidate migrations (NaN: none), of
        which the one whose response explains the patch best at the starting offsets is fitted (a wrap count
        that the TDM phase leaves open between two alias numbers).
        ``channels`` (K, C), optional: each peak's channel amplitudes as far as known (the separable fit's
        snapshot). One target's channels are one vector times one template, so the candidates are judged and
        the search runs on the patch projected on that vector (one channel instead of C, C times cheaper; the
        part of the patch it leaves out is the other directions' noise), and only the final snapshot uses every
        channel.
        ``chosen`` (K,) float, optional: filled with the migration each peak was fitted with (of its candidates)."""
        d, r, fd, fr, halves = _checked(rd, d, r, delta_d, delta_r, half, self.max_half)
        k = d.size
        mu = np.asarray(mu, dtype=np.float64)
        if k == 0:
            return fd, fr, np.zeros((0, rd.shape[0]), dtype=np.complex128)
        mu = np.broadcast_to(mu, (k,))[:, None] if mu.ndim < 2 and mu.size in (1, k) else mu
        given = ~np.isnan(mu)
        if mu.ndim != 2 or mu.shape[0] != k or not np.all(np.abs(mu[given]) <= self.MAX_MIGRATION) \
                or not np.all(given.any(axis=1)):
            raise ValueError(f"mu: expected {k} migrations (or rows of candidates, NaN for none, at least one a "
                             f"row) within ±{self.MAX_MIGRATION} bins")
        halves = np.minimum(halves, self.max_half)                   # (a larger patch is cut to the largest)
        if channels is not None and np.shape(channels) != (k, rd.shape[0]):
            raise ValueError(f"channels: shape {np.shape(channels)} is not allowed; expected ({k}, {rd.shape[0]}): "
                             "each peak's amplitude in every channel of rd")
        if chosen is not None and np.shape(chosen) != (k,):
            raise ValueError(f"chosen: shape {np.shape(chosen)} is not allowed; expected ({k},)")
        picked = np.zeros(k) if chosen is None else chosen

        def fit(sel, b):
            fd_, fr_, snap_, picked[sel] = self._fit(rd, d[sel], r[sel], fd[sel], fr[sel], mu[sel], halves[sel],
                                                     *self.axes[b], None if channels is None else channels[sel])
            return fd_, fr_, snap_

        return _per_bucket(self.buckets, halves, fd, fr, rd.shape[0], fit, self.CALL_CELLS)

    def peak_gain(self, delta_d: np.ndarray, delta_r: np.ndarray, mu: np.ndarray) -> np.ndarray:
        """The power of the cell a tone at offsets (``delta_d``, ``delta_r``) from its centre lands in, for a target
        that migrates ``mu`` bins over the frame, over that of a still one at the same offsets: shape (K,), ≤ 1
        about the peak. The energy a migrating peak spreads over its neighbouring range cells, which a
        detector that reads the peak cell and divides the still tone's straddle loss out of it loses (a Hann map, the tone on
        its cell's centre: 0.07 dB at 0.6 bin of migration, 0.26 dB at 1.2, 0.70 dB at 2, 1.51 dB at 3; the same to
        0.001 dB as the peak cell of the windowed FFTs of the migrating tone, sample by sample)."""
        fd = np.asarray(delta_d, dtype=np.float64)
        fr = np.asarray(delta_r, dtype=np.float64)
        mu = np.asarray(mu, dtype=np.float64)
        if fd.size == 0:
            return np.ones(0)
        off = np.zeros(1)
        a = self._doppler_terms(fd, off)[:, 0]                                          # (K, ORDER)
        moving = np.sum(a * self._range_terms(fr, mu, off)[:, 0], axis=1)
        still = np.sum(a * self._range_terms(fr, np.zeros_like(mu), off)[:, 0], axis=1)
        return (moving.real ** 2 + moving.imag ** 2) / np.maximum(still.real ** 2 + still.imag ** 2, _TINY)

    def _fit(self, rd, d, r, fd, fr, mu, halves, axis_d: _PatchAxis, axis_r: _PatchAxis, channels=None):
        k, m = d.size, axis_d.max_half
        off = np.arange(-m, m + 1, dtype=np.float64)
        x_all = _patches(rd, d, r, m)                                                    # (K, C, J_d, J_r)
        # R⁻¹ is real (the noise correlation of a real window): products with it run on the real and imaginary
        # parts side by side (_real_left), half the arithmetic of a complex product
        inv_d, inv_r = axis_d.inverse_real[halves], axis_r.inverse_real[halves]          # (K, J, J)
        if channels is None:
            x = x_all
        else:                                         # the patch along the channel vector: (K, 1, J_d, J_r)
            u = np.asarray(channels, dtype=np.complex128)
            u = u / np.maximum(np.linalg.norm(u, axis=1, keepdims=True), _TINY)
            x = (u.conj()[:, None, :] @ x_all.reshape(k, x_all.shape[1], -1)).reshape(k, 1, 2 * m + 1, 2 * m + 1)
        # the patches whitened once: Y_c = R_d⁻¹·X_c·R_r⁻¹ (R real and symmetric)
        y = _real_left(inv_d[:, None], x)
        y = _real_left(inv_r[:, None], y.transpose(0, 1, 3, 2)).transpose(0, 1, 3, 2)  # (K, C, J_d, J_r)
        if mu.shape[1] > 1:                           # the candidate that explains the patch best, at the start
            given = ~np.isnan(mu)
            like = self._likelihood(self._doppler_terms(fd[:, None], off),
                                    self._range_terms(fr[:, None], np.where(given, mu, 0.0), off), y, inv_d, inv_r)
            mu = mu[np.arange(k), np.argmax(np.where(given, like[:, 0], -np.inf), axis=1)]
        else:
            mu = mu[:, 0]
        fd, fr = self._newton(y, fd, fr, mu, off, inv_d, inv_r)
        a, b = self._doppler_terms(fd, off), self._range_terms(fr, mu, off)
        ga, gb = _real_left(inv_d, a), _real_left(inv_r, b)
        # <T, X_c> = Σ_ij X_c[i, j]·conj(Σ_q ga[i, q]·gb[j, q]): the whitened template once, then one product a peak
        tmpl = (ga @ gb.transpose(0, 2, 1)).conj()                                       # (K, J_d, J_r)
        num = (x_all.reshape(k, x_all.shape[1], -1) @ tmpl.reshape(k, -1, 1))[..., 0]   # (K, C)
        den = np.einsum("kqr,kqr->k", a.conj().transpose(0, 2, 1) @ ga, b.conj().transpose(0, 2, 1) @ gb).real
        # <T, X_c> = <T, T>·a_c for a noise-free X_c = a_c·T: over √<T, T>, the amplitude with one cell's noise
        return fd, fr, num / np.sqrt(np.maximum(den, _TINY))[:, None], mu

    @staticmethod
    def _likelihood(a, b, y, inv_d, inv_r) -> np.ndarray:
        """The concentrated likelihood Σ_c |<T, X_c>|² / <T, T> of every pair of I Doppler terms ``a`` (n, J, I, Q)
        and P range terms ``b`` (n, J, P, Q) on the whitened patches ``y`` (n, C, J_d, J_r): shape (n, I, P).

        With T = Σ_q a_q·b_qᵀ and Y_c = R_d⁻¹·X_c·R_r⁻¹, <T, X_c> = Σ_q a_q^H·Y_c·conj(b_q) and
        <T, T> = Σ_qq' (a^H R_d⁻¹ a)_qq'·(b^H R_r⁻¹ b)_qq': the pairs cost the terms of I + P offsets, and each
        product is one matrix product a peak."""
        n, j, i, q = a.shape
        p, c = b.shape[2], y.shape[1]
        ga = _real_left(inv_d, a.reshape(n, j, i * q)).reshape(n, j, i, q)
        gb = _real_left(inv_r, b.reshape(n, j, p * q)).reshape(n, j, p, q)
        aa = a.conj().transpose(0, 2, 3, 1) @ ga.transpose(0, 2, 1, 3)                  # (n, I, Q, Q)
        bb = b.conj().transpose(0, 2, 3, 1) @ gb.transpose(0, 2, 1, 3)                  # (n, P, Q, Q)
        den = (aa.reshape(n, i, q * q) @ bb.reshape(n, p, q * q).transpose(0, 2, 1)).real          # (n, I, P)
        z = a.reshape(n, 1, j, i * q).conj().transpose(0, 1, 3, 2) @ y                  # (n, C, I·Q, J_r)
        bq = np.ascontiguousarray(b.conj().transpose(0, 3, 1, 2)).reshape(n, q * j, p)   # (n, Q·J_r, P)
        num = z.reshape(n, c * i, q * j) @ bq                                            # (n, C·I, P)
        like = (num.real ** 2 + num.imag ** 2).reshape(n, c, i, p).sum(axis=1)
        return like / np.maximum(den, _TINY)

    def _newton(self, y, fd, fr, mu, off, inv_d, inv_r):
        """The offsets that maximise the likelihood (:meth:`_likelihood`) of the whitened patches ``y`` (K, C,
        J_d, J_r), from (fd, fr): Newton steps on the quadratic through a 3 × 3 grid around the estimate.

        Migration couples the axes (the likelihood's ridge runs across both), which the grid's cross term sees:
        the step goes along the ridge, where alternate one-axis searches zig-zag. A peak whose quadratic has no
        maximum moves to the best of its nine points, and its grid widens (up to NEWTON_WIDEST) while that point is
        on the grid's edge; its grid shrinks by NEWTON_SHRINK once its step is within half a grid step. A step that
        lowered the likelihood (a noisy, many-peaked likelihood at low SNR) is taken back and the grid halved, so
        that the answer is never less likely than the start."""
        k = y.shape[0]
        three = np.array([-1.0, 0.0, 1.0])
        fd, fr = fd.copy(), fr.copy()
        held = np.full(k, -np.inf)                          # the likelihood at the last point that was not worse …
        kept_d, kept_r = fd.copy(), fr.copy()               # … and that point
        h = np.full(k, self.NEWTON_STEP[0])                 # each peak's grid step
        going = np.arange(k)                                # the peaks still searching (the others cost nothing)
        for _ in range(self.NEWTON_ITERATIONS):
            going = going[h[going] >= self.NEWTON_STEP[1]]
            if not going.size:
                break
            n, g, e_d, e_r = going.size, h[going], fd[going], fr[going]
            cd = _clamp(e_d[:, None] + g[:, None] * three, -1.0, 1.0)                     # (n, 3)
            cr = _clamp(e_r[:, None] + g[:, None] * three, -1.0, 1.0)
            like = self._likelihood(self._doppler_terms(cd, off), self._range_terms(cr, mu[going, None], off),
                                    y[going], inv_d[going], inv_r[going])                # (n, i: Doppler, j: range)
            worse = like[:, 1, 1] < held[going]             # the last step went down: back, on a finer grid
            better = going[~worse]
            held[better], kept_d[better], kept_r[better] = like[~worse, 1, 1], e_d[~worse], e_r[~worse]
            # the quadratic through the nine points (central differences), its maximum within ±reach·h
            gx = (like[:, 2, 1] - like[:, 0, 1]) / (2.0 * g)
            gy = (like[:, 1, 2] - like[:, 1, 0]) / (2.0 * g)
            hxx = (like[:, 2, 1] - 2.0 * like[:, 1, 1] + like[:, 0, 1]) / (g * g)
            hyy = (like[:, 1, 2] - 2.0 * like[:, 1, 1] + like[:, 1, 0]) / (g * g)
            hxy = (like[:, 2, 2] - like[:, 2, 0] - like[:, 0, 2] + like[:, 0, 0]) / (4.0 * g * g)
            det = hxx * hyy - hxy * hxy
            peak = (hxx < 0.0) & (det > 0.0)
            with np.errstate(divide="ignore", invalid="ignore"):
                sx = (hxy * gy - hyy * gx) / det
                sy = (hxy * gx - hxx * gy) / det
            best = np.argmax(like.reshape(n, 9), axis=1)
            best[~peak & (like.reshape(n, 9)[np.arange(n), best] <= like[:, 1, 1])] = 4    # flat (a zero patch): stay
            reach = self.NEWTON_REACH * g
            sx = np.where(peak, _clamp(sx, -reach, reach), (best // 3 - 1) * g)
            sy = np.where(peak, _clamp(sy, -reach, reach), (best % 3 - 1) * g)
            fd[going] = np.where(worse, kept_d[going], _clamp(e_d + sx, -1.0, 1.0))
            fr[going] = np.where(worse, kept_r[going], _clamp(e_r + sy, -1.0, 1.0))
            small = (peak | (best == 4)) & (np.maximum(np.abs(sx), np.abs(sy)) <= 0.5 * g)
            # outside the concave region, uphill to an edge of the grid: the next grid twice as wide (a start half
            # a bin or more off the peak is reached in a few steps instead of one grid step at a time)
            wider = ~peak & (best != 4)
            h[going] = np.where(worse, 0.5 * g, np.where(small, g / self.NEWTON_SHRINK,
                                                         np.where(wider, np.minimum(2.0 * g, self.NEWTON_WIDEST), g)))
        # the last steps, not yet judged: each kept where it is at least as likely as the point before it
        moved = np.flatnonzero((fd != kept_d) | (fr != kept_r))
        if moved.size:
            last = self._likelihood(self._doppler_terms(fd[moved, None], off),
                                    self._range_terms(fr[moved, None], mu[moved, None], off),
                                    y[moved], inv_d[moved], inv_r[moved])[:, 0, 0]
            back = moved[last < held[moved]]
            fd[back], fr[back] = kept_d[back], kept_r[back]
        return fd, fr
