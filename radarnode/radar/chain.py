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
from radarnode.errors import ConfigError
from radarnode.dsp.cfar import CFAR_KINDS, make_cfar
from radarnode.dsp.detection_stats import DetectionStatistic, noise_correlation
from radarnode.dsp.doa import DOA_METHODS, make_doa
from radarnode.dsp.peaks import PatchFit, interpolate, local_maxima, patch_halves
from radarnode.dsp import spread
from radarnode.dsp.spectra import WINDOWS, noncoherent_power, range_doppler, window
from radarnode.perception.types import Detections
from radarnode.radar import equation, tables
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
    doa_floor_db: float = 9.0
    doa_secondary_snr_db: float = 12.0   # a cell's second angle peak must stand this far above the beam noise
    range_ml: bool = True          # maximum-likelihood range and Doppler refinement of the strongest peaks
    range_ml_max_peaks: int = 128
    ml_patch_half: int = 12        # its patch: ±12 bins each way where no other peak is near
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
        validate.integer("max_detections", self.max_detections, lo=1, hi=100_000)


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


class DspChain:
    """Processes cubes of one preset; windows, CFAR and steering are built once."""

    def __init__(self, preset: RadarPreset, config: DspConfig = DspConfig()) -> None:
        self.preset = preset
        self.config = config
        self.statistic = detection_statistic(config, preset.num_virtual, preset.num_chirps, preset.num_range_bins)
        self.cfar = self.statistic.cfar
        if config.doa != "fft" and preset.num_virtual < 3:
            raise ConfigError(f"signal.dsp.doa: value {config.doa!r} is not allowed with preset {preset.name} "
                              f"({preset.num_virtual} virtual channel(s)); expected 'fft' (super-resolution needs "
                              "3 channels or more)")
        self.doa = make_doa(config.doa, preset.num_virtual, preset.element_spacing_wl,
                            n_fft=max(config.doa_fft_size, preset.num_virtual))
        self._tx_of = np.repeat(np.arange(preset.num_tx), preset.num_rx)
        self._patch_fits: dict[tuple[int, int], PatchFit] = {}

    def _patch_fit(self, m: int, n: int) -> PatchFit:
        """The patch fit for maps of m Doppler × n range bins (built once per shape)."""
        if (m, n) not in self._patch_fits:
            cfg = self.config
            half = min(cfg.ml_patch_half, (min(m, n) - 1) // 2)
            self._patch_fits[(m, n)] = PatchFit(window(cfg.doppler_window, m), window(cfg.range_window, n),
                                                max(half, 1))
        return self._patch_fits[(m, n)]

    def _tdm_hypotheses(self, snap: np.ndarray, sigma2: float) -> np.ndarray:
        """Undo the TDM phase of an aliased speed: each snapshot under the N_tx hypotheses of its wrap count.

        With N_tx transmitters in TDM, a speed that aliases by k·2·v_max leaves a
        phase step of 2π·k/N_tx from one transmitter's slot to the next after the
        (aliased) Doppler correction: for k not a multiple of N_tx the virtual
        array is broken into sub-arrays and the beam splits into ghosts (a post
        at motorway speed seen at two wrong angles). The hypothesis whose beam
        peak is highest restores the array (production TDM-MIMO radars do this).
        Returns the snapshots with the chosen correction, shape (n, channels).
        """
        p = self.preset
        h = np.arange(p.num_tx)
        fix = np.exp(-2j * np.pi * h[:, None] * self._tx_of[None, :] / p.num_tx)       # (hyp, channel)
        trial = snap[:, None, :] * fix[None, :, :]                                       # (n, hyp, channel)
        peak = self.doa.spectrum(trial).max(axis=-1)                                      # (n, hyp)
        # another wrap count only where it beats "no wrap" by more than noise can: the beam peak's power
        # fluctuates by about 2/√SNR of itself, so the margin is three times that (2 dB at a beam SNR of
        # 20 dB, 0.7 dB at 30 dB). A fixed 2 dB kept the wrong hypothesis of a 3-transmitter array (its
        # staircase costs only ~1.5 dB) at every SNR; none at all scattered weak unaliased targets.
        best = np.argmax(peak, axis=1)
        with np.errstate(over="ignore"):          # a noise-free map (tests) has a floor of ~0
            beam_snr = peak[:, 0] / (snap.shape[1] * max(sigma2, np.finfo(np.float64).tiny))
        margin = 1.0 + 6.0 / np.sqrt(np.maximum(beam_snr, 1.0))
        best = np.where(peak[np.arange(peak.shape[0]), best] > peak[:, 0] * margin, best, 0)
        return trial[np.arange(snap.shape[0]), best]

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
        res = stat.cfar(power)
        d, r = local_maxima(power, res.mask)
        if d.size > cfg.max_detections:
            keep = np.argsort(power[d, r])[::-1][: cfg.max_detections]
            d, r = d[keep], r[keep]
        dd, dr = interpolate(power, d, r, cfg.range_window if cfg.range_window == cfg.doppler_window else "")
        snap = rd[:, d, r].T                                            # (detection, channel): the peak cell
        if cfg.range_ml and d.size:
            # the strongest peaks get the joint maximum-likelihood fit over a patch of cells around them
            # (radarnode.dsp.peaks.PatchFit: ~1.1-1.2× the CRB where the three-bin interpolator is ~2.7× in range
            # and ~1.5× at best after it); its snapshot holds the patch's energy, so the angle gains too. A patch
            # stops short of another peak's main lobe.
            top = np.argsort(power[d, r])[::-1][: cfg.range_ml_max_peaks]
            fit = self._patch_fit(m, n)
            half = patch_halves(d, r, top, (m, n), fit.max_half)
            fd, fr, s_top = fit(rd, d[top], r[top], dd[top], dr[top], half)
            dd, dr, snap = dd.copy(), dr.copy(), snap.copy()
            dd[top], dr[top], snap[top] = fd, fr, s_top
        r_bins = r + dr
        speed = (d - m // 2 + dd) * p.doppler_bin_mps               # positive: opening (λ at mid-sweep)
        # the range FFT is circular: a beat frequency past the last bin is the first bins' (never a negative
        # range); coupling and migration to mid-frame are taken out (RadarPreset.range_rate_coupling_s)
        range_m = np.mod(r_bins * p.range_resolution_m - speed * p.range_rate_coupling_s,
                         n * p.range_resolution_m)
        # TDM: transmitter t fires t·T_c after transmitter 0 — remove that Doppler phase, then beamform
        fd = 2.0 * speed / p.centre_wavelength_m
        snap = snap * np.exp(-2j * np.pi * fd[:, None] * self._tx_of[None, :] * p.chirp_period_s)
        # energy over the calibrated noise floor (the median cell is noise), not the CFAR's local estimate,
        # which a strong target's sidelobes inflate
        sigma2 = stat.noise_floor(power)
        if p.num_tx > 1 and d.size:
            snap = self._tdm_hypotheses(snap, sigma2)
        with np.errstate(over="ignore"):          # a noise-free map (tests) has a floor of ~0
            energy = np.minimum(np.maximum(power[d, r] / sigma2 - c, 1e-30), 1e300)
        delta_r = np.mod(r_bins, n) - np.rint(np.mod(r_bins, n))
        rho = energy / np.maximum(stat.energy(1.0, delta_r, dd), 1e-30)
        if d.size and c > 1:   # every angle peak of a cell is a detection, sharing the cell's energy
            row, sin_t, rel_db = self.doa.estimate_peaks(snap, cfg.doa_floor_db, sigma2, cfg.doa_secondary_snr_db)
            range_m, speed, rho = range_m[row], speed[row], rho[row] * 10.0 ** (rel_db / 10.0)
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
