"""The fidelity levels behind one interface, and ``auto``.

Every model has ``step(t_s, config, sensor_velocity_est) -> (RadarFrame, SensorView)``.
The detection and signal levels share the scatterer generation (with the
actors' Swerling fluctuation), the velocity-ambiguity resolution
(:mod:`radarnode.radar.ambiguity`) and the perception step (clusters and the
object tracker); only how scatterers become detections differs. ``auto``
(:class:`AutoModel`) renders each actor at the cheapest level that keeps the
chain's answer and feeds one tracker.
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from radarnode.errors import ConfigError
from radarnode.dsp.spectra import noncoherent_power, range_doppler
from radarnode.radar.chain import DspChain
from radarnode.perception.tracker import (GROUP_EPS_LONG_M, GROUP_EPS_M, ObjectTracker, clusters_from_detections,
                                         follows_one_wrap)
from radarnode.perception.types import ClusterList, Detections, RadarFrame
from radarnode.radar import ambiguity, detection_model
from radarnode.radar.calibration import RESOLUTION
from radarnode.radar.elevation import GROUND_REFLECTION
from radarnode.radar.levels import FIDELITY_LEVELS, check_doa, make_model  # noqa: F401 (imported from here too)
from radarnode.radar.object_model import (POINT_SIZE_M, ObjectModel, RuntimeConfig, StepInfo, check_step, in_fov,
                                          nearest_in_fov, visible_fraction)
from radarnode.radar.presets import RadarPreset
from radarnode.radar.scatterers import Scatterers, scene_scatterers
from radarnode.radar.options import SignalOptions
from radarnode.radar.signal_model import check_cube_memory, decimation_for, synthesize, synthesize_rd
from radarnode.scene.world import Scene, SensorView


def tracker_for(preset: RadarPreset, period_s: float | None = None) -> ObjectTracker:
    """The detection and signal levels' tracker for ``preset`` run every ``period_s``: with staggered ramps it takes
    an unpaired detection's range rate modulo the first sequence's 2·v_max, and lists no track whose speed only such
    detections measured; with a single ramp whose one wrap moves a target less than the tracker's gate in a cycle
    (:func:`~radarnode.perception.tracker.follows_one_wrap`: ``fast_chirp``), it follows an aliased target and lists
    a track once the range it walks resolved the wrap (:class:`radarnode.perception.tracker.ObjectTracker`,
    ``range_walk``). A single ramp with a longer wrap (``mimo12``, ``acc_lrr``) never follows an aliased target: its
    range rates are taken as measured."""
    fov = tuple((s.max_range_m, math.radians(s.half_angle_deg)) for s in preset.fov)
    if preset.stagger_chirp_period_s > 0:
        return ObjectTracker(alias_span_mps=2.0 * preset.alias_speed_mps, fov=fov)
    span = 2.0 * preset.alias_speed_mps
    if period_s is not None and follows_one_wrap(span, period_s):
        return ObjectTracker(alias_span_mps=span, range_walk=True, fov=fov)
    return ObjectTracker(fov=fov)


def reportable(preset: RadarPreset, det: Detections, config: RuntimeConfig) -> np.ndarray:
    """Detections the radar reports: inside its field of view as it measured them and within MaxDistance.

    A λ/2 array cannot tell +88° from −92°; what lies outside the sectors is
    discarded, as the object level never sees it.
    """
    return in_fov(preset, det.range_m, det.azimuth_rad) & (det.range_m <= config.max_distance_m)


class ScattererModel:
    """Shared part of the detection and signal levels: scatterers in, frame out."""

    level = ""

    def __init__(self, scene: Scene, preset: RadarPreset, rng: np.random.Generator,
                 options: SignalOptions = SignalOptions(), keep_cube: bool = False) -> None:
        self.scene = scene
        self.preset = preset
        self.rng = rng
        self.options = options
        self.tracker = tracker_for(preset, scene.scenario.period_s)
        self.cycle = 0
        self.info = StepInfo()
        self.keep_cube = keep_cube

    def scatterers(self, t_s: float, view: SensorView, config: RuntimeConfig) -> Scatterers:
        o = self.options
        # the signal level's multipath impairment reflects every scatterer off the road itself: not twice
        scat = scene_scatterers(self.scene, t_s, view, self.preset, config.max_distance_m, o.scatterer_spacing_m,
                                self.rng, o.clutter_density_per_m2, o.clutter_rcs_dbsm,
                                0.0 if o.impairments.multipath else GROUND_REFLECTION)
        return fluctuate(self.scene, scat, self.rng)

    def sequences(self) -> list[RadarPreset]:
        """One preset per chirp sequence of a cycle (two with staggered ramps)."""
        return self.preset.sequences()

    def detections(self, scat: Scatterers, config: RuntimeConfig, preset: RadarPreset) -> Detections:
        """The detections of one chirp sequence (``preset``) of the cycle, speeds as measured (aliased)."""
        raise NotImplementedError  # pragma: no cover

    def step(self, t_s: float, config: RuntimeConfig, sensor_velocity_est: tuple[float, float] | None = None
             ) -> tuple[RadarFrame, SensorView]:
        check_step(t_s, sensor_velocity_est)
        t0 = time.perf_counter()
        view = self.scene.view(t_s)
        scat = self.scatterers(t_s, view, config)
        t1 = time.perf_counter()
        sv, yaw = ego_motion(self.scene, t_s, view, sensor_velocity_est)
        det = ambiguity.resolve(self.preset, [self.detections(scat, config, seq) for seq in self.sequences()], sv)
        det = det.take(reportable(self.preset, det, config))
        t2 = time.perf_counter()
        clusters = clusters_from_detections(det, self.preset.near_range_m, sv)
        objects = self.tracker.step(t_s, det, sv, yaw)
        t3 = time.perf_counter()
        self.info.level, self.info.scatterers, self.info.detections = self.level, scat, det
        self.info.seconds = {"scene": t1 - t0, "radar": t2 - t1, "perception": t3 - t2}
        frame = RadarFrame(t_s, self.cycle, objects, clusters)
        self.cycle += 1
        return frame, view


def fluctuate(scene: Scene, scat: Scatterers, rng: np.random.Generator) -> Scatterers:
    """Swerling 1 actors: one exponential power factor per actor and frame, shared by all its scatterers.

    Guardrail posts and clutter (actor −1) fluctuate each on its own (Swerling 1
    per post). One draw per actor of the scene whether it is visible or not, then
    one per scatterer. With ``signal.snr_db`` stated the amplitudes ignore the
    RCS, so nothing fluctuates.
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
    #: keep the range–Doppler power map of every cycle in ``info.rd_power`` (for a viewer; off: it costs a pass)
    keep_rd = False

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        for seq in self.sequences():
            check_cube_memory(seq, self.options.complex_dtype)
        self.chains = {seq.chirp_period_s: DspChain(seq, self.options.dsp) for seq in self.sequences()}

    def detections(self, scat: Scatterers, config: RuntimeConfig, preset: RadarPreset) -> Detections:
        o = self.options
        chain = self.chains[preset.chirp_period_s]
        cfg = o.dsp
        # the windowed range–Doppler spectrum straight from the scatterers where that path is exact (Hann
        # windows, no RF impairment, migration within its series; a kept cube needs the time domain)
        rd_path = (o.domain != "time" and not self.keep_cube and not o.impairments.any
                   and cfg.range_window == cfg.doppler_window == "hann")
        if rd_path:
            try:
                rd = synthesize_rd(preset, scat, self.rng, snr_db=o.snr_db, power_reduction_db=config.power_reduction_db,
                                   dtype=o.complex_dtype)
            except ConfigError:
                if o.domain == "range_doppler":
                    raise
                rd_path = False
        if rd_path:
            det = chain.process_rd(rd, config.power_reduction_db)
        else:
            far = float(np.max(scat.range_m)) if len(scat) else 0.0
            dec = decimation_for(preset, max(far, 1.0)) if o.decimate else 1
            cube = synthesize(preset, scat, self.rng, snr_db=o.snr_db, power_reduction_db=config.power_reduction_db,
                              dtype=o.complex_dtype, impairments=o.impairments, decimation=dec)
            if self.keep_cube and preset is self.preset:
                self.info.cube = cube
            if self.keep_rd:
                rd = range_doppler(cube, range_window=cfg.range_window, doppler_window=cfg.doppler_window)
                det = chain.process_rd(rd, config.power_reduction_db)
            else:
                det = chain.process(cube, dec, config.power_reduction_db)
        if self.keep_rd and preset is self.preset:
            self.info.rd_power = noncoherent_power(rd)
        # the signal chain cannot know the truth; tag each detection with the nearest scatterer for evaluation: where
        # it is, or where the chain sees it (an aliased speed's range coupling, a grating lobe's angle: a fast car's
        # detections were 1–2 m from it on ars408_like and went untagged, an independent tester's finding)
        if len(det) and len(scat):
            vb = detection_model.apparent_positions(preset, scat)[1]
            seen_r = ambiguity.coupled_range(preset, scat.range_m, scat.range_rate_mps, vb * preset.doppler_bin_mps)
            seen_az = ambiguity.apparent_azimuth(preset, scat.azimuth_rad)
            d2 = np.minimum((det.x_m[:, None] - scat.x_m[None, :]) ** 2 + (det.y_m[:, None] - scat.y_m[None, :]) ** 2,
                            (det.x_m[:, None] - (seen_r * np.cos(seen_az))[None, :]) ** 2
                            + (det.y_m[:, None] - (seen_r * np.sin(seen_az))[None, :]) ** 2)
            near = np.argmin(d2, axis=1)
            det.actor_index = np.where(d2[np.arange(len(det)), near] < 4.0, scat.actor_index[near], -1)
        return det


