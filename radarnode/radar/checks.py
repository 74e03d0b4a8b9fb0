"""Checks of a loaded scenario for what a tester gets wrong, beyond the value checks of each field.

Run by the loader (:func:`radarnode.radar.setup.load_scenario`) on every scenario file, with the file's lines:

* **Conflicting motion** (error). An actor with ``waypoints`` moves along them; ``speed_mps``, ``heading_deg``,
  ``x_m``, ``y_m`` or ``lane`` written beside them are not used. Where such a field agrees with the waypoints
  (the speed or the direction of one of its segments, the first waypoint's position) it is
  taken as the note the user meant it to be; where it disagrees the file says two different things and the
  error names the field, its line and what the waypoints say.
* **An actor on top of the ego at the start** (error): its box and the ego's (``ego.length_m`` ×
  ``ego.width_m``, the rear axle 1 m ahead of the rear end, as the viewer draws it) intersect at t = 0. No radar
  reports a car inside the car it sits on; the model's output would be meaningless. An actor whose bottom is
  ``EGO_HEIGHT_M`` (2 m, :mod:`radarnode.scene.world`) or more above the road (a bridge, a gantry, an overhead sign)
  passes over the ego. The test is ``Scene.ego_contacts``, the one the report's collision judge takes.
* **An expectation's option without the expectation** (error): ``min_gap_m``, ``fcw_ttc_min_s``,
  ``fcw_before_impact_s``, ``gap_settle_s`` or ``ttc_with_lead_decel`` without ``ecu.expect.lead`` (they are
  measured to the lead; without one they compared nothing and passed); ``ecu.expect.gap_tolerance`` without
  ``gap_settle_s`` would be checked against nothing.
* **A MaxDistance the sensor would not take** (error): ``radar.max_distance_m`` from 10 m up to what the preset
  sees, in steps of 2 m (RadarConfiguration's and RadarState's grid), checked for every command.
* **An actor the radar can never see** (warning): at no cycle of the scenario is the actor's nearest point or
  its centre inside the preset's field of view (its sectors, its minimum range, ``radar.max_distance_m``).
  Occlusion is not considered. A warning, not an error: an actor may be there for the ground truth or a
  viewer, but usually the tester meant 100 m, not 1000 m. Guardrail actors are not checked (their posts, not
  their box, are what the radar sees).
* **A speed a single-ramp radar wraps unknowingly** (warning): a preset whose one chirp sequence measures ±400
  km/h closing (``acc_lrr``) says every speed it measures is unambiguous (AmbigState 3), as such a sensor does.
  An actor whose range rate goes beyond that within the field of view (the schema allows an ego at 100 m/s and
  an actor at 150 m/s) is then reported at its alias with that flag, at every level, and listed as no object;
  the warning names the actor, its range rate and when.

* **An actor placed a loop or more along a circular road** (error): on a road of one constant curvature
  (``road.curvature_1pm``) the lane is a loop of 2π/|κ|; an actor that starts that far or further from the ego along
  it stands where one a loop nearer would (a lead 150 m along a road of radius 20 m sat 24 m ahead, the radar saw it
  there, and ``report`` measured 150 m). Only the start is checked: an actor that laps the ego later, and a road of
  segments that comes back near itself, are measured along the lane as they are (scenarios/README.md).

* **A frame longer than its cycle** (error): a radar's chirps (both sequences of a staggered one) take longer
  than ``cycle_period_s`` (or the preset's cycle, with ``radar.overrides`` that lengthen the frame).

* **A run of no cycle, a window beyond the run** (error): ``duration_s`` shorter than one radar cycle; an
  ``ecu.expect.gap_settle_s`` (or ``acc_follows``' default 2 s) after the run's last cycle.

Errors are :class:`ScenarioError` with ``file:line: field '…': …``; warnings go to this module's logger.
"""

from __future__ import annotations

import logging
import math

import numpy as np

from radarnode.errors import ScenarioError
from radarnode.scene.scenario import Actor, Scenario
from radarnode.schema import Source

