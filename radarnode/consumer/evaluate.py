"""Run a scenario through node, wire, consumer and ECU, and measure what the ECU did.

Everything goes through real frames: the node's ARS 408 frames and the
vehicle's 0x300/0x301 are decoded by a :class:`CycleAssembler`, the ECU
decides on the decoded cycles, and its AccStatus/FcwStatus frames are
decoded and E2E-checked again. In closed loop (``ecu.closed_loop``) the ego
follows the ACC request through a first-order actuator lag and its speed
and yaw rate go back to the node as 0x300/0x301.

Truth for the figures: gap and closing speed to the scenario's ``expect.lead``
actor, measured from the sensor (front bumper) to the lead's nearest point.
"""

from __future__ import annotations

import collections
import math
from dataclasses import dataclass, field

import numpy as np

from radarnode.consumer.acc import AccSettings, iso15622_limits
from radarnode.consumer.assembler import ClusterCycle, CycleAssembler, ObjectCycle
from radarnode.consumer.ecu import Ecu
from radarnode.consumer.fcw import LEVEL_PREWARNING, LEVEL_WARNING, FcwSettings, time_to_collision
from radarnode.consumer.path import SensorMount
from radarnode.scene.scenario import Scenario
from radarnode.radar.checks import ACC_FOLLOWS_FROM_S
from radarnode.consumer.fusion import FusingConsumer
from radarnode.wire.group import ego_motion_for, make_node


#: ``ScenarioResult.warned_for`` of a warning for an object that is no actor of the scenario
NO_ACTOR = "no actor"
#: cycles of an ECU track's truth tags that say which actor it is where a cycle's tag does not
TAG_WINDOW = 10
#: an ECU target within this of an actor's box (its outline, not its nearest point) is at that actor; of several,
#: the nearest in range, an actor whose reflecting point lies more than OVERHEAD_Z_M above the sensor taken
#: AT_ACTOR_OVERHEAD_M farther (about the far scan's range resolution)
AT_ACTOR_M = 0.75
OVERHEAD_Z_M, AT_ACTOR_OVERHEAD_M = 0.5, 1.5
STANDSTILL_JUDGE_MPS = 0.5     # below this the ego is stopping or standing: the ISO 15622 limits are not judged
#: the simulated driver resumes ACC from a standstill (no lead in the scenario) only with no standing actor this near
#: ahead in the ego's lane (m): he sees it (ACC, which never saw it move, would not brake for it above
#: radarnode.consumer.ecu.FCW_BRAKE_MAX_MPS)
DRIVER_CLEAR_M = 100.0
#: the judge looks for contacts between two cycles this often (s): the ego's and every actor's box
CONTACT_STEP_S = 0.005
NO_BRAKING_MPS2 = -0.5         # ``expect.no_braking``: an ACC request below this is braking (above: coasting)


class EgoActuator:
    """Closed loop: the ego follows the ACC request through a first-order lag (time constant ``lag_s``)."""

    def __init__(self, scene, lag_s: float, speed_mps: float) -> None:
        self.ego = scene.drive_ego()
        self.script = self.ego.lateral          # the scenario's own motion of the ego (speed profile, lane change)
        self.lag_s = lag_s
        self.s_m, self.v_mps, self.a_mps2 = 0.0, speed_mps, 0.0

    def at(self, t_s: float) -> None:
        """Publish the current state to the scene for the cycle at ``t_s``."""
        self.ego.set(t_s, self.s_m, self.v_mps, self.a_mps2)

    def follow_script(self, t_s: float) -> None:
        """Take the ego's state from the scenario's own profile at ``t_s`` (no ACC in the loop, no driver yet)."""
        st = self.script.state(t_s)
        self.s_m, self.v_mps, self.a_mps2 = float(st.x_m[0]), float(st.vx_mps[0]), float(st.ax_mps2[0])

    def apply(self, request_mps2: float, dt_s: float) -> None:
        a_new = self.a_mps2 + (request_mps2 - self.a_mps2) * (1.0 - math.exp(-dt_s / self.lag_s))
        if self.v_mps <= 0.0 and a_new <= 0.0:
            self.a_mps2 = 0.0        # standing, brakes applied: the car does not roll backwards
            return
        self.s_m += self.v_mps * dt_s + 0.5 * a_new * dt_s * dt_s
        self.v_mps = max(self.v_mps + a_new * dt_s, 0.0)
        self.a_mps2 = a_new if self.v_mps > 0 else 0.0


