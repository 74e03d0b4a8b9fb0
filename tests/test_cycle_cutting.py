"""Where a cycle ends is decided by the cycle's own frames (issue 13, item 2): stray RadarState frames, garbage
between and inside cycles, a node that stops or starts sending groups; every well-formed cycle arrives whole."""

from __future__ import annotations

import time

import can
import numpy as np
import pytest

from radarnode.consumer.assembler import LAYOUT_MEMORY, CycleAssembler, ObjectCycle
from radarnode.wire import ars408 as P
from radarnode.wire.dbc import load_database
from radarnode.wire.node import EgoMotionSender, RadarNode
from tests.helpers import scenario

TRAFFIC = """
  - {id: a, class: car, x_m: 40.0, lane: 1, speed_mps: 22.0}
  - {id: b, class: truck, x_m: 70.0, lane: 0, speed_mps: 18.0}
  - {id: c, class: motorcycle, x_m: 55.0, lane: 2, speed_mps: 25.0}
  - {id: d, class: car, x_m: 120.0, lane: 1, speed_mps: 28.0}
"""
LIST_IDS = (P.OBJ_STATUS, P.OBJ_GENERAL, P.OBJ_QUALITY, P.OBJ_EXTENDED)


def _msg(can_id, data, ts=0.0, **kw) -> can.Message:
    return can.Message(arbitration_id=can_id, data=bytes(data), is_extended_id=kw.pop("is_extended_id", False),
                       timestamp=ts, check=False, **kw)


def _radar_state(quality: bool, ext: bool) -> can.Message:
    db = load_database()
    m = db.get_message_by_frame_id(P.RADAR_STATE)
    values = {s.name: 0 for s in m.signals}
    values.update(RadarState_SendQualityCfg=int(quality), RadarState_SendExtInfoCfg=int(ext),
                  RadarState_MaxDistanceCfg=196, RadarState_OutputTypeCfg=1)
    return _msg(P.RADAR_STATE, m.encode(values))


def _cfg(**fields) -> can.Message:
    db = load_database()
    m = db.get_message_by_frame_id(P.RADAR_CFG)
    values = {s.name: 0 for s in m.signals}
    values.update(fields)
    return _msg(P.RADAR_CFG, m.encode(values))


def _node_cycles(n_cycles: int, radar: str = "{preset: ars408_like}", toggles: dict | None = None, seed: int = 1):
    """Run a node; returns per cycle (frames, sent object list, SendQuality, SendExtInfo, MeasCounter).

    ``toggles`` maps a cycle index to a RadarConfiguration frame the node receives before that cycle."""
    sc = scenario(TRAFFIC, radar=radar, duration=n_cycles * 0.072 + 0.1, seed=seed)
    node = RadarNode(sc)
    vehicle = EgoMotionSender(node.scene)
    out = []
    for k in range(n_cycles):
        t = k * node.period_s
        ego = vehicle.frames(t)
        for m in ego:
            node.receive(m, t)
        extra = []
        if toggles and k in toggles:
            node.receive(toggles[k], t)
            extra = [toggles[k]]
        res = node.cycle(t)
        counter = node.db.decode_message(P.OBJ_STATUS, next(m.data for m in res.messages
                                                                if m.arbitration_id == P.OBJ_STATUS))["Obj_MeasCounter"]
        out.append((extra + ego + res.messages, res.frame.objects, node.config.send_quality,
                    node.config.send_ext_info, counter))
    return out


def _intact(cycle, sent, quality: bool, ext: bool, counter: int) -> bool:
    """The delivered cycle holds what the node sent, object by object (frames reordered on the way may change
    the list order, not the content)."""
    got = cycle.objects
    n = len(sent)
    if not isinstance(cycle, ObjectCycle) or len(got) != n or cycle.meas_counter != counter:
        return False
    got, sent = got.take(np.argsort(got.id)), sent.take(np.argsort(sent.id))
    return (np.array_equal(got.id, sent.id)
            and np.allclose(got.dist_long_m, sent.dist_long_m, atol=0.1 + 1e-9)
            and np.allclose(got.dist_lat_m, sent.dist_lat_m, atol=0.1 + 1e-9)
            and np.allclose(got.vrel_long_mps, sent.vrel_long_mps, atol=0.125 + 1e-9)
            and cycle.has_quality == (quality and n > 0) and cycle.has_extended == (ext and n > 0)
            and (not (ext and n) or np.array_equal(got.obj_class, sent.obj_class)))


