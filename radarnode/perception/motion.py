"""Motion models shared by the radar's own tracker and the consumer ECU's: state transition and process noise, and
the turn of the objects' velocities when the ego turns (:func:`road_turn`)."""

from __future__ import annotations

import math

import numpy as np

from radarnode.errors import ConfigError


def transition(model: str, dt: float, q: float) -> tuple[np.ndarray, np.ndarray]:
    """State transition F and process noise Q (white acceleration for CV, white jerk for CA), 2-D."""
    if model == "cv":
        f1 = np.array([[1.0, dt], [0.0, 1.0]])
        q1 = q * np.array([[dt ** 4 / 4, dt ** 3 / 2], [dt ** 3 / 2, dt ** 2]])
        order = [0, 2]                                # x, vx ; y, vy
    elif model == "ca":
        f1 = np.array([[1.0, dt, dt * dt / 2], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
        q1 = q * np.array([[dt ** 5 / 20, dt ** 4 / 8, dt ** 3 / 6], [dt ** 4 / 8, dt ** 3 / 3, dt ** 2 / 2],
                           [dt ** 3 / 6, dt ** 2 / 2, dt]])
        order = [0, 2, 4]
    else:
        raise ConfigError(f"motion model: value {model!r} is not allowed; expected 'cv' or 'ca'")
    n = 2 * len(order)
    f, qq = np.zeros((n, n)), np.zeros((n, n))
    for axis in range(2):
        idx = [o + axis for o in order]
        f[np.ix_(idx, idx)] = f1
        qq[np.ix_(idx, idx)] = q1
    return f, qq


#: the objects follow the ego's road (:func:`road_turn`) in full from the first speed on, not at all below the
#: second (m/s): the path's curvature, yaw rate over speed, means nothing at walking pace
ROAD_SPEED_MPS = (3.0, 1.0)
#: … and in full up to the first curvature, not at all beyond the second (1/m): a road's bend is R 50 m and wider,
#: a turn at a junction or in a car park R 25 m and tighter, and there the others do not drive the ego's circle
ROAD_CURVATURE_1PM = (0.02, 0.04)


def road_share(speed_mps: float, kappa_1pm: float) -> float:
    """How much the objects follow the ego's road (0 … 1, linear between the edges of ROAD_SPEED_MPS and
    ROAD_CURVATURE_1PM)."""
    (s_full, s_none), (k_full, k_none) = ROAD_SPEED_MPS, ROAD_CURVATURE_1PM
    by_speed = min(max((speed_mps - s_none) / (s_full - s_none), 0.0), 1.0)
    by_bend = min(max((k_none - abs(kappa_1pm)) / (k_none - k_full), 0.0), 1.0)
    return by_speed * by_bend


def road_turn(before: np.ndarray, moved: np.ndarray, yaw_rad: float, dt: float, sensor_velocity,
              sensor_accel=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """Relative states (N, d) = [x, y, vx, vy(, ax, ay)] after the linear step of ``dt`` (``moved``; ``before``
    it) into the axes of a sensor that turned by ``yaw_rad`` meanwhile, for objects that follow the ego's road;
    and the rotation (N, d, d) that does it to the step's Jacobian.

    Positions turn by −yaw_rad. An object's velocity over ground g = v + u (u: the sensor's own, in its axes)
    follows the ego's path: it turns by κ·s, κ the path's curvature (the yaw rate over the sensor's speed) and s
    how far the object drove along the path's tangent where it is; in the sensor's axes by φ = κ·s − yaw_rad,
    while u stays what it is in the sensor's own axes: v' = R(φ)(v + u) − u, and the acceleration likewise with
    the sensor's own. A standing object (g = 0) stays where it is on the ground; a vehicle ahead on the ego's
    bend at the ego's speed keeps its velocity relative to the sensor (φ = 0; the world-fixed model, φ = −yaw_rad,
    made it lag by a few tenths of a m/s, which ACC took for closing); an oncoming one turns the other way.

    That holds on roads, not where the ego turns in a car park or at a junction: the road's share fades out below
    walking pace and at a path tighter than a road's (:func:`road_share`), where the objects keep their course
    over ground (the world-fixed model), with no jump at either edge."""
    n, d = moved.shape
    ux, uy = float(sensor_velocity[0]), float(sensor_velocity[1])
    speed = math.hypot(ux, uy)
    phi = np.full(n, -yaw_rad)
    g = moved[:, 2:4] + (ux, uy)
    kappa = yaw_rad / dt / speed if speed > 0.0 and dt > 0.0 else 0.0
    share = road_share(speed, kappa) if kappa else 0.0
    if share > 0.0:
        hx, hy = ux / speed, uy / speed
        # the path through the sensor: tangent along u, heading β + κ·(distance along it) at the object's place
        heading = math.atan2(uy, ux) + kappa * (before[:, 0] * hx + before[:, 1] * hy)
        phi += share * kappa * dt * (g[:, 0] * np.cos(heading) + g[:, 1] * np.sin(heading))
    c, s = math.cos(-yaw_rad), math.sin(-yaw_rad)
    cp, sp = np.cos(phi), np.sin(phi)
    out = np.empty_like(moved)
    out[:, 0] = c * moved[:, 0] - s * moved[:, 1]
    out[:, 1] = s * moved[:, 0] + c * moved[:, 1]
    out[:, 2] = cp * g[:, 0] - sp * g[:, 1] - ux
    out[:, 3] = sp * g[:, 0] + cp * g[:, 1] - uy
    rot = np.zeros((n, d, d))
    rot[:, 0, 0] = rot[:, 1, 1] = c
    rot[:, 0, 1], rot[:, 1, 0] = -s, s
    rot[:, 2, 2] = rot[:, 3, 3] = cp
    rot[:, 2, 3], rot[:, 3, 2] = -sp, sp
    if d == 6:
        ax, ay = float(sensor_accel[0]), float(sensor_accel[1])
        ga = moved[:, 4:6] + (ax, ay)
        out[:, 4] = cp * ga[:, 0] - sp * ga[:, 1] - ax
        out[:, 5] = sp * ga[:, 0] + cp * ga[:, 1] - ay
        rot[:, 4, 4] = rot[:, 5, 5] = cp
        rot[:, 4, 5], rot[:, 5, 4] = -sp, sp
    return out, rot


def road_predict(x: np.ndarray, p: np.ndarray, f: np.ndarray, q: np.ndarray, yaw_rad: float, dt: float,
                 sensor_velocity, sensor_accel=(0.0, 0.0)) -> tuple[np.ndarray, np.ndarray]:
    """States (n, d) and covariances (n, d, d) through the linear step ``f`` (process noise ``q``) and
    :func:`road_turn`: the prediction both trackers make while the ego turns."""
    moved, rot = road_turn(x, x @ f.T, yaw_rad, dt, sensor_velocity, sensor_accel)
    fk = rot @ f
    return moved, fk @ p @ fk.transpose(0, 2, 1) + q