class DriverModel:
    """The ego's driver (``ego.driver``): ``reaction_s`` after the ECU's first FCW warning he brakes at
    ``decel_mps2`` (through the actuator's lag) until the ego stands, and holds it; his braking overrides ACC."""

    def __init__(self, driver) -> None:
        self.reaction_s, self.decel_mps2 = driver.reaction_s, driver.decel_mps2
        self.warned_s: float | None = None

    def warn(self, t_s: float) -> None:
        """The warning reached the driver at ``t_s`` (the first one counts)."""
        if self.warned_s is None:
            self.warned_s = t_s

    @property
    def brake_s(self) -> float:
        """When the driver's foot is on the brake (inf: not yet warned)."""
        return math.inf if self.warned_s is None else self.warned_s + self.reaction_s


def drive(actuator: EgoActuator, t_s: float, period_s: float, latency_s: float, held: float, new: float,
          driver: DriverModel | None, scripted: bool) -> None:
    """Move the closed-loop ego over the cycle [t_s, t_s + period_s]: the previous ACC request ``held`` until
    the ECU's output comes ``latency_s`` after the cycle, then ``new``; from the driver's braking on his
    deceleration; without ACC in the loop (``scripted``) the scenario's own profile until the driver brakes."""
    t_end = t_s + period_s
    brake = driver.brake_s if driver is not None else math.inf
    if scripted and brake >= t_end:
        actuator.follow_script(t_end)
        return
    if scripted and brake > t_s:
        actuator.follow_script(brake)
        t_s = brake
    cuts = sorted({t_s, t_end, min(max(t_s + latency_s, t_s), t_end), min(max(brake, t_s), t_end)})
    for a, b in zip(cuts[:-1], cuts[1:]):
        if b - a <= 0.0:
            continue
        if a >= brake:
            request = -driver.decel_mps2
        else:
            request = held if a < t_s + latency_s and not scripted else new
        actuator.apply(0.0 if scripted and a < brake else request, b - a)


@dataclass
class ScenarioResult:
    """Figures of one run; ``passed`` against the scenario's ``ecu.expect``."""

    name: str
    seed: int
    warning_time_s: float | None = None
    driver_brake_time_s: float | None = None   # the driver model's braking began (ego.driver)
    impact_time_s: float | None = None      # the lead's gap closed (in the ego lane)
    prewarning_time_s: float | None = None  # the first cycle with FCW at prewarning level or above
    latency_s: float = 0.0                  # the ECU's processing latency applied to its outputs
    checked: bool = True                    # False: the scenario's expectation states nothing to check
    ttc_at_warning_s: float | None = None
    warned_for: str | None = None           # the actor FCW's first warning was for ("no actor": posts, clutter, ghosts)
    min_ttc_s: float = math.inf
    min_gap_m: float = math.inf
    peak_decel_mps2: float = 0.0
    peak_accel_mps2: float = 0.0
    peak_jerk_mps3: float = 0.0
    final_time_gap_s: float | None = None
    iso_limits_ok: bool = True
    #: every actor whose box met the ego's (``Scene.ego_contacts``), with the first time: a failure where the ego is
    #: driven (closed loop or ``ego.driver``), whichever actor it is; the script's doing where it is not
    collisions: dict[str, float] = field(default_factory=dict)
    passed: bool = True
    reasons: list[str] = field(default_factory=list)
    trace: dict = field(default_factory=dict)