logger = logging.getLogger(__name__)

SPEED_TOLERANCE = (0.5, 0.05)  # m/s, or this fraction of the speed, whichever is larger
HEADING_TOLERANCE_DEG = 5.0
POSITION_TOLERANCE_M = 0.5
CHUNK_CYCLES = 1024            # cycles evaluated at once when looking for the first sight of every actor
#: ``ecu.expect.acc_follows`` is checked from this time where ``gap_settle_s`` is not given (radarnode.consumer.evaluate)
ACC_FOLLOWS_FROM_S = 2.0


def check_scenario(scenario: Scenario) -> Scenario:
    """Raise ScenarioError for what cannot be meant, log a warning for what is probably not meant; returns the
    scenario unchanged (so the loader can chain it)."""
    src = Source.of_lines(scenario.source, scenario.lines)
    _check_timing(scenario, src)
    for i, actor in enumerate(scenario.actors):
        if actor.waypoints:
            _check_waypoint_fields(scenario, src, i, actor)
    _check_max_distance(scenario, src)          # (before the warnings that read it)
    _check_range_bins(scenario, src)
    _check_frame_in_cycle(scenario, src)
    if scenario.actors:
        _check_road_loop(scenario, src)
        _check_overlap_at_start(scenario, src)
        _check_visibility(scenario, src)
        _check_speed_span(scenario, src)
    expect = scenario.ecu.expect
    if _given(scenario, "ecu.expect.gap_tolerance") and expect.gap_settle_s is None:
        # (a tester's finding: it was accepted and had no effect)
        raise src.error("ecu.expect.gap_tolerance",
                        f"field 'ecu.expect.gap_tolerance': value {expect.gap_tolerance!r} is not allowed without "
                        "'ecu.expect.gap_settle_s': it is the tolerance of the time gap from that time on; expected "
                        "gap_settle_s beside it, or it left out")
    if expect.lead is None:
        # measured to the lead: without one they compared nothing and passed (a tester's finding: min_gap_m 500
        # passed where 37.4 m was measured with the lead named)
        for key, what in (("min_gap_m", "the gap to the lead"),
                          ("fcw_ttc_min_s", "the time to collision with the lead"),
                          ("fcw_before_impact_s", "the time before the impact with the lead"),
                          ("gap_settle_s", "the time gap to the lead"),
                          ("ttc_with_lead_decel", "the time to collision with the lead")):
            value = getattr(expect, key)
            if value is not None and value is not False:
                raise src.error(f"ecu.expect.{key}",
                                f"field 'ecu.expect.{key}': value {value!r} is not allowed without 'ecu.expect.lead': "
                                f"it is checked on {what}; expected lead naming the actor (one of "
                                f"{', '.join(repr(a.id) for a in scenario.actors) or 'none: no actor here'})")
    return scenario


# --- a run of no cycle, an expectation's window beyond the run ----------------------------------------------


def _check_timing(scenario: Scenario, src: Source) -> None:
    """A run shorter than one radar cycle computes nothing (``log`` wrote an empty file and ``report`` passed it); an
    expectation checked from a time after the run's last cycle compares nothing (it failed with "0 % of the
    cycles" or "off by inf")."""
    period = scenario.period_s
    where = "cycle_period_s" if scenario.cycle_period_s is not None and _given(scenario, "cycle_period_s") \
        else f"the {scenario.radar.preset} preset's cycle"
    if scenario.num_cycles < 1:
        raise src.error("duration_s", f"field 'duration_s': value {scenario.duration_s!r} is not allowed: the run is "
                                      f"shorter than one radar cycle ({period:g} s, {where}) and would compute "
                                      f"nothing; expected at least {period:g}")
    last = (scenario.num_cycles - 1) * period          # the time of the run's last cycle
    expect = scenario.ecu.expect
    if expect.gap_settle_s is not None and expect.gap_settle_s > last:
        raise src.error("ecu.expect.gap_settle_s",
                        f"field 'ecu.expect.gap_settle_s': value {expect.gap_settle_s!r} is not allowed: the run's "
                        f"last cycle is at {last:g} s (duration_s {scenario.duration_s:g}), so the time gap would be "
                        f"checked on no cycle; expected at most {last:g}, or a longer duration_s")
    if expect.acc_follows is not None and expect.gap_settle_s is None and ACC_FOLLOWS_FROM_S > last:
        raise src.error("ecu.expect.acc_follows",
                        f"field 'ecu.expect.acc_follows': value {expect.acc_follows!r} is not allowed here: ACC's "
                        f"target is checked from {ACC_FOLLOWS_FROM_S:g} s (gap_settle_s, where given) but the run's "
                        f"last cycle is at {last:g} s (duration_s {scenario.duration_s:g}); expected duration_s "
                        f"beyond {ACC_FOLLOWS_FROM_S:g}, or gap_settle_s earlier")


