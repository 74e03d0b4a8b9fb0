"""Struct-of-arrays records for one radar cycle.

Every array of a list has shape (n,), one entry per object or cluster, in the
order the radar sends them. Positions and velocities are in the sensor frame
(x forward, y left); σ fields are one standard deviation in SI units.
"""

from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass

import numpy as np

# ARS 408 Obj_DynProp codes
DYN_MOVING, DYN_STATIONARY, DYN_ONCOMING, DYN_STATIONARY_CANDIDATE = 0, 1, 2, 3
DYN_UNKNOWN, DYN_CROSSING_STATIONARY, DYN_CROSSING_MOVING, DYN_STOPPED = 4, 5, 6, 7
DYN_NAMES = ("moving", "stationary", "oncoming", "stat.cand", "unknown", "cross.stat", "crossing", "stopped")
CLASS_NAMES = ("point", "car", "truck", "pedestrian", "motorcycle", "bicycle", "wide", "reserved")
# ARS 408 Cluster_AmbigState codes
AMBIG_INVALID, AMBIG_AMBIGUOUS, AMBIG_STAGGERED, AMBIG_UNAMBIGUOUS, AMBIG_STATIONARY = 0, 1, 2, 3, 4
AMBIG_NAMES = ("invalid", "ambiguous", "staggered ramp", "unambiguous", "stationary candidate")
# ARS 408 Obj_MeasState codes
MEAS_DELETED, MEAS_NEW, MEAS_MEASURED, MEAS_PREDICTED = 0, 1, 2, 3


def _empty(n: int, dtype: type = np.float64) -> np.ndarray:
    return np.zeros(n, dtype=dtype)


@functools.cache
def _names(cls: type) -> tuple[str, ...]:
    """A list class's field names, in order (once a class: ``dataclasses.fields`` costs more than a cycle's
    selection)."""
    return tuple(f.name for f in dataclasses.fields(cls))


class _Columns:
    """Shared behaviour of the struct-of-arrays lists: construction, length, selection, range."""

    INT_FIELDS: tuple[str, ...] = ()
    BOOL_FIELDS: tuple[str, ...] = ()

    @classmethod
    def empty(cls, n: int = 0):
        """A list of ``n`` zero entries (integer and boolean fields get their own dtypes)."""
        kw = {}
        for name in _names(cls):
            dtype = bool if name in cls.BOOL_FIELDS else np.int64 if name in cls.INT_FIELDS else np.float64
            kw[name] = _empty(n, dtype)
        return cls(**kw)

    @classmethod
    def of(cls, *values):
        """A list from its fields' arrays, in the fields' order: what ``cls(*values)`` makes, without the dataclass's
        ``__init__`` (the object level builds a list this way every cycle)."""
        out = object.__new__(cls)
        out.__dict__.update(zip(_names(cls), values))
        return out

    def __len__(self) -> int:
        return int(getattr(self, _names(type(self))[0]).shape[0])

    def take(self, index: np.ndarray):
        """A new list with the entries ``index`` (an integer or boolean array), in that order."""
        return type(self)(**{name: getattr(self, name)[index] for name in _names(type(self))})

    @classmethod
    def concat(cls, parts: list):
        """One list of the entries of ``parts``, in order."""
        return cls(**{name: np.concatenate([getattr(p, name) for p in parts]) for name in _names(cls)})


class _Planar:
    """Range of list entries given by longitudinal and lateral distance."""

    @property
    def range_m(self) -> np.ndarray:
        return np.hypot(self.dist_long_m, self.dist_lat_m)


@dataclass
class _Reported(_Columns, _Planar):
    """Fields objects and clusters share: ID, position and relative velocity (sensor frame), their σ."""

    id: np.ndarray
    dist_long_m: np.ndarray
    dist_lat_m: np.ndarray
    vrel_long_mps: np.ndarray
    vrel_lat_mps: np.ndarray
    dyn_prop: np.ndarray
    rcs_dbsm: np.ndarray
    dist_long_sigma_m: np.ndarray
    dist_lat_sigma_m: np.ndarray
    vrel_long_sigma_mps: np.ndarray
    vrel_lat_sigma_mps: np.ndarray


@dataclass
class ObjectList(_Reported):
    """One cycle's object list (ARS 408 messages 0x60B, 0x60C, 0x60D).

    Quality and extended fields are NaN (or -1 for codes) when the cycle did
    not carry them. ``actor_index`` links an object to its ground-truth actor
    (-1 when unknown, e.g. after decoding).
    """

    arel_long_sigma_mps2: np.ndarray
    arel_lat_sigma_mps2: np.ndarray
    orientation_sigma_rad: np.ndarray
    meas_state: np.ndarray
    prob_of_exist: np.ndarray  # ARS 408 code 0..7
    arel_long_mps2: np.ndarray
    arel_lat_mps2: np.ndarray
    obj_class: np.ndarray
    orientation_rad: np.ndarray
    length_m: np.ndarray
    width_m: np.ndarray
    actor_index: np.ndarray

    INT_FIELDS = ("id", "dyn_prop", "meas_state", "prob_of_exist", "obj_class", "actor_index")


@dataclass
class ClusterList(_Reported):
    """One cycle's cluster list (ARS 408 messages 0x701, 0x702): near clusters first, then far."""

    pdh0: np.ndarray            # false-alarm probability code 0..7
    ambig_state: np.ndarray
    invalid_state: np.ndarray
    is_near: np.ndarray         # bool
    actor_index: np.ndarray     # -1 for guardrail posts, false alarms and decoded clusters

    INT_FIELDS = ("id", "dyn_prop", "pdh0", "ambig_state", "invalid_state", "actor_index")
    BOOL_FIELDS = ("is_near",)


@dataclass
class RadarFrame:
    """What the radar reports for one cycle."""

    t_s: float
    cycle: int
    objects: ObjectList
    clusters: ClusterList


@dataclass
class Detections(_Columns):
    """One cycle's detections, the common output of the detection and signal models.

    ``range_rate_mps`` is negative when closing. ``actor_index`` is the ground
    truth the detection came from where the model knows it (-1: noise, clutter,
    merged from several actors, or unknown). ``snr_db`` is the estimated
    integrated SNR ρ (:func:`radarnode.radar.equation.snr_db`). ``ambig_state``
    is the ARS 408 Cluster_AmbigState of the range rate (:data:`AMBIG_NAMES`);
    left out, it is 3 (unambiguous). ``azimuth_spread_rad`` is the angle the
    reflector in the detection's cell spans as its array snapshot shows it
    (:mod:`radarnode.dsp.spread`; 0 for a point, left out: 0): its angle
    glints over about that much.
    """

    range_m: np.ndarray
    range_rate_mps: np.ndarray
    azimuth_rad: np.ndarray
    rcs_dbsm: np.ndarray
    snr_db: np.ndarray
    actor_index: np.ndarray
    ambig_state: np.ndarray | None = None
    azimuth_spread_rad: np.ndarray | None = None

    INT_FIELDS = ("actor_index", "ambig_state")

    def __post_init__(self) -> None:
        if self.ambig_state is None:
            self.ambig_state = np.full(np.shape(self.range_m), AMBIG_UNAMBIGUOUS, dtype=np.int64)
        if self.azimuth_spread_rad is None:
            self.azimuth_spread_rad = np.zeros(np.shape(self.range_m))

    @property
    def x_m(self) -> np.ndarray:
        return self.range_m * np.cos(self.azimuth_rad)

    @property
    def y_m(self) -> np.ndarray:
        return self.range_m * np.sin(self.azimuth_rad)
