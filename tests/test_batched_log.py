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
import numpy as np
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


def _node_frames(text: str, cycles: int, reconfigure_at: tuple[int, ...] = ()) -> list[tuple[int, bytes]]:
    """A node's frames over ``cycles`` cycles (simulated time, no vehicle), with MaxDistance changed by 0x200 before
    each cycle of ``reconfigure_at`` (alternately 120 m and back to 250 m)."""
    from radarnode.wire import ars408 as P
    from radarnode.wire.dbc import load_database
    from radarnode.wire.node import RadarNode
    from tests.helpers import scenario
    db = load_database()
    msg = db.get_message_by_frame_id(P.RADAR_CFG)
    node = RadarNode(scenario(text, ego="{speed_mps: 25.0}", duration=cycles * 0.072 + 0.1))
    out = []
    for k in range(cycles):
        if k in reconfigure_at:
            values = {s.name: 0 for s in msg.signals}
            values.update(RadarCfg_MaxDistance_valid=1,
                          RadarCfg_MaxDistance=120 if reconfigure_at.index(k) % 2 == 0 else 250)
            node.receive(can.Message(arbitration_id=P.RADAR_CFG, data=msg.encode(values), is_extended_id=False),
                         k * node.period_s)
        out += [(m.arbitration_id, bytes(m.data)) for m in node.cycle(k * node.period_s).messages]
    return out


PASSING = """
  - {id: slow, class: car, x_m: 40.0, lane: 1, speed_mps: 15.0}
  - {id: fast, class: car, x_m: 60.0, lane: 2, speed_mps: 33.0}
  - {id: oncoming, class: car, x_m: 240.0, lane: 0, speed_mps: 20.0, heading_deg: 180.0}
"""


def test_configuration_changes_restart_the_chunks_without_changing_a_frame(monkeypatch):
    """A 0x200 that changes MaxDistance makes the object level compute a new chunk from that cycle (the chunks
    grow again from FIRST_CHUNK_CYCLES): the frames are those computed one cycle at a time."""
    import radarnode.radar.object_model as om
    changes = (5, 40, 41, 200, 330)
    batched = _node_frames(PASSING, 400, changes)
    monkeypatch.setattr(om, "CHUNK_CYCLES", 1)
    single = _node_frames(PASSING, 400, changes)
    assert len(batched) == len(single) > 400
    assert batched == single


def test_cycles_with_nothing_in_view_are_skipped_without_changing_a_frame(monkeypatch):
    """The object level computes its physics only at the cycles where some actor may be in a sector: here the slow
    car falls behind, the fast one drives out of range and the oncoming one passes, so most of the run has
    nothing in view. Computing every cycle gives the same frames."""
    import radarnode.radar.object_model as om
    seen = []
    original = om.ObjectModel._cycles_in_view

    def spy(self, truth):
        rows = original(self, truth)
        seen.append((rows.size, truth.t_s.size))
        return rows

    monkeypatch.setattr(om.ObjectModel, "_cycles_in_view", spy)
    skipped = _node_frames(PASSING, 700)
    assert sum(t - r for r, t in seen) > 300          # most cycles skipped
    monkeypatch.setattr(om.ObjectModel, "_cycles_in_view", lambda self, truth: np.arange(truth.t_s.size))
    every = _node_frames(PASSING, 700)
    assert len(skipped) == len(every) > 700
    assert skipped == every
