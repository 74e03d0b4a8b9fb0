"""A lane change between guardrails past a car stopped in the lane being left: FCW stays silent.

An attempt to tell a lane change from the boundaries' offsets (so that a curve's exit, where a quadratic fitted to a
boundary that straightens tilts its heading by 3° while its offset stays, would no longer drop the boundaries)
made these scenes warn: at the start of a lane change the heading passes the limit before the offsets have moved,
and a boundary re-fitted mid-change moves its offset by metres in one cycle (an independent tester's scenes). The
fitted heading alone decides (README, the curve's exit as a known limit); these keep that behaviour."""

from __future__ import annotations

import pytest

from radarnode.consumer.evaluate import simulate
from radarnode.radar.setup import parse_scenario


LANE_CHANGE_PAST = """
name: lane_change_past_guardrails
duration_s: 9.0
seed: {seed}
radar: {{preset: ars408_like}}
ego: {{speed_mps: 25.0, lane_change: {{t_s: 1.0, duration_s: 4.0, to_lane: 1}}}}
road: {{lanes: 2, lane_width_m: 3.5, ego_lane: 0, guardrails: {{left_offset_m: 1.0, right_offset_m: 1.0}}}}
ecu: {{acc_enabled: false, expect: {{lead: stopped, no_fcw: true, never_target: [stopped]}}}}
actors:
  - {{id: stopped, class: car, x_m: {x}, lane: 0, speed_mps: 0.0}}
"""


@pytest.mark.parametrize("seed, x", [(1, 150.0), (2, 150.0), (3, 150.0), (1, 140.0), (2, 160.0)])
def test_a_lane_change_past_a_stopped_car_between_guardrails_draws_no_warning(seed, x):
    # with the offsets' test a boundary re-fitted mid lane change made the drift look like keeping, the boundaries'
    # course put the car in the lane being left in the path, and FCW warned in 2 of 3 seeds at 150 m
    res = simulate(parse_scenario(LANE_CHANGE_PAST.format(seed=seed, x=x)), fidelity="object")
    assert res.passed, res.reasons
