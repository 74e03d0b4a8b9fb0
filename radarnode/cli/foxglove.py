"""Foxglove for the subcommands: ``--foxglove`` (a live view) on ``run`` and ``node``, MCAP for ``log -o x.mcap``.

The recorder (:class:`radarnode.viz.recorder.FoxgloveRecorder`) sees the frames the way a bus tap does: on ``run``
through a bus handle of its own on the run's virtual bus (so it sees the node's and the ECU's frames), on
``node`` through the frames the node sends and receives. The node hands over each cycle for the ground truth.
"""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path

import can

from radarnode.errors import BusError, UsageError

DEFAULT_PORT = 8765          # Foxglove's usual WebSocket port
HOST = "127.0.0.1"           # the live view is served on this machine only


def is_mcap(path: str) -> bool:
    return Path(path).suffix.lower() == ".mcap"


def require_foxglove(option: str, value) -> None:
    """A usage error naming the option when foxglove-sdk is not installed, before any work is done."""
    try:
        import foxglove  # noqa: F401
    except ImportError:
        raise UsageError(f"option {option}: value {value!r} needs foxglove-sdk, which is not installed; expected "
                         "it installed: pip install 'radarnode[foxglove]'") from None


def check_mcap_span(start_s: float, span_s: float, option: str) -> None:
    """A usage error naming ``option`` when a run of ``span_s`` seconds from ``start_s`` would end beyond the times a
    Foxglove message holds (:data:`radarnode.viz.MAX_STAMP_S`), before it is run (an MCAP log started at 1e10 s ran,
    then ended in a traceback: an independent tester's finding)."""
    from radarnode.viz import MAX_STAMP_S
    if start_s + span_s >= MAX_STAMP_S:
        raise UsageError(f"option {option}: value {start_s!r} is not allowed for an .mcap log of {span_s:g} s: "
                         f"Foxglove's timestamps end at {MAX_STAMP_S} s (2106-02-07); expected a start below "
                         f"{MAX_STAMP_S - span_s:.3f} s, or another format (.log keeps any)")


def add_live_arguments(parser) -> None:
    g = parser.add_argument_group("Foxglove live view (needs radarnode[foxglove])")
    g.add_argument("--foxglove", action="store_true",
                   help="serve the run live over Foxglove's WebSocket protocol on localhost (in Foxglove: Open "
                        "connection → Foxglove WebSocket → ws://localhost:PORT)")
    from radarnode.cli.options import PORT
    g.add_argument("--foxglove-port", type=PORT, default=None, metavar="PORT",
                   help=f"port of the live view, with --foxglove (default {DEFAULT_PORT}; 0: any free port, printed "
                        "at the start)")


def check_live_arguments(args) -> None:
    """``--foxglove-port`` without ``--foxglove`` would be ignored: a usage error naming both, before any work."""
    if getattr(args, "foxglove_port", None) is not None and not getattr(args, "foxglove", False):
        raise UsageError(f"option --foxglove-port: value {args.foxglove_port} is not allowed without --foxglove; "
                         "expected --foxglove with it (or no --foxglove-port)")


def layout_hint() -> str:
    from radarnode.viz.layout import layout_path
    p = layout_path()
    return f"layout {p}" if p is not None else "layout layouts/foxglove_radarnode.json of the source tree"


def scenario_metadata(scenario, fidelity: str) -> tuple[dict, list]:
    """The MCAP's ``radarnode`` metadata record and the scenario file as an attachment."""
    from radarnode import __version__
    meta = {"radarnode_version": __version__, "scenario": scenario.name, "seed": scenario.seed,
            "fidelity": fidelity, "duration_s": scenario.duration_s, "sensor_id": scenario.radar.sensor_id}
    attachments = []
    source = getattr(scenario, "source", None)
    if source and Path(str(source)).is_file():
        attachments.append((Path(str(source)).name, "application/yaml", Path(str(source)).read_bytes()))
    return meta, attachments


