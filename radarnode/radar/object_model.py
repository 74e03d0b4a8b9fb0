"""Fidelity level 1: the statistical object-level radar model (DESIGN.md section 5.1).

Per cycle and per actor, vectorised over actors:

1. field of view (the preset's sectors), minimum/maximum range and the
   configured MaxDistance;
2. occlusion: the fraction of an actor's azimuth extent not hidden behind
   nearer actors; below ``MIN_VISIBLE_FRACTION`` it is not seen, above it its
   RCS is scaled by the visible fraction;
3. SNR from the radar equation, detection with the Swerling 1 probability;
4. measurement noise in range, radial speed and azimuth with σ from the
   Cramér–Rao bound at that SNR, floored by the preset;
5. an internal tracker the way a production radar has one: an object is
   confirmed after 2 detections in 3 cycles, its velocity is smoothed with an
   alpha filter (gain ``VELOCITY_GAIN``), coasts (MeasState "predicted")
   through up to ``COAST_CYCLES`` misses, keeps its ID while it lives, and the
   lowest free ID is given to a new object;
6. ARS 408 DynProp from the ego-motion-compensated velocity, class, size,
   orientation, ProbOfExist and the σ fields.

The cluster list holds this cycle's detections (actors and guardrail posts)
plus Poisson false alarms at the preset's false-alarm rate.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from radarnode.perception.types import (
    AMBIG_AMBIGUOUS, AMBIG_UNAMBIGUOUS, DYN_CROSSING_MOVING, DYN_MOVING, DYN_ONCOMING, DYN_STATIONARY, DYN_STOPPED,
    MEAS_MEASURED, MEAS_NEW,
    MEAS_PREDICTED, ClusterList, ObjectList, RadarFrame)
from radarnode.dsp.detection_stats import normal_cdf
from radarnode.dsp.spectra import circular as _circular
from radarnode.errors import ConfigError
from radarnode.perception.types import Detections
from radarnode.perception.tracker import (ALIAS_GATE_M, COAST_STATIONARY_CYCLES, MIN_BODY_M, RANGE_WALK_MIN_HITS,
                                          RCS_GAIN, accel_sigma_mps2, classify, cluster_dyn_prop, follows_one_wrap,
                                          orientation_sigma_rad)
from radarnode.radar import ambiguity, elevation, equation
from radarnode.radar.chain import DspChain
from radarnode.radar.calibration import RESOLUTION, chain_efficiency, false_alarms_per_pfa_cell
from radarnode.radar.options import SignalOptions
from radarnode.radar.presets import RadarPreset
from radarnode.scene.world import POINT_SIZE_M, Scene, SensorView

MIN_VISIBLE_FRACTION = 0.25
FOV_EDGE_TOLERANCE = 1e-9   # rad and m: a field-of-view edge computed to the last bit is inside (in_fov)
COAST_CYCLES = 3
CONFIRM_HITS = 2          # detections in the last CONFIRM_WINDOW cycles that make an object
CONFIRM_WINDOW = 3
MAX_OBJECTS = 100         # ARS 408 object list capacity
MAX_CLUSTERS = 250        # ARS 408 cluster list capacity (near + far counts are 8 bits each)
#: cycles whose cluster lists are built together (the same lists whatever the size, tests/test_batched_log.py): the
#: 300-s highway_cut_in log in 1.53 s at 64 and at 128, 1.63 s at 32 (medians of 7 alternated, 2026-11-30); at 64 a
#: block of a guardrail road costs about 5 ms once every 64 cycles, well within a real-time cycle
CLUSTER_BLOCK = 64
MOVING_THRESHOLD_MPS = 1.0   # over-ground speed above which an object counts as moving
VELOCITY_GAIN = 0.3          # the internal tracker's velocity smoothing (alpha filter gain)
OCCLUSION_SAMPLES = 16
#: points on each sensor-facing edge of a body, for what it puts into a neighbour's CA-CFAR ring where its outline
#: spans Doppler bins (:meth:`ObjectModel._outline_interference`) …
OUTLINE_SAMPLES = 16
#: … blended in from the first to the second of these Doppler bins spanned (below: the whole body at its nearest point)
OUTLINE_SPAN_BINS = (0.5, 1.5)
#: equally likely draws of a Swerling 1 neighbour's power over which a masking factor is averaged
FLUCTUATION_POINTS = 16
#: the fluctuating neighbours' draws, equally likely, among which a masked detection's reading takes the one it was
#: made with (:meth:`ObjectModel._masked_loss`): finer than the Pd's FLUCTUATION_POINTS, since the detections of a
#: point beside a strong one come from the lowest draws (the least of 16 is 0.03 of the mean). Measured on the test's
#: scene (tests/test_object_model.py): 16, 32, 64 and 256 draws read within 0.15 dB of each other; 32 cost a
#: highway_cut_in chunk 2 ms, 64 6 ms
READING_DRAWS = 32
READING_DRAWS_X = -np.log1p(-(np.arange(READING_DRAWS) + 0.5) / READING_DRAWS)
READING_DRAWS_X /= READING_DRAWS_X.mean()
CHUNK_CYCLES = 1024       # at most this many cycles' physics in one vectorised pass (fewer for crowded scenes) …
FIRST_CHUNK_CYCLES = 128  # … the first chunk after a restart (a configuration change, a step off sequence), …
CHUNK_GROWTH = 4          # … each next one this many times the last
CHUNK_OCCLUSION_CELLS = 16_000_000   # bound on the (cycles, actors, samples, actors) occlusion test
CHUNK_ACTOR_CYCLES = 4096   # bound on cycles × actors of a chunk: about 20 ms to compute (a real-time node's cycle)
DRAW_BLOCK = 64           # cycles whose random numbers are drawn together (fixed, for reproducibility)
KEEP_DRAW_STATES = 4096   # blocks whose starting random state is kept (a step back that far: about 5 h at 72 ms)
_NO_CLUSTERS = ClusterList.empty(0)   # shared by every cycle that sends objects: never modified
_POPCOUNT = np.array([bin(i).count("1") for i in range(256)], dtype=np.int64)
_POPCOUNT_LOW3 = np.array([bin(i & ((1 << 3) - 1)).count("1") for i in range(256)], dtype=np.int64)
_POPCOUNT_LOW5 = np.array([bin(i & ((1 << 5) - 1)).count("1") for i in range(256)], dtype=np.int64)
_PROB_EDGES = np.array([0.25, 0.5, 0.75, 0.9, 0.99, 0.999])
#: the object list's fields of a chunk after position and velocity, gathered in row tables (ObjectModel._track)
#: so that a cycle takes its objects with one slice per table (ObjectList field, chunk key)
_OBJECT_FLOATS = (("rcs_dbsm", "rcs_obj"), ("dist_long_sigma_m", "sig_long"), ("dist_lat_sigma_m", "sig_lat"),
                  ("vrel_long_sigma_mps", "sig_vlong"), ("vrel_lat_sigma_mps", "sig_vlat"),
                  ("arel_long_sigma_mps2", "sig_along"), ("arel_lat_sigma_mps2", "sig_alat"),
                  ("orientation_sigma_rad", "sig_orient"), ("arel_long_mps2", "arel_long"),
                  ("arel_lat_mps2", "arel_lat"), ("orientation_rad", "orientation"), ("length_m", "length"),
                  ("width_m", "width"))
_OBJECT_INTS = (("meas_state", "meas_state"), ("prob_of_exist", "prob_of_exist"), ("obj_class", "obj_class"))
# the float and integer rows of an empty object list (obj_f: x, y, vx, vy and the floats above; obj_i: ID, DynProp, the
# integers above and the actor), shared by every cycle without objects (empty: nothing to modify)
_NO_OBJECT_ROWS = (tuple(np.zeros(0) for _ in range(4 + len(_OBJECT_FLOATS))),
                   tuple(np.zeros(0, dtype=np.int64) for _ in range(3 + len(_OBJECT_INTS))))


def _object_list(f, g) -> ObjectList:
    """The object list of float rows ``f`` and integer rows ``g`` (obj_f's and obj_i's order, above)."""
    return ObjectList.of(g[0], f[0], f[1], f[2], f[3], g[1], *f[4:12], g[2], g[3], f[12], f[13], g[4], f[14], f[15],
                         f[16], g[5])


#: the empty object list of _NO_OBJECT_ROWS, its fields by name (a cycle without objects takes a copy: a new list, the
#: same arrays)
_NO_OBJECT_FIELDS = dict(_object_list(*_NO_OBJECT_ROWS).__dict__)
#: the detections' fields (Detections' order after the actor index: range, range rate, azimuth, RCS, SNR; the RCS and
#: SNR as the chain reads them, :meth:`ObjectModel._physics`)
_DETECTION_FLOATS = ("m_r", "m_vr", "m_az", "rcs_read", "snr_read")


@dataclass
class StepInfo:
    """What the last step did (for the benchmarks and ``radarnode image``)."""

    level: str = ""
    scatterers: object = None
    detections: Detections | None = None
    cube: np.ndarray | None = None
    seconds: dict = field(default_factory=dict)
    #: signal level with ``keep_rd`` set: the non-coherent range–Doppler power of the cycle's first chirp sequence,
    #: shape (doppler, range), Doppler fftshifted (bin M/2 is zero speed), range bins of ``range_resolution_m``
    rd_power: np.ndarray | None = None


def outline_share(span_bins: np.ndarray) -> np.ndarray:
    """The share of a body's energy that :meth:`ObjectModel._masking` spreads over its outline (the rest at its nearest
    point), from how many Doppler bins the outline spans: 0 up to the first of ``OUTLINE_SPAN_BINS``, 1 from the
    second, linear between (no step in the interference where a body comes near)."""
    lo, hi = OUTLINE_SPAN_BINS
    return np.clip((np.asarray(span_bins, dtype=np.float64) - lo) / (hi - lo), 0.0, 1.0)


def _expand(values, rows: np.ndarray, t_n: int):
    """An array computed at the cycles ``rows`` (axis 0) as one of all ``t_n`` cycles, zeros (False) elsewhere."""
    if not isinstance(values, np.ndarray) or values.ndim == 0:
        return values
    out = np.zeros((t_n,) + values.shape[1:], dtype=values.dtype)
    out[rows] = values
    return out


def _dyn_codes(gx: np.ndarray, gy: np.ndarray, speed: np.ndarray, moving: np.ndarray, ever: np.ndarray
               ) -> np.ndarray:
    """ARS 408 DynProp from the ground velocity (sensor axes) and whether the object was ever seen moving: the
    heading against the sensor's x axis, > 135° oncoming, 45°–135° crossing; standing: stopped or stationary."""
    cos45 = 0.7071067811865476
    dyn = np.where(gx < -cos45 * speed, DYN_ONCOMING, np.where(gx < cos45 * speed, DYN_CROSSING_MOVING, DYN_MOVING))
    return np.where(moving, dyn, np.where(ever, DYN_STOPPED, DYN_STATIONARY))


class ObjectStepInfo:
    """:class:`StepInfo` of the object level: the last step's detections, built from its chunk when asked for."""

    level = "object"
    scatterers = None
    cube = None
    rd_power = None

    def __init__(self) -> None:
        self.seconds: dict = {}
        self._at: tuple | None = None

    def at(self, ch: dict, i: int, reportable: np.ndarray) -> None:
        self._at = (ch, i, reportable)

    @property
    def detections(self) -> Detections | None:
        if self._at is None:
            return None
        ch, i, reportable = self._at
        seen = np.flatnonzero(ch["seen"][i] & reportable)
        d = ch["detection_floats"][i, seen]
        return Detections(d[:, 0], d[:, 1], d[:, 2], d[:, 3], d[:, 4], seen, ch["ambig"][i, seen])


@dataclass(frozen=True)
class RuntimeConfig:
    """The part of the sensor configuration that RadarConfiguration (0x200) can change."""

    max_distance_m: float
    power_reduction_db: float = 0.0
    high_sensitivity: bool = False
    clusters: bool = True       # the object level builds its cluster list only when it is sent

    def __post_init__(self) -> None:
        # (a NaN distance emptied the object level's lists silently and failed deep in numpy at the detection level;
        # a negative one emptied every level's)
        for name, ok, allowed in (
                ("max_distance_m", _real(self.max_distance_m) and self.max_distance_m > 0.0, "a finite distance > 0 m"),
                ("power_reduction_db", _real(self.power_reduction_db) and self.power_reduction_db >= 0.0,
                 "a finite reduction >= 0 dB"),
                ("high_sensitivity", isinstance(self.high_sensitivity, (bool, np.bool_)), "true or false"),
                ("clusters", isinstance(self.clusters, (bool, np.bool_)), "true or false")):
            if not ok:
                raise ConfigError(f"RuntimeConfig.{name}: value {getattr(self, name)!r} is not allowed; expected "
                                  f"{allowed}")


def _real(x) -> bool:
    """A finite real number (not a bool)."""
    if type(x) is float:                  # (a step's time and ego motion: four a cycle)
        return math.isfinite(x)
    return isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, (bool, np.bool_)) \
        and math.isfinite(x)


#: a model step's time lies within ±this, seconds (about 116 days; the command line runs at most 86,400 s): the
#: object level draws every cycle's random numbers up to the one it steps to (a first step at 10⁶ s: about 4 s), so
#: a time of 10¹² s would have run for weeks where it is refused now
MAX_STEP_TIME_S = 1e7


def check_step(t_s, sensor_velocity_est) -> None:
    """A model step's inputs: a finite time within ±MAX_STEP_TIME_S, and an ego-motion estimate of 2 or 3 finite
    numbers (vx, vy[, yaw rate]) or None. A NaN time failed deep in numpy ("cannot convert float NaN to integer"); a
    NaN or infinite velocity gave a frame."""
    if not _real(t_s) or abs(t_s) > MAX_STEP_TIME_S:
        raise ConfigError(f"t_s: value {t_s!r} is not allowed; expected a finite time in seconds within "
                          f"±{MAX_STEP_TIME_S:g} (about {MAX_STEP_TIME_S / 86400.0:.0f} days)")
    if sensor_velocity_est is not None and not (
            isinstance(sensor_velocity_est, (tuple, list, np.ndarray)) and len(sensor_velocity_est) in (2, 3)
            and all(map(_real, sensor_velocity_est))):
        raise ConfigError(f"sensor_velocity_est: value {sensor_velocity_est!r} is not allowed; expected None or "
                          "(vx, vy) or (vx, vy, yaw rate), finite numbers (m/s, rad/s)")


#: the columns of a cluster list's rows before it is sorted: position, velocity, RCS, σ of range, azimuth and range
#: rate, the actor's index (−1: a guardrail post or a false alarm), AmbigState
_CL_X, _CL_Y, _CL_VX, _CL_VY, _CL_RCS, _CL_SIG_R, _CL_SIG_AZ, _CL_SIG_V, _CL_ACTOR, _CL_AMBIG = range(10)


def _cluster_rows(*columns) -> np.ndarray:
    """Rows of the ``_CL_*`` columns from arrays of one shape (…, m) and scalars: shape (…, m, 10), float64 (the
    actor index and AmbigState are small integers, exact in it)."""
    out = np.empty(np.broadcast(*columns).shape + (len(columns),))
    for k, c in enumerate(columns):
        out[..., k] = c
    return out


