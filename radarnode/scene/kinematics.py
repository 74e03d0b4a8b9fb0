"""Piecewise motion profiles evaluated for many movers at once.

Each mover is a speed profile (initial speed, piecewise-constant acceleration;
the speed never goes below zero) driven either along a fixed road-relative
heading or along a path of untimed waypoints (straight legs; beyond the last
waypoint it goes on in the last leg's direction), or a timed waypoint path
(straight segments, constant speed on each). The profiles are compiled once
into padded knot tables so that evaluating all movers at one time is a
handful of numpy operations.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from radarnode.scene.scenario import AccelStep


@dataclass(frozen=True)
class MoverState:
    """Road-frame state of every mover at one time; every array has shape (n_movers,)."""

    x_m: np.ndarray
    y_m: np.ndarray
    vx_mps: np.ndarray
    vy_mps: np.ndarray
    ax_mps2: np.ndarray
    ay_mps2: np.ndarray


def _speed_knots(speed0: float, steps: Sequence[AccelStep]) -> list[tuple[float, float, float, float]]:
    """Return (t, v, L, a) knots: at time t the speed is v, the distance L, and a holds until the next knot."""
    events = [(0.0, 0.0)] + [(s.t_s, s.accel_mps2) for s in steps]
    # A step at t=0 replaces the implicit zero acceleration.
    merged: list[tuple[float, float]] = []
    for t, a in events:
        if merged and merged[-1][0] == t:
            merged[-1] = (t, a)
        else:
            merged.append((t, a))
    knots: list[tuple[float, float, float, float]] = []
    v, dist = speed0, 0.0
    for i, (t, a) in enumerate(merged):
        t_next = merged[i + 1][0] if i + 1 < len(merged) else np.inf
        if v <= 0.0 and a <= 0.0:
            knots.append((t, 0.0, dist, 0.0))
            v = 0.0
            continue
        knots.append((t, v, dist, a))
        if a < 0.0 and v + a * (t_next - t) < 0.0:  # comes to a stop inside this segment
            t_stop = t - v / a
            dist += v * (t_stop - t) + 0.5 * a * (t_stop - t) ** 2
            knots.append((t_stop, 0.0, dist, 0.0))
            v = 0.0
            continue
        if np.isfinite(t_next):
            dt = t_next - t
            dist += v * dt + 0.5 * a * dt * dt
            v += a * dt
    return knots


class MoverTable:
    """Compiled motion profiles of many movers.

    Parameters
    ----------
    x0_m, y0_m, speed_mps, heading_rad : sequences of length n
        Initial road-frame position, speed and road-relative heading.
    accel : sequence of n sequences of AccelStep
    waypoints : sequence of n sequences of Waypoint
        Timed (every ``t_s`` given): the mover follows them and ignores the rest; untimed: the path along
        which the speed profile drives (the initial position and heading are not used).
    """

    def __init__(self, x0_m, y0_m, speed_mps, heading_rad, accel, waypoints, lateral=None) -> None:
        n = len(x0_m)
        # lateral manoeuvres (t0, duration, dy) of profile movers: a cosine step of dy over the duration
        lat = [(math.inf, 1.0, 0.0) if m is None else m for m in (lateral or [None] * n)]
        self.lat_t0 = np.array([m[0] for m in lat], dtype=np.float64)
        self.lat_dur = np.array([m[1] for m in lat], dtype=np.float64)
        self.lat_dy = np.array([m[2] for m in lat], dtype=np.float64)
        self.n = n
        spd = [_speed_knots(float(speed_mps[i]), accel[i]) for i in range(n)]
        k = max([len(s) for s in spd] + [len(w) for w in waypoints] + [1])
        self.is_path = np.array([len(w) >= 2 and w[0].t_s is not None for w in waypoints], dtype=bool)
        # untimed waypoints: legs of a path driven by the speed profile (start, direction, cumulative length)
        self.is_route = np.array([len(w) >= 2 and w[0].t_s is None for w in waypoints], dtype=bool)
        kl = max([len(w) - 1 for w, r in zip(waypoints, self.is_route) if r] + [1])
        self.leg_x = np.zeros((n, kl))
        self.leg_y = np.zeros((n, kl))
        self.leg_ux = np.ones((n, kl))
        self.leg_uy = np.zeros((n, kl))
        # distance along the path at each leg's start: legs beyond a path's last are never reached; an actor without
        # a path has one leg from 0 (its numbers unused, finite: inf·0 in them warned of NaN on every step)
        self.leg_s = np.full((n, kl), np.inf)
        self.leg_s[:, 0] = 0.0
        for i in np.flatnonzero(self.is_route):
            px = np.array([p.x_m for p in waypoints[i]])
            py = np.array([p.y_m for p in waypoints[i]])
            dx, dy = np.diff(px), np.diff(py)
            ell = np.hypot(dx, dy)
            m = ell.size
            self.leg_x[i, :m], self.leg_y[i, :m] = px[:-1], py[:-1]
            self.leg_ux[i, :m], self.leg_uy[i, :m] = dx / ell, dy / ell
            self.leg_s[i, :m] = np.concatenate([[0.0], np.cumsum(ell)[:-1]])
        self.t = np.full((n, k), np.inf)
        self.v = np.zeros((n, k))
        self.dist = np.zeros((n, k))
        self.a = np.zeros((n, k))
        self.px = np.zeros((n, k))
        self.py = np.zeros((n, k))
        for i in range(n):
            if self.is_path[i]:
                w = waypoints[i]
                self.t[i, : len(w)] = [p.t_s for p in w]
                self.px[i, : len(w)] = [p.x_m for p in w]
                self.py[i, : len(w)] = [p.y_m for p in w]
                # hold the last point after the path ends
                self.px[i, len(w):] = w[-1].x_m
                self.py[i, len(w):] = w[-1].y_m
            else:
                rows = np.array(spd[i])
                self.t[i, : len(rows)] = rows[:, 0]
                self.v[i, : len(rows)] = rows[:, 1]
                self.dist[i, : len(rows)] = rows[:, 2]
                self.a[i, : len(rows)] = rows[:, 3]
        self.x0 = np.asarray(x0_m, dtype=np.float64)
        self.y0 = np.asarray(y0_m, dtype=np.float64)
        self.cos_h = np.cos(np.asarray(heading_rad, dtype=np.float64))
        self.sin_h = np.sin(np.asarray(heading_rad, dtype=np.float64))
        self._rows = np.arange(n)
        # the knots' columns side by side, so that a time's knot is one gather: t, a, v, dist, px, py
        self._knots = np.stack([self.t, self.a, self.v, self.dist, self.px, self.py], axis=-1)
        self._sorted = bool(np.all(self.t[:, 1:] >= self.t[:, :-1]))

    def state(self, t_s: float | np.ndarray) -> MoverState:
        """Road-frame position, velocity and acceleration of every mover at ``t_s``.

        A scalar time gives arrays of shape (n_movers,); an array of T times gives (T, n_movers).
        """
        t = np.asarray(t_s, dtype=np.float64)
        if t.ndim == 0:
            idx = np.maximum(np.sum(self.t <= t, axis=1) - 1, 0)
            r = self._rows
        else:
            if self._sorted and t.ndim == 1 and not np.isnan(t).any():    # a binary search a mover, all times
                idx = np.empty((t.size, self.n), dtype=np.intp)
                for j in range(self.n):
                    idx[:, j] = np.searchsorted(self.t[j], t, side="right")
                idx -= 1
                np.maximum(idx, 0, out=idx)
            else:
                idx = np.maximum(np.sum(self.t[None, :, :] <= t[:, None, None], axis=2) - 1, 0)
            t = t[:, None]
            r = self._rows[None, :]
        t_s = t
        knot = self._knots[r, idx]                       # (..., n, 6): t, a, v, dist, px, py
        t_k = knot[..., 0]
        t0 = np.where(np.isfinite(t_k), t_k, 0.0)
        dt = np.maximum(t_s - t0, 0.0)
        # speed-profile movers
        a = knot[..., 1]
        v = knot[..., 2] + a * dt
        dist = knot[..., 3] + knot[..., 2] * dt + 0.5 * a * dt * dt
        sx = self.x0 + dist * self.cos_h
        sy = self.y0 + dist * self.sin_h
        svx, svy = v * self.cos_h, v * self.sin_h
        sax, say = a * self.cos_h, a * self.sin_h
        if self.is_route.any():
            # along the path: the leg the distance has reached (the last leg goes on beyond its end)
            leg = np.maximum(np.sum(self.leg_s[:, 1:] <= dist[..., None], axis=-1), 0)
            ux, uy = self.leg_ux[r, leg], self.leg_uy[r, leg]
            along = dist - self.leg_s[r, leg]
            q = self.is_route
            sx = np.where(q, self.leg_x[r, leg] + along * ux, sx)
            sy = np.where(q, self.leg_y[r, leg] + along * uy, sy)
            svx, svy = np.where(q, v * ux, svx), np.where(q, v * uy, svy)
            sax, say = np.where(q, a * ux, sax), np.where(q, a * uy, say)
        if np.any(self.lat_dy != 0.0):
            u = np.clip((t_s - self.lat_t0) / self.lat_dur, 0.0, 1.0)
            inside = (u > 0.0) & (u < 1.0)
            w = np.pi / self.lat_dur
            sy = sy + self.lat_dy * 0.5 * (1.0 - np.cos(np.pi * u))
            svy = svy + np.where(inside, self.lat_dy * 0.5 * w * np.sin(np.pi * u), 0.0)
            say = say + np.where(inside, self.lat_dy * 0.5 * w * w * np.cos(np.pi * u), 0.0)
        if not self.is_path.any():
            return MoverState(sx, sy, svx, svy, sax, say)
        # waypoint movers: before the first waypoint they wait at it
        nxt = np.minimum(idx + 1, self.t.shape[1] - 1)
        knot1 = self._knots[r, nxt]
        t1 = knot1[..., 0]
        seg = np.where(np.isfinite(t1) & (t1 > t0) & (t_s >= self.t[:, 0]), t1 - t0, np.inf)
        frac = np.clip(dt / seg, 0.0, 1.0)
        dpx, dpy = knot1[..., 4] - knot[..., 4], knot1[..., 5] - knot[..., 5]
        px = knot[..., 4] + frac * dpx
        py = knot[..., 5] + frac * dpy
        moving = np.isfinite(seg) & (frac < 1.0)
        pvx = np.where(moving, dpx / np.where(moving, seg, 1.0), 0.0)
        pvy = np.where(moving, dpy / np.where(moving, seg, 1.0), 0.0)
        p = self.is_path
        zero = np.zeros_like(sx)
        return MoverState(np.where(p, px, sx), np.where(p, py, sy), np.where(p, pvx, svx),
                          np.where(p, pvy, svy), np.where(p, zero, sax), np.where(p, zero, say))
