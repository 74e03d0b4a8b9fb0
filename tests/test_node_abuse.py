"""A node under bad and flooding input (issue 13, item 9): malformed and useless 0x200/0x202/0x300/0x301/0x400/0x401
frames, remote and error frames, frames the bus cannot read. It keeps its cycle, counts exactly what it refused,
a valid message among the flood still takes effect, and the consumer receives every cycle intact.

The real-time version over udp_multicast (three processes, a flood of 4000 frames/s) is ``benchmarks/soak.py``;
``tests/test_soak.py`` runs it briefly."""

from __future__ import annotations

from collections import Counter, deque

import can
import numpy as np
import pytest

from radarnode.consumer.assembler import CycleAssembler
from radarnode.wire import ars408 as P
from radarnode.wire.dbc import load_database
from radarnode.wire.node import EgoMotionSender, RadarNode
from radarnode.wire.runner import SimulatedClock, run_node
from tests.helpers import scenario
from tests.test_config_protocol import ACTORS, coll_det_cfg, filter_cfg, radar_cfg, region_cfg

DLC = {0x200: 8, 0x202: 8, 0x300: 2, 0x301: 2, 0x400: 2, 0x401: 8}
# FilterCfg: 5 bytes in Continental's DBC for sensor 1 (every signal lies in them), 8 in sensor 0's; 5…8 are taken
#: the DLCs each input is taken with: its own and longer (padded, as AUTOSAR's DLC check takes them), FilterCfg from
#: 5 bytes (Continental's DBC for sensor 1)
_ACCEPTED_DLC = {base: tuple(range(5 if base == 0x202 else dlc, 9)) for base, dlc in DLC.items()}


def _raw_filter(index: int, lo_raw: int, hi_raw: int, ftype: int = 1, valid: int = 1) -> bytes:
    """A FilterCfg payload from raw 12-bit bounds (reaches values cantools would refuse to encode)."""
    word = (valid << 1 | 1 << 2 | index << 3 | ftype << 7) << 56 | (lo_raw & 0xFFF) << 40 | (hi_raw & 0xFFF) << 24
    return word.to_bytes(8, "big")


def _abuse(rng: np.random.Generator, n: int, sensor: int = 0) -> tuple[list, Counter]:
    """``n`` bad or useless frames for sensor ``sensor``'s inputs, and what the node must count for them."""
    out, expect = [], Counter()
    refused_200 = [dict(RadarCfg_OutputType_valid=1, RadarCfg_OutputType=3),
                   dict(RadarCfg_RadarPower_valid=1, RadarCfg_RadarPower=6),
                   dict(RadarCfg_MaxDistance_valid=1, RadarCfg_MaxDistance=1200),
                   dict(RadarCfg_MaxDistance_valid=1, RadarCfg_MaxDistance=2),
                   dict(RadarCfg_SortIndex_valid=1, RadarCfg_SortIndex=5),
                   dict(RadarCfg_RCS_Threshold_Valid=1, RadarCfg_RCS_Threshold=4)]
    refused_202 = [_raw_filter(15, 0, 1), _raw_filter(1, 4000, 10), _raw_filter(6, 0, 10, ftype=0),
                   _raw_filter(8, 0, 4095), _raw_filter(8, 9, 9), _raw_filter(13, 0, 5, ftype=1, valid=1)[:4]]
    shift = 0x10 * sensor

    def msg(base, data, **kw):
        return can.Message(arbitration_id=base + shift, data=data, is_extended_id=kw.pop("ext", False), **kw)

    for _ in range(n):
        kind = int(rng.integers(13))
        base = int(rng.choice(list(DLC)))
        if kind <= 2:
            length = int(rng.choice([d for d in range(9) if d not in _ACCEPTED_DLC.get(base, (DLC[base],))]))
            out.append(msg(base, bytes(rng.integers(0, 256, length, dtype=np.uint8))))
            expect["rx_wrong_dlc"] += 1
        elif kind == 3:
            out.append(radar_cfg(sensor, **refused_200[int(rng.integers(len(refused_200)))]))
            expect["config_rejected"] += 1
            expect["rx_config"] += 1
        elif kind == 4:                                    # a flood of no-op RadarConfiguration
            out.append(radar_cfg(sensor))
            expect["rx_config"] += 1
        elif kind == 5:
            data = refused_202[int(rng.integers(len(refused_202)))]
            out.append(msg(P.FILTER_CFG, data))
            expect["rx_wrong_dlc" if len(data) != 8 else "config_rejected"] += 1
            expect["rx_filter_cfg"] += len(data) == 8
        elif kind == 6:                                    # FilterCfg with Valid 0
            out.append(msg(P.FILTER_CFG, _raw_filter(1, 0, 100, valid=0)))
            expect["rx_filter_cfg"] += 1
        elif kind == 7:                                    # speed direction 3 (reserved)
            out.append(msg(P.SPEED_INFO, bytes([0xC0 | int(rng.integers(32)), int(rng.integers(256))])))
            expect["rx_invalid_speed_direction"] += 1
        elif kind == 8:                                    # yaw rate 0xFFFF, beyond the signal's range
            out.append(msg(P.YAW_RATE_INFO, b"\xff\xff"))
            expect["rx_out_of_range"] += 1
        elif kind == 9:                                    # a region never given corners
            out.append(region_cfg(int(rng.integers(5, 8)), coords=0, sensor=sensor))
            expect["config_rejected"] += 1
            expect["rx_coll_det_region_cfg"] += 1
        elif kind == 10:
            out.append(can.Message(arbitration_id=base + shift, is_remote_frame=True, dlc=DLC[base],
                                   is_extended_id=False))
            expect["rx_remote_frames"] += 1
        elif kind == 11:
            out.append(can.Message(is_error_frame=True))
            expect["rx_error_frames"] += 1
        else:                                              # not for this node: 29-bit IDs, another sensor's inputs
            if rng.integers(2):
                out.append(msg(base, bytes(8), ext=True))
            else:
                out.append(can.Message(arbitration_id=base + 0x10 * ((sensor + 1 + int(rng.integers(6))) % 8),
                                       data=bytes(DLC[base]), is_extended_id=False))
    return out, expect


