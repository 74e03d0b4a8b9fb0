"""Helpers shared by the subcommands: scenario loading, stop handling, tables, progress, atomic output, bit rate."""

from __future__ import annotations

import contextlib
import dataclasses
import json
import os
import signal
import sys
import tempfile
import threading
from pathlib import Path

import numpy as np

from radarnode.consumer.assembler import ClusterCycle, ConsumerStats, ObjectCycle
from radarnode.errors import ConfigError
from radarnode.perception.types import CLASS_NAMES, DYN_NAMES
from radarnode.radar.setup import load_scenario
from radarnode.scene.scenario import Scenario


def add_scenario_argument(parser) -> None:
    parser.add_argument("scenario", help="scenario file (YAML), e.g. scenarios/highway_cut_in.yaml")
    parser.add_argument("--seed", type=int, help="override the scenario's seed")
    parser.add_argument("--duration", type=float, help="override the scenario's duration in seconds")
    parser.add_argument("--fidelity", choices=("object", "detection", "signal", "auto"),
                        help="radar model level (default: the scenario's)")


def scenario_from_args(args) -> Scenario:
    import dataclasses

    from radarnode import validate
    from radarnode.errors import ConfigError, FieldError
    sc = load_scenario(args.scenario)
    try:
        if args.seed is not None:
            sc = dataclasses.replace(sc, seed=validate.integer("--seed", args.seed, lo=0))
        if getattr(args, "fidelity", None):
            sc = dataclasses.replace(sc, fidelity=args.fidelity)
        if args.duration is not None:
            sc = dataclasses.replace(sc, duration_s=validate.number("--duration", args.duration, lo=0.0,
                                                                      hi=86_400.0, lo_open=True))
    except FieldError as exc:
        raise ConfigError(f"option {exc.field}: value {exc.value!r} is not allowed; expected {exc.allowed}") from None
    return sc


@contextlib.contextmanager
def stop_on_signals():
    """An Event set by Ctrl-C or SIGTERM, so loops can finish the current cycle and close files."""
    stop = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return
    previous = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}

    def handler(signum, frame):
        if stop.is_set():          # second Ctrl-C: give up at once
            raise KeyboardInterrupt
        stop.set()

    for s in previous:
        signal.signal(s, handler)
    try:
        yield stop
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def format_cycle(cycle: ObjectCycle | ClusterCycle, t_s: float | None = None, max_rows: int = 20) -> str:
    """A small fixed-width table of one decoded cycle."""
    when = f" t={t_s:7.2f} s" if t_s is not None else f" ts={cycle.timestamp:.3f}"
    if isinstance(cycle, ObjectCycle):
        ol = cycle.objects
        lines = [f"cycle {cycle.meas_counter:5d}{when}  {len(ol)} objects",
                 "   ID  class       dynprop     long_m   lat_m  vlong_m/s vlat_m/s  rcs_dBsm  LxW_m"]
        for k in range(min(len(ol), max_rows)):
            cls = CLASS_NAMES[ol.obj_class[k]] if 0 <= ol.obj_class[k] < 8 else "-"
            size = f"{ol.length_m[k]:.1f}x{ol.width_m[k]:.1f}" if np.isfinite(ol.length_m[k]) else "-"
            lines.append(f"  {ol.id[k]:3d}  {cls:10s}  {DYN_NAMES[ol.dyn_prop[k]]:10s} {ol.dist_long_m[k]:7.1f} "
                         f"{ol.dist_lat_m[k]:7.1f} {ol.vrel_long_mps[k]:9.2f} {ol.vrel_lat_mps[k]:8.2f} "
                         f"{ol.rcs_dbsm[k]:8.1f}  {size}")
    else:
        cl = cycle.clusters
        n_near = int(cl.is_near.sum())
        lines = [f"cycle {cycle.meas_counter:5d}{when}  {len(cl)} clusters ({n_near} near, {len(cl) - n_near} far)",
                 "   ID  dynprop     long_m   lat_m  vlong_m/s vlat_m/s  rcs_dBsm"]
        for k in range(min(len(cl), max_rows)):
            lines.append(f"  {cl.id[k]:3d}  {DYN_NAMES[cl.dyn_prop[k]]:10s} {cl.dist_long_m[k]:7.1f} "
                         f"{cl.dist_lat_m[k]:7.1f} {cl.vrel_long_mps[k]:9.2f} {cl.vrel_lat_mps[k]:8.2f} "
                         f"{cl.rcs_dbsm[k]:8.1f}")
    n = len(cycle.objects) if isinstance(cycle, ObjectCycle) else len(cycle.clusters)
    if n > max_rows:
        lines.append(f"  ... {n - max_rows} more")
    return "\n".join(lines)


def format_boundaries(boundaries: dict) -> str:
    """One line with the decoded road boundaries (radarnode's RoadBoundary_Left/Right, 0x680/0x681 + 8 × SensorID)."""
    parts = []
    for side in ("left", "right"):
        b = boundaries.get(side)
        if b is None:
            continue
        if not b.valid:
            parts.append(f"{side} unavailable")
        else:
            parts.append(f"{side} {b.offset_m:+.2f} m, heading {np.degrees(b.heading_rad):+.1f}°, "
                         f"{b.range_start_m:.0f}-{b.range_end_m:.0f} m, confidence {b.confidence:.2f}")
    return "road: " + "; ".join(parts) if parts else ""


