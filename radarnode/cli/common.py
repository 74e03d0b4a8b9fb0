"""Helpers shared by the subcommands: scenario loading, stop handling, tables, progress."""

from __future__ import annotations

import contextlib
import signal
import sys
import threading

import numpy as np

from radarnode.consumer.assembler import ClusterCycle, ConsumerStats, ObjectCycle
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


class Progress:
    """A one-line progress bar on stderr, only when stderr is a terminal."""

    def __init__(self, total: int, label: str) -> None:
        self.total = max(total, 1)
        self.label = label
        self.enabled = sys.stderr.isatty()

    def update(self, done: int) -> None:
        if self.enabled and (done % 10 == 0 or done == self.total):
            width = 30
            filled = int(width * done / self.total)
            sys.stderr.write(f"\r{self.label} [{'#' * filled}{'.' * (width - filled)}] {done}/{self.total}")
            sys.stderr.flush()

    def close(self) -> None:
        if self.enabled:
            sys.stderr.write("\n")
