"""What the signal chain measurably does, for the levels that do not run it.

The detection and object levels reproduce the signal level through these
figures; ``benchmarks/calibration.py`` measures them on point targets and
prints the three levels side by side (BENCHMARKS.md, "Calibration"). Change
the chain, re-run it, and update them here.
"""

from __future__ import annotations

#: separations (range bins, Doppler bins, beamwidths 1/K in d·sinθ) below which the chain sees one peak
RESOLUTION = (2.0, 2.0, 1.0)
#: RMSE of the chain's estimates over the Cramér–Rao bound (range, range rate, azimuth), measured on point
#: targets at ρ = 30 dB (at 20 dB the chain is worse: about 2.0, 2.3 and 1.7; BENCHMARKS.md, "Calibration")
CHAIN_EFFICIENCY = (1.25, 1.4, 1.7)
#: detections the chain reports per cell over its threshold under noise alone (peak grouping merges
#: neighbouring exceedances; the DOA may find several peaks in one noise cell)
FALSE_ALARMS_PER_PFA_CELL = 1.0
#: the chain's DOA reports every angle peak within this many dB of a cell's strongest
DOA_FLOOR_DB = 9.0
