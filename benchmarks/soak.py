"""Soak and abuse: a node and a consumer ECU in two processes over udp_multicast, for minutes, then bad traffic.

Three processes on one ``udp_multicast`` group inside a private network namespace (``unshare -rn``, loopback
only: nothing leaves the machine):

* **node**: ``RadarNode`` on a highway scene that keeps its traffic for as long as it runs (vehicles at the
  ego's speed, some of them slowly oscillating, guardrails on both sides: object list, road boundaries and
  collision detection all busy), paced in real time by the runner, with the vehicle's 0x300/0x301;
* **ECU**: a ``CycleAssembler`` that configures the sensor at start (a collision-detection region ahead,
  collision detection on), records every cycle it assembles, and half-way through the abuse phase sends a
  valid FilterCfg (objects, Distance 0–60 m) — again every 0.5 s until FilterState answers it, as an ECU
  does — and checks that it is applied;
* **abuser** (abuse phase only): floods the node's inputs at a steady rate (default 4000 frames/s, about what a
  saturated 500 kbit/s bus carries) with malformed and useless frames on 0x200, 0x202, 0x300, 0x301, 0x400
  and 0x401 — wrong DLCs, refused values, out-of-range signals, remote and error frames, no-op configuration,
  extended IDs, other sensors' IDs, datagrams that are no CAN frame at all — and counts what the node should
  refuse.

Figures, per phase (soak: the first ``--minutes``; abuse: the ``--abuse-seconds`` after it):

* **send error**: when the node handed each cycle's header to the bus, against ``origin + k × period``
  (the origin is the run's earliest ``send_k − k × period``; ``k`` from MeasCounter), median / p99 / max;
* **period**: consecutive header receive times (kernel time stamps) in the ECU process, median / p99 / max;
* **drift**: receive time of the last header minus that of the first, against ``(k_last − k_first) × period``;
* **frames lost**: the node's frames handed to the bus minus the frames of the node's IDs the ECU received;
  cycles lost (MeasCounter gaps the node did not flag as missed) and incomplete cycles;
* **memory**: resident set size (VmRSS) of the node and the ECU at the start and at the end of the phase;
* **refused**: for each kind of bad frame, how many the abuser sent and how many the node counted; the
  difference is what the kernel dropped before the node read it (its socket's receive buffer was full;
  ``radarnode.wire.bus.enlarge_receive_buffer`` gives it 4 MiB, as ``radarnode node`` does).

Run: ``python benchmarks/soak.py --minutes 10`` (I/O-paced: light on CPU). ``--json FILE`` also writes
every figure. ``tests/test_soak.py`` runs a short version.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(HERE))
GROUP = "239.74.163.17"
PORT = 43113                 # python-can's udp_multicast default port
NETNS_FLAG = "RADARNODE_SOAK_NETNS"
PERIOD_S = 0.072
# what the node sends (sensor 0): status, configuration replies, list frames, own frames
NODE_TX = {0x201, 0x700, 0x203, 0x204, 0x408, 0x402, 0x008, 0x60A, 0x60B, 0x60C, 0x60D, 0x60E, 0x680, 0x681}
REGION = {"CollDetRegCfg_RegionID": 0, "CollDetRegCfg_Point1X": 10.0, "CollDetRegCfg_Point1Y": -2.0,
          "CollDetRegCfg_Point2X": 80.0, "CollDetRegCfg_Point2Y": 2.0}
VALID_FILTER_MAX_M = 60.0


def scenario_yaml(duration_s: float) -> str:
    """A highway that keeps its traffic: vehicles at the ego's speed, three of them oscillating ±1 m/s."""
    def osc(phase: float) -> str:
        steps, t, a = [], 0.0, 0.2
        steps.append(f"{{t_s: 0.0, accel_mps2: {a if phase == 0 else -a}}}")
        t = 5.0
        while t < duration_s:
            a = -a
            steps.append(f"{{t_s: {t:.1f}, accel_mps2: {a if phase == 0 else -a}}}")
            t += 10.0
        return "[" + ", ".join(steps) + "]"
    v = 27.8
    return f"""
name: soak_highway
description: highway traffic that stays around the ego for as long as the run lasts
duration_s: {duration_s:.3f}
seed: 11
radar: {{preset: ars408_like, sensor_id: 0, output: objects, sort_index: range}}
ego: {{speed_mps: {v}}}
road: {{lanes: 3, lane_width_m: 3.5, ego_lane: 1, guardrails: {{left_offset_m: 1.0, right_offset_m: 1.0,
        post_spacing_m: 2.0}}}}
actors:
  - {{id: lead, class: car, x_m: 45.0, lane: 1, speed_mps: {v}, accel: {osc(0)}}}
  - {{id: far_lead, class: car, x_m: 95.0, lane: 1, speed_mps: {v}}}
  - {{id: truck, class: truck, x_m: 70.0, lane: 0, speed_mps: {v}, accel: {osc(1)}}}
  - {{id: left, class: car, x_m: 30.0, lane: 2, speed_mps: {v}, accel: {osc(0)}}}
  - {{id: far_left, class: car, x_m: 140.0, lane: 2, speed_mps: {v}}}
  - {{id: far_right, class: motorcycle, x_m: 120.0, lane: 0, speed_mps: {v}}}
"""


