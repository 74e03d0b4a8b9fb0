"""Display geometry of the radar image: the direct-perspective transform of seed 002.

Seed 002 turns the rectangular (bird's-eye) radar image into a view a driver
reads as perspective: the near (bottom) edge of the image is widened by a
factor k and the widening falls linearly to 1 at the far (top) edge. A point
at lateral offset y and range x moves to

    u = y · s(x),   v = x,   s(x) = k − (k − 1) · x / x_max.

Lines parallel to the ego's axis (road edges, lane lines: y = const) stay
straight and all meet at one vanishing point, (0, k·x_max/(k − 1)), beyond
the top of the image; an object at range x is drawn s(x) times wider. With
k = 2.5 and the 250 m image of the scanning_ka radar, a car at 100 m is
1.9 times larger — the figure seed 002 reports.
"""

from __future__ import annotations

import numpy as np

from radarnode.errors import ConfigError


def _check(k: float, range_max_m: float) -> None:
    if not k >= 1.0:
        raise ConfigError(f"perspective k: value {k!r} is not allowed; expected a number >= 1 (1.7 and 2.5 in seed 002)")
    if not range_max_m > 0:
        raise ConfigError(f"perspective range_max_m: value {range_max_m!r} is not allowed; expected > 0")


def perspective_gain(range_m: np.ndarray, k: float, range_max_m: float) -> np.ndarray:
    """s(x): how much wider the view draws an object at range x."""
    _check(k, range_max_m)
    return k - (k - 1.0) * np.asarray(range_m, dtype=np.float64) / range_max_m


def direct_perspective(lateral_m: np.ndarray, range_m: np.ndarray, k: float, range_max_m: float
                       ) -> tuple[np.ndarray, np.ndarray]:
    """Image coordinates (u, v) of points given by lateral offset and range; shapes broadcast."""
    r = np.asarray(range_m, dtype=np.float64)
    return np.asarray(lateral_m, dtype=np.float64) * perspective_gain(r, k, range_max_m), r


def vanishing_point(k: float, range_max_m: float) -> tuple[float, float]:
    """Where every line parallel to the axis meets in the view (at infinity for k = 1)."""
    _check(k, range_max_m)
    return (0.0, float("inf")) if k == 1.0 else (0.0, k * range_max_m / (k - 1.0))
