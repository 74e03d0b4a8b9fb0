"""Scenario files and the synthetic road scene they describe."""

from radarnode.scene.scenario import Scenario, load_scenario

__all__ = ["Scenario", "load_scenario"]