def _match(delivered, cycles) -> tuple[int, list]:
    """Walk the delivered cycles against what the node sent, in order; returns (matched, extra deliveries)."""
    k, extra = 0, []
    for c in delivered:
        if k < len(cycles) and _intact(c, *cycles[k][1:]):
            k += 1
        else:
            extra.append(c)
    return k, extra


def test_a_stray_radar_state_cannot_strip_groups():
    cycles = _node_cycles(40)
    stream = []
    for frames, *_ in cycles:
        stream += [_radar_state(False, False)] + frames            # before every header: "no quality, no ext"
        stream.insert(len(stream) - 3, _radar_state(False, False))  # and inside the cycle
    asm = CycleAssembler()
    got = list(asm.feed(stream))
    matched, extra = _match(got, cycles)
    assert matched == len(cycles) and not extra
    assert all(c.has_quality and c.has_extended for c in got if len(c.objects))
    assert asm.stats.orphan_frames == asm.stats.late_frames == asm.stats.incomplete_cycles == 0


def test_a_node_that_stops_and_starts_sending_groups():
    """SendExtInfo off at cycle 10, SendQuality off at 20, both on again at 35 — by RadarConfiguration."""
    toggles = {10: _cfg(RadarCfg_SendExtInfo_valid=1, RadarCfg_SendExtInfo=0),
               20: _cfg(RadarCfg_SendQuality_valid=1, RadarCfg_SendQuality=0),
               35: _cfg(RadarCfg_SendQuality_valid=1, RadarCfg_SendQuality=1, RadarCfg_SendExtInfo_valid=1,
                        RadarCfg_SendExtInfo=1)}
    cycles = _node_cycles(50, toggles=toggles)
    asm = CycleAssembler()
    delivered_at = []          # cycle index at whose frames each delivery happened
    for k, (frames, *_) in enumerate(cycles):
        for m in frames:
            asm.on_message_received(m)
            delivered_at += [k] * len(asm.drain())
    asm.flush()
    delivered_at += [len(cycles)] * len(asm.drain())
    assert asm.stats.cycles == len(cycles) and asm.stats.incomplete_cycles == 0 and asm.stats.dropped() == 0
    assert asm.stats.late_frames == 0
    # a group that stops is waited for at the next header for LAYOUT_MEMORY cycles, then no longer
    late = [k for k in range(len(cycles)) if delivered_at[k] == k + 1]
    assert late == [*range(10, 10 + LAYOUT_MEMORY), *range(20, 20 + LAYOUT_MEMORY)]


def test_a_waiting_cycle_is_closed_by_the_timeout():
    cycles = _node_cycles(8, radar="{preset: ars408_like, send_quality: false, send_ext_info: false}")
    j = next(k for k, c in enumerate(cycles) if len(c[1]))        # the first cycle with objects
    asm = CycleAssembler(cycle_timeout_s=0.05)
    for frames, *_ in cycles[:j + 1]:
        for m in frames:
            asm.on_message_received(m)
    assert len(asm.drain()) == j                 # empty cycles at once; then no 0x60C/0x60D: is more coming?
    t0 = time.monotonic()
    cycle = asm.get(timeout=1.0)
    waited = time.monotonic() - t0
    assert cycle is not None and _intact(cycle, *cycles[j][1:]) and 0.04 < waited < 0.5
    assert asm.stats.timed_out_cycles == 1
    for m in cycles[j + 1][0]:                   # learned: the next one is delivered on its last frame
        asm.on_message_received(m)
    (second,) = asm.drain()
    assert _intact(second, *cycles[j + 1][1:]) and asm.stats.incomplete_cycles == 0


