"""Which model renders a fidelity level: :func:`make_model`, and the check of options a level cannot honour.

The object level is built here directly; the scatterer levels (detection, signal, auto, in
:mod:`radarnode.radar.models`) are imported only when one is asked for, so a command at the object level does
not import the signal chain's synthesis.
"""

from __future__ import annotations

import numpy as np

from radarnode.errors import ConfigError
from radarnode.radar.object_model import ObjectModel
from radarnode.radar.options import SignalOptions
from radarnode.radar.presets import RadarPreset
from radarnode.scene.world import Scene

FIDELITY_LEVELS = ("object", "detection", "signal", "auto")


def auto_refused(preset: RadarPreset) -> str | None:
    """Why ``auto`` cannot render ``preset``, or None: the object level reports a scanning radar's beam angle, the
    others measure none with one channel, so a frame mixing them would put one actor at its angle and its neighbour
    at boresight. One rule for the model, the scenario loader (file and line) and ``--fidelity``."""
    if preset.num_virtual < 2:
        return "one channel: the detection and signal levels measure no angle, the object level the beam's"
    return None


def check_doa(level: str, options: SignalOptions, scenario=None) -> None:
    """A super-resolution angle estimator exists only in the signal chain: refuse it at another level.

    The object and detection levels reproduce the beamformer's resolution (:data:`radarnode.radar.calibration.RESOLUTION`), not a
    super-resolution estimator's: they would report what that estimator does not. With ``scenario`` the error
    names its file and the line of ``signal.dsp.doa``.
    """
    if options.dsp.doa != "fft" and level in FIDELITY_LEVELS and level != "signal":
        msg = (f"field 'signal.dsp.doa': value {options.dsp.doa!r} is not allowed at fidelity {level!r}; "
               "expected 'fft' (the object and detection levels model the FFT beamformer), or fidelity 'signal' for a "
               "super-resolution estimator")
        if scenario is not None:
            from radarnode.schema import Source
            raise Source.of_lines(scenario.source, scenario.lines).error("signal.dsp.doa", msg)
        raise ConfigError(msg)


def check_level(level: str, options: SignalOptions, scenario=None) -> None:
    """Refuse the scenario's signal options that ``level`` cannot honour (each was taken and ignored without a word
    before, an independent tester's finding for the last two): a super-resolution estimator (:func:`check_doa`); a
    stated ``signal.snr_db`` at the object level, which takes each actor's SNR from the radar equation (one return
    per actor: no scatterers to give that SNR to; ``auto`` renders every actor at the detection level then); RF
    impairments at the object and detection levels, which exist only in the time-domain signal (``auto`` runs the
    signal level then). With ``scenario`` the error names its file and the field's line."""
    check_doa(level, options, scenario)
    field, msg = None, None
    if options.snr_db is not None and level == "object":
        field = "signal.snr_db"
        msg = (f"field 'signal.snr_db': value {options.snr_db:g} is not allowed at fidelity 'object': the object level "
               "takes each actor's SNR from the radar equation (one return per actor, no scatterers to give that SNR "
               "to); expected fidelity 'detection', 'signal' or 'auto' (which then renders every actor at the "
               "detection level), or no signal.snr_db")
    elif options.impairments.any and level in ("object", "detection"):
        field = "signal.impairments"
        msg = (f"field 'signal.impairments': RF impairments are not allowed at fidelity {level!r}: they exist only in "
               "the time-domain signal; expected fidelity 'signal' or 'auto' (which then runs the signal level), or "
               "no signal.impairments")
    if msg is None and scenario is not None:
        field, msg = _cube_refusal(level, options, scenario)
    if msg is None:
        return
    if scenario is not None:
        from radarnode.schema import Source
        raise Source.of_lines(scenario.source, scenario.lines).error(field, msg)
    raise ConfigError(msg)


def _cube_refusal(level: str, options: SignalOptions, scenario) -> tuple[str | None, str | None]:
    """(field, error) for a signal-level cube larger than this machine allows at ``level``
    (:func:`radarnode.radar.signal_model.check_cube_memory`, every chirp sequence of the scenario's radar), else
    (None, None): checked here, with the scenario, so that the error names its file and the line of its overrides
    before any run (it named neither, and a ``report`` of several scenarios did not say which to fix: an independent
    tester's finding)."""
    if not (level == "signal" or (level == "auto" and options.impairments.any)):
        return None, None
    from radarnode.radar.setup import radar_config, radar_path
    from radarnode.radar.signal_model import check_cube_memory
    preset = radar_config(scenario).preset
    field = f"{radar_path(scenario)}.overrides"
    try:
        for seq in preset.sequences():
            check_cube_memory(seq, options.complex_dtype, field)
    except ConfigError as exc:
        return field, str(exc)
    return None, None


def make_model(level: str, scene: Scene, preset: RadarPreset, rng: np.random.Generator,
               options: SignalOptions = SignalOptions(), clusters_wanted: bool = False):
    check_level(level, options)
    if level == "object":
        return ObjectModel(scene, preset, rng, options)
    from radarnode.radar import models     # the scatterer levels' modules only when one runs (a faster start)
    if level == "detection":
        return models.DetectionModel(scene, preset, rng, options)
    if level == "signal":
        return models.SignalModel(scene, preset, rng, options)
    if level == "auto":
        why = auto_refused(preset)
        if why is not None:
            raise ConfigError(f"fidelity: value 'auto' is not allowed with preset {preset.name} ({why}); expected "
                              "object, detection or signal")
        return models.AutoModel(scene, preset, rng, options, clusters_wanted)
    raise ConfigError(f"fidelity: value {level!r} is not allowed; expected one of {', '.join(FIDELITY_LEVELS)}")