def format_stats(stats: ConsumerStats) -> str:
    d = stats.as_dict()
    shown = {k: v for k, v in d.items() if v or k in ("frames", "cycles")}
    return "consumer: " + ", ".join(f"{k}={v}" for k, v in shown.items())


def progress(total: int | None, label: str, unit: str = "cycle"):
    """A tqdm progress bar on stderr, shown only when stderr is a terminal (never in piped output or logs).

    tqdm rather than a hand-written bar: it measures the rate and the time left, redraws at most ~10 times a
    second whatever the loop's speed, adapts to the terminal width and to resizes, and leaves a clean line when
    closed or interrupted. ``total`` None shows a running count without a bar.
    """
    from tqdm import tqdm
    return tqdm(total=total, desc=label, unit=unit, file=sys.stderr, disable=not sys.stderr.isatty(),
                dynamic_ncols=True, leave=False)


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, option: str, mode: str = "w", newline: str | None = None):
    """Write ``path`` through a temporary name in the same directory, renamed over it only on success.

    A reader never sees a half-written file: an exception (or Ctrl-C) removes the temporary file and leaves
    any earlier ``path`` untouched. Yields the open file; ``option`` names the option in error messages.
    """
    target = Path(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=target.parent)
    except OSError as exc:
        raise ConfigError(f"option {option}: cannot write {str(path)!r}: {exc.strerror or exc}") from None
    try:
        with os.fdopen(fd, mode, newline=newline, **({} if "b" in mode else {"encoding": "utf-8"})) as f:
            yield f
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike, option: str):
    """Like :func:`atomic_output`, for writers that want a file name (matplotlib's savefig): yields the
    temporary path, renamed to ``path`` on success, removed on failure. The last two suffixes are kept
    (``.blf``, ``.log.gz``) so writers that choose the format by suffix (python-can, matplotlib) still do."""
    target = Path(path)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part" + "".join(target.suffixes[-2:]),
                                   dir=target.parent)
        os.close(fd)
    except OSError as exc:
        raise ConfigError(f"option {option}: cannot write {str(path)!r}: {exc.strerror or exc}") from None
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@dataclasses.dataclass(frozen=True)
class Bitrate:
    """The CAN bit rate in force and where it came from (for the bus-load budget's message)."""

    bit_s: int
    source: str

    def __str__(self) -> str:
        return f"{self.bit_s} bit/s ({self.source})"


def resolve_bitrate(cli_bitrate: int | None, scenario_bitrate: int, *, use_can_config: bool = True,
                    context: str | None = None) -> Bitrate:
    """The bit rate for the bus-load budget, as python-can would open the bus.

    In order: ``-b/--bitrate`` on the command line; python-can's configuration — the environment
    (``CAN_BITRATE``, or ``bitrate`` in the JSON of ``CAN_CONFIG``), then its configuration files
    (``~/can.conf``, ``/etc/can.conf``, ``~/.can``, ``~/.canrc``; section ``[default]``), the same sources and
    precedence as ``can.util.load_config``; last the scenario's ``radar.bitrate`` (500 kbit/s unless the
    scenario says otherwise). ``use_can_config=False`` skips python-can's configuration (``radarnode log``
    opens no bus, so its output must not depend on the machine it runs on).

    Raises ConfigError naming the source when the value is not an integer in 10 000..1 000 000 bit/s.
    """
    import can.util

    candidates: list[tuple[object, str]] = []
    if cli_bitrate is not None:
        candidates.append((cli_bitrate, "command line -b/--bitrate"))
    elif use_can_config:
        suffix = f"_{context}" if context else ""
        env = os.environ.get(f"CAN_BITRATE{suffix}")
        if env:
            candidates.append((env, f"python-can environment CAN_BITRATE{suffix}"))
        else:
            try:
                env_json = json.loads(os.environ.get(f"CAN_CONFIG{suffix}", "{}"))
            except ValueError:
                env_json = {}
            if isinstance(env_json, dict) and "bitrate" in env_json:
                candidates.append((env_json["bitrate"], f"python-can environment CAN_CONFIG{suffix}"))
            else:
                found = None
                for name in can.util.CONFIG_FILES:      # later files override earlier ones, as ConfigParser.read
                    f = os.path.expanduser(name)
                    if os.path.isfile(f):
                        with contextlib.suppress(OSError, ValueError):
                            value = can.util.load_file_config(f, context or "default").get("bitrate")
                            if value:
                                found = (value, f"python-can config file {f}")
                if found:
                    candidates.append(found)
    if not candidates:
        return Bitrate(int(scenario_bitrate), "scenario radar.bitrate")
    value, source = candidates[0]
    try:
        bit_s = int(str(value).strip())
    except ValueError:
        bit_s = None
    if bit_s is None or not 10_000 <= bit_s <= 1_000_000:
        raise ConfigError(f"{source}: bit rate value {value!r} is not allowed; expected an integer "
                          "10000..1000000 bit/s")
    return Bitrate(bit_s, source)
