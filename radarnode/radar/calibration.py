"""What the signal chain measurably does, for the levels that do not run it.

The detection and object levels reproduce the signal level through these
figures; ``benchmarks/calibration.py`` measures them on point targets and
prints the three levels side by side (BENCHMARKS.md, "Calibration"). Change
the chain, re-run it, and update them here.
"""

from __future__ import annotations

import numpy as np

#: separations (range bins, Doppler bins, beamwidths 1/K in d·sinθ) below which the chain sees one peak: its
#: 50 % resolution points for two equal targets with random phases (1.62, 1.77, 0.67 measured; the angle's
#: CLEAN search resolves closer sources than the beam's peaks alone did, 0.83)
RESOLUTION = (1.7, 1.8, 0.7)
#: RMSE of the chain's estimates over the Cramér–Rao bound (range, range rate, azimuth) on point targets,
#: measured at the integrated SNRs of EFFICIENCY_SNR_DB and interpolated in between (held beyond)
EFFICIENCY_SNR_DB = (20.0, 30.0)
CHAIN_EFFICIENCY_AT = ((1.18, 1.19, 1.07), (1.18, 1.19, 1.10))


def chain_efficiency(snr_db: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(range, range rate, azimuth) RMSE over the CRB that the chain achieves at integrated SNR ``snr_db``."""
    table = np.asarray(CHAIN_EFFICIENCY_AT)
    return tuple(np.interp(snr_db, EFFICIENCY_SNR_DB, table[:, i]) for i in range(3))
#: false alarms the chain reports per cell over its threshold under noise alone, 1 − c·Pfa^β: the peak test
#: keeps one local maximum of a clump of neighbouring exceedances (the Hann windows correlate neighbouring cells),
#: and clumps grow as the threshold falls. Fitted to the chain's reported false alarms per Pfa × cells on
#: noise-only frames of mimo12 and ars408_like (0.71 at 1e-2, 0.85–0.88 at 1e-3, 0.92–1.0 at 1e-4; the same on
#: both presets, whose chains differ in channels and map size, not in windows and CFAR;
#: ``benchmarks/false_alarms.py``); 0.98 at the default 1e-6
FALSE_ALARM_CLUMP = (1.24, 0.316)


def false_alarms_per_pfa_cell(pfa: float) -> float:
    """Reported false alarms per cell over the threshold at ``pfa`` (:data:`FALSE_ALARM_CLUMP`)."""
    c, beta = FALSE_ALARM_CLUMP
    return max(0.0, 1.0 - c * pfa ** beta)
#: the chain's DOA reports every angle peak within this many dB of a cell's strongest
DOA_FLOOR_DB = 9.0
#: at most this many sources a cell's snapshot gives (``radarnode.dsp.doa``'s CLEAN, as the chain calls it)
DOA_MAX_SOURCES = 4
#: a cell's second and later angle peaks must stand this many dB above the beam's noise (K·σ²) in the snapshot's
#: residual (the chain's CLEAN, ``DspConfig.doa_secondary_snr_db``'s default)
DOA_SECONDARY_SNR_DB = 12.0
