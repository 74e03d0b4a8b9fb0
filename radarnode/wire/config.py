"""The ARS 408-21 configuration protocol beyond RadarConfiguration: list filters and collision detection.

:class:`ListFilters` holds what FilterCfg 0x202 configured and answers with FilterState_Header 0x203 and
FilterState_Cfg 0x204; :class:`CollisionDetection` holds what CollDetCfg 0x400 and CollDetRegionCfg 0x401
configured, evaluates the regions on each cycle's object list and answers with CollDetState 0x408,
CollDetRegionState 0x402 (one per region) and Obj_4_Warning 0x60E (one per object). The node
(:mod:`radarnode.wire.node`) decides when the frames go out; this module holds the state and the rules.

What the public ARS 408 material leaves open, and what radarnode does:

**Filters.** A filter is one criterion (``FilterCfg_Index``) for objects or clusters (``FilterCfg_Type``),
with ``Active`` and a [Min, Max] interval; a frame with ``FilterCfg_Valid`` 0 changes nothing. An item is
sent when it lies inside the interval of every *active* filter of its list type (bounds included). The
quantities, in the sensor frame (x forward, y left) and from the values the node sends:

=====  ===========  ======================================================================================
index  criterion    quantity
=====  ===========  ======================================================================================
0      NofObj       the number of items: at most Max are sent (the first by the node's priority —
                    nearest, or strongest with SortIndex RCS); a list is never padded up to Min
1      Distance     radial distance √(x² + y²), m
2      Azimuth      atan2(y, x), degrees
3, 4   VrelOncome,  the radial relative speed of items approaching (3) or receding (4), m/s, as a
       VrelDepart   magnitude; an item moving the other way (or not at all radially) passes the filter
5      RCS          dBm²
6      Lifetime     seconds since the node's tracker first reported the object (objects only)
7      Size         length × width, m² (objects only)
8      ProbExists   the Obj_ProbOfExist code 0..7 (objects only)
9, 10  Y, X         lateral and longitudinal distance, m
11,13  VYLeftRight, the lateral relative speed of items moving from left to right (11: VrelLat < 0) or right
       VYRightLeft  to left (13: VrelLat > 0), as a magnitude; other items pass
12,14  VXOncome,    the longitudinal relative speed of items approaching (12: VrelLong < 0) or receding
       VXDepart     (14: VrelLong > 0), as a magnitude; other items pass
=====  ===========  ======================================================================================

The index → criterion mapping is the DBC's multiplexer (the public ARS 408 DBC has VYLeftRight at 11 and
VYRightLeft at 13; some public driver headers list them the other way round — the DBC is what tools decode).
A cluster has no lifetime, size or probability of existence: a *cluster* filter on index 6, 7 or 8 is
refused. A filter is also refused for index 15 (reserved), a bound outside the signal's range (the 12-bit
fields can carry ProbExists codes up to 4095) or Min > Max; a refused filter leaves the table as it was.

Once set, a filter stays *configured* (active or not) until the node restarts: FilterState_Header counts the
configured cluster and object filters and one FilterState_Cfg per configured filter follows it (cluster
filters first, then object filters, each by index).

**Collision detection.** Up to eight rectangular regions (``RegionID`` 0..7) given by two opposite corners
in sensor coordinates. CollDetRegionCfg with ``Coordinates_valid`` sets a region's corners (and creates it);
without, it only switches an existing region on or off (for a region never given corners it is refused).
``Activate`` switches the region on or off. CollDetCfg switches collision detection on or off
(``Activate``), sets the minimum detection time with ``MinTime_valid``, clears every region
(``ClearRegions``) and resets the warnings (``WarningReset``); in that order.

While collision detection is on, each cycle every object of the list sent is tested against every active
region, on the values sent (DistLong/DistLat on their 0.2-m grid, the regions' corners on theirs, compared
as raw integers, bounds included — so a consumer can check the result exactly). An object *warns* in a region
once it has been inside it continuously for at least MinDetectTime (0: at once); its Obj_4_Warning carries
one bit per region it warns in. A region's warning is latched: WarningLevel 1 ("object warning") from the
first object that warned in it until a WarningReset (or new corners), 0 otherwise, 3 ("warning deactivated")
while the region is switched off or collision detection is off. NofObjects counts the objects inside the
region now, whether they warn yet or not. Collision detection works on the object list: with OutputType
clusters the regions see no objects.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radarnode.perception.types import ClusterList, ObjectList
from radarnode.wire import ars408 as P

TYPE_CLUSTER, TYPE_OBJECT = 0, 1
TYPE_NAMES = {TYPE_CLUSTER: "cluster", TYPE_OBJECT: "object"}
FILTER_NAMES = {0: "NofObj", 1: "Distance", 2: "Azimuth", 3: "VrelOncome", 4: "VrelDepart", 5: "RCS",
                6: "Lifetime", 7: "Size", 8: "ProbExists", 9: "Y", 10: "X", 11: "VYLeftRight", 12: "VXOncome",
                13: "VYRightLeft", 14: "VXDepart"}
NOFOBJ = 0
OBJECT_ONLY = frozenset({6, 7, 8})
NUM_REGIONS = 8
MAX_OBJECT_ID = 255          # Obj_ID is 8 bits

# Obj_DistLong / CollDetRegCfg_PointNX and Obj_DistLat / CollDetRegCfg_PointNY share scale and offset
_X_SCALE, _X_OFFSET, _X_RAW_MAX = 0.2, -500.0, 8191
_Y_SCALE, _Y_OFFSET, _Y_RAW_MAX = 0.2, -204.6, 2047


def _raw(value: np.ndarray, scale: float, offset: float, raw_max: int) -> np.ndarray:
    """The raw integer a value goes on the wire as (saturated like the codec, rounded like cantools)."""
    r = np.rint((np.asarray(value, dtype=np.float64) - offset) / scale)
    return np.clip(r, 0, raw_max).astype(np.int64)


@dataclass(frozen=True)
class Filter:
    """One configured filter: list type, criterion index, active flag and the interval (physical units)."""

    type: int
    index: int
    active: bool
    min: float
    max: float

    @property
    def name(self) -> str:
        return FILTER_NAMES[self.index]


class ListFilters:
    """The object and cluster filters configured by FilterCfg 0x202, and their application to a list.

    Parameters
    ----------
    database : cantools Database
        The ARS 408 DBC (FilterCfg, FilterState_Header, FilterState_Cfg are multiplexed: cantools encodes them).
    """

    def __init__(self, database) -> None:
        self._cfg = database.get_message_by_frame_id(P.FILTER_CFG)
        self._header = database.get_message_by_frame_id(P.FILTER_STATE_HEADER)
        self._state = database.get_message_by_frame_id(P.FILTER_STATE_CFG)
        self._limits = {s.name: (s.minimum, s.maximum) for s in self._cfg.signals}
        self.filters: dict[tuple[int, int], Filter] = {}

    def configure(self, data: bytes) -> tuple[Filter | None, str | None]:
        """Apply one FilterCfg payload.

        Returns (the filter now in force or None, the reason it was refused or None); (None, None) when
        ``FilterCfg_Valid`` is 0 (nothing to change).
        """
        v = self._cfg.decode(data, decode_choices=False, scaling=True)
        if not int(v["FilterCfg_Valid"]):
            return None, None
        ftype, index = int(v["FilterCfg_Type"]), int(v["FilterCfg_Index"])
        if index not in FILTER_NAMES:
            return None, f"FilterCfg_Index={index} is reserved (allowed 0..14)"
        name = FILTER_NAMES[index]
        if ftype == TYPE_CLUSTER and index in OBJECT_ONLY:
            return None, f"a cluster filter on {name} (index {index}) is not possible: clusters have no {name}"
        lo, hi = v[f"FilterCfg_Min_{name}"], v[f"FilterCfg_Max_{name}"]
        smin, smax = self._limits[f"FilterCfg_Min_{name}"]
        for which, x in (("Min", lo), ("Max", hi)):
            if not smin - 1e-9 <= x <= smax + 1e-9:
                return None, f"FilterCfg_{which}_{name}={x:g} is out of range (allowed {smin:g}..{smax:g})"
        if lo > hi + 1e-9:
            return None, f"FilterCfg_Min_{name}={lo:g} is above FilterCfg_Max_{name}={hi:g}"
        f = Filter(ftype, index, bool(int(v["FilterCfg_Active"])), float(lo), float(hi))
        self.filters[(ftype, index)] = f
        return f, None

    def state_payloads(self) -> list[tuple[int, bytes]]:
        """FilterState_Header 0x203 and one FilterState_Cfg 0x204 per configured filter, as (base ID, payload)."""
        n_cl = sum(1 for t, _ in self.filters if t == TYPE_CLUSTER)
        out = [(P.FILTER_STATE_HEADER, self._header.encode({
            "FilterState_NofClusterFilterCfg": n_cl, "FilterState_NofObjectFilterCfg": len(self.filters) - n_cl}))]
        for key in sorted(self.filters):
            f = self.filters[key]
            out.append((P.FILTER_STATE_CFG, self._state.encode({
                "FilterState_Active": int(f.active), "FilterState_Index": f.index, "FilterState_Type": f.type,
                f"FilterState_Min_{f.name}": f.min, f"FilterState_Max_{f.name}": f.max})))
        return out

    def active(self, ftype: int) -> list[Filter]:
        return [f for (t, _), f in sorted(self.filters.items()) if t == ftype and f.active]

    def max_count(self, ftype: int) -> int | None:
        """Max_NofObj of the active NofObj filter of ``ftype``, or None."""
        f = self.filters.get((ftype, NOFOBJ))
        return int(f.max) if f is not None and f.active else None

    def object_mask(self, ol: ObjectList, lifetime_s: np.ndarray) -> np.ndarray:
        """Which objects every active object filter (but NofObj) lets through; shape (n,), bool."""
        return self._mask(self.active(TYPE_OBJECT), ol, {
            6: lambda: (lifetime_s, None), 7: lambda: (ol.length_m * ol.width_m, None),
            8: lambda: (ol.prob_of_exist.astype(np.float64), None)})

    def cluster_mask(self, cl: ClusterList) -> np.ndarray:
        """Which clusters every active cluster filter (but NofObj) lets through; shape (n,), bool."""
        return self._mask(self.active(TYPE_CLUSTER), cl, {})

    @staticmethod
    def _mask(filters: list[Filter], lst, extra: dict) -> np.ndarray:
        n = len(lst)
        keep = np.ones(n, dtype=bool)
        if not filters or n == 0:
            return keep
        x, y = lst.dist_long_m, lst.dist_lat_m
        vx, vy = lst.vrel_long_mps, lst.vrel_lat_mps
        r = np.hypot(x, y)
        with np.errstate(invalid="ignore", divide="ignore"):
            vr = np.where(r > 0, (x * vx + y * vy) / np.where(r > 0, r, 1.0), 0.0)
        # criterion -> (value, where the criterion applies; None: everywhere)
        quantities = {
            1: lambda: (r, None), 2: lambda: (np.degrees(np.arctan2(y, x)), None),
            3: lambda: (-vr, vr < 0), 4: lambda: (vr, vr > 0), 5: lambda: (lst.rcs_dbsm, None),
            9: lambda: (y, None), 10: lambda: (x, None),
            11: lambda: (-vy, vy < 0), 12: lambda: (-vx, vx < 0), 13: lambda: (vy, vy > 0), 14: lambda: (vx, vx > 0),
            **extra}
        for f in filters:
            if f.index == NOFOBJ:
                continue
            value, applies = quantities[f.index]()
            inside = (value >= f.min - 1e-9) & (value <= f.max + 1e-9)
            keep &= inside if applies is None else (inside | ~applies)
        return keep


@dataclass
class Region:
    """One collision-detection region: corners as configured (m) and their raw wire values."""

    region_id: int
    active: bool
    point1: tuple[float, float]
    point2: tuple[float, float]
    warning: bool = False          # latched until a WarningReset

    def raw_box(self) -> tuple[int, int, int, int]:
        """(x_lo, x_hi, y_lo, y_hi) as raw integers of the 0.2-m grids."""
        xs = _raw(np.array([self.point1[0], self.point2[0]]), _X_SCALE, _X_OFFSET, _X_RAW_MAX)
        ys = _raw(np.array([self.point1[1], self.point2[1]]), _Y_SCALE, _Y_OFFSET, _Y_RAW_MAX)
        return int(xs.min()), int(xs.max()), int(ys.min()), int(ys.max())


@dataclass
class RegionResult:
    """One cycle's evaluation: per object the region bitfield, per region the objects inside (by region ID)."""

    bits: np.ndarray                 # (n_objects,) int64, bit r: the object warns in region r
    inside_count: np.ndarray         # (NUM_REGIONS,) int64


