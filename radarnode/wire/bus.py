"""Opening python-can buses the way python-can's own tools do.

Options left out on the command line are not passed, so python-can fills them
from its configuration file (``~/can.conf``, ``can.ini``) and the environment
(``CAN_INTERFACE``, ``CAN_CHANNEL``, ``CAN_BITRATE``, ``CAN_CONFIG``).
"""

from __future__ import annotations

import argparse
import inspect
import logging
import math
import socket

import can

from radarnode.errors import BusError, UsageError

logger = logging.getLogger(__name__)

UDP_RECEIVE_BUFFER_BYTES = 4 << 20   # udp_multicast: about 5000 datagrams, a second of a saturated 500 kbit/s bus
#: how long the node's send of one frame may wait for a bus that does not take it (a full transmit queue; a virtual
#: bus whose reader's bounded queue is full): then the frame is lost and counted (``tx_failed``). Without it a send
#: waited for ever and the node, stuck in it, kept neither its cycle nor a Ctrl-C. On a bus that takes nothing a
#: cycle's 17 frames then cost 34 ms; a cycle of 36 or more frames misses its 72-ms deadline, and the node drops and
#: counts such cycles as any late one (README, "On time like the sensor")
SEND_TIMEOUT_S = 0.002


def add_bus_arguments(parser: argparse.ArgumentParser, bitrate: bool = True) -> None:
    group = parser.add_argument_group("bus (python-can conventions; missing options come from its config)")
    group.add_argument("-i", "--interface", help="python-can interface, e.g. socketcan, virtual, udp_multicast")
    group.add_argument("-c", "--channel", type=_channel, help="channel, e.g. vcan0, 239.74.163.2")
    if bitrate:
        group.add_argument("-b", "--bitrate", type=bitrate_option,
                           help="bit rate in bit/s, 10000..1000000 (also used for the bus-load budget)")
    group.add_argument("--bus-kwargs", nargs="*", default=[], metavar="KEY=VALUE",
                       help="extra keyword arguments for can.Bus, e.g. receive_own_messages=True")


def bitrate_option(text: str) -> int:
    """argparse type of ``-b/--bitrate``: an integer 10000..1000000 bit/s, or one line naming the value."""
    try:
        value = int(text.strip(), 10)
    except ValueError:
        value = None
    if value is None or not 10_000 <= value <= 1_000_000:
        shown = text.strip() if text.strip().lstrip("+-").isdigit() else repr(text)
        raise argparse.ArgumentTypeError(f"value {shown} is not allowed; expected an integer in [10000, 1000000] "
                                         "bit/s")
    return value


def _parse_value(text: str) -> object:
    for conv in (int, float):
        try:
            return conv(text)
        except ValueError:
            pass
    if text in ("True", "False", "true", "false"):
        return text.lower() == "true"
    return text


#: python-can's keyword arguments that take a truth value (common to its interfaces)
_BOOLEAN_KWARGS = ("receive_own_messages", "fd", "local_loopback")


