"""``radarnode decode FILE``: read any python-can log and print the radar cycles it holds.

``--format text`` (default) prints the assembled object or cluster lists, the
consumer's counters and a per-object summary. ``--format json`` writes one
JSON object per CAN frame (JSON Lines), ``--format csv`` one row per frame:
timestamp, channel, CAN ID, sensor ID, cycle counter, message name, DLC, data
and every decoded signal with its unit, decoded with ``dbc/radarnode_bus.dbc``
(every sensor ID, radarnode's own messages and the ECU's). The cycle counter
of a frame is the MeasCounter of the latest object or cluster list header of
its sensor (of ``--sensor-id``, default 0, for the ECU's frames and 0x008);
empty before the first header. ``-o FILE`` writes under a temporary name and
renames it when complete.
"""

from __future__ import annotations

import csv
import json
import math
import os
import sys
from pathlib import Path

import can

from radarnode.cli import options
from radarnode.cli.common import ChannelPick, SensorCensus, add_channel_option, atomic_output, format_cycle, \
    format_fused, format_stats, fusion_mounts, progress
from radarnode.consumer.assembler import CycleAssembler, ObjectCycle, summarize_objects
from radarnode.errors import FileError, UsageError
from radarnode.perception.types import CLASS_NAMES
from radarnode.wire.busdbc import frame_table, signal_value
from radarnode.wire.logfiles import FORMATS, ReadReport, check_input, check_stem, log_format, read_frames

FORMATS_OUT = ("text", "json", "csv")
FIXED_COLUMNS = ["timestamp", "channel", "can_id", "sensor_id", "cycle_counter", "message", "dlc", "data"]
COUNTER_SIGNALS = {"Obj_0_Status": "Obj_MeasCounter", "Cluster_0_Status": "Cluster_MeasCounter"}


def add_subparser(sub) -> None:
    p = sub.add_parser("decode", help="decode radar cycles (or every frame, as JSON/CSV) from a CAN log file",
                       description=__doc__)
    p.add_argument("file", help="log file (" + " ".join(FORMATS) + "; .mf4 with radarnode[mf4])")
    p.add_argument("--format", default="text", choices=FORMATS_OUT,
                   help="text: cycles and summary (default); json: one JSON object per frame; csv: one row per frame")
    p.add_argument("-o", "--output", help="write to this file instead of standard output")
    p.add_argument("--sensor-id", type=options.SENSOR_ID, default=None,
                   help="radar sensor ID 0..7 (text: whose cycles, default 0; json/csv: only this sensor's frames and "
                        "the ECU's, default every frame)")
    p.add_argument("--fuse", metavar="SCENARIO",
                   help="text: fuse the object lists of every radar of SCENARIO (its radars' sensor IDs and mounts) "
                        "into one list in the vehicle frame and print that")
    add_channel_option(p)
    p.add_argument("--summary", action="store_true", help="text: only the per-object summary, no per-cycle tables")
    p.add_argument("--max-cycles", type=options.COUNT, default=0,
                   help="text: print at most this many cycles (0: all)")
    p.set_defaults(func=cmd)


def _number(v):
    """A JSON/CSV-friendly number: ints stay ints, floats lose the binary noise of scale × raw + offset."""
    if isinstance(v, float):
        return float(f"{v:.12g}") if math.isfinite(v) else None
    return int(v) if isinstance(v, int) else v


def carries_no_message(msg: can.Message) -> bool:
    """An error, remote or CAN FD frame: none is one of the bus's messages, so decode skips it (a CAN FD frame, which
    no classical ARS 408 bus carries, was decoded as a list header and its bytes became the cycle counter of the frames
    after it: an independent tester's finding; the text output's consumer drops it too)."""
    return bool(msg.is_error_frame or msg.is_remote_frame or msg.is_fd)


