"""The consumer ECU's tracker on decoded object or cluster lists.

Stone Soup's composition of single-purpose roles, each a function tested alone:

* :func:`predict` — Kalman prediction with a constant-velocity or constant-acceleration model, plus the
  ego's rotation (the lists are relative to a sensor that turns with the car); or an IMM of the two
  (:func:`imm_mix`, :func:`imm_update`, :func:`imm_combine`, model ``'imm'``);
* :func:`update` — linear Kalman update with [x, y, vx, vy] (objects) or [x, y] (clusters);
* :func:`associate` — Mahalanobis gate and global nearest neighbour (``linear_sum_assignment``);
  object lists carry IDs, which take precedence inside the gate;
* :func:`initiate` — new tentative tracks; :class:`Tracker` confirms with M of N and deletes after
  ``max_coast`` missed cycles.

State per track, relative to the sensor: [x, y, vx, vy, ax, ay] (CA) or [x, y, vx, vy] (CV).
Quality figures: :func:`nees`, :func:`ospa` and :func:`gospa`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from radarnode.errors import ConfigError
from radarnode.perception.motion import road_predict, road_turn, transition

MODELS = ("cv", "ca", "imm")
IMM_SWITCH = 0.05          # probability per cycle of switching between the constant-velocity and -acceleration mode


def imm_models(dt: float, q: float) -> tuple[np.ndarray, np.ndarray]:
    """The IMM's two modes in one 6-state space: constant velocity (acceleration forced to zero, little
    process noise) and constant acceleration. Returns F (2, 6, 6) and Q (2, 6, 6)."""
    f_ca, q_ca = transition("ca", dt, q)
    f_cv4, q_cv4 = transition("cv", dt, 0.1 * q)
    f_cv, q_cv = np.zeros((6, 6)), np.zeros((6, 6))
    f_cv[:4, :4], q_cv[:4, :4] = f_cv4, q_cv4
    q_cv[4:, 4:] = np.eye(2) * 1e-4                   # the acceleration of the CV mode stays at ~0
    return np.stack([f_cv, f_ca]), np.stack([q_cv, q_ca])


def imm_mix(xm: np.ndarray, pm: np.ndarray, mu: np.ndarray, switch: float = IMM_SWITCH):
    """IMM interaction: mixed initial states for each mode. Shapes (n, 2, d), (n, 2, d, d), (n, 2).

    Returns (x0 (n, 2, d), p0 (n, 2, d, d), predicted mode probabilities c (n, 2))."""
    trans = np.array([[1.0 - switch, switch], [switch, 1.0 - switch]])      # trans[i, j]: from i to j
    c = mu @ trans                                                         # (n, 2)
    w = mu[:, :, None] * trans[None, :, :] / np.maximum(c[:, None, :], 1e-300)   # (n, i, j)
    x0 = np.einsum("nij,nid->njd", w, xm)
    dx = xm[:, :, None, :] - x0[:, None, :, :]                             # (n, i, j, d)
    p0 = np.einsum("nij,nijde->njde", w, pm[:, :, None, :, :] + dx[..., :, None] * dx[..., None, :])
    return x0, p0, c


def imm_combine(xm: np.ndarray, pm: np.ndarray, mu: np.ndarray):
    """Moment-matched estimate of the mixture: (x (n, d), p (n, d, d))."""
    x = np.einsum("nj,njd->nd", mu, xm)
    dx = xm - x[:, None, :]
    p = np.einsum("nj,njde->nde", mu, pm + dx[..., :, None] * dx[..., None, :])
    return x, p


def imm_update(xm, pm, c, z, r, h):
    """Update both modes with one measurement each; mode probabilities from their likelihoods."""
    n, modes, d = xm.shape
    xs, ps = update(xm.reshape(n * modes, d), pm.reshape(n * modes, d, d), np.repeat(z, modes, axis=0),
                    np.repeat(r, modes, axis=0), h)
    nu = np.repeat(z, modes, axis=0) - xm.reshape(n * modes, d) @ h.T
    s = h @ pm.reshape(n * modes, d, d) @ h.T + np.repeat(r, modes, axis=0)
    m = h.shape[0]
    quad = np.einsum("ni,nij,nj->n", nu, np.linalg.inv(s), nu)
    like = np.exp(-0.5 * quad) / np.sqrt((2 * np.pi) ** m * np.linalg.det(s))
    mu = c * like.reshape(n, modes)
    mu = mu / np.maximum(mu.sum(axis=1, keepdims=True), 1e-300)
    mu = np.where(np.isfinite(mu).all(axis=1, keepdims=True) & (mu.sum(axis=1, keepdims=True) > 0), mu, c)
    return xs.reshape(n, modes, d), ps.reshape(n, modes, d, d), mu


def _rotation(n: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    rot = np.zeros((n, n))
    for k in range(0, n, 2):
        rot[k:k + 2, k:k + 2] = [[c, -s], [s, c]]
    return rot


def predict(x: np.ndarray, p: np.ndarray, model: str, dt: float, q: float, yaw_rad: float = 0.0,
            road: tuple | None = None):
    """Predict states (n, d) and covariances (n, d, d) by ``dt``; the sensor turned by ``yaw_rad`` meanwhile.

    Without ``road`` every vector of the state turns by −yaw_rad (fixed in the world). With ``road`` = (sensor
    velocity, sensor acceleration), each over ground in the sensor's axes, the objects follow the ego's road
    (:func:`road_turn`)."""
    f, qq = transition(model, dt, q)
    if not yaw_rad:
        return x @ f.T, f @ p @ f.T + qq
    if road is None:
        f = _rotation(f.shape[0], -yaw_rad) @ f
        return x @ f.T, f @ p @ f.T + qq
    return road_predict(x, p, f, qq, yaw_rad, dt, *road)


def measurement_matrix(state_dim: int, kind: str) -> np.ndarray:
    """H for 'objects' ([x, y, vx, vy]) or 'clusters' ([x, y])."""
    m = 4 if kind == "objects" else 2
    h = np.zeros((m, state_dim))
    h[np.arange(m), np.arange(m)] = 1.0
    return h


def update(x, p, z, r, h):
    """Kalman update of states (n, d) with measurements (n, m) and their covariances (n, m, m)."""
    s = h @ p @ h.T + r
    k = p @ h.T @ np.linalg.inv(s)
    x_new = x + np.einsum("nij,nj->ni", k, z - x @ h.T)
    i_kh = np.eye(x.shape[1])[None] - k @ h
    # Joseph form: stays symmetric and positive definite
    p_new = i_kh @ p @ np.transpose(i_kh, (0, 2, 1)) + k @ r @ np.transpose(k, (0, 2, 1))
    return x_new, p_new


def mahalanobis2(x, p, z, r, h) -> np.ndarray:
    """Squared Mahalanobis distances, shape (tracks, measurements)."""
    if len(x) == 0 or len(z) == 0:
        return np.zeros((len(x), len(z)))
    nu = z[None, :, :] - (x @ h.T)[:, None, :]                        # (n, m, dim)
    s = (h @ p @ h.T)[:, None, :, :] + r[None, :, :, :]                 # (n, m, dim, dim)
    return np.einsum("nmi,nmij,nmj->nm", nu, np.linalg.inv(s), nu)


ID_GATE_FACTOR = 25.0      # a measurement with the track's object ID: accepted within 5σ of the wider gate
#: the gate on a cluster's measured radial speed against a track's predicted one (χ², 1 degree, 99.9 %)
RADIAL_GATE = 10.83


def line_of_sight(z: np.ndarray) -> np.ndarray:
    """Unit vectors (m, 2) from the sensor to measured positions (m, 2)."""
    return z / np.maximum(np.hypot(z[:, 0], z[:, 1]), 1e-6)[:, None]


def radial_mismatch2(x: np.ndarray, p: np.ndarray, z: np.ndarray, vr: np.ndarray, vr_var: np.ndarray) -> np.ndarray:
    """Squared normalised differences (tracks, measurements) between each measurement's radial speed ``vr`` (its
    variance ``vr_var``) and each track's velocity (state 2:4) along the measurement's line of sight."""
    if len(x) == 0 or len(z) == 0:
        return np.zeros((len(x), len(z)))
    u = line_of_sight(z)
    pred = x[:, 2:4] @ u.T                                                           # (n, m)
    var = np.einsum("mi,nij,mj->nm", u, p[:, 2:4, 2:4], u) + vr_var[None, :]
    return (vr[None, :] - pred) ** 2 / np.maximum(var, 1e-12)


def radial_update(x: np.ndarray, p: np.ndarray, z: np.ndarray, vr: np.ndarray, vr_var: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Kalman update of states (k, d) with radial speeds (k,) measured at positions z (k, 2): h(x) = u·v with u the
    measured line of sight (linear in the velocity; Joseph form)."""
    k, d = x.shape
    h = np.zeros((k, d))
    h[:, 2:4] = line_of_sight(z)
    ph = np.einsum("kij,kj->ki", p, h)                                                # (k, d)
    s = np.einsum("ki,ki->k", h, ph) + vr_var
    gain = ph / s[:, None]
    x_new = x + gain * (vr - np.einsum("ki,ki->k", h, x))[:, None]
    i_kh = np.eye(d)[None] - gain[:, :, None] * h[:, None, :]
    p_new = i_kh @ p @ np.transpose(i_kh, (0, 2, 1)) + vr_var[:, None, None] * gain[:, :, None] * gain[:, None, :]
    return x_new, p_new


