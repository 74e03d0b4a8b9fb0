"""``radarnode node SCENARIO -i IFACE -c CHANNEL``: be the radar on a real (or virtual) bus.

Listens for RadarConfiguration 0x200 and ego motion 0x300/0x301 and sends the
ARS 408-21 cycle. Real time by default (benches); ``--fast`` sends as fast as
possible with scenario timestamps.
"""

from __future__ import annotations

import functools
import sys

from radarnode.cli.common import add_scenario_argument, resolve_bitrate, saturation_note, scenario_from_args, stop_on_signals, with_bitrate
from radarnode.cli.foxglove import add_live_arguments, check_live_arguments, live_view
from radarnode.wire.bus import SEND_TIMEOUT_S, add_bus_arguments, echoes_own, open_bus
from radarnode.wire.group import ego_motion_for, make_node
from radarnode.wire.runner import RealTimeClock, SimulatedClock, run_node


def add_subparser(sub) -> None:
    p = sub.add_parser("node", help="run the radar node on a CAN bus", description=__doc__)
    add_scenario_argument(p)
    add_bus_arguments(p)
    mode = p.add_mutually_exclusive_group()
    mode.add_argument("--realtime", dest="fast", action="store_false", help="pace cycles in real time (default)")
    mode.add_argument("--fast", dest="fast", action="store_true", help="simulated time, as fast as possible")
    p.add_argument("--send-ego-motion", action="store_true",
                   help="also send the scenario ego's 0x300/0x301 (when no vehicle ECU does)")
    add_live_arguments(p)
    p.set_defaults(func=cmd, fast=False)


def _sensors(node) -> str:
    ids = getattr(node, "sensor_ids", None)
    return f"sensors {', '.join(map(str, ids))}" if ids else f"sensor {node.config.sensor_id}"


def cmd(args) -> int:
    check_live_arguments(args)
    scenario = scenario_from_args(args)
    # the budget's bit rate as python-can opens the bus: -b, CAN_BITRATE/can.conf, else the scenario's
    bitrate = resolve_bitrate(args.bitrate, scenario.radar.bitrate)
    scenario = with_bitrate(scenario, bitrate.bit_s)
    node = make_node(scenario)
    vehicle = ego_motion_for(node) if args.send_ego_motion else None
    with open_bus(args) as bus, stop_on_signals() as stop, live_view(args, node) as live:
        print(f"radarnode node: {scenario.name} on {bus.channel_info}, {_sensors(node)}, "
              f"{scenario.num_cycles} cycles of {node.period_s * 1e3:.0f} ms; bus-load budget "
              f"{100 * node.bus_load_limit:.0f} % of {bitrate}", file=sys.stderr, flush=True)
        stats = run_node(node, clock=SimulatedClock() if args.fast else RealTimeClock(),
                         sinks=[functools.partial(bus.send, timeout=SEND_TIMEOUT_S), *live.sinks],
                         recv=live.tap(lambda timeout: bus.recv(timeout)), vehicle=vehicle, stop=stop,
                         on_cycle=live.on_node_cycle, echoes_own=echoes_own(bus))
    failed = node.counters.get("tx_failed", 0)       # frames the bus did not take (lost, not sent)
    print(f"{'interrupted: ' if stop.is_set() else ''}sent {stats.cycles} cycles, {stats.frames - failed} frames"
          + (f" ({failed} more the bus did not take)" if failed else "") + "; " +
          ", ".join(f"{k}={v}" for k, v in sorted(node.counters.items())), file=sys.stderr)
    note = saturation_note(node)
    if note:
        print(note, file=sys.stderr)
    return stop.exit_status       # 130/143 when stopped by SIGINT/SIGTERM