class FrameDecoder:
    """Frame -> record with sensor ID and cycle counter, decoded with the whole-bus DBC."""

    def __init__(self, sensor_id: int | None) -> None:
        self.table = frame_table()
        self.only = sensor_id
        self.default_sensor = 0 if sensor_id is None else sensor_id
        self.counters: dict[int, int] = {}
        self.frames = self.unknown = self.errors = self.skipped = self.bad_times = 0

    def record(self, msg: can.Message) -> dict | None:
        if carries_no_message(msg):
            self.skipped += 1
            return None
        info = self.table.get(msg.arbitration_id) if not msg.is_extended_id else None
        sensor = info.sensor_id if info is not None else None
        if self.only is not None and sensor is not None and sensor != self.only:
            return None
        self.frames += 1
        # the channel as text whatever the reader gives (.log "can0", .blf 0): one JSON type per field
        channel = None if msg.channel is None else str(msg.channel)
        # a NaN or infinite timestamp (a damaged or hand-made log) is written as null: JSON has no NaN
        stamp = float(msg.timestamp) if math.isfinite(msg.timestamp) else None
        self.bad_times += stamp is None
        # an extended ID is said (JSON "extended"; CSV 8 hex digits, as candump writes it): 0x0000060A with the
        # radar's low bits read as the standard 0x60A before (an independent tester's finding)
        rec = {"timestamp": stamp, "channel": channel, "can_id": msg.arbitration_id,
               "extended": bool(msg.is_extended_id), "sensor_id": sensor, "cycle_counter": None,
               "message": info.base_name if info else None,
               "dlc": msg.dlc, "data": bytes(msg.data).hex().upper(), "signals": {}}
        if info is None:
            self.unknown += 1
        else:
            try:
                values = info.message.decode(bytes(msg.data), decode_choices=False, scaling=True)
            except Exception as exc:  # noqa: BLE001 - cantools raises several kinds on a bad frame
                self.errors += 1
                rec["error"] = str(exc)
                values = {}
            for sig in info.message.signals:
                if sig.name not in values:
                    continue           # a multiplexed signal of another multiplexer value
                v = values[sig.name]
                entry = {"value": _number(signal_value(sig, v)), "unit": sig.unit or ""}
                if sig.choices and v in sig.choices:
                    entry["label"] = str(sig.choices[v])
                rec["signals"][sig.name] = entry
            counter_signal = COUNTER_SIGNALS.get(info.base_name)
            if counter_signal is not None and counter_signal in values:
                self.counters[sensor] = int(values[counter_signal])
        rec["cycle_counter"] = self.counters.get(sensor if sensor is not None else self.default_sensor)
        return rec


def _signal_columns(table, arbitration_ids: set[int]) -> list[tuple[str, str]]:
    """(signal name, column header) for every signal of the messages the log holds, in DBC order."""
    cols: dict[str, str] = {}
    for can_id in sorted(arbitration_ids):
        info = table.get(can_id)
        if info is None:
            continue
        for sig in info.message.signals:
            cols.setdefault(sig.name, f"{sig.name} [{sig.unit}]" if sig.unit else sig.name)
    return list(cols.items())


def refuse_channel(args, report: ReadReport) -> None:
    """FileError where ``--channel`` picked no frame of the log (after a pass over it; before a summary or a CSV
    header is written): no output file, status 1, as export's. An empty decode with a warning and status 0 read as a
    decode of a silent bus; the summary line before the error still did (a tester's finding). A damaged log's
    damage is named with it (its unreadable part may hold the channel)."""
    refused = args.pick.refusal()
    if refused:
        raise FileError(refused + (f"; {report.message('argument FILE')}" if report.damaged else ""))


def _frames(args, report: ReadReport):
    """The log's frames (:func:`read_frames`), only those of ``--channel`` where it is given."""
    return args.pick(read_frames(args.file, report))


def _write_machine(args, out, report: ReadReport, census: SensorCensus) -> FrameDecoder:
    decoder = FrameDecoder(args.sensor_id)
    if args.format == "csv":
        # a first pass for the columns: only the signals of messages that occur, not the whole DBC's ~200
        first = ReadReport(report.path, report.fmt)
        present = {m.arbitration_id for m in _frames(args, first)
                   if not carries_no_message(m)}
        if first.frames == 0:                            # not even a header line for a file with no frame
            raise FileError(first.message("argument FILE"))
        refuse_channel(args, first)                      # … nor for a --channel with no frame
        columns = _signal_columns(decoder.table, present)
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(FIXED_COLUMNS + [header for _, header in columns])
    bar = progress(None, f"decoding {args.file}", unit="frame", to_stdout=args.output is None)
    try:
        for msg in _frames(args, report):
            bar.update(1)
            census.note(msg)
            rec = decoder.record(msg)
            if rec is None:
                continue
            if args.format == "json":
                out.write(json.dumps(rec, ensure_ascii=False) + "\n")
                continue
            sig = rec["signals"]
            row = ["" if rec["timestamp"] is None else repr(rec["timestamp"]),
                   "" if rec["channel"] is None else rec["channel"],
                   f"0x{rec['can_id']:08X}" if rec["extended"] else f"0x{rec['can_id']:03X}",
                   "" if rec["sensor_id"] is None else rec["sensor_id"],
                   "" if rec["cycle_counter"] is None else rec["cycle_counter"], rec["message"] or "",
                   rec["dlc"], rec["data"]]
            row += ["" if name not in sig or sig[name]["value"] is None else sig[name]["value"]
                    for name, _ in columns]
            writer.writerow(row)
    finally:
        bar.close()
    return decoder