def make_ecu(scenario: Scenario, period_s: float, acc_enabled: bool | None = None) -> Ecu:
    """The consumer ECU a scenario describes (``ecu``), with the radar's mount as calibrated into it."""
    spec = scenario.ecu
    acc = AccSettings(enabled=spec.acc_enabled if acc_enabled is None else acc_enabled,
                      set_speed_mps=spec.set_speed_mps, time_gap_s=spec.time_gap_s,
                      path_half_width_m=spec.path_half_width_m, path_from_trails=spec.path_from_trails,
                      min_speed_mps=spec.acc_min_speed_mps)
    fcw = FcwSettings(ttc_warn_s=spec.fcw_ttc_warn_s, ttc_prewarn_s=max(4.0, spec.fcw_ttc_warn_s),
                      decel_warn_mps2=spec.fcw_decel_warn_mps2,
                      stationary_max_speed_mps=spec.fcw_stationary_max_speed_mps)
    # the radar's carrier, as the ECU has it calibrated for its sensor (the overhead test needs the wavelength)
    from radarnode.radar.setup import radar_config
    return Ecu(acc, fcw, sensor_id=scenario.radar.sensor_id, period_s=period_s,
               mount=SensorMount.of(scenario.radar.mount), wavelength_m=radar_config(scenario).preset.wavelength_m)


def contacts_since(scene, t_s: float, period_s: float, first: bool = False) -> list[tuple[int, float]]:
    """(actor index, first time) of every actor whose box meets the ego's since the last cycle (``t_s`` − ``period_s``
    to ``t_s``; at ``t_s`` only on the ``first`` cycle), sampled every CONTACT_STEP_S: a point actor crossed at 75 m/s
    meets the ego for 66 ms, between two 72-ms cycles."""
    steps = 1 if first else max(int(math.ceil(period_s / CONTACT_STEP_S - 1e-9)), 1)
    times = t_s - period_s * np.arange(steps - 1, -1, -1) / steps
    met = scene.ego_contacts(times)
    return [(int(i), float(times[np.argmax(met[:, i])])) for i in np.flatnonzero(met.any(axis=0))]


