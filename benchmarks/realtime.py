"""Real-time benchmark: does each cycle go out on its deadline, whatever the model costs?

The node runs ``highway_cut_in`` in real time on a ``udp_multicast`` bus inside a private network namespace
(``unshare -rn``, loopback only, so nothing leaves the machine); a second process listens on the same group and
records the kernel receive time of every cycle header (0x60A). For each case:

* **send error**: when the node handed each cycle's header to the bus, against the schedule
  ``origin + k × period``. The origin is the earliest ``send_k − k × period`` of the run, so the error is the
  lateness against the best the run achieved (the same rule for every version of the code);
* **period**: the difference of consecutive header receive times in the listening process (median, p99,
  min, max; a cycle that was not sent shows as a doubled period);
* **missed**: cycles the node flagged as not computed in time and did not send (``cycles_missed_deadline``);
* **sent late**: cycles the bus took beyond the tolerance after the node's check passed (the process preempted in
  between), which the node flagged when the send returned (``cycles_sent_late``).

Cases: the scenario as shipped (object level), and the same with the model made artificially slower by a busy
wait of 30 and 90 ms inside every model step (holding the GIL like Python model code does): 30 ms still fits
in the 72 ms cycle, 90 ms cannot.

``--threaded`` adds the alternative design measured against it: a sender thread that sends on the deadlines
while the main thread computes ahead (no flagging: it sends whatever it has).

Run: ``python benchmarks/realtime.py`` (about 1 minute; ``--seconds``, ``--extra-ms``). ``--root DIR`` imports
radarnode from another source tree (e.g. ``git archive`` of an older commit) to measure before and after with
one script. Without ``unshare -rn`` it falls back to python-can's ``virtual`` bus in one process and says so.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parents[1]
GROUP = "239.74.163.9"
NETNS_FLAG = "RADARNODE_BENCH_NETNS"

RECEIVER = """
import json, sys, time, can
bus = can.Bus(interface="udp_multicast", channel=sys.argv[1], receive_own_messages=False)
print("listening", flush=True)
stamps, last = [], time.monotonic()
while time.monotonic() - last < float(sys.argv[2]):
    m = bus.recv(0.2)
    if m is None:
        continue
    last = time.monotonic()
    if m.arbitration_id == 0x60A:
        stamps.append(m.timestamp)
