"""The batched paths against the cycle-by-cycle one: `radarnode log` writes the same frames either way.

The object level computes its physics, the guardrail posts and the lists' field tables for chunks of up to
``CHUNK_CYCLES`` cycles at once, the scene the ego's states for ``EGO_BLOCK`` cycles (issue 13 item 10, issue 9
item 7). With both 1 every cycle is computed on its own — the reference path. Each shipped scenario here is logged both ways and the logs must hold
the same frames, byte for byte and stamp for stamp: an object list with road boundaries (highway_cut_in), a
cluster list beside guardrails on a bend (guardrail_traffic), a closed loop with the consumer ECU on a bend
(acc_follow_bend_250, whose ego is computed one cycle at a time in both paths).
"""

from __future__ import annotations

from pathlib import Path

import can
import pytest

from radarnode.cli.main import main

SCENARIOS = Path(__file__).resolve().parents[1] / "scenarios"
CASES = {
    "objects+boundaries": ["highway_cut_in.yaml", "--fidelity", "object", "--duration", "20"],
    "clusters+guardrails+bend": ["guardrail_traffic.yaml", "--fidelity", "object"],
    "closed loop+ecu+bend": ["acc_follow_bend_250.yaml", "--fidelity", "object", "--ecu", "--duration", "15"],
}


def _frames(path: Path) -> list[tuple[int, float, bytes]]:
    return [(m.arbitration_id, m.timestamp, bytes(m.data)) for m in can.BLFReader(str(path))]


@pytest.mark.parametrize("case", list(CASES))
def test_a_log_is_the_same_computed_in_chunks_and_cycle_by_cycle(case, tmp_path, monkeypatch, capsys):
    import radarnode.radar.object_model as om
    import radarnode.scene.world as world
    name, *args = CASES[case]
    batched, single = tmp_path / "batched.blf", tmp_path / "single.blf"
    assert main(["log", str(SCENARIOS / name), *args, "-o", str(batched)]) == 0
    monkeypatch.setattr(om, "CHUNK_CYCLES", 1)
    monkeypatch.setattr(world, "EGO_BLOCK", 1)
    assert main(["log", str(SCENARIOS / name), *args, "-o", str(single)]) == 0
    a, b = _frames(batched), _frames(single)
    assert len(a) > 100
    assert len(a) == len(b)
    for k, (x, y) in enumerate(zip(a, b)):
        assert x == y, f"frame {k}: {x} batched, {y} cycle by cycle"


@pytest.mark.parametrize("name", ["lane_change_to_stopped.yaml", "clothoid_stopped_own_lane.yaml", "acc_stop_and_go.yaml"])
def test_the_ego_on_the_cycle_grid_is_the_ego_computed_on_its_own(name):
    """Scene.ego_state takes a scripted ego's states on the cycle grid from blocks computed in one pass: each is
    the state computed for its time alone (a lane change, a clothoid, speed changes), and off the grid too."""
    from radarnode.radar.setup import load_scenario
    from radarnode.scene.world import EGO_BLOCK, EgoState, Scene
    sc = load_scenario(SCENARIOS / name)
    scene = Scene(sc)

    def alone(t):
        x, y, heading, _, _, speed, accel, yaw = scene._ego_pose(scene._ego.state(t))
        return EgoState(*(float(v[0]) for v in (x, y, heading, speed, accel, yaw)))

    for k in list(range(0, 2 * EGO_BLOCK + 3, 7)) + [EGO_BLOCK - 1, EGO_BLOCK]:
        t = k * sc.period_s
        assert scene.ego_state(t) == alone(t), k
    assert scene.ego_state(0.5 * sc.period_s) == alone(0.5 * sc.period_s)