class CollisionDetection:
    """Collision detection as configured by CollDetCfg 0x400 and CollDetRegionCfg 0x401 (see the module doc)."""

    def __init__(self, database) -> None:
        self._state = database.get_message_by_frame_id(P.COLL_DET_STATE)
        self._region_state = database.get_message_by_frame_id(P.COLL_DET_REGION_STATE)
        self.active = False
        self.min_detect_time_s = 0.0
        self.regions: dict[int, Region] = {}
        # when each object ID entered each region (NaN: not inside), shape (NUM_REGIONS, 256)
        self._entry = np.full((NUM_REGIONS, MAX_OBJECT_ID + 1), np.nan)
        self.last = RegionResult(np.zeros(0, dtype=np.int64), np.zeros(NUM_REGIONS, dtype=np.int64))

    def configure(self, v: dict[str, float]) -> None:
        """Apply decoded CollDetCfg values (every combination of the bits is meaningful: nothing to refuse)."""
        if int(v["CollDetCfg_ClearRegions"]):
            self.regions.clear()
            self._entry[:] = np.nan
        if int(v["CollDetCfg_WarningReset"]):
            for r in self.regions.values():
                r.warning = False
        if int(v["CollDetCfg_MinTime_valid"]):
            self.min_detect_time_s = float(v["CollDetCfg_MinDetectTime"])
        active = bool(int(v["CollDetCfg_Activate"]))
        if not active:
            self._entry[:] = np.nan
        self.active = active

    def configure_region(self, v: dict[str, float]) -> str | None:
        """Apply decoded CollDetRegionCfg values; returns why it was refused, or None."""
        rid = int(v["CollDetRegCfg_RegionID"])
        active = bool(int(v["CollDetRegCfg_Activate"]))
        if int(v["CollDetRegCfg_Coordinates_valid"]):
            p1 = (float(v["CollDetRegCfg_Point1X"]), float(v["CollDetRegCfg_Point1Y"]))
            p2 = (float(v["CollDetRegCfg_Point2X"]), float(v["CollDetRegCfg_Point2Y"]))
            old = self.regions.get(rid)
            same = old is not None and (old.point1, old.point2) == (p1, p2)
            self.regions[rid] = Region(rid, active, p1, p2, warning=old.warning if same else False)
            if not same:
                self._entry[rid] = np.nan
            return None
        region = self.regions.get(rid)
        if region is None:
            return f"CollDetRegCfg_RegionID={rid} has no corners yet (send it with Coordinates_valid=1 first)"
        region.active = active
        if not active:
            self._entry[rid] = np.nan
        return None

    def evaluate(self, t_s: float, obj_id: np.ndarray, dist_long_m: np.ndarray, dist_lat_m: np.ndarray
                 ) -> RegionResult:
        """Test the objects sent this cycle against the active regions (vectorised over objects and regions).

        Parameters
        ----------
        t_s : float
            Scenario time of the cycle, s.
        obj_id, dist_long_m, dist_lat_m : ndarray, shape (n,)
            The objects as sent (IDs, positions in the sensor frame).
        """
        n = len(obj_id)
        slot = np.clip(np.asarray(obj_id, dtype=np.int64), 0, MAX_OBJECT_ID)
        boxes = np.full((NUM_REGIONS, 4), -1, dtype=np.int64)     # an empty box where no active region is
        boxes[:, 0] = 1
        boxes[:, 1] = 0
        if self.active:
            for rid, region in self.regions.items():
                if region.active:
                    boxes[rid] = region.raw_box()
        rx = _raw(dist_long_m, _X_SCALE, _X_OFFSET, _X_RAW_MAX)
        ry = _raw(dist_lat_m, _Y_SCALE, _Y_OFFSET, _Y_RAW_MAX)
        inside = ((rx[None, :] >= boxes[:, 0:1]) & (rx[None, :] <= boxes[:, 1:2])
                  & (ry[None, :] >= boxes[:, 2:3]) & (ry[None, :] <= boxes[:, 3:4]))    # (regions, n)
        prev = self._entry[:, slot]
        entered = np.where(inside, np.where(np.isnan(prev), t_s, prev), np.nan)
        self._entry[:] = np.nan
        self._entry[:, slot] = entered
        with np.errstate(invalid="ignore"):
            warns = inside & (t_s - entered >= self.min_detect_time_s - 1e-9)
        for rid in np.flatnonzero(warns.any(axis=1)):
            self.regions[int(rid)].warning = True
        weights = (1 << np.arange(NUM_REGIONS, dtype=np.int64))[:, None]
        bits = (warns * weights).sum(axis=0) if n else np.zeros(0, dtype=np.int64)
        self.last = RegionResult(bits.astype(np.int64), inside.sum(axis=1).astype(np.int64))
        return self.last

    def warning_level(self, region: Region) -> int:
        if not (self.active and region.active):
            return 3
        return 1 if region.warning else 0

    def relay_bits(self) -> int:
        """CollDetRelayCtrl_Param: one bit per region whose warning is latched."""
        return sum(1 << rid for rid, r in self.regions.items() if self.active and r.active and r.warning)

    def state_payloads(self, meas_counter: int) -> list[tuple[int, bytes]]:
        """CollDetState 0x408 and one CollDetRegionState 0x402 per region (by ID), as (base ID, payload)."""
        out = [(P.COLL_DET_STATE, self._state.encode({
            "CollDetState_Active": int(self.active), "CollDetState_NofRegions": len(self.regions),
            "CollDetState_MinDetectTime": min(self.min_detect_time_s, 25.5),
            "CollDetState_MeasCounter": meas_counter & 0xFFFF}))]
        for rid in sorted(self.regions):
            r = self.regions[rid]
            out.append((P.COLL_DET_REGION_STATE, self._region_state.encode({
                "CollDetRegState_WarningLevel": self.warning_level(r), "CollDetRegState_RegionID": rid,
                "CollDetRegState_Point1X": r.point1[0], "CollDetRegState_Point1Y": r.point1[1],
                "CollDetRegState_Point2X": r.point2[0], "CollDetRegState_Point2Y": r.point2[1],
                "CollDetRegState_NofObjects": min(int(self.last.inside_count[rid]), 255) if self.active else 0})))
        return out

    def state_dlcs(self) -> list[int]:
        """The DLCs of what :meth:`state_payloads` returns (for the bus-load budget before it is computed)."""
        return [self._state.length] + [self._region_state.length] * len(self.regions)


def inside_raw(dist_long_m: np.ndarray, dist_lat_m: np.ndarray, point1: tuple[float, float],
               point2: tuple[float, float]) -> np.ndarray:
    """Whether positions lie inside the box of two corners, compared on the wire's raw 0.2-m grids (for
    consumers that check a region's state against the object list)."""
    box = Region(0, True, point1, point2).raw_box()
    rx = _raw(dist_long_m, _X_SCALE, _X_OFFSET, _X_RAW_MAX)
    ry = _raw(dist_lat_m, _Y_SCALE, _Y_OFFSET, _Y_RAW_MAX)
    return (rx >= box[0]) & (rx <= box[1]) & (ry >= box[2]) & (ry <= box[3])


__all__ = ["CollisionDetection", "Filter", "FILTER_NAMES", "ListFilters", "Region", "RegionResult",
           "TYPE_CLUSTER", "TYPE_OBJECT", "inside_raw"]
