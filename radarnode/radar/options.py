"""Options of the scatterer-based fidelity levels (scenario key ``signal``), validated on construction."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radarnode import validate
from radarnode.errors import ConfigError, FieldError
from radarnode.radar.chain import DspConfig


@dataclass(frozen=True)
class Impairments:
    """RF impairments; every one is off by default."""

    multipath: bool = False                 # two-ray ground reflection (seed 003)
    radar_height_m: float = 0.5
    target_height_m: float = 0.5
    ground_reflection: float = -0.7         # reflection coefficient of the road
    phase_noise_deg: float = 0.0            # rms phase step per chirp (random walk)
    iq_gain_db: float = 0.0                 # IQ amplitude imbalance
    iq_phase_deg: float = 0.0               # IQ phase imbalance
    channel_gain_sigma_db: float = 0.0      # per virtual channel gain mismatch (fixed by the seed)
    channel_phase_sigma_deg: float = 0.0    # per virtual channel phase mismatch
    adc_bits: int = 0                       # 0: ideal ADC
    adc_headroom_db: float = 6.0            # full scale above the largest sample

    def __post_init__(self) -> None:
        validate.boolean("multipath", self.multipath)
        for f in ("radar_height_m", "target_height_m"):
            validate.number(f, getattr(self, f), lo=0.0, hi=10.0)
        validate.number("ground_reflection", self.ground_reflection, lo=-1.0, hi=1.0)
        for f in ("phase_noise_deg", "channel_gain_sigma_db", "channel_phase_sigma_deg"):
            validate.number(f, getattr(self, f), lo=0.0, hi=90.0)
        validate.number("iq_gain_db", self.iq_gain_db, lo=-6.0, hi=6.0)
        validate.number("iq_phase_deg", self.iq_phase_deg, lo=-45.0, hi=45.0)
        validate.integer("adc_bits", self.adc_bits, lo=0, hi=24)
        validate.number("adc_headroom_db", self.adc_headroom_db, lo=0.0, hi=40.0)

    @property
    def any(self) -> bool:
        return (self.multipath or self.phase_noise_deg > 0 or self.iq_gain_db != 0 or self.iq_phase_deg != 0
                or self.channel_gain_sigma_db > 0 or self.channel_phase_sigma_deg > 0 or self.adc_bits > 0)



#: the per-sample, per-channel SNR a scenario's ``signal.snr_db`` and the levels' ``snr_db`` argument take (dB)
SNR_DB_LIMITS = (-60.0, 100.0)


def check_snr_db(snr_db: object) -> float | None:
    """``snr_db`` as a float within :data:`SNR_DB_LIMITS` (:func:`radarnode.validate.number`, numpy scalars taken as
    their value), or None; a :class:`ConfigError` naming it otherwise (the detection and signal levels' functions take
    it directly, not only through a scenario)."""
    if snr_db is None:
        return None
    value = snr_db.item() if isinstance(snr_db, (np.floating, np.integer)) else snr_db
    try:
        return validate.number("snr_db", value, lo=SNR_DB_LIMITS[0], hi=SNR_DB_LIMITS[1])
    except FieldError as exc:
        raise ConfigError(str(exc)) from None


@dataclass(frozen=True)
class SignalOptions:
    """Options of the scatterer-based levels (scenario key ``signal``)."""

    dtype: str = "complex128"
    snr_db: float | None = None
    scatterer_spacing_m: float = 1.0
    clutter_density_per_m2: float = 0.0
    clutter_rcs_dbsm: float = -20.0
    decimate: bool = True
    #: signal level: "auto" synthesises the range–Doppler spectrum directly where that is exact (Hann windows,
    #: no impairment), else the time-domain cube; "time" always the cube; "range_doppler" never falls back
    domain: str = "auto"
    dsp: DspConfig = DspConfig()
    impairments: Impairments = Impairments()

    def __post_init__(self) -> None:
        validate.choice("dtype", self.dtype, ("complex128", "complex64"))
        if self.snr_db is not None:
            validate.number("snr_db", self.snr_db, lo=SNR_DB_LIMITS[0], hi=SNR_DB_LIMITS[1])
        validate.number("scatterer_spacing_m", self.scatterer_spacing_m, lo=0.1, hi=10.0)
        validate.number("clutter_density_per_m2", self.clutter_density_per_m2, lo=0.0, hi=1.0)
        validate.number("clutter_rcs_dbsm", self.clutter_rcs_dbsm, lo=-60.0, hi=20.0)
        validate.boolean("decimate", self.decimate)
        validate.choice("domain", self.domain, ("auto", "time", "range_doppler"))

    @property
    def complex_dtype(self):
        return np.complex64 if self.dtype == "complex64" else np.complex128