def _write_fused(args, out, report: ReadReport, census: SensorCensus) -> None:
    """Every radar of ``--fuse``'s scenario decoded, their object lists fused in the vehicle frame."""
    from radarnode.consumer.fusion import FusingConsumer
    fuser = FusingConsumer(args.mounts)
    bar = progress(None, f"decoding {args.file}", unit="frame", to_stdout=args.output is None)
    rounds = 0
    seen: dict[int, set] = {}

    def counted(reader):
        for msg in reader:
            bar.update(1)
            census.note(msg)
            yield msg

    def show(batch) -> None:
        nonlocal rounds
        for cycles, fused in batch:
            rounds += 1
            for k in range(len(fused)):
                seen.setdefault(int(fused.id[k]), set()).update(fused.sensor_ids(k))
            if not args.summary and (not args.max_cycles or rounds <= args.max_cycles):
                out.write(format_fused(fused) + "\n")

    try:
        for batch in fuser.feed(counted(_frames(args, report))):
            show([batch])
        fuser.flush()
        show(fuser.drain())
    finally:
        bar.close()
    if report.frames == 0:
        raise FileError(report.message("argument FILE"))
    refuse_channel(args, report)
    # sensors the log holds that the scenario has no radar for: named where one of its radars sent nothing (a log of
    # other sensor IDs gave a warning per radar and no word of the IDs it held: an independent tester's finding)
    others = sorted(census.present - set(fuser.stats))
    held = f" (the log holds frames of sensor ID {', '.join(map(str, others))}, which it has no radar for)" \
        if others else ""
    for sid, st in fuser.stats.items():
        out.write(f"sensor {sid}: " + format_stats(st) + "\n")
        if st.as_dict()["cycles"] == 0:
            print(f"warning: sensor {sid} of --fuse {args.fuse} sent no cycle in {args.file}{held}", file=sys.stderr)
    if fuser.cluster_lists:
        print(f"warning: {fuser.cluster_lists} cluster lists were not fused (only object lists are)", file=sys.stderr)
    left = {k: v for k, v in fuser.counters().items() if v and k not in ("cluster_lists", "bus_errors")}
    if left:
        # (lists too far in time from their round's, or without a time; objects not finite; fused tracks restarted
        # after a gap or a step back in time: counted, never printed before — an independent tester's finding)
        print("warning: fusion: " + ", ".join(f"{k}={v}" for k, v in left.items()), file=sys.stderr)
    out.write(f"fused: {rounds} rounds, {len(seen)} fused objects; seen by several sensors: "
              f"{sum(len(v) > 1 for v in seen.values())}\n")


def _write_text(args, out, report: ReadReport, census: SensorCensus) -> None:
    if getattr(args, "mounts", None):
        return _write_fused(args, out, report, census)
    sensor = 0 if args.sensor_id is None else args.sensor_id
    assembler = CycleAssembler(sensor_id=sensor)
    cycles = []
    bar = progress(None, f"decoding {args.file}", unit="frame", to_stdout=args.output is None)

    def counted(reader):
        for msg in reader:
            bar.update(1)
            census.note(msg)
            yield msg

    try:
        for cycle in assembler.feed(counted(_frames(args, report))):
            cycles.append(cycle)
            if not args.summary and (not args.max_cycles or len(cycles) <= args.max_cycles):
                out.write(format_cycle(cycle) + "\n")
    finally:
        bar.close()
    if report.frames == 0:                               # no frame, no summary of nothing
        raise FileError(report.message("argument FILE"))
    refuse_channel(args, report)                         # … nor of a --channel with no frame
    out.write(format_stats(assembler.stats) + "\n")
    objects = summarize_objects([c for c in cycles if isinstance(c, ObjectCycle)])
    for oid, d in sorted(objects.items(), key=lambda kv: -kv[1]["cycles"]):
        cls = CLASS_NAMES[d["obj_class"]] if d["obj_class"] >= 0 else "-"
        out.write(f"object {oid:3d} {cls:10s} in {d['cycles']:5d} cycles, median {d['dist_long_m']:7.1f} m long "
                  f"{d['dist_lat_m']:6.1f} m lat\n")


