"""Scenario files and the synthetic road scene they describe."""

from radarnode.scene.scenario import Scenario, read_scenario

__all__ = ["Scenario", "read_scenario"]