# --- conflicting motion fields ----------------------------------------------------------------------------


def _given(scenario: Scenario, path: str) -> bool:
    """Whether the file wrote this field (a scenario built in code has no lines, and no field counts as given)."""
    return path in scenario.lines


def _segments(actor: Actor) -> list[tuple[float | None, float]]:
    """(speed m/s, direction rad) of every waypoint segment the actor moves on; the speed is None on an untimed
    path (no t_s: speed_mps and accel drive it, so they cannot conflict with it)."""
    out = []
    for a, b in zip(actor.waypoints, actor.waypoints[1:]):
        dx, dy = b.x_m - a.x_m, b.y_m - a.y_m
        dist = math.hypot(dx, dy)
        if dist > 1e-9:
            timed = a.t_s is not None and b.t_s is not None
            out.append((dist / (b.t_s - a.t_s) if timed else None, math.atan2(dy, dx)))
    return out


def _check_waypoint_fields(scenario: Scenario, src: Source, i: int, actor: Actor) -> None:
    """A field beside ``waypoints`` that matches one of their segments (the speed or the heading of a segment,
    the first waypoint's position) is a note and accepted; one that matches none contradicts them."""
    base = f"actors[{i}]"
    w0 = actor.waypoints[0]
    segments = _segments(actor)
    why = "an actor with waypoints moves along them"

    def conflict(key: str, value: object, says: str) -> ScenarioError:
        return src.error(f"{base}.{key}", f"field '{base}.{key}': value {value!r} conflicts with "
                                          f"'{base}.waypoints' ({why}: {says}); expected it left out, or equal")

    if _given(scenario, f"{base}.speed_mps") and actor.timed_path:
        v = actor.speed_mps
        speeds = [seg[0] for seg in segments] + ([0.0] if len(segments) < len(actor.waypoints) - 1 else [])
        if not any(abs(v - u) <= max(SPEED_TOLERANCE[0], SPEED_TOLERANCE[1] * max(v, u)) for u in speeds):
            says = ("they move it at " + ", ".join(f"{u:.2f}" for u in speeds) + " m/s" if segments
                    else "they never move it")
            raise conflict("speed_mps", v, says)
    if _given(scenario, f"{base}.heading_deg") and segments:
        headings = [math.degrees(seg[1]) for seg in segments]
        if not any(abs((actor.heading_deg - h + 180.0) % 360.0 - 180.0) <= HEADING_TOLERANCE_DEG for h in headings):
            raise conflict("heading_deg", actor.heading_deg,
                           "they head " + ", ".join(f"{h:.1f}" for h in headings) + "°")
    if _given(scenario, f"{base}.x_m") and abs(actor.x_m - w0.x_m) > POSITION_TOLERANCE_M:
        raise conflict("x_m", actor.x_m, f"it starts at the first waypoint, x_m {w0.x_m}")
    for key in ("y_m", "lane"):
        if _given(scenario, f"{base}.{key}"):
            y = scenario.actor_y_m(actor)
            if abs(y - w0.y_m) > POSITION_TOLERANCE_M:
                raise conflict(key, getattr(actor, key), f"it starts at the first waypoint, y_m {w0.y_m}, and "
                                                         f"{key} {getattr(actor, key)!r} is y {y:.2f} m")


