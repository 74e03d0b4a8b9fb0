"""Velocity ambiguity, resolved as production radars resolve it, and flagged where it cannot be.

A chirp sequence with repetition period T measures the radial speed only
modulo 2·v_max, v_max = λ/(4T). Two things resolve it:

* **Staggered ramps** (the ARS 408's AmbigState "staggered ramp"): a second
  chirp sequence in the same cycle with another period T₂ aliases the same
  speed differently. Of the candidates v₁ + 2k₁·v_max,1 within the sensor's
  speed span, the one that a candidate v₂ + 2k₂·v_max,2 of the second
  sequence meets within a tolerance is the speed (Chinese-remainder search;
  the wrong candidates miss by at least the beat of the two lattices, e.g.
  4.9 m/s for ``ars408_like``). Unique over a span of
  2·v_max,1·p where T₂/T₁ = (p + 1)/p.
* **A resolved neighbour** (AmbigState 2 too): a reflector the second
  sequence missed, within a car's length and a beamwidth of one it resolved, whose
  measured speed is that speed modulo 2·v_max,1 (within a Doppler bin),
  is taken for another reflector of the same body and takes that wrap of its own
  measurement. A car has several reflectors in a cell; the pairing is one to
  one, so the first sequence's extra ones stayed at their alias, and the
  trackers listed an oncoming convoy as cars receding at +4.9 m/s.
* **Stationary candidates** (AmbigState 4): with the ego motion known, a
  stationary reflector at azimuth θ has range rate −(v_x cosθ + v_y sinθ);
  a detection that equals it modulo 2·v_max is unwrapped to it.

Everything else keeps its measured (aliased) speed and is flagged
ambiguous (AmbigState 1): never silently wrapped. A single ramp whose
alias speed reaches ``UNAMBIGUOUS_SPEED_MPS`` (the ARS 408 data sheet's
400 km/h closing, faster than any two road users) has nothing to resolve:
its detections are "unambiguous" (AmbigState 3). AmbigState 0 ("invalid")
is never given: every detection has a measured speed. All levels call the same
functions on their detections, so aliasing and its resolution agree.
"""

from __future__ import annotations

import math

import numpy as np

from radarnode.perception.types import AMBIG_AMBIGUOUS, AMBIG_STAGGERED, AMBIG_STATIONARY, AMBIG_UNAMBIGUOUS, Detections
from radarnode.radar import equation
from radarnode.radar.presets import STAGGER_MAX_WRAPS, STAGGER_TOLERANCE_MPS, RadarPreset

#: a detection within this many Doppler bins of the stationary hypothesis is a stationary candidate
STATIONARY_TOLERANCE_BINS = 2.0
#: a single ramp that measures this range rate without aliasing measures every road user's (400 km/h closing)
UNAMBIGUOUS_SPEED_MPS = 400.0 / 3.6
_K = np.arange(-STAGGER_MAX_WRAPS, STAGGER_MAX_WRAPS + 1)     # wraps considered on each side
#: an ambiguous detection this close in range (or within 1.5 range cells, if more) and within a beamwidth of one
#: the staggered pair resolved may be another reflector of its body (:func:`resolve_by_neighbours`): a car's length
NEIGHBOUR_REACH_M = 5.0


def spatial_frequency(preset: RadarPreset, azimuth_rad: np.ndarray) -> np.ndarray:
    """d·sinθ modulo 1, in [−½, ½): the phase step between elements the beamformer measures, cycles."""
    return np.mod(preset.element_spacing_wl * np.sin(azimuth_rad) + 0.5, 1.0) - 0.5