def simulate(scenario: Scenario, fidelity: str | None = None) -> ScenarioResult:
    """Run ``scenario`` in simulated time and return the ECU's figures.

    With several radars (``radars:``) every one is a node on the bus and the ECU takes their object lists fused
    in the vehicle frame (:mod:`radarnode.consumer.fusion`), re-expressed in the first radar's frame (the ECU's
    path, warning and following logic is written for a front radar at that mount)."""
    spec = scenario.ecu
    node = make_node(scenario, fidelity=fidelity)
    scene = node.scene
    driver = DriverModel(scenario.ego.driver) if scenario.ego.driver is not None else None
    # a driver who reacts to the warning closes the loop even without ACC in it
    actuator = (EgoActuator(scene, spec.actuator_lag_s, scenario.ego.speed_mps)
                if spec.closed_loop or driver is not None else None)
    vehicle = ego_motion_for(node)
    fuser = (FusingConsumer({r.sensor_id: SensorMount.of(r.mount) for r in scenario.sensors})
             if len(scenario.sensors) > 1 else None)
    front = SensorMount.of(scenario.radar.mount)
    fused_members: dict[int, dict] = {}
    period = node.period_s
    ecu = make_ecu(scenario, period)
    assembler = CycleAssembler(sensor_id=scenario.radar.sensor_id)
    lead = next((i for i, a in enumerate(scenario.actors) if a.id == spec.expect.lead), None)
    res = ScenarioResult(scenario.name, scenario.seed)
    track_tags: dict[int, collections.deque] = {}     # ECU track → its objects' last truth tags
    prev_a = None
    prev_gap = math.inf
    latency, request = spec.processing_latency_s, 0.0
    resume_cue_s, lead_v, prev_speed = 0.0, 0.0, scenario.ego.speed_mps
    res.latency_s = latency
    tr = {k: [] for k in ("t", "gap", "ttc", "rel_speed", "speed", "accel", "request", "warning", "state",
                          "time_gap", "target", "target_track", "fcw_target")}
    for k in range(scenario.num_cycles):
        t = k * period
        if actuator is not None:
            actuator.at(t)
        for m in vehicle.frames(t):
            node.receive(m, t)
            assembler.on_message_received(m)
        out = node.cycle(t)
        for m in out.messages:
            assembler.on_message_received(m)
            if fuser is not None:
                fuser.on_message_received(m)
        ecu.set_ego(t, assembler.ego_speed_mps, assembler.ego_yaw_rate_dps, assembler.ego_frames,
                    assembler.yaw_frames)
        ecu.boundaries = assembler.road_boundaries          # as the radar reported them (0x680/0x681)
        decision = None
        primary = assembler.drain()
        if fuser is None:
            cycles = [c for c in primary if isinstance(c, (ObjectCycle, ClusterCycle))]     # the ECU takes both
        else:
            cycles = []
            for _, fused in fuser.drain():
                fused_members = {int(i): m for i, m in zip(fused.id, fused.members)}
                cycles.append(ObjectCycle(len(cycles), fused.t_s, fused.in_sensor_frame(front), True, True))
        for cycle in cycles:
            decision = ecu.on_cycle(t, cycle)
        if decision is None:
            decision = ecu.tick(t)
        if decision is not None:
            for m in ecu.frames(decision, timestamp=t + latency):
                assembler.on_message_received(m)       # the ECU's frames, decoded and E2E-checked
        # truth
        ego_state = scene.ego_state(t)
        for i, when in contacts_since(scene, t, period, first=k == 0):
            res.collisions.setdefault(scenario.actors[i].id, when)
        gap = ttc = math.inf
        rel_speed = math.nan
        if lead is not None:
            # along the ego's lane (a bend too): ahead and within 2 m of the lane centre
            lane_gap, lateral, closing, lead_v, lead_a = scene.lane_gap(t, lead)
            ahead = lane_gap > 0.0 and abs(lateral) < 2.0
            gap = lane_gap if ahead else math.inf
            if spec.expect.ttc_with_lead_decel and math.isfinite(gap):
                ttc = time_to_collision(gap, lead_v + closing, lead_v, ego_state.accel_mps2, lead_a)
            else:
                ttc = gap / closing if closing > 0.1 and math.isfinite(gap) else math.inf
            rel_speed = -closing if ahead else math.nan      # lead minus ego, negative when closing
        res.min_gap_m, res.min_ttc_s = min(res.min_gap_m, gap), min(res.min_ttc_s, ttc)
        if lead is not None:
            if res.impact_time_s is None and 0.0 < prev_gap and lane_gap <= 0.0 and abs(lateral) < 2.0:
                res.impact_time_s = t
            prev_gap = lane_gap
        # which actor the ECU selected: the actor whose box its target lies at (_actor_at); else its object ID looked
        # up in this cycle's object list (truth tags), and where this cycle says no actor, or its list lacks the
        # object (the radar dropped it for a cycle), the actor the ECU track's objects were most often in its last
        # TAG_WINDOW cycles (at the detection and signal levels a car's object is tagged no actor in a cycle a
        # guardrail post's return outweighs it in, or, at the signal level, lies nearest its detection)
        seen_now: dict[int, int] = {}
        view = None

        def actor_of(target) -> int:
            nonlocal view
            if target is None:
                return -1
            if target.track_id in seen_now:
                return seen_now[target.track_id]
            # where it is first (a merged return of a car and the truck beside it lies at the car, whoever's power
            # outweighs in the cell; a cluster track has no object to look up)
            if view is None:
                view = scene.view(t)
            at = _actor_at(view, scene, front, target)
            if at is not None:
                seen_now[target.track_id] = at
                return at
            found = _actor_in_cycle(target)
            tags = track_tags.setdefault(target.track_id, collections.deque(maxlen=TAG_WINDOW))
            if found is not None:
                tags.append(found)
            who = found if found is not None and found >= 0 else (
                collections.Counter(tags).most_common(1)[0][0] if tags else -1)
            seen_now[target.track_id] = who
            return who

        def _actor_in_cycle(target) -> int | None:
            if fuser is not None:
                # a fused object: the actor of the radar objects that fed it this cycle
                for sid, oid in fused_members.get(int(target.object_id), {}).items():
                    ol = out.outputs[node.sensor_ids.index(sid)].frame.objects
                    hit = np.flatnonzero(ol.id == oid)
                    if hit.size:
                        return int(ol.actor_index[hit[0]])
                return None
            hit = np.flatnonzero(out.frame.objects.id == target.object_id)
            return int(out.frame.objects.actor_index[hit[0]]) if hit.size else None

        target_actor = actor_of(decision.target) if decision is not None else -1
        # FCW's object, while it (pre)warns: what FCW selected and acted on
        fcw_actor = (actor_of(decision.fcw_target) if decision is not None and decision.warning_level >= LEVEL_PREWARNING
                     else -1)
        warning = decision is not None and decision.warning_level == LEVEL_WARNING
        # the ECU's outputs exist from t + latency: the warning is judged then (TTC shorter by the latency)
        if warning and res.warning_time_s is None:
            res.warning_time_s, res.ttc_at_warning_s = t + latency, ttc - latency
            res.warned_for = scenario.actors[fcw_actor].id if fcw_actor >= 0 else NO_ACTOR
        if warning and driver is not None:
            driver.warn(t + latency)
        if decision is not None and decision.warning_level >= LEVEL_PREWARNING and res.prewarning_time_s is None:
            res.prewarning_time_s = t + latency
        # the driver confirms driving off after a long standstill, a reaction time after he sees the way clear
        if ecu.acc.standstill:
            resume_cue_s = resume_cue_s + period if driver_resumes(scene, t, decision) else 0.0
            if resume_cue_s >= spec.driver_reaction_s:
                ecu.acc.confirm_resume()
        # closed loop: the ego follows the request through a first-order lag
        if actuator is not None:
            # the previous request holds until this cycle's is out, latency after the cycle; the driver's braking
            # (ego.driver) overrides it from the moment his foot is on the brake
            new = decision.accel_request_mps2 if (decision is not None and spec.acc_enabled) else 0.0
            drive(actuator, t, period, min(latency, period), request, new, driver,
                  scripted=not (spec.closed_loop and spec.acc_enabled))
            request = new
            if driver is not None and res.driver_brake_time_s is None and driver.brake_s <= t + period:
                res.driver_brake_time_s = driver.brake_s
        accel = ego_state.accel_mps2
        jerk = abs(accel - prev_a) / period if prev_a is not None else 0.0
        if ego_state.speed_mps >= STANDSTILL_JUDGE_MPS and prev_speed >= STANDSTILL_JUDGE_MPS:
            res.peak_jerk_mps3 = max(res.peak_jerk_mps3, jerk)
        prev_a = accel
        res.peak_decel_mps2 = min(res.peak_decel_mps2, accel)
        res.peak_accel_mps2 = max(res.peak_accel_mps2, accel)
        # ISO 15622's limits while driving; the instant the wheels stop (the deceleration ends with the speed)
        # is the vehicle's, not the controller's
        acc_drives = driver is None or t < driver.brake_s        # the driver's braking is not ACC's to judge
        if (actuator is not None and acc_drives and ego_state.speed_mps >= STANDSTILL_JUDGE_MPS
                and prev_speed >= STANDSTILL_JUDGE_MPS):
            lo, hi, jerk_max = iso15622_limits(ego_state.speed_mps)
            if accel < lo - 0.05 or accel > hi + 0.05 or jerk > jerk_max + 0.05:
                res.iso_limits_ok = False
        prev_speed = ego_state.speed_mps
        for key, val in (("t", t), ("gap", gap), ("ttc", ttc), ("rel_speed", rel_speed),
                         ("speed", ego_state.speed_mps), ("accel", accel),
                         ("request", decision.accel_request_mps2 if decision else 0.0),
                         ("warning", decision.warning_level if decision else 0),
                         ("state", decision.acc_state if decision else 0),
                         ("time_gap", gap / ego_state.speed_mps if ego_state.speed_mps > 0.5 else math.inf),
                         ("target", target_actor), ("fcw_target", fcw_actor),
                         ("target_track", decision.target.track_id if decision and decision.target else -1)):
            tr[key].append(val)
    res.trace = {k: np.asarray(v) for k, v in tr.items()}
    res.final_time_gap_s = float(res.trace["time_gap"][-1]) if len(res.trace["t"]) else None
    res.trace["assembler"] = assembler
    res.trace["ecu"] = ecu                         # the ECU as it ended (its landmarks, for the benchmarks)
    _judge(scenario, res)
    return res