def socket_drops(bus) -> int:
    """Datagrams the kernel dropped for this python-can udp_multicast bus's socket (its receive buffer was
    full): the ``drops`` column of /proc/net/udp; -1 where that cannot be read."""
    try:
        inode = os.fstat(bus._multicast._socket.fileno()).st_ino
        with open("/proc/net/udp") as f:
            for line in f.readlines()[1:]:
                cols = line.split()
                if int(cols[9]) == inode:
                    return int(cols[-1])
    except (AttributeError, OSError, ValueError, IndexError):
        pass
    return -1


def rss_kb() -> int:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1])
    return -1


# --- node process -----------------------------------------------------------------------------------------------

def role_node(args) -> int:
    import can

    from radarnode.radar.setup import parse_scenario
    from radarnode.wire.node import EgoMotionSender, RadarNode
    from radarnode.wire.runner import RealTimeClock, run_node

    from radarnode.wire.bus import enlarge_receive_buffer

    sc = parse_scenario(scenario_yaml(args.total), "soak.yaml")
    node = RadarNode(sc)
    bus = can.Bus(interface="udp_multicast", channel=GROUP, receive_own_messages=False)
    enlarge_receive_buffer(bus)             # as `radarnode node` opens it
    # every header's send time goes straight to a file, so that the process's memory is the node's, not the
    # benchmark's records
    records = open(args.out + ".headers", "w", buffering=1 << 16)
    header_codec = node.db.get_message_by_frame_id(0x60A)
    rss: list[tuple[float, int]] = []
    sent_node_frames = [0]

    def sink(m):
        if m.arbitration_id in NODE_TX:
            sent_node_frames[0] += 1
        if m.arbitration_id == 0x60A:
            p, w = time.perf_counter(), time.time()
            records.write(f"{p!r} {w!r} {m.data[1] << 8 | m.data[2]}\n")     # Obj_MeasCounter: 15|16
        bus.send(m)

    next_rss = [0.0]

    def on_cycle(out):
        now = time.time()
        if now >= next_rss[0]:
            rss.append((now, rss_kb()))
            next_rss[0] = now + 5.0
            if len(rss) == 1:
                print("started", flush=True)

    stats = run_node(node, clock=RealTimeClock(), sinks=[sink], recv=lambda t: bus.recv(t),
                     vehicle=EgoMotionSender(node.scene), on_cycle=on_cycle)
    rss.append((time.time(), rss_kb()))
    drops = socket_drops(bus)
    bus.shutdown()
    records.close()
    assert header_codec.decode(bytes([0, 0x12, 0x34, 0x10]))["Obj_MeasCounter"] == 0x1234   # the slice above
    headers = [(float(p), float(w), int(k)) for p, w, k in
               (line.split() for line in open(args.out + ".headers"))]
    json.dump({"headers": headers, "rss": rss, "counters": dict(node.counters), "cycles": stats.cycles, "missed": stats.missed,
               "frames_node_ids": sent_node_frames[0], "rx_drain_cut": stats.rx_drain_cut,
               "period_s": node.period_s, "socket_drops": drops}, open(args.out, "w"))
    return 0


# --- ECU process --------------------------------------------------------------------------------------------------