def apparent_azimuth(preset: RadarPreset, azimuth_rad: np.ndarray) -> np.ndarray:
    """The azimuth an array measures: :func:`spatial_frequency` back to an angle (grating lobes where the element
    spacing d exceeds λ/2), as the signal chain's beamformer and the detection level see it. A one-channel radar
    measures no angle (its beam's direction is its angle): the azimuth is returned as it is, as for d ≤ λ/2."""
    az = np.asarray(azimuth_rad, dtype=np.float64)
    d = preset.element_spacing_wl
    if preset.num_virtual < 2 or d <= 0.5:
        return az
    return np.arcsin(np.clip(spatial_frequency(preset, az) / d, -1.0, 1.0))


#: beyond this angle (every shipped preset's field of view ends at 75° or less) a measured angle's noise is drawn in
#: d·sinθ, where the array measures it (:func:`measured_azimuth`); within it, in angle with the bound's 1/cosθ, whose
#: curvature misses the arcsine's by ½·tanθ·σ_θ: 5 % of σ_θ at 75°, 10 % at 80° (mimo12, ρ 20 dB)
ENDFIRE_RAD = math.radians(80.0)
#: … and wherever the wrap of d·sinθ at ±½ (the visible edge ±d where d < ½) lies within this many of its σ: there the
#: chain reads a return on the other side (or at its scan's edge) in some frames, which a draw in angle, wrapping only
#: past ±90°, does far more rarely (a −4-dBsm point at 60 m, ρ ≈ 16 dB, at 79.9° on mimo12: 0.014 of the frames
#: against the chain's 0.044; 0.09 and 0.095 at 80.1°: an independent tester's finding). Beyond 5σ the draw in angle
#: misses a wrap the chain has in fewer than 3 of 10⁷ frames
WRAP_REACH_SIGMA = 5.0
#: the chain's beamformer grid (``radarnode.radar.chain.DspConfig.doa_fft_size``'s default): where d < ½ it reads
#: no angle beyond half a bin inside its last bin inside the visible ±d (its peak refined towards the bin inside; at
#: d = 0.4: 82.40° for a return at 85°, 88° or 89.5°, measured); at d = ½ the grid reaches ±90°
CHAIN_DOA_BINS = 256