def associate(d2: np.ndarray, gate: float, track_ids: np.ndarray | None = None,
              meas_ids: np.ndarray | None = None) -> list[tuple[int, int]]:
    """Global nearest neighbour inside the gate; equal IDs (object lists) win.

    The radar keeps an object's ID while it tracks it, so a measurement with the track's ID is accepted inside
    a gate ``ID_GATE_FACTOR`` times wider (5σ instead of the χ² 99.9 % point): a lead that brakes hard moves
    away from the constant-velocity prediction by more than its reported σ, and must not be dropped and
    re-created. Beyond that the ID is not trusted (it may have been reused for another object)."""
    if d2.size == 0:
        return []
    cost = np.where(d2 <= gate, d2, np.inf)
    if track_ids is not None and meas_ids is not None:
        same = track_ids[:, None] == meas_ids[None, :]
        cost = np.where(same & (d2 <= ID_GATE_FACTOR * gate), np.minimum(d2, 1e6) - 1e6, cost)
    finite = np.where(np.isfinite(cost), cost, 1e12)
    import scipy.optimize  # imported when first needed: a faster start
    rows, cols = scipy.optimize.linear_sum_assignment(finite)
    return [(int(i), int(j)) for i, j in zip(rows, cols) if np.isfinite(cost[i, j])]