def role_ecu(args) -> int:
    import can
    import numpy as np

    from radarnode.consumer.assembler import CycleAssembler
    from radarnode.wire.bus import enlarge_receive_buffer
    from radarnode.wire.dbc import load_database

    db = load_database()

    def frame(name, **values):
        m = db.get_message_by_name(name)
        if not m.is_multiplexed():
            values = {**{s.name: 0 for s in m.signals}, **values}
        return can.Message(arbitration_id=m.frame_id, data=m.encode(values), is_extended_id=False)

    bus = can.Bus(interface="udp_multicast", channel=GROUP, receive_own_messages=False)
    enlarge_receive_buffer(bus)             # as `radarnode consume` opens it
    asm = CycleAssembler(cycle_timeout_s=0.2)
    print("listening", flush=True)
    # per cycle: header receive time, MeasCounter, objects, farthest object (m), objects warning, when assembled;
    # streamed to a file so that the process's memory is the consumer's, not the benchmark's records
    records = open(args.out + ".cycles", "w", buffering=1 << 16)
    rss = [(time.time(), rss_kb())]
    node_frames = 0
    configured = False
    valid_sent_at = None
    valid_answered_at = None
    valid_tries = 0
    valid_at = None
    next_check = 0.0
    last = time.monotonic()
    started = False
    next_rss = time.time() + 5.0
    recv_errors = 0
    while True:
        try:
            m = bus.recv(0.2)
        except can.CanError:            # a datagram that is no CAN frame (the abuser sends some)
            recv_errors += 1
            asm.on_error(sys.exc_info()[1])
            continue
        now_w = time.time()
        if now_w >= next_rss:
            rss.append((now_w, rss_kb()))
            next_rss = now_w + 5.0
        if m is None:
            asm.expire()
            if started and time.monotonic() - last > args.silence:
                break
        else:
            last = time.monotonic()
            if m.arbitration_id in NODE_TX:
                node_frames += 1
                started = True
            asm.on_message_received(m)
        if started and not configured:
            # the ECU configures the sensor as it starts: a region ahead, collision detection on
            bus.send(frame("CollDetRegionCfg", CollDetRegCfg_Activate=1, CollDetRegCfg_Coordinates_valid=1,
                           **REGION))
            bus.send(frame("CollDetCfg", CollDetCfg_Activate=1, CollDetCfg_MinTime_valid=1,
                           CollDetCfg_MinDetectTime=0.5))
            configured = True
        if valid_at is None and args.valid_file and now_w >= next_check:
            next_check = now_w + 0.5
            if os.path.exists(args.valid_file):
                valid_at = float(Path(args.valid_file).read_text())
        # like an ECU, it sends the configuration again when no answer came within half a second
        if valid_at is not None and now_w >= valid_at and valid_answered_at is None and (
                valid_sent_at is None or now_w >= valid_sent_at + 0.5 * valid_tries):
            bus.send(frame("FilterCfg", FilterCfg_Valid=1, FilterCfg_Active=1, FilterCfg_Index=1, FilterCfg_Type=1,
                           FilterCfg_Min_Distance=0.0, FilterCfg_Max_Distance=VALID_FILTER_MAX_M))
            valid_sent_at = now_w if valid_sent_at is None else valid_sent_at
            valid_tries += 1
        if valid_sent_at is not None and valid_answered_at is None:
            f = asm.filter_state.get((1, 1))
            if f is not None and f["FilterState_Max_Distance"] == VALID_FILTER_MAX_M and f["FilterState_Active"]:
                valid_answered_at = now_w
        for c in asm.drain():
            ol = c.objects
            records.write(f"{c.timestamp!r} {c.meas_counter} {len(ol)} {float(np.max(ol.range_m, initial=0.0))!r} "
                          f"{int(np.count_nonzero(c.collision_regions)) if c.collision_regions is not None else -1} "
                          f"{now_w!r}\n")
    asm.flush()
    for c in asm.drain():
        records.write(f"{c.timestamp!r} {c.meas_counter} {len(c.objects)} "
                      f"{float(np.max(c.objects.range_m, initial=0.0))!r} -1 {time.time()!r}\n")
    rss.append((time.time(), rss_kb()))
    drops = socket_drops(bus)
    bus.shutdown()
    records.close()
    cycles = [(float(t), int(k), int(n), float(r), int(w), float(at)) for t, k, n, r, w, at in
              (line.split() for line in open(args.out + ".cycles"))]
    json.dump({"socket_drops": drops, "cycles": cycles, "rss": rss, "stats": asm.stats.as_dict(), "node_frames": node_frames,
               "valid_sent_at": valid_sent_at, "valid_answered_at": valid_answered_at, "valid_tries": valid_tries,
               "coll_det_active": bool(asm.coll_det_state and asm.coll_det_state["CollDetState_Active"]),
               "recv_errors": recv_errors}, open(args.out, "w"))
    return 0


