"""Seed 002: sizes of a car's radar-image central sections (0.8 level, eq. 1), 1.8 × 5 m car at 30–150 m."""

from __future__ import annotations

import numpy as np
import pytest

from radarnode.perception.size import SectionStatistics, central_sections, section_width
from radarnode.radar.scan_image import AZIMUTH_CELL_DEG, RANGE_CELL_M, multipoint_vehicle, scan_image


def test_section_width_of_known_profiles():
    x = np.arange(0.0, 10.0, 0.5)
    box = np.where((x >= 3.0) & (x <= 6.0), 1.0, 0.0)
    assert section_width(box, x, 8) == pytest.approx(3.0 + 2 * 0.5 * 0.2)    # edges interpolated at 0.8
    tri = np.maximum(0.0, 1.0 - np.abs(x - 5.0) / 2.5)                       # 0.8 level at ±0.5 around 5
    assert section_width(tri, x, 10) == pytest.approx(1.0)


def _stats(range_m, snr_db, frames, rng, noise=True):
    fp = multipoint_vehicle(range_m, 0.0, 5.0, 1.8)
    ra = np.arange(range_m - 8.0, range_m + 13.0, RANGE_CELL_M)
    aa = np.arange(-6.0, 6.0, AZIMUTH_CELL_DEG)
    st = SectionStatistics()
    for _ in range(frames):
        st.add(*central_sections(scan_image(fp, snr_db, rng, ra, aa, noise=noise), ra, aa))
    return st


@pytest.mark.parametrize("range_m", [30.0, 60.0, 120.0, 150.0])
def test_section_sizes_within_10_and_15_percent(range_m):
    rng = np.random.default_rng(int(range_m))
    truth = _stats(range_m, 40.0, 300, rng, noise=False).mean()
    st = _stats(range_m, 35.0, 100, rng)       # object power 35 dB over the noise of a cell, 100 frames
    d_r, d_az = st.mean()
    assert abs(d_r - truth[0]) / truth[0] <= 0.10
    assert abs(d_az - truth[1]) / truth[1] <= 0.15
    s_r, s_az = st.std()
    assert s_r > 0 and s_az > 0          # eq. 1's spread is reported, and the image does fluctuate