class _Unreadable:
    """Stands for a datagram the bus cannot turn into a frame: ``recv`` raises on it."""


def test_a_flooded_node_keeps_its_cycle_counts_what_it_refused_and_applies_a_valid_message():
    rng = np.random.default_rng(408)
    sc = scenario(ACTORS, duration=6.0)
    node = RadarNode(sc)
    n_cycles = sc.num_cycles
    inbox: deque = deque()
    expect = Counter()
    per_cycle = 300                                         # ~4200 frames/s: a saturated 500 kbit/s bus
    for k in range(n_cycles):
        frames, e = _abuse(rng, per_cycle)
        expect += e
        if k == 2:                                          # the ECU's legitimate configuration, amid the flood
            frames[150:150] = [region_cfg(0, (10.0, -2.0), (80.0, 2.0)), coll_det_cfg(1, min_time=0.5)]
            expect.update(rx_coll_det_region_cfg=1, rx_coll_det_cfg=1)
        if k == 40:
            frames[100:100] = [filter_cfg(1, 0.0, 60.0)]
            expect["rx_filter_cfg"] += 1
        if k % 10 == 5:
            frames.insert(7, _Unreadable())
            expect["rx_unreadable"] += 1
        inbox.append(frames)
    polls = deque()

    def recv(timeout):
        # one cycle's worth of flood is queued before each cycle is computed
        if not polls:
            if not inbox:
                return None
            polls.extend(inbox.popleft())
            polls.append(None)
        m = polls.popleft()
        if isinstance(m, _Unreadable):
            raise can.CanOperationError("could not unpack received message")
        return m

    sent = []
    asm = CycleAssembler()

    def sink(m):
        sent.append(m)
        asm.on_message_received(m)

    stats = run_node(node, clock=SimulatedClock(), sinks=[sink], recv=recv, vehicle=EgoMotionSender(node.scene))
    asm.flush()
    cycles = asm.drain()
    # it keeps its cycle: every cycle computed and sent, and the consumer got every one whole
    assert stats.cycles == n_cycles and stats.missed == 0
    assert len(cycles) == n_cycles and asm.stats.incomplete_cycles == 0 and asm.stats.lost_cycles == 0
    # it counted exactly what it refused
    for key, value in expect.items():
        assert node.counters[key] == value, (key, node.counters[key], value)
    assert node.config.max_distance_m == 250.0 and node.config.output_type == P.OUTPUT_OBJECTS
    assert not node.filters.filters.keys() - {(1, 1)}                   # nothing of the flood configured a filter
    # refusals are flagged: every RadarState during the flood has Temporary_Error, and one goes out every cycle
    db = load_database()
    states = [db.decode_message(P.RADAR_STATE, m.data) for m in sent if m.arbitration_id == P.RADAR_STATE]
    assert len(states) == n_cycles and all(s["RadarState_Temporary_Error"] == "Temporary error active"
                                           for s in states)
    # the valid messages took effect in the cycle computed after them: collision detection from cycle 2 on, the
    # filter from cycle 40 on
    assert all(c.has_warning for c in cycles[2:]) and not any(c.has_warning for c in cycles[:2])
    assert any(c.collision_regions.any() for c in cycles[2:])
    assert max(np.max(c.objects.range_m, initial=0) for c in cycles[:40]) > 60.2
    assert all(np.all(c.objects.range_m <= 60.15) for c in cycles[40:])
    assert asm.filter_state[(1, 1)]["FilterState_Max_Distance"] == 60.0
    # a burst is answered once per cycle: one FilterState header per cycle, not one per FilterCfg received
    headers = sum(m.arbitration_id == P.FILTER_STATE_HEADER for m in sent)
    assert headers == n_cycles < node.counters["rx_filter_cfg"]


