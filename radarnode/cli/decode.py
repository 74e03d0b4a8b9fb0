"""``radarnode decode FILE``: read any python-can log and print the radar cycles it holds."""

from __future__ import annotations

import can

from radarnode.cli.common import format_cycle, format_stats
from radarnode.consumer.assembler import CycleAssembler, ObjectCycle, summarize_objects
from radarnode.errors import ConfigError
from radarnode.perception.types import CLASS_NAMES


def add_subparser(sub) -> None:
    p = sub.add_parser("decode", help="decode radar cycles from a CAN log file", description=__doc__)
    p.add_argument("file", help="log file (.blf .asc .log .csv .trc …)")
    p.add_argument("--sensor-id", type=int, default=0, choices=range(8), help="radar sensor ID (default 0)")
    p.add_argument("--summary", action="store_true", help="only the per-object summary, no per-cycle tables")
    p.add_argument("--max-cycles", type=int, default=0, help="print at most this many cycles (0: all)")
    p.set_defaults(func=cmd)


def cmd(args) -> int:
    try:
        reader = can.LogReader(args.file)
    except (ValueError, OSError) as exc:
        raise ConfigError(f"argument FILE: cannot read {args.file!r}: {exc}") from None
    assembler = CycleAssembler(sensor_id=args.sensor_id)
    cycles = []
    try:
        for cycle in assembler.feed(reader):
            cycles.append(cycle)
            if not args.summary and (not args.max_cycles or len(cycles) <= args.max_cycles):
                print(format_cycle(cycle))
    except (ValueError, OSError, EOFError) as exc:
        raise ConfigError(f"argument FILE: {args.file!r} is not a readable log: {exc}") from None
    finally:
        if hasattr(reader, "stop"):
            reader.stop()
    print(format_stats(assembler.stats))
    objects = summarize_objects([c for c in cycles if isinstance(c, ObjectCycle)])
    for oid, d in sorted(objects.items(), key=lambda kv: -kv[1]["cycles"]):
        cls = CLASS_NAMES[d["obj_class"]] if d["obj_class"] >= 0 else "-"
        print(f"object {oid:3d} {cls:10s} in {d['cycles']:5d} cycles, median {d['dist_long_m']:7.1f} m long "
              f"{d['dist_lat_m']:6.1f} m lat")
    return 0