def lane_clear_ahead(scene, t_s: float) -> bool:
    """The simulated driver's look ahead before he resumes ACC from a standstill: no actor slower than 1 m/s whose box
    reaches into the ego's lane (between its lines) within DRIVER_CLEAR_M ahead (he resumed into a car stopped 6 m
    ahead, where FCW was quiet only because the ego stood; and, judging an actor by its centre and its length along the
    road, past a truck parked crosswise across the lane with its centre 3–6 m to the side, or 4 m ahead with its
    centre 10 m ahead; and, taking 2 m either side of the lane's centre, he never resumed behind a car parked at the
    kerb 0.3 m beyond the line or a pedestrian on the pavement: independent testers' findings)."""
    half = scene.scenario.road.lane_width_m / 2.0
    for i in range(scene.n):
        if scene.elevated[i] or scene.is_guardrail[i]:          # a deck or a gantry above the road, a guardrail
            continue
        near, far, lat_lo, lat_hi, speed = scene.lane_footprint(t_s, i)
        if far > 0.0 and near < DRIVER_CLEAR_M and lat_lo < half and lat_hi > -half and abs(speed) < 1.0:
            return False
    return True


def driver_resumes(scene, t_s: float, decision) -> bool:
    """Whether the simulated driver sees the way clear to resume ACC from a standstill (``report`` and
    ``run --closed-loop`` alike): FCW not warning, the lane ahead clear (:func:`lane_clear_ahead`), and ACC's target,
    if it has one, driving off (faster than the ego by 1 m/s). ``report`` went by the scenario's lead alone where it
    names one: it resumed with a car that had squeezed in 5 m ahead, where ``run`` did not (a tester's finding)."""
    if decision is not None and decision.warning_level == LEVEL_WARNING:
        return False
    if decision is not None and decision.target is not None and decision.target.rel_speed_mps <= 1.0:
        return False
    return lane_clear_ahead(scene, t_s)


