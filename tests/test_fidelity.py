"""Fidelity levels behind the node: every level gives frames the consumer decodes; auto picks by content."""

from __future__ import annotations

import numpy as np
import pytest

from radarnode.consumer.assembler import CycleAssembler
from radarnode.radar.models import AutoModel, shares_a_cell
from radarnode.radar.object_model import RuntimeConfig
from radarnode.radar.presets import PRESETS
from radarnode.radar.scatterers import point_targets
from radarnode.scene.world import Scene
from radarnode.wire.node import EgoMotionSender, RadarNode
from radarnode.wire.runner import SimulatedClock, run_node
from tests.conftest import SCENARIOS
from tests.helpers import scenario

TRAFFIC = """
  - {id: a, class: car, x_m: 30.0, lane: 1, speed_mps: 22.0}
  - {id: b, class: truck, x_m: 60.0, lane: 0, speed_mps: 18.0}
"""


@pytest.mark.parametrize("level", ["object", "detection", "signal", "auto"])
@pytest.mark.parametrize("output", ["objects", "clusters"])
def test_every_level_feeds_the_same_wire_and_consumer(level, output):
    sc = scenario(TRAFFIC, radar=f"{{preset: mimo12, output: {output}}}", duration=1.5)
    node = RadarNode(sc, fidelity=level)
    frames, outs = [], []
    run_node(node, clock=SimulatedClock(), sinks=[frames.append], on_cycle=outs.append,
             vehicle=EgoMotionSender(node.scene))
    assembler = CycleAssembler()
    cycles = list(assembler.feed(frames))
    assert len(cycles) == len(outs) == 20 and assembler.stats.dropped() == 0
    last = cycles[-1]
    if output == "objects":
        ol = last.objects
        near = np.argmin(np.abs(ol.dist_long_m - outs[-1].view.x_m[0]) + np.abs(ol.dist_lat_m))
        assert abs(ol.dist_long_m[near] - outs[-1].view.x_m[0]) < 1.0      # the car 26 m ahead
        assert abs(ol.vrel_long_mps[near] - 2.0) < 0.6
    else:
        assert len(last.clusters) >= 2


def test_auto_picks_the_signal_level_when_scatterers_share_a_cell():
    p = PRESETS["mimo12"]
    apart = point_targets([20.0, 40.0], [0.0, 10.0], [1.0, 2.0])
    together = point_targets([40.0, 40.05], [10.0, 10.2], [2.0, 2.0])
    assert not shares_a_cell(p, apart) and shares_a_cell(p, together)


def test_auto_counts_its_choices_and_uses_signal_for_impairments():
    import dataclasses
    sc = scenario(TRAFFIC, radar="{preset: mimo12}", duration=1.0)
    cfg = RuntimeConfig(max_distance_m=100.0, clusters=False)
    model = AutoModel(Scene(sc), sc.radar.model, np.random.default_rng(0), sc.signal)
    for k in range(5):
        model.step(k * 0.072, cfg)
    assert model.choices["object"] == 5
    imp = dataclasses.replace(sc.signal, impairments=dataclasses.replace(sc.signal.impairments, adc_bits=10))
    model = AutoModel(Scene(sc), sc.radar.model, np.random.default_rng(0), imp)
    model.step(0.0, cfg)
    assert model.choices["signal"] == 1


def test_signal_options_in_scenario_files_are_validated(tmp_path):
    from radarnode.errors import ScenarioError
    from radarnode.scene.scenario import load_scenario
    base = (SCENARIOS / "highway_mimo12.yaml").read_text()
    for bad, fragment in [
        ("signal: {dtype: complex32}", "signal.dtype"),
        ("signal: {impairments: {adc_bits: 40}}", "signal.impairments.adc_bits"),
        ("signal: {dsp: {cfar: gocfar}}", "signal.dsp.cfar"),
        ("signal: {scatterer_spacing_m: .nan}", "signal.scatterer_spacing_m"),
        ("signal: {colour: 1}", "unknown field 'signal.colour'"),
        ("fidelity: raytrace", "fidelity"),
    ]:
        key = bad.split(":")[0]
        lines = [ln for ln in base.splitlines() if not ln.startswith(key + ":")]
        path = tmp_path / "s.yaml"
        path.write_text("\n".join(lines) + "\n" + bad + "\n")
        with pytest.raises(ScenarioError, match=fragment):
            load_scenario(path)