# --- abuser process -----------------------------------------------------------------------------------------------

def abuse_frames(rng, db):
    """Yield (frame or raw datagram, what the node should count) forever: malformed and useless input."""
    import can

    def enc(name, **values):
        m = db.get_message_by_name(name)
        if not m.is_multiplexed():
            values = {**{s.name: 0 for s in m.signals}, **values}
        return m.encode(values)

    def msg(can_id, data, **kw):
        return can.Message(arbitration_id=can_id, data=data, is_extended_id=kw.pop("ext", False), **kw)

    dlc = {0x200: 8, 0x202: 8, 0x300: 2, 0x301: 2, 0x400: 2, 0x401: 8}
    refused_200 = [dict(RadarCfg_OutputType_valid=1, RadarCfg_OutputType=3),
                   dict(RadarCfg_RadarPower_valid=1, RadarCfg_RadarPower=5),
                   dict(RadarCfg_MaxDistance_valid=1, RadarCfg_MaxDistance=1000),
                   dict(RadarCfg_MaxDistance_valid=1, RadarCfg_MaxDistance=4),
                   dict(RadarCfg_SortIndex_valid=1, RadarCfg_SortIndex=6),
                   dict(RadarCfg_RCS_Threshold_Valid=1, RadarCfg_RCS_Threshold=3)]
    filt = db.get_message_by_name("FilterCfg")

    def filter_bytes(index, lo_raw, hi_raw, ftype=1, valid=1):
        # raw 12-bit fields (bits 11|12 and 27|12, Motorola), to reach values cantools would not encode
        word = (valid << 1 | 1 << 2 | index << 3 | ftype << 7) << 56 | (lo_raw & 0xFFF) << 40 | (hi_raw & 0xFFF) << 24
        return word.to_bytes(8, "big")
    assert filt.decode(filter_bytes(8, 0, 4095))["FilterCfg_Max_ProbExists"] == 4095
    refused_202 = [lambda: filter_bytes(15, 0, 10), lambda: filter_bytes(1, 3000, 100),
                   lambda: filter_bytes(6, 0, 100, ftype=0), lambda: filter_bytes(8, 0, 4095),
                   lambda: filter_bytes(7, 0, 10, ftype=0)]
    while True:
        kind = int(rng.integers(16))
        base = int(rng.choice(list(dlc)))
        if kind <= 3:               # a wrong DLC on any input (FilterCfg is taken with 5 to 8 bytes: 0…4 are wrong)
            n = int(rng.choice([d for d in range(9) if d != dlc[base] and not (base == 0x202 and d >= 5)]))
            yield msg(base, bytes(rng.integers(0, 256, n, dtype="u1"))), "rx_wrong_dlc"
        elif kind == 4:             # RadarConfiguration with one refused field
            yield msg(0x200, enc("RadarConfiguration", **refused_200[int(rng.integers(len(refused_200)))])), \
                "config_rejected"
        elif kind == 5:             # RadarConfiguration that changes nothing (no valid bit): a flood of valid frames
            yield msg(0x200, enc("RadarConfiguration")), "rx_config"
        elif kind == 6:             # a refused FilterCfg
            yield msg(0x202, refused_202[int(rng.integers(len(refused_202)))]()), "config_rejected"
        elif kind == 7:             # FilterCfg with Valid 0: changes nothing
            yield msg(0x202, filter_bytes(1, 0, 100, valid=0)), "rx_filter_cfg"
        elif kind == 8:             # speed with the reserved direction 3 (the top two bits)
            yield msg(0x300, bytes([0xC0 | int(rng.integers(0, 32)), int(rng.integers(0, 256))])), \
                "rx_invalid_speed_direction"
        elif kind == 9:             # yaw rate 0xFFFF: beyond the signal's range
            yield msg(0x301, b"\xff\xff"), "rx_out_of_range"
        elif kind == 10:            # a region switched without corners (regions 5..7 are never defined)
            yield msg(0x401, enc("CollDetRegionCfg", CollDetRegCfg_Activate=1,
                                 CollDetRegCfg_RegionID=int(rng.integers(5, 8)))), "config_rejected"
        elif kind == 11:            # remote frames on the inputs
            yield can.Message(arbitration_id=base, is_remote_frame=True, dlc=dlc[base], is_extended_id=False), \
                "rx_remote_frames"
        elif kind == 12:            # error frames
            yield can.Message(is_error_frame=True), "rx_error_frames"
        elif kind == 13:            # not for this node: 29-bit IDs, other sensors' inputs
            if rng.integers(2):
                yield msg(base, bytes(rng.integers(0, 256, 8, dtype="u1")), ext=True), "ignored"
            else:
                yield msg(base + 0x10 * int(rng.integers(1, 8)), bytes(rng.integers(0, 256, dlc[base], dtype="u1"))), \
                    "ignored"
        elif kind == 14:            # a datagram that is no CAN frame at all
            yield bytes(rng.integers(0, 256, int(rng.integers(1, 40)), dtype="u1")), "rx_unreadable"
        else:                       # 0x400 with a wrong DLC (every bit combination of a right one is meaningful)
            n = int(rng.choice([0, 1, 3, 4, 5, 6, 7, 8]))
            yield msg(0x400, bytes(rng.integers(0, 256, n, dtype="u1"))), "rx_wrong_dlc"