def _actor_at(view, scene, mount: SensorMount, target) -> int | None:
    """The actor an ECU target lies at: within AT_ACTOR_M of its box (sensor frame, the box turned by its orientation),
    the one whose nearest point's range is nearest the target's if several (a car under a bridge lies in the deck's
    footprint too; the radar measures range best; a structure above the road taken AT_ACTOR_OVERHEAD_M farther),
    or None."""
    if not len(view.x_m):
        return None
    # the target is in the vehicle's axes (along the car from the sensor, across from its centre line)
    x, y = mount.to_sensor(target.distance_m + mount.x_m, target.lateral_m)
    co, so = np.cos(view.orientation_rad), np.sin(view.orientation_rad)
    rx, ry = x - view.centre_x_m, y - view.centre_y_m
    out_l = np.maximum(np.abs(co * rx + so * ry) - scene.length_m / 2.0, 0.0)
    out_w = np.maximum(np.abs(-so * rx + co * ry) - scene.width_m / 2.0, 0.0)
    near = np.hypot(out_l, out_w) <= AT_ACTOR_M
    if not near.any():
        return None
    # an actor above the road (a deck, a gantry) counts AT_ACTOR_OVERHEAD_M farther: a return at a stopped car's
    # rear right under a deck's near edge is the car's (the one FCW is for), not the deck's
    above = view.z_m > OVERHEAD_Z_M if view.z_m is not None else np.zeros(len(view.x_m), dtype=bool)
    miss = np.abs(math.hypot(x, y) - view.range_m) + np.where(above, AT_ACTOR_OVERHEAD_M, 0.0)
    return int(np.argmin(np.where(near, miss, np.inf)))


