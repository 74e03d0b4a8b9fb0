"""``radarnode consume -i IFACE -c CHANNEL``: decode and print the radar's cycles from a bus."""

from __future__ import annotations

import json
import sys
import time

import can
import numpy as np

from radarnode.cli.common import format_cycle, format_stats, stop_on_signals
from radarnode.consumer.assembler import CycleAssembler, ObjectCycle
from radarnode.wire.bus import add_bus_arguments, open_bus


def add_subparser(sub) -> None:
    p = sub.add_parser("consume", help="decode radar cycles from a CAN bus", description=__doc__)
    add_bus_arguments(p, bitrate=True)
    p.add_argument("--sensor-id", type=int, default=0, choices=range(8), help="radar sensor ID (default 0)")
    p.add_argument("--count", type=int, default=0, help="stop after this many cycles (0: until Ctrl-C)")
    p.add_argument("--timeout", type=float, default=0.0, help="stop after this many seconds without a cycle")
    p.add_argument("--json", action="store_true", help="one JSON object per cycle instead of tables")
    p.set_defaults(func=cmd)


def cycle_to_json(cycle) -> str:
    if isinstance(cycle, ObjectCycle):
        ol = cycle.objects
        rows = [{"id": int(ol.id[k]), "dist_long_m": round(float(ol.dist_long_m[k]), 3),
                 "dist_lat_m": round(float(ol.dist_lat_m[k]), 3), "vrel_long_mps": float(ol.vrel_long_mps[k]),
                 "vrel_lat_mps": float(ol.vrel_lat_mps[k]), "dyn_prop": int(ol.dyn_prop[k]),
                 "obj_class": int(ol.obj_class[k])} for k in range(len(ol))]
        return json.dumps({"type": "objects", "meas_counter": cycle.meas_counter, "objects": rows})
    cl = cycle.clusters
    rows = [{"id": int(cl.id[k]), "dist_long_m": float(np.round(cl.dist_long_m[k], 3)),
             "dist_lat_m": float(np.round(cl.dist_lat_m[k], 3))} for k in range(len(cl))]
    return json.dumps({"type": "clusters", "meas_counter": cycle.meas_counter, "clusters": rows})


def cmd(args) -> int:
    assembler = CycleAssembler(sensor_id=args.sensor_id)
    with open_bus(args) as bus, stop_on_signals() as stop:
        notifier = can.Notifier(bus, [assembler], timeout=0.05)
        print(f"listening on {bus.channel_info}", file=sys.stderr, flush=True)
        n = 0
        last = time.monotonic()
        try:
            while not stop.is_set():
                cycle = assembler.get(timeout=0.1)
                if cycle is None:
                    if args.timeout and time.monotonic() - last > args.timeout:
                        break
                    continue
                last = time.monotonic()
                n += 1
                print(cycle_to_json(cycle) if args.json else format_cycle(cycle), flush=True)
                if args.count and n >= args.count:
                    break
        finally:
            notifier.stop()
    print(format_stats(assembler.stats), file=sys.stderr)
    return 0
