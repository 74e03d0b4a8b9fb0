"""Is a stationary object a bridge or a sign gantry? The two-ray signature of its RCS on the wire (issue 10).

An ARS 408 measures no elevation. What it does report, every cycle, is the object's RCS — the power it receives,
as if the object stood on boresight in free space. For a reflector at height h above the road the road's
reflection makes that power swing with range (``radarnode.radar.elevation``): the two-way factor
|1 + Γ·exp(−j·2π·2·h_r·h/(λ·R))|⁴ has nulls every Δ(1/R) = λ/(2·h_r·h) — for a radar at 0.5 m and a deck edge
at 5 m, at 214, 183, 160, 142, 128 … m. A car's reflection centres spread over its height and the swings
average out: its RCS stays flat. The ECU knows its radar's mount height (calibrated), its carrier and how it
averages the RCS (in power, :data:`RCS_FILTER_GAIN` per cycle); so for every candidate height it can predict the
RCS-vs-range pattern of the history it has recorded, and test the history against it (Diewald et al.,
"Radar-interference-based bridge identification for collision avoidance systems", IEEE IV 2011):

* the correlation ``corr`` of the recorded RCS (dB) with the predicted pattern (dB), and the regression slope
  ``beta`` of the one on the other (1 for a true two-ray reflector with |Γ| ≈ 0.7; a flat, fluctuating car
  correlates by chance and then with a small slope);
* over the heights :data:`HEIGHT_MIN_M` … :data:`HEIGHT_MAX_M` (overhead clearances are at least 4 m), using
  only the samples at which the pattern's phase moves by at most :data:`MAX_PHASE_STEP` of a lobe per cycle
  (faster lobes are sampled too sparsely and averaged away by the sensor) and beyond :data:`MIN_RANGE_M` (where
  the far scan sees a structure as one reflector);
* the test is *mature* once the usable samples cover :data:`MIN_LOBES` lobes of a reflector at
  :data:`REFERENCE_HEIGHT_M`; an object is overhead when, mature, ``corr ≥`` :data:`CORR_MIN` and ``beta`` lies in
  [:data:`BETA_MIN`, :data:`BETA_MAX`] for some height in :data:`CONSECUTIVE` cycles in a row, that height
  steady within :data:`HEIGHT_STABLE_M` (a chance fit of a fluctuating car wanders from height to height). That
  decision is latched.

Measured (``benchmarks/overhead_cue.py``, BENCHMARKS.md): at 50, 90 and 100 km/h bridges and gantries are
recognised in 83 of 84 runs at 146–160 m, at their true height, and none of 168 stopped cars and trucks (straight
road, bend, under a bridge). At 130 km/h the lobes a sensor that averages its RCS can resolve (beyond ~116 m) come
too late: the test latches at ~120 m, after the 163 m at which a stationary object must be warned for, and took a
stopped truck for a bridge in 1 of 7 runs — which is why the ECU warns for stationary objects never seen moving
only up to ``fcw_stationary_max_speed_mps`` (``radarnode.consumer.ecu``).

The samples of one object are kept per *landmark* — a place in the ECU's odometry frame — so that when the
radar drops a track and creates another at the same place (as it does with wide structures) the history goes on.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

#: the sensor's RCS average: exponential in power, this gain per cycle (the ARS 408-like radar's tracker)
RCS_FILTER_GAIN = 0.2
GROUND_REFLECTION = -0.7          # the road's reflection coefficient the ECU assumes (asphalt at grazing incidence)
HEIGHT_MIN_M, HEIGHT_MAX_M, HEIGHT_STEP_M = 4.0, 8.0, 0.1
REFERENCE_HEIGHT_M = 5.0
MAX_PHASE_STEP = 0.25             # lobes per radar cycle
#: a radar track is reported from its confirmation, which follows its first detection by this many cycles at least
#: (2 hits: radarnode.perception.tracker, radarnode.radar.object_model): its RCS average began there
TRACK_LEAD_CYCLES = 1
MIN_RANGE_M = 60.0
MIN_LOBES = 2.5
MIN_SAMPLES = 40
CORR_MIN = 0.65
BETA_MIN, BETA_MAX = 0.65, 1.6
CONSECUTIVE = 8                   # cycles in a row the test must say "overhead" before it is latched …
HEIGHT_STABLE_M = 0.3             # … at a height that moves by no more than this from one cycle to the next
MAX_SAMPLES = 400                 # a landmark's history is capped (≈ 29 s of cycles)
#: a stationary track belongs to a landmark within these distances of it (odometry frame, m); across the road an
#: overhead landmark takes any track within OVERHEAD_MATCH_LAT_M (a bridge spans the road, and the radar reports
#: its parts as objects of their own as they come into the near scan)
MATCH_LONG_M, MATCH_LAT_M, OVERHEAD_MATCH_LAT_M = 4.0, 2.5, 25.0
#: a standing landmark whose RCS, averaged in power over its history, is at least this strong could be a structure's
#: (a bridge deck is 25 dBsm from the front and a gantry 20, their lobing adds up to 5 dB to the mean; a truck's rear
#: is 20, a car's 10, a guardrail post −5): across the road it reaches as far as a recognised one
#: (:meth:`LandmarkMap.structure_at`)
STRUCTURE_RCS_DBSM = 15.0
#: a landmark of an object reported this wide or wider is a structure's across the road (a deck or a gantry spans two
#: lanes and more; a truck is 2.5 m wide): :meth:`LandmarkMap.structure_at`
STRUCTURE_WIDTH_M = 6.0
#: :meth:`LandmarkMap.structure_at`'s answers
NO_STRUCTURE, STRUCTURE_POSSIBLE, STRUCTURE_WIDE, STRUCTURE_RECOGNISED = 0, 1, 2, 3
#: a vehicle that stood in the ECU's path this many cycles in a row (0.72 s) is continued by a track the radar creates
#: at its place after losing it (:meth:`Landmark.continues`); a shorter stay is no evidence (clutter on a guardrail road
#: is classed a car at times), nor is a car standing beside the path (a deck part over the lane near it is no car)
CONTINUE_MIN_CYCLES = 10
#: how deep an overhead structure may reach beyond its near edge (a motorway deck, m): what the radar reports of it
#: from underneath, moving as its Doppler makes it, belongs to it
OVERHEAD_DEPTH_M = 20.0
#: a track seen moving whose object came farther than this from where the ECU first saw it drove to its place: a
#: vehicle that stopped, never a part of a structure it stands under (parts glint within OVERHEAD_DEPTH_M of the deck)
DROVE_IN_M = 2.0 * OVERHEAD_DEPTH_M
#: landmarks take turns (are parts of one glinting structure) when measured together in at most this fraction of the
#: cycles the less frequent one was measured
POOL_SHARED = 0.25
#: a new track at a recognised structure's landmark while the structure's own track is alive is on probation for
#: this many of its samples; measured together with the structure in more than TOGETHER_SHARE of them, it is
#: another object (parts of one structure take turns)
TOGETHER_CYCLES, TOGETHER_SHARE = 6, 0.75
#: … if it was first seen beyond the near scan (the ARS 408's reaches 70 m: within it the radar resolves a
#: structure's parts, which it then measures together) by a margin for the track's confirmation
TOGETHER_MIN_RANGE_M = 80.0


def _along_across(cand: Landmark, x_m: float, y_m: float, c: float, s: float) -> tuple[float, float]:
    """Where landmark ``cand`` lies from the point (x_m, y_m), odometry frame: along and across the heading whose
    cosine and sine are ``c`` and ``s``."""
    dx, dy = cand.x_m - x_m, cand.y_m - y_m
    return c * dx + s * dy, -s * dx + c * dy


def two_ray_db(range_m: np.ndarray, height_m: np.ndarray, radar_height_m: float, wavelength_m: float,
               reflection: float = GROUND_REFLECTION) -> np.ndarray:
    """Two-way power factor (dB) of a reflector ``height_m`` above the road at ranges ``range_m``, far field
    (the elevation beam ≈ 1). Broadcasts ``height_m`` (H, 1) against ``range_m`` (N,) to (H, N)."""
    r = np.maximum(np.asarray(range_m, dtype=np.float64), 1.0)
    phase = 2.0 * radar_height_m * np.asarray(height_m, dtype=np.float64) / (wavelength_m * r)
    f = np.abs(1.0 + reflection * np.exp(-2j * np.pi * np.mod(phase, 1.0))) ** 4
    return 10.0 * np.log10(np.maximum(f, 1e-12))


def averaged_db(pattern_db: np.ndarray, starts: np.ndarray, gain: float = RCS_FILTER_GAIN,
                before_db: np.ndarray | None = None) -> np.ndarray:
    """What the sensor reports of a pattern (H, N) (dB): its power average along the samples, restarted at each
    index in ``starts``. A new radar track starts its average at its first detection; ``before_db`` (H, len(starts)),
    where given, is the pattern in the cycle before each track's first report — the detection that began the track
    one cycle before its confirmation (:data:`TRACK_LEAD_CYCLES`) — and otherwise the average starts at the first
    value reported."""
    import scipy.signal  # imported when first needed: a faster start
    x = 10.0 ** (pattern_db / 10.0)
    first = None if before_db is None else 10.0 ** (np.asarray(before_db) / 10.0)
    out = np.empty_like(x)
    bounds = list(starts) + [x.shape[1]]
    for j, (a, b) in enumerate(zip(bounds[:-1], bounds[1:])):   # one filter per radar track (a handful)
        if b <= a:
            continue
        seg = x[:, a:b]
        init = seg[:, :1] if first is None else first[:, j:j + 1]
        out[:, a:b], _ = scipy.signal.lfilter([gain], [1.0, gain - 1.0], seg, axis=1, zi=((1.0 - gain) * init))
    return 10.0 * np.log10(np.maximum(out, 1e-12))


def _detrend(v: np.ndarray, r: np.ndarray, w: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """Rows of ``v`` (H, N) less their weighted least-squares line in ``r`` (N,), weights ``w`` (H, N), fitted
    separately on each contiguous segment of samples starting at ``bounds`` (ascending, first 0): one line per
    radar track pooled into the history (the parts of one structure differ in level)."""
    def seg_sum(a: np.ndarray) -> np.ndarray:
        return np.repeat(np.add.reduceat(a, bounds, axis=1), sizes, axis=1)
    sizes = np.diff(np.append(bounds, v.shape[1]))
    s0 = np.maximum(seg_sum(w), 1.0)
    rm = seg_sum(w * r) / s0
    vm = seg_sum(w * v) / s0
    dr = r - rm
    slope = seg_sum(w * dr * (v - vm)) / np.maximum(seg_sum(w * dr * dr), 1e-12)
    return v - vm - slope * dr


def covered_lobes(range_m: np.ndarray, radar_height_m: float, wavelength_m: float,
                  height_m: float = REFERENCE_HEIGHT_M) -> float:
    """How many lobes of a reflector ``height_m`` up the ranges ``range_m`` cover: the phase span of their union,
    counting only gaps of at most :data:`MAX_PHASE_STEP` (samples of several tracks at the same ranges count once)."""
    phase = np.unique(2.0 * radar_height_m * height_m / (wavelength_m * np.maximum(range_m, 1.0)))
    step = np.diff(phase)
    return float(step[step <= MAX_PHASE_STEP].sum())


@dataclass
class Fit:
    """The best overhead height for a history and how well it fits."""

    mature: bool
    height_m: float = math.nan
    corr: float = 0.0
    beta: float = 0.0
    lobes: float = 0.0
    samples: int = 0

    @property
    def overhead(self) -> bool:
        return self.mature and self.corr >= CORR_MIN and BETA_MIN <= self.beta <= BETA_MAX


def fit_history(range_m: np.ndarray, rcs_dbsm: np.ndarray, starts: np.ndarray, radar_height_m: float,
                wavelength_m: float, members: np.ndarray | None = None, cycles: np.ndarray | None = None) -> Fit:
    """Test an RCS history (shape (N,), in the order received; ``starts``: indices where a radar track began)
    against the two-ray pattern of every overhead height (see the module docstring).

    ``members``: indices where the samples of another pooled landmark begin (ascending; each member's samples are
    contiguous and in the order received, and each begins a radar track): every member gets its own trend line,
    and the lobes count over the union of the members' ranges. ``cycles``: the cycle of each sample; the pattern's
    phase step that makes a sample usable is then taken between the structure's consecutive samples in time,
    whichever member they came from (each member's own average is modelled over its own samples)."""
    r = np.asarray(range_m, dtype=np.float64)
    y = np.asarray(rcs_dbsm, dtype=np.float64)
    if r.size < MIN_SAMPLES:
        return Fit(False, samples=int(r.size))
    bounds = np.array([0], dtype=np.int64) if members is None else np.asarray(members, dtype=np.int64)
    heights = np.arange(HEIGHT_MIN_M, HEIGHT_MAX_M + 1e-9, HEIGHT_STEP_M)[:, None]        # (H, 1)
    phase = 2.0 * radar_height_m * heights / (wavelength_m * np.maximum(r, 1.0))           # lobes, (H, N)
    if cycles is None:
        step = np.abs(np.diff(phase, axis=1, prepend=phase[:, :1]))
    else:
        order = np.argsort(np.asarray(cycles), kind="stable")
        step = np.empty_like(phase)
        step[:, order] = np.abs(np.diff(phase[:, order], axis=1, prepend=phase[:, order[:1]]))
    new = np.zeros(r.size, dtype=bool)
    new[np.asarray(starts, dtype=np.int64)] = True
    new[bounds] = True
    usable = (step <= MAX_PHASE_STEP) & (r >= MIN_RANGE_M) & ~new
    ref_phase = 2.0 * radar_height_m * REFERENCE_HEIGHT_M / (wavelength_m * np.maximum(r, 1.0))
    if cycles is None:
        ref = np.abs(np.diff(ref_phase, prepend=np.nan))
    else:
        ref = np.empty_like(ref_phase)
        ref[order] = np.abs(np.diff(ref_phase[order], prepend=np.nan))
    ref_ok = (ref <= MAX_PHASE_STEP) & (r >= MIN_RANGE_M) & ~new
    n_ok = int(np.count_nonzero(ref_ok))
    lobes = covered_lobes(r[ref_ok], radar_height_m, wavelength_m) if n_ok else 0.0
    if lobes < MIN_LOBES or n_ok < MIN_SAMPLES:
        return Fit(False, lobes=lobes, samples=n_ok)
    # each track's average began at its first detection, TRACK_LEAD_CYCLES before its first report: the pattern
    # there, at the range extrapolated back along the track's first two samples
    first = np.flatnonzero(new)
    nxt = np.minimum(first + 1, r.size - 1)
    step = np.where(new[nxt] | (nxt == first), 0.0, r[first] - r[nxt])
    t = averaged_db(two_ray_db(r, heights, radar_height_m, wavelength_m), first,
                    before_db=two_ray_db(r[first] + TRACK_LEAD_CYCLES * step, heights, radar_height_m, wavelength_m))
    w = usable.astype(np.float64)
    # both without their straight-line trend in range: a slow drift of the RCS (a car turning in a bend, the
    # azimuth pattern, a fade) is no lobing; the lobes of a reflector 4 m up and more repeat within the history
    ym = _detrend(np.broadcast_to(y, t.shape), r, w, bounds)
    tm = _detrend(t, r, w, bounds)
    syt = (w * ym * tm).sum(axis=1)
    stt = (w * tm * tm).sum(axis=1)
    syy = (w * ym * ym).sum(axis=1)
    corr = syt / np.sqrt(np.maximum(stt * syy, 1e-12))
    beta = syt / np.maximum(stt, 1e-12)
    corr = np.where(w.sum(axis=1) >= MIN_SAMPLES, corr, -1.0)
    k = int(np.argmax(corr))
    return Fit(True, float(heights[k, 0]), float(corr[k]), float(beta[k]), lobes, n_ok)


@dataclass
class Landmark:
    """A stationary object's place (odometry frame) and the RCS history of the radar tracks seen there."""

    x_m: float
    y_m: float
    range_m: list = field(default_factory=list)
    rcs_dbsm: list = field(default_factory=list)
    cycles: list = field(default_factory=list)      # the ECU cycle of each sample
    starts: list = field(default_factory=list)      # sample index where each radar track's history starts
    last_object: int | None = None
    overhead: bool = False                          # latched once the test says so
    moved: bool = False                             # a track seen moving stopped here: a vehicle, never overhead
    ground: bool = False                            # an object of its own beside a structure: never overhead
    obstacle: bool = False                          # a track filed here qualified as a collision candidate (the ECU)
    in_path: int = 0                                # cycles in a row its object was measured standing in the ECU's path
    crossed_path: bool = False                      # its object was measured standing in the ECU's path, once or more
    left: bool = False                              # a track filed here was later measured moving away from it
    fit: Fit | None = None
    streak: int = 0                                 # consecutive cycles the test said "overhead" at one height
    latched_range_m: float | None = None            # the range at which the overhead decision was latched
    latched_fit: Fit | None = None
    pooled: int = 1                                 # landmarks whose histories the last test pooled (itself too)
    power_sum: float = 0.0                          # Σ 10^(RCS/10) over the history kept (for its power mean)
    width_m: float = 0.0                            # the widest object filed here, as the radar reported it
    _last_height: float = math.nan

    def continues(self) -> bool:
        """A vehicle stood here in the ECU's path as a collision candidate for :data:`CONTINUE_MIN_CYCLES` cycles and
        was never measured moving away: a track the radar creates here after losing it is that vehicle again."""
        return self.obstacle and self.in_path >= CONTINUE_MIN_CYCLES and not self.left and not self.overhead

    def add(self, object_id: int, range_m: float, rcs_dbsm: float, cycle: int = -1) -> None:
        if object_id != self.last_object:
            self.starts.append(len(self.range_m))
            self.last_object = object_id
        self.range_m.append(range_m)
        self.rcs_dbsm.append(rcs_dbsm)
        self.cycles.append(cycle)
        self.power_sum += 10.0 ** (rcs_dbsm / 10.0)
        if len(self.range_m) > MAX_SAMPLES:
            drop = len(self.range_m) - MAX_SAMPLES
            self.power_sum = max(self.power_sum - sum(10.0 ** (v / 10.0) for v in self.rcs_dbsm[:drop]), 0.0)
            del self.range_m[:drop], self.rcs_dbsm[:drop], self.cycles[:drop]
            self.starts = [max(s - drop, 0) for s in self.starts]
            self.starts = sorted(set(self.starts))

    def evaluate(self, radar_height_m: float, wavelength_m: float, pool: list[Landmark] = ()) -> Fit:
        """Test this landmark's history, pooled with the histories of ``pool`` (other landmarks that are parts of
        the same structure: :meth:`LandmarkMap.pool`), and latch "overhead" after :data:`CONSECUTIVE` steady fits."""
        parts = [self, *pool]
        offsets = np.cumsum([0] + [len(p.range_m) for p in parts])
        starts = np.concatenate([np.asarray(p.starts, dtype=np.int64) + o for p, o in zip(parts, offsets)])
        self.fit = fit_history(np.concatenate([p.range_m for p in parts]),
                               np.concatenate([p.rcs_dbsm for p in parts]), starts, radar_height_m, wavelength_m,
                               members=offsets[:-1] if pool else None,
                               cycles=np.concatenate([p.cycles for p in parts]) if pool else None)
        self.pooled = len(parts)
        # a real reflector fits at its own height cycle after cycle; a chance fit wanders from height to height
        steady = self.fit.overhead and (self.streak == 0
                                        or abs(self.fit.height_m - self._last_height) <= HEIGHT_STABLE_M + 1e-9)
        self.streak = self.streak + 1 if steady else (1 if self.fit.overhead else 0)
        self._last_height = self.fit.height_m
        if not self.overhead and self.streak >= CONSECUTIVE and not self.moved and not self.ground:
            self.overhead, self.latched_range_m, self.latched_fit = True, self.range_m[-1], self.fit
        return self.fit


class LandmarkMap:
    """Stationary objects' landmarks along the drive; each cycle :meth:`observe` files the stationary tracks.

    **Pooling.** The radar sees a bridge deck as one range–Doppler cell of many reflectors across the road; the
    angle it measures wanders with their phases (glint: several metres either way at 150 m), so its tracker
    alternates between objects metres apart, each measured in every other cycle or less, and no one history holds
    enough samples for the test. The test therefore pools the histories of the landmarks at the same place along
    the road (within :data:`MATCH_LONG_M`) anywhere across it (:data:`OVERHEAD_MATCH_LAT_M`) that take turns —
    measured together in at most :data:`POOL_SHARED` of the cycles the less frequent one was measured — and never
    moved. A stopped car under the bridge is measured in the same cycles as the deck (two resolved reflectors):
    it keeps its own, flat history.

    **Probation.** A structure recognised, a new standing track across the road where it stands is taken for one of
    its parts (the radar reports a deck's parts as objects of their own as they come into view). On a bend a car
    standing under the deck comes into the far beam after the deck was recognised; so a new track first seen
    beyond the near scan (:data:`TOGETHER_MIN_RANGE_M`) while the structure's own track is alive is on probation
    for :data:`TOGETHER_CYCLES` samples, and measured together with the structure in more than
    :data:`TOGETHER_SHARE` of them, and in the ego's path then, it becomes an object of its own (``ground``: never
    overhead, never pooled); otherwise it is one of the structure's parts for good. (A deck's ends beyond the road
    are resolved from it in angle from about 130 m and measured together with it, and matter to no warning.)"""

    def __init__(self, radar_height_m: float, wavelength_m: float) -> None:
        self.radar_height_m = radar_height_m
        self.wavelength_m = wavelength_m
        self.landmarks: list[Landmark] = []
        self.by_track: dict[int, Landmark] = {}
        self.own: dict[int, Landmark] = {}         # tracks on probation at a structure's landmark
        self.cycle = 0

    def next_cycle(self) -> None:
        """A new radar cycle begins (the samples filed from here on are measured together)."""
        self.cycle += 1

    def pool(self, lm: Landmark, heading_rad: float) -> list[Landmark]:
        """The other landmarks whose histories :meth:`Landmark.evaluate` pools with ``lm``'s (class docstring)."""
        if lm.moved or lm.ground:
            return []
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        mine = set(lm.cycles)
        out = []
        for cand in self.landmarks:
            if cand is lm or cand.moved or cand.ground or not cand.range_m:
                continue
            along, across = _along_across(cand, lm.x_m, lm.y_m, c, s)
            if abs(along) > MATCH_LONG_M or abs(across) > OVERHEAD_MATCH_LAT_M:
                continue
            # taking turns: measured over the same stretch of time (a track that ended before the other began
            # takes no turns with it: a car that came into view after a deck's first track ended is no part)
            if cand.cycles[0] > lm.cycles[-1] or lm.cycles[0] > cand.cycles[-1]:
                continue
            shared = len(mine.intersection(cand.cycles))
            if shared <= POOL_SHARED * min(len(mine), len(cand.cycles)):
                out.append(cand)
        return out

    def observe(self, track_id: int, object_id: int, x_m: float, y_m: float, heading_rad: float, range_m: float,
                rcs_dbsm: float, moved: bool = False, in_path: bool = True, drove_m: float = 0.0,
                width_m: float = 0.0) -> Landmark:
        """File a stationary track at odometry-frame position (x_m, y_m) with the ego's heading ``heading_rad``
        (matching is along and across the ego's heading); returns its landmark, re-evaluated. ``moved``: the
        track was seen moving (a vehicle that stopped: its landmark is never overhead, and a new track the radar
        creates there later inherits that it moved). ``in_path``: the track is in the ego's predicted path (a track
        on probation at a structure is released as an object of its own only if it is there when its probation ends,
        where a car under the structure matters: the structure's parts beyond the road are measured together with
        it too). ``drove_m``: how far the track's object came from where it was first seen; seen moving and farther
        than :data:`DROVE_IN_M`, it drove here and stopped, and a recognised structure it stands under does not take
        it (a lead that stopped with its rear under a deck was filed as one of the deck's parts and never warned
        for)."""
        lm = self.by_track.get(track_id)
        if lm is None:
            # a landmark another live track is filed at is that track's: two objects seen at once are two
            # (a post of the guardrail beside a stopped car must not mix into the car's history)
            busy = {id(v) for v in self.by_track.values()}
            lm = self.match(x_m, y_m, heading_rad, exclude=busy)
            if lm is not None and lm.overhead and moved and drove_m > DROVE_IN_M:
                lm = None                        # a vehicle that drove here and stopped: a place of its own
            if lm is not None and lm.overhead and id(lm) in busy:
                # a structure's track is alive: an object that stood here on its own, measured together with the
                # structure, is back (the radar lost a car under a deck for a while), not one of the structure's parts
                lm = self.separate(x_m, y_m, heading_rad, lm, busy) or lm
            if lm is None:
                lm = Landmark(x_m, y_m)
                self.landmarks.append(lm)
            elif lm.overhead and id(lm) in busy and range_m >= TOGETHER_MIN_RANGE_M:
                # a recognised structure's track is alive: this one is one of its parts if the two take turns
                # (glint), another object if they are measured together (a car that came into view under it)
                self.own[track_id] = Landmark(x_m, y_m)
            self.by_track[track_id] = lm
        lm.moved |= moved
        if math.isfinite(width_m) and width_m > lm.width_m:
            lm.width_m = width_m
        if math.isfinite(rcs_dbsm) and math.isfinite(range_m) and not lm.moved:
            lm.add(object_id, range_m, rcs_dbsm, self.cycle)
            if not lm.overhead:
                lm.evaluate(self.radar_height_m, self.wavelength_m, self.pool(lm, heading_rad))
            own = self.own.get(track_id)
            if own is not None:
                own.add(object_id, range_m, rcs_dbsm, self.cycle)
                if len(own.cycles) > TOGETHER_CYCLES:
                    # the cycles before this one, now that every track of them was filed
                    mine = own.cycles[:-1]
                    counts = Counter(lm.cycles)          # this track's own sample and another's: measured together
                    together = sum(counts[c] >= 2 for c in mine)
                    del self.own[track_id]
                    if in_path and together > TOGETHER_SHARE * len(mine):
                        own.ground = True
                        self.landmarks.append(own)
                        self.by_track[track_id] = lm = own
        return lm

    def separate(self, x_m: float, y_m: float, heading_rad: float, structure: Landmark,
                 busy: set[int] | None = None) -> Landmark | None:
        """A free landmark at (x_m, y_m) of an object of its own beside ``structure`` (a recognised structure's
        landmark): not overhead, never moved, and measured together with the structure in more than
        :data:`POOL_SHARED` of its cycles (the structure's parts take turns with it: glint), and a vehicle that stood
        in the ECU's path (:meth:`Landmark.continues`: a car parked beside the lane under a deck does not make the deck's
        part over the lane near it a car), or None."""
        if busy is None:
            busy = {id(v) for v in self.by_track.values()}
        best = self.match(x_m, y_m, heading_rad, exclude=busy,
                          only=lambda cand: cand.continues() and not cand.moved and bool(cand.cycles))
        if best is None:
            return None
        shared = len(set(best.cycles).intersection(structure.cycles))
        return best if shared > POOL_SHARED * len(best.cycles) else None

    def match(self, x_m: float, y_m: float, heading_rad: float, overhead_only: bool = False,
              beyond_m: float = 0.0, exclude: set[int] = frozenset(),
              only: Callable[[Landmark], bool] | None = None) -> Landmark | None:
        """The landmark at odometry-frame (x_m, y_m), matched along and across the ego's heading (see
        :data:`MATCH_LONG_M`); ``overhead_only``: only an overhead one; ``beyond_m``: the point may also lie up to
        this much farther along than the landmark (the deck behind a bridge's near edge); ``only``: only landmarks
        for which it is true."""
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        best, best_d = None, math.inf
        for cand in self.landmarks:
            if (overhead_only and not cand.overhead) or (id(cand) in exclude and not cand.overhead) \
                    or (only is not None and not only(cand)):
                continue
            along, across = _along_across(cand, x_m, y_m, c, s)
            lat = OVERHEAD_MATCH_LAT_M if cand.overhead else MATCH_LAT_M
            if -MATCH_LONG_M - beyond_m <= along <= MATCH_LONG_M and abs(across) <= lat and abs(along) < best_d:
                best, best_d = cand, abs(along)
        return best

    def structure_at(self, x_m: float, y_m: float, heading_rad: float) -> int:
        """Whether a structure could stand where a track is first seen, at odometry-frame (x_m, y_m): a landmark no
        vehicle stood at (never moved, no object of its own beside a structure) from MATCH_LONG_M beyond the point
        to MATCH_LONG_M + OVERHEAD_DEPTH_M before it along the ego's heading (the ECU places a reflector above the
        road at its slant range, beyond where it stands), and across within MATCH_LAT_M — or within
        OVERHEAD_MATCH_LAT_M for one recognised as overhead or as strong as a structure (STRUCTURE_RCS_DBSM: a deck's
        reported point glints across the road, on a bend metres from where its landmark was filed).
        :data:`STRUCTURE_RECOGNISED` where such a landmark is recognised as overhead, else :data:`STRUCTURE_WIDE`
        where one was reported as wide as a structure (STRUCTURE_WIDTH_M) and measured standing in the ECU's path
        (:attr:`Landmark.crossed_path`), else :data:`STRUCTURE_POSSIBLE` where one
        is, :data:`NO_STRUCTURE` where none is."""
        c, s = math.cos(heading_rad), math.sin(heading_rad)
        strong = 10.0 ** (STRUCTURE_RCS_DBSM / 10.0)
        found = NO_STRUCTURE
        for cand in self.landmarks:
            if cand.moved or cand.ground:
                continue
            along, across = _along_across(cand, x_m, y_m, c, s)
            across = abs(across)
            if not -MATCH_LONG_M - OVERHEAD_DEPTH_M <= along <= MATCH_LONG_M or across > OVERHEAD_MATCH_LAT_M:
                continue
            if cand.overhead:
                return STRUCTURE_RECOGNISED
            if across <= MATCH_LAT_M or (cand.range_m and cand.power_sum >= strong * len(cand.range_m)):
                # wide as a structure across the road, and seen where it crosses the ego's path (a truck parked
                # crosswise beside the road is as wide, 12 m, and a creeping car first seen 6 m beside it was never
                # followed: an independent tester's finding)
                wide = cand.width_m >= STRUCTURE_WIDTH_M and cand.crossed_path
                found = max(found, STRUCTURE_WIDE if wide else STRUCTURE_POSSIBLE)
        return found

    def forget(self, alive: set[int], ego_x_m: float, ego_y_m: float, keep_m: float = 300.0) -> None:
        """Drop the tracks that ended and the landmarks far behind the ego."""
        self.by_track = {k: v for k, v in self.by_track.items() if k in alive}
        self.own = {k: v for k, v in self.own.items() if k in alive}
        kept = set(map(id, self.by_track.values()))
        self.landmarks = [lm for lm in self.landmarks
                          if id(lm) in kept or math.hypot(lm.x_m - ego_x_m, lm.y_m - ego_y_m) <= keep_m]


__all__ = ["Fit", "Landmark", "LandmarkMap", "averaged_db", "covered_lobes", "fit_history", "two_ray_db"]