# --- an actor on top of the ego at t = 0 ----------------------------------------------------------------


def _check_overlap_at_start(scenario: Scenario, src: Source) -> None:
    from radarnode.scene.world import EGO_REAR_OVERHANG_M, Scene
    scene = Scene(scenario)
    touching = scene.ego_contacts(np.zeros(1))[0]      # (a bridge, a gantry, a sign overhead: the ego passes under)
    if not touching.any():
        return
    view = scene.view(0.0)
    mx, my, myaw = scene.mount
    ego = scenario.ego
    ego_h = (0.5 * ego.length_m, 0.5 * ego.width_m)
    c, s = math.cos(myaw), math.sin(myaw)
    i = int(np.flatnonzero(touching)[0])
    actor = scenario.actors[i]
    # the actor's box in the ego frame (the sensor frame turned by the mount's yaw and moved by its position)
    cx, cy = float(view.centre_x_m[i]), float(view.centre_y_m[i])
    ex, ey = c * cx - s * cy + mx, s * cx + c * cy + my
    half = (0.5 * actor.length, 0.5 * actor.width)
    base = f"actors[{i}]"
    key = f"{base}.x_m" if f"{base}.x_m" in scenario.lines else f"{base}.waypoints" if actor.waypoints else base
    front = ego.length_m - EGO_REAR_OVERHANG_M
    ego_box = (f"the ego's (x {-EGO_REAR_OVERHANG_M:g} to {front:g} m, y {ego.y_m - ego_h[1]:.2f} to "
               f"{ego.y_m + ego_h[1]:.2f} m)")
    if actor.object_class == "guardrail":
        # a guardrail is its posts along the road's curve (what the judge tests), not its box: name the post inside
        px, py = scene.post_inside_ego(i, 0.0)
        raise src.error(key, f"actor '{actor.id}' ({base}) overlaps the ego at t = 0: its posts (from x_m, over its "
                             f"{actor.length:g} m) include one at x {px:.2f} m, y {py + ego.y_m:.2f} "
                             f"m, inside {ego_box}; expected every post clear of the ego (e.g. x_m >= "
                             f"{front + 0.5:.1f}, or the rail beside the ego's lane)")
    raise src.error(key, f"actor '{actor.id}' ({base}) overlaps the ego at t = 0: its {actor.length:g} × "
                         f"{actor.width:g} m box centred at x {ex:.2f} m, y {ey + ego.y_m:.2f} m intersects "
                         f"{ego_box}; expected it clear of the ego, e.g. x_m >= {front + half[0] + 0.5:.1f} in the "
                         f"ego's lane")


# --- an actor the radar can never see ----------------------------------------------------------------------


def _check_visibility(scenario: Scenario, src: Source) -> None:
    """Warn of an actor that no radar of the scenario ever has in its field of view."""
    from radarnode.radar.setup import radar_config, radar_scenarios
    candidates = [i for i, a in enumerate(scenario.actors) if a.object_class != "guardrail"]
    if not candidates:
        return
    per = [_seen_by(sc, candidates) for sc in radar_scenarios(scenario)]
    seen = np.logical_or.reduce([p[0] for p in per])
    if seen.all():
        return
    _, closest, closest_az, closest_t = per[0]
    preset = radar_config(radar_scenarios(scenario)[0]).preset
    _warn_unseen(scenario, src, preset, seen, closest, closest_az, closest_t)


