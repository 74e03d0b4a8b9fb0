"""Sizes of an object's radar image from its central cross-sections (seed 002, eq. 1).

The central sections are the range profile and the azimuth profile through
the image maximum of the object; each is measured as its width at 0.8 of the
maximum amplitude (the contiguous region around the peak, edges interpolated
between cells), and the widths are averaged over the N frames of a track:
D = (1/N)·Σ D_i, σ = √(Σ (D − D_i)² / (N − 1)).

What this measures is the size of the object's *radar image*, which is what
seed 002 estimates to 10 % (range) and 15 % (azimuth): a car's image has one
dominant mode at 30 m and beyond, so the 0.8-level widths are set by that mode
and the resolution, not by the car's 5 m length — the physical length and
width cannot be read from them (see the issue note). radarnode's object length
and width come from the extent of the object's detections instead.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def section_width(profile: np.ndarray, axis: np.ndarray, peak: int, level: float = 0.8) -> float:
    """Width of the contiguous region around ``peak`` where ``profile`` ≥ level·profile[peak]."""
    p = np.asarray(profile, dtype=np.float64)
    thr = level * p[peak]
    below = p < thr
    left_idx = np.flatnonzero(below[:peak])
    right_idx = np.flatnonzero(below[peak + 1:])
    i = left_idx[-1] + 1 if left_idx.size else 0             # first cell of the region
    j = peak + right_idx[0] if right_idx.size else p.size - 1  # last cell of the region

    def edge(inside: int, outside: int) -> float:
        return axis[inside] + (thr - p[inside]) / (p[outside] - p[inside]) * (axis[outside] - axis[inside])

    lo = edge(i, i - 1) if i > 0 else axis[i]
    hi = edge(j, j + 1) if j < p.size - 1 else axis[j]
    return float(abs(hi - lo))


def central_sections(image: np.ndarray, range_axis: np.ndarray, azimuth_axis: np.ndarray,
                     level: float = 0.8) -> tuple[float, float]:
    """(D_r in range units, D_az in azimuth units) of the image (shape (range, azimuth)) through its maximum."""
    r, a = np.unravel_index(int(np.argmax(image)), image.shape)
    return (section_width(image[:, a], range_axis, r, level), section_width(image[r, :], azimuth_axis, a, level))


@dataclass
class SectionStatistics:
    """Seed 002 eq. 1 over the frames of a track."""

    widths: list[tuple[float, float]] = field(default_factory=list)

    def add(self, d_r: float, d_az: float) -> None:
        self.widths.append((d_r, d_az))

    def mean(self) -> tuple[float, float]:
        w = np.asarray(self.widths)
        return float(w[:, 0].mean()), float(w[:, 1].mean())

    def std(self) -> tuple[float, float]:
        w = np.asarray(self.widths)
        return float(w[:, 0].std(ddof=1)), float(w[:, 1].std(ddof=1))