def role_abuser(args) -> int:
    import can
    import numpy as np

    from radarnode.wire.dbc import load_database

    from can.interfaces.udp_multicast.utils import pack_message

    rng = np.random.default_rng(5)
    gen = abuse_frames(rng, load_database())
    # a send-only socket, packed as python-can's udp_multicast packs a frame (a bus would also receive, and drop,
    # everything on the group)
    raw = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    raw.setsockopt(socket.IPPROTO_IP, socket.IP_MULTICAST_TTL, 1)
    counts: dict[str, int] = {}
    print("ready", flush=True)
    time.sleep(max(0.0, args.start_at - time.time()))
    t0 = time.perf_counter()
    sent = 0
    start_wall = time.time()
    while True:
        now = time.perf_counter() - t0
        if now >= args.seconds:
            break
        due = int(now * args.rate) + 1
        while sent < due:
            item, what = next(gen)
            if isinstance(item, can.Message):
                item.timestamp = time.time()
                item = pack_message(item)
            raw.sendto(item, (GROUP, PORT))
            counts[what] = counts.get(what, 0) + 1
            sent += 1
        time.sleep(0.002)
    end_wall = time.time()
    json.dump({"counts": counts, "sent": sent, "start": start_wall, "end": end_wall}, open(args.out, "w"))
    return 0


# --- the parent: start, wait, evaluate ----------------------------------------------------------------------------

def _pct(x, q):
    import numpy as np
    x = np.asarray(x, dtype=float)
    return float(np.percentile(x, q)) if x.size else float("nan")