def _garbage(rng: np.random.Generator, sensor: int, n: int, own_header: bytes | None) -> list[can.Message]:
    """Valid-looking garbage that cannot be mistaken for frames of a well-formed cycle of ``sensor``."""
    db = load_database()
    dlc = {m.frame_id: m.length for m in db.messages}
    ours = {P.shifted(b, sensor) for b in LIST_IDS}
    out = []
    for _ in range(n):
        kind = rng.integers(9)
        ts = float(rng.choice([np.nan, -1e9, 1e300, rng.uniform(0, 1e4)]))
        if kind == 0:        # RadarState with random bits, or explicitly the groups switched off / on
            m = _radar_state(bool(rng.integers(2)), bool(rng.integers(2))) if rng.integers(2) else \
                _msg(P.RADAR_STATE, rng.integers(0, 256, 8, dtype=np.uint8))
            m.arbitration_id = P.shifted(P.RADAR_STATE, sensor)
        elif kind == 1:      # any ARS 408 message of another sensor, its own DLC, random bytes
            base = int(rng.choice(list(dlc)))
            other = int(rng.choice([s for s in range(8) if s != sensor]))
            m = _msg(P.shifted(base, other), rng.integers(0, 256, dlc[base], dtype=np.uint8))
        elif kind == 2:      # an ID around the real ones; ours only with a wrong DLC
            can_id = int(rng.integers(0x5F0, 0x720))
            length = int(rng.integers(0, 9))
            if can_id in ours:
                length = int(rng.choice([d for d in range(9) if d != dlc[P.shifted(can_id, -sensor)]]))
            m = _msg(can_id, rng.integers(0, 256, length, dtype=np.uint8))
        elif kind == 3:      # our list IDs, every wrong DLC
            can_id = int(rng.choice(sorted(ours)))
            right = dlc[can_id - 0x10 * sensor]
            m = _msg(can_id, rng.integers(0, 256, int(rng.choice([d for d in range(9) if d != right])),
                                         dtype=np.uint8))
        elif kind == 4:      # remote and extended frames on our IDs
            can_id = int(rng.choice(sorted(ours)))
            ext = bool(rng.integers(2))
            m = _msg(can_id, rng.integers(0, 256, 8, dtype=np.uint8), is_extended_id=ext,
                     is_remote_frame=not ext or bool(rng.integers(2)))
        elif kind == 5:      # radarnode's own range: E2E protected, random bytes fail
            m = _msg(int(rng.integers(0x680, 0x700)), rng.integers(0, 256, 8, dtype=np.uint8))
        elif kind == 6:      # ego motion and version, random but valid DLC
            base = int(rng.choice([P.SPEED_INFO, P.YAW_RATE_INFO, P.VERSION_ID]))
            m = _msg(P.shifted(base, sensor), rng.integers(0, 256, dlc[base], dtype=np.uint8))
        elif kind == 7 and own_header is not None:    # the cycle's own header again
            m = _msg(P.shifted(P.OBJ_STATUS, sensor), own_header)
        else:                # unknown IDs anywhere, standard and extended
            m = _msg(int(rng.integers(0, 0x800)), rng.integers(0, 256, int(rng.integers(0, 9)), dtype=np.uint8))
            if m.arbitration_id in ours:
                m.arbitration_id = 0x123
        m.timestamp = ts
        out.append(m)
    return out


def _bogus_cycle(rng: np.random.Generator, real_counter: int) -> tuple[list[can.Message], bool]:
    """A header that is not the node's, and fewer general frames than it announces (or an empty list)."""
    n = int(rng.integers(0, 12))
    counter = (real_counter + 0x8000 + int(rng.integers(0, 100))) & 0xFFFF     # never a real counter
    header = load_database().encode_message(P.OBJ_STATUS, {"Obj_NofObjects": n, "Obj_MeasCounter": counter,
                                                          "Obj_InterfaceVersion": 1})
    frames = [_msg(P.OBJ_STATUS, header)]
    for _ in range(int(rng.integers(0, n)) if n else 0):
        frames.append(_msg(int(rng.choice([P.OBJ_GENERAL, P.OBJ_QUALITY, P.OBJ_EXTENDED])),
                           rng.integers(0, 256, 8, dtype=np.uint8)))
        if frames[-1].arbitration_id == P.OBJ_QUALITY:
            frames[-1].data = frames[-1].data[:7]
            frames[-1].dlc = 7
    return frames, n == 0


