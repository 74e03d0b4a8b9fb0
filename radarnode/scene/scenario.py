"""Scenario description: frozen, validated dataclasses and the YAML loader.

The schema is documented in ``scenarios/README.md``. Every dataclass checks its
own values in ``__post_init__`` and raises :class:`FieldError`; the loader adds
the file name, the dotted path of the field and its line, and raises
:class:`ScenarioError`. Unknown keys and missing required fields are caught by
the loader from the dataclass definitions themselves, so the schema has one
source of truth.

Coordinates: the road frame has x along the road (metres from the ego's start
position) and y to the left of the centre of the ego lane. Headings are
relative to the road direction, positive to the left (counter-clockwise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path


from radarnode import validate
from radarnode.errors import FieldError, ScenarioError, yaml_repr
from radarnode.schema import Schema, Source, build

#: class name -> (ARS 408 Obj_Class code, default length m, default width m, default RCS dBsm)
ACTOR_CLASSES: dict[str, tuple[int, float, float, float]] = {
    "point": (0, 0.3, 0.3, 0.0),
    "car": (1, 4.5, 1.8, 10.0),
    "truck": (2, 12.0, 2.5, 20.0),
    "pedestrian": (3, 0.5, 0.6, -5.0),
    "motorcycle": (4, 2.2, 0.8, 3.0),
    "bicycle": (5, 1.8, 0.6, 0.0),
    "sign": (0, 0.2, 0.8, 10.0),
    "guardrail": (6, 0.0, 0.3, -5.0),  # length required; RCS per post
    # overhead structures (issue 10): length along the road, width across it, RCS of the structure seen from
    # the front in free space (a deck's fascia and girders; a gantry's truss and sign panels)
    "bridge": (6, 12.0, 40.0, 25.0),
    "gantry": (6, 1.0, 25.0, 20.0),
}

#: class name -> (default bottom height above the road z_m, default height_m): where an actor's body is in height
ACTOR_HEIGHTS: dict[str, tuple[float, float]] = {
    "point": (0.0, 0.3), "car": (0.0, 1.5), "truck": (0.0, 3.5), "pedestrian": (0.0, 1.8),
    "motorcycle": (0.0, 1.4), "bicycle": (0.0, 1.7), "sign": (0.0, 2.5), "guardrail": (0.0, 0.8),
    "bridge": (5.0, 1.5),     # a motorway bridge: 4.5–5.5 m clearance, a deck fascia ~1.5 m deep
    "gantry": (5.5, 2.0),     # a sign gantry: sign panels from 5.5 m up
}

OUTPUT_TYPES = ("objects", "clusters", "none")
ACC_TIME_GAPS_S = (1.0, 1.5, 2.0)      # the ISO 15622 time-gap settings
SORT_INDICES = ("none", "range", "rcs")
FIDELITIES = ("object", "detection", "signal", "auto")


@dataclass(frozen=True)
class AccelStep:
    """From ``t_s`` on, the acceleration along the path is ``accel_mps2`` (until the next step)."""

    t_s: float
    accel_mps2: float

    def __post_init__(self) -> None:
        validate.number("t_s", self.t_s, lo=0.0)
        validate.number("accel_mps2", self.accel_mps2, lo=-15.0, hi=15.0)


#: the fastest an actor may move (m/s): its ``speed_mps``, and what its timed waypoints' legs imply
MAX_ACTOR_SPEED_MPS = 150.0


@dataclass(frozen=True)
class Waypoint:
    """Road-frame position; the actor moves in straight segments between waypoints.

    With ``t_s`` the actor is there at that time (a timed path); without it the waypoints are a path the
    actor drives along with its speed profile (``speed_mps`` and ``accel``).
    """

    x_m: float
    y_m: float
    t_s: float | None = None

    def __post_init__(self) -> None:
        if self.t_s is not None:
            validate.number("t_s", self.t_s, lo=0.0)
        validate.number("x_m", self.x_m, lo=-1e5, hi=1e5)
        validate.number("y_m", self.y_m, lo=-1e4, hi=1e4)


def _check_profile(accel: tuple[AccelStep, ...], waypoints: tuple[Waypoint, ...] = ()) -> None:
    timed = [w for w in waypoints if w.t_s is not None]
    if timed and len(timed) != len(waypoints):
        k = next(i for i, w in enumerate(waypoints) if w.t_s is None)
        raise FieldError(f"waypoints[{k}].t_s", None, "a time on every waypoint (a timed path) or on none (a path "
                         "driven with the speed profile)")
    for name, seq in (("accel", accel), ("waypoints", timed)):
        times = [s.t_s for s in seq]
        if any(b <= a for a, b in zip(times, times[1:])):
            raise FieldError(name, times, "strictly increasing t_s")
    for k, (a, b) in enumerate(zip(timed, timed[1:])):
        # the speed the times give a leg, held to what speed_mps allows (2000 m/s between two waypoints, a jump of
        # 30 m in 1e-12 s, passed silently)
        speed = math.hypot(b.x_m - a.x_m, b.y_m - a.y_m) / (b.t_s - a.t_s)
        if not speed <= MAX_ACTOR_SPEED_MPS:
            raise FieldError(f"waypoints[{k + 1}]", {"x_m": b.x_m, "y_m": b.y_m, "t_s": b.t_s},
                             f"a leg from waypoints[{k}] at most {MAX_ACTOR_SPEED_MPS:g} m/s ({speed:.4g} m/s here), "
                             "as speed_mps")
    if waypoints and not timed:
        for k, (a, b) in enumerate(zip(waypoints, waypoints[1:])):
            if a.x_m == b.x_m and a.y_m == b.y_m:
                raise FieldError(f"waypoints[{k + 1}]", {"x_m": b.x_m, "y_m": b.y_m},
                                 "a point different from the one before (a path has no zero-length legs)")


@dataclass(frozen=True)
class Mount:
    """Sensor position on the ego (from the rear-axle centre, x forward, y left) and yaw."""

    x_m: float = 3.7
    y_m: float = 0.0
    z_m: float = 0.5
    yaw_deg: float = 0.0

    def __post_init__(self) -> None:
        validate.number("x_m", self.x_m, lo=-10.0, hi=10.0)
        validate.number("y_m", self.y_m, lo=-5.0, hi=5.0)
        validate.number("z_m", self.z_m, lo=0.0, hi=5.0)
        validate.number("yaw_deg", self.yaw_deg, lo=-180.0, hi=180.0)


@dataclass(frozen=True)
class RadarSetup:
    """Which radar, where it sits, and how it talks on the bus."""

    preset: str = "ars408_like"
    overrides: dict = field(default_factory=dict)
    mount: Mount = Mount()
    sensor_id: int = 0
    bitrate: int = 500_000
    output: str = "objects"
    send_quality: bool = True
    send_ext_info: bool = True
    sort_index: str = "range"
    max_distance_m: float | None = None
    radar_power: int = 0
    bus_load_limit: float = 0.8
    road_boundaries: bool | None = None    # publish RoadBoundary_Left/Right (0x680/0x681 + 8 × sensor_id); None: when the road has guardrails

    def __post_init__(self) -> None:
        # preset and overrides are the radar package's to check (radarnode.radar.setup), like the `signal` options
        validate.text("preset", self.preset)
        if not isinstance(self.overrides, dict):
            raise FieldError("overrides", self.overrides, "a mapping of preset field to value")
        validate.integer("sensor_id", self.sensor_id, lo=0, hi=7)
        validate.integer("bitrate", self.bitrate, lo=10_000, hi=1_000_000)
        validate.choice("output", self.output, OUTPUT_TYPES)
        validate.boolean("send_quality", self.send_quality)
        validate.boolean("send_ext_info", self.send_ext_info)
        validate.choice("sort_index", self.sort_index, SORT_INDICES)
        if self.max_distance_m is not None:
            validate.number("max_distance_m", self.max_distance_m, lo=2.0, hi=2046.0)
        validate.integer("radar_power", self.radar_power, lo=0, hi=3)
        validate.number("bus_load_limit", self.bus_load_limit, lo=0.0, hi=1.0, lo_open=True)
        if self.road_boundaries is not None:
            validate.boolean("road_boundaries", self.road_boundaries)


@dataclass(frozen=True)
class Guardrails:
    """Guardrails along the road edges; an offset of null means no guardrail on that side."""

    left_offset_m: float | None = None
    right_offset_m: float | None = None
    post_spacing_m: float = 2.0
    rcs_dbsm: float = -5.0

    def __post_init__(self) -> None:
        for name in ("left_offset_m", "right_offset_m"):
            v = getattr(self, name)
            if v is not None:
                validate.number(name, v, lo=0.0, hi=50.0)
        validate.number("post_spacing_m", self.post_spacing_m, lo=0.5, hi=50.0)
        validate.number("rcs_dbsm", self.rcs_dbsm, lo=-40.0, hi=40.0)


SEGMENT_TYPES = ("straight", "arc", "clothoid")
MAX_CURVATURE_1PM = 0.05           # 1/radius: a 20 m radius, tighter than any road an ACC drives


@dataclass(frozen=True)
class RoadSegment:
    """One piece of the reference line (OpenDRIVE plan view): a straight, an arc of constant curvature, or a
    clothoid whose curvature changes linearly from ``curvature_start_1pm`` to ``curvature_end_1pm``."""

    type: str
    length_m: float
    curvature_1pm: float | None = None          # arc
    curvature_start_1pm: float | None = None    # clothoid
    curvature_end_1pm: float | None = None      # clothoid

    #: the curvature fields each type takes
    FIELDS = {"straight": (), "arc": ("curvature_1pm",), "clothoid": ("curvature_start_1pm", "curvature_end_1pm")}

    def __post_init__(self) -> None:
        validate.choice("type", self.type, SEGMENT_TYPES)
        validate.number("length_m", self.length_m, lo=0.0, hi=1e5, lo_open=True)
        wanted = self.FIELDS[self.type]
        for name in ("curvature_1pm", "curvature_start_1pm", "curvature_end_1pm"):
            value = getattr(self, name)
            if name in wanted:
                if value is None:
                    raise FieldError(name, None, f"a curvature in 1/m for a {self.type} segment, in "
                                     f"[{-MAX_CURVATURE_1PM:g}, {MAX_CURVATURE_1PM:g}] (left positive)")
                validate.number(name, value, lo=-MAX_CURVATURE_1PM, hi=MAX_CURVATURE_1PM)
            elif value is not None:
                allowed = ", ".join(wanted) if wanted else "no curvature"
                raise FieldError(name, value, f"not given for a {self.type} segment (it takes {allowed})")

    @property
    def curvatures(self) -> tuple[float, float]:
        """Curvature at the start and at the end (1/m)."""
        if self.type == "straight":
            return 0.0, 0.0
        if self.type == "arc":
            return self.curvature_1pm, self.curvature_1pm
        return self.curvature_start_1pm, self.curvature_end_1pm


@dataclass(frozen=True)
class Road:
    """Lanes (index 0 is the rightmost), the ego lane, the reference line's shape, guardrails.

    The shape is either ``curvature_1pm`` (one arc everywhere; 0: straight) or ``segments`` from the ego's start
    on (before the first the road continues with its starting curvature, after the last with its end curvature).
    """

    lanes: int = 3
    lane_width_m: float = 3.5
    ego_lane: int = 1
    curvature_1pm: float = 0.0
    segments: tuple[RoadSegment, ...] = ()
    guardrails: Guardrails = Guardrails()

    def __post_init__(self) -> None:
        validate.integer("lanes", self.lanes, lo=1, hi=10)
        validate.number("lane_width_m", self.lane_width_m, lo=2.0, hi=6.0)
        validate.integer("ego_lane", self.ego_lane, lo=0, hi=self.lanes - 1)
        validate.number("curvature_1pm", self.curvature_1pm, lo=-MAX_CURVATURE_1PM, hi=MAX_CURVATURE_1PM)
        if len(self.segments) > 10_000:
            raise FieldError("segments", f"{len(self.segments)} segments", "at most 10000 segments")
        if self.segments and self.curvature_1pm != 0.0:
            raise FieldError("segments", "...", "either curvature_1pm (one arc) or segments, not both")

    def geometry_segments(self) -> list[tuple[float, float, float]]:
        """(length, start curvature, end curvature) of every segment, for :class:`radarnode.scene.road.RoadGeometry`."""
        return [(s.length_m, *s.curvatures) for s in self.segments]

    def lane_center_y_m(self, lane: int) -> float:
        return (lane - self.ego_lane) * self.lane_width_m

    @property
    def left_edge_y_m(self) -> float:
        return (self.lanes - self.ego_lane - 0.5) * self.lane_width_m

    @property
    def right_edge_y_m(self) -> float:
        return -(self.ego_lane + 0.5) * self.lane_width_m


@dataclass(frozen=True)
class LaneChange:
    """A lateral manoeuvre: from ``t_s`` over ``duration_s`` to lane ``to_lane`` (or by ``by_m``), a cosine step."""

    t_s: float
    duration_s: float = 4.0
    to_lane: int | None = None
    by_m: float | None = None

    def __post_init__(self) -> None:
        validate.number("t_s", self.t_s, lo=0.0, hi=86_400.0)
        validate.number("duration_s", self.duration_s, lo=0.5, hi=30.0)
        if (self.to_lane is None) == (self.by_m is None):
            raise FieldError("to_lane", self.to_lane, "exactly one of to_lane (a lane index) or by_m (metres, left "
                             "positive)")
        if self.to_lane is not None:
            validate.integer("to_lane", self.to_lane, lo=0, hi=9)
        if self.by_m is not None:
            validate.number("by_m", self.by_m, lo=-20.0, hi=20.0)


@dataclass(frozen=True)
class Driver:
    """The ego's driver: ``reaction_s`` after the ECU's FCW warning, brakes at ``decel_mps2`` to a standstill.

    The brake builds up through the ego's actuator lag (``ecu.actuator_lag_s``); the driver's braking overrides
    the ACC request (a brake pedal cancels ACC). 1.0–1.5 s is the reaction of an alert driver to a warning
    (NHTSA's FCW test procedure assumes 1.2 s as the typical); 5–8 m/s² an emergency stop.
    """

    reaction_s: float = 1.2
    decel_mps2: float = 6.0

    def __post_init__(self) -> None:
        validate.number("reaction_s", self.reaction_s, lo=0.0, hi=5.0)
        validate.number("decel_mps2", self.decel_mps2, lo=1.0, hi=12.0)


@dataclass(frozen=True)
class Ego:
    """The vehicle carrying the radar: in its lane, ``y_m`` off the lane centre, with an optional lane change
    and an optional driver who brakes after an FCW warning."""

    speed_mps: float = 0.0
    accel: tuple[AccelStep, ...] = ()
    length_m: float = 4.7
    width_m: float = 1.9
    y_m: float = 0.0                       # lateral offset from the centre of the ego lane (left positive)
    lane_change: LaneChange | None = None
    driver: Driver | None = None

    def __post_init__(self) -> None:
        validate.number("speed_mps", self.speed_mps, lo=0.0, hi=100.0)
        validate.number("y_m", self.y_m, lo=-3.0, hi=3.0)
        validate.number("length_m", self.length_m, lo=0.0, hi=30.0, lo_open=True)
        validate.number("width_m", self.width_m, lo=0.0, hi=5.0, lo_open=True)
        _check_profile(self.accel)


@dataclass(frozen=True)
class Actor:
    """One road user or roadside object.

    Give either ``y_m`` or ``lane`` (default: the ego lane). Motion is a speed with piecewise-constant
    ``accel`` (speeds never go below zero: a braking vehicle stops) along ``heading_deg``, or along a path of
    untimed ``waypoints``; or timed ``waypoints`` (each with ``t_s``). ``z_m`` is the height of the actor's
    bottom above the road (a bridge's or a gantry's clearance), ``height_m`` its height.
    """

    id: str
    object_class: str
    x_m: float = 0.0
    y_m: float | None = None
    lane: int | None = None
    speed_mps: float = 0.0
    heading_deg: float = 0.0
    accel: tuple[AccelStep, ...] = ()
    waypoints: tuple[Waypoint, ...] = ()
    length_m: float | None = None
    width_m: float | None = None
    rcs_dbsm: float | None = None
    swerling: int | None = None      # RCS fluctuation: 0 steady, 1 Rayleigh from frame to frame
    z_m: float | None = None         # bottom above the road (default by class: 0, a bridge 5, a gantry 5.5)
    height_m: float | None = None    # height of the body (default by class)

    def __post_init__(self) -> None:
        # (an empty id was taken, and warnings and ecu.expect named an actor '': a tester's finding)
        validate.name("id", self.id, "the actor in warnings, errors and ecu.expect")
        validate.choice("class", self.object_class, ACTOR_CLASSES)
        validate.number("x_m", self.x_m, lo=-1e5, hi=1e5)
        if self.y_m is not None:
            validate.number("y_m", self.y_m, lo=-1e4, hi=1e4)
            if self.lane is not None:
                raise FieldError("lane", self.lane, "no lane when y_m is given (use one of them)")
        if self.lane is not None:
            validate.integer("lane", self.lane, lo=0, hi=9)
        validate.number("speed_mps", self.speed_mps, lo=0.0, hi=MAX_ACTOR_SPEED_MPS)
        validate.number("heading_deg", self.heading_deg, lo=-180.0, hi=180.0)
        for name in ("length_m", "width_m"):
            v = getattr(self, name)
            if v is not None:
                validate.number(name, v, lo=0.0, hi=1e4, lo_open=True)
        if self.object_class == "guardrail" and self.length_m is None:
            raise FieldError("length_m", None, "a guardrail length in metres (> 0)")
        if self.rcs_dbsm is not None:
            validate.number("rcs_dbsm", self.rcs_dbsm, lo=-60.0, hi=60.0)
        if self.swerling is not None:
            validate.integer("swerling", self.swerling, lo=0, hi=1)
        if self.z_m is not None:
            validate.number("z_m", self.z_m, lo=0.0, hi=20.0)
        if self.height_m is not None:
            validate.number("height_m", self.height_m, lo=0.0, hi=50.0, lo_open=True)
        if len(self.waypoints) == 1:
            raise FieldError("waypoints", "one waypoint", "two or more waypoints")
        _check_profile(self.accel, self.waypoints)
        if self.timed_path and self.accel:
            raise FieldError("accel", "...", "no accel with timed waypoints (their times set the speed); leave "
                             "out the waypoints' t_s to drive the path with speed_mps and accel")

    @property
    def timed_path(self) -> bool:
        """Waypoints with times (a timed path), as opposed to a path driven with the speed profile."""
        return bool(self.waypoints) and self.waypoints[0].t_s is not None

    @property
    def z(self) -> float:
        """Height of the bottom above the road, m."""
        return self.z_m if self.z_m is not None else ACTOR_HEIGHTS[self.object_class][0]

    @property
    def height(self) -> float:
        return self.height_m if self.height_m is not None else ACTOR_HEIGHTS[self.object_class][1]

    @property
    def elevated(self) -> bool:
        """Off the ground (a bridge, a gantry, an overhead sign): the radar sees it through its elevation beam
        and the ground's reflection (radarnode.radar.elevation)."""
        return self.z > 0.0

    @property
    def class_code(self) -> int:
        return ACTOR_CLASSES[self.object_class][0]

    @property
    def swerling_case(self) -> int:
        """Swerling case: as given, else 0 for a point reflector (a corner reflector is steady) and 1 otherwise
        (a car or a person is many scatterers whose sum fluctuates as the aspect changes)."""
        if self.swerling is not None:
            return self.swerling
        # a bridge or a gantry is rigid and stands still: seen from the road ahead its aspect changes only in
        # elevation, which the elevation model accounts for (radarnode.radar.elevation); its RCS is steady
        return 0 if self.object_class in ("point", "bridge", "gantry") else 1

    @property
    def length(self) -> float:
        return self.length_m if self.length_m is not None else ACTOR_CLASSES[self.object_class][1]

    @property
    def width(self) -> float:
        return self.width_m if self.width_m is not None else ACTOR_CLASSES[self.object_class][2]

    @property
    def rcs(self) -> float:
        return self.rcs_dbsm if self.rcs_dbsm is not None else ACTOR_CLASSES[self.object_class][3]


@dataclass(frozen=True)
class Expectation:
    """Acceptance criteria checked by ``radarnode report`` (all optional)."""

    lead: str | None = None                # actor whose gap and TTC are measured
    fcw_ttc_min_s: float | None = None     # an FCW warning must come at a (constant-speed) TTC ≥ this
    fcw_required: bool = False             # an FCW warning must come before the gap closes
    no_fcw: bool = False                   # no FCW warning at all
    gap_settle_s: float | None = None      # ACC: time gap within ±gap_tolerance of the setting from then on
    gap_tolerance: float = 0.1
    min_gap_m: float | None = None         # the gap to the lead never below this
    fcw_before_impact_s: float | None = None   # the warning comes at least this long before the truth's impact
    fcw_prewarning: bool = False           # a prewarning (level 1) comes before the warning
    ttc_with_lead_decel: bool = False      # fcw_ttc_min_s on the TTC that counts the lead's deceleration (LVD)
    acc_follows: str | None = None         # ACC's target is this actor (from gap_settle_s, else 2 s): ≥ 95 % of cycles
    never_target: tuple[str, ...] = ()     # actors ACC and FCW must never select (adjacent lane, roadside)
    no_braking: bool = False               # ACC never requests braking (< NO_BRAKING_MPS2) and the driver never brakes

    @property
    def checks(self) -> bool:
        """Whether anything is to be checked (a lead alone only names the actor figures are measured to)."""
        return any((self.fcw_ttc_min_s is not None, self.fcw_required, self.no_fcw, self.gap_settle_s is not None,
                    self.min_gap_m is not None, self.fcw_before_impact_s is not None, self.fcw_prewarning,
                    self.acc_follows is not None, bool(self.never_target), self.no_braking))

    def __post_init__(self) -> None:
        if self.lead is not None:
            validate.text("lead", self.lead)
        if self.fcw_ttc_min_s is not None:
            validate.number("fcw_ttc_min_s", self.fcw_ttc_min_s, lo=0.0, hi=20.0)
        validate.boolean("fcw_required", self.fcw_required)
        validate.boolean("no_fcw", self.no_fcw)
        if self.gap_settle_s is not None:
            validate.number("gap_settle_s", self.gap_settle_s, lo=0.0, hi=3600.0)
        validate.number("gap_tolerance", self.gap_tolerance, lo=0.0, hi=1.0, lo_open=True)
        if self.min_gap_m is not None:
            validate.number("min_gap_m", self.min_gap_m, lo=0.0, hi=500.0)
        if self.fcw_before_impact_s is not None:
            validate.number("fcw_before_impact_s", self.fcw_before_impact_s, lo=0.0, hi=20.0)
        validate.boolean("fcw_prewarning", self.fcw_prewarning)
        validate.boolean("ttc_with_lead_decel", self.ttc_with_lead_decel)
        validate.boolean("no_braking", self.no_braking)
        if self.acc_follows is not None:
            validate.text("acc_follows", self.acc_follows)
        if not isinstance(self.never_target, (tuple, list)) or not all(isinstance(a, str) for a in self.never_target):
            raise FieldError("never_target", self.never_target, "a list of actor ids")
        object.__setattr__(self, "never_target", tuple(self.never_target))


@dataclass(frozen=True)
class EcuSpec:
    """The consumer ECU under test: ACC settings, closed loop, and what to expect."""

    acc_enabled: bool = False
    set_speed_mps: float = 30.0
    time_gap_s: float = 1.5
    closed_loop: bool = False
    actuator_lag_s: float = 0.3
    #: from a radar cycle's arrival to the ECU's frames and request (one 10–20 ms task of a production ADAS
    #: ECU; 20 ms: a 10 ms task that the cycle just missed, plus its run)
    processing_latency_s: float = 0.02
    acc_min_speed_mps: float = 0.0         # below it ACC waits in standby (0: stop and go)
    driver_reaction_s: float = 1.0         # the driver confirms a resume this long after the lead drove off
    path_half_width_m: float = 1.6         # the predicted path's half-width
    path_from_trails: bool = True          # the trails of the vehicles ahead shape the predicted path
    fcw_ttc_warn_s: float = 2.8            # FCW warns at a TTC at or below this …
    fcw_decel_warn_mps2: float = 4.0       # … or when avoiding the collision needs this deceleration
    #: above this speed a stationary object never seen moving draws no FCW (a radar without elevation cannot
    #: tell it from a bridge in time: radarnode.consumer.overhead); 27.8 m/s = 100 km/h
    fcw_stationary_max_speed_mps: float = 27.8
    expect: Expectation = Expectation()

    def __post_init__(self) -> None:
        validate.boolean("acc_enabled", self.acc_enabled)
        validate.number("set_speed_mps", self.set_speed_mps, lo=0.0, hi=70.0)
        if self.time_gap_s not in ACC_TIME_GAPS_S:
            raise FieldError("time_gap_s", self.time_gap_s, "one of 1.0, 1.5, 2.0 s (ISO 15622 settings)")
        validate.boolean("closed_loop", self.closed_loop)
        validate.number("actuator_lag_s", self.actuator_lag_s, lo=0.01, hi=5.0)
        validate.number("processing_latency_s", self.processing_latency_s, lo=0.0, hi=0.5)
        validate.number("acc_min_speed_mps", self.acc_min_speed_mps, lo=0.0, hi=30.0)
        validate.number("driver_reaction_s", self.driver_reaction_s, lo=0.0, hi=10.0)
        validate.number("path_half_width_m", self.path_half_width_m, lo=0.5, hi=5.0)
        validate.boolean("path_from_trails", self.path_from_trails)
        validate.number("fcw_ttc_warn_s", self.fcw_ttc_warn_s, lo=0.5, hi=10.0)
        validate.number("fcw_decel_warn_mps2", self.fcw_decel_warn_mps2, lo=1.0, hi=10.0)
        validate.number("fcw_stationary_max_speed_mps", self.fcw_stationary_max_speed_mps, lo=0.0, hi=70.0)


@dataclass(frozen=True)
class Scenario:
    """A complete scenario: timing, seed, radar, ego, road and actors."""

    name: str
    duration_s: float
    seed: int
    description: str = ""
    cycle_period_s: float | None = None
    fidelity: str = "object"
    #: the signal-level options as written; validated and built by radarnode.radar.setup
    signal: dict = field(default_factory=dict)
    ecu: EcuSpec = EcuSpec()
    radar: RadarSetup = RadarSetup()
    #: several radars on one bus (each its own node, one scene, one clock); ``radar`` is then the first of them
    radars: tuple[RadarSetup, ...] | None = ()
    ego: Ego = Ego()
    road: Road = Road()
    actors: tuple[Actor, ...] = ()
    source: str = "<memory>"
    #: line of every dotted field path in the source file, for errors found after loading
    lines: dict = field(default_factory=dict, compare=False, repr=False)

    def __post_init__(self) -> None:
        validate.name("name", self.name)
        validate.text("description", self.description)
        validate.number("duration_s", self.duration_s, lo=0.0, hi=86_400.0, lo_open=True)
        validate.integer("seed", self.seed, lo=0, hi=2**63 - 1)
        if self.cycle_period_s is not None:
            validate.number("cycle_period_s", self.cycle_period_s, lo=0.005, hi=10.0)
        validate.choice("fidelity", self.fidelity, FIDELITIES)
        if not isinstance(self.signal, dict):
            raise FieldError("signal", self.signal, "a mapping of signal-level options")
        if self.radars is None:          # one radar of several (radarnode.radar.setup.radar_scenarios)
            object.__setattr__(self, "radars", ())
        elif self.radars:
            self._check_radars()
        ids = [a.id for a in self.actors]
        dup = sorted({i for i in ids if ids.count(i) > 1})
        if dup:
            raise FieldError("actors", dup, "unique actor ids")
        e = self.ecu.expect
        for name, named in (("lead", [e.lead]), ("acc_follows", [e.acc_follows]), ("never_target", e.never_target)):
            for a in named:
                if a is not None and a not in ids:
                    raise FieldError(f"ecu.expect.{name}", a, "the id of one of the actors: " + ", ".join(ids))
        lc = self.ego.lane_change
        if lc is not None and lc.to_lane is not None and lc.to_lane >= self.road.lanes:
            raise FieldError("ego.lane_change.to_lane", lc.to_lane, f"a lane index in [0, {self.road.lanes - 1}]")
        for i, a in enumerate(self.actors):
            if a.lane is not None and a.lane >= self.road.lanes:
                raise FieldError(f"actors[{i}].lane", a.lane, f"a lane index in [0, {self.road.lanes - 1}]")

    def _check_radars(self) -> None:
        """Several radars: each its own sensor ID, all on one bus (one bit rate); ``radar`` becomes the first."""
        if any(k == "radar" or k.startswith("radar.") for k in self.lines):
            raise FieldError("radar", {"preset": self.radar.preset},
                             "no 'radar' beside 'radars': either 'radar' (one radar) or 'radars' (a list)")
        if len(self.radars) > 8:
            raise FieldError("radars", f"a list of {len(self.radars)}", "at most 8 radars (sensor IDs 0..7)")
        for i, r in enumerate(self.radars):
            for j in range(i):
                if self.radars[j].sensor_id == r.sensor_id:
                    raise FieldError(f"radars[{i}].sensor_id", r.sensor_id,
                                     f"a sensor ID no other radar uses (radars[{j}] has {r.sensor_id}; sensor_id "
                                     "is 0 where not given): each radar is its own node, its CAN IDs shifted by "
                                     "0x10 x sensor ID")
            if r.bitrate != self.radars[0].bitrate:
                raise FieldError(f"radars[{i}].bitrate", r.bitrate,
                                 f"{self.radars[0].bitrate} (radars[0].bitrate): the radars share one bus")
        object.__setattr__(self, "radar", self.radars[0])

    @property
    def sensors(self) -> tuple[RadarSetup, ...]:
        """Every radar of the scenario: ``radars``, or the one ``radar``."""
        return self.radars if self.radars else (self.radar,)

    @property
    def period_s(self) -> float:
        if self.cycle_period_s is None:
            raise ScenarioError(f"{self.source}: the cycle period comes from the radar preset; load the scenario "
                                "with radarnode.radar.setup.load_scenario, which fills it in")
        return self.cycle_period_s

    @property
    def num_cycles(self) -> int:
        return int(math.floor(self.duration_s / self.period_s + 1e-9))

    def ego_lateral(self) -> tuple[float, float, float] | None:
        """The ego's lane change as (start, duration, lateral step in metres), or None."""
        lc = self.ego.lane_change
        if lc is None:
            return None
        dy = lc.by_m if lc.by_m is not None else self.road.lane_center_y_m(lc.to_lane) - self.ego.y_m
        return lc.t_s, lc.duration_s, dy

    def actor_y_m(self, actor: Actor) -> float:
        if actor.y_m is not None:
            return actor.y_m
        lane = self.road.ego_lane if actor.lane is None else actor.lane
        return self.road.lane_center_y_m(lane)


# ---------------------------------------------------------------------------
# Loader
# ---------------------------------------------------------------------------

SCHEMA = Schema(
    aliases={Actor: {"class": "object_class"}},
    nested={
        Scenario: {"radar": (RadarSetup, False), "radars": (RadarSetup, True), "ego": (Ego, False), "road": (Road, False),
                   "actors": (Actor, True), "ecu": (EcuSpec, False)},
        EcuSpec: {"expect": (Expectation, False)},
        RadarSetup: {"mount": (Mount, False)},
        Road: {"guardrails": (Guardrails, False), "segments": (RoadSegment, True)},
        Ego: {"accel": (AccelStep, True), "lane_change": (LaneChange, False), "driver": (Driver, False)},
        Actor: {"accel": (AccelStep, True), "waypoints": (Waypoint, True)},
    },
    non_empty={Actor: {"waypoints": "two waypoints or more, or no field 'waypoints' (an actor placed by x_m, y_m "
                                    "or lane)"}})


#: the largest scenario file read (the shipped ones are a few kB; a waypoint list of 100,000 points fits)
MAX_SCENARIO_BYTES = 16 << 20


def read_scenario(path: str | Path) -> Scenario:
    """Read a scenario file and validate the scene (the radar options are checked by radarnode.radar.setup).

    Raises
    ------
    ScenarioError
        With ``file:line: field 'a.b': value X is not allowed; expected ...``.
    """
    p = Path(path)
    try:
        with open(p, "rb") as f:
            # at most a little more than any scenario needs (an 800-MB capture given by mistake was read whole first,
            # and /dev/zero until the kernel killed the process: an independent tester's finding)
            raw = f.read(MAX_SCENARIO_BYTES + 1)
        if len(raw) > MAX_SCENARIO_BYTES:
            raise ScenarioError(f"{p}: not a scenario file: more than {MAX_SCENARIO_BYTES // (1 << 20)} MiB; expected a "
                                "YAML scenario (a few kB)")
        text = raw.decode("utf-8")
    except OSError as exc:
        raise ScenarioError(f"{p}: cannot read scenario file: {exc.strerror}") from None
    except UnicodeDecodeError as exc:
        raise ScenarioError(f"{p}: not a scenario file: byte {exc.object[exc.start]:#04x} at offset {exc.start} is not "
                            "UTF-8 text; expected a YAML scenario in UTF-8") from None
    src = Source(str(p), text)
    return _built(src, str(p))


def read_scenario_text(text: str, name: str = "<string>") -> Scenario:
    """Like :func:`read_scenario` for YAML text."""
    return _built(Source(name, text), name)


def _built(src: Source, name: str) -> Scenario:
    if isinstance(src.data, dict) and "radars" in src.data and not src.data["radars"]:
        raise src.error("radars", f"field 'radars': value {yaml_repr(src.data['radars'])} is not allowed; expected a "
                                  "list of one radar or more (or no 'radars' and one 'radar')")
    return build(Scenario, src.data, "", src, SCHEMA, extra={"source": name, "lines": src.lines})


__all__ = ["ACTOR_CLASSES", "ACTOR_HEIGHTS", "Actor", "AccelStep", "Driver", "Ego", "Guardrails", "Mount",
           "RadarSetup", "Road", "RoadSegment", "LaneChange", "Scenario", "Waypoint", "read_scenario",
           "read_scenario_text"]
