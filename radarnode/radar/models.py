"""The fidelity levels behind one interface, and ``auto``.

Every model has ``step(t_s, config, sensor_velocity_est) -> (RadarFrame, SensorView)``.
The detection and signal levels share the scatterer generation and the
perception step (clusters and the object tracker); only how scatterers become
detections differs. ``auto`` picks per frame the cheapest level that keeps the
scene's accuracy: the signal level where the scene asks for RF impairments or
where two scatterers of different actors share a resolution cell (only the
signal level resolves or merges them as the radar would), the detection
level where a cluster list is sent (the object level has no per-scatterer
detections), the object level otherwise.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from radarnode.dsp.chain import DspChain
from radarnode.perception.tracker import ObjectTracker, clusters_from_detections
from radarnode.perception.types import Detections, RadarFrame
from radarnode.radar import ambiguity, detection_model
from radarnode.radar.object_model import ObjectModel, RuntimeConfig, StepInfo
from radarnode.radar.presets import RadarPreset
from radarnode.radar.scatterers import Scatterers, scene_scatterers
from radarnode.radar.options import SignalOptions
from radarnode.radar.signal_model import decimation_for, synthesize
from radarnode.scene.world import Scene, SensorView

FIDELITY_LEVELS = ("object", "detection", "signal", "auto")


class ScattererModel:
    """Shared part of the detection and signal levels: scatterers in, frame out."""

    level = ""

    def __init__(self, scene: Scene, preset: RadarPreset, rng: np.random.Generator,
                 options: SignalOptions = SignalOptions(), keep_cube: bool = False) -> None:
        self.scene = scene
        self.preset = preset
        self.rng = rng
        self.options = options
        self.tracker = ObjectTracker()
        self.cycle = 0
        self.info = StepInfo()
        self.keep_cube = keep_cube

    def scatterers(self, t_s: float, view: SensorView, config: RuntimeConfig) -> Scatterers:
        o = self.options
        scat = scene_scatterers(self.scene, t_s, view, self.preset, config.max_distance_m, o.scatterer_spacing_m,
                                self.rng, o.clutter_density_per_m2, o.clutter_rcs_dbsm)
        return fluctuate(self.scene, scat, self.rng)

    def sequences(self) -> list[RadarPreset]:
        """One preset per chirp sequence of a cycle (two with staggered ramps)."""
        p = self.preset
        return [p, p.second_sequence()] if p.stagger_chirp_period_s else [p]

    def detections(self, scat: Scatterers, config: RuntimeConfig, preset: RadarPreset) -> Detections:
        """The detections of one chirp sequence (``preset``) of the cycle, speeds as measured (aliased)."""
        raise NotImplementedError  # pragma: no cover

    def step(self, t_s: float, config: RuntimeConfig, sensor_velocity_est: tuple[float, float] | None = None
             ) -> tuple[RadarFrame, SensorView]:
        t0 = time.perf_counter()
        view = self.scene.view(t_s)
        scat = self.scatterers(t_s, view, config)
        t1 = time.perf_counter()
        sv = sensor_velocity_est if sensor_velocity_est is not None else (view.sensor_vx_mps, view.sensor_vy_mps)
        det = ambiguity.resolve(self.preset, [self.detections(scat, config, seq) for seq in self.sequences()], sv)
        det = det.take(det.range_m <= config.max_distance_m)
        t2 = time.perf_counter()
        clusters = clusters_from_detections(det, self.preset.near_range_m, sv)
        objects = self.tracker.step(t_s, det, sv)
        t3 = time.perf_counter()
        self.info.level, self.info.scatterers, self.info.detections = self.level, scat, det
        self.info.seconds = {"scene": t1 - t0, "radar": t2 - t1, "perception": t3 - t2}
        frame = RadarFrame(t_s, self.cycle, objects, clusters)
        self.cycle += 1
        return frame, view


def fluctuate(scene: Scene, scat: Scatterers, rng: np.random.Generator) -> Scatterers:
    """Swerling 1 actors: one exponential power factor per actor and frame, shared by all its scatterers.

    Guardrail posts and clutter (actor −1) fluctuate each on its own (Swerling 1
    per post). One draw per actor and one per scatterer, always, so the random
    stream does not depend on which actors are visible.
    """
    per_actor = rng.exponential(1.0, max(scene.n, 1))
    per_point = rng.exponential(1.0, len(scat))
    if len(scat) == 0:
        return scat
    a = scat.actor_index
    own = a >= 0
    factor = np.where(own, per_actor[np.where(own, a, 0)], per_point)
    steady = own & (scene.swerling[np.where(own, a, 0)] == 0) if scene.n else np.zeros(len(scat), dtype=bool)
    factor = np.where(steady, 1.0, factor)
    scat.rcs_dbsm = scat.rcs_dbsm + 10.0 * np.log10(np.maximum(factor, 1e-12))
    return scat


class DetectionModel(ScattererModel):
    level = "detection"

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.statistic = DspChain(self.preset, self.options.dsp).statistic

    def detections(self, scat: Scatterers, config: RuntimeConfig, preset: RadarPreset) -> Detections:
        return detection_model.detect(preset, scat, self.rng, self.statistic,
                                      power_reduction_db=config.power_reduction_db, snr_db=self.options.snr_db)


class SignalModel(ScattererModel):
    level = "signal"

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.chains = {seq.chirp_period_s: DspChain(seq, self.options.dsp) for seq in self.sequences()}

    def detections(self, scat: Scatterers, config: RuntimeConfig, preset: RadarPreset) -> Detections:
        o = self.options
        far = float(np.max(scat.range_m)) if len(scat) else 0.0
        dec = decimation_for(preset, max(far, 1.0)) if o.decimate else 1
        cube = synthesize(preset, scat, self.rng, snr_db=o.snr_db, power_reduction_db=config.power_reduction_db,
                          dtype=o.complex_dtype, impairments=o.impairments, decimation=dec)
        if self.keep_cube and preset is self.preset:
            self.info.cube = cube
        det = self.chains[preset.chirp_period_s].process(cube, dec, config.power_reduction_db)
        # the signal chain cannot know the truth; tag each detection with the nearest scatterer for evaluation
        if len(det) and len(scat):
            d2 = ((det.x_m[:, None] - scat.x_m[None, :]) ** 2 + (det.y_m[:, None] - scat.y_m[None, :]) ** 2)
            near = np.argmin(d2, axis=1)
            det.actor_index = np.where(d2[np.arange(len(det)), near] < 4.0, scat.actor_index[near], -1)
        return det


def shares_a_cell(preset: RadarPreset, scat: Scatterers) -> bool:
    """True when scatterers of two different actors fall in one range–Doppler–angle resolution cell."""
    if len(scat) < 2:
        return False
    key = np.stack([np.rint(scat.range_m / preset.range_resolution_m),
                    np.rint(scat.range_rate_mps / preset.speed_resolution_mps),
                    np.rint(np.sin(scat.azimuth_rad) / preset.angular_resolution_rad)], axis=1).astype(np.int64)
    _, inv = np.unique(key, axis=0, return_inverse=True)
    inv = inv.ravel()
    lo = np.full(inv.max() + 1, np.iinfo(np.int64).max)
    hi = np.full(inv.max() + 1, np.iinfo(np.int64).min)
    np.minimum.at(lo, inv, scat.actor_index)
    np.maximum.at(hi, inv, scat.actor_index)
    return bool(np.any(lo != hi))


class AutoModel:
    """Per frame, the cheapest level the scene needs (see the module docstring); counts the choices."""

    def __init__(self, scene: Scene, preset: RadarPreset, rng: np.random.Generator,
                 options: SignalOptions = SignalOptions(), clusters_wanted: bool = False) -> None:
        self.object = ObjectModel(scene, preset, rng, options)
        self.detection = DetectionModel(scene, preset, rng, options)
        self.signal = SignalModel(scene, preset, rng, options)
        self.options = options
        self.clusters_wanted = clusters_wanted
        self.preset = preset
        self.choices = {"object": 0, "detection": 0, "signal": 0}
        self.info = StepInfo()

    def step(self, t_s, config, sensor_velocity_est=None):
        if self.options.impairments.any:
            level = "signal"
        else:
            view = self.detection.scene.view(t_s)
            scat = self.detection.scatterers(t_s, view, config)
            if shares_a_cell(self.preset, scat):
                level = "signal"
            elif self.clusters_wanted:
                level = "detection"
            else:
                level = "object"
        self.choices[level] += 1
        model = getattr(self, level)
        out = model.step(t_s, config, sensor_velocity_est)
        self.info = getattr(model, "info", StepInfo(level=level))
        self.info.level = level
        return out


def make_model(level: str, scene: Scene, preset: RadarPreset, rng: np.random.Generator,
               options: SignalOptions = SignalOptions(), clusters_wanted: bool = False):
    from radarnode.errors import ConfigError
    if level == "object":
        return ObjectModel(scene, preset, rng, options)
    if level == "detection":
        return DetectionModel(scene, preset, rng, options)
    if level == "signal":
        return SignalModel(scene, preset, rng, options)
    if level == "auto":
        return AutoModel(scene, preset, rng, options, clusters_wanted)
    raise ConfigError(f"fidelity: value {level!r} is not allowed; expected one of {', '.join(FIDELITY_LEVELS)}")
