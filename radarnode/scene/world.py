"""The road scene in the world frame and as the sensor sees it.

The road's reference line is the centre of the ego lane, made of straight, arc and clothoid segments
(:class:`radarnode.scene.road.RoadGeometry`; one arc of constant curvature κ when the scenario gives
``road.curvature_1pm``). Road coordinates (s, d) — distance along the reference line and lateral offset to the
left — map to world coordinates by

    x = X(s) − d·sin θ(s),   y = Y(s) + d·cos θ(s)

with (X, Y, θ) the reference line's pose at s (for one arc: X = sin(κs)/κ, Y = (1 − cos(κs))/κ, θ = κs).
Movers are integrated in road coordinates (so a car keeps its lane around a bend and through a curve's
entry); their speed is measured along the reference line.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from radarnode.scene.kinematics import MoverState, MoverTable
from radarnode.scene.road import RoadGeometry
from radarnode.scene.scenario import Scenario

EGO_REAR_OVERHANG_M = 1.0      # rear end to rear axle, as radarnode.viz draws the ego
OVERLAP_TOLERANCE_M = 0.01     # boxes that only touch do not overlap
#: an actor whose bottom is this high or higher (a bridge, a gantry, an overhead sign) passes over the ego: a car or
#: a van (the scenario gives the ego no height); a run may start under a bridge
EGO_HEIGHT_M = 2.0


@dataclass(frozen=True)
class EgoState:
    """World-frame pose and motion of the ego's rear-axle centre."""

    x_m: float
    y_m: float
    heading_rad: float
    speed_mps: float
    accel_mps2: float
    yaw_rate_rps: float


@dataclass(frozen=True)
class SensorView:
    """The actors as the sensor sees them at one time (sensor frame: x forward, y left).

    Every array has shape (n_actors,), in scenario actor order.
    ``x_m``/``y_m`` is the point of the actor's outline nearest to the sensor
    (what a radar reports); ``az_lo_rad``/``az_hi_rad`` bound its azimuth extent.
    """

    t_s: float
    x_m: np.ndarray
    y_m: np.ndarray
    vx_mps: np.ndarray          # relative velocity (actor minus sensor), sensor axes
    vy_mps: np.ndarray
    ax_mps2: np.ndarray         # relative acceleration, sensor axes
    ay_mps2: np.ndarray
    ground_vx_mps: np.ndarray   # actor velocity over ground, sensor axes
    ground_vy_mps: np.ndarray
    orientation_rad: np.ndarray  # actor heading relative to the sensor's x axis
    az_lo_rad: np.ndarray
    az_hi_rad: np.ndarray
    centre_x_m: np.ndarray      # centre of the actor's box
    centre_y_m: np.ndarray
    sensor_vx_mps: float        # sensor velocity over ground, sensor axes
    sensor_vy_mps: float
    #: height of the reflecting point above the sensor: an elevated actor's lower edge (z_m − mount height), 0 for
    #: an actor standing on the road (its reflection centres spread around the mount's height); None: all 0
    z_m: np.ndarray | None = None

    @property
    def range_m(self) -> np.ndarray:
        """Range to the reflecting point (slant range where it is above the sensor: what the radar measures)."""
        if self.z_m is None:
            return np.hypot(self.x_m, self.y_m)
        return np.sqrt(self.x_m ** 2 + self.y_m ** 2 + self.z_m ** 2)

    @property
    def azimuth_rad(self) -> np.ndarray:
        return np.arctan2(self.y_m, self.x_m)

    def take_times(self, rows: np.ndarray) -> SensorView:
        """The times ``rows`` of a view computed for several times: a view of those times only."""
        return SensorView(np.asarray(self.t_s)[rows], *(getattr(self, name)[rows] for name in _VIEW_ARRAYS),
                          self.sensor_vx_mps[rows], self.sensor_vy_mps[rows], None if self.z_m is None else self.z_m[rows])

    def row(self, k: int) -> SensorView:
        """Time ``k`` of a view computed for several times (see :meth:`Scene.views`).

        The row of a view of many times (the object level's chunk) is a :class:`_ViewRow`: its times and sensor
        velocity are set at once, its arrays indexed out of this view's when one of them is first read (the same
        fields, the same values), so that a cycle whose truth nobody reads costs no array views."""
        rows = self.__dict__.get("_rows")
        if rows is None:
            if np.size(self.t_s) == 1:
                f = [getattr(self, name)[k] for name in _VIEW_ARRAYS]
                return SensorView(float(self.t_s[k]), *f, float(self.sensor_vx_mps[k]),
                                  float(self.sensor_vy_mps[k]), None if self.z_m is None else self.z_m[k])
            rows = (np.asarray(self.t_s).tolist(), np.asarray(self.sensor_vx_mps).tolist(),
                    np.asarray(self.sensor_vy_mps).tolist())
            object.__setattr__(self, "_rows", rows)
        t, svx, svy = rows
        out = object.__new__(_ViewRow)
        d = out.__dict__
        d["t_s"], d["sensor_vx_mps"], d["sensor_vy_mps"] = t[k], svx[k], svy[k]
        d["z_m"] = None if self.z_m is None else self.z_m[k]
        d["_of"] = (self, k)
        return out