bus.shutdown()
json.dump(stamps, open(sys.argv[3], "w"))
"""


def _percentiles(x, qs=(50, 99)):
    import numpy as np
    x = np.asarray(x, dtype=float)
    return [float(np.percentile(x, q)) if x.size else float("nan") for q in qs]


def run_threaded(node, sink, vehicle, n_cycles: int) -> int:
    """The alternative measured against the runner: a sender thread sends each cycle on its deadline while the
    main thread computes the next ones (a queue of one, so up to two cycles ahead). Returns cycles sent."""
    import queue
    import threading
    q: queue.Queue = queue.Queue(maxsize=1)
    period = node.period_s
    origin = []

    def sender():
        while (item := q.get()) is not None:
            k, out = item
            deadline = origin[0] + k * period
            while (left := deadline - time.perf_counter()) > 0.0005:
                time.sleep(left - 0.0005)
            while time.perf_counter() < deadline:
                pass
            for m in out.messages:
                sink(m)

    th = threading.Thread(target=sender)
    th.start()
    for k in range(n_cycles):
        t = k * period
        for m in vehicle.frames(t):
            node.receive(m, t)
            sink(m)
        out = node.cycle(t)
        if not origin:
            origin.append(time.perf_counter())
        q.put((k, out))
    q.put(None)
    th.join()
    return n_cycles


def run_case(extra_ms: float, seconds: float, use_udp: bool, tmp: Path, threaded: bool = False) -> dict:
    import can
    import numpy as np

    from radarnode.radar.setup import load_scenario
    from radarnode.wire.node import EgoMotionSender, RadarNode
    from radarnode.wire.runner import RealTimeClock, run_node

    import dataclasses
    sc = load_scenario(HERE / "scenarios" / "highway_cut_in.yaml")
    sc = dataclasses.replace(sc, duration_s=seconds)
    node = RadarNode(sc)
    if extra_ms:
        step = node.model.step

        def slow_step(*a, **k):
            end = time.perf_counter() + extra_ms / 1e3
            while time.perf_counter() < end:     # busy: holds the GIL like Python model code
                pass
            return step(*a, **k)
        node.model.step = slow_step
    sends: list[float] = []
    receiver = None
    out_file = tmp / f"recv_{extra_ms:g}.json"
    if use_udp:
        receiver = subprocess.Popen([sys.executable, "-c", RECEIVER, GROUP, "1.5", str(out_file)],
                                    stdout=subprocess.PIPE, text=True)
        assert receiver.stdout.readline().strip() == "listening"
        bus = can.Bus(interface="udp_multicast", channel=GROUP)
        rx_stamps = None
    else:
        channel = f"bench-rt-{os.getpid()}"
        bus = can.Bus(interface="virtual", channel=channel)
        rx = can.Bus(interface="virtual", channel=channel)
        rx_stamps = []

    def sink(m):
        if m.arbitration_id == 0x60A:
            sends.append((time.perf_counter(), bytes(m.data)))
        bus.send(m)

    if threaded:
        run_threaded(node, sink, EgoMotionSender(node.scene), sc.num_cycles)
    else:
        run_node(node, clock=RealTimeClock(), sinks=[sink], recv=lambda t: bus.recv(t),
                 vehicle=EgoMotionSender(node.scene))
    if use_udp:
        bus.shutdown()
        receiver.wait(timeout=30)
        stamps = json.loads(out_file.read_text())
    else:
        while (m := rx.recv(0)) is not None:
            if m.arbitration_id == 0x60A:
                rx_stamps.append(m.timestamp)
        bus.shutdown()
        rx.shutdown()
        stamps = rx_stamps
    period = node.period_s
    s = np.array([t for t, _ in sends])
    # the cycle index from the header's MeasCounter (radarnode counts one per cycle, sent or not)
    header = node.db.get_message_by_frame_id(0x60A)
    k = np.array([header.decode(d)["Obj_MeasCounter"] for _, d in sends], dtype=float)
    err = s - k * period
    err -= err.min()
    periods = np.diff(np.asarray(stamps))
    e50, e99 = _percentiles(err * 1e3)
    p50, p99 = _percentiles(periods * 1e3)
    return {"extra_ms": extra_ms, "cycles": len(s), "missed": int(node.counters.get("cycles_missed_deadline", 0)),
            "late": int(node.counters.get("cycles_sent_late", 0)),
            "err_med": e50, "err_p99": e99, "err_max": float(err.max() * 1e3),
            "per_med": p50, "per_p99": p99, "per_min": float(periods.min() * 1e3) if periods.size else float("nan"),
            "per_max": float(periods.max() * 1e3) if periods.size else float("nan"), "received": len(stamps),
            "mode": "sender thread" if threaded else "runner"}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=15.0, help="scenario seconds per case (default 15)")
    ap.add_argument("--extra-ms", default="0,30,90", help="extra model cost per step, comma-separated (ms)")
    ap.add_argument("--root", default=None, help="import radarnode from this source tree instead of this one")
    ap.add_argument("--label", default="", help="a label for the table's first column")
    ap.add_argument("--threaded", action="store_true",
                    help="also measure the alternative: a sender thread beside the computing main thread")
    args = ap.parse_args()
    root = Path(args.root).resolve() if args.root else HERE
    in_netns = os.environ.get(NETNS_FLAG) == "1"
    if not in_netns and shutil.which("unshare") and shutil.which("ip") and \
            subprocess.run(["unshare", "-rn", "true"], capture_output=True).returncode == 0:
        setup = "ip link set lo up && ip link set lo multicast on && ip route add 224.0.0.0/4 dev lo && exec \"$@\""
        return subprocess.run(["unshare", "-rn", "bash", "-c", setup, "bash", sys.executable, *sys.argv],
                              env={**os.environ, NETNS_FLAG: "1"}).returncode
    sys.path.insert(0, str(root))
    use_udp = in_netns
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        rows = [run_case(float(x), args.seconds, use_udp, Path(tmp)) for x in args.extra_ms.split(",")]
        if args.threaded:
            rows += [run_case(float(x), args.seconds, use_udp, Path(tmp), threaded=True)
                     for x in args.extra_ms.split(",")]
    bus = "udp_multicast in `unshare -rn`" if use_udp else "python-can virtual bus, one process (no unshare)"
    print(f"highway_cut_in, {args.seconds:g} s, real time, {bus}; code: {root}")
    print("| code | extra model cost | cycles sent | missed (flagged) | sent late (flagged) | send error median | p99 | "
          "max | period median | p99 | min | max |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {args.label or root.name}{' (sender thread)' if r['mode'] != 'runner' else ''} | {r['extra_ms']:g} ms | {r['cycles']} | {r['missed']} | {r['late']} | "
              f"{r['err_med']:.2f} ms | {r['err_p99']:.2f} ms | {r['err_max']:.2f} ms | {r['per_med']:.2f} ms | "
              f"{r['per_p99']:.2f} ms | {r['per_min']:.2f} ms | {r['per_max']:.2f} ms |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
