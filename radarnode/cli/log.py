"""``radarnode log SCENARIO -o FILE``: render a scenario to a CAN log, faster than real time.

The writer is python-can's, chosen by the file suffix (.blf, .asc, .log, .csv,
…). The vehicle's 0x300/0x301 frames are included, as a bus capture would
have them. Ctrl-C ends the run after the current cycle and closes the file,
so it is always complete and readable.
"""

from __future__ import annotations

import sys

import can

from radarnode.cli.common import Progress, add_scenario_argument, scenario_from_args, stop_on_signals
from radarnode.errors import ConfigError
from radarnode.wire.node import EgoMotionSender, RadarNode
from radarnode.wire.runner import SimulatedClock, run_node


def add_subparser(sub) -> None:
    p = sub.add_parser("log", help="render a scenario to a CAN log file", description=__doc__)
    add_scenario_argument(p)
    p.add_argument("-o", "--output", required=True, help="log file; the suffix picks the format (.blf .asc .log .csv)")
    p.add_argument("--channel", default="can0", help="channel name written into the log (default can0)")
    p.add_argument("--start-time", type=float, default=0.0, help="timestamp of the first frame, s (default 0)")
    p.add_argument("--no-ego-motion", action="store_true", help="leave out the vehicle's 0x300/0x301 frames")
    p.set_defaults(func=cmd)


def cmd(args) -> int:
    scenario = scenario_from_args(args)
    node = RadarNode(scenario)
    vehicle = None if args.no_ego_motion else EgoMotionSender(node.scene, scenario.radar.sensor_id)
    try:
        writer = can.Logger(args.output)
    except (ValueError, OSError) as exc:
        raise ConfigError(f"option --output: cannot write {args.output!r}: {exc}; "
                          "allowed suffixes: .asc .blf .csv .log .mf4 .trc .txt") from None
    progress = Progress(scenario.num_cycles, f"logging {scenario.name}")
    done = [0]

    def on_cycle(out) -> None:
        done[0] += 1
        progress.update(done[0])

    def write(msg: can.Message) -> None:
        msg.channel = args.channel
        writer.on_message_received(msg)

    try:
        with stop_on_signals() as stop:
            stats = run_node(node, clock=SimulatedClock(args.start_time), sinks=[write], vehicle=vehicle,
                             on_cycle=on_cycle, stop=stop)
    finally:
        writer.stop()
        progress.close()
    interrupted = stats.cycles < scenario.num_cycles
    print(f"{'interrupted: ' if interrupted else ''}wrote {stats.frames} frames in {stats.cycles} complete cycles "
          f"to {args.output}", file=sys.stderr)
    return 0