def _check_road_loop(scenario: Scenario, src: Source) -> None:
    """ScenarioError for an actor placed a loop or more along a road of one constant curvature from the ego at the
    start (the module's list): it stands where an actor a loop nearer would, and ``report`` measures its gap along
    the lane. Only the placement is checked: where the actors are later depends on the run (a closed loop, a
    driver, ``--duration``), and on a road of segments the lane can come back near itself at any turn."""
    kappa = abs(scenario.road.curvature_1pm)
    if kappa == 0.0 or scenario.road.segments:
        return
    from radarnode.scene.world import Scene
    scene = Scene(scenario)
    loop = 2.0 * math.pi / kappa
    ego_s, actor_s = scene.stations(np.zeros(1))
    along = actor_s[0] - ego_s[0]
    far = np.flatnonzero(~scene.is_guardrail & (np.abs(along) >= loop))
    if far.size == 0:
        return
    i = int(far[0])
    actor = scenario.actors[i]
    base = f"actors[{i}]"
    key = f"{base}.x_m" if f"{base}.x_m" in scenario.lines else f"{base}.waypoints" if actor.waypoints else base
    d = float(along[i])
    raise src.error(key, f"actor '{actor.id}' ({base}) starts {abs(d):.1f} m {'ahead of' if d > 0 else 'behind'} the "
                         f"ego along a road of radius {1.0 / kappa:g} m (road.curvature_1pm), whose lane is a loop of "
                         f"{loop:.1f} m: it stands where {abs(math.fmod(d, loop)):.1f} m would put it, the radar "
                         f"sees it there, and report would measure its gap as {abs(d):.1f} m; expected it less than "
                         f"one loop from the ego ({loop:.1f} m)")


def _seen_by(scenario: Scenario, candidates: list[int]) -> tuple[np.ndarray, ...]:
    """Which actors the scenario's (one) radar ever has in its field of view; the closest range, its azimuth and
    time of each."""
    from radarnode.radar.object_model import nearest_in_fov
    from radarnode.radar.setup import radar_config
    from radarnode.scene.world import Scene
    preset = radar_config(scenario).preset
    max_m = preset.max_range_m if scenario.radar.max_distance_m is None else scenario.radar.max_distance_m
    scene = Scene(scenario)
    n_cycles = max(scenario.num_cycles, 1)
    seen = np.zeros(len(scenario.actors), dtype=bool)
    seen[[i for i in range(len(scenario.actors)) if i not in candidates]] = True
    closest = np.full(len(scenario.actors), np.inf)
    closest_az = np.zeros(len(scenario.actors))
    closest_t = np.zeros(len(scenario.actors))
    for k0 in range(0, n_cycles, CHUNK_CYCLES):
        times = np.arange(k0, min(k0 + CHUNK_CYCLES, n_cycles)) * scenario.period_s
        v = scene.views(times)
        # the nearest point, the centre, and the nearest point inside the field of view (where the radar measures a
        # body a sector's edge crosses)
        for x, y in ((v.x_m, v.y_m), (v.centre_x_m, v.centre_y_m), nearest_in_fov(preset, v, scene.length_m,
                                                                                  scene.width_m)):
            rng, az = np.hypot(x, y), np.arctan2(y, x)
            inside = np.zeros(rng.shape, dtype=bool)
            for sector in preset.fov:
                inside |= (rng <= min(sector.max_range_m, max_m)) & (np.abs(az) <= math.radians(sector.half_angle_deg))
            seen |= (inside & (rng >= preset.min_range_m)).any(axis=0)
        rng, az = v.range_m, v.azimuth_rad
        k = np.argmin(rng, axis=0)
        cols = np.arange(rng.shape[1])
        better = rng[k, cols] < closest
        closest = np.where(better, rng[k, cols], closest)
        closest_az = np.where(better, az[k, cols], closest_az)
        closest_t = np.where(better, times[k], closest_t)
        if seen.all():
            break
    return seen, closest, closest_az, closest_t


