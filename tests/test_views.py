"""Direct-perspective view (seed 002): straight edges stay straight, meet at one point; gain at 100 m."""

from __future__ import annotations

import numpy as np
import pytest

from radarnode.errors import ConfigError
from radarnode.perception.views import direct_perspective, perspective_gain, vanishing_point


@pytest.mark.parametrize("k", [1.7, 2.5])
def test_edges_parallel_to_the_axis_stay_straight_and_meet_at_one_point(k):
    r = np.linspace(5.0, 250.0, 50)
    vp = vanishing_point(k, 250.0)
    for y in (-7.0, -3.5, 0.0, 3.5, 7.0):
        u, v = direct_perspective(np.full_like(r, y), r, k, 250.0)
        # straight: the second differences vanish
        assert np.allclose(np.diff(u, 2), 0.0, atol=1e-12)
        # the line through its points passes through the vanishing point
        slope = (u[-1] - u[0]) / (v[-1] - v[0])
        assert u[0] + slope * (vp[1] - v[0]) == pytest.approx(0.0, abs=1e-9)


def test_a_car_at_100_m_is_1_9_times_larger_with_k_2_5():
    assert perspective_gain(100.0, 2.5, 250.0) == pytest.approx(1.9)
    assert perspective_gain(100.0, 1.7, 250.0) == pytest.approx(1.42)
    assert perspective_gain(250.0, 2.5, 250.0) == pytest.approx(1.0)   # the far edge keeps its scale


def test_bad_factor():
    with pytest.raises(ConfigError, match="perspective k"):
        perspective_gain(10.0, 0.5, 250.0)