def phase_figures(node: dict, ecu: dict, lo: float, hi: float) -> dict:
    """Figures of the cycles whose headers the node sent between wall times ``lo`` and ``hi``."""
    import numpy as np
    period = node["period_s"]
    h = np.array([(p, w, k) for p, w, k in node["headers"]], dtype=float)
    k_all = np.unwrap(h[:, 2], period=65536) if len(h) else h
    err_all = h[:, 0] - k_all * period
    err_all -= err_all.min()
    sel = (h[:, 1] >= lo) & (h[:, 1] < hi)
    err = err_all[sel] * 1e3
    c = np.array([(t, k) for t, k, *_ in ecu["cycles"]], dtype=float)
    c = c[np.isfinite(c[:, 0])]
    kc = np.unwrap(c[:, 1], period=65536)
    csel = (c[:, 0] >= lo) & (c[:, 0] < hi)
    t, kk = c[csel, 0], kc[csel]
    periods = np.diff(t) * 1e3
    # drift: the slope of receive time over cycle index against the period, times the phase's length (a fit, so
    # that the jitter of the first and last cycle does not count as drift)
    drift = (np.polyfit(kk - kk[0], t - t[0], 1)[0] - period) * (kk[-1] - kk[0]) * 1e3 if len(t) > 2 else math.nan
    gaps = np.diff(kk) - 1
    rss_n = [r for w, r in node["rss"] if lo - 6 <= w <= hi + 6]
    rss_e = [r for w, r in ecu["rss"] if lo - 6 <= w <= hi + 6]

    def growth(samples):
        """KiB per minute after the first minute of the phase (a straight-line fit), and RSS at one minute."""
        pts = np.array([(w, r) for w, r in samples if lo + 60 <= w <= hi], dtype=float)
        if len(pts) < 3:
            return math.nan, math.nan
        return float(np.polyfit(pts[:, 0] / 60.0, pts[:, 1], 1)[0]), float(pts[0, 1])
    return {"cycles_sent": int(sel.sum()), "cycles_received": int(csel.sum()),
            "err_med": _pct(err, 50), "err_p99": _pct(err, 99), "err_max": float(err.max()) if err.size else math.nan,
            "per_med": _pct(periods, 50), "per_p99": _pct(periods, 99),
            "per_max": float(periods.max()) if periods.size else math.nan,
            "drift_ms": drift, "span_s": float(t[-1] - t[0]) if len(t) > 1 else 0.0,
            "gaps": int(gaps[gaps > 0].sum()) if gaps.size else 0,
            "rss_node": (rss_n[0], rss_n[-1]) if rss_n else (-1, -1),
            "rss_ecu": (rss_e[0], rss_e[-1]) if rss_e else (-1, -1),
            "rss_node_growth": growth(node["rss"]), "rss_ecu_growth": growth(ecu["rss"])}


def udp_rcvbuf_errors() -> int:
    """UDP datagrams this network namespace's kernel dropped because a receive buffer was full."""
    with open("/proc/net/snmp") as f:
        rows = [line.split() for line in f if line.startswith("Udp:")]
    return int(rows[1][rows[0].index("RcvbufErrors")]) if len(rows) == 2 else -1


