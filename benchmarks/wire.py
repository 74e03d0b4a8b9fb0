"""Wire benchmark: encode time per cycle, frames per cycle, bus load, real-time cycle jitter.

For 1, 32 and 100 objects (pedestrians on arcs in the near field, so none hides
another), with quality and extended frames:

* encode: median time to turn the cycle's object list into CAN messages
  (radarnode's vectorised codec), and, for comparison, cantools'
  ``Message.encode`` per frame with ``strict=False`` and ``strict=True``;
* frames per cycle and bus load at 500 kbit/s (worst-case bit stuffing);
* jitter: the node run in real time on python-can's virtual bus for a few
  seconds; deviation of each cycle start from its deadline (median and max).

Run: ``python benchmarks/wire.py`` (``make bench``). Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
import uuid
from pathlib import Path

import can
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from radarnode.radar.setup import parse_scenario  # noqa: E402
from radarnode.wire import ars408 as P  # noqa: E402
from radarnode.wire.busload import bus_load  # noqa: E402
from radarnode.wire.node import RadarNode  # noqa: E402
from radarnode.wire.runner import RealTimeClock, run_node  # noqa: E402


def fan_scenario(n: int, duration: float) -> str:
    actors = []
    rings = [20.0, 27.0, 34.0, 41.0, 48.0]
    per_ring = int(np.ceil(n / len(rings)))
    for i in range(n):
        r = rings[i % len(rings)]
        k = i // len(rings)
        az = np.radians(-35.0 + 70.0 * (k + (i % len(rings)) / len(rings)) / max(per_ring, 1))
        actors.append(f"  - {{id: p{i}, class: pedestrian, x_m: {3.7 + r * np.cos(az):.3f}, "
                      f"y_m: {r * np.sin(az):.3f}, speed_mps: 0.0}}")
    return (f"name: fan{n}\nduration_s: {duration}\nseed: 1\nradar: {{preset: ars408_like, bus_load_limit: 1.0}}\n"
            f"ego: {{speed_mps: 0.0}}\nroad: {{lanes: 1, ego_lane: 0}}\nactors:\n" + "\n".join(actors) + "\n")


def encode_cycle(node: RadarNode, ol) -> list[can.Message]:
    general, quality, extended = P.object_signals(ol)
    rows = [(P.OBJ_STATUS, node.codecs[P.OBJ_STATUS].encode({"Obj_NofObjects": len(ol), "Obj_MeasCounter": 1,
                                                             "Obj_InterfaceVersion": 1})[0])]
    rows += [(P.OBJ_GENERAL, r) for r in node.codecs[P.OBJ_GENERAL].encode(general)]
    rows += [(P.OBJ_QUALITY, r) for r in node.codecs[P.OBJ_QUALITY].encode(quality)]
    rows += [(P.OBJ_EXTENDED, r) for r in node.codecs[P.OBJ_EXTENDED].encode(extended)]
    return [can.Message(arbitration_id=i, data=p.tobytes(), is_extended_id=False, check=False) for i, p in rows]


def cantools_cycle(node: RadarNode, ol, strict: bool) -> list[can.Message]:
    db = node.db
    out = []
    for fid, sig in zip((P.OBJ_GENERAL, P.OBJ_QUALITY, P.OBJ_EXTENDED), P.object_signals(ol)):
        msg = db.get_message_by_frame_id(fid)
        for k in range(len(ol)):
            values = {name: float(np.clip(v[k], msg.get_signal_by_name(name).minimum,
                                          msg.get_signal_by_name(name).maximum)) for name, v in sig.items()}
            out.append(can.Message(arbitration_id=fid, data=msg.encode(values, strict=strict), is_extended_id=False))
    return out


def timed(fn, repeat: int) -> float:
    samples = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t0)
    return statistics.median(samples)


def jitter(n: int, seconds: float) -> tuple[float, float, int, float, int]:
    """Real time on python-can's virtual bus: median and largest |send time − the cycle's own deadline| (ms; the
    runner's send error, so a dropped cycle does not shift the ones after it), cycles sent, frames a cycle sent, and
    cycles dropped and flagged (not ready in time) or sent late and flagged."""
    sc = parse_scenario(fan_scenario(n, seconds))
    node = RadarNode(sc)
    channel = f"bench-{uuid.uuid4().hex}"
    with can.Bus(interface="virtual", channel=channel) as tx, can.Bus(interface="virtual", channel=channel) as rx:
        stats = run_node(node, clock=RealTimeClock(), sinks=[tx.send], recv=lambda t: tx.recv(t))
        while rx.recv(0) is not None:
            pass
    dev = np.abs(np.array(stats.send_error_s)) * 1e3
    return (float(np.median(dev)), float(np.max(dev)), stats.cycles, stats.frames / max(stats.cycles, 1),
            stats.missed + stats.sent_late)


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()      # (--help; no options)
    print("| objects | frames/cycle | bus load @500 kbit/s | encode median (radarnode) | cantools strict=False | "
          "cantools strict=True | speed-up vs strict=False | jitter median | jitter max |")
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in (1, 32, 100):
        sc = parse_scenario(fan_scenario(n, 2.0))
        node = RadarNode(sc)
        ol = None
        for k in range(5):
            ol = node.cycle(k * node.period_s).frame.objects
        # exactly n objects for the encode figures: repeat the model's objects, fresh IDs
        ol = ol.take(np.resize(np.arange(len(ol)), n))
        ol.id = np.arange(n, dtype=np.int64)
        msgs = encode_cycle(node, ol)
        dlcs = [len(m.data) for m in msgs]
        t_ours = timed(lambda: encode_cycle(node, ol), 500)
        t_ct = timed(lambda: cantools_cycle(node, ol, False), 20)
        t_cts = timed(lambda: cantools_cycle(node, ol, True), 20)
        j_med, j_max, cycles, sent, flagged = jitter(n, 3.0)
        print(f"| {len(ol)} | {len(msgs)} | {100 * bus_load(dlcs, 500_000, node.period_s):.1f} % | "
              f"{t_ours * 1e3:.3f} ms | {t_ct * 1e3:.3f} ms | {t_cts * 1e3:.3f} ms | {t_ct / t_ours:.1f}x | "
              f"{j_med:.3f} ms | {j_max:.3f} ms ({sent:.0f} frames/cycle sent, {flagged} cycles flagged) |", flush=True)


if __name__ == "__main__":
    main()
