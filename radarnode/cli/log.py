"""``radarnode log SCENARIO -o FILE``: render a scenario to a CAN log, faster than real time.

The writer is python-can's, chosen by the file suffix (.blf, .asc, .log, .csv,
…). The vehicle's 0x300/0x301 frames are included, as a bus capture would
have them. Ctrl-C ends the run after the current cycle and closes the file,
so it is always complete and readable; the file is written under a temporary
name and renamed when closed, so a failed run leaves no partial file.
"""

from __future__ import annotations

import logging
import sys

import can

from radarnode.cli import options
from radarnode.cli.common import add_scenario_argument, atomic_path, progress, resolve_bitrate, saturation_note, scenario_from_args, stop_on_signals, with_bitrate
from radarnode.cli.foxglove import check_mcap_span, is_mcap, mcap_writer, require_foxglove, summary
from radarnode.errors import FileError
from radarnode.wire.logfiles import check_channel, check_output_format, check_start_time, open_writer
from radarnode.wire.group import ego_motion_for, make_node
from radarnode.wire.pipeline import pipeline_for
from radarnode.wire.runner import SimulatedClock, run_node

logger = logging.getLogger(__name__)


def add_subparser(sub) -> None:
    p = sub.add_parser("log", help="render a scenario to a CAN log file", description=__doc__)
    add_scenario_argument(p)
    p.add_argument("-o", "--output", required=True,
                   help="log file; the suffix picks the format: .blf .asc .log .csv .trc .db, .asc.gz .log.gz .csv.gz "
                        ".trc.gz, .mf4 (needs radarnode[mf4]), .mcap (Foxglove, with --ecu; needs radarnode[foxglove])")
    p.add_argument("--channel", default="can0", type=options.name("a channel name"),
                   help="channel name written into the log (default can0)")
    p.add_argument("--start-time", type=options.START_TIME, default=0.0,
                   help="timestamp of the first frame, s (default 0; up to 1e10, e.g. a Unix time)")
    p.add_argument("--no-ego-motion", action="store_true", help="leave out the vehicle's 0x300/0x301 frames")
    p.add_argument("--ecu", action="store_true",
                   help="also run the consumer ECU on the frames and log its AccStatus/FcwStatus, stamped when it "
                        "produces them (the scenario's ecu.processing_latency_s after the cycle)")
    p.add_argument("-b", "--bitrate", type=options.BITRATE,
                   help="bit rate of the logged bus for the bus-load budget, bit/s (default: the scenario's "
                        "radar.bitrate; python-can's configuration is not read, as no bus is opened)")
    p.set_defaults(func=cmd)


class _NothingWritten(Exception):
    """The run was stopped before it wrote a frame: its file is removed (:func:`cmd`); ``status`` 130 or 143."""

    def __init__(self, status: int) -> None:
        super().__init__(status)
        self.status = status


def cmd(args) -> int:
    try:
        return _log(args)
    except _NothingWritten as stopped:
        print(f"interrupted before the first frame: nothing written, no file {args.output!r}", file=sys.stderr)
        return stopped.status