def run(args) -> dict:
    soak_s = args.minutes * 60.0
    total = soak_s + args.abuse_seconds + 2.0
    tmp = Path(tempfile.mkdtemp(prefix="radarnode-soak-"))
    me = [sys.executable, str(Path(__file__).resolve())]
    env = {**os.environ, "PYTHONPATH": str(HERE)}
    valid_file = tmp / "valid_at"
    logs = {r: open(tmp / f"{r}.err", "w") for r in ("ecu", "node", "abuser")}
    load_start = os.getloadavg()
    ecu = subprocess.Popen([*me, "--role", "ecu", "--out", str(tmp / "ecu.json"), "--valid-file", str(valid_file),
                            "--silence", "3"], stdout=subprocess.PIPE, stderr=logs["ecu"], text=True, env=env)
    assert ecu.stdout.readline().strip() == "listening"
    node = subprocess.Popen([*me, "--role", "node", "--out", str(tmp / "node.json"), "--total", str(total)],
                            stdout=subprocess.PIPE, stderr=logs["node"], text=True, env=env)
    assert node.stdout.readline().strip() == "started"
    t_node = time.time()
    abuse = None
    if args.abuse_seconds > 0:
        # the ECU sends its valid FilterCfg half-way through the flood
        (tmp / "valid.tmp").write_text(repr(t_node + soak_s + args.abuse_seconds / 2))
        (tmp / "valid.tmp").rename(valid_file)
        # started ahead (python's start-up is seconds on a loaded machine), flooding from the soak's end on
        time.sleep(max(0.0, t_node + soak_s - 15.0 - time.time()))
        abuse = subprocess.Popen([*me, "--role", "abuser", "--out", str(tmp / "abuser.json"),
                                  "--seconds", str(args.abuse_seconds), "--rate", str(args.flood_rate),
                                  "--start-at", repr(t_node + soak_s)], stdout=subprocess.PIPE,
                                 stderr=logs["abuser"], text=True, env=env)
        assert abuse.stdout.readline().strip() == "ready"
    if node.wait() != 0 or (abuse is not None and abuse.wait() != 0):
        raise SystemExit("a process of the soak failed")
    if ecu.wait(timeout=60) != 0:
        raise SystemExit("the ECU process failed")
    for f in logs.values():
        f.close()
    n = json.loads((tmp / "node.json").read_text())
    e = json.loads((tmp / "ecu.json").read_text())
    a = json.loads((tmp / "abuser.json").read_text()) if abuse is not None else None
    warnings = {r: (tmp / f"{r}.err").read_text() for r in logs}
    shutil.rmtree(tmp, ignore_errors=True)
    first = n["headers"][0][1]
    soak_end = a["start"] if a else math.inf
    res = {"minutes": args.minutes, "abuse_seconds": args.abuse_seconds, "flood_rate": args.flood_rate,
           "soak": phase_figures(n, e, first - 1.0, soak_end),
           "node": {k: n[k] for k in ("counters", "cycles", "missed", "frames_node_ids", "rx_drain_cut")},
           "ecu": {k: e[k] for k in ("stats", "node_frames", "coll_det_active", "recv_errors")},
           "frames_lost": n["frames_node_ids"] - e["node_frames"], "udp_rcvbuf_errors": udp_rcvbuf_errors(),
           "socket_drops": {"node": n["socket_drops"], "ecu": e["socket_drops"]},
           "load_average": (load_start, os.getloadavg()), "warnings": warnings,
           "rss_series": {"node": n["rss"], "ecu": e["rss"]}}
    if a:
        res["abuse"] = phase_figures(n, e, a["start"], a["end"] + 0.5)
        res["abuser"] = a
        # what the node counted against what the abuser sent, for each kind
        c = n["counters"]
        res["refused"] = {k: (a["counts"].get(k, 0), c.get(k, 0)) for k in
                          ("rx_wrong_dlc", "config_rejected", "rx_invalid_speed_direction", "rx_out_of_range",
                           "rx_remote_frames", "rx_error_frames", "rx_unreadable")}
        vs, va = e["valid_sent_at"], e["valid_answered_at"]
        after = [x for x in e["cycles"] if vs is not None and x[5] > (va or math.inf) + 2 * PERIOD_S]
        res["valid"] = {"sent": vs is not None, "answered_ms": (va - vs) * 1e3 if vs and va else None,
                        "tries": e["valid_tries"],
                        "cycles_after": len(after),
                        "farthest_after_m": max((x[3] for x in after), default=None),
                        "farthest_before_m": max((x[3] for x in e["cycles"] if vs and x[5] < vs), default=None)}
    return res