def resolved_posts(p: RadarPreset, g: dict, u_hit: np.ndarray, idx: np.ndarray | None, svx: np.ndarray, svy: np.ndarray,
                   response=None) -> np.ndarray:
    """Which of the detected guardrail posts ``idx`` (rows of the chunk's post table ``g``; None: all of them, in
    order) the chain would report
    as peaks of their own: those that no stronger detected post of the same cycle lies within the chain's measured
    resolution of (:data:`radarnode.radar.calibration.RESOLUTION`: range bins, Doppler bins and beamwidths apart,
    the detection level's rule). Posts 2 m apart are 1.1 of ars408_like's range bins: drawn each on its own, the
    object level listed 2.7–3.8× the chain's clusters on a guardrail road (84 a frame against 31 with one
    guardrail; `benchmarks/calibration.py --only posts`). A post's power is read from the uniform that decided its
    detection (given the detection, u/Pd is uniform and −ln(u/Pd) an Exp(1) factor of its mean power, a Swerling 1
    post's): no new draw, so every random stream stays as it was.

    With ``response`` (the chain's window response, :meth:`DetectionStatistic.response`), a post that stays is also
    dropped where another one's range–Doppler lobe hides it (:func:`lobe_hidden`): the chain keeps a cell only where
    its map is a local maximum, so a weaker post 1.7–3 bins from a stronger one is lost when the stronger one's lobe
    rises over it (the detection level's rule; without it the object level listed 1.9× the chain's clusters with
    posts 3.1 m apart, 1.7 of ars408_like's bins). Shape (idx.size,), bool."""
    n = u_hit.size if idx is None else idx.size
    keep = np.ones(n, dtype=bool)
    if n < 2:
        return keep
    col = (lambda a: a) if idx is None else (lambda a: a.take(idx))
    cycle = col(g["cycle"])
    power = 10.0 ** (col(g["snr"]) / 10.0) * -np.log(np.maximum(col(u_hit) / col(g["pd"]), 1e-300))
    rb = col(g["range"]) / p.range_resolution_m
    vb = -(svx.take(cycle) * col(g["cos"]) + svy.take(cycle) * col(g["sin"])) / p.doppler_bin_mps
    ub = p.element_spacing_wl * np.sin(col(g["azimuth"])) * p.num_virtual
    # by cycle, then range: one key (numpy's lexsort((rb, cycle)), the cycle's step beyond any range), sorted stably
    # (a cycle's posts come as two runs by range, the left edge's and the right edge's, which a merge sort takes fast)
    key = cycle * (2.0 * (rb.max() + RESOLUTION[0]) + 1.0) + rb
    order = np.argsort(key, kind="stable")
    cycle, rb, vb, ub, power, key = (a.take(order) for a in (cycle, rb, vb, ub, power, key))
    # how far along that order a post's range box reaches (the same cycle, within RESOLUTION[0] bins): every pair
    # within it is compared, one offset at a time (a handful of offsets: posts 0.5 m apart at the closest)
    reach = _reach(key, RESOLUTION[0])
    kept = np.ones(n, dtype=bool)
    for d in range(1, reach + 1):
        a, b = slice(d, None), slice(None, -d)                # a: the later post of each pair, b: the earlier
        near = ((cycle[a] == cycle[b]) & (rb[a] - rb[b] <= RESOLUTION[0]) & (np.abs(vb[a] - vb[b]) <= RESOLUTION[1])
                & (np.abs(ub[a] - ub[b]) <= RESOLUTION[2]))
        kept[a] &= ~(near & (power[b] > power[a]))
        kept[b] &= ~(near & (power[a] > power[b]))
    if response is not None:
        at = np.flatnonzero(kept)
        kept[at[_hidden_peaks(cycle.take(at), rb.take(at), vb.take(at), power.take(at), key.take(at), p.num_chirps,
                              response)]] = False
    keep[order] = kept
    return keep


def _reach(key: np.ndarray, bins: float) -> int:
    """How many places along the sorted ``key`` (cycle, then range bins) the farthest pair within ``bins`` range bins
    of each other lies apart (0: no two posts that close): the largest d with key[i + d] ≤ key[i] + bins for some i.
    The keys within a post's box follow it without a gap (sorted), so the offsets are tried one by one until none
    holds a pair — a few cheap passes, where a binary search of every key (the count of each box, the same number)
    was some 0.7 M instructions a call over a block's 10,000 posts."""
    ahead = key + bins
    d = 0
    while d + 1 < key.size and (key[d + 1:] <= ahead[:-(d + 1)]).any():
        d += 1
    return d


#: how far apart (range and Doppler bins) a post's lobe can hide another's peak (:func:`lobe_hidden`): Hann's main
#: lobe reaches 2 bins, the hidden post's own cell ±½ and its neighbour one more; beyond, the first sidelobe is
#: 31 dB down
POST_LOBE_REACH_BINS = 3.5


def _hidden_peaks(cycle: np.ndarray, rb: np.ndarray, vb: np.ndarray, power: np.ndarray, key: np.ndarray, m: int,
                  response) -> np.ndarray:
    """Which of the peaks (sorted by ``key``: cycle, then range bins ``rb``) a stronger peak of the same cycle within
    :data:`POST_LOBE_REACH_BINS` hides (:func:`lobe_hidden`), shape (n,), bool."""
    n = rb.size
    hidden = np.zeros(n, dtype=bool)
    if n < 2:
        return hidden
    reach = _reach(key, POST_LOBE_REACH_BINS)
    ia, ib = [], []
    for d in range(1, reach + 1):
        a, b = slice(d, None), slice(None, -d)
        near = ((cycle[a] == cycle[b]) & (rb[a] - rb[b] <= POST_LOBE_REACH_BINS)
                & (np.abs(_circular(vb[a] - vb[b], m)) <= POST_LOBE_REACH_BINS))
        later = np.flatnonzero(near) + d
        ia.append(later)
        ib.append(later - d)
    if not ia:
        return hidden
    a, b = np.concatenate(ia), np.concatenate(ib)
    # the weaker of each pair is tested against the stronger (a stronger peak that straddles two cells is not lost
    # to a weaker one's lobe: it is seen one cell over)
    weaker = power.take(a) < power.take(b)
    i, j = np.where(weaker, a, b), np.where(weaker, b, a)
    if i.size:
        hidden[i[lobe_hidden(rb.take(i), vb.take(i), power.take(i), rb.take(j), vb.take(j), power.take(j), m,
                             response)]] = True
    return hidden


def lobe_hidden(r: np.ndarray, v: np.ndarray, power: np.ndarray, r_o: np.ndarray, v_o: np.ndarray,
                power_o: np.ndarray, m: int, response) -> np.ndarray:
    """Whether a peak at (r, v) (range and Doppler bins, on-bin power ``power``) is lost to another at (r_o, v_o):
    the noise-free map, which the chain sums over its channels (so at any angle), at the peak's cell and its
    neighbours towards the other, from both returns through the windows' response (``response(axis, δ)``, signed
    amplitude); lost where a neighbour towards which the other's lobe rises stands higher than the peak's own cell.
    The detection level's test (:func:`radarnode.radar.detection_model._inside_lobes`) for one other return and
    without the cross-term (the object level has no phases: its mean is zero); of the eight neighbours only the
    three towards the other (one range step, one Doppler step, both) can be ones its lobe rises to, in the main lobe,
    where the response falls with the distance. Doppler circular over ``m`` bins. Shape (n,), bool."""
    cr, cd = np.rint(r), np.rint(v)
    o_r, o_d = r_o - cr, _circular(v_o - cd, m)          # the other, from the peak's cell
    s_r, s_d = np.sign(o_r), np.sign(o_d)                # the steps towards it
    # rows: the peak at its cell and one step on, the other at the same two
    a_r = response("r", _lobe_offsets(r, cr, o_r, s_r))
    a_d = response("d", _lobe_offsets(v, cd, o_d, s_d))
    own = (a_r[:2, None, :] * a_d[None, :2, :]) ** 2 * power          # (range step, Doppler step, n)
    oth = (a_r[2:, None, :] * a_d[None, 2:, :]) ** 2 * power_o
    total = own + oth
    rising = oth > oth[0, 0]
    rising[0, 0] = False
    return np.any(rising & (total > total[0, 0]), axis=(0, 1))


def _lobe_offsets(x: np.ndarray, cell: np.ndarray, other: np.ndarray, step: np.ndarray) -> np.ndarray:
    """:func:`lobe_hidden`'s four offsets along one axis, rows of one array (4, n): the peak from its cell and from
    the cell one ``step`` on, the other (``other`` from the cell) likewise — cell − x, step + cell − x, −other,
    step − other, each the same expression as written out (no stack of four temporaries)."""
    out = np.empty((4,) + np.shape(x), dtype=np.result_type(x, cell, other, step))
    np.subtract(cell, x, out=out[0])
    np.add(step, cell, out=out[1])
    out[1] -= x
    np.negative(other, out=out[2])
    np.subtract(step, other, out=out[3])
    return out


def in_fov(preset: RadarPreset, range_m: np.ndarray, azimuth_rad: np.ndarray) -> np.ndarray:
    """True where (range, azimuth) lies inside any of the preset's sectors and above the minimum range.

    The edges belong to the sectors within ``FOV_EDGE_TOLERANCE`` (1e-9 rad and m): a point that
    :func:`nearest_in_fov` puts on an edge is inside, whatever the last bit of its rounding."""
    inside = np.zeros(np.shape(range_m), dtype=bool)
    abs_az = np.abs(azimuth_rad)
    tol = FOV_EDGE_TOLERANCE
    for sector in preset.fov:
        inside |= (range_m <= sector.max_range_m + tol) & (abs_az <= math.radians(sector.half_angle_deg) + tol)
    return inside & (range_m >= preset.min_range_m - tol)


def facing_edges(centre_x: np.ndarray, centre_y: np.ndarray, heading_rad: np.ndarray, length_m: np.ndarray,
                 width_m: np.ndarray) -> tuple[np.ndarray, ...]:
    """The four edges (front, rear, left, right) of boxes centred at (``centre_x``, ``centre_y``), sensor frame,
    heading ``heading_rad``: their midpoints (x, y), outward normals (x, y), lengths, and whether each faces the sensor
    at the origin (its outward normal points at it); each shape (n, 4)."""
    L, W = length_m, width_m
    ch, sh = np.cos(heading_rad), np.sin(heading_rad)
    zero = np.zeros_like(L)
    ex, ey = np.stack([L / 2, -L / 2, zero, zero], axis=1), np.stack([zero, zero, W / 2, -W / 2], axis=1)
    nx = np.broadcast_to(np.array([1.0, -1.0, 0.0, 0.0]), ex.shape)
    ny = np.broadcast_to(np.array([0.0, 0.0, 1.0, -1.0]), ex.shape)
    mx = centre_x[:, None] + ch[:, None] * ex - sh[:, None] * ey
    my = centre_y[:, None] + sh[:, None] * ex + ch[:, None] * ey
    wnx, wny = ch[:, None] * nx - sh[:, None] * ny, sh[:, None] * nx + ch[:, None] * ny
    return mx, my, wnx, wny, np.stack([W, W, L, L], axis=1), (wnx * -mx + wny * -my) > 0


def edge_taper(u: np.ndarray) -> np.ndarray:
    """The weight of a point ``u`` along an edge (−½ … ½) in the share of a body's RCS: 0.3 at the ends, 1 in the
    middle."""
    return 0.3 + 0.7 * np.cos(np.pi * u)


#: The share of a face seen edge-on (grazing incidence) against one seen face-on: wheels, mirrors and seams still
#: reflect when the panel does not.
ASPECT_FLOOR = 0.1


def aspect_weight(px: np.ndarray, py: np.ndarray, nx: np.ndarray, ny: np.ndarray) -> np.ndarray:
    """The weight of an outline point at (``px``, ``py``) (sensor frame; the sensor at the origin) on a face of
    outward normal (``nx``, ``ny``) in the share of a body's RCS: the cosine of the incidence angle, floored at
    :data:`ASPECT_FLOOR`. Points lie along an edge at a fixed spacing, so the cosine makes a face's share its length
    as seen from the sensor (its projected width), as a rough body's is; without it a car a few degrees off the
    axis put about 70 % of its power on its side at grazing incidence, and the detection level reported it 0.6 m
    beyond its nearest point by the median (``benchmarks/object_sigma.py``)."""
    r = np.maximum(np.hypot(px, py), 1e-9)
    cos_inc = -(px * nx + py * ny) / r
    return ASPECT_FLOOR + (1.0 - ASPECT_FLOOR) * np.clip(cos_inc, 0.0, 1.0)