def conflicting_actors(preset: RadarPreset, scat: Scatterers, n_actors: int,
                       positions: tuple[np.ndarray, ...] | None = None) -> np.ndarray:
    """Actors with a scatterer within the reach of the detection level's lobe test
    (:data:`radarnode.radar.detection_model.LOBE_REACH_BINS`) of another actor's or of a post's, in range and Doppler
    at any angle (where they appear, aliasing included): shape (n_actors,) bool.

    Those are the actors whose detections the object level cannot give: the chain merges or splits what lies
    within its resolution (:data:`radarnode.radar.calibration.RESOLUTION`, plus a bin of margin: inside that reach),
    and its local-maximum test on the channel-summed map hides a weaker target there whatever the angle.
    ``positions``: the scatterers' :func:`~radarnode.radar.detection_model.apparent_positions`, if already known.
    """
    out = np.zeros(n_actors, dtype=bool)
    if len(scat) < 2:
        return out
    at = detection_model.apparent_positions(preset, scat) if positions is None else positions
    reach = np.maximum(detection_model.LOBE_REACH_BINS, np.asarray(RESOLUTION[:2], dtype=np.float64) + 1.0)
    pts, box = _map_points(preset, at, reach)
    import scipy.spatial  # imported when first needed: a faster start
    pairs = scipy.spatial.cKDTree(pts, boxsize=box).query_pairs(1.0, p=np.inf, output_type="ndarray")
    if pairs.size == 0:
        return out
    a, b = scat.actor_index[pairs[:, 0]], scat.actor_index[pairs[:, 1]]
    other = a != b
    for side in (a[other], b[other]):
        out[side[side >= 0]] = True
    return out