#: σ across the line of sight of a new cluster track whose radial speed is the standing world's (m/s): it starts
#: standing, as the radar's tracker starts such tracks (radarnode.perception.tracker.TANGENTIAL_PRIOR_VAR)
STANDING_PRIOR_SIGMA_MPS = 2.0


def initiate(z: np.ndarray, r: np.ndarray, state_dim: int, kind: str, v_sigma: float = 10.0,
             a_sigma: float = 3.0, radial: tuple[np.ndarray, np.ndarray] | None = None,
             sensor_velocity: tuple[float, float] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """New states from measurements: measured parts as measured, the rest zero with a wide covariance. A cluster's
    measured radial speed (``radial``: speeds and variances) starts the velocity along its line of sight, as a
    radar's tracker starts it; across it stays unknown — unless that speed is the standing world's (the sensor's
    ``sensor_velocity`` over ground seen along the line of sight, within 3σ): then the track starts standing,
    ``STANDING_PRIOR_SIGMA_MPS`` across."""
    n, m = z.shape
    x = np.zeros((n, state_dim))
    x[:, :m] = z
    p = np.zeros((n, state_dim, state_dim))
    p[:, :m, :m] = r
    diag = np.arange(m, state_dim)
    p[:, diag, diag] = np.where(diag < 4, v_sigma ** 2, a_sigma ** 2)
    if radial is not None and m == 2 and n:
        vr, var = radial
        u = line_of_sight(z)
        perp = np.stack([-u[:, 1], u[:, 0]], axis=1)
        x[:, 2:4] = vr[:, None] * u
        across = np.full(n, v_sigma ** 2)
        if sensor_velocity is not None:
            standing = -np.asarray(sensor_velocity, dtype=np.float64)                     # relative velocity
            still = np.abs(vr - u @ standing) <= 3.0 * np.sqrt(var)
            x[still, 2:4] = standing
            across = np.where(still, STANDING_PRIOR_SIGMA_MPS ** 2, across)
        p[:, 2:4, 2:4] = var[:, None, None] * u[:, :, None] * u[:, None, :] \
            + across[:, None, None] * perp[:, :, None] * perp[:, None, :]
    return x, p


def nees(x_est: np.ndarray, p_est: np.ndarray, x_true: np.ndarray) -> np.ndarray:
    """Normalised estimation error squared of each estimate, shape (n,)."""
    e = x_est - x_true
    return np.einsum("ni,nij,nj->n", e, np.linalg.inv(p_est), e)


def nees_bounds(dim: int, runs: int, confidence: float = 0.95) -> tuple[float, float]:
    """Two-sided χ² bounds of the average NEES over ``runs`` Monte Carlo runs."""
    import scipy.stats  # imported when first needed: a faster start
    lo, hi = scipy.stats.chi2.ppf([(1 - confidence) / 2, (1 + confidence) / 2], dim * runs)
    return lo / runs, hi / runs


def ospa(estimates: np.ndarray, truth: np.ndarray, c: float = 10.0, order: float = 2.0) -> float:
    """OSPA distance (Schuhmacher et al., 2008) between two point sets of shape (n, d) and (m, d)."""
    n, m = len(estimates), len(truth)
    if n == 0 and m == 0:
        return 0.0
    if n == 0 or m == 0:
        return c
    d = np.minimum(np.linalg.norm(estimates[:, None, :] - truth[None, :, :], axis=2), c) ** order
    import scipy.optimize  # imported when first needed: a faster start
    rows, cols = scipy.optimize.linear_sum_assignment(d)
    total = d[rows, cols].sum() + c ** order * abs(n - m)
    return float((total / max(n, m)) ** (1.0 / order))


def gospa(estimates: np.ndarray, truth: np.ndarray, c: float = 10.0, order: float = 2.0) -> float:
    """GOSPA distance with α = 2 (Rahmathullah et al., 2017): localisation error of the assigned pairs
    plus c^p/2 for every missed or false track, not normalised by the set size."""
    n, m = len(estimates), len(truth)
    if n == 0 and m == 0:
        return 0.0
    if n == 0 or m == 0:
        return float((c ** order / 2.0 * (n + m)) ** (1.0 / order))
    d = np.linalg.norm(estimates[:, None, :] - truth[None, :, :], axis=2) ** order
    # a pair farther than c is cheaper as one miss plus one false track
    cost = np.minimum(d, c ** order)
    import scipy.optimize  # imported when first needed: a faster start
    rows, cols = scipy.optimize.linear_sum_assignment(cost)
    assigned = d[rows, cols] < c ** order
    total = d[rows, cols][assigned].sum() + c ** order / 2.0 * (n + m - 2 * int(assigned.sum()))
    return float(total ** (1.0 / order))


@dataclass
class Track:
    """One track; ``history`` holds the last N association results for M-of-N confirmation."""

    id: int
    x: np.ndarray
    p: np.ndarray
    meas_id: int = -1
    hits: list[bool] = field(default_factory=list)
    confirmed: bool = False
    misses: int = 0
    age: int = 0
    xm: np.ndarray | None = None          # IMM: per-mode states (2, 6), covariances (2, 6, 6), probabilities (2,)
    pm: np.ndarray | None = None
    mu: np.ndarray | None = None


class Tracker:
    """Tracks from object lists (``kind='objects'``) or cluster lists (``kind='clusters'``).

    Parameters
    ----------
    model : 'cv' or 'ca'
    confirm : (M, N) — confirmed after M hits in the last N cycles
    max_coast : cycles a confirmed track survives without a measurement
    gate : χ² gate on the squared Mahalanobis distance
    """

    def __init__(self, kind: str = "objects", model: str = "ca", q: float = 4.0, confirm: tuple[int, int] = (2, 3),
                 max_coast: int = 3, gate: float | None = None) -> None:
        if kind not in ("objects", "clusters"):
            raise ConfigError(f"tracker kind: value {kind!r} is not allowed; expected 'objects' or 'clusters'")
        if model not in MODELS:
            raise ConfigError(f"tracker model: value {model!r} is not allowed; expected one of {', '.join(MODELS)}")
        self.kind, self.model, self.q = kind, model, q
        self.dim = 6 if model in ("ca", "imm") else 4
        self.h = measurement_matrix(self.dim, kind)
        m = self.h.shape[0]
        import scipy.stats  # imported when first needed: a faster start
        self.gate = gate if gate is not None else float(scipy.stats.chi2.ppf(0.999, m))
        self.confirm = confirm
        self.max_coast = max_coast
        self.tracks: list[Track] = []
        self._next_id = 0
        self.last_t: float | None = None

    def step(self, t_s: float, z: np.ndarray, r: np.ndarray, meas_ids: np.ndarray | None = None,
             yaw_rate_rps: float = 0.0, road: tuple | None = None,
             radial: tuple[np.ndarray, np.ndarray] | None = None) -> list[Track]:
        """One cycle: predict all tracks to ``t_s``, associate the measurements (n, m) with covariances
        (n, m, m), update, initiate, confirm and delete; returns the confirmed tracks. ``road``: the sensor's
        velocity and acceleration over ground (its axes), for the objects to follow the ego's road when it turns
        (:func:`road_turn`); without it they keep their course over ground. ``radial``: clusters' measured radial
        speeds and their variances (n,): they gate the association (:data:`RADIAL_GATE`), update the velocity
        along each line of sight (:func:`radial_update`) and start new tracks' velocity — a position-only tracker
        strung standing clutter into tracks moving with the ego and took a lead's deceleration from its noise."""
        dt = 0.0 if self.last_t is None else max(t_s - self.last_t, 0.0)
        self.last_t = t_s
        imm = self.model == "imm"
        if self.tracks:
            x = np.stack([t.x for t in self.tracks])
            p = np.stack([t.p for t in self.tracks])
            if imm:
                xm, pm, mu = (np.stack([getattr(t, a) for t in self.tracks]) for a in ("xm", "pm", "mu"))
                x0, p0, c = imm_mix(xm, pm, mu)
                if dt > 0:
                    f, qq = imm_models(dt, self.q)
                    if yaw_rate_rps and road is None:
                        rot = _rotation(6, -yaw_rate_rps * dt)
                        f = rot[None] @ f
                    n = x0.shape[0]
                    moved = np.einsum("jde,nje->njd", f, x0)
                    if yaw_rate_rps and road is not None:
                        moved, rot = road_turn(x0.reshape(2 * n, 6), moved.reshape(2 * n, 6), yaw_rate_rps * dt, dt,
                                               *road)
                        fk = rot.reshape(n, 2, 6, 6) @ f[None]
                        moved = moved.reshape(n, 2, 6)
                    else:
                        fk = np.broadcast_to(f[None], (n, 2, 6, 6))
                    x0 = moved
                    p0 = fk @ p0 @ np.swapaxes(fk, -1, -2) + qq[None]
                xm, pm = x0, p0
                x, p = imm_combine(xm, pm, c)
            elif dt > 0:
                x, p = predict(x, p, self.model, dt, self.q, yaw_rate_rps * dt, road)
        else:
            x, p = np.zeros((0, self.dim)), np.zeros((0, self.dim, self.dim))
        ids = np.array([t.meas_id for t in self.tracks]) if meas_ids is not None else None
        d2 = mahalanobis2(x, p, z, r, self.h)
        if radial is not None and not imm:
            dop = radial_mismatch2(x, p, z, *radial)
            d2 = np.where((dop <= RADIAL_GATE) & (d2 <= self.gate), d2 + dop, np.inf)     # both gates hold
        pairs = associate(d2, self.gate + (RADIAL_GATE if radial is not None and not imm else 0.0), ids, meas_ids)
        hit = np.zeros(len(self.tracks), dtype=bool)
        used = np.zeros(len(z), dtype=bool)
        if pairs:
            ti, mi = np.array(pairs).T
            if imm:
                xm[ti], pm[ti], c[ti] = imm_update(xm[ti], pm[ti], c[ti], z[mi], r[mi], self.h)
                x[ti], p[ti] = imm_combine(xm[ti], pm[ti], c[ti])
            else:
                x[ti], p[ti] = update(x[ti], p[ti], z[mi], r[mi], self.h)
                if radial is not None:
                    x[ti], p[ti] = radial_update(x[ti], p[ti], z[mi], radial[0][mi], radial[1][mi])
            hit[ti], used[mi] = True, True
        m_conf, n_conf = self.confirm
        for k, tr in enumerate(self.tracks):
            tr.x, tr.p = x[k], p[k]
            if imm:
                tr.xm, tr.pm, tr.mu = xm[k], pm[k], c[k]
            tr.hits = (tr.hits + [bool(hit[k])])[-n_conf:]
            tr.misses = 0 if hit[k] else tr.misses + 1
            tr.age += 1
            if hit[k] and meas_ids is not None:
                tr.meas_id = int(meas_ids[[j for i, j in pairs if i == k][0]])
            if not tr.confirmed and sum(tr.hits) >= m_conf:
                tr.confirmed = True
        # deletion: confirmed tracks after max_coast misses, tentative ones at their first miss
        self.tracks = [t for t in self.tracks if (t.misses <= self.max_coast if t.confirmed else t.misses == 0)]
        new = np.flatnonzero(~used)
        if new.size:
            nx, npc = initiate(z[new], r[new], self.dim, self.kind,
                               radial=None if radial is None or imm else (radial[0][new], radial[1][new]),
                               sensor_velocity=None if road is None else road[0])
            for k, j in enumerate(new):
                tr = Track(self._next_id, nx[k], npc[k], int(meas_ids[j]) if meas_ids is not None else -1,
                           [True], m_conf <= 1)
                if imm:
                    tr.xm, tr.pm, tr.mu = np.stack([nx[k], nx[k]]), np.stack([npc[k], npc[k]]), np.array([0.5, 0.5])
                self.tracks.append(tr)
                self._next_id += 1
        return [t for t in self.tracks if t.confirmed]