def _judge(scenario: Scenario, res: ScenarioResult) -> None:
    e = scenario.ecu.expect
    if res.impact_time_s is not None:
        res.min_gap_m = 0.0                     # the gap closed, whatever the 72-ms samples showed
    if e.fcw_ttc_min_s is not None:
        if res.warning_time_s is None:
            res.reasons.append("no FCW warning")
        elif res.impact_time_s is not None and res.warning_time_s >= res.impact_time_s:
            res.reasons.append(f"FCW warning at t = {res.warning_time_s:.2f} s, after the impact at "
                               f"{res.impact_time_s:.2f} s")
        elif not (res.ttc_at_warning_s is not None and res.ttc_at_warning_s >= e.fcw_ttc_min_s):
            res.reasons.append(f"warning at TTC {res.ttc_at_warning_s:.2f} s < {e.fcw_ttc_min_s} s")
    if e.fcw_required and res.warning_time_s is None:
        res.reasons.append("no FCW warning")
    elif e.fcw_required and res.impact_time_s is not None and res.warning_time_s >= res.impact_time_s:
        res.reasons.append(f"FCW warning at t = {res.warning_time_s:.2f} s, after the impact at "
                           f"{res.impact_time_s:.2f} s")
    if e.fcw_before_impact_s is not None:
        if res.warning_time_s is None:
            res.reasons.append("no FCW warning")
        elif res.impact_time_s is not None and res.impact_time_s - res.warning_time_s < e.fcw_before_impact_s:
            res.reasons.append(f"FCW warning {res.impact_time_s - res.warning_time_s:.2f} s before the impact "
                               f"< {e.fcw_before_impact_s} s")
    if (e.lead is not None and (e.fcw_ttc_min_s is not None or e.fcw_required or e.fcw_before_impact_s is not None)
            and res.warning_time_s is not None and res.warned_for != e.lead):
        who = ("an object that is no actor of the scenario (a post, clutter, a ghost)" if res.warned_for == NO_ACTOR
               else res.warned_for)
        res.reasons.append(f"the first FCW warning (t = {res.warning_time_s:.2f} s) was for {who}, not {e.lead}")
    if e.fcw_prewarning and (res.prewarning_time_s is None or res.warning_time_s is not None
                             and res.prewarning_time_s >= res.warning_time_s):
        res.reasons.append("no prewarning before the warning")
    # a driven ego (ACC in the loop or a driver braking) must touch no actor, whatever the expectation names: a car
    # cutting in that the ego ran into passed when only the lead's gap was judged
    driven = scenario.ecu.closed_loop or scenario.ego.driver is not None
    if driven:
        for name, t in res.collisions.items():
            res.reasons.append(f"collision with {name} at t = {t:.2f} s")
    res.checked = e.checks or (driven and bool(res.collisions))
    names = [a.id for a in scenario.actors]
    targets = res.trace["target"]
    for a in e.never_target:
        n = int(np.sum(targets == names.index(a)))
        if n:
            res.reasons.append(f"{a} selected as the target in {n} cycles")
        n = int(np.sum(res.trace["fcw_target"] == names.index(a)))
        if n:
            res.reasons.append(f"FCW warned for {a} in {n} cycles")
    if e.acc_follows is not None:
        after = res.trace["t"] >= (e.gap_settle_s if e.gap_settle_s is not None else ACC_FOLLOWS_FROM_S)
        share = float(np.mean(targets[after] == names.index(e.acc_follows))) if after.any() else 0.0
        others = sorted({names[i] for i in targets[after] if i >= 0 and i != names.index(e.acc_follows)})
        if share < 0.95 or others:
            res.reasons.append(f"ACC followed {e.acc_follows} in {share:.0%} of the cycles"
                               + (f", also {', '.join(others)}" if others else ""))
    if e.no_fcw and res.warning_time_s is not None:
        res.reasons.append(f"FCW warning at t = {res.warning_time_s:.2f} s")
    if e.no_braking:
        req = res.trace["request"]
        braking = np.flatnonzero(req < NO_BRAKING_MPS2) if scenario.ecu.acc_enabled else np.zeros(0, dtype=int)
        if braking.size:
            k = int(braking[0])
            res.reasons.append(f"ACC braking at t = {res.trace['t'][k]:.2f} s ({req[k]:+.2f} m/s²)")
        if res.driver_brake_time_s is not None:
            res.reasons.append(f"the driver braked at t = {res.driver_brake_time_s:.2f} s")
    if e.gap_settle_s is not None:
        tr = res.trace
        after = tr["t"] >= e.gap_settle_s
        target = scenario.ecu.time_gap_s
        gaps = tr["time_gap"][after]
        if gaps.size == 0 or np.any(np.abs(gaps - target) > e.gap_tolerance * target):
            worst = float(np.max(np.abs(gaps - target))) if gaps.size else math.inf
            res.reasons.append(f"time gap off the {target} s setting by up to {worst:.2f} s after {e.gap_settle_s} s")
    if e.min_gap_m is not None and res.min_gap_m < e.min_gap_m:
        res.reasons.append(f"gap fell to {res.min_gap_m:.1f} m < {e.min_gap_m} m")
    if scenario.ecu.closed_loop and not res.iso_limits_ok:
        res.reasons.append("acceleration outside the ISO 15622 limits")
    res.passed = not res.reasons
