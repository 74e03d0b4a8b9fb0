"""ARS 408-21 protocol facts: frame IDs, sensor-ID shift, σ codes, and the list <-> signal mapping.

Both directions live here so the node and the consumer cannot disagree.
"""

from __future__ import annotations

import math

import numpy as np

from radarnode.perception.types import ClusterList, ObjectList

RADAR_CFG, RADAR_STATE = 0x200, 0x201
FILTER_CFG, FILTER_STATE_HEADER, FILTER_STATE_CFG = 0x202, 0x203, 0x204
SPEED_INFO, YAW_RATE_INFO = 0x300, 0x301
COLL_DET_CFG, COLL_DET_REGION_CFG, COLL_DET_REGION_STATE, COLL_DET_STATE = 0x400, 0x401, 0x402, 0x408
CLUSTER_STATUS, CLUSTER_GENERAL, CLUSTER_QUALITY = 0x600, 0x701, 0x702
OBJ_STATUS, OBJ_GENERAL, OBJ_QUALITY, OBJ_EXTENDED, OBJ_WARNING = 0x60A, 0x60B, 0x60C, 0x60D, 0x60E
VERSION_ID = 0x700
COLL_DET_RELAY = 0x008          # the one ID that is not shifted by the sensor ID
# radarnode's own messages (dbc/radarnode.dbc) are not shifted like these: see radarnode.wire.ids

INTERFACE_VERSION = 1
FIRMWARE_VERSION = (4, 30, 2)

OUTPUT_NONE, OUTPUT_OBJECTS, OUTPUT_CLUSTERS = 0, 1, 2
OUTPUT_CODES = {"none": OUTPUT_NONE, "objects": OUTPUT_OBJECTS, "clusters": OUTPUT_CLUSTERS}
SORT_CODES = {"none": 0, "range": 1, "rcs": 2}

# σ code tables: code i means σ < 0.005·(top/0.005)^(i/30); 31 is "invalid"
RMS_FLOOR = 0.005
RMS_TOP_LINEAR = 10.0
RMS_TOP_ANGLE_DEG = 180.0


def shifted(base_id: int, sensor_id: int) -> int:
    """The CAN ID of message ``base_id`` for sensor ``sensor_id`` (0..7)."""
    return base_id if base_id == COLL_DET_RELAY else base_id + 0x10 * sensor_id


def unshifted(can_id: int) -> tuple[int, int]:
    """Split a received ID into (base ID, sensor ID); sensor ID is 0 for IDs outside the radar's ranges."""
    for base in (RADAR_CFG, SPEED_INFO, COLL_DET_CFG, CLUSTER_STATUS, VERSION_ID):
        off = can_id - base
        if 0 <= off < 0x80 and (off & 0xF) <= 0xE:
            sensor = off >> 4
            return can_id - 0x10 * sensor, sensor
    return can_id, 0


def sigma_to_code(sigma: np.ndarray, top: float = RMS_TOP_LINEAR) -> np.ndarray:
    """Smallest ARS 408 σ code whose bound exceeds σ (0..30; NaN -> 31 "invalid")."""
    return _codes(np.asarray(sigma, dtype=np.float64), math.log(top / RMS_FLOOR))


