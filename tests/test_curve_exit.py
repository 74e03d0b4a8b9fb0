"""A curve's exit: the road straightens ahead while the ego is still in the arc. A quadratic fitted to a boundary
that straightens tilts its heading by about 3°, past the lane-change limit, and the ECU dropped the boundaries
and let the yaw-rate circle alone decide: a car stopped in the inner lane beyond the exit drew a full FCW warning
(an independent tester's scene). A lane change is now told by the boundaries' offsets moving as their heading
moves them (radarnode.consumer.path.lane_keeping)."""

from __future__ import annotations

import math

import pytest

from radarnode.consumer.evaluate import simulate
from radarnode.consumer.path import LANE_CHANGE_WINDOW_S, LANE_KEEPING_HEADING_RAD, lane_keeping
from radarnode.radar.setup import parse_scenario

LIMIT = LANE_KEEPING_HEADING_RAD


def _history(heading, drift_mps, span_s=LANE_CHANGE_WINDOW_S, dt=0.072, sides=("left", "right")):
    out, t = [], 0.0
    while t <= span_s + 1e-9:
        out.append((t, {s: ((5.0 if s == "left" else -5.0) + drift_mps * t, heading) for s in sides}))
        t += dt
    return out


@pytest.mark.parametrize("heading", [0.0, LIMIT - 1e-4, -(LIMIT - 1e-4)])
def test_within_the_heading_limit_the_ego_keeps_its_lane_whatever_the_offsets(heading):
    assert lane_keeping(_history(heading, 0.0), 25.0) is True
    assert lane_keeping(_history(heading, 2.0), 25.0) is True


@pytest.mark.parametrize("factor", [1.0, 2.0])     # at the heading limit just over, and at twice it
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_beyond_the_limit_offsets_that_move_with_the_heading_are_a_lane_change(factor, sign):
    heading = sign * (LIMIT + 1e-4) * factor
    expected = 25.0 * math.sin(heading)                  # m/s: how a lane change at that heading moves the offsets
    assert lane_keeping(_history(heading, expected), 25.0) is False
    assert lane_keeping(_history(heading, 0.51 * expected), 25.0) is False     # just above half of it
    assert lane_keeping(_history(heading, 0.49 * expected), 25.0) is True      # just below: a tilted fit
    assert lane_keeping(_history(heading, 0.0), 25.0) is True                   # steady offsets: the curve's exit
    assert lane_keeping(_history(heading, -expected), 25.0) is True             # moving the other way


def test_without_enough_history_the_fitted_heading_decides():
    heading = 2 * LIMIT
    assert lane_keeping([], 25.0) is None
    assert lane_keeping(_history(heading, 0.0, span_s=0.5 * LANE_CHANGE_WINDOW_S - 0.08), 25.0) is None
    # a side seen now but not then: nothing to compare
    h = _history(heading, 0.0, sides=("left",))
    h[-1] = (h[-1][0], {"right": (-5.0, heading)})
    assert lane_keeping(h, 25.0) is None


EXIT = """
name: curve_exit
duration_s: 9.0
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: 25.0}}
road:
  lanes: 3
  lane_width_m: 3.5
  ego_lane: 1
  segments:
    - {{type: arc, length_m: 160.0, curvature_1pm: 0.004}}
    - {{type: clothoid, length_m: 30.0, curvature_start_1pm: 0.004, curvature_end_1pm: 0.0}}
    - {{type: straight, length_m: 600}}
  guardrails: {{left_offset_m: 1.0, right_offset_m: 1.0}}
ecu: {{acc_enabled: false, expect: {{lead: stopped, no_fcw: true, never_target: [stopped]}}}}
actors:
  - {{id: stopped, class: car, x_m: 200.0, lane: 2, speed_mps: 0.0}}
"""


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_car_stopped_in_the_inner_lane_beyond_a_curve_exit_draws_no_warning(seed):
    res = simulate(parse_scenario(EXIT.format(seed=seed)), fidelity="object")
    assert res.passed, res.reasons