def measured_azimuth(preset: RadarPreset, azimuth_rad: np.ndarray, sigma_rad: np.ndarray, n: np.ndarray,
                     snr_db: np.ndarray, efficiency: np.ndarray, floor_rad: np.ndarray | float = 0.0,
                     where: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(angle, where drawn in d·sinθ): the angle the chain reports for a return at ``azimuth_rad`` (as the array sees
    it: :func:`apparent_azimuth`) with the standard normal draws ``n``: ``azimuth_rad + sigma_rad·n``; near endfire
    (beyond :data:`ENDFIRE_RAD`), wherever the wrap lies within :data:`WRAP_REACH_SIGMA` of its σ, and wherever that
    draw leaves ±90°, drawn where the array measures it instead: d·sinθ plus the noise there (the angle bound at
    boresight times d, times the chain's ``efficiency`` at ``snr_db``; a body's floor ``floor_rad`` times d·cosθ),
    wrapped into [−½, ½) as the channels' phases wrap, and read back as an angle (a spatial frequency beyond the
    visible ±d, where d < ½, where the chain's beamformer reads it, half a bin inside the last bin of its grid
    inside ±d, :data:`CHAIN_DOA_BINS`). A target near ±90° is then read on the other side in some frames, as at the
    signal level, never at ±90°, where the element pattern divided out of the RCS is nil (99 dBsm at the detection
    level, at d = ½ and at d = 0.4: independent testers' findings). Arrays broadcast to ``azimuth_rad +
    sigma_rad·n``'s shape; ``where``: only these returns are measured (the others keep the draw in angle: a body out
    of view, whose angle is never reported)."""
    az = np.asarray(azimuth_rad, dtype=np.float64)
    out = az + sigma_rad * n
    d = preset.element_spacing_wl
    # the chain's last readable sinθ: ±1 where d ≥ ½, else its beamformer grid's edge inside the visible ±d
    edge = 1.0 if d >= 0.5 else max(0.0, (math.floor(CHAIN_DOA_BINS * d) - 0.5) / (CHAIN_DOA_BINS * d))
    # the wrap's (or that edge's) distance in d·sinθ, against the draw's σ there (d·cosθ·σ_θ)
    near_wrap = min(0.5, d * edge) - d * np.abs(np.sin(az)) < WRAP_REACH_SIGMA * d * np.cos(az) * sigma_rad
    wide = (np.abs(az) > ENDFIRE_RAD) | near_wrap | (np.abs(out) > 0.5 * math.pi)
    wide &= preset.num_virtual >= 2            # (one channel measures no angle: its callers report boresight)
    if where is not None:
        wide &= where
    if wide.any():

        def pick(x):
            return np.broadcast_to(x, out.shape)[wide]
        a = pick(az)
        sigma_u = d * np.hypot(pick(efficiency) * equation.crb_azimuth_rad(preset, pick(snr_db), np.zeros(a.shape)),
                               np.cos(a) * pick(floor_rad))
        drawn = np.mod(d * np.sin(a) + sigma_u * pick(n) + 0.5, 1.0) - 0.5
        out[wide] = np.arcsin(np.clip(drawn / d, -edge, edge))
    return out, wide


def stationary_range_rate(azimuth_rad: np.ndarray, sensor_velocity: tuple[float, float]) -> np.ndarray:
    """Range rate of a stationary reflector seen from a sensor moving at ``sensor_velocity`` (x, y), m/s."""
    vx, vy = sensor_velocity
    return -(vx * np.cos(azimuth_rad) + vy * np.sin(azimuth_rad))


def _stationary_unwrap(preset: RadarPreset, range_rate_mps: np.ndarray, azimuth_rad: np.ndarray,
                       sensor_velocity: tuple) -> tuple[np.ndarray, np.ndarray]:
    """A measured range rate moved by whole wraps (2·v_max) next to the stationary hypothesis, and whether it
    then matches it (within STATIONARY_TOLERANCE_BINS Doppler bins)."""
    vmax = preset.alias_speed_mps
    vs = stationary_range_rate(azimuth_rad, sensor_velocity)
    unwrapped = range_rate_mps + 2 * vmax * np.rint((vs - range_rate_mps) / (2 * vmax))
    return unwrapped, np.abs(unwrapped - vs) <= STATIONARY_TOLERANCE_BINS * preset.doppler_bin_mps


def unambiguous(preset: RadarPreset) -> bool:
    """A single ramp whose alias speed covers every road user's range rate: no speed it measures is aliased."""
    return not preset.stagger_chirp_period_s and preset.alias_speed_mps >= UNAMBIGUOUS_SPEED_MPS


def flag_stationary(det: Detections, preset: RadarPreset, sensor_velocity: tuple[float, float]) -> Detections:
    """Unwrap detections that match the stationary hypothesis modulo 2·v_max; flag the rest of a single-ramp
    radar ambiguous (``ambig_state`` of detections already resolved by staggered ramps is kept)."""
    out = det.take(np.arange(len(det)))
    if unambiguous(preset):
        out.ambig_state = np.full(len(det), AMBIG_UNAMBIGUOUS, dtype=np.int64)
        return out
    unwrapped, candidate = _stationary_unwrap(preset, det.range_rate_mps, det.azimuth_rad, sensor_velocity)
    resolved = det.ambig_state == AMBIG_STAGGERED
    take = candidate & ~resolved
    out.range_rate_mps = np.where(take, unwrapped, det.range_rate_mps)
    out.range_m, out.rcs_dbsm = recoupled(preset, det.range_m, det.rcs_dbsm, det.range_rate_mps, out.range_rate_mps)
    out.ambig_state = np.where(take, AMBIG_STATIONARY, np.where(resolved, AMBIG_STAGGERED, AMBIG_AMBIGUOUS))
    return out


