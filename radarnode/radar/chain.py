"""The signal-level DSP chain: cube -> range–Doppler map -> CFAR -> peaks -> DOA -> detections.

Pure functions of arrays and the preset; the configuration is one frozen
dataclass. The TDM MIMO Doppler phase between transmit slots is removed with
each detection's own Doppler estimate before beamforming.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from radarnode import validate
from radarnode.errors import ConfigError, FieldError, short_repr
from radarnode.dsp.cfar import CFAR_KINDS, make_cfar, ring_problem
from radarnode.dsp.detection_stats import DetectionStatistic, noise_correlation
from radarnode.dsp.doa import DOA_METHODS, make_doa
from radarnode.dsp.peaks import (MigrationFit, PatchFit, PatchStore, interpolate, local_maxima, nearest_peak,
                                 patch_halves, reached)
from radarnode.dsp import spread
from radarnode.dsp.spectra import WINDOWS, noncoherent_power, range_doppler, window
from radarnode.perception.types import Detections
from radarnode.radar import equation, tables
from radarnode.radar.calibration import DOA_FLOOR_DB, DOA_MAX_SOURCES, DOA_SECONDARY_SNR_DB
from radarnode.radar.presets import RadarPreset


@dataclass(frozen=True)
class DspConfig:
    """Signal-chain settings."""

    range_window: str = "hann"
    doppler_window: str = "hann"
    cfar: str = "ca"
    pfa: float = 1e-6
    guard_doppler: int = 2
    guard_range: int = 2
    train_doppler: int = 4
    train_range: int = 8
    doa: str = "fft"
    doa_fft_size: int = 256
    doa_floor_db: float = DOA_FLOOR_DB
    # a cell's second angle peak must stand this far above the beam noise
    doa_secondary_snr_db: float = DOA_SECONDARY_SNR_DB
    range_ml: bool = True          # maximum-likelihood range and Doppler refinement of the strongest peaks
    range_ml_max_peaks: int = 128
    ml_patch_half: int = 12        # its patch: ±12 bins each way where no other peak is near
    #: beyond the alias speed, fit the wrapped peaks again with a range-migrating target's response (TDM presets:
    #: the wrap count from the TDM phase gives the true speed): RMSE near the CRB at 40–70 m/s, at 1.15–1.65× the
    #: frame's cost at 40–70 m/s ego speed (BENCHMARKS.md, benchmarks/migration_fit.py). true, false, or "auto" (the
    #: default): on for complex128 spectra of presets with two transmitters or more, for the peaks that migrate at
    #: least MIGRATION_AUTO_MIN_BINS; off for complex64 ones (the fast setting: with the fit its frames miss the 30 ms
    #: target at 60–70 m/s) and single-transmitter presets
    migration_fit: bool | str = "auto"
    #: a patch cut short by a neighbour fitted again, wider, with the other peaks' tones taken out (PatchFit.refit):
    #: two returns 3–6 bins apart at 1.13–1.33× the CRB in range instead of 1.46–2.25×, at about 1.4× the frame's cost
    #: on the post-lined highway_mimo12 (medians 1.33× and 1.46× over 18 speeds; BENCHMARKS.md, "Signal level at
    #: every ego speed"). true, false, or "auto" (the default): on for complex128 spectra, off for complex64 ones (the
    #: fast setting)
    refit: bool | str = "auto"
    max_detections: int = 1000

    def __post_init__(self) -> None:
        validate.choice("range_window", self.range_window, WINDOWS)
        validate.choice("doppler_window", self.doppler_window, WINDOWS)
        validate.choice("cfar", self.cfar, CFAR_KINDS)
        validate.number("pfa", self.pfa, lo=0.0, hi=0.5, lo_open=True, hi_open=True)
        for f in ("guard_doppler", "guard_range", "train_doppler", "train_range"):
            validate.integer(f, getattr(self, f), lo=0, hi=64)
        validate.choice("doa", self.doa, DOA_METHODS)
        validate.integer("doa_fft_size", self.doa_fft_size, lo=4, hi=1 << 16)
        validate.number("doa_floor_db", self.doa_floor_db, lo=0.0, hi=40.0)
        validate.number("doa_secondary_snr_db", self.doa_secondary_snr_db, lo=0.0, hi=60.0)
        validate.boolean("range_ml", self.range_ml)
        validate.integer("range_ml_max_peaks", self.range_ml_max_peaks, lo=0, hi=10_000)
        validate.integer("ml_patch_half", self.ml_patch_half, lo=1, hi=32)
        if self.migration_fit is not True and self.migration_fit is not False and self.migration_fit != "auto":
            raise FieldError("migration_fit", self.migration_fit, "true, false or auto")
        if self.migration_fit is True and not self.range_ml:
            raise FieldError("migration_fit", self.migration_fit,
                             "false or auto while range_ml is false (the migration fit refines the patch fit's "
                             "peaks)")
        if self.refit is not True and self.refit is not False and self.refit != "auto":
            raise FieldError("refit", self.refit, "true, false or auto")
        if self.refit is True and not self.range_ml:
            raise FieldError("refit", self.refit, "false or auto while range_ml is false (the refit refines the patch "
                             "fit's peaks)")
        validate.integer("max_detections", self.max_detections, lo=1, hi=100_000)


def preset_conflicts(config: DspConfig, preset: RadarPreset) -> list[tuple[str, str, str]]:
    """The options of ``config`` that ``preset`` cannot run, as (field, why, what is allowed): one rule for the
    chain (when it is built), the scenario loader (with the file and line) and the command line's ``--doa``."""
    out = []
    if config.doa != "fft" and preset.num_virtual < 3:
        out.append(("doa", f"{preset.num_virtual} virtual channel(s): super-resolution needs 3 channels or more",
                    "'fft'"))
    if config.migration_fit is True and preset.num_tx < 2:
        out.append(("migration_fit", f"{preset.num_tx} transmitter: the true speed of a wrapped peak comes from the "
                                     "TDM wrap count", "false or auto"))
    # the CFAR ring on this preset's map (its windows' noise correlation): refused when the chain was built, without
    # the file and line (an independent tester's finding)
    corr = (noise_correlation(window(config.doppler_window, preset.num_chirps)),
            noise_correlation(window(config.range_window, preset.num_range_bins)))
    problem = ring_problem((config.guard_doppler, config.guard_range), (config.train_doppler, config.train_range),
                           corr)
    if problem is not None:
        kind, axis, _, allowed = problem
        field = f"{kind}_{'range' if axis == 'both' else axis}"
        out.append((field, f"the CFAR ring (guard_doppler, guard_range) = ({config.guard_doppler}, "
                           f"{config.guard_range}), (train_doppler, train_range) = ({config.train_doppler}, "
                           f"{config.train_range})", allowed))
    return out


