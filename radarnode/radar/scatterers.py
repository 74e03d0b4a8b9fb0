"""Point scatterers: extended actors as points on their visible outline, guardrails as rows of posts.

Struct of arrays in the sensor frame (x forward, y left); velocities are
relative to the sensor. Only what lies inside the field of view and range is
generated (DESIGN §5: model only what the scene requires).

References
----------
seed 000 (scattering centres on the visible outline of extended objects);
seed 002 (multi-point model of a vehicle).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from radarnode.perception.types import _Columns
from radarnode.radar import elevation
from radarnode.radar.object_model import POINT_SIZE_M, aspect_weight, edge_taper, facing_edges, in_fov, nearest_in_fov
from radarnode.radar.presets import RadarPreset
from radarnode.scene.world import Scene, SensorView


@dataclass
class Scatterers(_Columns):
    """Point scatterers of one frame; every array has shape (n,)."""

    x_m: np.ndarray
    y_m: np.ndarray
    z_m: np.ndarray
    vx_mps: np.ndarray
    vy_mps: np.ndarray
    rcs_dbsm: np.ndarray
    actor_index: np.ndarray   # -1 for guardrail posts and clutter

    INT_FIELDS = ("actor_index",)

    @property
    def range_m(self) -> np.ndarray:
        return np.sqrt(self.x_m ** 2 + self.y_m ** 2 + self.z_m ** 2)

    @property
    def azimuth_rad(self) -> np.ndarray:
        return np.arctan2(self.y_m, self.x_m)

    @property
    def range_rate_mps(self) -> np.ndarray:
        r = np.maximum(self.range_m, 1e-9)
        return (self.x_m * self.vx_mps + self.y_m * self.vy_mps) / r

    def require_finite(self) -> None:
        """Raise if any float field holds a NaN or an infinity, or a value beyond :data:`SCATTERER_LIMITS`.

        One NaN scatterer turns a whole signal-level cube into NaN, and every
        detection of the frame vanishes without a word; this names the culprit
        instead. Every float field is checked (positions, velocities, RCS), in
        field order; the message names the field, the first bad scatterer's
        index and ``actor_index``, its value, and how many entries are bad.

        Raises
        ------
        radarnode.errors.ConfigError
        """
        import dataclasses

        from radarnode.errors import ConfigError

        for f in dataclasses.fields(self):
            if f.name in self.INT_FIELDS:
                continue
            values = np.asarray(getattr(self, f.name), dtype=np.float64)
            bad = ~np.isfinite(values)
            what = "a finite number"
            limit = SCATTERER_LIMITS.get(f.name)
            if not bad.any() and limit is not None:
                # finite but beyond any radar's scene (x = 1e200 m): its square overflowed and the cube came out
                # non-finite without an error (a tester's finding)
                bad = np.abs(values) > limit[0]
                what = f"a number within ±{limit[0]:g} {limit[1]}"
            if bad.any():
                i = int(np.flatnonzero(bad)[0])
                raise ConfigError(
                    f"field '{f.name}' of scatterer {i} (actor_index {int(self.actor_index[i])}): value "
                    f"{float(values[i])!r} is not allowed; expected {what} "
                    f"({int(bad.sum())} of {values.size} entries of {f.name} are not)")


#: the largest magnitude a scatterer's field may have (and its unit): a thousand kilometres, ten kilometres a
#: second, ±300 dBsm — far beyond every scene, well within float64's range for their squares and powers
SCATTERER_LIMITS = {"x_m": (1e6, "m"), "y_m": (1e6, "m"), "z_m": (1e6, "m"), "vx_mps": (1e4, "m/s"),
                    "vy_mps": (1e4, "m/s"), "rcs_dbsm": (300.0, "dBsm")}


def point_targets(range_m, azimuth_deg, range_rate_mps, rcs_dbsm=10.0) -> Scatterers:
    """Point targets given in polar form (for the source documents' test cases)."""
    r = np.atleast_1d(np.asarray(range_m, dtype=np.float64))
    az = np.radians(np.broadcast_to(np.asarray(azimuth_deg, dtype=np.float64), r.shape))
    vr = np.broadcast_to(np.asarray(range_rate_mps, dtype=np.float64), r.shape)
    rcs = np.broadcast_to(np.asarray(rcs_dbsm, dtype=np.float64), r.shape)
    c, s = np.cos(az), np.sin(az)
    return Scatterers(r * c, r * s, np.zeros_like(r), vr * c, vr * s, rcs.copy(), np.arange(r.size))


def actor_scatterers(scene: Scene, view: SensorView, spacing_m: float = 1.0) -> Scatterers:
    """Scatterers on the sensor-facing edges of every actor's box, spaced at most ``spacing_m``.

    The actor's RCS is shared among its points with weights tapering towards
    the ends of each edge (0.3 at the ends, 1 in the middle) and following each
    face's aspect (:func:`~radarnode.radar.object_model.aspect_weight`: its
    projected width as seen from the sensor); small actors are
    one point at their nearest point. Guardrail actors are left to
    :func:`guardrail_scatterers`.
    """
    keep = ~scene.is_guardrail
    idx = np.flatnonzero(keep)
    if idx.size == 0:
        return Scatterers.empty(0)
    cx = view.x_m[idx]
    cy = view.y_m[idx]
    L, W = scene.length_m[idx], scene.width_m[idx]
    small = (L <= POINT_SIZE_M) & (W <= POINT_SIZE_M)
    # the four edges: midpoints, outward normals, lengths, and which face the sensor
    mx, my, wnx, wny, length, facing = facing_edges(view.centre_x_m[idx], view.centre_y_m[idx],
                                                    view.orientation_rad[idx], L, W)
    n_pts = np.where(facing & ~small[:, None], np.maximum(np.ceil(length / spacing_m).astype(np.int64), 1), 0)
    n_pts[small, 0] = 1                                       # small actors: one point
    counts = n_pts.ravel()
    total = int(counts.sum())
    edge = np.repeat(np.arange(counts.size), counts)
    start = np.repeat(np.cumsum(counts) - counts, counts)
    k = np.arange(total) - start
    nk = counts[edge]
    u = (k + 0.5) / nk - 0.5                                   # position along the edge, -0.5..0.5
    a_i, e_i = np.divmod(edge, 4)
    tx, ty = -wny.ravel()[edge], wnx.ravel()[edge]             # edge direction
    px = mx.ravel()[edge] + u * length.ravel()[edge] * tx
    py = my.ravel()[edge] + u * length.ravel()[edge] * ty
    px = np.where(small[a_i], cx[a_i], px)
    py = np.where(small[a_i], cy[a_i], py)
    weight = np.where(small[a_i], 1.0, edge_taper(u) * aspect_weight(px, py, wnx.ravel()[edge], wny.ravel()[edge]))
    wsum = np.bincount(a_i, weights=weight, minlength=idx.size)
    rcs = scene.rcs_dbsm[idx][a_i] + 10.0 * np.log10(weight / wsum[a_i])
    actor = idx[a_i]
    # height above the sensor: an elevated actor's lower edge, 0 for one on the road (SensorView.z_m)
    pz = np.zeros(total) if view.z_m is None else np.asarray(view.z_m, dtype=np.float64)[actor]
    return Scatterers(px, py, pz, view.vx_mps[actor], view.vy_mps[actor], rcs, actor.astype(np.int64))


def guardrail_scatterers(scene: Scene, t_s: float, view: SensorView, max_range_m: float) -> Scatterers:
    """Guardrail posts as stationary point scatterers (their velocity is minus the sensor's)."""
    gx, gy = scene.guardrail_posts(t_s, max_range_m)
    n = gx.size
    rcs = np.full(n, scene.scenario.road.guardrails.rcs_dbsm)
    return Scatterers(gx, gy, np.zeros(n), np.full(n, -view.sensor_vx_mps), np.full(n, -view.sensor_vy_mps), rcs,
                      np.full(n, -1, dtype=np.int64))


def clutter_scatterers(rng: np.random.Generator, preset: RadarPreset, view: SensorView, density_per_m2: float,
                       rcs_dbsm: float) -> Scatterers:
    """Road-surface clutter: stationary points, Poisson in number, uniform over the covered area."""
    if density_per_m2 <= 0:
        return Scatterers.empty(0)
    half = preset.max_half_fov_rad
    area = half * preset.max_range_m ** 2
    n = int(rng.poisson(density_per_m2 * area))
    r = preset.max_range_m * np.sqrt(rng.random(n))
    az = rng.uniform(-half, half, n)
    x, y = r * np.cos(az), r * np.sin(az)
    return Scatterers(x, y, np.zeros(n), np.full(n, -view.sensor_vx_mps), np.full(n, -view.sensor_vy_mps),
                      np.full(n, rcs_dbsm) + rng.normal(0, 3, n), np.full(n, -1, dtype=np.int64))


def visible(preset: RadarPreset, scat: Scatterers, view: SensorView, occluder: np.ndarray,
            max_range_m: float, elevation: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Scatterers inside the field of view and not behind a nearer occluding actor (by azimuth).

    ``elevation`` is (bottom, top, elevated) of every actor (elevation angles in rad, as
    :meth:`radarnode.scene.world.Scene.elevation_extent` gives them): where the scatterer's actor or the
    occluder is off the ground, the scatterer is behind the occluder only within its elevation extent.
    """
    r, az = scat.range_m, scat.azimuth_rad
    ok = in_fov(preset, r, az) & (r <= max_range_m)
    if occluder.any() and len(scat):
        occ = np.flatnonzero(occluder)
        lo, hi, rng_a = view.az_lo_rad[occluder], view.az_hi_rad[occluder], view.range_m[occluder]
        own = scat.actor_index[:, None] == occ[None, :]
        behind = (az[:, None] > lo[None, :]) & (az[:, None] < hi[None, :]) & (r[:, None] > rng_a[None, :] + 0.5)
        if elevation is not None:
            el_lo, el_hi, up = elevation
            el = np.arctan2(scat.z_m, np.maximum(np.hypot(scat.x_m, scat.y_m), 0.1))
            mine = np.where(scat.actor_index >= 0, up[np.maximum(scat.actor_index, 0)], False)
            inside = (el[:, None] >= el_lo[occ][None, :]) & (el[:, None] <= el_hi[occ][None, :])
            behind &= inside | ~(mine[:, None] | up[occ][None, :])
        ok &= ~(behind & ~own).any(axis=1)
    return ok


def scene_scatterers(scene: Scene, t_s: float, view: SensorView, preset: RadarPreset, max_range_m: float,
                     spacing_m: float = 1.0, rng: np.random.Generator | None = None,
                     clutter_density_per_m2: float = 0.0, clutter_rcs_dbsm: float = -20.0,
                     ground_reflection: float = elevation.GROUND_REFLECTION) -> Scatterers:
    """Every visible scatterer of the scene at ``t_s``.

    The scatterers of an actor above the road carry its height (``z_m``, above the sensor) and, in their RCS,
    what the elevation beam and the road's reflection make of it (:func:`radarnode.radar.elevation.propagation_db`
    with ``ground_reflection``; 0 leaves the reflection to the signal level's ``multipath`` impairment).
    """
    # a small actor is one point at its nearest point inside the field of view, where the object level measures it
    # (a body at a sector's edge is seen on its inner side)
    x_in, y_in = nearest_in_fov(preset, view, scene.length_m, scene.width_m)
    inner = dataclasses.replace(view, x_m=x_in, y_m=y_in) if (x_in is not view.x_m) else view
    parts = [actor_scatterers(scene, inner, spacing_m), guardrail_scatterers(scene, t_s, view, max_range_m)]
    if clutter_density_per_m2 > 0 and rng is not None:
        parts.append(clutter_scatterers(rng, preset, view, clutter_density_per_m2, clutter_rcs_dbsm))
    scat = Scatterers.concat(parts)
    occluder = ~scene.is_guardrail & in_fov(preset, view.range_m, view.azimuth_rad)
    up = scene.elevated
    ext = None
    if up.any():
        ext = (*scene.elevation_extent(view), up)
        a = scat.actor_index
        lifted = np.where(a >= 0, up[np.maximum(a, 0)], False)
        if lifted.any():
            gain = elevation.propagation_db(preset, np.hypot(scat.x_m[lifted], scat.y_m[lifted]),
                                            scat.z_m[lifted] + scene.mount_z_m, scene.mount_z_m, ground_reflection)
            scat.rcs_dbsm = scat.rcs_dbsm.copy()
            scat.rcs_dbsm[lifted] += gain
    return scat.take(visible(preset, scat, view, occluder, max_range_m, ext))


__all__ = ["Scatterers", "point_targets", "actor_scatterers", "guardrail_scatterers", "clutter_scatterers",
           "scene_scatterers"]