def resolve_staggered(det1: Detections, det2: Detections, preset: RadarPreset) -> Detections:
    """Pair the two sequences' detections (same range and angle cell) and recover each speed (module docstring).

    Returns the first sequence's detections; the paired ones carry the resolved
    speed and AmbigState 2, the others their measured speed and AmbigState 1.
    """
    seq2 = preset.second_sequence()
    v1max, v2max = preset.alias_speed_mps, seq2.alias_speed_mps
    lo, hi = preset.range_rate_span_mps
    out = det1.take(np.arange(len(det1)))
    out.ambig_state = np.full(len(det1), AMBIG_AMBIGUOUS, dtype=np.int64)
    if len(det1) == 0 or len(det2) == 0:
        return out
    # pairs in the same range cell and beam: (n1, n2)
    dr = np.abs(det1.range_m[:, None] - det2.range_m[None, :]) / preset.range_resolution_m
    da = np.abs(np.sin(det1.azimuth_rad)[:, None] - np.sin(det2.azimuth_rad)[None, :]) / preset.angular_resolution_rad
    near = (dr <= 1.5) & (da <= 1.0)
    # every candidate of sequence 1 inside the span, against the nearest candidate of sequence 2: (n1, n2, K)
    cand = det1.range_rate_mps[:, None, None] + 2 * v1max * _K[None, None, :]
    inside = (cand >= lo) & (cand <= hi)
    k2 = np.rint((cand - det2.range_rate_mps[None, :, None]) / (2 * v2max))
    miss = np.abs(det2.range_rate_mps[None, :, None] + 2 * v2max * k2 - cand)
    miss = np.where(inside & near[:, :, None], miss, np.inf)
    kk_all = np.argmin(miss, axis=2)                                              # (n1, n2): best wrap per pair
    m = np.take_along_axis(miss, kk_all[:, :, None], axis=2)[:, :, 0]
    # one reflector, one pair: each detection of either sequence pairs with at most one of the other, the two
    # choosing each other (mutually best by speed mismatch, then by distance in the cell). A reflector that the
    # second sequence missed would otherwise borrow its neighbour's second detection, whose lattice meets its
    # own within the tolerance for about one speed pair in five: a wrong speed flagged "resolved"
    cost = np.where(m <= STAGGER_TOLERANCE_MPS, m / STAGGER_TOLERANCE_MPS + (dr / 1.5) ** 2 + da ** 2, np.inf)
    j = np.argmin(cost, axis=1)
    rows = np.arange(len(det1))
    ok = np.isfinite(cost[rows, j]) & (np.argmin(cost, axis=0)[j] == rows)
    kk = kk_all[rows, j]
    # the speed: the mean of the two unwrapped estimates (each as accurate as the other)
    v1 = det1.range_rate_mps + 2 * v1max * _K[kk]
    v2 = det2.range_rate_mps[j] + 2 * v2max * k2[rows, j, kk]
    out.range_rate_mps = np.where(ok, 0.5 * (v1 + v2), det1.range_rate_mps)
    out.range_m, out.rcs_dbsm = recoupled(preset, det1.range_m, det1.rcs_dbsm, det1.range_rate_mps,
                                          out.range_rate_mps)
    out.ambig_state = np.where(ok, AMBIG_STAGGERED, AMBIG_AMBIGUOUS).astype(np.int64)
    return out