def _warn_unseen(scenario, src, preset, seen, closest, closest_az, closest_t) -> None:
    max_m = preset.max_range_m if scenario.radar.max_distance_m is None else scenario.radar.max_distance_m
    # every sector with its own range (the widest angle with the farthest range read as one sector: a point at
    # 70.3 m and 44.5°, outside ars408_like's ±45° to 70 m, was said to be outside "0.2–250 m within ±60°": a
    # tester's finding)
    sectors = ", ".join(f"to {min(s.max_range_m, max_m):g} m within ±{s.half_angle_deg:g}°" for s in preset.fov)
    n_other = len(scenario.radars) - 1
    others = "" if n_other < 1 else " (nor does the other radar)" if n_other == 1 else \
        f" (nor do the other {n_other} radars)"
    for i in np.flatnonzero(~seen):
        actor = scenario.actors[i]
        base = f"actors[{i}]"
        named = [f"ecu.expect.{k}" for k in ("lead", "acc_follows") if getattr(scenario.ecu.expect, k) == actor.id]
        line = src.where(f"{base}.x_m" if f"{base}.x_m" in scenario.lines else base)
        logger.warning("%s: actor '%s' (%s) is never in the radar's field of view during the scenario's %g s: "
                       "preset %s sees from %g m %s, the actor comes no nearer than %.1f m (azimuth %.1f° at "
                       "t = %.2f s), so the radar never reports it%s%s", line, actor.id, base, scenario.duration_s,
                       preset.name, preset.min_range_m, sectors, closest[i], math.degrees(closest_az[i]),
                       closest_t[i], others, f"; it is {' and '.join(named)}" if named else "")


def _check_speed_span(scenario: Scenario, src: Source) -> None:
    """Warn of an actor whose range rate, inside the field of view, exceeds what a radar that calls every speed
    unambiguous (:func:`radarnode.radar.ambiguity.unambiguous`) measures without wrapping."""
    from radarnode.radar import ambiguity
    from radarnode.radar.object_model import in_fov
    from radarnode.radar.setup import radar_config, radar_scenarios
    from radarnode.scene.world import Scene
    for sc in radar_scenarios(scenario):
        preset = radar_config(sc).preset
        if not ambiguity.unambiguous(preset):
            continue
        scene = Scene(sc)
        vmax = preset.alias_speed_mps
        worst = np.zeros(len(sc.actors))
        when = np.zeros(len(sc.actors))
        for k0 in range(0, max(sc.num_cycles, 1), CHUNK_CYCLES):
            times = np.arange(k0, min(k0 + CHUNK_CYCLES, max(sc.num_cycles, 1))) * sc.period_s
            v = scene.views(times)
            c, s_ = np.cos(v.azimuth_rad), np.sin(v.azimuth_rad)
            signed = v.vx_mps * c + v.vy_mps * s_
            rate = np.where(in_fov(preset, v.range_m, v.azimuth_rad), np.abs(signed), 0.0)
            k = np.argmax(rate, axis=0)
            cols = np.arange(rate.shape[1])
            better = rate[k, cols] > np.abs(worst)
            worst = np.where(better, signed[k, cols], worst)
            when = np.where(better, times[k], when)
        for i in np.flatnonzero(np.abs(worst) > vmax):
            actor, base = sc.actors[i], f"actors[{i}]"
            logger.warning("%s: actor '%s' (%s) reaches a range rate of %+.1f m/s at t = %.2f s, beyond the ±%.1f m/s "
                           "that preset %s's single chirp sequence measures: its detections wrap (reported at "
                           "%+.1f m/s) and, as on such a sensor, are flagged AmbigState 3 'unambiguous'; no object "
                           "is listed for it", src.where(base), actor.id, base, worst[i], when[i], vmax,
                           preset.name, float(np.mod(worst[i] + vmax, 2 * vmax) - vmax))