@functools.lru_cache(maxsize=16)
def detection_statistic(config: DspConfig, n_channels: int, n_doppler: int, n_range: int) -> DetectionStatistic:
    """The CFAR and detection statistic of a chain (built once per configuration and cube shape)."""
    w_r, w_d = window(config.range_window, n_range), window(config.doppler_window, n_doppler)
    cfar = make_cfar(config.cfar, pfa=config.pfa, guard=(config.guard_doppler, config.guard_range),
                     train=(config.train_doppler, config.train_range), n_channels=n_channels,
                     correlation=(noise_correlation(w_d), noise_correlation(w_r)))
    stat = DetectionStatistic(cfar, w_r, w_d)
    tables.warm(stat)                 # its tables from the disk cache (radarnode.radar.tables), or built and kept
    return stat


#: the largest patch half-width of the migrating fit (radarnode.dsp.peaks.MigrationFit): the separable fit's default;
#: smaller patches lost accuracy (half-widths 3 and 6: 1.5× and 1.3× the CRB in range rate at −70 m/s, measured on
#: an earlier version of the fit)
MIGRATION_HALF = 12
#: passes of the patch fit's refit of crowded peaks (DspChain.process_rd, PatchFit.refit): each takes the others'
#: tones from the pass before out of a peak's wider patch (every refitted peak, every pass); two equal returns
#: 2.0–2.2 bins apart, started from their cells, came to 1.35–1.45× the CRB in range with three, 1.6–2.1× with two
#: (mimo12, ρ = 30 dB, 200 frames)
REFIT_PASSES = 3
#: … and their patch half-width there, at most: measured on two returns 3–6 bins apart, ρ = 30 dB, 200 draws,
#: 1.13–1.33× the CRB in range (one alone 1.09–1.20×); ±12 came to 1.1× at 4–6 bins for twice the cost (it grows
#: as the square)
REFIT_HALF = 6
#: … and a peak whose first fit came within this many bins (Chebyshev) of another's starts its refit again from
#: its cell (DspChain.process_rd): two returns about 2 bins apart whose 3 × 3 fits leaned into each other's lobe.
#: Refitted from where they met they stayed there (3.0–10.8× the CRB in range at 2.0–2.1 bins, mimo12, ρ = 30 dB);
#: left unrefitted, under a 1.5-bin rule before, likewise. With 1.0 here, pairs whose first fits met 1.0–1.2 bins
#: apart stayed 4–11× the bound (an independent tester: 2.0–2.4 bins apart, mimo12 and ars408_like); with 1.5,
#: 0.9–1.3× (mimo12, 100 frames a separation)
REFIT_APART = 1.5
#: … and a peak whose patch another peak's sidelobes reach at this level or above (that peak's cell power summed
#: over the channels times the windows' worst-case sidelobe at the patch's nearest cell, over one channel's noise
#: variance, dB) is refitted too, at its own half-width, with that tone taken out: two equal returns 9–20 bins
#: apart at ρ = 45 dB, whose patches end 3–8 bins short of the other, came to 1.3–2.7× the CRB in range without
#: it, 1.0–1.3× with it (mimo12 and ars408_like, 60 frames); at −20 dB 20 bins apart stayed 1.3–1.4×. A 25-dB return
#: 16 bins from a 60-dB one: 11× without, 1.15× with it
LEAK_REFIT_DB = -30.0
#: a wrap hypothesis is taken where its score (DspChain._wrap_score: the energy one plane wave, or two less a
#: penalty, explain under it, over one channel's noise power: a log-likelihood) beats no wrap's by this much; the
#: margin keeps noise from wrapping weak unaliased targets (a 3σ excursion of the difference). A margin
#: proportional to the beam's power (6/√SNR of it, the rule before) took the wrap in only 0–20 % of the frames at
#: ρ = 20 dB beyond the alias speed: the angle of a wrapped target was wrong (tests/test_ambiguity.py)
WRAP_LL_MARGIN = 9.0
#: a second plane wave counts in a wrap hypothesis' score only for what it explains beyond this (log-likelihood):
#: about what the strongest of the beam's independent looks at noise explains
WRAP_SOURCE_PENALTY = 20.0
#: a cell of which two plane waves, under the hypothesis that explains it best, leave more than this many
#: WRAP_SOURCE_PENALTY (and more than the noise's one σ² a channel plus one penalty) is judged again on up to
#: WRAP_FINE_SOURCES plane waves fitted jointly (DspChain._wrap_score_fine), with WRAP_FINE_PASSES passes of alternating
#: projection: below that a third wave cannot pay its penalty, and the judgement is the two waves'. There was a second
#: gate, two waves explaining less than 93 % of the cell: a third source 4–10 dB below two equal ones passed under it
#: and came out as ghosts (mimo12 at −1.3× the alias speed: 3–5 frames of 20, none judged again in every cell; one or
#: two sources gave the same detections either way, and 1 of 82 highway_cut_in frames changed)
WRAP_FINE_REST_PENALTIES = 2.0
WRAP_FINE_SOURCES, WRAP_FINE_PASSES = 3, 2
#: the margin's growth for a wrap judged on a migrating fit (signal.dsp.migration_fit), log-likelihood
MIGRATION_EXTRA_MARGIN = 3.0
#: migration_fit "auto" fits a wrapped peak only where one of its alias numbers moves it at least this far (range
#: bins over the frame): below it the fit moved the estimates by a median 0.03–0.04 of the CRB (ars408_like, 0.1–0.25
#: bin) and 0.1–0.2 at 0.4 bin, with the same RMSE (benchmarks/migration_fit.py, --threshold-trials); ars408_like
#: migrates 0.25 bin at 70 m/s, so its frames skip the fit's cost; every wrapped mimo12 peak migrates 0.57 bin or more
MIGRATION_AUTO_MIN_BINS = 0.3