def resolve_by_neighbours(det: Detections, preset: RadarPreset, sensor_velocity: tuple[float, float]
                          ) -> Detections:
    """The staggered pair's ambiguous detections (AmbigState 1) that a resolved one (AmbigState 2) within
    ``NEIGHBOUR_REACH_M`` in range and a beamwidth in angle explains: their measured speed is its resolved
    speed modulo 2·v_max,1 within a Doppler bin (a rigid body's reflectors, a few beamwidths at most apart, move
    alike). Each takes that wrap of its own measurement (the nearest such neighbour's, by speed mismatch and
    distance) and AmbigState 2; a stationary candidate is left to :func:`flag_stationary`. Another body there whose
    speed differs by a whole number of wraps within that bin takes the wrong wrap: for two bodies at unrelated
    speeds, 2 bins in 2·v_max,1 of the pairs (1.6 % on ``ars408_like``), the price of listing no oncoming car as
    receding. See the module docstring."""
    amb = det.ambig_state == AMBIG_AMBIGUOUS
    res = det.ambig_state == AMBIG_STAGGERED
    if not amb.any() or not res.any():
        return det
    _, standing = _stationary_unwrap(preset, det.range_rate_mps, det.azimuth_rad, sensor_velocity)
    ia, ir = np.flatnonzero(amb & ~standing), np.flatnonzero(res)
    if ia.size == 0:
        return det
    v1max = preset.alias_speed_mps
    lo, hi = preset.range_rate_span_mps
    dr = np.abs(det.range_m[ia, None] - det.range_m[None, ir]) / max(NEIGHBOUR_REACH_M, 1.5 * preset.range_resolution_m)
    da = np.abs(np.sin(det.azimuth_rad)[ia, None] - np.sin(det.azimuth_rad)[None, ir]) \
        / preset.angular_resolution_rad
    wraps = np.rint((det.range_rate_mps[None, ir] - det.range_rate_mps[ia, None]) / (2 * v1max))
    speed = det.range_rate_mps[ia, None] + 2 * v1max * wraps
    miss = np.abs(speed - det.range_rate_mps[None, ir])
    tol = preset.doppler_bin_mps
    fits = (dr <= 1.0) & (da <= 1.0) & (miss <= tol) & (speed >= lo) & (speed <= hi)
    cost = np.where(fits, miss / tol + dr ** 2 + da ** 2, np.inf)
    j = np.argmin(cost, axis=1)
    rows = np.arange(ia.size)
    ok = np.isfinite(cost[rows, j])
    if not ok.any():
        return det
    out = det.take(np.arange(len(det)))
    take = ia[ok]
    out.range_rate_mps[take] = speed[rows[ok], j[ok]]
    out.range_m[take], out.rcs_dbsm[take] = recoupled(preset, det.range_m[take], det.rcs_dbsm[take],
                                                      det.range_rate_mps[take], out.range_rate_mps[take])
    out.ambig_state[take] = AMBIG_STAGGERED
    return out


def coupled_range(preset: RadarPreset, range_m: np.ndarray, coupled_mps: np.ndarray,
                  taken_out_mps: np.ndarray) -> np.ndarray:
    """The range the chain reports for ``range_m``, which carries the range–Doppler coupling of the speed
    ``coupled_mps`` (a peak sits at its true speed's), once the coupling is taken out with ``taken_out_mps``
    (the speed it reports: ``RadarPreset.range_rate_coupling_s``), modulo the unambiguous range (never negative);
    ``range_m`` itself where the two speeds agree. A target reported at an aliased speed keeps (true − aliased) ×
    the coupling in its range; a speed resolved later (staggered ramps, stationary candidates) recouples it."""
    shift = coupling_left(preset, coupled_mps, taken_out_mps)
    return np.where(shift != 0.0, np.mod(range_m + shift, preset.unambiguous_range_m), range_m)