def bus_kwargs(args: argparse.Namespace) -> dict:
    kwargs: dict = {}
    for item in getattr(args, "bus_kwargs", []) or []:
        key, _, text = item.partition("=")
        key = key.strip()
        if "=" not in item or not key.isidentifier():
            raise UsageError(f"option --bus-kwargs: value {item!r} is not allowed; expected KEY=VALUE with KEY a "
                             "python-can keyword argument, e.g. receive_own_messages=True")
        value = _parse_value(text)
        if key == "bitrate":
            # the bus would run at one rate and the cycle's bus-load budget be planned for another
            raise UsageError(f"option --bus-kwargs: key 'bitrate' ({text!r}) is not allowed; expected -b/--bitrate, "
                             "which opens the bus at that rate and plans the bus-load budget for it")
        if isinstance(value, float) and not math.isfinite(value):
            raise UsageError(f"option --bus-kwargs: value {item!r} is not allowed; expected a finite number, "
                             "True/False or text")
        for option, attr, keys in (("-i/--interface", "interface", ("interface", "bustype")),
                                   ("-c/--channel", "channel", ("channel",))):
            if key in keys and getattr(args, attr, None):
                # the option's value was taken and the key dropped without a word (a tester's finding)
                raise UsageError(f"option --bus-kwargs: key {key!r} ({text!r}) is not allowed with {option} "
                                 f"{getattr(args, attr)!r}; expected one of them")
        if key == "can_filters":
            # a list of {can_id, can_mask} entries, which KEY=VALUE cannot give: the text was taken and failed on
            # every frame (bus_errors, status 0: a tester's finding); and the consumer needs every radar frame
            raise UsageError(f"option --bus-kwargs: key 'can_filters' ({text!r}) is not allowed: it takes a list of "
                             "{can_id, can_mask} entries, which KEY=VALUE cannot give; expected no filter (the node "
                             "and the consumer pick their own frames by ID)")
        if key in _BOOLEAN_KWARGS and not isinstance(value, bool):
            raise UsageError(f"option --bus-kwargs: value {item!r} is not allowed; expected {key}=True or "
                             f"{key}=False")
        kwargs[key] = value
    if args.interface:
        kwargs["interface"] = args.interface
    if args.channel:
        kwargs["channel"] = args.channel
    if getattr(args, "bitrate", None):
        kwargs["bitrate"] = args.bitrate
    return kwargs


def _channel(text: str) -> str:
    """An argparse type: a channel name, not empty and printable (an empty one opened python-can's virtual bus on a
    channel of its own choosing, "channel-0": an independent tester's finding)."""
    if not text.strip() or not text.isprintable():
        raise argparse.ArgumentTypeError(f"value {text!r} is not allowed; expected a channel name, e.g. vcan0 or "
                                         "239.74.163.2 (printable characters, not empty)")
    return text


def open_bus(args: argparse.Namespace) -> can.BusABC:
    """Open the bus the arguments describe.

    Raises UsageError for an interface python-can does not know (or whose driver package is not installed) and
    BusError when the interface cannot open the channel (a missing device, no permission, a bad address)."""
    kwargs = bus_kwargs(args)
    what = kwargs or "(from python-can config)"
    try:
        bus = can.Bus(**kwargs)
    except (can.exceptions.CanInterfaceNotImplementedError, ImportError) as exc:
        given = {"interface", "bustype"} & set(bus_kwargs_given(args))
        source = "option -i/--interface" if getattr(args, "interface", None) else \
            f"option --bus-kwargs {sorted(given)[0]}" if given else "python-can configuration"
        name = kwargs.get("interface") or kwargs.get("bustype") or "(none)"
        raise UsageError(f"{source}: interface {name!r} cannot be used here ({exc}); expected one of "
                         f"{', '.join(sorted(can.interfaces.VALID_INTERFACES))} with its driver installed") from None
    except (can.CanError, ValueError, TypeError, OSError, NotImplementedError) as exc:
        error = BusError(f"cannot open CAN bus: {_named(args, kwargs)}: {_with_causes(exc)}; expected a channel that "
                         f"interface can open{_CHANNEL_HINTS.get(kwargs.get('interface'), '')}")
        _drop_half_open(exc)
        raise error from None
    refused = _unread_refusal(bus, args, kwargs)
    if refused:
        bus.shutdown()
        raise UsageError(refused)
    enlarge_receive_buffer(bus)
    name_bus(bus, kwargs)
    return bus


#: python-can buses that read no keyword argument beyond the named parameters of their ``__init__`` and BusABC's
#: ``can_filters`` (python-can 4.x, read in its source): any other key given to them is dropped without a word. Other
#: interfaces read further keys from their ``**kwargs`` and are not checked here
_NAMED_ONLY_BUSES = frozenset({"VirtualBus", "UdpMulticastBus", "SocketcanBus"})


