"""``radarnode consume -i IFACE -c CHANNEL``: decode and print the radar's cycles from a bus."""

from __future__ import annotations

import json
import sys
import time

import can
import numpy as np

from radarnode.cli import options
from radarnode.cli.common import format_cycle, format_fused, format_stats, fusion_mounts, stop_on_signals
from radarnode.consumer.assembler import CycleAssembler, ObjectCycle
from radarnode.errors import UsageError
from radarnode.wire.bus import add_bus_arguments, open_bus


def add_subparser(sub) -> None:
    p = sub.add_parser("consume", help="decode radar cycles from a CAN bus", description=__doc__)
    add_bus_arguments(p, bitrate=True)
    p.add_argument("--sensor-id", type=options.SENSOR_ID, default=None, help="radar sensor ID 0..7 (default 0)")
    p.add_argument("--fuse", metavar="SCENARIO",
                   help="decode every radar of SCENARIO (its radars' sensor IDs and mounts) and print their object "
                        "lists fused into one, in the vehicle frame (instead of --sensor-id's cycles)")
    p.add_argument("--count", type=options.COUNT, default=0, help="stop after this many cycles (0: until Ctrl-C)")
    p.add_argument("--timeout", type=options.TIMEOUT, default=0.0,
                   help="stop after this many seconds without a cycle, up to 86400 (0: never, the default)")
    p.add_argument("--json", action="store_true", help="one JSON object per cycle (timestamp, sensor_id, cycle_counter, objects or "
                        "clusters) instead of tables")
    p.set_defaults(func=cmd)


def _f(v, digits: int = 3):
    """A finite float rounded for JSON, None for NaN (JSON has no NaN)."""
    v = float(v)
    return round(v, digits) if np.isfinite(v) else None


def cycle_to_json(cycle, sensor_id: int = 0) -> str:
    """One line of JSON for one decoded cycle: when (the header frame's timestamp, s), which sensor, which cycle
    (the header's MeasCounter), and every object or cluster with units in the field names."""
    head = {"timestamp": cycle.timestamp, "sensor_id": sensor_id, "cycle_counter": cycle.meas_counter}
    if isinstance(cycle, ObjectCycle):
        ol = cycle.objects
        rows = [{"id": int(ol.id[k]), "dist_long_m": _f(ol.dist_long_m[k]), "dist_lat_m": _f(ol.dist_lat_m[k]),
                 "vrel_long_mps": _f(ol.vrel_long_mps[k]), "vrel_lat_mps": _f(ol.vrel_lat_mps[k]),
                 "dyn_prop": int(ol.dyn_prop[k]), "obj_class": int(ol.obj_class[k]), "rcs_dbsm": _f(ol.rcs_dbsm[k], 1),
                 "length_m": _f(ol.length_m[k], 1), "width_m": _f(ol.width_m[k], 1)} for k in range(len(ol))]
        regions = cycle.collision_regions
        if regions is not None and len(regions) == len(rows):
            # Obj_4_Warning 0x60E (collision detection on): the regions each object warns in, as a list and as
            # the message's Obj_CollDetRegionBitfield
            for row, bits in zip(rows, regions):
                row["collision_regions"] = [r for r in range(8) if int(bits) >> r & 1]
                row["coll_det_region_bitfield"] = int(bits)
        return json.dumps({**head, "type": "objects", "objects": rows})
    cl = cycle.clusters
    rows = [{"id": int(cl.id[k]), "dist_long_m": _f(cl.dist_long_m[k]), "dist_lat_m": _f(cl.dist_lat_m[k]),
             "vrel_long_mps": _f(cl.vrel_long_mps[k]), "vrel_lat_mps": _f(cl.vrel_lat_mps[k]),
             "dyn_prop": int(cl.dyn_prop[k]), "rcs_dbsm": _f(cl.rcs_dbsm[k], 1)} for k in range(len(cl))]
    return json.dumps({**head, "type": "clusters", "clusters": rows})


def fused_to_json(fused) -> str:
    """One fused object list as one JSON object (vehicle frame; ``sensors``: the sensor IDs that saw each)."""
    rows = [{"id": int(fused.id[k]), "x_m": _f(fused.x_m[k]), "y_m": _f(fused.y_m[k]),
             "vx_mps": _f(fused.vx_mps[k]), "vy_mps": _f(fused.vy_mps[k]), "rcs_dbsm": _f(fused.rcs_dbsm[k], 1),
             "obj_class": int(fused.obj_class[k]),
             "sensors": fused.sensor_ids(k)} for k in range(len(fused))]
    return json.dumps({"timestamp": fused.t_s, "type": "fused_objects", "objects": rows})


def _stopped_on_purpose(args, n: int, stop) -> bool:
    """Whether ``consume`` stopped by ``--count`` (``n`` cycles or rounds shown) or a signal: the cycle in progress
    was cut by this stop, not lost on the bus, and is left unfinished; after a ``--timeout`` of silence it ends as it
    is (as at the end of a log)."""
    return bool(args.count and n >= args.count) or stop.is_set()


def _consume_fused(args) -> int:
    from radarnode.consumer.fusion import FusingConsumer
    from radarnode.radar.setup import load_scenario
    fuser = FusingConsumer(fusion_mounts(load_scenario(args.fuse)))
    with open_bus(args) as bus, stop_on_signals() as stop:
        notifier = can.Notifier(bus, [fuser], timeout=0.05)
        print(f"listening on {bus.channel_info} for sensors {', '.join(map(str, fuser.assemblers))}",
              file=sys.stderr, flush=True)
        n = 0
        last = time.monotonic()
        try:
            while not stop.is_set():
                rounds = fuser.drain()
                if not rounds:
                    if args.timeout and time.monotonic() - last > args.timeout:
                        break
                    time.sleep(0.01)
                    continue
                last = time.monotonic()
                for _, fused in rounds:
                    n += 1
                    print(fused_to_json(fused) if args.json else format_fused(fused), flush=True)
                    if args.count and n >= args.count:
                        break
                if args.count and n >= args.count:
                    break
        finally:
            fuser.leave_unfinished = _stopped_on_purpose(args, n, stop)         # (as a lone consumer)
            notifier.stop()
    for sid, st in fuser.stats.items():
        print(f"sensor {sid}: " + format_stats(st), file=sys.stderr)
    print("fusion: " + ", ".join(f"{k}={v}" for k, v in fuser.counters().items()), file=sys.stderr)
    return stop.exit_status


def cmd(args) -> int:
    if args.fuse is not None:
        if args.sensor_id is not None:          # (decode refuses the same pair)
            raise UsageError("option --fuse: not allowed with --sensor-id; expected one of them (--fuse takes every "
                             "radar of its scenario)")
        return _consume_fused(args)
    if args.sensor_id is None:
        args.sensor_id = 0
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
                print(cycle_to_json(cycle, args.sensor_id) if args.json else format_cycle(cycle), flush=True)
                if args.count and n >= args.count:
                    break
        finally:
            assembler.leave_unfinished = _stopped_on_purpose(args, n, stop)
            notifier.stop()
    print(format_stats(assembler.stats), file=sys.stderr)
    return stop.exit_status       # 130/143 when stopped by SIGINT/SIGTERM