def mcap_writer(tmp_path: str, scenario, node):
    """A recorder writing MCAP to ``tmp_path`` for ``radarnode log``: a python-can writer (on_message_received,
    stop) that also takes each cycle of ``node`` (``on_node_cycle``) for the truth and the ego."""
    from radarnode.viz.recorder import FoxgloveRecorder
    rec = FoxgloveRecorder(sensor_id=scenario.radar.sensor_id)
    meta, attachments = scenario_metadata(scenario, node.fidelity)
    rec.attach_node(node)
    rec.open_mcap(tmp_path, metadata=meta, attachments=attachments)
    return rec


def summary(rec, output: str) -> str:
    n = sum(rec.counts.values())
    return (f"foxglove: {len(rec.counts)} topics, {n} messages in {output}; open it in Foxglove (Open local file) "
            f"with the {layout_hint()}")


class _NoLiveView:
    """What the commands call when ``--foxglove`` is not given: nothing."""

    sinks: list = []
    on_node_cycle = None

    @staticmethod
    def tap(recv):
        return recv


class LiveView:
    """A recorder serving on localhost, fed by a bus tap or by the node's own frames."""

    def __init__(self, recorder, server) -> None:
        self.recorder = recorder
        self.server = server
        self.sinks = [recorder.on_message_received]
        self.on_node_cycle = recorder.on_node_cycle
        self._bus = None
        self._notifier = None

    def listen(self, bus: can.BusABC) -> None:
        """Feed the recorder from its own handle on the bus (every frame anyone sent on it)."""
        self._bus = bus
        self._notifier = can.Notifier(bus, [self.recorder], timeout=0.01)
        self.sinks = []

    def tap(self, recv):
        """``recv`` (a bus's receive) that also hands every frame received to the recorder."""
        def tapped(timeout):
            msg = recv(timeout)
            if msg is not None:
                self.recorder.on_message_received(msg)
            return msg
        return tapped

    def close(self) -> None:
        if self._notifier is not None:
            self._notifier.stop()
            while (msg := self._bus.recv(0.0)) is not None:      # the frames still queued on the tap
                self.recorder.on_message_received(msg)
            self._bus.shutdown()
        self.recorder.close()


@contextlib.contextmanager
def live_view(args, node, virtual_channel: str | None = None):
    """``--foxglove``: serve ``node``'s run on ``HOST:--foxglove-port`` for the duration of the block.

    With ``virtual_channel`` the recorder listens on its own handle of that python-can virtual bus; without,
    the command passes ``live.sinks`` to the runner and wraps its receive in ``live.tap``. Yields a no-op
    object without ``--foxglove``.
    """
    if not getattr(args, "foxglove", False):
        yield _NoLiveView()
        return
    require_foxglove("--foxglove", True)
    port = DEFAULT_PORT if getattr(args, "foxglove_port", None) is None else args.foxglove_port
    if isinstance(port, bool) or not isinstance(port, int) or not 0 <= port <= 65535:
        raise UsageError(f"option --foxglove-port: value {port!r} is not allowed; expected an integer 0..65535 "
                         "(0: any free port)")
    from radarnode.viz.recorder import FoxgloveRecorder
    rec = FoxgloveRecorder(sensor_id=node.config.sensor_id)
    rec.attach_node(node)
    try:
        server = rec.serve(HOST, port)
    except Exception as exc:  # noqa: BLE001 - foxglove-sdk raises its own kinds for a port in use
        rec.close()
        raise BusError(f"option --foxglove-port: cannot serve the live view on {HOST}:{port}: {exc}; "
                       "expected a free port (0: any free port)") from None
    live = LiveView(rec, server)
    try:
        if virtual_channel is not None:
            live.listen(can.Bus(interface="virtual", channel=virtual_channel, preserve_timestamps=True))
        print(f"foxglove: live view on ws://{HOST}:{server.port} (in Foxglove: Open connection → Foxglove "
              f"WebSocket; {layout_hint()})", file=sys.stderr, flush=True)
        yield live
    finally:
        live.close()