def _unread_refusal(bus: can.BusABC, args: argparse.Namespace, kwargs: dict) -> str | None:
    """The error for the first ``--bus-kwargs`` key ``bus`` does not read (:func:`unread_keys`), else None; the
    interface named as -i names it, and where it came from when not from -i or the keys."""
    given = bus_kwargs_given(args)
    unread = unread_keys(bus, given)
    if not unread:
        return None
    # (can_filters is refused on the command line; bustype and context are the deprecated interface and config_context)
    allowed = ", ".join(sorted(read_keys(type(bus)) - {"can_filters", "bustype", "context"}))
    name = kwargs.get("interface") or kwargs.get("bustype")
    where = "" if getattr(args, "interface", None) or {"interface", "bustype"} & set(given) else \
        " (from python-can's configuration)"
    if name is None:        # the interface python-can's configuration chose: its name, as -i takes it
        name = next((key for key, (_, cls) in can.interfaces.BACKENDS.items() if cls == type(bus).__name__),
                    type(bus).__name__)
    return (f"option --bus-kwargs: key {unread[0]!r} is not allowed for interface {name!r}{where}: python-can's "
            f"{type(bus).__name__} does not read it (it would be dropped without a word); expected one of {allowed}")


def read_keys(bus_class: type) -> frozenset[str]:
    """The keyword arguments a bus of ``bus_class`` reads (its ``__init__``'s named parameters, BusABC's
    ``can_filters`` and can.Bus's own ``interface``, ``config_context`` and ``ignore_config``, with their deprecated
    names), or an empty set where its ``**kwargs`` may hold more (:data:`_NAMED_ONLY_BUSES`)."""
    if bus_class.__name__ not in _NAMED_ONLY_BUSES:
        return frozenset()
    named = {name for name, par in inspect.signature(bus_class.__init__).parameters.items()
             if par.kind in (par.POSITIONAL_OR_KEYWORD, par.KEYWORD_ONLY) and name != "self"}
    # can.Bus's own (interface, config_context, ignore_config) and their deprecated spellings (bustype, context):
    # python-can reads them to choose and configure the bus (interface= without -i was refused as dropped: a
    # tester's finding)
    own = {name for name in inspect.signature(can.Bus).parameters if name != "kwargs"}
    return frozenset(named | own | {"can_filters", "bustype", "context"})


def unread_keys(bus: can.BusABC, given: list[str]) -> list[str]:
    """The keys of ``given`` (``--bus-kwargs``) that ``bus`` does not read (:func:`read_keys`), in their order;
    none for a bus whose keys are not known."""
    known = read_keys(type(bus))
    return [key for key in given if known and key not in known]


def bus_kwargs_given(args: argparse.Namespace) -> list[str]:
    """The keys of the ``--bus-kwargs`` items (checked by :func:`bus_kwargs`), in their order."""
    return [item.partition("=")[0].strip() for item in getattr(args, "bus_kwargs", []) or []]


def echoes_own(bus: can.BusABC) -> bool:
    """Whether ``bus`` gives back the frames this process sends: udp_multicast loops its datagrams back to every
    listener on the host, the sender's own socket included; other interfaces only when asked to
    (``receive_own_messages``)."""
    config = getattr(bus, "init_config", None) or {}
    return type(bus).__name__ == "UdpMulticastBus" or bool(getattr(bus, "receive_own_messages", False)) \
        or bool(config.get("receive_own_messages", False))


#: what a channel of an interface looks like, for the error of a bus that cannot be opened
_CHANNEL_HINTS = {
    "udp_multicast": " (udp_multicast: an IPv4 or IPv6 multicast group, e.g. 239.74.163.2 or ff15:7079:7468:6f6e:6465:6d6f:6d63:6173)",
    "socketcan": " (socketcan: a CAN network interface that is up, e.g. vcan0: `ip link add dev vcan0 type vcan; ip link set up vcan0`)",
    "virtual": " (virtual: any name)",
}