def _codes(s: np.ndarray, log_span: float | np.ndarray) -> np.ndarray:
    """:func:`sigma_to_code` with log(top / RMS_FLOOR) given (a column of them: several σ fields in one pass)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        code = np.floor(30.0 * np.log(np.maximum(s, 1e-12) / RMS_FLOOR) / log_span) + 1.0
    code = np.clip(code, 0, 30)
    return np.where(np.isnan(s), 31, code).astype(np.int64)


#: Obj_2_Quality's σ fields (six linear, the orientation's in degrees) and log(top / RMS_FLOOR) for each, a column
_OBJECT_RMS = ("Obj_DistLong_rms", "Obj_DistLat_rms", "Obj_VrelLong_rms", "Obj_VrelLat_rms", "Obj_ArelLong_rms",
               "Obj_ArelLat_rms", "Obj_Orientation_rms")
_OBJECT_LOG_SPAN = np.array([math.log(RMS_TOP_LINEAR / RMS_FLOOR)] * 6
                            + [math.log(RMS_TOP_ANGLE_DEG / RMS_FLOOR)])[:, None]


def code_to_sigma(code: np.ndarray, top: float = RMS_TOP_LINEAR) -> np.ndarray:
    """Upper bound of σ that a code stands for (NaN for 31, invalid)."""
    c = np.asarray(code, dtype=np.float64)
    bound = RMS_FLOOR * (top / RMS_FLOOR) ** (c / 30.0)
    return np.where(c >= 31, np.nan, bound)


def object_signals(ol: ObjectList) -> tuple[dict, dict, dict]:
    """Signal values of Obj_1_General, Obj_2_Quality and Obj_3_Extended for every object."""
    general = {
        "Obj_ID": ol.id, "Obj_DistLong": ol.dist_long_m, "Obj_DistLat": ol.dist_lat_m,
        "Obj_VrelLong": ol.vrel_long_mps, "Obj_VrelLat": ol.vrel_lat_mps, "Obj_DynProp": ol.dyn_prop,
        "Obj_RCS": ol.rcs_dbsm,
    }
    sigmas = np.stack([ol.dist_long_sigma_m, ol.dist_lat_sigma_m, ol.vrel_long_sigma_mps, ol.vrel_lat_sigma_mps,
                       ol.arel_long_sigma_mps2, ol.arel_lat_sigma_mps2, np.degrees(ol.orientation_sigma_rad)])
    codes = _codes(sigmas.astype(np.float64, copy=False), _OBJECT_LOG_SPAN)      # the seven σ codes in one pass
    quality = {"Obj_ID": ol.id, **dict(zip(_OBJECT_RMS, codes)),
               "Obj_MeasState": ol.meas_state, "Obj_ProbOfExist": ol.prob_of_exist}
    extended = {
        "Obj_ID": ol.id, "Obj_ArelLong": ol.arel_long_mps2, "Obj_ArelLat": ol.arel_lat_mps2,
        # (an angle just past −180° is the direction just short of +180°: wrapped, not saturated at −180, a tester's
        # finding on pedestrian_crossing)
        "Obj_Class": ol.obj_class, "Obj_OrientationAngle": np.mod(np.degrees(ol.orientation_rad) + 180.0, 360.0) - 180.0,
        "Obj_Length": ol.length_m, "Obj_Width": ol.width_m,
    }
    return general, quality, extended


def cluster_signals(cl: ClusterList) -> tuple[dict, dict]:
    """Signal values of Cluster_1_General and Cluster_2_Quality for every cluster."""
    general = {
        "Cluster_ID": cl.id, "Cluster_DistLong": cl.dist_long_m, "Cluster_DistLat": cl.dist_lat_m,
        "Cluster_VrelLong": cl.vrel_long_mps, "Cluster_VrelLat": cl.vrel_lat_mps, "Cluster_DynProp": cl.dyn_prop,
        "Cluster_RCS": cl.rcs_dbsm,
    }
    quality = {
        "Cluster_ID": cl.id,
        "Cluster_DistLong_rms": sigma_to_code(cl.dist_long_sigma_m),
        "Cluster_DistLat_rms": sigma_to_code(cl.dist_lat_sigma_m),
        "Cluster_VrelLong_rms": sigma_to_code(cl.vrel_long_sigma_mps),
        "Cluster_VrelLat_rms": sigma_to_code(cl.vrel_lat_sigma_mps),
        "Cluster_PdH0": cl.pdh0, "Cluster_AmbigState": cl.ambig_state, "Cluster_InvalidState": cl.invalid_state,
    }
    return general, quality


def _col(rows: list[dict], name: str, default: float = np.nan) -> np.ndarray:
    return np.array([r.get(name, default) if r is not None else default for r in rows], dtype=np.float64)


def objects_from_signals(general: list[dict], quality: list[dict | None], extended: list[dict | None]) -> ObjectList:
    """Build an ObjectList from decoded frames (one dict per object; None where a group was absent)."""
    n = len(general)
    ol = ObjectList.empty(n)
    ol.id = _col(general, "Obj_ID").astype(np.int64)
    ol.dist_long_m, ol.dist_lat_m = _col(general, "Obj_DistLong"), _col(general, "Obj_DistLat")
    ol.vrel_long_mps, ol.vrel_lat_mps = _col(general, "Obj_VrelLong"), _col(general, "Obj_VrelLat")
    ol.dyn_prop = _col(general, "Obj_DynProp").astype(np.int64)
    ol.rcs_dbsm = _col(general, "Obj_RCS")
    ol.dist_long_sigma_m = code_to_sigma(_col(quality, "Obj_DistLong_rms", 31))
    ol.dist_lat_sigma_m = code_to_sigma(_col(quality, "Obj_DistLat_rms", 31))
    ol.vrel_long_sigma_mps = code_to_sigma(_col(quality, "Obj_VrelLong_rms", 31))
    ol.vrel_lat_sigma_mps = code_to_sigma(_col(quality, "Obj_VrelLat_rms", 31))
    ol.arel_long_sigma_mps2 = code_to_sigma(_col(quality, "Obj_ArelLong_rms", 31))
    ol.arel_lat_sigma_mps2 = code_to_sigma(_col(quality, "Obj_ArelLat_rms", 31))
    ol.orientation_sigma_rad = np.radians(code_to_sigma(_col(quality, "Obj_Orientation_rms", 31), RMS_TOP_ANGLE_DEG))
    ol.meas_state = _col(quality, "Obj_MeasState", -1).astype(np.int64)
    ol.prob_of_exist = _col(quality, "Obj_ProbOfExist", -1).astype(np.int64)
    ol.arel_long_mps2, ol.arel_lat_mps2 = _col(extended, "Obj_ArelLong"), _col(extended, "Obj_ArelLat")
    ol.obj_class = _col(extended, "Obj_Class", -1).astype(np.int64)
    ol.orientation_rad = np.radians(_col(extended, "Obj_OrientationAngle"))
    ol.length_m, ol.width_m = _col(extended, "Obj_Length"), _col(extended, "Obj_Width")
    ol.actor_index = np.full(n, -1, dtype=np.int64)
    return ol


def clusters_from_signals(general: list[dict], quality: list[dict | None], n_near: int) -> ClusterList:
    """Build a ClusterList from decoded frames; the first ``n_near`` are near-scan clusters."""
    n = len(general)
    cl = ClusterList.empty(n)
    cl.id = _col(general, "Cluster_ID").astype(np.int64)
    cl.dist_long_m, cl.dist_lat_m = _col(general, "Cluster_DistLong"), _col(general, "Cluster_DistLat")
    cl.vrel_long_mps, cl.vrel_lat_mps = _col(general, "Cluster_VrelLong"), _col(general, "Cluster_VrelLat")
    cl.dyn_prop = _col(general, "Cluster_DynProp").astype(np.int64)
    cl.rcs_dbsm = _col(general, "Cluster_RCS")
    cl.dist_long_sigma_m = code_to_sigma(_col(quality, "Cluster_DistLong_rms", 31))
    cl.dist_lat_sigma_m = code_to_sigma(_col(quality, "Cluster_DistLat_rms", 31))
    cl.vrel_long_sigma_mps = code_to_sigma(_col(quality, "Cluster_VrelLong_rms", 31))
    cl.vrel_lat_sigma_mps = code_to_sigma(_col(quality, "Cluster_VrelLat_rms", 31))
    cl.pdh0 = _col(quality, "Cluster_PdH0", -1).astype(np.int64)
    cl.ambig_state = _col(quality, "Cluster_AmbigState", -1).astype(np.int64)
    cl.invalid_state = _col(quality, "Cluster_InvalidState", -1).astype(np.int64)
    cl.is_near = np.arange(n) < n_near
    cl.actor_index = np.full(n, -1, dtype=np.int64)
    return cl