#: the suffixes of decode's own formats; an output named for one must be written in it
OWN_SUFFIXES = {"json": (".json", ".jsonl"), "csv": (".csv",)}
SUGGESTED = {"text": ".txt", "json": ".jsonl, .json or .txt", "csv": ".csv or .txt"}


def check_output_suffix(path: str, fmt: str) -> None:
    """Refuse (UsageError) an ``-o`` whose suffix says another format than the one written: a CAN log format
    (decode writes no CAN log: ``-o text.blf``), another of decode's formats (``--format json -o x.csv``) or a
    compressed one (``.gz``: decode writes none). Any other suffix (``.txt``, none) is taken as it is."""
    check_stem(path, "--output", FORMATS + (".mcap",) + tuple(x for own in OWN_SUFFIXES.values() for x in own))
    suffix = log_format(path)
    if suffix in OWN_SUFFIXES.get(fmt, ()):
        return
    what = next((f"{suffix} is decode's --format {other}" for other, suffixes in OWN_SUFFIXES.items()
                 if suffix in suffixes), None)
    if what is None and (suffix in FORMATS or suffix == ".mcap"):
        what = f"{suffix} is a CAN log format, and decode writes no CAN log"
    if what is not None:
        raise UsageError(f"option --output: value {path!r} is not allowed with --format {fmt}: {what}; expected "
                         f"a file name ending in {SUGGESTED[fmt]} (or any suffix that is not a CAN log's or "
                         "another format's)")
    if Path(path).suffix.lower() == ".gz":
        # (decode wrote plain text under x.json.gz: a reader that unpacks it fails)
        raise UsageError(f"option --output: value {path!r} is not allowed: decode writes no compressed output; "
                         f"expected a file name ending in {SUGGESTED[fmt]} (compress it afterwards)")


def cmd(args) -> int:
    args.mounts = None
    if args.fuse is not None:
        if args.format != "text":
            raise UsageError(f"option --fuse: not allowed with --format {args.format}; expected --format text (the "
                             "json and csv formats list every frame of every sensor already)")
        if args.sensor_id is not None:
            raise UsageError("option --fuse: not allowed with --sensor-id; expected one of them (--fuse takes every "
                             "radar of its scenario)")
        from radarnode.radar.setup import load_scenario
        args.mounts = fusion_mounts(load_scenario(args.fuse))
    if args.output is not None:
        check_output_suffix(args.output, args.format)
    fmt = check_input(args.file, "argument FILE")     # a missing, empty or unknown file fails before any output
    args.pick = ChannelPick(args.channel, fmt)
    if args.output is not None:
        if os.path.exists(args.output) and os.path.samefile(args.output, args.file):
            raise UsageError(f"option --output: value {args.output!r} is not allowed: it is the log being decoded; "
                             "expected another file name")
    report = ReadReport(args.file, fmt)
    write = _write_text if args.format == "text" else _write_machine

    def nothing_readable() -> None:
        if report.frames == 0:          # an empty log, or not a log of this format: no output file at all
            raise FileError(report.message("argument FILE"))
        refuse_channel(args, report)

    census = SensorCensus()
    if args.output is None:
        result = write(args, sys.stdout, report, census)
        nothing_readable()
    else:
        with atomic_output(args.output, "--output", newline="" if args.format == "csv" else None) as out:
            result = write(args, out, report, census)
            nothing_readable()
    if (args.format == "text" and args.mounts is None) or args.sensor_id is not None:
        # the sensor asked for (text: 0 by default) sent nothing here, others did: say which there are
        warning = census.warning(0 if args.sensor_id is None else args.sensor_id, "--sensor-id", args.channel)
        if warning:
            print(warning, file=sys.stderr)
        warning = census.channel_warning(0 if args.sensor_id is None else args.sensor_id, "--channel")
        if warning:
            print(warning, file=sys.stderr)
    if result is not None:
        where = f" to {args.output}" if args.output else ""
        print(f"decoded {result.frames} frames{where}: {result.unknown} of unknown ID, {result.errors} not "
              f"decodable, {result.skipped} error/remote/CAN FD frames skipped"
              + (f", {result.bad_times} with a timestamp that is not a finite number (written as "
                 f"{'null' if args.format == 'json' else 'an empty field'})" if result.bad_times else ""),
              file=sys.stderr)
    if report.damaged:
        # everything readable was decoded (and written); the status says the log itself is not whole
        raise FileError(report.message("argument FILE"))
    return 0