def recoupled(preset: RadarPreset, range_m: np.ndarray, rcs_dbsm: np.ndarray, coupled_mps: np.ndarray,
              taken_out_mps: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(range, RCS) of detections read at ``range_m`` with ``rcs_dbsm`` under the coupling of ``coupled_mps``, once
    their speed is ``taken_out_mps``: the range :func:`coupled_range` gives and the RCS read there
    (:func:`range_db`). Every step that resolves a speed after the chain (the three of :func:`resolve`) moves both."""
    moved = coupled_range(preset, range_m, coupled_mps, taken_out_mps)
    return moved, rcs_dbsm + range_db(range_m, moved)


def range_db(read_at_m: np.ndarray, reported_m: np.ndarray) -> np.ndarray:
    """What an RCS read at the range ``read_at_m`` gains when read at ``reported_m`` instead (dB): the radar
    equation's R⁴, 40·log10 of the ratio (ranges floored at 1 cm, as :func:`radarnode.radar.equation.snr_db`
    floors them); 0 where the two agree. A speed resolved after the RCS was read recouples the range
    (:func:`coupled_range`), and the radar reports the RCS its power gives at the range it reports: read at the
    first, aliased speed's range, a 20-dBsm point closing at 75–100 m/s read 19.3–19.6 dBsm on ``ars408_like``
    where the object level read 20.0 (a tester's finding)."""
    a, b = np.broadcast_arrays(np.asarray(read_at_m, dtype=np.float64), np.asarray(reported_m, dtype=np.float64))
    out = np.zeros(a.shape)
    moved = a != b
    if moved.any():         # (the logarithm only where a range moved: most detections' and objects' do not)
        out[moved] = 40.0 * np.log10(np.maximum(b[moved], 0.01) / np.maximum(a[moved], 0.01))
    return out


def coupling_left(preset: RadarPreset, coupled_mps: np.ndarray, taken_out_mps: np.ndarray) -> np.ndarray:
    """The range (m) the range–Doppler coupling of the speed ``coupled_mps`` leaves in a peak once the chain takes
    it out with ``taken_out_mps`` (:func:`coupled_range` before its fold)."""
    return (np.asarray(coupled_mps) - np.asarray(taken_out_mps)) * preset.range_rate_coupling_s


def resolve(preset: RadarPreset, sequences: list[Detections], sensor_velocity: tuple[float, float]) -> Detections:
    """The detections of one cycle with their speeds resolved and ``ambig_state`` filled truthfully.

    ``sequences`` holds one Detections per chirp sequence of the preset (two
    with staggered ramps). A single ramp cannot tell v from v ± 2·v_max: its
    moving detections are flagged ambiguous, whatever their speed.
    """
    if preset.stagger_chirp_period_s > 0:
        if len(sequences) != 2:
            raise ValueError(f"sequences: {len(sequences)} given; preset {preset.name} has two chirp sequences")
        det = resolve_by_neighbours(resolve_staggered(sequences[0], sequences[1], preset), preset, sensor_velocity)
    else:
        det = sequences[0]
    return flag_stationary(det, preset, sensor_velocity)


def apparent_range_rate(preset: RadarPreset, range_rate_mps: np.ndarray, azimuth_rad: np.ndarray,
                        sensor_velocity: tuple, second: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """What :func:`resolve` makes of a true range rate, for the object level (which has no per-sequence data).

    Staggered ramps: the true speed inside the span where the second sequence
    detected the target too (``second``, broadcast with the speeds; default
    everywhere) (AmbigState 2); else what the first sequence alone gives, as a
    single ramp. A single ramp: the alias, unwrapped to the stationary
    hypothesis where it matches (4), else flagged ambiguous (1).
    Arrays broadcast; ``sensor_velocity`` may hold arrays (e.g. one per cycle).
    """
    v = np.asarray(range_rate_mps, dtype=np.float64)
    vmax = preset.alias_speed_mps
    alias = np.mod(v + vmax, 2 * vmax) - vmax
    if unambiguous(preset):
        return alias, np.full(np.shape(alias), AMBIG_UNAMBIGUOUS, dtype=np.int64)
    unwrapped, candidate = _stationary_unwrap(preset, alias, azimuth_rad, sensor_velocity)
    rate = np.where(candidate, unwrapped, alias)
    state = np.where(candidate, AMBIG_STATIONARY, AMBIG_AMBIGUOUS)
    if preset.stagger_chirp_period_s > 0:
        lo, hi = preset.range_rate_span_mps
        paired = (v >= lo) & (v <= hi)
        if second is not None:
            paired = paired & second
        rate, state = np.where(paired, v, rate), np.where(paired, AMBIG_STAGGERED, state)
    return rate, state.astype(np.int64)