def test_a_flood_for_another_sensor_changes_nothing():
    rng = np.random.default_rng(7)
    node = RadarNode(scenario(ACTORS, duration=1.0))
    frames, _ = _abuse(rng, 3000, sensor=3)                 # its "other sensors" are 4..7, 0..1: not 0
    frames = [m for m in frames if m.is_error_frame or P.unshifted(m.arbitration_id)[1] != 0]
    frames += [filter_cfg(1, 0.0, 10.0, sensor=3), coll_det_cfg(1, sensor=3), region_cfg(0, (0, -5), (50, 5), sensor=3),
               radar_cfg(3, RadarCfg_SendQuality_valid=1, RadarCfg_SendQuality=0)]
    for m in frames:
        node.receive(m, 0.0)
    counted = {k: v for k, v in node.counters.items() if k != "rx_error_frames"}   # error frames have no ID
    assert counted == {} and not node.filters.filters and not node.coll_det.active and node.config.send_quality


@pytest.mark.parametrize("base", sorted(DLC))
def test_every_dlc_and_random_bytes_on_every_input_never_raise(base):
    rng = np.random.default_rng(base)
    node = RadarNode(scenario(ACTORS, duration=1.0))
    for length in range(9):
        for _ in range(200):
            node.receive(can.Message(arbitration_id=base, data=bytes(rng.integers(0, 256, length, dtype=np.uint8)),
                                     is_extended_id=False), 0.0)
    assert node.counters["rx_wrong_dlc"] == (9 - len(_ACCEPTED_DLC.get(base, (DLC[base],)))) * 200
    out = node.cycle(0.0)                      # whatever random configuration it accepted, it still sends a cycle
    # (random bytes may have moved it to another SensorID: its IDs move with it)
    assert any(P.unshifted(m.arbitration_id)[0] in (P.OBJ_STATUS, P.CLUSTER_STATUS) for m in out.messages) or \
        node.config.output_type == P.OUTPUT_NONE


@pytest.mark.parametrize("pad", [b"\x00", b"\xcc"])
def test_ego_motion_and_configuration_padded_to_eight_bytes_are_taken(pad):
    """Bench tools and gateways often send every frame with DLC 8: SpeedInformation and YawRateInformation padded
    from 2 bytes were dropped as a wrong DLC by the node (which then ran with 'speed missing', MotionRxState 3) and by
    the consumer (an independent tester's finding). A longer DLC is now taken, its first bytes read and counted in
    rx_padded / padded_frames, whatever the padding; a shorter one is still dropped."""
    from radarnode.consumer.assembler import CycleAssembler
    from radarnode.wire.node import EgoMotionSender
    node = RadarNode(scenario(ACTORS, duration=1.0))
    asm = CycleAssembler()
    ego = EgoMotionSender(node.scene)
    for k in range(4):
        t = k * node.period_s
        for m in ego.frames(t):
            padded = can.Message(arbitration_id=m.arbitration_id, data=bytes(m.data) + pad * (8 - len(m.data)),
                                 is_extended_id=False)
            node.receive(padded, t)
            asm.on_message_received(padded)
        node.cycle(t)
    assert node.motion_rx_state(3 * node.period_s) == 0 and node.counters["rx_padded"] == 8
    assert node.counters["rx_wrong_dlc"] == 0
    assert asm.ego_speed_mps == pytest.approx(node.scene.scenario.ego.speed_mps, abs=0.02)
    assert asm.stats.padded_frames == 8 and asm.stats.wrong_dlc == 0
    node.receive(can.Message(arbitration_id=0x300, data=b"\x01", is_extended_id=False), 0.3)
    assert node.counters["rx_wrong_dlc"] == 1
    padded_cfg = coll_det_cfg(1, min_time=0.0)
    node.receive(can.Message(arbitration_id=padded_cfg.arbitration_id, data=bytes(padded_cfg.data) + pad * (
        8 - len(padded_cfg.data)), is_extended_id=False), 0.3)
    assert node.coll_det.active