class DspChain:
    """Processes cubes of one preset; windows, CFAR and steering are built once."""

    def __init__(self, preset: RadarPreset, config: DspConfig = DspConfig()) -> None:
        self.preset = preset
        self.config = config
        self.statistic = detection_statistic(config, preset.num_virtual, preset.num_chirps, preset.num_range_bins)
        self.cfar = self.statistic.cfar
        conflicts = preset_conflicts(config, preset)
        if conflicts:
            field, why, allowed = conflicts[0]
            raise ConfigError(f"signal.dsp.{field}: value {short_repr(getattr(config, field))} is not allowed with "
                              f"preset {preset.name} ({why}); expected {allowed}")
        self.doa = make_doa(config.doa, preset.num_virtual, preset.element_spacing_wl,
                            n_fft=max(config.doa_fft_size, preset.num_virtual))
        self._tx_of = np.repeat(np.arange(preset.num_tx), preset.num_rx)
        self._patch_fits: dict[tuple[int, int], PatchFit] = {}
        self._migration_fits: dict[tuple[int, int], MigrationFit] = {}

    def migrates(self, dtype) -> bool:
        """Whether spectra of ``dtype`` get the migration fit beyond the alias speed (``DspConfig.migration_fit``:
        "auto" fits complex128 spectra, and only with two transmitters or more, whose wrap count gives the true
        speed; of those, the peaks that migrate at least MIGRATION_AUTO_MIN_BINS)."""
        mode = self.config.migration_fit
        if mode == "auto":
            return self.config.range_ml and self.preset.num_tx > 1 and np.dtype(dtype) == np.complex128
        return bool(mode)

    def _patch_fit(self, m: int, n: int) -> PatchFit:
        """The patch fit for maps of m Doppler × n range bins (built once per shape)."""
        if (m, n) not in self._patch_fits:
            cfg = self.config
            half = min(cfg.ml_patch_half, (min(m, n) - 1) // 2)
            self._patch_fits[(m, n)] = PatchFit(window(cfg.doppler_window, m), window(cfg.range_window, n),
                                                max(half, 1))
        return self._patch_fits[(m, n)]

    def _tdm_hypotheses(self, snap: np.ndarray, sigma2: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Each snapshot under the N_tx hypotheses of its wrap count, and each one's beam peak.

        With N_tx transmitters in TDM, a speed that aliases by k·2·v_max leaves a
        phase step of 2π·k/N_tx from one transmitter's slot to the next after the
        (aliased) Doppler correction: for k not a multiple of N_tx the virtual
        array is broken into sub-arrays and the beam splits into ghosts (a post
        at motorway speed seen at two wrong angles). The hypothesis h ≡ k (mod
        N_tx) whose beam peak is highest restores the array (production TDM-MIMO
        radars do this). Returns the corrected snapshots, shape (n, N_tx,
        channels), each one's score (:meth:`_wrap_score`), shape (n, N_tx), and
        the energy two plane waves explain of each, shape (n, N_tx).
        """
        p = self.preset
        h = np.arange(p.num_tx)
        fix = np.exp(-2j * np.pi * h[:, None] * self._tx_of[None, :] / p.num_tx)       # (hyp, channel)
        trial = snap[:, None, :] * fix[None, :, :]                                       # (n, hyp, channel)
        e = self.doa.explained(trial, 2)
        return trial, self._wrap_score(trial, sigma2, e), e[..., 1]                     # (n, hyp)

    def _wrap_score(self, snapshots: np.ndarray, sigma2: float, explained: np.ndarray | None = None
                    ) -> np.ndarray:
        """How well a snapshot is explained under a wrap hypothesis, in units of one channel's noise power
        times σ² (a log-likelihood): by one plane wave, or by two less WRAP_SOURCE_PENALTY, whichever is more.
        One plane wave alone would take the ghost lobes of two sources in one cell (posts left and right) for a
        wrap; two alone would explain the split beam of one wrapped source nearly as well as its wrap.
        ``explained``: the snapshots' :meth:`~radarnode.dsp.doa.FftBeamformer.explained` two waves, if known."""
        e = self.doa.explained(snapshots, 2) if explained is None else explained
        return np.maximum(e[..., 0], e[..., 1] - WRAP_SOURCE_PENALTY * sigma2)

    def _wrap_score_fine(self, snapshots: np.ndarray, sigma2: float) -> np.ndarray:
        """:meth:`_wrap_score` for a cell two plane waves do not explain: up to three plane waves, each one more a
        penalty more, fitted jointly (:meth:`radarnode.dsp.doa.FftBeamformer.explained` refined). Three sources in one cell (two cars and
        a post, three parked cars at standstill, all at one range and speed) are explained by no hypothesis with
        two waves, and the hypothesis that breaks the array into sub-arrays explained them better with two waves
        between the sources than the true one: the chain took the wrap and reported ghosts between the sources,
        three equal reflectors at −30°, 0°, 30° at ±14° and ±47° in 33 of 40 frames."""
        e = self.doa.explained(snapshots, WRAP_FINE_SOURCES, refine=WRAP_FINE_PASSES)
        q = np.arange(WRAP_FINE_SOURCES)
        return np.max(e - q * WRAP_SOURCE_PENALTY * sigma2, axis=-1)

    def _fine_gate(self, channels: int, sigma2: float) -> float:
        """What two plane waves must leave of a cell's energy for it to be judged again on three
        (:meth:`_wrap_score_fine`): WRAP_FINE_REST_PENALTIES penalties, and more than the noise leaves (about one σ² a
        channel: a 72-channel array's noise alone left more than two penalties) plus one penalty."""
        return max(WRAP_FINE_REST_PENALTIES * WRAP_SOURCE_PENALTY,
                   channels + WRAP_SOURCE_PENALTY) * sigma2

    def _positions(self, d, r, dd, dr, m: int, n: int):
        """Range bins, speed (positive: opening; λ at mid-sweep) and range of peaks at cells (d, r) + offsets."""
        p = self.preset
        r_bins = r + dr
        speed = (d - m // 2 + dd) * p.doppler_bin_mps
        return r_bins, speed, self._range(r_bins, speed, n)

    def _range(self, r_bins, speed, n: int):
        """Range of peaks at ``r_bins`` reported at ``speed``: the range FFT is circular, so a beat frequency past
        the last bin is the first bins' (never a negative range); coupling and migration to mid-frame are taken out
        (RadarPreset.range_rate_coupling_s)."""
        p = self.preset
        return np.mod(r_bins * p.range_resolution_m - speed * p.range_rate_coupling_s, n * p.range_resolution_m)

    def _tdm_phase(self, speed: np.ndarray) -> np.ndarray:
        """The factor that takes each channel's TDM Doppler phase out of snapshots at ``speed``, (n, channels)."""
        fd = 2.0 * speed / self.preset.centre_wavelength_m
        return np.exp(-2j * np.pi * fd[:, None] * self._tx_of[None, :] * self.preset.chirp_period_s)

    def _refit_migrating(self, rd, again, wrap, d, r, dd, dr, speed, halves, trial, peak, snap, sigma2
                         ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Fit the peaks ``again`` once more as targets that migrate in range (radarnode.dsp.peaks.MigrationFit).

        Their TDM beam says the speed wrapped: k ≡ ``wrap`` (mod N_tx) alias numbers, so the true speed is the
        measured one plus k·2·v_max, and the target moved μ = v·T_frame/Δr range bins during the frame. Of the
        two counts next to zero, k = wrap and wrap − N_tx (further ones are more than N_tx·v_max away, beyond
        what a road holds for N_tx ≤ 3), the one whose migrating response explains the patch (along the still
        fit's channel vector) better at the still fit's offsets is fitted; the fit replaces the still one where
        its beam is stronger than the still fit's under the same wrap: ``trial`` (the snapshots under each hypothesis) and ``peak`` (their beam peaks)
        are updated in place, and (peaks, Doppler offsets, range offsets) of the fits that replaced the still
        ones are returned, for the caller to take where the wrap is taken. ``snap``: the patch fit's snapshots,
        whose channel vectors the search projects the patches on.
        """
        p = self.preset
        m, n = rd.shape[1], rd.shape[2]
        if not again.size:
            return again, np.zeros(0), np.zeros(0), again, np.zeros(0)
        fit = self._migration_fit(m, n)
        k = np.stack([wrap[again], wrap[again] - p.num_tx], axis=1)                     # (peaks, 2) alias numbers
        mu = (speed[again, None] + k * (2.0 * p.alias_speed_mps)) * p.integration_time_s / p.range_resolution_m
        mu[np.abs(mu) > MigrationFit.MAX_MIGRATION] = np.nan                              # beyond what the fit models
        keep = ~np.all(np.isnan(mu), axis=1)
        if self.config.migration_fit == "auto":         # only where the migration is enough to matter
            keep &= np.any(np.abs(mu) >= MIGRATION_AUTO_MIN_BINS, axis=1)
        again, mu = again[keep], mu[keep]
        if not again.size:
            return again, np.zeros(0), np.zeros(0), again, np.zeros(0)
        # the fit judges the two alias numbers at the still fit's offsets and fits the better one
        chosen = np.zeros(again.size)
        fd, fr, fitted = fit(rd, d[again], r[again], dd[again], dr[again], mu, halves[again], snap[again], chosen)
        _, moved, _ = self._positions(d[again], r[again], fd, fr, m, n)
        h = wrap[again]
        fitted *= self._tdm_phase(moved) * np.exp(-2j * np.pi * h[:, None] * self._tx_of[None, :] / p.num_tx)
        beam = self._wrap_score(fitted, sigma2)
        better = beam > peak[again, h]
        take = again[better]
        trial[take, wrap[take]] = fitted[better]
        peak[take, wrap[take]] = beam[better]
        return take, fd[better], fr[better], again, chosen

    def _migration_fit(self, m: int, n: int) -> MigrationFit:
        """The migrating-target fit for maps of m Doppler × n range bins (built once per shape)."""
        if (m, n) not in self._migration_fits:
            cfg = self.config
            half = max(min(MIGRATION_HALF, (min(m, n) - 1) // 2), 1)
            self._migration_fits[(m, n)] = MigrationFit(window(cfg.doppler_window, m), window(cfg.range_window, n),
                                                        half)
        return self._migration_fits[(m, n)]

    def process(self, cube: np.ndarray, decimation: int = 1, power_reduction_db: float = 0.0) -> Detections:
        """Detections of one cube (shape (channel, chirp, sample)); see the module docstring."""
        cfg = self.config
        rd = range_doppler(cube, range_window=cfg.range_window, doppler_window=cfg.doppler_window)
        return self.process_rd(rd, power_reduction_db)

    def process_rd(self, rd: np.ndarray, power_reduction_db: float = 0.0) -> Detections:
        """Detections of one windowed range–Doppler spectrum, shape (channel, doppler, range), Doppler
        fftshifted (bin M/2 is zero speed), as :func:`radarnode.dsp.spectra.range_doppler` returns it.

        ``snr_db`` of a detection is the estimate of the integrated SNR ρ (the
        convention of :func:`radarnode.radar.equation.snr_db`): the cell's power
        less the noise's share, over the unbiased noise floor, with the window
        and straddle losses at the interpolated position divided out.
        """
        p, cfg = self.preset, self.config
        if rd.ndim != 3 or rd.shape[0] != p.num_virtual or rd.shape[1] != p.num_chirps:
            raise ConfigError(f"rd: shape {rd.shape} is not allowed; expected (channel, doppler, range) with "
                              f"{p.num_virtual} channels and {p.num_chirps} Doppler bins for preset {p.name}")
        c, m, n = rd.shape
        stat = self.statistic if (m, n) == (len(self.statistic.doppler_window), len(self.statistic.range_window)) \
            else detection_statistic(cfg, c, m, n)
        power = noncoherent_power(rd)
        if not np.all(np.isfinite(power)):
            raise ConfigError(f"rd: {int(np.sum(~np.isfinite(power)))} range–Doppler cells are NaN or infinite; "
                              "expected a finite spectrum (check the cube's samples)")
        # energy over the calibrated noise floor (the median cell is noise), not the CFAR's local estimate,
        # which a strong target's sidelobes inflate
        sigma2 = stat.noise_floor(power)
        d, r = local_maxima(power, stat.cfar.detect(power))
        if d.size > cfg.max_detections:
            keep = np.argsort(power[d, r])[::-1][: cfg.max_detections]
            d, r = d[keep], r[keep]
        migration_gain = np.ones(d.size)    # each peak cell's power against a still tone's: its migration's loss
        dd, dr = interpolate(power, d, r, cfg.range_window if cfg.range_window == cfg.doppler_window else "")
        snap = rd[:, d, r].T                                            # (detection, channel): the peak cell
        fitted_half = None                  # the patch half-widths of the peaks the patch fit refined (0: not)
        if cfg.range_ml and d.size:
            # the strongest peaks get the joint maximum-likelihood fit over a patch of cells around them
            # (radarnode.dsp.peaks.PatchFit: ~1.1-1.2× the CRB where the three-bin interpolator is ~2.7× in range
            # and ~1.5× at best after it); its snapshot holds the patch's energy, so the angle gains too. A patch
            # stops short of another peak's main lobe.
            top = np.argsort(power[d, r])[::-1][: cfg.range_ml_max_peaks]
            fit = self._patch_fit(m, n)
            half = patch_halves(d, r, top, (m, n), fit.max_half)
            fd, fr, s_top = fit(rd, d[top], r[top], dd[top], dr[top], half)
            # a patch cut short by a neighbour is fitted again, larger, with the other peaks' fitted tones taken
            # out of it (PatchFit.refit): a neighbour 3–6 bins away cost 1.5–2.2× the bound in range before; and
            # a patch a loud neighbour's sidelobes reach (LEAK_REFIT_DB) at its own half-width
            again = np.zeros(0, dtype=np.int64)
            if REFIT_PASSES and (cfg.refit is True or (cfg.refit == "auto" and rd.dtype == np.complex128)):
                reach = fit.leak_reach(power[d, r], sigma2 * 10.0 ** (LEAK_REFIT_DB / 10.0))
                loud = reached(d, r, top, (m, n), half, reach)
                again = np.flatnonzero((half < fit.max_half) | loud)
            if again.size:
                wider = np.full(again.size, min(fit.max_half, REFIT_HALF), dtype=np.int64)
                if top.size < d.size:              # only as far as the peaks not fitted (not in the model)
                    rest = np.setdiff1d(np.arange(d.size), top)
                    both = np.concatenate([top[again], rest])
                    wider = patch_halves(d[both], r[both], np.arange(again.size), (m, n),
                                         min(fit.max_half, REFIT_HALF), among=np.arange(again.size, both.size))
                take = (wider > half[again]) | loud[again]
                grow, wider = again[take], np.maximum(wider, half[again])[take]
                # … those far from every other peak (≥ REFIT_HALF + 3 bins) start from the three-bin interpolation:
                # their first fit took a loud neighbour's sidelobes at its patch's edge for their own and may lie
                # beyond the refit's search (a 25-dB return 12–14 bins from a 60-dB one: 1.7–2.9× the CRB in range
                # from there, 1.07× from the interpolation, whose three cells lie 9+ bins from that neighbour)
                fresh = grow[half[grow] >= REFIT_HALF]
                first_last = fresh[~reached(d, r, top[fresh], (m, n), half[fresh], reach, power[d, r])]
                if fresh.size:
                    fd[fresh], fr[fresh] = dd[top[fresh]], dr[top[fresh]]
                    s_top[fresh] = fit.snapshot(rd, d[top[fresh]], r[top[fresh]], fd[fresh], fr[fresh], half[fresh])
                # peaks whose first fits came within REFIT_APART bins of another's start again from their cells:
                # two returns about 2 bins apart, each 3 × 3 fit leaning half a bin or more into the other's lobe,
                # stayed where they met when refitted from there (3–11× the CRB in range at 2.0–2.1 bins); their
                # cells, two local maxima, are where the returns stand within half a bin
                meet = grow[nearest_peak(d[top] + fd, r[top] + fr, grow, (m, n)) <= REFIT_APART]
                if meet.size:
                    fd[meet], fr[meet] = 0.0, 0.0
                    s_top[meet] = fit.snapshot(rd, d[top[meet]], r[top[meet]], 0.0, 0.0, half[meet])
                seen = half.copy()
                store = PatchStore(rd, d[top], r[top])          # every pass cuts the same patches of the same map
                for k in range(REFIT_PASSES if grow.size else 0):
                    # every pass for every peak refitted: what the first pass took out for a neighbour was the
                    # neighbour's first fit, which leaned into this peak's lobe or took its sidelobes for its own.
                    # Neighbours 2 bins apart: one pass left them at 1.4× the bound in range on ars408_like, two at
                    # 1.3×. Neighbours 6–8 bins apart at 45–55 dB: one pass left the louder at 1.6–2.0× (ars408_like,
                    # 55/45 dB, 200 frames) and the other at 1.4–1.6× (mimo12, 45/45), three 1.2× and 1.15–1.3×. Equal
                    # returns 9–14 bins apart at 70–80 dB: one pass 1.5–5.2×, three 1.1–1.4× (60 frames). (The later
                    # passes were for the peaks 1 bin from a neighbour only before: at ρ = 30 dB one pass is enough
                    # 3–6 bins apart)
                    # (the fresh starts with the first fit's wider search: from the interpolation the refit's
                    # narrow one lost at ρ = 20 dB, 1.25× the CRB in range against 1.19×; and those no louder peak
                    # reaches after the others: a much weaker neighbour's first fit, which the loud one's sidelobes
                    # swamp, is no tone to take out — an 80-dB return 14 bins from a 25-dB one: 1.7× the CRB in
                    # range before it, 1.0× with it, ars408_like; 5× with the refit's search)
                    far = np.isin(grow, fresh) if k == 0 else np.zeros(grow.size, dtype=bool)
                    last = np.isin(grow, first_last) if k == 0 else far
                    for stage in (~last, last):
                        fits = [(sel, fit.refit(rd, d[top], r[top], fd, fr, s_top, seen, grow[sel], wider[sel],
                                                reach[top], rounds, store))
                                for sel, rounds in ((stage & ~far, None), (stage & far, fit.ROUNDS)) if sel.any()]
                        for sel, (new_d, new_r, new_s) in fits:
                            which = grow[sel]
                            fd[which], fr[which], s_top[which], seen[which] = new_d, new_r, new_s, wider[sel]
            dd, dr, snap = dd.copy(), dr.copy(), snap.copy()
            dd[top], dr[top], snap[top] = fd, fr, s_top
            fitted_half = np.zeros(d.size, dtype=np.int64)
            fitted_half[top] = half
        r_bins, speed, range_m = self._positions(d, r, dd, dr, m, n)
        # TDM: transmitter t fires t·T_c after transmitter 0 — remove that Doppler phase, then beamform
        raw, snap = snap, snap * self._tdm_phase(speed)
        if p.num_tx > 1 and d.size:
            trial, peak, two = self._tdm_hypotheses(snap, sigma2)
            rows = np.arange(d.size)
            wrap = 1 + np.argmax(peak[:, 1:], axis=1)           # the best wrap hypothesis other than none
            margin = np.full(d.size, WRAP_LL_MARGIN * sigma2)
            take = None                         # the peaks a migrating fit was judged on (signal.dsp.migration_fit)
            still, fitted_wrap = trial, wrap    # the snapshots before any migrating fit, and the wrap each was for
            if fitted_half is not None and self.migrates(rd.dtype):
                still, fitted_wrap = trial.copy(), wrap.copy()
                # a wrap count is also a true speed, and with it a range migration over the frame: the fitted peaks
                # where a wrap looks better than none are fitted again with that migrating target's response
                # (radarnode.dsp.peaks.MigrationFit), and the wrap is judged on that fit's beam
                again = np.flatnonzero((fitted_half > 0) & (peak[rows, wrap] > peak[:, 0]))
                take, fd, fr, judged, mu = self._refit_migrating(rd, again, wrap, d, r, dd, dr, speed, fitted_half,
                                                                 trial, peak, raw, sigma2)
                # a wrap judged on a migrating fit had the better of two alias numbers and a fit of its own: the
                # margin grows by what that choice can win from noise
                margin[take] += MIGRATION_EXTRA_MARGIN * sigma2
            wrap = np.where(peak[rows, wrap] - peak[:, 0] > margin, wrap, 0)
            # a cell that two plane waves explain under no hypothesis (three sources, wrapped or not) is judged
            # again on the joint fit of up to three waves, every hypothesis on the same (still) snapshot
            snap_energy = np.sum(snap.real ** 2 + snap.imag ** 2, axis=1)      # the same under each hypothesis
            rest = snap_energy - two.max(axis=1)
            again = np.flatnonzero(rest > self._fine_gate(c, sigma2))
            if again.size:
                fine = self._wrap_score_fine(still[again], sigma2)
                best = 1 + np.argmax(fine[:, 1:], axis=1)
                wrap[again] = np.where(fine[np.arange(again.size), best] - fine[:, 0] > margin[again], best, 0)
            if take is not None and take.size:
                # the migrating fit's offsets where its wrap was taken (not where the cell was judged again to
                # another wrap: its fit was for the wrap it was judged on first)
                taken = (wrap[take] != 0) & (wrap[take] == fitted_wrap[take])
                dd[take[taken]], dr[take[taken]] = fd[taken], fr[taken]
                r_bins, speed, range_m = self._positions(d, r, dd, dr, m, n)
            if take is not None and judged.size:
                # a peak judged wrapped at the alias number the migrating fit chose for it migrated, whether that
                # fit placed it or the still one kept it (a neighbour 3–4 Doppler bins away cuts its patch to 3 × 3
                # cells, where the still fit's beam wins): its peak cell lacks the energy the migration spread over
                # the neighbouring range cells (below; a 20-dBsm point closing at 100 m/s on mimo12 read 0.6 dB low,
                # and 0.2–0.3 dB at 70 m/s beside such a neighbour: testers' findings)
                alike = (wrap[judged] != 0) & (wrap[judged] == fitted_wrap[judged])
                migrated = judged[alike]
                migration_gain[migrated] = self._migration_fit(m, n).peak_gain(dd[migrated], dr[migrated], mu[alike])
            snap = trial[rows, wrap]
        # a peak in the span's first Doppler bin interpolated towards its neighbour across the wrap (or in its last
        # towards the first) lies beyond ±v_a: it is reported at its alias inside [−v_a, v_a), as the other levels
        # report it, and its range coupling taken out at that speed (an independent tester: +32.25 m/s on mimo12
        # came out as −32.41 m/s, 0.40 m further, in 30 of 30 frames). The TDM wrap hypotheses above were judged on
        # the speed as interpolated: the snapshot they chose is the same whichever alias names the speed.
        v_a = 0.5 * m * p.doppler_bin_mps
        beyond = (speed < -v_a) | (speed >= v_a)
        if beyond.any():
            speed = np.where(beyond, np.mod(speed + v_a, 2.0 * v_a) - v_a, speed)
            range_m = self._range(r_bins, speed, n)
        with np.errstate(over="ignore"):          # a noise-free map (tests) has a floor of ~0
            energy = np.minimum(np.maximum(power[d, r] / sigma2 - c, 1e-30), 1e300)
        delta_r = np.mod(r_bins, n) - np.rint(np.mod(r_bins, n))
        rho = energy / np.maximum(stat.energy(1.0, delta_r, dd) * migration_gain, 1e-30)
        if d.size and c > 1:   # every angle peak of a cell is a detection, sharing the cell's energy
            row, sin_t, rel_db = self.doa.estimate_peaks(snap, cfg.doa_floor_db, sigma2, cfg.doa_secondary_snr_db,
                                                         DOA_MAX_SOURCES)
            # in proportion to the peaks' powers, so that the cell's peaks add up to its energy (the strongest took
            # all of it before, and each other one its share on top: two equal reflectors resolved in angle in one
            # range–Doppler cell were each reported 3 dB above their RCS)
            power_share = 10.0 ** (rel_db / 10.0)
            power_share /= np.bincount(row, weights=power_share, minlength=d.size)[row]
            range_m, speed, rho = range_m[row], speed[row], rho[row] * power_share
            # what the cell's sources leave unexplained: the angle an extended reflector spans (its glint)
            frac = spread.unexplained_fraction(snap, row, sin_t, self.doa.spacing_wl, sigma2)
        else:                  # one channel measures no angle: boresight (a scanning radar adds its beam angle)
            sin_t = np.zeros(d.size)
            frac, row = np.zeros(d.size), np.arange(d.size)
        snr = 10.0 * np.log10(rho)
        azimuth = np.arcsin(sin_t)
        rcs = snr - equation.snr_db(p, range_m, 0.0, power_reduction_db, azimuth)
        return Detections(range_m, speed, azimuth, rcs, snr, np.full(range_m.size, -1, dtype=np.int64),
                          azimuth_spread_rad=spread.azimuth_spread(frac[row], c, self.doa.spacing_wl, azimuth))
