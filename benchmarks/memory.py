"""The node's resident memory over a long run in simulated time: does it level off?

The soak's scene (``benchmarks/soak.py``: traffic around the ego for the whole run, object list, road boundaries),
the node stepped as fast as it computes with the vehicle's ego-motion frames, for ``--cycles`` cycles; the
process's resident set size (``/proc/self/statm``, after a garbage collection) every ``--every`` cycles. The
object level's chunks grow to their full size in the first few thousand cycles; after that the memory must stay
flat.

Run: ``python benchmarks/memory.py [--cycles 30000] [--every 3000] [--root DIR]``. Prints a Markdown table.
"""

from __future__ import annotations

import argparse
import gc
import sys

from tree import use_tree  # --root DIR: radarnode from another tree

use_tree()

from radarnode.radar.setup import parse_scenario  # noqa: E402
from radarnode.wire.node import EgoMotionSender, RadarNode  # noqa: E402
from soak import scenario_yaml  # noqa: E402


def rss_mib() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * 4096 / 2 ** 20


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cycles", type=int, default=30000)
    ap.add_argument("--every", type=int, default=3000)
    ap.add_argument("--root", help="import radarnode from this tree")
    args = ap.parse_args()
    node = RadarNode(parse_scenario(scenario_yaml(args.cycles * 0.072 + 1.0), "soak.yaml"))
    vehicle = EgoMotionSender(node.scene)
    print(f"| cycles | resident memory ({sys.modules['radarnode'].__file__.rsplit('/', 2)[0]}) |")
    print("|---:|---:|")
    for k in range(args.cycles + 1):
        t = k * node.period_s
        for m in vehicle.frames(t):
            node.receive(m, t)
        node.cycle(t)
        if k % args.every == 0:
            gc.collect()
            print(f"| {k} | {rss_mib():.1f} MiB |", flush=True)


if __name__ == "__main__":
    main()