def _with_causes(exc: BaseException) -> str:
    """``exc``'s text and, in brackets, that of each exception it was raised from (or during) that it does not say
    already: python-can's udp_multicast says only "could not create or configure socket" and keeps the operating
    system's reason (``[Errno 19] No such device``: no multicast route) as the cause (an independent tester's
    finding)."""
    text = str(exc) or type(exc).__name__
    seen = {id(exc)}
    cause = exc.__cause__ or exc.__context__
    while cause is not None and id(cause) not in seen:
        seen.add(id(cause))
        more = str(cause) or type(cause).__name__
        if more not in text:
            text += f" ({more})"
        cause = cause.__cause__ or cause.__context__
    return text


def _named(args: argparse.Namespace, kwargs: dict) -> str:
    """The options (or python-can configuration) that chose the bus, for an error: which to change."""
    parts = []
    for key, option in (("interface", "-i/--interface"), ("channel", "-c/--channel")):
        if key in kwargs:
            given = getattr(args, key, None) is not None
            label = f"option {option}" if given else f"python-can configuration {key}"
            parts.append(f"{label} {kwargs[key]!r}")
    extra = sorted(k for k in kwargs if k not in ("interface", "channel", "bitrate"))
    if extra:
        parts.append("option --bus-kwargs " + ", ".join(f"{k}={kwargs[k]!r}" for k in extra))
    if "bitrate" in kwargs:
        parts.append(f"option -b/--bitrate {kwargs['bitrate']}")
    return " with ".join(parts) if parts else "python-can configuration (no interface or channel given)"


def _drop_half_open(exc: BaseException) -> None:
    """Let a bus whose construction failed go now, with python-can's "was not properly shut down" warning (logged by
    its destructor: it never opened, so there is nothing to shut down) kept off the error output."""
    import gc
    import traceback
    bus_logger = logging.getLogger("can.bus")
    disabled = bus_logger.disabled
    bus_logger.disabled = True
    try:
        tb, exc.__traceback__ = exc.__traceback__, None
        if tb is not None:
            traceback.clear_frames(tb)
        del tb
        gc.collect()
    finally:
        bus_logger.disabled = disabled


def name_bus(bus: can.BusABC, kwargs: dict) -> None:
    """Give a bus whose interface leaves ``channel_info`` at python-can's ``"unknown"`` (udp_multicast) a name
    that says what it is: the interface and the channel (multicast group), as python-can resolved them from the
    options and its configuration."""
    if bus.channel_info and bus.channel_info != "unknown":
        return
    try:
        config = can.util.load_config(config=dict(kwargs))
    except Exception:  # noqa: BLE001 - a configuration python-can already opened the bus with; keep what it said
        config = kwargs
    interface = config.get("interface") or type(bus).__name__
    channel = config.get("channel")
    bus.channel_info = f"{interface} channel {channel}" if channel is not None else str(interface)


def enlarge_receive_buffer(bus: can.BusABC, size: int = UDP_RECEIVE_BUFFER_BYTES) -> int | None:
    """Give a ``udp_multicast`` bus's socket a receive buffer of ``size`` bytes; returns the size in force.

    python-can leaves the operating system's default (about 200 KiB, some 250 datagrams: 50 ms of a saturated
    500 kbit/s bus), so a process that is busy or descheduled for longer loses frames in the kernel. A CAN
    controller's FIFO plays this role on a real bus. Other interfaces, or a python-can whose internals differ,
    are left as they are (None)."""
    sock = getattr(getattr(bus, "_multicast", None), "_socket", None)
    if not isinstance(sock, socket.socket):
        return None
    for option in (getattr(socket, "SO_RCVBUFFORCE", None), socket.SO_RCVBUF):   # FORCE: beyond rmem_max (root)
        if option is None:
            continue
        try:
            sock.setsockopt(socket.SOL_SOCKET, option, size)
            break
        except OSError:
            continue
    got = sock.getsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF)
    logger.debug("udp_multicast receive buffer: %d bytes", got)
    return got
