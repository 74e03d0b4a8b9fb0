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
#: detections the chain reports per cell over its threshold under noise alone (peak grouping merges
#: neighbouring exceedances; the DOA may find several peaks in one noise cell)
FALSE_ALARMS_PER_PFA_CELL = 1.0
#: the chain's DOA reports every angle peak within this many dB of a cell's strongest
DOA_FLOOR_DB = 9.0