def _check_frame_in_cycle(scenario: Scenario, src: Source) -> None:
    """ScenarioError where a radar's chirps take longer than its cycle: one frame (both chirp sequences of a
    staggered radar) must fit in the cycle that reports it. A 5-ms cycle ran on presets whose frame takes 7.7 and
    13.7 ms, and 8192 chirps of a 246-ms frame in a 72-ms cycle (an independent tester's finding). The error names
    what set the cycle — ``cycle_period_s``, or the overrides of the radar whose preset gives a scenario of several
    its cycle — or else the overrides that lengthened this radar's frame."""
    from radarnode.radar.setup import radar_config, radar_path, radar_scenarios
    period = scenario.period_s
    radars = radar_scenarios(scenario)
    for sc in radars:
        p = radar_config(sc).preset
        parts = [q.num_chirps * q.frame_chirp_period_s for q in p.sequences()]
        frame = sum(parts)
        if frame <= period:
            continue
        need = math.ceil(frame * 1e6) / 1e6                  # (rounded up: the value suggested is taken)
        what = (f"one frame of the {p.name} radar's chirps takes {1e3 * frame:.4f} ms"
                + (f" (its two chirp sequences, {' + '.join(f'{1e3 * x:.3f}' for x in parts)} ms)" if len(parts) > 1
                   else "") + f", longer than the cycle of {1e3 * period:g} ms that reports it")
        if scenario.cycle_period_s is not None and _given(scenario, "cycle_period_s"):
            raise src.error("cycle_period_s", f"field 'cycle_period_s': value {scenario.cycle_period_s!r} is not "
                                              f"allowed: {what}; expected at least {need:g}")
        first = radars[0]
        if "cycle_period_s" in (first.radar.overrides or {}):      # the first radar's overrides set the cycle
            field = f"{radar_path(first)}.overrides"
            raise src.error(field, f"field '{field}': cycle_period_s {period:g} is not allowed here: {what}; expected "
                                   f"cycle_period_s of at least {need:g}")
        field = f"{radar_path(sc)}.overrides" if sc.radar.overrides else f"{radar_path(sc)}.preset"
        cycle = "" if sc is first else f" (the cycle of {first.radar.preset}, {radar_path(first)}, the scenario's)"
        raise src.error(field, f"field '{field}': {what}{cycle}; expected fewer chirps (num_chirps) or a shorter chirp "
                               f"period, or cycle_period_s of at least {need:g} s")


def _check_range_bins(scenario: Scenario, src: Source) -> None:
    """A warning where a radar's range bins end inside the range it sees (``overrides: {num_samples: 64}``): a target
    beyond folds to a near range with complex sampling, and with real sampling the anti-alias filter takes it (80 dB
    down), so it vanishes though the preset claims to see it (a tester's finding: no word was said)."""
    from radarnode.radar.presets import max_distance
    from radarnode.radar.setup import radar_config, radar_path, radar_scenarios
    for sc in radar_scenarios(scenario):
        p = radar_config(sc).preset
        seen = max_distance(p, sc.radar.max_distance_m)[0]
        if p.unambiguous_range_m < min(seen, p.max_range_m) - 1e-9:
            beyond = ("folds: it is reported at its range modulo that, with the RCS read there" if p.complex_sampling
                      else "is taken by the real-sampling receiver's anti-alias filter (80 dB down): it is not "
                           "reported (complex_sampling: true folds it instead)")
            logger.warning("%s: preset %s's range bins end at %.2f m (%d samples a chirp, %s sampling), inside the "
                           "%g m it sees: a target beyond %s", src.where(radar_path(sc)), p.name,
                           p.unambiguous_range_m, p.num_samples, "complex" if p.complex_sampling else "real", seen,
                           beyond)


def _check_max_distance(scenario: Scenario, src: Source) -> None:
    """Every radar's ``max_distance_m``: one the sensor takes (:func:`radarnode.radar.presets.max_distance`), for
    every command alike (``image`` drew what ``log`` refused)."""
    from radarnode.radar.presets import max_distance
    from radarnode.radar.setup import radar_config, radar_path, radar_scenarios
    for sc in radar_scenarios(scenario):
        value, problem = max_distance(radar_config(sc).preset, sc.radar.max_distance_m)
        if problem is not None:
            field = f"{radar_path(sc)}.max_distance_m"
            raise src.error(field, f"field '{field}': value {value:g} is not allowed; expected {problem}")