class _ViewRow(SensorView):
    """Time k of a view of many times (:meth:`SensorView.row`), a SensorView in every respect: its arrays are
    indexed out of that view's on the first read of any of them. Pickled and copied as a plain SensorView."""

    def __getattr__(self, name: str):            # (only for what the instance does not hold yet)
        d = self.__dict__
        if name in _VIEW_ARRAY_SET and "_of" in d:
            view, k = d.pop("_of")
            for a in _VIEW_ARRAYS:
                d[a] = getattr(view, a)[k]
            return d[name]
        raise AttributeError(f"'SensorView' object has no attribute {name!r}")

    def __reduce__(self):
        return SensorView, tuple(getattr(self, name) for name in _VIEW_FIELDS)

    def __repr__(self) -> str:
        return SensorView.__repr__(self).replace(type(self).__qualname__, "SensorView", 1)

    def __eq__(self, other):             # SensorView's dataclass __eq__, across the two classes
        if not isinstance(other, SensorView):
            return NotImplemented
        return tuple(getattr(self, f) for f in _VIEW_FIELDS) == tuple(getattr(other, f) for f in _VIEW_FIELDS)

    __hash__ = SensorView.__hash__


#: cycles of a scripted ego computed together by :meth:`Scene.ego_state` (the vehicle's 0x300/0x301 every cycle)
EGO_BLOCK = 256
#: an actor shorter and narrower than this (m) is a point to the radar (a pedestrian, a sign's post): what it
#: reflects comes from where the line of sight through its centre meets its outline, not from its outline's
#: nearest point, which stalls at the sensor's axis for as long as the body takes to cross it (a pedestrian
#: 0.6 m wide walking at 1.5 m/s: 0.4 s, in which a tracker took it for stopped)
POINT_SIZE_M = 1.0

_VIEW_ARRAYS = ("x_m", "y_m", "vx_mps", "vy_mps", "ax_mps2", "ay_mps2", "ground_vx_mps", "ground_vy_mps",
                "orientation_rad", "az_lo_rad", "az_hi_rad", "centre_x_m", "centre_y_m")
_VIEW_FIELDS = ("t_s", *_VIEW_ARRAYS, "sensor_vx_mps", "sensor_vy_mps", "z_m")
_VIEW_ARRAY_SET = frozenset(_VIEW_ARRAYS)


