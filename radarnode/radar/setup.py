"""The radar part of a scenario: preset, overrides and signal-level options, validated by the radar package.

The scene package reads a scenario file and checks the scene; what the radar is (``radar.preset``,
``radar.overrides``) and how the signal level runs (``signal``) are the radar's to check, here, with the same
``file:line: field …`` errors. :func:`load_scenario` is the one loader callers use: it reads the file, builds
the radar configuration and fills in the cycle period from the preset when the file does not set one.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

from radarnode.errors import FieldError, short_repr
from radarnode.radar.chain import DspConfig
from radarnode.radar.checks import check_scenario
from radarnode.radar.options import Impairments, SignalOptions
from radarnode.radar.presets import RadarPreset, get_preset
from radarnode.scene.scenario import Scenario, read_scenario, read_scenario_text
from radarnode.schema import Schema, Source, build

SIGNAL_SCHEMA = Schema(nested={SignalOptions: {"dsp": (DspConfig, False), "impairments": (Impairments, False)}})


@dataclass(frozen=True)
class RadarConfig:
    """The radar a scenario asks for: the preset with its overrides applied, and the signal-level options."""

    preset: RadarPreset
    signal: SignalOptions


def radar_config(scenario: Scenario) -> RadarConfig:
    """Build and validate the scenario's radar configuration (built once per scenario object)."""
    cached = scenario.__dict__.get("_radar_config")
    if cached is not None:
        return cached
    src = Source.of_lines(scenario.source, scenario.lines)
    try:
        preset = get_preset(scenario.radar.preset).with_overrides(scenario.radar.overrides)
    except FieldError as exc:
        child = f"radar.{exc.field}"
        raise src.error(child, f"field '{child}': value {short_repr(exc.value)} is not allowed; expected "
                               f"{exc.allowed}") from None
    signal = build(SignalOptions, scenario.signal, "signal", src, SIGNAL_SCHEMA)
    cfg = RadarConfig(preset=preset, signal=signal)
    object.__setattr__(scenario, "_radar_config", cfg)  # a cache on a frozen dataclass, like functools.cached_property
    return cfg


def with_signal(scenario: Scenario, **changes) -> Scenario:
    """A copy of ``scenario`` whose signal options have ``changes`` applied (validated like the file's)."""
    return resolved(dataclasses.replace(scenario, signal={**scenario.signal, **changes}))


def resolved(scenario: Scenario) -> Scenario:
    """Validate the radar part and fill in the preset's cycle period where the scenario sets none."""
    cfg = radar_config(scenario)
    if scenario.cycle_period_s is None:
        scenario = dataclasses.replace(scenario, cycle_period_s=cfg.preset.cycle_period_s)
        object.__setattr__(scenario, "_radar_config", cfg)
    return scenario


def load_scenario(path: str | Path) -> Scenario:
    """Read and validate a scenario file, scene and radar.

    Raises
    ------
    ScenarioError
        With ``file:line: field 'a.b': value X is not allowed; expected ...``.
    """
    return check_scenario(resolved(read_scenario(path)))      # what a tester gets wrong: radarnode.radar.checks


def parse_scenario(text: str, name: str = "<string>") -> Scenario:
    """Like :func:`load_scenario` for YAML text (used by tests and tools)."""
    return check_scenario(resolved(read_scenario_text(text, name)))


__all__ = ["RadarConfig", "load_scenario", "parse_scenario", "radar_config", "resolved", "with_signal"]
