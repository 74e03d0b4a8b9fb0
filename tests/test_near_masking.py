"""A pedestrian beside parked cars in front of a stopped ego (README, "Known limit, near range").

ars408_like has one waveform (1.79-m range cells at every range) and its CA-CFAR ring spans ±18 m in range: a
parked car a few metres away, some 100 dB above the noise, masks a pedestrian at the same (zero) Doppler within
that span, at every level alike. The shipped ``pedestrian_crossing.yaml`` therefore sets OS-CFAR.
"""

from __future__ import annotations

import numpy as np
import pytest

from radarnode.radar.models import make_model
from radarnode.radar.object_model import RuntimeConfig
from radarnode.radar.setup import load_scenario, parse_scenario, radar_config
from radarnode.scene.world import Scene
from tests.conftest import SCENARIOS


def _reported(sc, level: str, seed: int, cycles: int | None = None) -> tuple[int, int]:
    """In how many cycles the first actor is in the object list, and in how many of them as crossing-moving."""
    cfg = radar_config(sc)
    model = make_model(level, Scene(sc), cfg.preset, np.random.default_rng(seed), cfg.signal)
    n = cycles or int(round(sc.duration_s / sc.period_s))
    if hasattr(model, "planned_cycles"):
        model.planned_cycles = n
    seen = crossing = 0
    for k in range(n):
        frame, _ = model.step(k * sc.period_s, RuntimeConfig(max_distance_m=cfg.preset.max_range_m))
        mine = frame.objects.actor_index == 0
        seen += int(mine.any())
        crossing += int((frame.objects.dyn_prop[mine] == 6).any())
    return seen, crossing


@pytest.mark.parametrize("level", ["object", "detection"])
def test_the_shipped_crossing_pedestrian_is_reported_once_out_from_behind_the_parked_car(level):
    sc = load_scenario(SCENARIOS / "pedestrian_crossing.yaml")
    assert sc.signal["dsp"]["cfar"] == "os"
    seen, crossing = _reported(sc, level, seed=3)
    # it steps out at about 2.1 s (cycle 29 of 111) and walks on until the end: reported in most of those cycles
    assert seen >= 50
    if level == "object":
        assert crossing == seen


def _stopped_ego_pedestrian(cfar: str, parked: bool) -> str:
    cars = "  - {id: parked, class: car, x_m: 8.0, y_m: -3.6, speed_mps: 0.0}\n" if parked else ""
    return f"""
name: t
duration_s: 2.0
seed: 1
radar: {{preset: ars408_like}}
signal: {{dsp: {{cfar: {cfar}}}}}
ego: {{speed_mps: 0.0}}
road: {{lanes: 2, lane_width_m: 3.25, ego_lane: 0}}
actors:
  - {{id: pedestrian, class: pedestrian, x_m: 15.0, y_m: 1.0, speed_mps: 0.0}}
{cars}"""


@pytest.mark.parametrize("level", ["object", "detection"])
def test_a_parked_car_a_few_metres_away_masks_a_pedestrian_in_the_ca_cfar_ring_not_in_the_os(level):
    # the pedestrian 11 m beyond a car parked 4 m ahead of the sensor (6 range cells: inside the ring), both standing
    ca_alone = _reported(parse_scenario(_stopped_ego_pedestrian("ca", False)), level, 1)[0]
    # masked in most cycles, not in all: where the car's reflectors happen to fade together for a few frames its
    # energy in the ring drops and the pedestrian comes through, in a few seeds' runs and then for some 10 cycles.
    # Seeds 1–24 with each face weighted by its aspect (2026-12-02): 62, 58 and 63 of 672 cycles at the object,
    # detection and signal levels (seeds 1–8 alone: 15, 39 and 9 — too few runs to bound a rate that comes in lumps)
    seeds = range(1, 25)
    ca_parked = sum(_reported(parse_scenario(_stopped_ego_pedestrian("ca", True)), level, seed)[0]
                    for seed in seeds)
    os_parked = _reported(parse_scenario(_stopped_ego_pedestrian("os", True)), level, 1)[0]
    assert ca_alone >= 20                              # of 28 cycles (two to confirm)
    assert ca_parked <= 0.15 * len(seeds) * 28
    # OS-CFAR ignores the car's cells: the object level misses none; at the detection level (and at the signal
    # level, 13–24 of 27 over seeds 1–3) the car's near-range response still costs some cycles (12–26 of 27)
    assert os_parked >= (25 if level == "object" else 10)