def _log(args) -> int:
    # what the command line alone decides comes first: a format nothing reads back is refused before the run
    check_output_format(args.output, "--output", extra=(".mcap",))
    channel = check_channel(args.output, args.channel, "--channel")     # (the frames' channel, as the writer takes it)
    check_start_time(args.output, args.start_time, "--start-time")
    if is_mcap(args.output):        # for Foxglove (needs foxglove-sdk): a run to watch shows the ECU's decisions too
        require_foxglove("--output", args.output)
        args.ecu = True
    scenario = scenario_from_args(args)
    if is_mcap(args.output):
        check_mcap_span(args.start_time, scenario.duration_s + scenario.ecu.processing_latency_s, "--start-time")
    bitrate = resolve_bitrate(args.bitrate, scenario.radar.bitrate, use_can_config=False)
    scenario = with_bitrate(scenario, bitrate.bit_s)
    node = make_node(scenario)
    vehicle = None if args.no_ego_motion else ego_motion_for(node)
    with atomic_path(args.output, "--output") as tmp:      # no partial file if the run fails
        try:
            writer = mcap_writer(tmp, scenario, node) if is_mcap(args.output) else open_writer(tmp)
        except (ValueError, OSError) as exc:
            reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
            raise FileError(f"option --output: cannot write {args.output!r}: {reason}") from None
        ecu = assembler = None
        if args.ecu:            # the consumer's modules only when they run (a faster start without --ecu)
            from radarnode.consumer.assembler import CycleAssembler
            from radarnode.consumer.evaluate import make_ecu
            ecu = make_ecu(scenario, node.period_s)
            assembler = CycleAssembler(sensor_id=scenario.radar.sensor_id)
        ecu_frames = [0]

        def write(msg: can.Message) -> None:
            msg.channel = channel
            writer.on_message_received(msg)
            if assembler is not None:
                assembler.on_message_received(msg)

        def on_cycle(out) -> None:
            bar.update(1)
            if hasattr(writer, "on_node_cycle"):       # .mcap: the ego and the ground truth beside the frames
                writer.on_node_cycle(out)
            if ecu is None:
                return
            # the ECU decides on what it decoded from the logged frames, as it would on the bus
            ecu.set_ego(out.t_s, assembler.ego_speed_mps, assembler.ego_yaw_rate_dps, assembler.ego_frames,
                        assembler.yaw_frames)
            ecu.boundaries = assembler.road_boundaries
            # an object list or a cluster list, whichever the radar sends (as run and report): an ECU fed only
            # object lists would decide "radar unavailable" on a cluster radar, on its timer, not every cycle
            decision = None
            for cycle in assembler.drain():
                decision = ecu.on_cycle(out.t_s, cycle) or decision
            if decision is None:
                decision = ecu.tick(out.t_s)
            if decision is not None:
                stamp = args.start_time + out.t_s + scenario.ecu.processing_latency_s
                for m in ecu.frames(decision, timestamp=stamp):
                    m.channel = channel
                    writer.on_message_received(m)
                    ecu_frames[0] += 1

        pipeline = bar = None
        try:
            with stop_on_signals() as stop:
                # the road boundaries in a second process where nothing in the run reads them back (no ECU): the
                # same frames in about 0.6 of the time at the object level (radarnode.wire.pipeline); started with
                # the signals caught, so that a Ctrl-C while it forks stops the run instead of being lost in the fork
                if not args.ecu:
                    pipeline = pipeline_for(node, scenario.num_cycles)
                bar = progress(scenario.num_cycles, f"logging {scenario.name}")
                logger.info("logging %s to %s (as %s until it is complete)", scenario.name, args.output, tmp)
                stats = run_node(node, clock=SimulatedClock(args.start_time), sinks=[write], vehicle=vehicle,
                                 on_cycle=on_cycle, stop=stop, pipeline=pipeline)
                if pipeline is not None:
                    pipeline.close()
        finally:
            if pipeline is not None:            # after an error or a second Ctrl-C: ended at once
                pipeline.close(graceful=False)
            writer.stop()
            if bar is not None:
                bar.close()
        if stats.frames == 0 and stats.cycles < scenario.num_cycles:
            # stopped before its first frame: an empty log (a .log of 0 bytes, which nothing can tell from a
            # truncated one, and decode refuses) is not kept (an independent tester's Ctrl-C at 0.1 s)
            raise _NothingWritten(stop.exit_status)
    interrupted = stats.cycles < scenario.num_cycles
    if is_mcap(args.output):
        print(summary(writer, args.output), file=sys.stderr)
    # every frame in the file: the radar's and the vehicle's, and the consumer ECU's with --ecu (an independent tester
    # decoded 773 frames from a log that said it wrote 691)
    total = stats.frames + (ecu_frames[0] if args.ecu else 0)
    if args.ecu:
        print(f"consumer ECU: {ecu_frames[0]} AccStatus/FcwStatus frames logged (in the frames below)", file=sys.stderr)
    print(f"{'interrupted: ' if interrupted else ''}wrote {total} frames in {stats.cycles} complete cycles "
          f"to {args.output}; bus-load budget {100 * node.bus_load_limit:.0f} % of {bitrate}", file=sys.stderr)
    note = saturation_note(node)
    if note:
        print(note, file=sys.stderr)
    # 130/143 when a signal cut the run short: the file is complete, the run is not
    return stop.exit_status if interrupted else 0