def _map_points(preset: RadarPreset, positions: tuple[np.ndarray, ...], reach: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Scatterers where they appear on the range–Doppler map (``positions``: range and Doppler bins, as
    :func:`~radarnode.radar.detection_model.apparent_positions` gives them) in units of ``reach`` (range bins,
    Doppler bins), wrapped into the map's box, and that box: for a periodic k-d tree (Doppler is circular), in which
    points within 1 (max-norm) are within ``reach`` of each other. Shapes (n, 2) and (2,)."""
    rb, vb, _ = positions
    box = np.array([preset.num_range_bins, preset.num_chirps]) / reach
    return np.mod(np.stack([rb, np.mod(vb, preset.num_chirps)], axis=1) / reach, box), box


def within_ring(preset: RadarPreset, positions: tuple[np.ndarray, ...], sources: np.ndarray,
                ring: tuple[float, float]) -> np.ndarray:
    """Scatterers with one of ``sources`` (bool, per scatterer) within the CA-CFAR's training ring of them: at most
    ``ring`` (range bins, Doppler bins) apart, where they appear (``positions``: the scatterers'
    :func:`~radarnode.radar.detection_model.apparent_positions`; Doppler circular). Shape (n,) bool; a source counts
    itself."""
    if not sources.any():
        return np.zeros(positions[0].size, dtype=bool)
    pts, box = _map_points(preset, positions, np.asarray(ring, dtype=np.float64))
    import scipy.spatial  # imported when first needed: a faster start
    dist, _ = scipy.spatial.cKDTree(pts[sources], boxsize=box).query(pts, k=1, p=np.inf, distance_upper_bound=1.0)
    return np.isfinite(dist)


#: an actor whose own reflectors, within the chain's range and Doppler resolution of each other, span at least this
#: many beams in angle (d·sinθ in units of 1/K) is an extended reflector to the chain: half its measured angular
#: resolution (:data:`RESOLUTION`), so that the cell's reflectors either glint — their sum's apparent angle wanders
#: across the span with their phases — or split into several angle peaks; the object level reports one point
GLINT_SPAN_BEAMS = 0.5 * RESOLUTION[2]


def extended_actors(preset: RadarPreset, scat: Scatterers, n_actors: int,
                    positions: tuple[np.ndarray, ...] | None = None) -> np.ndarray:
    """Actors with reflectors that share a range–Doppler resolution cell (:data:`RESOLUTION`, on a grid of cells that
    size, where they appear) and span :data:`GLINT_SPAN_BEAMS` or more in angle there: shape (n_actors,) bool.

    A bridge deck or a sign gantry across the road is 25–40 reflectors in one range cell over 0.4–1.1 beams at
    140–240 m (``ars408_like``), which the chain reports as one glinting, splitting, fragmenting object; a car ahead
    spans 0.02–0.2 beams there; a car crossing at 11 m a whole beam. ``positions`` as for :func:`conflicting_actors`.
    """
    out = np.zeros(n_actors, dtype=bool)
    own = scat.actor_index >= 0
    if n_actors == 0 or np.count_nonzero(own) < 2:
        return out
    p = preset
    rb, vb, u = detection_model.apparent_positions(p, scat) if positions is None else positions
    a = scat.actor_index[own]
    qr = np.floor(rb[own] / RESOLUTION[0]).astype(np.int64)
    qv = np.floor(np.mod(vb[own], p.num_chirps) / RESOLUTION[1]).astype(np.int64)
    uniq, inv = np.unique(np.stack([a, qr, qv], axis=1), axis=0, return_inverse=True)
    uniq = uniq[:, 0]
    lo = np.full(uniq.size, np.inf)
    hi = np.full(uniq.size, -np.inf)
    np.minimum.at(lo, inv.ravel(), u[own])
    np.maximum.at(hi, inv.ravel(), u[own])
    wide = (hi - lo) * p.num_virtual >= GLINT_SPAN_BEAMS
    first = np.zeros(uniq.size, dtype=np.int64)
    first[inv.ravel()] = a
    out[first[wide]] = True
    return out


#: a body wider than this many beamwidths as the sensor sees it is rendered at the detection level (:func:`wide_actors`)
WIDE_BEAMS = 2.0


def span_in_view(preset: RadarPreset, view) -> np.ndarray:
    """The azimuth (rad) each actor spans inside the field of view: its extent between its corners
    (``view.az_lo_rad``..``view.az_hi_rad``; across the ±π seam, the way round behind the sensor, for a box behind it)
    cut to each sector its nearest point is within range of, the widest of those cuts. 0 for an actor in no sector's
    reach or wholly outside every sector. Shape like ``view.x_m``."""
    lo = np.asarray(view.az_lo_rad, dtype=np.float64)
    hi = np.asarray(view.az_hi_rad, dtype=np.float64)
    # a box that does not enclose the sensor spans less than π: an extent of more is the one behind, through ±π,
    # [hi, lo + 2π], whose parts in front of the sector's edges are [hi, π] and [-π, lo]
    seam = (hi - lo) > np.pi
    rng = np.hypot(view.x_m, view.y_m)
    span = np.zeros(lo.shape)
    for sector in preset.fov:                                                  # a few sectors
        h = min(math.radians(sector.half_angle_deg), math.pi)
        front = np.clip(np.minimum(hi, h) - np.maximum(lo, -h), 0.0, None)
        behind = np.clip(h - np.maximum(hi, -h), 0.0, None) + np.clip(np.minimum(lo, h) + h, 0.0, None)
        cut = np.where(seam, behind, front)
        span = np.maximum(span, np.where(rng <= sector.max_range_m, cut, 0.0))
    return span


def wide_actors(preset: RadarPreset, view, beams: float = WIDE_BEAMS) -> np.ndarray:
    """Which actors span more than ``beams`` beamwidths of azimuth inside the field of view (:func:`span_in_view`:
    a body beside a corner radar, a car alongside). The chain reports such a body as several detections across the
    beam, whose radial speeds let the tracker fit its velocity at once; the object level's one point per actor
    carries one radial speed, near zero for a body sliding past, and a track started on it at the standing world's
    speed drifted off it by a metre a cycle: a car overtaking beside a corner radar yawed 45° was listed as two
    objects in 7–16 of its 70 cycles (seeds 1–2) where the signal level listed one (an independent tester's
    finding). A body behind the sensor or beside it outside the view is not one (its extent between its corners
    crossed the ±π seam and counted as 355°: a second tester's finding). Shape (n,)."""
    return span_in_view(preset, view) > beams * preset.angular_resolution_rad


#: a body whose reflectors in view lie further apart than this, in the trackers' grouping metric (x over
#: :data:`~radarnode.perception.tracker.GROUP_EPS_LONG_M`, y over :data:`~radarnode.perception.tracker.GROUP_EPS_M`),
#: is rendered at the detection level (:func:`long_actors`). Measured, not derived (``benchmarks/long_bodies.py``): on
#: ``ars408_like`` the detection level lists a car, an SUV or a van as two objects in 1–2 % of the cycles where that
#: diameter is below 1.2 and in 8–88 % of them above; 1.2 renders about as many actor-cycles at the detection level as
#: the axis-by-axis rule before it (47 % of the benchmark's set, 45 % before) and holds 92 % of those splits (83 %)
LONG_DIAMETER = 1.2


def long_actors(preset: RadarPreset, scat: Scatterers, n_actors: int, eps_long_m: float = GROUP_EPS_LONG_M,
                eps_m: float = GROUP_EPS_M, diameter: float = LONG_DIAMETER) -> np.ndarray:
    """Which actors' reflectors inside the field of view lie more than ``diameter`` apart in the trackers'
    grouping metric, sqrt((Δx/eps_long_m)² + (Δy/eps_m)²) (:func:`~radarnode.perception.tracker.group_detections`'
    DBSCAN scales, :data:`LONG_DIAMETER`): a truck or a bus whose side the sensor sees, beside it or crossing in front
    of it, and a van or an SUV seen obliquely on a bend. The chain detects its nearest corner and, of the reflectors
    along its side, the one that is strongest in that frame, 4–8 m further along as their fluctuation draws it; where
    the two fall in two groups the tracker lists two objects of the one body, as the ARS 408 often does with a truck.
    The object level's one point per actor never does: a truck the ego overtook in the next lane (ego 30 m/s, the
    truck 22 m/s from 30 m ahead, ``ars408_like``) was listed twice in 12–29 of 83 cycles at the detection and signal
    levels, by auto in 4 (seeds 1–2); a truck crossing 26 m ahead at 10 m/s in 190 and 215 of 216, by auto in none
    (seeds 1–4); a 5.1-m SUV 50 m ahead on a bend of 250 m radius (its reflectors 4.5 m apart along x and 2.4 m
    across: neither axis alone beyond its scale) in 57 of 328 cycles, by auto in none while each axis was tested
    alone (independent testers' findings). Measured in the metric the tracker groups by, the diameter of a body whose
    side is seen edge-on in the next lane grows with its length only: a 5.05-m car there (1.16) is left to the
    object level, where the axis rule rendered every cycle of it at the detection level (1.9 → 5.2 ms a cycle) and
    the chain listed it once in every cycle. The box of its reflectors decides most bodies (its longer side beyond
    ``diameter``: long; its diagonal within: not); the pairs are taken only of bodies between, whose box is at most
    ``diameter`` on a side (a 300-m body of 2,467 reflectors had cost 6.1 million pairs, 161 ms and 232 MiB: an
    independent tester's finding). ``actor_index`` ≥ ``n_actors`` is refused. Shape (n_actors,)."""
    out = np.zeros(n_actors, dtype=bool)
    own = scat.actor_index >= 0
    if n_actors == 0 or not own.any():
        return out
    if int(scat.actor_index.max()) >= n_actors:
        raise ValueError(f"long_actors: actor_index holds {int(scat.actor_index.max())}, not below n_actors = "
                         f"{n_actors}; expected -1 (no actor) or an actor's index 0 … n_actors − 1")
    seen = in_fov(preset, scat.range_m[own], scat.azimuth_rad[own])
    if np.count_nonzero(seen) < 2:
        return out
    a = scat.actor_index[own][seen]
    order = np.argsort(a, kind="stable")
    a = a[order]
    u = (scat.x_m[own][seen] / eps_long_m)[order]
    v = (scat.y_m[own][seen] / eps_m)[order]
    # the diameter lies between the box's longer side and its diagonal: those decide most bodies outright
    count = np.bincount(a, minlength=n_actors)
    first = np.cumsum(count) - count
    has = np.flatnonzero(count)
    span_u = np.maximum.reduceat(u, first[has]) - np.minimum.reduceat(u, first[has])
    span_v = np.maximum.reduceat(v, first[has]) - np.minimum.reduceat(v, first[has])
    out[has] = np.maximum(span_u, span_v) > diameter
    open_ = has[~out[has] & (np.hypot(span_u, span_v) > diameter)]
    if open_.size:
        # every pair of the reflectors of the bodies left, whose box is at most ``diameter`` on a side (some 5 × 3 m:
        # a few hundred reflectors at the finest spacing, where a whole body's pairs grew with its length squared)
        pick = np.isin(a, open_)
        a, u, v = a[pick], u[pick], v[pick]
        count = np.bincount(a, minlength=n_actors)
        first = np.cumsum(count) - count
        reps = count[a]
        i = np.repeat(np.arange(a.size), reps)
        j = first[a[i]] + (np.arange(i.size) - np.repeat(np.cumsum(reps) - reps, reps))
        d2 = (u[i] - u[j]) ** 2 + (v[i] - v[j]) ** 2
        widest = np.zeros(n_actors)
        np.maximum.at(widest, a[i], d2)
        out[open_] = widest[open_] > diameter * diameter
    return out


def across_an_edge(preset: RadarPreset, view, length_m: np.ndarray, width_m: np.ndarray) -> np.ndarray:
    """Which actors a sector's edge crosses (their nearest point outside the field of view, a part of them inside:
    :func:`radarnode.radar.object_model.nearest_in_fov` moves it), bodies larger than a point. The object level
    measures such a body at its point on the edge, which slides along the edge as the body comes into view; the
    chain sees the inner parts of its outline. Fed to one tracker in turns, the two were taken for two bodies: a
    car overtaking into the view listed a second object of it, with a lateral speed of 12 m/s, for four cycles (an
    independent tester's finding; 11 cycles in seeds 1–6 of that overtake, none at either level alone). Shape (n,)."""
    x_in, y_in = nearest_in_fov(preset, view, length_m, width_m)
    return ((x_in != view.x_m) | (y_in != view.y_m)) & ~((length_m <= POINT_SIZE_M) & (width_m <= POINT_SIZE_M))


def shadowed_actors(preset: RadarPreset, scene: Scene, view, max_distance_m: float) -> np.ndarray:
    """Which actors in view another actor nearer the sensor partly hides (:func:`visible_fraction` strictly between 0
    and 1, measured as the object level measures it: at each body's nearest point in the field of view, guardrails
    hiding nothing). The object level takes such a body as one point whose RCS it scales by the fraction seen; the
    chain sees the reflectors in the part left in view, which a sliver may hold none of: a motorcycle 11 m behind a
    car and 1.1 m across was listed in 35 of 35 cycles by the object level, and by ``auto``, which left it there, in
    none by the detection and signal levels (mimo12; 17, 0 and 0 on ars408_like; an independent tester's finding).
    Shape (n,)."""
    x_in, y_in = nearest_in_fov(preset, view, scene.length_m, scene.width_m)
    seen = dataclasses.replace(view, x_m=x_in, y_m=y_in)
    rng_m = seen.range_m
    observable = in_fov(preset, rng_m, seen.azimuth_rad) & (rng_m <= max_distance_m)
    if np.count_nonzero(observable) < 2:
        return np.zeros(rng_m.shape, dtype=bool)
    elev = (*scene.elevation_extent(seen), scene.elevated) if scene.elevated.any() else None
    frac = visible_fraction(rng_m, seen.az_lo_rad, seen.az_hi_rad, ~scene.is_guardrail & observable, elev)
    return observable & (frac > 0.0) & (frac < 1.0)


class AutoModel:
    """``auto``: each actor at the cheapest level that keeps the chain's answer, one tracker for all.

    Per frame and per actor: the object level's detection of it (the chain's
    Pd law, its measured accuracy and the same velocity aliasing, by
    construction and checked by ``benchmarks/calibration.py``) unless its
    scatterers come within the chain's measured resolution of another actor's
    or of a guardrail post's — there the detection level renders them, because
    the chain merges or splits what lies that close — or posts or clutter lie in
    its CA-CFAR training ring (:func:`within_ring`: the object level's masking
    counts the other actors only), or its own reflectors
    spread across the beam within one resolution cell (:func:`extended_actors`:
    a bridge deck, a gantry, a car crossing close by), whose glint and splitting
    the object level's one point per actor does not have, or a sector's edge
    crosses it (:func:`across_an_edge`: the object level's point slides along
    the edge, the chain sees the inner outline), or it spans more than
    WIDE_BEAMS beamwidths (:func:`wide_actors`: the chain's detections across
    it give the tracker its velocity, one point does not), or its reflectors in
    view lie further apart than LONG_DIAMETER in the trackers' grouping metric
    (:func:`long_actors`: a truck whose side the chain sees, listed as two
    objects where its corner and its side's strongest reflector fall in two
    groups; one point never is), or another actor nearer the sensor hides part of
    it (:func:`shadowed_actors`: the object level scales one point's RCS by the
    fraction seen, the chain sees the reflectors in the part in view). Posts and clutter always
    go through the detection level (the object level has no model of them,
    and the chain reports them as clusters and stationary objects), with the
    reflectors of object-level actors in their rings for their energy (their
    detections are the object level's). RF impairments
    exist only in the time-domain signal: a scene that asks for them runs the
    signal level throughout; a stated ``signal.snr_db`` (every scatterer's SNR)
    renders every actor at the detection level, the object level having no
    scatterers. Because both parts feed one tracker, a change of level never
    drops a track, swaps an ID or empties a frame.
    """

    def __init__(self, scene: Scene, preset: RadarPreset, rng: np.random.Generator,
                 options: SignalOptions = SignalOptions(), clusters_wanted: bool = False) -> None:
        # the object level's own stream: it draws a block of cycles when it computes a chunk, and how its chunks
        # fall (the run's length) must not change what the detection level draws from ``rng``
        self.object = ObjectModel(scene, preset, np.random.default_rng(int(rng.integers(0, 2**63))), options)
        self.detection = DetectionModel(scene, preset, rng, options)
        # the signal level only where the scene asks for impairments, the one case that runs it (its cube must then
        # fit, and its chains are built for nothing otherwise)
        self.signal = SignalModel(scene, preset, rng, options) if options.impairments.any else None
        self.scene = scene
        self.options = options
        self.clusters_wanted = clusters_wanted
        self.preset = preset
        self.tracker = tracker_for(preset, scene.scenario.period_s)
        cfar = self.detection.statistic.cfar
        #: the CA-CFAR training ring's reach (range bins, Doppler bins) from a cell under test
        self.ring = (cfar.guard[1] + cfar.train[1], cfar.guard[0] + cfar.train[0])
        self.wide_beams = WIDE_BEAMS
        self.cycle = 0
        self.choices = {"object": 0, "detection": 0, "signal": 0}
        self.actor_frames = {"object": 0, "detection": 0}
        self.info = StepInfo()

    def step(self, t_s, config, sensor_velocity_est=None):
        check_step(t_s, sensor_velocity_est)
        if self.options.impairments.any:
            self.choices["signal"] += 1
            out = self.signal.step(t_s, config, sensor_velocity_est)
            self.info = self.signal.info
            return out
        t0 = time.perf_counter()
        view = self.scene.view(t_s)
        scat = self.detection.scatterers(t_s, view, config)
        # (where each scatterer appears, once for both tests: ``positions``, detection_model.apparent_positions)
        at = detection_model.apparent_positions(self.preset, scat)
        if self.options.snr_db is not None:
            # a stated per-scatterer SNR is the scatterer levels' (the object level takes the radar equation: its
            # actors kept their distance-given SNR beside the stated one, an independent tester's finding)
            conflict = np.ones(self.scene.n, dtype=bool)
        else:
            conflict = conflicting_actors(self.preset, scat, self.scene.n, at) | extended_actors(self.preset, scat,
                                                                                                 self.scene.n, at)
            conflict |= across_an_edge(self.preset, view, self.scene.length_m, self.scene.width_m)
            conflict |= wide_actors(self.preset, view, self.wide_beams)
            conflict |= long_actors(self.preset, scat, self.scene.n)
            conflict |= shadowed_actors(self.preset, self.scene, view, config.max_distance_m)
        # posts and clutter are many small reflectors: only the detection level has them (the chain reports them
        # as clusters and its tracker as stationary objects)
        need = scat.actor_index < 0
        ring = self.ring
        if need.any() and conflict.size:
            # an actor with posts or clutter in its CA-CFAR training ring: the object level's masking counts the
            # other actors only, so the chain's threshold there is the detection level's to draw (a bicycle 5.6
            # Doppler bins off a guardrail's posts, masked by them in the chain, was reported in every cycle)
            near = within_ring(self.preset, at, need, ring) & ~need
            conflict[scat.actor_index[near]] = True
        if conflict.size:
            need |= conflict[np.maximum(scat.actor_index, 0)] & ~need
        # the reflectors of object-level actors in the rendered ones' training rings come along for their energy
        # (the detection level's CFAR and lobe tests see them; their own detections are the object level's): two
        # pedestrians rendered without the truck 7 range bins away were reported where the chain loses them
        context = within_ring(self.preset, at, need, ring) & ~need if need.any() else need
        # the object level: kinematics, Pd and noise of every actor; its detections of the simple actors
        sv, yaw = ego_motion(self.scene, t_s, view, sensor_velocity_est)
        self.object.step(t_s, dataclasses.replace(config, clusters=False),
                         None if sensor_velocity_est is None else sv)
        det_o = self.object.info.detections
        parts = [det_o.take(~conflict[det_o.actor_index])]
        if need.any():
            sub = scat.take(need | context)
            rendered = ambiguity.resolve(self.preset, [self.detection.detections(sub, config, seq)
                                                       for seq in self.detection.sequences()], sv)
            if context.any():
                own = rendered.actor_index
                rendered = rendered.take((own < 0) | conflict[np.maximum(own, 0)])
            parts.append(rendered)
        det = Detections.concat(parts)
        det = det.take(reportable(self.preset, det, config))
        level = "detection" if need.any() else "object"
        self.choices[level] += 1
        self.actor_frames["detection"] += int(conflict.sum())
        self.actor_frames["object"] += int(self.scene.n - conflict.sum())
        t1 = time.perf_counter()
        clusters = clusters_from_detections(det, self.preset.near_range_m, sv) if config.clusters else \
            ClusterList.empty(0)
        objects = self.tracker.step(t_s, det, sv, yaw)
        self.info = StepInfo(level=level, scatterers=scat, detections=det,
                             seconds={"radar": t1 - t0, "perception": time.perf_counter() - t1})
        frame = RadarFrame(t_s, self.cycle, objects, clusters)
        self.cycle += 1
        return frame, view


def ego_motion(scene: Scene, t_s: float, view: SensorView, estimate) -> tuple[tuple[float, float], float]:
    """The sensor's velocity (sensor axes) and the ego's yaw rate as the radar knows them: from the ego-motion
    input, ``(vx, vy)`` or ``(vx, vy, yaw_rate_rps)``, or from the truth when there is none."""
    if estimate is None:
        return (view.sensor_vx_mps, view.sensor_vy_mps), scene.ego_state(t_s).yaw_rate_rps
    if len(estimate) == 3:
        return (estimate[0], estimate[1]), float(estimate[2])
    return (estimate[0], estimate[1]), 0.0