def print_table(res: dict, command: str) -> None:
    rows = [("soak", res["soak"])] + ([("abuse", res["abuse"])] if "abuse" in res else [])
    print(f"$ {command}")
    print("| phase | cycles sent | not sent (flagged) | send error median / p99 / max | "
          "period median / p99 / max | drift | RSS node start → [1 min →] end | RSS ECU start → [1 min →] end |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")

    def mem(r, who):
        start, end = r[f"rss_{who}"]
        slope, at1 = r[f"rss_{who}_growth"]
        if math.isnan(slope):
            return f"{start / 1024:.1f} → {end / 1024:.1f} MiB"
        return f"{start / 1024:.1f} → {at1 / 1024:.1f} → {end / 1024:.1f} MiB ({slope:+.0f} KiB/min after 1 min)"
    for name, r in rows:
        print(f"| {name} ({r['span_s'] / 60:.1f} min) | {r['cycles_sent']} | {r['gaps']} | {r['err_med']:.2f} / "
              f"{r['err_p99']:.2f} / {r['err_max']:.2f} ms | {r['per_med']:.2f} / {r['per_p99']:.2f} / "
              f"{r['per_max']:.2f} ms | {r['drift_ms']:+.2f} ms over {r['span_s']:.0f} s | {mem(r, 'node')} | "
              f"{mem(r, 'ecu')} |")
    st, node = res["ecu"]["stats"], res["node"]
    (l1, _, _), (l2, _, _) = res["load_average"]
    print(f"node: {node['cycles']} cycles sent, {node['missed']} not sent and flagged (Temporary_Error), "
          f"{node['frames_node_ids']} frames; ECU: {res['ecu']['node_frames']} of those frames received (lost "
          f"{res['frames_lost']}), {st['cycles']} cycles assembled, {st['incomplete_cycles']} incomplete, "
          f"{st['lost_cycles']} MeasCounter gaps ({st['lost_cycles'] - node['missed']} not flagged by the node); "
          f"collision detection on at the end: {res['ecu']['coll_det_active']}; datagrams the kernel dropped "
          f"(receive buffer full): node {res['socket_drops']['node']}, ECU {res['socket_drops']['ecu']}; load "
          f"average {l1:.2f} at the start, {l2:.2f} at the end")
    if "abuse" in res:
        a = res["abuser"]
        print(f"abuse: {a['sent']} frames in {a['end'] - a['start']:.1f} s ({a['sent'] / (a['end'] - a['start']):.0f}/s); "
              "refused by the node (sent / counted): " + ", ".join(f"{k} {s}/{c}" for k, (s, c) in res["refused"].items())
              + f"; not for the node, ignored: {a['counts'].get('ignored', 0)}; no-op configuration (applied, changes "
              f"nothing): {a['counts'].get('rx_config', 0)} RadarConfiguration, {a['counts'].get('rx_filter_cfg', 0)} "
              f"FilterCfg; polls cut short with input queued: {node['rx_drain_cut']}")
        v = res["valid"]
        print(f"valid FilterCfg (objects, Distance 0–{VALID_FILTER_MAX_M:g} m) half-way through the flood: answered "
              f"(FilterState) {v['answered_ms']:.0f} ms after it was first sent ({v['tries']} "
              f"{'try' if v['tries'] == 1 else 'tries'}, resent every 0.5 s until answered); farthest object "
              f"{v['farthest_before_m']:.1f} m "
              f"before, {v['farthest_after_m']:.1f} m in the {v['cycles_after']} cycles after"
              if v["answered_ms"] is not None else f"valid FilterCfg during the flood: NOT answered ({v})")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--minutes", type=float, default=10.0, help="length of the soak phase (default 10)")
    ap.add_argument("--abuse-seconds", type=float, default=60.0,
                    help="length of the abuse phase after it (default 60; 0: none)")
    ap.add_argument("--flood-rate", type=float, default=4000.0, help="abuse frames per second (default 4000)")
    ap.add_argument("--json", default=None, help="also write every figure to this file")
    ap.add_argument("--role", choices=("node", "ecu", "abuser"), help=argparse.SUPPRESS)
    ap.add_argument("--out", help=argparse.SUPPRESS)
    ap.add_argument("--total", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--valid-file", default=None, help=argparse.SUPPRESS)
    ap.add_argument("--silence", type=float, default=3.0, help=argparse.SUPPRESS)
    ap.add_argument("--seconds", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--rate", type=float, help=argparse.SUPPRESS)
    ap.add_argument("--start-at", type=float, default=0.0, help=argparse.SUPPRESS)
    ap.add_argument("-v", "--verbose", action="store_true", help="also print the processes' warnings")
    args = ap.parse_args()
    if args.role == "node":
        return role_node(args)
    if args.role == "ecu":
        return role_ecu(args)
    if args.role == "abuser":
        return role_abuser(args)
    for name in ("minutes", "abuse_seconds", "flood_rate"):
        v = getattr(args, name)
        if not (math.isfinite(v) and v >= 0) or (name == "minutes" and v <= 0):
            ap.error(f"--{name.replace('_', '-')}: value {v!r} is not allowed; expected a finite number "
                     f"{'> 0' if name == 'minutes' else '>= 0'}")
    if os.environ.get(NETNS_FLAG) != "1":
        if not (shutil.which("unshare") and shutil.which("ip")
                and subprocess.run(["unshare", "-rn", "true"], capture_output=True).returncode == 0):
            print("error: the soak needs a private network namespace (unshare -rn and iproute2) so that its "
                  "udp_multicast traffic never leaves this machine; not available here", file=sys.stderr)
            return 1
        setup = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && exec \"$@\""
        return subprocess.run(["unshare", "-rn", "bash", "-c", setup, "bash", sys.executable, *sys.argv],
                              env={**os.environ, NETNS_FLAG: "1"}).returncode
    res = run(args)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=1))
    command = "python benchmarks/soak.py " + " ".join(sys.argv[1:])
    print_table(res, command.strip())
    if args.verbose:
        for role, text in res["warnings"].items():
            if text.strip():
                print(f"--- {role} process:\n{text.rstrip()}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