def nearest_in_fov(preset: RadarPreset, view: SensorView, length_m: np.ndarray, width_m: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The point of each actor's box nearest to the sensor *within the field of view*, sensor frame (x, y).

    ``view.x_m``/``view.y_m`` is the box's nearest point anywhere. A wide body the beam crosses — a bridge deck on a
    bend, a car half in the beam — has it outside the field of view while part of the body is inside: the radar
    sees that part, and its nearest point is what it reports (the detection and signal levels, which sample the
    outline, see the same). Where the nearest point is inside a sector already, or no part of the box is, the
    nearest point is returned unchanged. Each box edge is clipped to each sector's wedge (two half-planes,
    Liang–Barsky) and the point of the clipped edge nearest to the sensor taken; the minimum over edges and
    sectors within the sector's range. Shapes like ``view.x_m``; sectors of half-angle ≥ 90° are not clipped
    (none of the presets has one).
    """
    x, y = view.x_m, view.y_m
    r_xy = np.hypot(x, y)
    z = np.zeros_like(x) if view.z_m is None else view.z_m
    inside = in_fov(preset, np.sqrt(r_xy * r_xy + z * z), np.arctan2(y, x))
    sectors = [s for s in preset.fov if s.half_angle_deg < 90.0]
    if inside.all() or not sectors:
        return x, y
    # only the boxes whose nearest point is outside while part of them may be inside: computed on those, put back
    out = ~inside & may_be_in_fov(preset, view, length_m, width_m)
    if not out.any():
        return x, y
    bx, by = _nearest_on_sectors(preset, sectors, x[out], y[out], z[out], view.centre_x_m[out],
                                 view.centre_y_m[out], view.orientation_rad[out],
                                 np.broadcast_to(length_m, x.shape)[out], np.broadcast_to(width_m, x.shape)[out])
    x_out, y_out = x.copy(), y.copy()
    x_out[out], y_out[out] = bx, by
    return x_out, y_out


#: the first two edges of a stable sort of the four that puts the facing ones first, for each pattern of which face
#: (bit k: edge k faces), and the bits' weights
_FACING_PAIRS = np.array([np.argsort([not (b >> k) & 1 for k in range(4)], kind="stable")[:2] for b in range(16)],
                         dtype=np.intp)
_EDGE_BITS = np.array([1, 2, 4, 8], dtype=np.intp)


def outline_points(centre_x: np.ndarray, centre_y: np.ndarray, heading_rad: np.ndarray, length_m: np.ndarray,
                   width_m: np.ndarray) -> tuple[np.ndarray, ...]:
    """``OUTLINE_SAMPLES`` points on each of the (at most two) edges of each box (n,) that face the sensor, as the
    scatterer levels share a body's RCS among its outline (:func:`radarnode.radar.scatterers.actor_scatterers`):
    their (x, y), each (n, 2, S), and each point's share of the body's RCS before range and antenna gain (tapered
    towards an edge's ends, as many points as metres, each weighted by its face's aspect; summing to 1 over a box,
    0 on an edge that does not face)."""
    mx, my, wnx, wny, length, facing = facing_edges(centre_x, centre_y, heading_rad, length_m, width_m)
    # a box faces a point outside it with one or two edges: those two (a second that does not face gets no weight),
    # by the pattern of the four edges' facing (the first two of a stable sort that puts the facing edges first)
    two = _FACING_PAIRS[facing @ _EDGE_BITS] + (4 * np.arange(facing.shape[0]))[:, None]      # flat indices (n, 2)
    mx, my, wnx, wny, length, facing = (a.reshape(-1).take(two) for a in (mx, my, wnx, wny, length, facing))
    u = (np.arange(OUTLINE_SAMPLES) + 0.5) / OUTLINE_SAMPLES - 0.5                          # (S,)
    px = mx[:, :, None] - wny[:, :, None] * (u * length[:, :, None])                          # (n, 2, S)
    py = my[:, :, None] + wnx[:, :, None] * (u * length[:, :, None])
    weight = np.where(facing[:, :, None], edge_taper(u) * length[:, :, None]
                      * aspect_weight(px, py, wnx[:, :, None], wny[:, :, None]), 0.0)
    return px, py, weight / np.maximum(weight.sum(axis=(1, 2), keepdims=True), 1e-300)


def visible_outline(preset: RadarPreset, view: SensorView, t_i: np.ndarray, j_i: np.ndarray, length_m: np.ndarray,
                    width_m: np.ndarray, max_distance_m: float) -> tuple[np.ndarray, ...]:
    """The :func:`outline_points` of the bodies ``view[t_i, j_i]`` (actor j_i's ``length_m``, ``width_m``), with each
    point's slant range and azimuth from the sensor and whether it reflects: on a facing edge, inside the field of
    view, within ``max_distance_m``. Returns (x, y, range, azimuth, share, reflects), each (R, 2, S); the azimuth only
    of the points on a facing edge (0 elsewhere: they never reflect, and an arctangent a point is the costliest step
    here)."""
    px, py, share = outline_points(view.centre_x_m[t_i, j_i], view.centre_y_m[t_i, j_i],
                                   view.orientation_rad[t_i, j_i], length_m[j_i], width_m[j_i])
    z = 0.0 if view.z_m is None else np.asarray(view.z_m, dtype=np.float64)[t_i, j_i][:, None, None]
    r_s = np.sqrt(px ** 2 + py ** 2 + z ** 2)
    facing = share > 0.0
    az_s = np.zeros(px.shape)
    np.arctan2(py, px, out=az_s, where=facing)
    return px, py, r_s, az_s, share, facing & in_fov(preset, r_s, az_s) & (r_s <= max_distance_m)


class SharedOutline:
    """:func:`visible_outline` of the bodies ``rows`` (shape like ``view.x_m``) selects, computed once, on first use,
    for every caller that needs a subset of them: a chunk's masking (:meth:`ObjectModel._outline_interference`) and
    its centroid across (:func:`visible_centre_y`) took the outline of mostly the same bodies twice. Each body's
    points are computed on their own (element by element, the sums per body), so a subset read from here holds the
    same numbers as the subset computed alone."""

    def __init__(self, preset: RadarPreset, view: SensorView, length_m: np.ndarray, width_m: np.ndarray,
                 rows: np.ndarray, max_distance_m: float) -> None:
        self._args = (preset, view, length_m, width_m, max_distance_m)
        self.rows = rows
        self._arrays: tuple[np.ndarray, ...] | None = None
        self._index: np.ndarray | None = None

    def of(self, t_i: np.ndarray, j_i: np.ndarray) -> tuple[np.ndarray, ...]:
        """:func:`visible_outline`'s arrays for the bodies ``(t_i, j_i)``; those outside ``rows`` computed here."""
        preset, view, length_m, width_m, max_distance_m = self._args
        if self._arrays is None:
            t_all, j_all = np.nonzero(self.rows)
            self._arrays = visible_outline(preset, view, t_all, j_all, length_m, width_m, max_distance_m)
            self._index = np.full(self.rows.shape, -1, dtype=np.intp)
            self._index[t_all, j_all] = np.arange(t_all.size)
        k = self._index[t_i, j_i]
        if k.size and k.min() < 0:              # not among the rows: computed alone (no caller of this module asks)
            return visible_outline(preset, view, t_i, j_i, length_m, width_m, max_distance_m)
        if k.size == self._arrays[0].shape[0] and np.array_equal(k, np.arange(k.size)):
            return self._arrays
        return tuple(a[k] for a in self._arrays)


def visible_centre_y(preset: RadarPreset, view: SensorView, length_m: np.ndarray, width_m: np.ndarray,
                     rows: np.ndarray, max_distance_m: float, outline: SharedOutline | None = None) -> np.ndarray:
    """Where across the sensor's axis the scatterer levels measure each body (at its nearest point's x): the y of its
    outline's reflected power centroid (the :func:`outline_points` inside the field of view, each by its share, its
    range to the fourth and the element pattern), for the actors where ``rows`` (shape like ``view.x_m``) is True;
    ``view.y_m`` (the nearest point's) elsewhere or where no outline point is inside. Where the point at the nearest x
    and that y falls outside the field of view (a body its edge crosses, turned: its nearest x with its centroid's y lay
    0.4° beyond acc_lrr's edge, or 0.4 m beyond the ±60° sector's 20 m, and the body was never reported — an independent
    tester's finding): the nearest point's y, as before (moved onto the edge, the measurement's noise put it outside in
    half the cycles).

    The detection and signal levels' tracker measures a group of detections at its nearest x and its detections'
    power-weighted y (:func:`radarnode.perception.tracker.group_detections`); a body narrower than a beam is one
    peak at its power centroid's azimuth. A car seen from behind is then measured at its rear face's middle, not at
    its nearest corner: in the next lane the two lie about 0.9 m apart (``benchmarks/object_sigma.py``: the object
    level's `across` column was 0.05 m where the detection level's was 0.58). ``outline``: the bodies' outlines where
    already computed (:class:`SharedOutline`, whose ``rows`` include these)."""
    y = view.y_m.copy()
    t_i, j_i = np.nonzero(rows)
    if t_i.size == 0:
        return y
    _, py, r_s, az_s, share, inside = visible_outline(preset, view, t_i, j_i, length_m, width_m, max_distance_m) \
        if outline is None else outline.of(t_i, j_i)
    r2 = np.maximum(r_s, 0.1)
    r2 *= r2
    power = np.where(inside, share * equation.pattern_gain(preset, az_s, inside) / (r2 * r2), 0.0)   # share·G(θ)/r⁴
    total = power.sum(axis=(1, 2))
    seen = total > 0.0
    t_i, j_i, total = t_i[seen], j_i[seen], total[seen]
    yc = (power * py).sum(axis=(1, 2))[seen] / total
    z0 = 0.0 if view.z_m is None else np.asarray(view.z_m, dtype=np.float64)[t_i, j_i]
    r3 = np.sqrt(view.x_m[t_i, j_i] ** 2 + yc * yc + z0 * z0)
    inside = in_fov(preset, r3, np.arctan2(yc, view.x_m[t_i, j_i])) & (r3 <= max_distance_m)
    y[t_i[inside], j_i[inside]] = yc[inside]
    return y


def may_be_in_fov(preset: RadarPreset, view: SensorView, length_m: np.ndarray, width_m: np.ndarray) -> np.ndarray:
    """Where a part of each actor's box may lie inside a sector: a necessary condition of :func:`in_fov` for any of
    its points (1e-6 m and rad to spare). Its nearest point within the farthest sector's range, its azimuth extent
    (from its corners; every direction for a box round the sensor or behind it) meeting the widest sector's, and
    where every sector looks forward, a part in front of the sensor. Shapes like ``view.x_m``."""
    r_max = max(sector.max_range_m for sector in preset.fov) + 1e-6
    h_max = max(math.radians(sector.half_angle_deg) for sector in preset.fov) + 1e-6
    may = (np.hypot(view.x_m, view.y_m) <= r_max) & (view.az_hi_rad >= -h_max) & (view.az_lo_rad <= h_max)
    if h_max < 0.5 * math.pi:       # sectors in front of the sensor: a box wholly behind it is in none
        c, s = np.abs(np.cos(view.orientation_rad)), np.abs(np.sin(view.orientation_rad))
        may &= view.centre_x_m + 0.5 * (c * length_m + s * width_m) > -1e-6
    return may


def _nearest_on_sectors(preset: RadarPreset, sectors: list, x: np.ndarray, y: np.ndarray, z: np.ndarray,
                        centre_x: np.ndarray, centre_y: np.ndarray, orientation: np.ndarray, length_m: np.ndarray,
                        width_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`nearest_in_fov` for boxes whose nearest point is outside every sector, flat arrays (m,): the point of
    each box nearest to the sensor within the sectors, or (x, y) where no part of the box is in one."""
    ch, sh = np.cos(orientation)[..., None], np.sin(orientation)[..., None]
    hl, hw = (length_m / 2.0)[..., None], (width_m / 2.0)[..., None]
    ux = np.array([1.0, 1.0, -1.0, -1.0])          # corners in box axes, in order round the box
    uy = np.array([1.0, -1.0, -1.0, 1.0])
    ax = centre_x[..., None] + ch * hl * ux - sh * hw * uy               # (..., 4)
    ay = centre_y[..., None] + sh * hl * ux + ch * hw * uy
    bx, by = np.roll(ax, -1, axis=-1), np.roll(ay, -1, axis=-1)                 # each edge A → B
    dx, dy = bx - ax, by - ay
    best = np.full(x.shape, np.inf)
    bx_out, by_out = x.copy(), y.copy()
    for sector in sectors:                                                      # a few sectors
        h = math.radians(sector.half_angle_deg)
        lo, hi = np.zeros(ax.shape), np.ones(ax.shape)
        empty = np.zeros(ax.shape, dtype=bool)
        # the wedge |azimuth| ≤ h as two half-planes: sin h·x ∓ cos h·y ≥ 0
        for sign in (1.0, -1.0):
            ga = math.sin(h) * ax - sign * math.cos(h) * ay
            gb = math.sin(h) * bx - sign * math.cos(h) * by
            with np.errstate(divide="ignore", invalid="ignore"):
                cut = ga / (ga - gb)
            lo = np.where((ga < 0.0) & (gb >= 0.0), np.maximum(lo, cut), lo)
            hi = np.where((ga >= 0.0) & (gb < 0.0), np.minimum(hi, cut), hi)
            empty |= (ga < 0.0) & (gb < 0.0)
        dd = np.maximum(dx * dx + dy * dy, 1e-300)
        foot = -(ax * dx + ay * dy) / dd
        t = np.clip(foot, lo, np.maximum(lo, hi))
        zz = z[..., None] ** 2
        px, py = ax + t * dx, ay + t * dy
        # nearer than the minimum range: where the edge leaves that circle instead (a body touching the sensor)
        near = px * px + py * py + zz < preset.min_range_m ** 2
        if near.any():
            fx, fy = ax + foot * dx, ay + foot * dy
            half = np.sqrt(np.maximum(preset.min_range_m ** 2 - zz - fx * fx - fy * fy, 0.0) / dd)
            t1, t2 = foot - half, foot + half
            t = np.where(near, np.where(t1 >= lo, t1, t2), t)
            empty |= near & (t1 < lo) & (t2 > hi)
            px, py = ax + t * dx, ay + t * dy
        rng = np.sqrt(px * px + py * py + zz)
        rng = np.where(empty | (lo > hi) | (rng > sector.max_range_m) | (rng < preset.min_range_m * (1.0 - 1e-9)),
                       np.inf, rng)
        k = np.argmin(rng, axis=-1)[..., None]
        r_k = np.take_along_axis(rng, k, axis=-1)[..., 0]
        take = r_k < best
        best = np.where(take, r_k, best)
        bx_out = np.where(take, np.take_along_axis(px, k, axis=-1)[..., 0], bx_out)
        by_out = np.where(take, np.take_along_axis(py, k, axis=-1)[..., 0], by_out)
    return bx_out, by_out


def visible_fraction(range_m: np.ndarray, az_lo: np.ndarray, az_hi: np.ndarray, occluder: np.ndarray,
                     elevation: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Fraction of each actor's azimuth extent not covered by any nearer occluding actor.

    Shapes: all inputs (..., n) — any leading axes, e.g. time; returns (..., n). ``elevation`` is
    (bottom, top, elevated): the actors' elevation extents (rad) and which are off the ground; a pair of which
    one is elevated occludes only where the target's reflecting point — an elevated body's lower edge, a body on
    the road at the sensor's height (``SensorView.z_m``) — lies within the occluder's elevation extent, as the
    detection level tests each scatterer (:func:`radarnode.radar.scatterers.visible`): a car is not hidden by the
    bridge it stands under or beyond, nor a second bridge's lower edge by the deck before it; two actors on the
    road occlude by azimuth alone.
    Cost O(n²·16) per leading index, fine for the tens of actors of a scene.
    """
    n = range_m.shape[-1]
    if n == 0:
        return np.ones(range_m.shape)
    nearer = (range_m[..., None, :] < range_m[..., :, None]) & occluder[..., None, :]    # (..., target, occluder)
    if elevation is not None:
        lo, hi, up = elevation
        point = np.where(up, lo, 0.0)                                                    # (..., n)
        behind = (lo[..., None, :] <= point[..., :, None]) & (point[..., :, None] <= hi[..., None, :])
        nearer &= behind | ~(up[..., :, None] | up[..., None, :])
    # the sampled test only at the times where a nearer occluder's extent meets a target's (a margin of 1e-9 rad
    # for the samples' rounding): elsewhere nothing is covered, the fraction is exactly 1
    nearer &= ((az_lo[..., None, :] <= az_hi[..., :, None] + 1e-9)
               & (az_hi[..., None, :] >= az_lo[..., :, None] - 1e-9))
    nearer = nearer.reshape(-1, n, n)
    frac = np.ones(nearer.shape[:2])
    # the (time, target, occluder) pairs that may cover something, in that order: each target's samples tested
    # against its own occluders only, the samples covered by any of them an OR of the pairs' bit masks
    row, tgt, occ = np.nonzero(nearer)
    if row.size:
        lo, hi = az_lo.reshape(-1, n), az_hi.reshape(-1, n)
        t_lo, t_hi = lo[row, tgt], hi[row, tgt]
        u = (np.arange(OCCLUSION_SAMPLES) + 0.5) / OCCLUSION_SAMPLES
        smp = t_lo[:, None] + u * (t_hi - t_lo)[:, None]                                   # (pairs, S)
        hit = np.packbits((smp >= lo[row, occ][:, None]) & (smp <= hi[row, occ][:, None]), axis=1)
        cell = row * n + tgt
        first = np.flatnonzero(np.r_[True, cell[1:] != cell[:-1]])                          # each target's pairs
        count = _POPCOUNT[np.bitwise_or.reduceat(hit, first, axis=0)].sum(axis=1)          # samples covered
        frac.reshape(-1)[cell[first]] = 1.0 - count / OCCLUSION_SAMPLES
    return frac.reshape(range_m.shape)


def sigma_to_xy(range_m, azimuth_rad, sigma_r, sigma_az):
    """Cartesian σ of a polar measurement (first-order propagation)."""
    c, s = np.cos(azimuth_rad), np.sin(azimuth_rad)
    sx = np.sqrt((c * sigma_r) ** 2 + (range_m * s * sigma_az) ** 2)
    sy = np.sqrt((s * sigma_r) ** 2 + (range_m * c * sigma_az) ** 2)
    return sx, sy


class _TrackerField:
    """One field of the internal tracker's state after the last step (``ObjectModel.hist`` …): the row of the chunk
    that step took (a chunk holds every cycle's, computed in one pass), or the value last set."""

    def __set_name__(self, owner, name: str) -> None:
        self.name = name

    def __get__(self, obj, owner=None):
        if obj is None:
            return self
        pos = obj.__dict__.get("_pos")
        if pos is not None:
            return pos[0]["trk"][self.name][pos[1]]
        return obj.__dict__["_trk"][self.name]

    def __set__(self, obj, value) -> None:
        obj._settle()
        obj.__dict__.setdefault("_trk", {})[self.name] = value


def affine_scan(alpha: np.ndarray, beta: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """x_k = alpha_k·x_(k−1) + beta_k for k = 0 … T−1 (axis 0) from x_(−1) = x0, every k at once.

    The maps are composed by a log-depth (Hillis–Steele) scan: about 3·log2(T) array operations instead of a
    loop over k. ``alpha`` broadcasts against ``beta`` (shape (T, …)), ``x0`` against ``beta[0]``. The sum is
    taken in another order than the loop's, so the result differs from it in the last bits (about 1e-16
    relative per term); a factor 0 restarts the recurrence exactly."""
    a = np.array(np.broadcast_to(alpha, beta.shape), dtype=np.float64)
    b = np.array(beta, dtype=np.float64)
    s = 1
    while s < a.shape[0]:
        b[s:] = a[s:] * b[:-s] + b[s:]       # the right sides are evaluated before the assignment
        a[s:] = a[s:] * a[:-s]
        s *= 2
    return a * x0 + b


def _draw_block(rng: np.random.Generator, n: int) -> dict[str, np.ndarray]:
    """One block of DRAW_BLOCK cycles' random numbers for ``n`` actors, in the order a run draws them: the uniforms
    ``u`` (DRAW_BLOCK, n), then the normals ``z`` (DRAW_BLOCK, 11, n) (a block drawn again, after a step back, from the
    state it began at, is the same numbers)."""
    return {"u": rng.random((DRAW_BLOCK, n)), "z": rng.standard_normal((DRAW_BLOCK, 11, n))}


class ObjectModel:
    """Statistical object-level radar model with its own light tracker.

    Parameters
    ----------
    scene : Scene
    preset : RadarPreset
    rng : numpy.random.Generator
        The only source of randomness; seed it from the scenario.
    """

    hist = _TrackerField()          # detection history, bit 0 = the last cycle (n,) uint8
    misses = _TrackerField()        # consecutive misses (n,)
    alive = _TrackerField()         # confirmed and not lost (n,) bool
    obj_id = _TrackerField()        # the object's ID, −1 when none (n,)
    state = _TrackerField()         # last reported x, y, vx, vy (n, 4)
    was_moving = _TrackerField()    # seen moving while listed, ever (n,) bool: "stopped" rather than "stationary"
    run_resolved = _TrackerField()  # an unambiguous detection since the last miss (n,) bool (staggered ramps)

    def __init__(self, scene: Scene, preset: RadarPreset, rng: np.random.Generator,
                 options: SignalOptions = SignalOptions()) -> None:
        self.scene = scene
        self.preset = preset
        self.rng = rng
        # the signal chain's detection test: every level detects with the same law (issue 9)
        self.statistic = DspChain(preset, options.dsp).statistic
        # a staggered radar's second chirp sequence: its SNR over the first's (its longer chirp collects more)
        self.second_gain_db = 0.0 if not preset.stagger_chirp_period_s else float(
            equation.snr_db(preset.second_sequence(), 100.0, 0.0) - equation.snr_db(preset, 100.0, 0.0))
        self.extended = (scene.length_m > 1.0) | (scene.width_m > 1.0)
        self.info = ObjectStepInfo()
        n = scene.n
        self._pos: tuple[dict, int] | None = None     # the chunk and row of the last step
        self._trk = {"hist": np.zeros(n, dtype=np.uint8), "misses": np.zeros(n, dtype=np.int64),
                     "alive": np.zeros(n, dtype=bool), "obj_id": np.full(n, -1, dtype=np.int64),
                     "state": np.zeros((n, 4)), "was_moving": np.zeros(n, dtype=bool),
                     "run_resolved": np.zeros(n, dtype=bool)}
        self.last_t = 0.0
        self.cycle = 0
        self.period_s = scene.scenario.period_s
        # a single ramp whose wrap the trackers resolve from the range a track walks (the other levels' tracker,
        # models.tracker_for): an aliased target is listed at its true speed, once RANGE_WALK_MIN_HITS hits resolved it
        self.range_walk = not preset.stagger_chirp_period_s and follows_one_wrap(2.0 * preset.alias_speed_mps,
                                                                                 self.period_s)
        #: the cycles the run will step (0 … planned_cycles − 1), when its runner knows (None: the scenario's)
        self.planned_cycles: int | None = None
        self._cache: dict | None = None
        self._physics_layout: tuple | None = None       # _physics' fields: (key, (shape after T, dtype))
        self._blocks: dict[int, dict[str, np.ndarray]] = {}
        self._block_states: dict[int, dict] = {}      # the generator's state where each recent block began
        self._drawn_upto = -1
        # clusters (guardrail posts, false alarms) draw a variable count of numbers: their own streams, one per
        # quantity, each read in cycle order, so that a chunk's draws are the same whatever the chunks
        hit, noise, count, value = np.random.SeedSequence(int(rng.integers(0, 2**63))).spawn(4)
        self._cluster_rngs = {"hit": np.random.default_rng(hit), "noise": np.random.default_rng(noise),
                              "count": np.random.default_rng(count), "value": np.random.default_rng(value)}
        self.occluder = ~scene.is_guardrail
        self.reportable = ~scene.is_guardrail         # guardrails show up as clusters only

    def _draws(self, k0: int, count: int) -> dict[str, np.ndarray]:
        """The random numbers of cycles k0 … k0+count−1, drawn in fixed blocks so that they depend only on
        the seed and the cycle index, never on how the cycles were grouped into chunks."""
        n = self.scene.n
        first, last = k0 // DRAW_BLOCK, (k0 + count - 1) // DRAW_BLOCK
        while self._drawn_upto < last:
            self._drawn_upto += 1
            self._block_states[self._drawn_upto] = self.rng.bit_generator.state
            self._block_states.pop(self._drawn_upto - KEEP_DRAW_STATES, None)
            block = _draw_block(self.rng, n)
            if self._drawn_upto >= first:
                self._blocks[self._drawn_upto] = block
            # (the blocks of the cycles a step skipped are drawn, so that the generator stands where a run through
            # them would leave it, and let go at once: a first step at 10⁶ s held 2.8 GB of them before, an
            # independent tester's finding)
        for b in [b for b in self._blocks if b < first]:
            del self._blocks[b]
        for b in range(first, last + 1):
            if b not in self._blocks:      # a step back to a block let go: drawn again from the state it began at
                if b not in self._block_states:
                    raise ValueError(f"the object level cannot step back to cycle {k0}: it keeps the random state of "
                                     f"the last {KEEP_DRAW_STATES * DRAW_BLOCK} cycles only")
                again = np.random.Generator(type(self.rng.bit_generator)())
                again.bit_generator.state = self._block_states[b]
                self._blocks[b] = _draw_block(again, n)
        off = k0 - first * DRAW_BLOCK
        return {name: np.concatenate([self._blocks[b][name] for b in range(first, last + 1)])[off:off + count]
                for name in ("u", "z")}

    def _chunk(self, k0: int, times: np.ndarray, config: RuntimeConfig) -> dict:
        """Everything of cycles k0 … that does not depend on the tracker's state, as (T, n) arrays.

        The physics (:meth:`_physics`) is computed only at the cycles where some actor may have a part inside a
        sector (:meth:`_cycles_in_view`; every cycle in a scene with structures above the road, whose averaged
        gain runs over all of them): at the others none is in the field of view, so none is detected, listed or
        coasting, and their rows hold zeros that nothing reads."""
        sc = self.scene
        truth = sc.views(times)
        draws = self._draws(k0, times.size)
        u, z = draws["u"], draws["z"]
        rows = None if sc.elevated.any() else self._cycles_in_view(truth)
        if rows is None or rows.size == times.size:
            ph = self._physics(truth, u, z, config)
        elif rows.size == 0 and self._physics_layout is not None:      # nothing in view: zeros of each field
            ph = {key: np.zeros((times.size, *tail), dtype=dtype) for key, (tail, dtype) in self._physics_layout}
        else:
            ph = {key: _expand(val, rows, times.size)
                  for key, val in self._physics(truth.take_times(rows), u[rows], z[rows], config).items()}
        if self._physics_layout is None and "body" not in ph:
            self._physics_layout = tuple((key, (val.shape[1:], val.dtype)) for key, val in ph.items())
        return self._derived(k0, times, config, truth, z, ph)

    def _second_look(self, u: np.ndarray, pd: np.ndarray, snr: np.ndarray, observable: np.ndarray
                     ) -> np.ndarray | None:
        """Where a staggered radar's second chirp sequence detects an actor its first detects ((T, n) bool; None
        for one sequence): with P(second | first) (:meth:`DetectionStatistic.pd_second_look`: its own noise, the
        same fluctuation), drawn from the first's draw ``u`` (given u < pd, u/pd is uniform: no new random
        numbers). A detection the second misses keeps the first's speed, aliased and flagged, as at the other levels
        (which missed it at about 18 dB in 0.3 of the cycles, where the object level never did)."""
        if not self.preset.stagger_chirp_period_s:
            return None
        first = observable & (u < pd)
        out = np.zeros(u.shape, dtype=bool)
        t, a = np.nonzero(first)
        if t.size:
            q = self.statistic.pd_second_look(snr[t, a], self.second_gain_db, self.scene.swerling[a])
            out[t, a] = u[t, a] < pd[t, a] * q
        return out

    def _cycles_in_view(self, truth: SensorView) -> np.ndarray:
        """The cycles (indices) where some actor may have a part inside a sector (:func:`may_be_in_fov`)."""
        return np.flatnonzero(may_be_in_fov(self.preset, truth, self.scene.length_m, self.scene.width_m).any(axis=-1))

    def _physics(self, truth: SensorView, u: np.ndarray, z: np.ndarray, config: RuntimeConfig) -> dict:
        """What the radar measures of each actor at the times of ``truth`` ((T, n) arrays): field of view,
        occlusion, SNR, Pd, the measurements and their σ, and the reported body; ``u`` and ``z`` are the cycles'
        draws."""
        p, sc = self.preset, self.scene
        # what the radar measures of a body is its nearest point within the field of view
        x_in, y_in = nearest_in_fov(p, truth, sc.length_m, sc.width_m)
        view = dataclasses.replace(truth, x_m=x_in, y_m=y_in)
        rng_m, az = view.range_m, view.azimuth_rad
        fov = in_fov(p, rng_m, az)
        observable = fov & (rng_m <= config.max_distance_m)
        elev = None
        if sc.elevated.any():
            elev = (*sc.elevation_extent(view), np.broadcast_to(sc.elevated, rng_m.shape))
        frac = visible_fraction(rng_m, view.az_lo_rad, view.az_hi_rad, self.occluder & observable, elev)
        observable &= frac >= MIN_VISIBLE_FRACTION
        rcs_eff = sc.rcs_dbsm + 10.0 * np.log10(np.maximum(frac, 1e-3))
        rcs_body = rcs_eff
        if sc.elevated.any():
            # an actor above the road: its elevation beam and the road's reflection (the radar's RCS is apparent)
            gain = np.where(sc.elevated, elevation.propagation_db(p, np.hypot(view.x_m, view.y_m), sc.z_m,
                                                                  sc.mount_z_m), 0.0)
            rcs_eff = rcs_eff + gain
        snr = equation.snr_db(p, rng_m, rcs_eff, config.power_reduction_db, az)
        stat = self.statistic
        pd = stat.pd_of_snr(snr, 1) if not (sc.swerling == 0).any() else \
            np.where(sc.swerling == 0, stat.pd_of_snr(snr, 0), stat.pd_of_snr(snr, 1))
        # a body a sector's edge crosses is measured at its point on the edge, but reflects from its parts inside
        crossing = ((x_in != truth.x_m) | (y_in != truth.y_m)) & ~((sc.length_m <= POINT_SIZE_M)
                                                                    & (sc.width_m <= POINT_SIZE_M))
        # the outlines of the extended bodies in view: the masking's (a subset) and the centroid's
        outline = SharedOutline(p, view, sc.length_m, sc.width_m, observable & self.extended, config.max_distance_m)
        pd_alone = pd
        self._mask_draws = None
        pd = pd * self._masking(view, rng_m, snr, observable, crossing, config.max_distance_m, outline)
        mask_draws = self._mask_draws
        # where the chain measures it: at its nearest x and its outline's power centroid across (visible_centre_y),
        # as the other levels' tracker measures a group of detections
        seen = dataclasses.replace(view, y_m=visible_centre_y(p, view, sc.length_m, sc.width_m, outline.rows,
                                                              config.max_distance_m, outline))
        r_seen, az = seen.range_m, seen.azimuth_rad
        # measurement noise: what the signal chain achieves (its efficiency times the Cramér–Rao bound); an
        # extended actor adds the preset's floor (where on the body the reflection centre lies)
        er, ev, ea = chain_efficiency(snr)
        ext = self.extended
        # where the array sees the actor: a sparse array's grating lobe folds it (the other levels' beamformer does)
        az_seen = ambiguity.apparent_azimuth(p, az)
        bound_r, bound_v, bound_az = equation.crbs(p, snr, az_seen)
        sig_r = np.hypot(er * bound_r, np.where(ext, p.range_sigma_floor_m, 0.0))
        sig_v = np.hypot(ev * bound_v, np.where(ext, p.speed_sigma_floor_mps, 0.0))
        # … and the RCS it infers there: the element pattern divided out at the angle it measures, not the truth's
        # (a grating lobe's 50° seen at −41.5° read 1.5 dB low at the other levels and true here: a tester's finding)
        if p.element_spacing_wl > 0.5:
            lobe_db = equation.pattern_moved_db(p, az, az_seen, az_seen != az)
            rcs_eff, rcs_body = rcs_eff + lobe_db, rcs_body + lobe_db
        floor_az = np.where(ext, math.radians(p.azimuth_sigma_floor_deg), 0.0)
        sig_az = np.hypot(ea * bound_az, floor_az)
        m_r = r_seen + sig_r * z[:, 0]
        # (near endfire in d·sinθ, where the array measures it, as the other levels: wrapped, never beyond ±90°, and
        # the RCS read with the element pattern at the angle measured, as theirs)
        m_az, endfire = ambiguity.measured_azimuth(p, az_seen, sig_az, z[:, 1], snr, ea, floor_az, observable)
        if endfire.any():
            pattern_db = equation.pattern_moved_db(p, az_seen, m_az, endfire)
            rcs_eff, rcs_body = rcs_eff + pattern_db, rcs_body + pattern_db
        # such a body's measured azimuth is mirrored back about the edge (the scatterer levels report its inner
        # points); a small body is one point, reported only where it is measured inside (as at the other levels)
        if crossing.any():
            edge_seen = ambiguity.apparent_azimuth(p, view.azimuth_rad)    # a crossing body's nearest point: the edge
            past = crossing & (np.abs(m_az) > np.abs(edge_seen))
            m_az = np.where(past, np.sign(m_az) * (2.0 * np.abs(edge_seen) - np.abs(m_az)), m_az)
        c, s = np.cos(az), np.sin(az)
        v_rad = view.vx_mps * c + view.vy_mps * s
        if sc.elevated.any():
            v_rad = v_rad * (np.hypot(seen.x_m, seen.y_m) / np.maximum(r_seen, 1e-9))   # cos(elevation)
        v_tan = -view.vx_mps * s + view.vy_mps * c
        # the speed the radar can measure: aliased and resolved by the same rules as the other levels
        v_meas = v_rad + sig_v * z[:, 2]
        m_vr, ambig = ambiguity.apparent_range_rate(p, v_meas, az,
                                                    (view.sensor_vx_mps[:, None], view.sensor_vy_mps[:, None]),
                                                    self._second_look(u, pd, snr, observable))
        # the range–Doppler coupling: the chain takes it out of the peak's range with the speed it reports, so a
        # speed it reports aliased leaves (true − reported) × the coupling in the range, as at the other levels
        # (without it the object level put an aliased target 0.4–3 m from where they do)
        m_read = m_r
        m_r = ambiguity.coupled_range(p, m_r, v_meas, m_vr)
        # beyond the unambiguous range (a preset whose range bins end inside its field of view) the beat folds: the
        # radar reports the range modulo it, as the other levels do (the object level reported 131 m where they
        # report 16.4 m: an independent tester's finding). A wrap, as the scatterer levels model real sampling too
        # (README, known limits). The fold is taken from the range before it: coupled_range has folded already
        # wherever some coupling is left (an aliased speed, or a remainder of 1e-15)
        beyond = observable & (r_seen >= p.unambiguous_range_m)
        if beyond.any():
            unfolded = m_read + ambiguity.coupling_left(p, v_meas, m_vr)
            m_r = np.where(beyond, np.mod(unfolded, p.unambiguous_range_m), m_r)
            # (a real-sampling receiver's anti-alias filter, which the SNR carries, is not divided out either)
            if not p.complex_sampling:
                filt = np.where(beyond, equation.ANTI_ALIAS_REJECTION_DB, 0.0)
                rcs_eff, rcs_body = rcs_eff - filt, rcs_body - filt
        # the RCS the radar infers at the range it reports, as the other levels read it: the coupling an aliased
        # speed leaves and a fold move it by the radar equation's R⁴ (a 30-dBsm target folded to 2 m read 30 dBsm
        # where the detection level read −25, a tester's finding)
        if np.any(m_r != m_read):
            moved_db = ambiguity.range_db(m_read, m_r)
            rcs_eff, rcs_body = rcs_eff + moved_db, rcs_body + moved_db
        m_vt = v_tan + p.lateral_speed_sigma_mps * z[:, 3]
        mc, ms = np.cos(m_az), np.sin(m_az)
        # the radial speed the internal tracker takes: with staggered ramps an ambiguous detection's at its track's
        # wrap, the true one's (below); with a single ramp whose tracker resolves the wrap from the range its track
        # walks (self.range_walk) the true one too, the track listed once it is resolved (_derived); the cluster list
        # keeps m_vr
        stagger = bool(p.stagger_chirp_period_s)
        m_vr_track = np.where(ambig == AMBIG_AMBIGUOUS, v_meas, m_vr) if stagger else \
            v_meas if self.range_walk else m_vr
        meas = np.stack([m_r * mc, m_r * ms, m_vr_track * mc - m_vt * ms, m_vr_track * ms + m_vt * mc], axis=-1)
        sx, sy = sigma_to_xy(r_seen, az_seen, sig_r, sig_az)
        ground = np.hypot(view.vx_mps + view.sensor_vx_mps[:, None], view.vy_mps + view.sensor_vy_mps[:, None])
        # a detection is reported where it was measured inside the field of view, as the other levels report
        # theirs (radarnode.radar.models.reportable): a body at a sector's edge is seen on its inner side only
        measured_in = in_fov(p, m_r, m_az) & (m_r <= config.max_distance_m)
        # a speed reported aliased (wraps away from the measured one) moves the prediction of a track at that speed
        # off the target by the difference times the cycle: within the tracker's gate the other levels' tracker
        # follows the target (and resolves the wrap from the range it walks, self.range_walk), beyond it never
        # confirms it (its clusters carry the aliased speed, flagged ambiguous): the internal tracker takes the same
        # detections (ALIAS_GATE_M)
        offset = np.abs(m_vr - v_meas)
        trackable = offset * self.period_s <= ALIAS_GATE_M
        if stagger:
            # with staggered ramps the tracker compares an ambiguous detection's speed with its track's modulo
            # 2·v_max,1 and takes the wrap nearest its own (radarnode.perception.tracker.ObjectTracker): a track
            # running at the true speed takes a cycle the second sequence missed as a measurement of that speed. A
            # track only ambiguous detections measured is never listed (_track_flags): beyond the span, none is
            trackable = np.ones(offset.shape, dtype=bool)
        det_in = observable & (u < pd) & measured_in
        # the RCS the chain reads of what it detects, drawn with the detection itself (DetectionStatistic.reading):
        # near the threshold a detected return is one its fluctuation and noise took over, and it reads high as at
        # the other levels (drawn apart, a −8-dBsm point at Pd ≈ 0.3 read −9.5 dBsm here against −4.5/−5.0 there:
        # an independent tester's finding). Given the detection u/Pd is uniform; the fluctuation's uniform is z[:, 4]
        # (the draw this reading took before): no new random numbers, every detection as it was
        rcs_read, snr_read = np.array(rcs_eff, dtype=np.float64, copy=True), np.array(snr, dtype=np.float64, copy=True)
        t, a = np.nonzero(det_in)
        if t.size:
            # a detection the other actors' energy in its ring made less likely passed a raised threshold: read as
            # one of the Pd it had (DetectionStatistic.reading's loss; 0 where nothing masked it)
            loss = np.zeros(t.size)
            masked = pd[t, a] < pd_alone[t, a]
            if masked.any():
                loss[masked] = self._masked_loss(t[masked], a[masked], pd_alone, u, pd, mask_draws)
            read_db = 10.0 * np.log10(stat.reading(snr[t, a], u[t, a] / pd[t, a], normal_cdf(z[t, 4, a]),
                                                   sc.swerling[a] == 1, loss))
            rcs_read[t, a] += read_db
            snr_read[t, a] += read_db
        out = {"det_in": det_in, "rcs_read": rcs_read, "snr_read": snr_read, "trackable": trackable, "fov": fov,
               "still": ground < MOVING_THRESHOLD_MPS,
               "az": az, "pd": pd, "sx": sx, "sy": sy, "orientation_truth": view.orientation_rad,
               "meas": meas, "snr": snr, "rcs_eff": rcs_eff, "m_r": m_r, "m_az": m_az, "m_vr": m_vr,
               "ambig": ambig, "sig_r": sig_r, "sig_v": sig_v, "sig_az": sig_az,
               # the acceleration reported keeps the model's small noise: drawn with σ_alat (about 1 m/s² from the
               # lateral speed's 0.5 m/s) it would saturate ArelLat (−2.5…2.61 m/s²); its σ fields are conservative
               "arel_long": view.ax_mps2 + 0.1 * z[:, 5], "arel_lat": view.ay_mps2 + 0.05 * z[:, 6]}
        if sc.elevated.any():     # the reported body after the track's averaged gain (_derived; every cycle)
            out["body"] = (view, rng_m, az, rcs_body, snr, gain, ground)
        else:
            out.update(self._reported_body(view, rng_m, az, rcs_body, snr, z, ground))
        return out

    def _derived(self, k0: int, times: np.ndarray, config: RuntimeConfig, truth: SensorView, z: np.ndarray,
                 ph: dict) -> dict:
        """The tracker's flags over the chunk (:meth:`_track_flags`) and the object list's fields that follow
        from them and the physics ``ph``, for every cycle of the chunk."""
        p, sc = self.preset, self.scene
        seen = ph.pop("det_in")                  # every detection (the cluster list); the tracker takes the trackable
        # a staggered radar's tracker lists no track until an unambiguous detection measured its speed; a single
        # ramp's that resolves wraps from the range a track walks, until RANGE_WALK_MIN_HITS hits did
        resolved = ph["ambig"] != AMBIG_AMBIGUOUS if p.stagger_chirp_period_s or self.range_walk else None
        flags = self._track_flags(seen & ph.pop("trackable"), ph["fov"], ph.pop("still"), resolved,
                                  RANGE_WALK_MIN_HITS if self.range_walk else None)
        if "body" in ph:
            # the object's reported RCS is its track's average in power (RCS_GAIN per measured cycle, from the
            # track's first detection, as the detection level's tracker and the real sensor report it): so is this
            # range-dependent factor
            view, rng_m, az_b, rcs_body, snr_b, gain, ground = ph.pop("body")
            gain_db, ph["gain_power"] = self._averaged_gain_db(k0, gain, flags["detected"], flags["first_hit"])
            rcs_body = rcs_body + gain_db
            ph.update(self._reported_body(view, rng_m, az_b, rcs_body, snr_b, z, ground))
        az, pd, sx, sy, sig_v = ph.pop("az"), ph["pd"], ph.pop("sx"), ph.pop("sy"), ph["sig_v"]
        orientation = ph.pop("orientation_truth")
        # the object list's fields that follow from the flags, for every cycle of the chunk
        det, misses, hits = flags["detected"], flags["misses"], flags["hits"]
        coast = np.where(det, 1.0, 1.0 + misses)                 # σ grows while coasting
        c2 = coast * coast
        p_exist = 1.0 - np.exp(np.maximum(hits, 1) * np.log1p(-np.minimum(pd, 0.999999)))
        c, s = np.cos(az), np.sin(az)
        lat = p.lateral_speed_sigma_mps
        # the object's own σ: position and velocity from this cycle's accuracy, grown while coasting;
        # acceleration as the slope of its velocities, heading from its two ends (radarnode.perception.tracker)
        sig_long, sig_lat = sx * coast, sy * coast
        sig_vlong = np.sqrt((c * sig_v) ** 2 * c2 + (s * lat) ** 2)
        sig_vlat = np.sqrt((s * sig_v) ** 2 * c2 + (c * lat) ** 2)
        sig_along = accel_sigma_mps2(sig_vlong, self.period_s) * coast
        sig_alat = accel_sigma_mps2(sig_vlat, self.period_s) * coast
        sig_orient = orientation_sigma_rad(np.sqrt(0.5 * (sig_long ** 2 + sig_lat ** 2)), sc.length_m)
        return {**ph, **flags, "seen": seen,
            "sig_long": sig_long, "sig_lat": sig_lat, "sig_vlong": sig_vlong, "sig_vlat": sig_vlat,
            "sig_along": sig_along, "sig_alat": sig_alat, "sig_orient": sig_orient,
            "orientation": orientation + sig_orient * z[:, 9],
            "meas_state": np.where(flags["new"], MEAS_NEW, np.where(det, MEAS_MEASURED, MEAS_PREDICTED)),
            "prob_of_exist": np.searchsorted(_PROB_EDGES, p_exist, side="right").astype(np.int64) + 1,
            "k0": k0, "times": times, "config": config, "view": truth,
        }

    def _tables(self, ch: dict) -> dict:
        """The tracker over the chunk (:meth:`_track`) and the per-cycle lists' fields as row tables, so that a
        cycle takes its object list with one slice per table (``obj_f`` float64 and ``obj_i`` int64, shape
        (F, rows), the rows of cycle i ``starts[i]`` … ``starts[i+1]``)."""
        self._track(ch)
        ch["detection_floats"] = np.stack([ch[key] for key in _DETECTION_FLOATS], axis=-1)
        if ch["config"].clusters:      # the actors' rows of the cluster list (_CL_* columns)
            t_n, n = ch["snr"].shape
            rcs = ch["rcs_read"]
            # a cluster is one detection: its velocity is the range rate split along its azimuth, as the other
            # levels and the ARS 408 give it (the tangential part is the tracker's, in the object list only)
            m_az, m_vr = ch["m_az"], ch["m_vr"]
            meas = ch["meas"]
            ch["cluster_actors"] = _cluster_rows(meas[..., 0], meas[..., 1], m_vr * np.cos(m_az),
                                                 m_vr * np.sin(m_az), rcs, ch["sig_r"], ch["sig_az"], ch["sig_v"],
                                                 np.broadcast_to(np.arange(n), (t_n, n)), ch["ambig"])
        return ch

    def _masking(self, view, rng_m: np.ndarray, snr: np.ndarray, observable: np.ndarray, crossing: np.ndarray,
                 max_distance_m: float, outline: SharedOutline | None = None) -> np.ndarray:
        """Pd factor (T, n) from the other actors' energy in each actor's CA-CFAR training ring.

        As the chain masks a weak target beside a strong one at about the same range and speed, and the
        detection level with it (:meth:`DetectionStatistic.ring_interference`): each actor's on-bin windowed
        energy, at its apparent range and Doppler bin, enters every other actor's ring through the window's
        response; the Pd with that interference over the Pd without it (both by
        :meth:`DetectionStatistic.masking_factor`) scales the tabulated Pd, so an actor alone keeps it exactly.
        A body whose outline spans more than a Doppler bin (near the sensor, or beside its line of sight), and a body
        a sector's edge crosses (``crossing``), puts in what its parts inside the field of view reflect, each at its
        own range and speed (:meth:`_outline_interference`); one that spans less, its whole energy at its nearest
        point (the two blended between ``OUTLINE_SPAN_BINS``, so the interference has no step).
        Guardrail posts are not counted here (they are drawn per cycle with the cluster list). ``outline``: the bodies'
        outlines where already computed (:class:`SharedOutline`, whose ``rows`` hold every extended body in view).
        """
        p, stat, sc = self.preset, self.statistic, self.scene
        if sc.n < 2 or stat.cfar.name != "ca":
            return np.ones(snr.shape)
        m, n_r = p.num_chirps, p.num_range_bins
        c, s_ = np.cos(view.azimuth_rad), np.sin(view.azimuth_rad)
        v_rad = view.vx_mps * c + view.vy_mps * s_
        pos_d = np.mod(v_rad / p.doppler_bin_mps, m)
        pos_r = np.mod(rng_m / p.range_resolution_m, n_r)
        # an extended actor's energy is spread over its visible outline, from its nearest point (where ``snr`` is
        # taken) out to about as far beyond its centre: the mean of (R_near/R)⁴ over that span, which the detection
        # level's scatterers sum one by one (a car 3 m beside the sensor puts 7 dB less into a neighbour's ring
        # than its whole RCS at the nearest point would)
        near = np.maximum(rng_m, 0.1)
        far = np.maximum(2.0 * np.hypot(view.centre_x_m, view.centre_y_m) - near, near)
        with np.errstate(divide="ignore", invalid="ignore"):
            spread = np.where(far > near * (1.0 + 1e-6),
                              near ** 4 * (near ** -3.0 - far ** -3.0) / (3.0 * (far - near)), 1.0)
        on_bin = np.where(observable, stat.energy(10.0 ** (snr / 10.0)), 0.0)
        # how many Doppler bins the outline spans: its radial speed at the ends of its azimuth extent and at its
        # nearest point (a truck beside a sensor passing it at 4 m/s: 5–6 bins; a car 50 m ahead: a hundredth)
        ends = [view.vx_mps * np.cos(a) + view.vy_mps * np.sin(a) for a in (view.az_lo_rad, view.az_hi_rad)]
        span = (np.maximum(np.maximum(ends[0], ends[1]), v_rad) - np.minimum(np.minimum(ends[0], ends[1]), v_rad)) \
            / p.doppler_bin_mps
        w = np.where(observable & self.occluder & self.extended, np.where(crossing, 1.0, outline_share(span)), 0.0)
        energy = (1.0 - w) * on_bin * np.clip(spread, 0.0, 1.0)                                    # (T, n)
        dd = np.mod(pos_d[:, None, :] - np.rint(pos_d)[:, :, None] + m / 2.0, m) - m / 2.0      # (T, i, j)
        dr = np.mod(pos_r[:, None, :] - np.rint(pos_r)[:, :, None] + n_r / 2.0, n_r) - n_r / 2.0
        kernel = stat.ring_kernel(dd, dr)
        # the steady bodies' energy and the fluctuating ones' (Swerling 1: one exponential power factor a frame for
        # the whole body, as the scatterer levels draw it), apart: the factor is averaged over the latter's draw
        steady = sc.swerling == 0
        parts = []
        for own in (steady, ~steady):
            if not own.any():
                parts.append(np.zeros(snr.shape))
                continue
            part = np.einsum("tij,tj->ti", kernel, np.where(own, energy, 0.0))
            if (w[:, own] > 0.0).any():
                part += self._outline_interference(view, rng_m, np.where(own, w * on_bin, 0.0), np.rint(pos_d),
                                                   np.rint(pos_r), max_distance_m, outline)
            parts.append(part)
        return self._averaged_masking(snr, parts[0], parts[1])

    #: the digits of a detection's uniform v = u/Pd below 2⁻²⁰ choose the fluctuating neighbours' draw it was
    #: detected with (:meth:`_masked_loss`; uniform, and independent of v's leading 20 bits to 1e-6)
    _SPLIT_DRAW = float(2 ** 20)

    def _masked_loss(self, t: np.ndarray, a: np.ndarray, pd_alone: np.ndarray, u: np.ndarray, pd: np.ndarray,
                     draws: tuple | None) -> np.ndarray:
        """The SNR loss (dB, ≥ 0) by which the ring's interference lowered the Pd of the masked detections (t, a):
        :meth:`DetectionStatistic.snr_of_pd` of the Pd alone less that of the Pd with the interference, each by its
        own Swerling case's table. A fluctuating neighbour's power is one of ``READING_DRAWS`` equally likely draws
        (as :meth:`_averaged_masking` averages the Pd over FLUCTUATION_POINTS of them), and a detection was most
        likely made in a draw that masked little: the draw is taken from its posterior given the detection (∝ the Pd
        with it), by the digits of v = u/Pd, and the loss is that draw's. Taken from the averaged Pd instead, a weak point beside a strong fluctuating one
        (45 dB beside 25 dB, ``ars408_like``) read 3–4 dB high, where the chain reads it as if unmasked: it is
        detected in the frames the strong one faded (an independent tester's finding). A steady neighbour's draws
        are all one: the loss of the averaged Pd."""
        alone, masked = pd_alone[t, a], pd[t, a]
        if draws is not None:
            some, snr, steady, fluct, case = draws
            row = np.full(some.shape, -1, dtype=np.int64)
            row[some] = np.arange(snr.size)
            at = row[t, a]
            ok = (at >= 0) & (fluct.take(np.maximum(at, 0)) > 0.0)
            if ok.any():
                at = at[ok]
                x = READING_DRAWS_X
                f = np.empty((at.size, x.size))
                i_all = steady[at][:, None] + fluct[at][:, None] * x[None, :]
                for sw in (0, 1):
                    sel = case[at] == sw
                    if sel.any():
                        f[sel] = self.statistic.masking_factor(snr[at][sel][:, None], i_all[sel], sw)
                cdf = np.cumsum(f, axis=1)
                w = np.mod(u[t[ok], a[ok]] / pd[t[ok], a[ok]] * self._SPLIT_DRAW, 1.0) * cdf[:, -1]
                k = np.minimum((cdf < w[:, None]).sum(axis=1), x.size - 1)     # the draw: its CDF reaches w
                masked = masked.copy()
                masked[ok] = alone[ok] * f[np.arange(at.size), k]
        case, lost = self.scene.swerling[a], np.zeros(t.size)
        stat = self.statistic
        for sw in (0, 1):                      # each detection by its own Swerling case's table
            k = case == sw
            if k.any():
                lost[k] = stat.snr_of_pd(alone[k], sw) - stat.snr_of_pd(masked[k], sw)
        return np.maximum(lost, 0.0)

    def _averaged_masking(self, snr: np.ndarray, steady: np.ndarray, fluctuating: np.ndarray) -> np.ndarray:
        """The masking factor (T, n) with ``steady`` interference in the ring and ``fluctuating`` interference of
        Swerling 1 bodies, averaged over its exponential draw (taken as one: the dominant neighbour's), at
        ``FLUCTUATION_POINTS`` equally likely values; each actor by its own Swerling case. A truck's mean energy
        20 dB above the masking threshold hides a lead in every frame by the mean, but in one frame of ten the truck
        draws a tenth of its mean and the lead comes through, as at the detection level (measured: a creeping lead
        beside a stopped truck, the ego passing at 2.4 m/s, was detected in 2–5 % of the cycles at the object level
        by the mean, 12–21 % at the detection level). Keeps the factor at each draw, (where some interference is,
        (count, FLUCTUATION_POINTS)), in ``_mask_draws`` for the reading (:meth:`_masked_loss`)."""
        stat, sc = self.statistic, self.scene
        case = np.broadcast_to(np.where(sc.swerling == 0, 0, 1), snr.shape)
        out = np.ones(snr.shape)
        mean_z = stat.n_channels * stat.eigenvalues.sum()
        some = (steady + fluctuating) >= 0.01 * mean_z
        self._mask_draws = None
        if not some.any():
            return out
        x = -np.log1p(-(np.arange(FLUCTUATION_POINTS) + 0.5) / FLUCTUATION_POINTS)          # exponential quantiles
        x = x / x.mean()                                                                   # mean 1 exactly
        # each cell's SNR once, against its row of draws (masking_factor broadcasts: the SNR's share of the table
        # read is computed once a cell, not once a draw)
        rho = snr[some][:, None]
        i_all = steady[some][:, None] + fluctuating[some][:, None] * x[None, :]
        cases = case[some]
        f = np.empty(i_all.shape)
        for sw in (0, 1):
            sel = cases == sw
            if sel.any():
                f[sel] = stat.masking_factor(rho[sel], i_all[sel], sw)
        out[some] = f.mean(axis=1)
        self._mask_draws = (some, snr[some], steady[some], fluctuating[some], case[some])
        return out

    def _outline_interference(self, view, rng_m: np.ndarray, on_bin: np.ndarray, cell_d: np.ndarray,
                              cell_r: np.ndarray, max_distance_m: float, outline: SharedOutline | None = None
                              ) -> np.ndarray:
        """What the bodies of energy ``on_bin`` (T, n; the whole body's at its nearest point in the field of view,
        its SNR's; 0: none) put into every actor's training ring (its cell ``cell_d``, ``cell_r``), (T, n): each body
        as its :func:`outline_points` (weighted as the scatterer levels share a body's RCS), of which only those
        inside the field of view reflect, each at its own range, radial speed and element-pattern gain. Measured on a
        truck stopped in the next lane beside a lead 8 m ahead, as the ego passes it at 4 m/s: the whole energy on the
        truck's nearest point gave the lead a masking factor of 0.0–0.16 once the edge of the field of view crossed
        the truck (its nearest point held there at the Doppler of 60°), where the detection level's scatterers give
        0.4–1.0."""
        p, stat, sc = self.preset, self.statistic, self.scene
        m, n_r = p.num_chirps, p.num_range_bins
        t_i, j_i = np.nonzero(on_bin > 0.0)
        # the points that reflect, flat: on a facing edge, inside the field of view
        px, py, r_s, az_s, weight, keep = visible_outline(p, view, t_i, j_i, sc.length_m, sc.width_m, max_distance_m) \
            if outline is None else outline.of(t_i, j_i)
        row = np.broadcast_to(np.arange(t_i.size)[:, None, None], keep.shape)[keep]
        px, py, r_s, az_s, weight = px[keep], py[keep], r_s[keep], az_s[keep], weight[keep]
        t_k, j_k = t_i[row], j_i[row]
        gain = equation.pattern_gain(p, az_s) / equation.pattern_gain(p, view.azimuth_rad[t_k, j_k])
        q = np.maximum(rng_m[t_k, j_k], 0.1) / np.maximum(r_s, 0.1)
        q *= q
        e_s = on_bin[t_k, j_k] * weight * (q * q) * gain                  # (its range over the point's)⁴
        v_s = (view.vx_mps[t_k, j_k] * px + view.vy_mps[t_k, j_k] * py) / np.maximum(r_s, 1e-9)
        pos_d, pos_r = np.mod(v_s / p.doppler_bin_mps, m), np.mod(r_s / p.range_resolution_m, n_r)          # (K,)
        dd = np.mod(pos_d[:, None] - cell_d[t_k] + m / 2.0, m) - m / 2.0                          # (K, n)
        dr = np.mod(pos_r[:, None] - cell_r[t_k] + n_r / 2.0, n_r) - n_r / 2.0
        put = stat.ring_kernel(dd, dr) * e_s[:, None]
        t_n, n = on_bin.shape[0], put.shape[1]
        # every (cycle, actor) sum in one bincount over the flat (point, actor) table: each sum in the points' order,
        # as a bincount per actor adds them
        at = (t_k * n)[:, None] + np.arange(n)
        return np.bincount(at.ravel(), weights=put.ravel(), minlength=t_n * n).reshape(t_n, n)

    def _averaged_gain_db(self, k0: int, gain_db: np.ndarray, detected: np.ndarray, first_hit: np.ndarray
                          ) -> tuple[np.ndarray, np.ndarray]:
        """The track's power average (gain RCS_GAIN per cycle) of the elevation factor ``gain_db`` (T, n) over
        the cycles k0 … k0+T−1, as the tracker keeps it: started at a track's first detection (``first_hit``),
        moved only in the cycles it is measured (``detected``), held while it coasts; continued from the tracker's
        state after the last cycle stepped (``gain``, in power; the second array returned). The ECU's overhead test
        estimates this start from the wire (:func:`radarnode.consumer.overhead.averaged_db`: the first detection
        taken one cycle before the track's first report). A recurrence over the chunk's cycles, vectorised over
        the actors (it runs only for scenes with structures above the road)."""
        x = 10.0 ** (gain_db / 10.0)
        before = self._trk.get("gain")
        prev = x[0].copy() if before is None else before.copy()
        y = np.empty_like(x)
        for k in range(x.shape[0]):
            moved = prev + RCS_GAIN * (x[k] - prev)
            prev = np.where(first_hit[k], x[k], np.where(detected[k], moved, prev))
            y[k] = prev
        return 10.0 * np.log10(np.maximum(y, 1e-30)), y

    def _reported_body(self, view, rng_m, az, rcs_eff, snr, z, ground) -> dict[str, np.ndarray]:
        """RCS, extent and class as the detection-level tracker reports them (``radarnode.perception.tracker``),
        drawn instead of copied from the truth, so that every level classes a body by the same rules.

        RCS: the power average over the cycles (relative spread √(g/(2−g)) for a fluctuating target, the
        amplitude noise 10^(−ρ/20)·√2 for a steady one). Extent: the faces the radar sees (the rear or front
        where the sensor is beyond the body's ends, a side where it is beside them), each measured only where it
        spans more than a resolution cell (range bins along x, the beam's cross-range width along y), reported
        along and across the body's heading when it moves (the ARS 408's length and width) and along the sensor's
        axes when it stands, as the tracker does; the class from extent, RCS and motion; at least the class's
        body.
        """
        p, sc = self.preset, self.scene
        steady = sc.swerling == 0
        spread = np.where(steady, math.sqrt(2.0) * 10.0 ** (-snr / 20.0), math.sqrt(RCS_GAIN / (2.0 - RCS_GAIN)))
        rcs = rcs_eff + 10.0 * np.log10(np.maximum(1.0 + spread * z[:, 10], 0.05))
        h = view.orientation_rad
        ch, sh = np.cos(h), np.sin(h)
        cx, cy = view.centre_x_m, view.centre_y_m
        L, W = sc.length_m, sc.width_m
        end_seen = np.abs(ch * cx + sh * cy) > L / 2.0           # sensor beyond the front or the rear
        side_seen = np.abs(-sh * cx + ch * cy) > W / 2.0        # sensor beside the body
        # a face is measured where it spans more than a resolution cell: range bins along x, the beam's cross-range
        # width along y (the side is the vector L·(cos h, sin h), the end W·(−sin h, cos h) in sensor axes)
        res_x, res_y = 2.0 * p.range_resolution_m, rng_m * p.angular_resolution_rad
        side_ok = side_seen & ((np.abs(L * ch) > res_x) | (np.abs(L * sh) > res_y))
        end_ok = end_seen & ((np.abs(W * sh) > res_x) | (np.abs(W * ch) > res_y))
        moving = ground >= MOVING_THRESHOLD_MPS
        # the measured faces' spans along and across the body's heading when it moves, along the sensor's axes when
        # it stands (as the tracker reports them: radarnode.perception.tracker.extents_along)
        d = np.where(moving, 0.0, h)
        cd, sd = np.abs(np.cos(d)), np.abs(np.sin(d))
        ext_a = np.where(side_ok, L * cd, 0.0) + np.where(end_ok, W * sd, 0.0)
        ext_c = np.where(side_ok, L * sd, 0.0) + np.where(end_ok, W * cd, 0.0)
        length = np.maximum(ext_a + p.size_sigma_m * z[:, 7], 0.2)
        width = np.maximum(ext_c + 0.5 * p.size_sigma_m * z[:, 8], 0.2)
        cls = classify(length, width, rcs, ground, moving)
        body = MIN_BODY_M[cls]
        return {"rcs_obj": rcs, "obj_class": cls, "length": np.maximum(length, body[..., 0]),
                "width": np.maximum(width, body[..., 1])}

    def _track_flags(self, det: np.ndarray, fov: np.ndarray, stationary: np.ndarray,
                     resolved: np.ndarray | None = None, walk_hits: int | None = None) -> dict[str, np.ndarray]:
        """The tracker's bookkeeping for a chunk of cycles, from its state before the chunk.

        Detection history, consecutive misses, confirmation (``CONFIRM_HITS`` of the last
        ``CONFIRM_WINDOW``) and loss (more than ``COAST_CYCLES`` misses, or out of the field of view) depend
        only on the detections, so they are computed for all cycles at once: ``alive`` is a set/reset
        latch — set by a confirmation, reset by a loss (the two never coincide: a detection needs the field
        of view) — i.e. the forward fill of the last event. Where ``resolved`` (T, n) is given (staggered ramps:
        the detection's speed unambiguous), a track is confirmed only once a resolved detection came since its
        last miss, as the tracker lists no track whose speed only ambiguous detections measured. ``walk_hits`` (a
        single ramp whose tracker resolves wraps from the range a track walks): a detection with at least this many
        in the last eight cycles resolves the track too.
        """
        t_n, n = det.shape
        prior = ((self.hist[None, :] >> np.arange(7, -1, -1)[:, None]) & 1).astype(bool)    # (8, n) oldest first
        ext = np.concatenate([prior, det]).astype(np.uint8)
        hist = np.zeros((t_n, n), dtype=np.uint8)
        for j in range(8):       # eight shifted slices, not a loop over cycles
            hist |= (ext[8 - j: 8 - j + t_n] << j).astype(np.uint8)
        # standing still over ground: confirmed over a longer window and coasting longer, as the tracker does
        # (radarnode.perception.tracker.COAST_STATIONARY_CYCLES)
        recent = np.where(stationary, _POPCOUNT_LOW5[hist], _POPCOUNT_LOW3[hist])
        steps = np.arange(t_n)[:, None]
        last = np.maximum.accumulate(np.where(det, steps, -1 - self.misses[None, :]), axis=0)
        misses = steps - last
        confirm = det & (recent >= CONFIRM_HITS) & self.reportable
        run_resolved = np.ones((t_n, n), dtype=bool)
        if resolved is not None and walk_hits is not None:
            resolved = resolved | (_POPCOUNT[hist] >= walk_hits)
        if resolved is not None:
            # the last resolved detection after the last miss (before the chunk: the state's flag says which)
            last_res = np.maximum.accumulate(np.where(det & resolved, steps, np.where(self.run_resolved, -1, -3)),
                                             axis=0)
            last_miss = np.maximum.accumulate(np.where(det, -2, steps), axis=0)
            run_resolved = last_res > last_miss
            confirm &= run_resolved
        loss = (misses > np.where(stationary, COAST_STATIONARY_CYCLES, COAST_CYCLES)) | ~fov
        event = np.where(confirm, 1, np.where(loss, -1, 0))
        at = np.maximum.accumulate(np.where(event != 0, steps, -1), axis=0)
        cols = np.broadcast_to(np.arange(n), at.shape)
        alive = np.where(at >= 0, event[np.maximum(at, 0), cols] == 1, self.alive[None, :])
        before = np.concatenate([self.alive[None, :], alive[:-1]])
        # the first detection of a track in the making: no other hit in its confirmation window, not alive before
        first_hit = det & ~before & (recent == 1)
        return {"detected": det, "hist": hist, "hits": _POPCOUNT[hist], "misses": misses, "alive": alive,
                "new": alive & ~before, "lost": before & ~alive, "first_hit": first_hit, "run_resolved": run_resolved}

    def _track(self, ch: dict) -> None:
        """The internal tracker over a chunk's cycles, from its state before the chunk: positions and velocities,
        the objects' IDs, DynProp, and the object list's rows.

        A detected actor takes its measurement; a continuing track's velocity is smoothed (an alpha filter, gain
        ``VELOCITY_GAIN``) from its prediction with the acceleration it reports (so a braking lead's speed does
        not lag by a·dt·(1−g)/g); an undetected one is predicted. Both are linear recurrences in the cycle,
        evaluated by :func:`affine_scan`. IDs change only where a track is confirmed or lost: a loop over those
        cycles gives a new object the lowest free ID. DynProp is computed from the sensor's true velocity; a
        step given the ego-motion input's estimate uses it unless the estimate is closer to the truth than every
        listed object is to a DynProp boundary (``slack``), where both give the same codes (:meth:`step`)."""
        times, trk = ch["times"], self._trk
        t_n, n = ch["detected"].shape
        det, alive, new = ch["detected"], ch["alive"], ch["new"]
        prev_t = self.last_t if self.cycle else times[0]
        dt = (times - np.concatenate([[prev_t], times[:-1]]))[:, None, None]
        meas = ch["meas"]
        g = VELOCITY_GAIN
        smooth = (det & alive & ~new)[..., None]
        # the velocity relative to the sensor, in the sensor's axes, changes by the relative acceleration less
        # ω × v, ω the axes' turn (the ego's yaw rate): a lead on the ego's bend at its speed keeps it, although
        # the two accelerate differently (both towards the bend's centre); with the acceleration alone the
        # smoothed velocity of that lead lagged by a few tenths of a m/s
        w = self.scene.yaw_rates(times)[:, None]
        a_dt = np.stack([ch["arel_long"] + w * ch["view"].vy_mps, ch["arel_lat"] - w * ch["view"].vx_mps],
                        axis=-1) * dt
        d3 = det[..., None]
        v = affine_scan(np.where(d3, np.where(smooth, 1.0 - g, 0.0), 1.0),
                        np.where(d3, np.where(smooth, (1.0 - g) * a_dt + g * meas[..., 2:4], meas[..., 2:4]), a_dt),
                        trk["state"][:, 2:4])
        v_before = np.concatenate([trk["state"][None, :, 2:4], v[:-1]])
        xy = affine_scan(np.where(d3, 0.0, 1.0), np.where(d3, meas[..., :2], v_before * dt), trk["state"][:, :2])
        state = np.concatenate([xy, v], axis=-1)
        # IDs: the lowest free one to each newly confirmed object, freed when it is lost
        ids = np.empty((t_n, n), dtype=np.int64)
        cur, k_prev = trk["obj_id"].copy(), 0
        for k in np.flatnonzero(new.any(axis=1) | ch["lost"].any(axis=1)):
            ids[k_prev:k] = cur
            cur[ch["lost"][k]] = -1
            used = set(cur[cur >= 0].tolist())
            free = (j for j in range(256) if j not in used)
            for a in np.flatnonzero(new[k]):      # the (rare) newly confirmed objects only
                cur[a] = next(free)
            k_prev = k
        ids[k_prev:] = cur
        # DynProp with the true sensor velocity; "stopped" once seen moving while listed
        svx, svy = ch["view"].sensor_vx_mps, ch["view"].sensor_vy_mps
        gx, gy = v[..., 0] + svx[:, None], v[..., 1] + svy[:, None]
        speed = np.hypot(gx, gy)
        moving = speed >= MOVING_THRESHOLD_MPS
        ever = np.logical_or.accumulate(alive & moving, axis=0) | trk["was_moving"]
        dyn = _dyn_codes(gx, gy, speed, moving, ever)
        # how far each object's ground velocity is from a DynProp boundary: the moving threshold's circle and
        # the ±45°/±135° heading lines (their full lines: a smaller slack, never a larger one)
        slack = np.abs(speed - MOVING_THRESHOLD_MPS)
        slack = np.where(moving, np.minimum(slack, np.minimum(np.abs(gx - gy), np.abs(gx + gy)) * math.sqrt(0.5)),
                         slack)
        ch["slack"] = np.min(np.where(alive, slack, np.inf), axis=1, initial=np.inf)
        ch["sv"] = (svx, svy)
        ch["ever0"] = trk["was_moving"]
        ch["by_cycle"] = False
        ch["trk"] = {"hist": ch["hist"], "misses": ch["misses"], "alive": alive, "obj_id": ids, "state": state,
                     "was_moving": ever, "run_resolved": ch["run_resolved"]}
        if "gain_power" in ch:          # structures above the road: their averaged elevation factor
            ch["trk"]["gain"] = ch["gain_power"]
        kk, aa = np.nonzero(alive)
        ch["starts"] = np.searchsorted(kk, np.arange(t_n + 1)).tolist()
        ch["obj_f"] = np.stack([state[kk, aa, 0], state[kk, aa, 1], state[kk, aa, 2], state[kk, aa, 3]]
                               + [ch[key][kk, aa] for _, key in _OBJECT_FLOATS])
        ch["obj_i"] = np.stack([ids[kk, aa], dyn[kk, aa]] + [ch[key][kk, aa].astype(np.int64, copy=False)
                                                            for _, key in _OBJECT_INTS] + [aa])

    def _settle(self) -> None:
        """Take the tracker's state out of the chunk row of the last step (before a new chunk is computed)."""
        pos = self.__dict__.get("_pos")
        if pos is not None:
            ch, i = pos
            self.__dict__["_trk"] = {name: np.array(values[i]) for name, values in ch["trk"].items()}
            self._pos = None

    def _row(self, t_s: float, config: RuntimeConfig) -> tuple[dict, int]:
        ch = self._cache
        pos = self.__dict__.get("_pos")
        if ch is not None and pos is not None and pos[0] is ch:      # the chunk's next row, at its time exactly
            i = pos[1] + 1
            times = ch["times_list"]
            if i < len(times) and t_s == times[i] and (config is ch["config"] or config == ch["config"]):
                return ch, i
        period = self.period_s
        k = int(round(t_s / period))
        on_grid = abs(t_s - k * period) <= 1e-9 * max(1.0, abs(t_s))
        # the chunk's next row: its tracker ran through every cycle before it. Any other step (a skipped cycle, a
        # step back, a time repeated or off the grid) starts a chunk there, from the state after the last step,
        # as a cycle-by-cycle tracker does
        if (ch is not None and pos is not None and pos[0] is ch and k == ch["k0"] + pos[1] + 1
                and k < ch["k0"] + ch["times"].size and ch["config"] == config
                and abs(ch["times"][k - ch["k0"]] - t_s) <= 1e-9 * max(1.0, abs(t_s))):
            return ch, k - ch["k0"]
        n = max(self.scene.n, 1)
        # a run starts with a full chunk (its length bounds it below); after a restart — a configuration change, a
        # skipped cycle, a step back — the chunks grow (128, 512, 1024 cycles) while each follows the last under the
        # same configuration: a flood of changes costs short chunks, a long run few passes
        follows = ch is not None and ch["config"] == config and k == ch["k0"] + ch["times"].size
        grown = int(min(CHUNK_CYCLES, CHUNK_GROWTH * ch["grown"] if follows
                        else CHUNK_CYCLES if ch is None else FIRST_CHUNK_CYCLES))
        size = int(min(grown, max(8, CHUNK_ACTOR_CYCLES // n),
                       max(8, CHUNK_OCCLUSION_CELLS // (n * n * OCCLUSION_SAMPLES))))
        if self.planned_cycles is not None:          # not past the run's last cycle …
            size = max(1, min(size, self.planned_cycles - k))
        else:                                        # … or, not knowing it, the scenario's (a run may go beyond)
            left = int(math.floor(self.scene.scenario.duration_s / period + 1e-9)) + 1 - k
            if left > 0:
                size = min(size, max(left, 8))
        if self.scene.dynamic_ego is not None:
            size = 1          # closed loop: the ego's future is not known in advance
        times = (k + np.arange(size)) * period if on_grid else np.array([t_s])
        if pos is not None:
            self._rewind_clusters(*pos)
        self._settle()
        self._cache = self._tables(self._chunk(k, times, config))
        self._cache["grown"] = grown
        self._cache["times_list"] = times.tolist()
        return self._cache, 0

    def step(self, t_s: float, config: RuntimeConfig, sensor_velocity_est: tuple[float, float] | None = None,
             cluster_list: bool = True) -> tuple[RadarFrame, SensorView]:
        """Advance to ``t_s`` and return the cycle's frame and the ground truth it came from.

        ``sensor_velocity_est`` is the sensor's velocity over ground (sensor axes)
        as the radar knows it from the ego-motion input; ``None`` uses the truth.
        The physics and the tracker of the next cycles (a chunk of up to
        ``CHUNK_CYCLES``) are computed in one vectorised pass and reused while the
        configuration stays the same: a step takes its cycle's rows. The lists'
        arrays are views of the chunk's tables: read them, do not write to them.
        ``cluster_list`` False: the frame's cluster list is left empty even where ``config.clusters`` asks for one,
        for a caller that reads the cycle's clusters from :meth:`cluster_rows` instead.
        """
        check_step(t_s, sensor_velocity_est)
        if sensor_velocity_est is not None and len(sensor_velocity_est) == 3:
            sensor_velocity_est = (sensor_velocity_est[0], sensor_velocity_est[1])   # (the yaw rate: truth here)
        ch, i = self._row(t_s, config)
        self._pos = (ch, i)
        self.last_t, self.cycle = t_s, self.cycle + 1
        view = ch["view"].row(i)
        s, e = ch["starts"][i], ch["starts"][i + 1]
        sv = (ch["sv"][0][i], ch["sv"][1][i]) if sensor_velocity_est is None else sensor_velocity_est
        by_cycle = ch["by_cycle"] or (sensor_velocity_est is not None
                                      and not math.hypot(sv[0] - ch["sv"][0][i], sv[1] - ch["sv"][1][i]) + 1e-9
                                      < ch["slack"][i])
        if e > s or by_cycle:
            f, g = (list(ch["obj_f"][:, s:e]), list(ch["obj_i"][:, s:e])) if e > s else _NO_OBJECT_ROWS
            if by_cycle:
                g = list(g)
                g[1] = self._dyn_cycle(ch, i, g[-1], f[2], f[3], sv)
            objects = _object_list(f, g)
        else:                   # a cycle without objects (half the cycles of a long run): its fields in one copy
            objects = object.__new__(ObjectList)
            objects.__dict__ = _NO_OBJECT_FIELDS.copy()
        self.info.at(ch, i, self.reportable)
        clusters = self._cluster_list(ch, i, sv) if config.clusters and cluster_list else _NO_CLUSTERS
        return RadarFrame(t_s, self.cycle - 1, objects, clusters), view

    def cluster_rows(self) -> tuple[np.ndarray, int, int]:
        """The last step's cluster list as rows of its block's table, for a reader of positions and velocities only
        (the road-boundary process, :mod:`radarnode.wire.pipeline`): the block's dist_long, dist_lat, vrel_long and
        vrel_lat, shape (4, m), one read-only array for every cycle of the block, and the
        cycle's rows a … b−1 of it — the values of the ClusterList :meth:`step` builds, without its DynProp, σ and
        the list object (step with ``cluster_list=False`` to skip those). The step's configuration must ask for
        clusters."""
        pos = self.__dict__.get("_pos")
        if pos is None or not pos[0]["config"].clusters:
            raise ValueError("cluster_rows: the last step computed no cluster list (no step yet, or a configuration "
                             "with clusters=False)")
        tab, j = self._cluster_table(*pos)
        return tab["rows"], tab["starts"][j], tab["starts"][j + 1]

    def _dyn_cycle(self, ch: dict, i: int, idx: np.ndarray, vx: np.ndarray, vy: np.ndarray, sv) -> np.ndarray:
        """DynProp of cycle i's objects with the sensor velocity ``sv`` (the ego-motion input's estimate), where
        the chunk's codes from the truth may differ; the rest of the chunk then goes the same way, its "seen
        moving" latch kept from the cycles stepped."""
        if ch["by_cycle"]:
            before = ch["ever_last"]
        else:
            before = ch["trk"]["was_moving"][i - 1] if i > 0 else ch["ever0"]
            ch["by_cycle"] = True
        gx, gy = vx + sv[0], vy + sv[1]
        speed = np.hypot(gx, gy)
        moving = speed >= MOVING_THRESHOLD_MPS
        ever = before.copy()
        ever[idx] |= moving
        ch["trk"]["was_moving"][i] = ever
        ch["ever_last"] = ever
        return _dyn_codes(gx, gy, speed, moving, ever[idx])

    def _posts(self, ch: dict, lo: int, hi: int) -> dict | None:
        """The guardrail posts the radar can see at the chunk's cycles lo … hi−1, and what does not depend on the
        draws: range, azimuth (true and as the radar sees it), SNR and Pd, flat, with each post's cycle (None: the scene
        has no guardrail posts). Element by element the same numbers as a cycle's own posts."""
        p, sc, config = self.preset, self.scene, ch["config"]
        g = sc.scenario.road.guardrails
        if not sc.is_guardrail.any() and g.left_offset_m is None and g.right_offset_m is None:
            return None
        gx, gy, starts = sc.guardrail_posts_many(ch["times"][lo:hi], p.max_range_m)
        g_r, g_az = np.hypot(gx, gy), np.arctan2(gy, gx)
        keep = in_fov(p, g_r, g_az) & (g_r <= config.max_distance_m)
        g_r, g_az = g_r[keep], g_az[keep]
        g_snr = equation.snr_db(p, g_r, g.rcs_dbsm, config.power_reduction_db, g_az)     # (one RCS: every post's)
        return {"cycle": lo + np.repeat(np.arange(starts.size - 1), np.diff(starts))[keep],
                "pd": self.statistic.pd_of_snr(g_snr, 1), "snr": g_snr, "range": g_r, "true_azimuth": g_az,
                "azimuth": ambiguity.apparent_azimuth(p, g_az)}

    @staticmethod
    def _post_accuracy(p: RadarPreset, g: dict) -> None:
        """The detected posts' measurement σ (the chain's accuracy at their SNR: point targets, no floor), added to
        their table ``g`` (computed for the posts kept only: a quarter of those in view on a guardrail road)."""
        er, ev, ea = chain_efficiency(g["snr"])
        bound_r, bound_v, bound_az = equation.crbs(p, g["snr"], g["azimuth"])
        g["sig_r"] = er * bound_r
        g["sig_az"] = ea * bound_az
        g["sig_v"] = ev * bound_v
        g["ea"] = ea

    def _cluster_table(self, ch: dict, i: int) -> tuple[dict, int]:
        """The cluster lists of the block of ``CLUSTER_BLOCK`` cycles holding the chunk's cycle i, and i's index in
        it (:meth:`_cluster_block`); the blocks are built in order, each when a cycle first asks for it, so that the
        cluster streams are read in cycle order."""
        blocks = ch.setdefault("cluster_blocks", [])
        while len(blocks) <= i // CLUSTER_BLOCK:
            lo = len(blocks) * CLUSTER_BLOCK
            blocks.append(self._cluster_block(ch, lo, min(lo + CLUSTER_BLOCK, ch["times"].size)))
        return blocks[i // CLUSTER_BLOCK], i % CLUSTER_BLOCK

    def _rewind_clusters(self, ch: dict, i: int) -> None:
        """Leaving a chunk after its row i: the cluster streams back to where cycle i's draws end, as if only the
        cycles up to i had drawn (its last block drew for the cycles after i too). The block's draws are taken
        again from its start up to cycle i: each stream is read in order, so they are the same numbers."""
        blocks = ch.get("cluster_blocks")
        if not blocks or i // CLUSTER_BLOCK >= len(blocks):
            return
        block = blocks[i // CLUSTER_BLOCK]
        m = i % CLUSTER_BLOCK + 1                        # the block's cycles kept
        if m == block["cycles"]:
            return
        rngs = self._cluster_rngs
        for name, state in block["states"].items():
            rngs[name].bit_generator.state = state
        rngs["hit"].random(int(np.count_nonzero(block["post_cycle"] < m)))
        rngs["noise"].standard_normal((int(np.count_nonzero(block["hit_cycle"] < m)), 3))
        counts = rngs["count"].poisson(block["rate"], size=m)
        rngs["value"].random((int(counts.sum()), 3))

    def _cluster_block(self, ch: dict, lo: int, hi: int) -> dict:
        """The cluster lists of the chunk's cycles lo … hi−1, before DynProp: the detected actors, the guardrail
        posts the draws detect and the false alarms, each cycle's rows near first, then far, each by range (ties in
        the order actors, posts, false alarms), at most ``MAX_CLUSTERS``; flat tables with ``starts`` like the
        objects'. Column by column, a block of cycles at once (a block, not the chunk: its arrays stay in cache)."""
        p, config, rngs, view = self.preset, ch["config"], self._cluster_rngs, ch["view"]
        t_n = hi - lo
        states = {name: g.bit_generator.state for name, g in rngs.items()}    # for _rewind_clusters
        post_cycle = hit_cycle = np.zeros(0, dtype=np.int64)
        svx, svy = view.sensor_vx_mps, view.sensor_vy_mps
        kk, aa = np.nonzero(ch["seen"][lo:hi] & self.reportable)
        # each part's rows of the _CL_* columns, and its cycles (0 … t_n − 1)
        parts = [(ch["cluster_actors"][lo + kk, aa], kk)]
        post_read = None                 # the posts' SNR and draws, for their RCS reading (_read_posts)
        # guardrail posts: stationary point targets
        g = self._posts(ch, lo, hi)
        if g is not None:
            u_hit = rngs["hit"].random(g["range"].size)
            hit = np.flatnonzero(u_hit < g["pd"])       # (indices: one pass over the mask, then a take a column)
            post_cycle = g["cycle"] - lo
            g = {key: val.take(hit) for key, val in g.items()}
            g["cos"], g["sin"] = np.cos(g["true_azimuth"]), np.sin(g["true_azimuth"])
            u_hit = u_hit.take(hit)
            # posts within the chain's resolution of a stronger one are its peak, not peaks of their own
            hit = np.flatnonzero(resolved_posts(p, g, u_hit, None, svx, svy, self.statistic.response))
            g = {key: val.take(hit) for key, val in g.items()}
            self._post_accuracy(p, g)
            # a staggered radar's second sequence, given the first (as for the actors: _second_look)
            second = None if not p.stagger_chirp_period_s else \
                u_hit.take(hit) < g["pd"] * self.statistic.pd_second_look(g["snr"], self.second_gain_db, 1)
            k = g["cycle"]
            hit_cycle = k - lo
            nz = rngs["noise"].standard_normal((k.size, 3))
            mr = g["range"] + g["sig_r"] * nz[:, 0]
            maz, endfire = ambiguity.measured_azimuth(p, g["azimuth"], g["sig_az"], nz[:, 1], g["snr"], g["ea"])
            # a stationary post moves at minus the sensor velocity; radar measures its radial part
            vr = -(svx[k] * g["cos"] + svy[k] * g["sin"]) + g["sig_v"] * nz[:, 2]
            vr_true = vr
            vr, g_amb = ambiguity.apparent_range_rate(p, vr, g["azimuth"], (svx[k], svy[k]), second)
            mr_read = mr
            mr = ambiguity.coupled_range(p, mr, vr_true, vr)
            cm, sm = np.cos(maz), np.sin(maz)
            # read at the range reported (the coupling an aliased speed leaves), as the other levels read it
            rcs = self.scene.scenario.road.guardrails.rcs_dbsm + ambiguity.range_db(mr_read, mr)
            if endfire.any():           # read with the element pattern at the angle measured (measured_azimuth)
                rcs = rcs + equation.pattern_moved_db(p, g["azimuth"], maz, endfire)
            post_read = (g["snr"], u_hit.take(hit) / g["pd"], len(parts))
            parts.append((_cluster_rows(mr * cm, mr * sm, vr * cm, vr * sm, rcs, g["sig_r"], g["sig_az"], g["sig_v"],
                                        -1, g_amb), k - lo))
        # false alarms: a Poisson count a cycle over the chain's whole map, uniform in its cells as the chain's are
        # (range bins out to the unambiguous range, Doppler bins, angle bins uniform in sin θ), kept where the chain
        # reports (the reported range, the sectors): drawn over the reported area itself, they came 1.3–2.4× as
        # often as the chain's (an independent tester's finding)
        pfa = self.statistic.cfar.pfa * (10.0 if config.high_sensitivity else 1.0)
        rate = pfa * p.num_cells * false_alarms_per_pfa_cell(pfa)
        counts = rngs["count"].poisson(rate, size=t_n)
        u = rngs["value"].random((int(counts.sum()), 3))
        if u.shape[0]:
            r_hi, v_hi = min(p.max_range_m, config.max_distance_m), p.max_unambiguous_speed_mps
            fr = p.num_range_bins * p.range_resolution_m * u[:, 0]
            faz = (np.arcsin(np.clip((u[:, 1] - 0.5) / p.element_spacing_wl, -1.0, 1.0)) if p.num_virtual >= 2
                   else np.zeros(u.shape[0]))
            fv = -v_hi + 2.0 * v_hi * u[:, 2]
            ok = in_fov(p, fr, faz) & (fr <= r_hi)
            fr, faz, fv, k = fr[ok], faz[ok], fv[ok], np.repeat(np.arange(t_n), counts)[ok]
            cf, sf = np.cos(faz), np.sin(faz)
            parts.append((_cluster_rows(fr * cf, fr * sf, fv * cf, fv * sf,
                                        13.0 - equation.snr_db(p, fr, np.zeros(fr.size)), p.range_resolution_m / 2,
                                        p.angular_resolution_rad / 2, p.speed_resolution_mps / 2, -1,
                                        AMBIG_UNAMBIGUOUS if ambiguity.unambiguous(p) else AMBIG_AMBIGUOUS), k))
        cols = np.concatenate([part[0] for part in parts]).T
        cyc = np.concatenate([part[1] for part in parts])
        r = np.hypot(cols[_CL_X], cols[_CL_Y])
        # by cycle; near first, then far, each by range; ties keep the parts' order: numpy's lexsort((r, far, cyc))
        # as two stable sorts, by range and then by the small integer cycle·2 + far (a radix sort, 7× faster)
        order = np.argsort(r, kind="stable")
        key = cyc.take(order) * 2 + (r.take(order) > p.near_range_m)
        order = order.take(np.argsort(key.astype(np.uint16 if t_n < 2 ** 15 else np.int64), kind="stable"))
        by_cycle = cyc[order]
        order = order[np.arange(order.size) - np.searchsorted(by_cycle, np.arange(t_n + 1))[by_cycle] < MAX_CLUSTERS]
        if post_read is not None:        # where the posts' rows went: their index among the posts, in the table's order
            first = sum(len(part[0]) for part in parts[:post_read[2]])
            at = order - first
            at = np.flatnonzero((at >= 0) & (at < post_read[0].size))
            post_read = (at, (order.take(at) - first), post_read[0], post_read[1])
        rows = np.empty((4, order.size))
        for k in range(4):                          # position and velocity: all a reader of rows needs (cluster_rows)
            cols[k].take(order, out=rows[k])
        rows.flags.writeable = False
        return {
            "cycles": t_n, "states": states, "post_cycle": post_cycle, "hit_cycle": hit_cycle, "rate": rate,
            "post_read": post_read, "rows": rows,
            "starts": np.searchsorted(cyc.take(order), np.arange(t_n + 1)).tolist(),
            # the rest of the table (_cluster_fields), made when a cycle's cluster list is first built from it
            "sorted": (cols, order, r)}

    def _cluster_fields(self, tab: dict) -> None:
        """The rest of a block's table (:meth:`_cluster_block`), made once, when a cycle's cluster list is first
        built from it (a reader of rows only, the road-boundary process, needs none of it): "f", the ClusterList's
        float fields after DynProp — position and velocity (``rows``), RCS, then sigma_to_xy(r, az, σr, σaz) with
        its cos and sin taken once, the speeds' σ; and the radial speed, azimuth, and its cos and sin DynProp is
        computed from —, "i" its integer fields and "near"."""
        cols, order, r = tab.pop("sorted")
        p = self.preset
        x, y, vx, vy = tab["rows"]
        rcs, s_r, s_az, s_v, actor, ambig = (c.take(order) for c in cols[4:])
        r = r.take(order)
        az = np.arctan2(y, x)
        c, s_ = np.cos(az), np.sin(az)
        ac, as_ = np.abs(c), np.abs(s_)
        lat = p.lateral_speed_sigma_mps
        actor = actor.astype(np.int64)
        tab["f"] = np.stack([x, y, vx, vy, rcs, np.sqrt((c * s_r) ** 2 + (r * s_ * s_az) ** 2),
                             np.sqrt((s_ * s_r) ** 2 + (r * c * s_az) ** 2), ac * s_v + as_ * lat,
                             as_ * s_v + ac * lat, vx * c + vy * s_, az, c, s_])
        tab["i"] = np.stack([np.where(actor >= 0, 1, 2), ambig.astype(np.int64), np.zeros(actor.size, dtype=np.int64),
                             actor])
        tab["near"] = r <= p.near_range_m

    #: the posts' second uniform is the digits of their detection's uniform below 2⁻²⁰ (:meth:`_read_posts`)
    _SPLIT = float(2 ** 20)

    def _read_posts(self, tab: dict) -> None:
        """The RCS the chain reads of the block's detected posts (:meth:`DetectionStatistic.reading`, Swerling 1),
        written into its table's RCS row, once, when a cycle's cluster list is first built from it (a reader of rows
        only, the road-boundary process, never needs it: 4 ms a block of 11,000 posts). No new random numbers: given
        the detection, v = u/Pd is uniform; its fluctuation is taken from 1 − v, as :func:`resolved_posts` takes a
        post's power from −ln v (the smaller v, the stronger), and the noise's quantile from v's digits below 2⁻²⁰
        (uniform, and independent of its leading 20 bits to 1e-6). The object level reported every post at the
        rail's nominal RCS where the other levels read a spread (guardrail_traffic: −3.0 dBsm always against
        quartiles −6.1 / −3.3 / −0.9 at the detection level within 30 m)."""
        at, idx, snr, v = tab.pop("post_read")
        tab["post_read"] = None
        if at.size:
            v = v.take(idx)
            read = self.statistic.reading(snr.take(idx), np.mod(v * self._SPLIT, 1.0), 1.0 - v, True)
            tab["f"][4, at] += 10.0 * np.log10(read)

    def _cluster_list(self, ch: dict, i: int, sv) -> ClusterList:
        """Cycle i's cluster list: its rows of the chunk's table (:meth:`_cluster_table`), DynProp from the sensor
        velocity ``sv`` the step was given."""
        tab, j = self._cluster_table(ch, i)
        if "sorted" in tab:
            self._cluster_fields(tab)
        if tab["post_read"] is not None:
            self._read_posts(tab)
        a, b = tab["starts"][j], tab["starts"][j + 1]
        f, g = list(tab["f"][:, a:b]), list(tab["i"][:, a:b])
        return ClusterList.of(np.arange(b - a, dtype=np.int64), f[0], f[1], f[2], f[3],
                              cluster_dyn_prop(f[9], f[10], sv, (f[11], f[12])), *f[4:9], g[0], g[1], g[2],
                              tab["near"][a:b], g[3])
