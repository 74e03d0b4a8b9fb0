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

import numpy as np

from radarnode.errors import FieldError, yaml_repr
from radarnode.radar.chain import DspConfig, preset_conflicts
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


def radar_path(scenario: Scenario) -> str:
    """The field path of the scenario's radar in its file: ``radar``, or ``radars[i]`` for one of several
    (:func:`radar_scenarios`)."""
    return scenario.__dict__.get("_radar_path", "radar")


def radar_config(scenario: Scenario) -> RadarConfig:
    """Build and validate the scenario's radar configuration (built once per scenario object)."""
    cached = scenario.__dict__.get("_radar_config")
    if cached is not None:
        return cached
    src = Source.of_lines(scenario.source, scenario.lines)
    root = radar_path(scenario)
    try:
        preset = get_preset(scenario.radar.preset).with_overrides(scenario.radar.overrides)
    except FieldError as exc:
        child = f"{root}.{exc.field}"
        raise src.error(child, f"field '{child}': value {yaml_repr(exc.value)} is not allowed; expected "
                               f"{exc.allowed}") from None
    if scenario.fidelity == "auto":
        from radarnode.radar.levels import auto_refused
        why = auto_refused(preset)
        if why is not None:
            raise src.error("fidelity", f"field 'fidelity': value 'auto' is not allowed with preset {preset.name} of "
                                        f"{root} ({why}); expected object, detection or signal")
    signal = _with_preset_pfa(build(SignalOptions, scenario.signal, "signal", src, SIGNAL_SCHEMA), scenario, preset,
                              src, root)
    _check_dsp_for_preset(signal.dsp, preset, src, root)
    cfg = RadarConfig(preset=preset, signal=signal)
    object.__setattr__(scenario, "_radar_config", cfg)  # a cache on a frozen dataclass, like functools.cached_property
    return cfg


def _with_preset_pfa(signal: SignalOptions, scenario: Scenario, preset: RadarPreset, src: Source,
                     root: str) -> SignalOptions:
    """The CFAR's false-alarm probability: ``signal.dsp.pfa`` where the file gives it, else the preset's ``pfa`` (so
    that ``overrides: {pfa: 1e-3}`` sets it; it used to be validated and then never read). Both given and different
    is refused: one of them would be ignored."""
    dsp = scenario.signal.get("dsp") if isinstance(scenario.signal, dict) else None
    given = isinstance(dsp, dict) and "pfa" in dsp
    overridden = "pfa" in (scenario.radar.overrides or {})
    if given and overridden and signal.dsp.pfa != preset.pfa:
        raise src.error("signal.dsp.pfa", f"field 'signal.dsp.pfa': value {yaml_repr(signal.dsp.pfa)} is not allowed; "
                                          f"expected {yaml_repr(preset.pfa)}, the pfa {root}.overrides sets (or one "
                                          "of the two left out)")
    if given or signal.dsp.pfa == preset.pfa:
        return signal
    return dataclasses.replace(signal, dsp=dataclasses.replace(signal.dsp, pfa=preset.pfa))


def _check_dsp_for_preset(dsp: DspConfig, preset: RadarPreset, src: Source, root: str) -> None:
    """The signal chain's options that the preset cannot run (``radarnode.radar.chain.preset_conflicts``), refused at
    load time with the file and line."""
    conflicts = preset_conflicts(dsp, preset)
    if conflicts:
        field, why, allowed = conflicts[0]
        child = f"signal.dsp.{field}"
        raise src.error(child, f"field '{child}': value {yaml_repr(getattr(dsp, field))} is not allowed; expected "
                               f"{allowed} with preset {preset.name} of {root} ({why})")


def with_signal(scenario: Scenario, **changes) -> Scenario:
    """A copy of ``scenario`` whose signal options have ``changes`` applied (validated like the file's)."""
    return resolved(dataclasses.replace(scenario, signal={**scenario.signal, **changes}))


def resolved(scenario: Scenario) -> Scenario:
    """Validate the radar part and fill in the preset's cycle period where the scenario sets none."""
    if scenario.radars:
        radar_scenarios(scenario)           # every radar checked first, so that an error names radars[i], not radar
    cfg = radar_config(scenario)
    if scenario.cycle_period_s is None:
        scenario = dataclasses.replace(scenario, cycle_period_s=cfg.preset.cycle_period_s)
        object.__setattr__(scenario, "_radar_config", cfg)
    return scenario


def radar_seed(seed: int, index: int) -> int:
    """The seed of radar ``index`` of several: the scenario's for the first (so adding radars does not change the
    first one's frames), one derived from (seed, index) for the others (independent noise)."""
    if index == 0:
        return seed
    return int(np.random.SeedSequence([seed, index]).generate_state(2, dtype=np.uint64)[0] >> np.uint64(1))


def radar_scenarios(scenario: Scenario) -> list[Scenario]:
    """One single-radar scenario per radar of ``scenario`` (its ``radars``, or itself): the same scene, period and
    duration; radar i's setup and seed (:func:`radar_seed`). Errors name ``radars[i].…``."""
    if not scenario.radars:
        return [scenario]
    cached = scenario.__dict__.get("_radar_scenarios")
    if cached is not None:
        return cached
    out = []
    for i, setup in enumerate(scenario.radars):
        sc = dataclasses.replace(scenario, radar=setup, radars=None, seed=radar_seed(scenario.seed, i))
        object.__setattr__(sc, "_radar_path", f"radars[{i}]")
        radar_config(sc)
        out.append(sc)
    object.__setattr__(scenario, "_radar_scenarios", out)
    return out


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


__all__ = ["RadarConfig", "load_scenario", "parse_scenario", "radar_config", "radar_path", "radar_scenarios", "radar_seed",
           "resolved", "with_signal"]
