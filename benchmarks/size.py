"""Seed 002's central-section sizes of a 1.8 × 5 m car's radar image against range and SNR.

For each range and SNR (object power over the noise of one cell), 100 frames
of the scanning_ka image (multi-point car, new scattering phases every frame);
the relative error of the eq.-1 mean of the 0.8-level widths against the
noise-free mean of 300 frames. Run: ``python benchmarks/size.py``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from radarnode.perception.size import SectionStatistics, central_sections  # noqa: E402
from radarnode.radar.scan_image import AZIMUTH_CELL_DEG, RANGE_CELL_M, multipoint_vehicle, scan_image  # noqa: E402


def stats(fp, ra, aa, snr, frames, rng, noise=True):
    st = SectionStatistics()
    for _ in range(frames):
        st.add(*central_sections(scan_image(fp, snr, rng, ra, aa, noise=noise), ra, aa))
    return st


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()      # (--help; no options)
    rng = np.random.default_rng(0)
    print("| range | D_r (noise-free) | D_az (noise-free) | error D_r / D_az at 15 dB | at 20 dB | at 25 dB | "
          "at 30 dB | at 35 dB |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in (30.0, 60.0, 120.0, 150.0):
        fp = multipoint_vehicle(r, 0.0, 5.0, 1.8)
        ra = np.arange(r - 8.0, r + 13.0, RANGE_CELL_M)
        aa = np.arange(-6.0, 6.0, AZIMUTH_CELL_DEG)
        t_r, t_az = stats(fp, ra, aa, 40.0, 300, rng, noise=False).mean()
        cells = []
        for snr in (15.0, 20.0, 25.0, 30.0, 35.0):
            m_r, m_az = stats(fp, ra, aa, snr, 100, rng).mean()
            cells.append(f"{100 * abs(m_r - t_r) / t_r:.0f} % / {100 * abs(m_az - t_az) / t_az:.0f} %")
        print(f"| {r:.0f} m | {t_r:.2f} m | {t_az:.2f}° ({np.radians(t_az) * r:.2f} m) | " + " | ".join(cells) + " |",
              flush=True)


if __name__ == "__main__":
    main()