def _rot(angle: np.ndarray | float, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return _rot_cs(np.cos(angle), np.sin(angle), x, y)


def _rot_cs(c, s, x: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_rot` by an angle of cosine ``c`` and sine ``s`` (taken once for several rotations by it)."""
    return c * x - s * y, s * x + c * y


def boxes_meet(dx, dy, turn, a_half_l, a_half_w, b_half_l, b_half_w, tol: float = OVERLAP_TOLERANCE_M):
    """Whether box B, its centre at (``dx``, ``dy``) in box A's axes (from A's centre) and turned by ``turn`` against
    them, overlaps box A by more than ``tol`` along every axis (boxes that only touch do not): a separating-axis
    test on the four axes of the two rectangles, half lengths and half widths given; arrays broadcast."""
    cr, sr = np.cos(turn), np.sin(turn)
    c, s = np.abs(cr), np.abs(sr)
    along_u = np.abs(dx * cr + dy * sr)                    # the centres' distance along B's axes
    along_v = np.abs(-dx * sr + dy * cr)
    return ((np.abs(dx) < a_half_l + b_half_l * c + b_half_w * s - tol)
            & (np.abs(dy) < a_half_w + b_half_l * s + b_half_w * c - tol)
            & (along_u < b_half_l + a_half_l * c + a_half_w * s - tol)
            & (along_v < b_half_w + a_half_l * s + a_half_w * c - tol))


class DynamicEgo:
    """An ego driven from outside (closed loop): position, speed and acceleration set each cycle.

    Between updates the state is extrapolated with constant acceleration; it
    answers ``state(t)`` like a :class:`MoverTable` of one mover.
    """

    def __init__(self, speed_mps: float, lateral: MoverTable | None = None) -> None:
        self.t0, self.s0, self.v0, self.a0 = 0.0, 0.0, speed_mps, 0.0
        self.lateral = lateral        # the scenario's lateral motion (offset, lane change): kept in closed loop

    def set(self, t_s: float, s_m: float, v_mps: float, a_mps2: float) -> None:
        self.t0, self.s0, self.v0, self.a0 = t_s, s_m, v_mps, a_mps2

    def state(self, t_s) -> MoverState:
        t = np.asarray(t_s, dtype=np.float64)
        dt = (t - self.t0)[..., None] if t.ndim else np.array([t - self.t0])
        v = np.maximum(self.v0 + self.a0 * dt, 0.0)
        x = self.s0 + self.v0 * dt + 0.5 * self.a0 * dt * dt
        z = np.zeros_like(x)
        if self.lateral is None:
            return MoverState(x, z, v, z.copy(), np.full_like(x, self.a0), z.copy())
        lat = self.lateral.state(t_s)
        return MoverState(x, lat.y_m.reshape(x.shape), v, lat.vy_mps.reshape(x.shape), np.full_like(x, self.a0),
                          lat.ay_mps2.reshape(x.shape))


class Scene:
    """Evaluates a scenario's ego and actors at any time."""

    def __init__(self, scenario: Scenario) -> None:
        self.scenario = scenario
        self.road = RoadGeometry(scenario.road.geometry_segments(), scenario.road.curvature_1pm)
        actors = scenario.actors
        self.actors = actors
        self.n = len(actors)
        self._ego = MoverTable([0.0], [scenario.ego.y_m], [scenario.ego.speed_mps], [0.0], [scenario.ego.accel], [()],
                               [scenario.ego_lateral()])
        self.dynamic_ego: DynamicEgo | None = None
        self._ego_block: tuple | None = None          # (ego, block, states) of :meth:`ego_state` on the cycle grid
        self._rails: dict[int, tuple[np.ndarray, np.ndarray]] = {}     # :meth:`_rail_posts`, by actor
        self._movers = MoverTable(
            [a.x_m for a in actors], [scenario.actor_y_m(a) for a in actors], [a.speed_mps for a in actors],
            [math.radians(a.heading_deg) for a in actors], [a.accel for a in actors], [a.waypoints for a in actors])
        self.z_m = np.array([a.z for a in actors], dtype=np.float64)              # bottom above the road
        self.height_m = np.array([a.height for a in actors], dtype=np.float64)
        self.elevated = np.array([a.elevated for a in actors], dtype=bool)
        self.mount_z_m = float(scenario.radar.mount.z_m)
        self.length_m = np.array([a.length for a in actors], dtype=np.float64)
        self.width_m = np.array([a.width for a in actors], dtype=np.float64)
        self.rcs_dbsm = np.array([a.rcs for a in actors], dtype=np.float64)
        self.class_code = np.array([a.class_code for a in actors], dtype=np.int64)
        self.swerling = np.array([a.swerling_case for a in actors], dtype=np.int64)
        self.is_guardrail = np.array([a.object_class == "guardrail" for a in actors], dtype=bool)
        self.heading_rel = np.array([math.radians(a.heading_deg) for a in actors], dtype=np.float64)
        m = scenario.radar.mount
        self.mount = (m.x_m, m.y_m, math.radians(m.yaw_deg))
        hl, hw = self.length_m / 2.0, self.width_m / 2.0
        self._corners_x = np.stack([hl, hl, -hl, -hl], axis=-1) if self.n else np.zeros((0, 4))
        self._corners_y = np.stack([hw, -hw, hw, -hw], axis=-1) if self.n else np.zeros((0, 4))

    def drive_ego(self) -> DynamicEgo:
        """Hand the ego to a closed loop: from now on its motion is set from outside."""
        self.dynamic_ego = DynamicEgo(self.scenario.ego.speed_mps, self._ego)
        self._ego = self.dynamic_ego
        return self.dynamic_ego

    # --- road geometry ---------------------------------------------------
    def stations(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where along the road (its station s, m) the ego, shape (T,), and the actors, shape (T, n), are at
        ``times`` (the scenario's motion; a closed loop's ego is not known in advance)."""
        t = np.asarray(times, dtype=np.float64)
        return self._ego.state(t).x_m[:, 0], self._movers.state(t).x_m

    def road_to_world(self, s: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """World position and road heading at road coordinates (s, d)."""
        return self.road.to_world(s, d)

    def _world_motion(self, st: MoverState) -> tuple[np.ndarray, ...]:
        x, y, psi = self.road_to_world(st.x_m, st.y_m)
        kappa = 0.0 if self.road.straight else self.road.curvature(st.x_m)
        scale = 1.0 - kappa * st.y_m  # ds along an offset line is (1 − κd) times longer
        vx, vy = _rot(psi, st.vx_mps * scale, st.vy_mps)
        return x, y, psi, vx, vy

    def _ego_pose(self, st: MoverState) -> tuple[np.ndarray, ...]:
        """World position, heading, world velocity, speed, acceleration and yaw rate of the ego's rear axle.

        The heading is the road's plus the angle of the ego's own lateral motion (an offset or a lane change);
        the yaw rate is the road's turn, κ(s)·ds/dt (κ changes along a clothoid), plus that angle's rate,
        d/dt atan(v_y / v_s).
        """
        x, y, psi, vxw, vyw = self._world_motion(st)
        kappa = 0.0 if self.road.straight else self.road.curvature(st.x_m)
        v_s = st.vx_mps * (1.0 - kappa * st.y_m)
        v_d = st.vy_mps
        heading = psi + np.arctan2(v_d, np.maximum(v_s, 1e-6))
        speed = np.hypot(v_s, v_d)
        turn = np.where(speed > 0.1, (st.ay_mps2 * v_s - v_d * st.ax_mps2) / np.maximum(speed * speed, 1e-2), 0.0)
        return x, y, heading, vxw, vyw, speed, st.ax_mps2, kappa * st.vx_mps + turn

    def _actor_pose(self, st: MoverState) -> tuple[np.ndarray, ...]:
        """World position, heading (its motion's direction, or the road's plus ``heading_deg`` when it stands) and
        world velocity of the actors' reference points (a box's centre, a guardrail's start)."""
        ax_, ay_, psi, avx, avy = self._world_motion(st)
        heading = np.where(np.hypot(avx, avy) > 0.1, np.arctan2(avy, avx), psi + self.heading_rel)
        return ax_, ay_, heading, avx, avy

    def _rail_posts(self, i: int) -> tuple[np.ndarray, np.ndarray]:
        """World positions of guardrail actor ``i``'s posts: from its start over its length, along the road's curve
        (its heading relative to the road), every ``road.guardrails.post_spacing_m``. They stand still: computed once
        (the radar's view and the collision judge ask every cycle)."""
        posts = self._rails.get(i)
        if posts is None:
            a = self.actors[i]
            n_posts = max(int(a.length / self.scenario.road.guardrails.post_spacing_m) + 1, 2)
            u = np.linspace(0.0, a.length, n_posts)
            h = self.heading_rel[i]
            wx, wy, _ = self.road_to_world(a.x_m + u * math.cos(h), self.scenario.actor_y_m(a) + u * math.sin(h))
            posts = self._rails[i] = (wx, wy)
        return posts

    def ego_contacts(self, times_s: np.ndarray) -> np.ndarray:
        """Which actors' boxes intersect the ego's at the times ``times_s`` (T,): bool (T, n_actors).

        The ego's box is ``ego.length_m`` × ``ego.width_m`` with the rear axle ``EGO_REAR_OVERHANG_M`` ahead of its
        rear end, turned by the ego's heading; an actor's is its length × width turned by its heading. Boxes that meet
        by less than ``OVERLAP_TOLERANCE_M`` along some axis only touch; an actor whose bottom is ``EGO_HEIGHT_M`` or
        more above the road passes over the ego. A separating-axis test, every actor and time at once. A guardrail
        actor is its posts, along the road's curve as the radar sees them (its straight box cut across the lane on a
        bend: an independent tester's false collision): met when a post lies inside the ego's box by more than the
        tolerance."""
        t = np.asarray(times_s, dtype=np.float64)
        ex, ey, epsi = (a[:, :1] for a in self._ego_pose(self._ego.state(t))[:3])           # (T, 1)
        ax_, ay_, heading, _, _ = self._actor_pose(self._movers.state(t))                    # (T, n)
        hl, hw = self.length_m / 2.0, self.width_m / 2.0
        ego = self.scenario.ego
        el, ew = ego.length_m / 2.0, ego.width_m / 2.0
        centre = el - EGO_REAR_OVERHANG_M                      # the ego box's centre ahead of the rear axle
        dx, dy = _rot(-epsi, ax_ - ex, ay_ - ey)               # the actor's centre in the ego's axes (rear axle 0)
        dx = dx - centre                                       # … from the ego box's centre
        met = boxes_meet(dx, dy, heading - epsi, el, ew, hl, hw) & (self.z_m < EGO_HEIGHT_M)
        for i in np.flatnonzero(self.is_guardrail):
            met[:, i] = self._posts_in_ego(int(i), ex, ey, epsi)[2].any(axis=1) & (self.z_m[i] < EGO_HEIGHT_M)
        return met

    def actor_contacts(self, times_s: np.ndarray, block: int = 256) -> np.ndarray:
        """Which pairs of actors' boxes overlap at the times ``times_s`` (T,): bool (T, n, n), symmetric, the diagonal
        false. The boxes and the touch tolerance are :meth:`ego_contacts`'; a pair one of whose bottoms is
        ``EGO_HEIGHT_M`` or more above the road does not meet (a bridge over a car), nor does a guardrail actor (its
        box is not its posts: see :meth:`ego_contacts`). Computed ``block`` times at a time."""
        t = np.asarray(times_s, dtype=np.float64)
        n = self.n
        out = np.zeros((t.size, n, n), dtype=bool)
        hl, hw = self.length_m / 2.0, self.width_m / 2.0
        road = (self.z_m < EGO_HEIGHT_M) & ~self.is_guardrail
        both = road[:, None] & road[None, :] & ~np.eye(n, dtype=bool)
        if not both.any():
            return out
        for k in range(0, t.size, block):
            ax_, ay_, heading, _, _ = self._actor_pose(self._movers.state(t[k:k + block]))      # (B, n)
            dx, dy = _rot(-heading[:, :, None], ax_[:, None, :] - ax_[:, :, None], ay_[:, None, :] - ay_[:, :, None])
            turn = heading[:, None, :] - heading[:, :, None]
            met = boxes_meet(dx, dy, turn, hl[:, None], hw[:, None], hl[None, :], hw[None, :])
            out[k:k + block] = met & both
        return out

    def _posts_in_ego(self, i: int, ex: np.ndarray, ey: np.ndarray, epsi: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Guardrail actor ``i``'s posts in the ego's axes (x from the rear axle, y from its centre line) at the ego's
        poses ``ex``, ``ey``, ``epsi`` (T, 1), and which lie inside the ego's box by more than the tolerance: (T, posts)
        each (:meth:`ego_contacts`' test of a guardrail actor)."""
        ego = self.scenario.ego
        el, ew = ego.length_m / 2.0, ego.width_m / 2.0
        wx, wy = self._rail_posts(i)
        px, py = _rot(-epsi, wx - ex, wy - ey)
        inside = (np.abs(px - (el - EGO_REAR_OVERHANG_M)) < el - OVERLAP_TOLERANCE_M) \
            & (np.abs(py) < ew - OVERLAP_TOLERANCE_M)
        return px, py, inside

    def post_inside_ego(self, i: int, t_s: float) -> tuple[float, float]:
        """Guardrail actor ``i``'s first post inside the ego's box at ``t_s`` (the nearest to the box's centre if none
        is), in the ego's axes: what the scenario check names where :meth:`ego_contacts` finds the actor on the ego."""
        ex, ey, epsi = self._ego_pose(self._ego.state(np.array([float(t_s)])))[:3]
        px, py, inside = (a[0] for a in self._posts_in_ego(i, ex[:, :1], ey[:, :1], epsi[:, :1]))
        centre = self.scenario.ego.length_m / 2.0 - EGO_REAR_OVERHANG_M
        k = int(np.flatnonzero(inside)[0]) if inside.any() else int(np.argmin(np.hypot(px - centre, py)))
        return float(px[k]), float(py[k])

    def ego_state(self, t_s: float) -> EgoState:
        """The ego at ``t_s``. On the cycle grid of a scripted ego (``t_s`` = k × period) it comes from a block of
        ``EGO_BLOCK`` cycles computed in one pass (the same numbers, element by element); a closed-loop ego, whose
        future is not known yet, and any other time are computed on their own."""
        if self.dynamic_ego is None:
            state = self._ego_on_grid(t_s)
            if state is not None:
                return state
        x, y, heading, _, _, speed, accel, yaw = self._ego_pose(self._ego.state(t_s))
        return EgoState(float(x[0]), float(y[0]), float(heading[0]), float(speed[0]), float(accel[0]), float(yaw[0]))

    def yaw_rates(self, times_s: np.ndarray) -> np.ndarray:
        """The ego's yaw rate (rad/s) at the times ``times_s`` (T,): the sensor's axes turn at it."""
        return self._ego_pose(self._ego.state(np.asarray(times_s, dtype=np.float64)))[7][:, 0]

    def _ego_on_grid(self, t_s: float) -> EgoState | None:
        period = self.scenario.period_s
        k = round(t_s / period)
        if not (0 <= k and k * period == t_s):
            return None
        block, i = divmod(k, EGO_BLOCK)
        cached = self._ego_block
        if cached is None or cached[0] is not self._ego or cached[1] != block:
            times = (block * EGO_BLOCK + np.arange(EGO_BLOCK)) * period
            x, y, heading, _, _, speed, accel, yaw = (a[:, 0].tolist() for a in self._ego_pose(self._ego.state(times)))
            cached = self._ego_block = (self._ego, block, list(zip(x, y, heading, speed, accel, yaw)))
        return EgoState(*cached[2][i])

    def lane_gap(self, t_s: float, i: int) -> tuple[float, float, float, float, float]:
        """Actor ``i`` against the ego in road coordinates, as a test judge measures a lead on any road.

        Returns the gap along the ego's lane from the sensor to the actor's rear end (m), the actor's lateral
        offset from the centre of the ego's lane (m, left positive), the closing speed along the lane
        (m/s, positive closing), and the actor's speed and acceleration along the lane (m/s, m/s²).
        """
        e, a = self._ego.state(t_s), self._movers.state(t_s)
        se, sa, de = float(e.x_m[0]), float(a.x_m[i]), float(e.y_m[0])
        # arc length along the ego's lane (offset de from the reference line), through any change of curvature
        gap = float(self.road.lane_length(se, sa, de)) - self.mount[0] - self.length_m[i] / 2.0
        scale_e = 1.0 - float(self.road.curvature(se)) * de
        scale_a = 1.0 - float(self.road.curvature(sa)) * de
        closing = float(e.vx_mps[0]) * scale_e - float(a.vx_mps[i]) * scale_a
        return (gap, float(a.y_m[i]) - de, closing, float(a.vx_mps[i]) * scale_a,
                float(a.ax_mps2[i]) * scale_a)

    def lane_footprint(self, t_s: float, i: int) -> tuple[float, float, float, float, float]:
        """Actor ``i``'s box against the ego's lane, turned by its heading on the road (a truck parked crosswise
        spans the lane across, not along): the gaps along the ego's lane from the sensor to its nearest and its
        farthest end (m), its lateral extent from the centre of the ego's lane (m, left positive), lowest and
        highest, and its speed along the lane (m/s, :meth:`lane_gap`'s). :meth:`lane_gap` takes an actor along the
        lane (its centre and half its length)."""
        gap, lateral, _, speed, _ = self.lane_gap(t_s, i)
        a = self._movers.state(t_s)
        vx, vy = float(a.vx_mps[i]), float(a.vy_mps[i])
        h = math.atan2(vy, vx) if math.hypot(vx, vy) > 0.1 else float(self.heading_rel[i])
        half_l, half_w = self.length_m[i] / 2.0, self.width_m[i] / 2.0
        along = abs(half_l * math.cos(h)) + abs(half_w * math.sin(h))
        across = abs(half_l * math.sin(h)) + abs(half_w * math.cos(h))
        centre = gap + half_l
        return centre - along, centre + along, lateral - across, lateral + across, speed

    # --- the sensor's view -------------------------------------------------
    def sensor_pose(self, ego: EgoState) -> tuple[float, float, float, float, float]:
        """World position, heading and velocity of the sensor."""
        mx, my, myaw = self.mount
        ox, oy = _rot(ego.heading_rad, np.float64(mx), np.float64(my))
        px, py = ego.x_m + float(ox), ego.y_m + float(oy)
        evx, evy = ego.speed_mps * math.cos(ego.heading_rad), ego.speed_mps * math.sin(ego.heading_rad)
        w = ego.yaw_rate_rps
        return px, py, ego.heading_rad + myaw, evx - w * float(oy), evy + w * float(ox)

    def view(self, t_s: float, h_s: float = 1e-3) -> SensorView:
        """Everything the sensor needs about the actors at ``t_s``."""
        return self.views(np.array([t_s], dtype=np.float64), h_s).row(0)

    def views(self, times_s: np.ndarray, h_s: float = 1e-3) -> SensorView:
        """The sensor's view at T times at once: arrays of shape (T, n_actors), sensor velocity (T,).

        One pass of numpy operations for all the times (the object level renders
        its cycles in chunks this way).
        """
        t = np.asarray(times_s, dtype=np.float64)
        est = self._ego.state(t)                                   # (T, 1)
        ex, ey, epsi, evx_w, evy_w, _, eacc, w = (a[:, 0] for a in self._ego_pose(est))
        mx, my, myaw = self.mount
        ox, oy = _rot(epsi, np.float64(mx), np.float64(my))
        px, py, psi_s = ex + ox, ey + oy, epsi + myaw
        svx, svy = evx_w - w * oy, evy_w + w * ox
        st = self._movers.state(t)                                 # (T, n)
        ax_, ay_, aheading, avx, avy = self._actor_pose(st)
        if self.road.straight:
            # straight road: the road frame is the world frame, the profiles' accelerations are exact
            aax, aay = st.ax_mps2, st.ay_mps2
            eax, eay = eacc, est.ay_mps2[:, 0]
        else:
            # curved road: central differences of the world velocity (centripetal terms included)
            tm = np.maximum(t - h_s, 0.0)
            dt = (h_s + np.minimum(h_s, t))[:, None]
            _, _, _, vpx, vpy = self._world_motion(self._movers.state(t + h_s))
            _, _, _, vmx, vmy = self._world_motion(self._movers.state(tm))
            aax, aay = (vpx - vmx) / dt, (vpy - vmy) / dt
            _, _, _, epx, epy = self._world_motion(self._ego.state(t + h_s))
            _, _, _, emx, emy = self._world_motion(self._ego.state(tm))
            eax, eay = (epx - emx)[:, 0] / dt[:, 0], (epy - emy)[:, 0] / dt[:, 0]
        c_ = psi_s[:, None]
        cx, cy = _rot(-c_, ax_ - px[:, None], ay_ - py[:, None])
        rel_heading = aheading - c_
        # nearest point of each box to the sensor
        lx, ly = _rot(-rel_heading, -cx, -cy)
        hl, hw = self.length_m / 2.0, self.width_m / 2.0
        qx, qy = np.clip(lx, -hl, hl), np.clip(ly, -hw, hw)
        c_h, s_h = np.cos(rel_heading), np.sin(rel_heading)          # (the box's turn: here and for its corners)
        ox_, oy_ = _rot_cs(c_h, s_h, qx, qy)
        rx, ry = cx + ox_, cy + oy_
        small = (self.length_m <= POINT_SIZE_M) & (self.width_m <= POINT_SIZE_M)
        if small.any():
            # a point-sized body: where the line of sight through its centre enters its box
            rc = np.maximum(np.hypot(cx, cy), 1e-9)
            ulx, uly = np.abs(lx) / rc, np.abs(ly) / rc           # the line of sight in the box's axes
            depth = np.minimum(hl / np.maximum(ulx, 1e-12), hw / np.maximum(uly, 1e-12))
            scale = np.maximum(rc - depth, 0.0) / rc
            rx, ry = np.where(small, cx * scale, rx), np.where(small, cy * scale, ry)
        # azimuth extent from the four corners
        kx, ky = _rot_cs(c_h[..., None], s_h[..., None], self._corners_x, self._corners_y)
        az = np.arctan2(cy[..., None] + ky, cx[..., None] + kx)
        vx, vy = _rot(-c_, avx - svx[:, None], avy - svy[:, None])
        gvx, gvy = _rot(-c_, avx, avy)
        ax_rel, ay_rel = _rot(-c_, aax - eax[:, None], aay - eay[:, None])
        s_vx, s_vy = _rot(-psi_s, svx, svy)
        wrapped = (rel_heading + np.pi) % (2.0 * np.pi) - np.pi
        # the four corners' extremes pairwise (a reduction over the last axis of 4 costs some 15× as much)
        lo = np.minimum(np.minimum(az[..., 0], az[..., 1]), np.minimum(az[..., 2], az[..., 3]))
        hi = np.maximum(np.maximum(az[..., 0], az[..., 1]), np.maximum(az[..., 2], az[..., 3]))
        rz = np.broadcast_to(np.where(self.elevated, self.z_m - self.mount_z_m, 0.0), rx.shape)
        return SensorView(t, rx, ry, vx, vy, ax_rel, ay_rel, gvx, gvy, wrapped, lo, hi, cx, cy, s_vx, s_vy, rz)

    def elevation_extent(self, view: SensorView) -> tuple[np.ndarray, np.ndarray]:
        """Elevation angles (rad, up positive) of each actor's bottom and top as the sensor sees them at the
        horizontal distance of its nearest point: shapes like ``view.x_m``."""
        r = np.maximum(np.hypot(view.x_m, view.y_m), 0.1)
        return (np.arctan2(self.z_m - self.mount_z_m, r),
                np.arctan2(self.z_m + self.height_m - self.mount_z_m, r))

    def road_line(self, t_s: float, d_m: float, max_range_m: float, step_m: float = 1.0
                  ) -> tuple[np.ndarray, np.ndarray]:
        """Sensor-frame points of the road-parallel line at lateral offset ``d_m`` (road frame), ahead of
        the ego up to ``max_range_m`` along the road — the ground truth of a road boundary."""
        ego = self.ego_state(t_s)
        px, py, psi_s, _, _ = self.sensor_pose(ego)
        s_ego = float(self._ego.state(t_s).x_m[0])
        s = s_ego + np.arange(0.0, max_range_m + step_m, step_m)
        wx, wy, _ = self.road_to_world(s, np.full_like(s, d_m))
        return _rot(-psi_s, wx - px, wy - py)

    def guardrail_posts(self, t_s: float, max_range_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Sensor-frame positions of the guardrail posts within ``max_range_m`` ahead and behind.

        Road-edge guardrails come from ``road.guardrails``; guardrail actors add
        posts along their own length. Posts are fixed in the world, so they are
        stationary targets. One time of :meth:`guardrail_posts_many`.
        """
        gx, gy, _ = self.guardrail_posts_many(np.array([t_s], dtype=np.float64), max_range_m)
        return gx, gy

    def guardrail_posts_many(self, times_s: np.ndarray, max_range_m: float
                             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`guardrail_posts` at T times in one pass: the posts of every time one after the other, and where
        each time's start, shape (T + 1,) (time k's posts are ``[starts[k]:starts[k + 1]]``, in the order of
        :meth:`guardrail_posts`: the left edge's, the right edge's, then the guardrail actors').

        The ego's state and the sensor's pose at each time, each post's world position and its rotation into the
        sensor frame are the same numbers as one time at a time (element by element), so a chunk of cycles sees
        exactly the posts that the cycles would one by one."""
        sc = self.scenario
        g = sc.road.guardrails
        t = np.asarray(times_s, dtype=np.float64)
        est = self._ego.state(t)                                   # (T, 1)
        ex, ey, heading = (a[:, 0] for a in self._ego_pose(est)[:3])
        mx, my, myaw = self.mount
        ox, oy = _rot(heading, np.float64(mx), np.float64(my))
        px, py, psi_s = ex + ox, ey + oy, heading + myaw
        s_ego = est.x_m[:, 0]
        rows, xs, ys = [], [], []
        # the posts from 5 m behind the ego to 5 m past the range ahead, and as far behind as the sensor can look:
        # its sectors span at most ±90° about its yaw, whose farthest look back along the ego's axis is −cos … or
        # −|sin| of it (a rear radar, yaw 180°, saw no post beyond 5 m behind the ego: a tester's finding)
        back = 1.0 if math.cos(myaw) <= 0.0 else abs(math.sin(myaw))
        k0 = np.floor((s_ego - 5.0 + min(0.0, float(mx) - back * max_range_m)) / g.post_spacing_m).astype(np.int64)
        k1 = np.ceil((s_ego + max_range_m + 5.0) / g.post_spacing_m).astype(np.int64)
        count = k1 - k0 + 1
        row = np.repeat(np.arange(t.size), count)
        starts = np.concatenate([[0], np.cumsum(count)])
        s = (np.repeat(k0, count) + (np.arange(row.size) - starts[row])) * g.post_spacing_m
        for offset, edge, sign in ((g.left_offset_m, sc.road.left_edge_y_m, 1.0),
                                   (g.right_offset_m, sc.road.right_edge_y_m, -1.0)):
            if offset is None:
                continue
            wx, wy, _ = self.road_to_world(s, np.full_like(s, edge + sign * offset))
            rows.append(row)
            xs.append(wx)
            ys.append(wy)
        for i in np.flatnonzero(self.is_guardrail):
            wx, wy = self._rail_posts(int(i))
            rows.append(np.repeat(np.arange(t.size), wx.size))
            xs.append(np.tile(wx, t.size))
            ys.append(np.tile(wy, t.size))
        if not xs:
            return np.zeros(0), np.zeros(0), np.zeros(t.size + 1, dtype=np.int64)
        row = np.concatenate(rows)
        order = np.argsort(row, kind="stable")                     # by time, each time's posts in list order
        row = row.take(order)
        wx, wy = np.concatenate(xs).take(order), np.concatenate(ys).take(order)
        c, s_ = np.cos(-psi_s), np.sin(-psi_s)
        dx, dy = wx - px.take(row), wy - py.take(row)
        c, s_ = c.take(row), s_.take(row)
        starts = np.searchsorted(row, np.arange(t.size + 1))
        return c * dx - s_ * dy, s_ * dx + c * dy, starts