def test_can_fd_frames_are_dropped_and_counted_by_the_node_and_the_consumer():
    """The ARS 408 and its ECU are classical CAN nodes: their controllers never take a CAN FD frame. A 64-byte FD frame
    on 0x300 was read as a padded SpeedInformation by both (an independent tester's finding); now dropped and counted,
    at every length FD has, and the classical frame beside it is taken."""
    from radarnode.consumer.assembler import CycleAssembler
    node = RadarNode(scenario(ACTORS, duration=1.0))
    asm = CycleAssembler()
    speed = EgoMotionSender(node.scene).frames(0.0)[0]
    assert P.unshifted(speed.arbitration_id)[0] == P.SPEED_INFO
    lengths = (2, 8, 12, 64)
    for n in lengths:
        fd = can.Message(arbitration_id=speed.arbitration_id, data=bytes(speed.data) + b"\xff" * (n - len(speed.data)),
                         is_extended_id=False, is_fd=True)
        node.receive(fd, 0.0)
        asm.on_message_received(fd)
    assert node.counters["rx_fd_frames"] == len(lengths) and node.counters["rx_padded"] == 0
    assert node.motion_rx_state(0.0) != 0                    # no speed taken from them
    assert asm.stats.fd_frames == len(lengths) and asm.stats.padded_frames == 0 and asm.ego_speed_mps is None
    assert asm.stats.dropped() == len(lengths)
    node.receive(speed, 0.0)
    asm.on_message_received(speed)
    assert node.counters["rx_speed"] == 1 and asm.ego_speed_mps is not None


def test_a_bus_that_does_not_take_some_frames_loses_only_those_and_the_node_goes_on(caplog):
    """A send the bus refused (socketcan's ENOBUFS: a full transmit queue on a physical bus no other node
    acknowledges) ended the node with a traceback. Now each such frame is lost and counted in tx_failed, warned once,
    and every other frame goes out in order."""
    sc = scenario(ACTORS, duration=2.0)
    node = RadarNode(sc)
    got, tried = [], [0]

    def flaky(m):                   # the bus refuses frames 40–79 of the run
        tried[0] += 1
        if 40 <= tried[0] - 1 < 80:
            raise can.CanOperationError("Failed to transmit: [Errno 105] No buffer space available", 105)
        got.append(m)

    kept = []
    stats = run_node(node, clock=SimulatedClock(), sinks=[flaky, kept.append])
    assert stats.cycles == int(2.0 / node.period_s) and node.counters["tx_failed"] == 40
    assert len(got) == tried[0] - 40 and len(kept) == tried[0]       # the other sink took every frame
    assert [m.arbitration_id for m in got] == [m.arbitration_id for m in kept[:40] + kept[80:]]
    assert sum("tx_failed" in r.getMessage() for r in caplog.records) == 1


def test_a_send_to_a_bus_whose_reader_is_full_times_out_instead_of_hanging():
    """A virtual bus whose other end keeps a bounded queue it never reads: the node's send waited for ever (and a
    Ctrl-C only set the stop it never reached). Sent with SEND_TIMEOUT_S each frame it cannot deliver is lost and
    counted, and the run ends."""
    import functools
    import time

    from radarnode.wire.bus import SEND_TIMEOUT_S
    sc = scenario(ACTORS, duration=1.0)
    node = RadarNode(sc)
    with can.Bus(interface="virtual", channel="full-reader", rx_queue_size=5) as reader, \
            can.Bus(interface="virtual", channel="full-reader") as sender:
        t0 = time.perf_counter()
        stats = run_node(node, clock=SimulatedClock(), sinks=[functools.partial(sender.send, timeout=SEND_TIMEOUT_S)])
        took = time.perf_counter() - t0
        queued = 0
        while reader.recv(0.0) is not None:
            queued += 1
    assert queued == 5 and node.counters["tx_failed"] == stats.frames - 5
    assert took < 5.0, took
