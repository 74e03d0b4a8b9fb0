"""Scenarios at the edges of what the schema allows, end to end through the commands (an independent tester's
findings, session 28): the slowest radar cycle, runs shorter than one cycle, structures overhead at the start,
waypoints with the heading they have, expectation windows beyond the run."""

from __future__ import annotations

import pytest

from tests.helpers import cli

SLOW = """name: slow
duration_s: 30.0
seed: 1
cycle_period_s: {period}
ego: {{speed_mps: 20.0}}
ecu: {{expect: {{no_fcw: true}}}}
actors:
  - {{id: a, class: car, x_m: 40, lane: 1, speed_mps: 20}}
"""


@pytest.mark.parametrize("period", [4.99, 5.0, 5.01, 10.0])
def test_the_slowest_radar_cycles_the_schema_allows_run_log_and_report(tmp_path, capsys, period):
    """The ECU's time guard took a step longer than 5 s for a discontinuity and refused a radar cycle above it: a cycle
    of 5.01–10 s (the schema allows 0.005–10 s) ended `run`, `log --ecu` and `report` in a traceback. Now every
    cycle is tracked: the ECU, fed one decoded cycle every period, skips none as a jump in time."""
    from radarnode.consumer.assembler import CycleAssembler
    from radarnode.consumer.evaluate import make_ecu
    from radarnode.radar.setup import load_scenario
    from radarnode.wire.node import EgoMotionSender, RadarNode
    path = tmp_path / "slow.yaml"
    path.write_text(SLOW.format(period=period))
    for argv in (["run", path, "--fast", "--quiet"], ["log", path, "--ecu", "-o", tmp_path / "slow.blf"],
                 ["report", path, "--seeds", "1", "--workers", "1"]):
        rc, out, err = cli(capsys, *argv)
        assert rc == 0 and "Traceback" not in err, (argv, err[-400:])
    sc = load_scenario(path)
    node, asm = RadarNode(sc), CycleAssembler()
    vehicle, ecu = EgoMotionSender(node.scene), make_ecu(sc, node.period_s)
    decisions = []
    for k in range(6):
        t = k * node.period_s
        for m in vehicle.frames(t):
            node.receive(m, t)
            asm.on_message_received(m)
        for m in node.cycle(t).messages:
            asm.on_message_received(m)
        ecu.set_ego(t, asm.ego_speed_mps, asm.ego_yaw_rate_dps)
        decisions += [ecu.on_cycle(t, c) for c in asm.drain()]
    assert len(decisions) == 6 and all(d is not None for d in decisions), decisions
    assert ecu.stats.time_jumps == 0 and ecu.stats.rejected_time == 0, ecu.stats