def _fuzz(cycles, rng: np.random.Generator, garbage_per_cycle: int = 12):
    """Interleave the node's cycles with garbage between and inside them; returns (stream, counts)."""
    stream, counts = [], {"garbage": 0, "bogus_empty": 0, "stray_state_off": 0}
    for frames, *_ in cycles:
        frames = list(frames)
        h = next(i for i, m in enumerate(frames) if m.arbitration_id == P.OBJ_STATUS)
        header = bytes(frames[h].data)
        body = frames[h + 1:]
        lists = [i for i, m in enumerate(body) if m.arbitration_id in LIST_IDS]
        if lists and rng.integers(2):                       # reorder the list frames, across groups too
            moved = [body[i] for i in rng.permutation(lists)]
            for i, m in zip(lists, moved):
                body[i] = m
        for _ in range(int(rng.integers(0, 4))):            # duplicates of frames already sent
            i = int(rng.integers(0, len(body) + 1))
            src = ([frames[h]] + body[:i])[int(rng.integers(0, i + 1))]
            body.insert(i, _msg(src.arbitration_id, src.data, src.timestamp))
        inside = _garbage(rng, 0, int(rng.integers(0, garbage_per_cycle)), header)
        if rng.integers(2):                                  # the attack of the issue: "no quality, no ext"
            inside.append(_radar_state(False, False))
        for m in inside:
            body.insert(int(rng.integers(0, len(body) + 1)), m)
        between = _garbage(rng, 0, int(rng.integers(0, garbage_per_cycle)), None)
        if rng.integers(2):
            between.append(_radar_state(False, False))
        if rng.integers(3) == 0:
            real = load_database().decode_message(P.OBJ_STATUS, header)["Obj_MeasCounter"]
            bogus, empty = _bogus_cycle(rng, real)
            between = between[: len(between) // 2] + bogus + between[len(between) // 2:]
            counts["bogus_empty"] += empty
            counts["garbage"] += len(bogus)
        counts["garbage"] += len(inside) + len(between)
        counts["stray_state_off"] += sum(m.arbitration_id == P.RADAR_STATE and len(m.data) == 8
                                         and not m.data[5] & 0x30 for m in inside + between)   # SendQuality/ExtInfo: bits 44, 45
        stream += between + frames[:h + 1] + body
    return stream, counts


def _check_fuzz(cycles, stream, counts):
    asm = CycleAssembler()
    got = list(asm.feed(stream))
    matched, extra = _match(got, cycles)
    st = asm.stats
    assert st.frames == len(stream) and st.decode_errors == 0               # nothing raised inside the listener
    assert matched == len(cycles), f"{len(cycles) - matched} of {len(cycles)} well-formed cycles not intact"
    assert len(extra) <= counts["bogus_empty"] and all(len(c.objects) == 0 for c in extra)
    assert st.late_frames == 0 and st.dropped() > 0
    return asm, len(extra)


@pytest.mark.parametrize("radar", ["{preset: ars408_like}",
                                   "{preset: ars408_like, send_quality: false, send_ext_info: false}",
                                   "{preset: ars408_like, send_ext_info: false}"])
def test_fuzz_every_well_formed_cycle_arrives_intact(radar):
    rng = np.random.default_rng(13)
    cycles = _node_cycles(120, radar=radar)
    stream, counts = _fuzz(cycles, rng)
    assert counts["stray_state_off"] > 20 and counts["garbage"] > len(cycles) * 5
    _check_fuzz(cycles, stream, counts)


@pytest.mark.slow
def test_fuzz_over_a_hundred_thousand_frames():
    rng = np.random.default_rng(2024)
    toggles = {k: _cfg(RadarCfg_SendQuality_valid=1, RadarCfg_SendQuality=int(rng.integers(2)),
                       RadarCfg_SendExtInfo_valid=1, RadarCfg_SendExtInfo=int(rng.integers(2)))
               for k in range(50, 3400, 250)}
    cycles = _node_cycles(3400, toggles=toggles, seed=7)
    stream, counts = _fuzz(cycles, rng, garbage_per_cycle=24)
    assert len(stream) >= 100_000
    asm, extra = _check_fuzz(cycles, stream, counts)
    print(f"fuzz: {len(stream)} frames, {counts['garbage']} garbage, {counts['stray_state_off']} stray RadarState "
          f"with both groups off, {len(cycles)} cycles intact, {extra} bogus empty cycles, "
          f"stats {asm.stats.as_dict()}")
