"""Pacing a node: simulated time (as fast as possible) or real time (frames paced to the cycle).

The runner owns the loop: each cycle it lets received frames reach the node,
adds the vehicle's ego-motion frames if asked, asks the node for the cycle's
frames and hands them to the sinks (a bus's ``send``, a log writer, both).
A stop request (Ctrl-C in the CLI) ends the run between cycles, so a log
never ends in the middle of a cycle.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import can

from radarnode.wire.busload import frame_time_s
from radarnode.wire.node import CycleOutput, EgoMotionSender, RadarNode

Sink = Callable[[can.Message], None]


@dataclass
class RunStats:
    """What a run did, for the end-of-run summary and the benchmark."""

    cycles: int = 0
    frames: int = 0
    bits: int = 0
    duration_s: float = 0.0
    cycle_start_s: list[float] = field(default_factory=list)   # wall-clock start of every cycle (real time)

    def bus_load(self, bitrate: int) -> float:
        return self.bits / (bitrate * self.duration_s) if self.duration_s > 0 else 0.0


class SimulatedClock:
    """Scenario time, no waiting; frame timestamps are ``epoch_s`` + scenario time."""

    realtime = False

    def __init__(self, epoch_s: float = 0.0) -> None:
        self.epoch_s = epoch_s

    def start(self) -> None:
        pass

    def wait_until(self, t_s: float, poll: Callable[[float], None] | None) -> None:
        if poll is not None:
            poll(0.0)

    def timestamp(self, t_s: float) -> float:
        return self.epoch_s + t_s


class RealTimeClock:
    """Wall-clock pacing against absolute deadlines (no drift); timestamps are wall-clock."""

    realtime = True

    def __init__(self) -> None:
        self._t0 = 0.0
        self._wall0 = 0.0

    def start(self) -> None:
        self._t0 = time.perf_counter()
        self._wall0 = time.time()

    def wait_until(self, t_s: float, poll: Callable[[float], None] | None) -> None:
        while True:
            remaining = self._t0 + t_s - time.perf_counter()
            if remaining <= 0.0:
                return
            if poll is not None:
                poll(min(remaining, 0.05))
            else:
                time.sleep(min(remaining, 0.05))

    def timestamp(self, t_s: float) -> float:
        return self._wall0 + (time.perf_counter() - self._t0)


def run_node(node: RadarNode, *, clock: SimulatedClock | RealTimeClock, sinks: Iterable[Sink],
             recv: Callable[[float], can.Message | None] | None = None,
             vehicle: EgoMotionSender | None = None, duration_s: float | None = None,
             on_cycle: Callable[[CycleOutput], None] | None = None,
             stop: threading.Event | None = None) -> RunStats:
    """Run ``node`` for the scenario's duration (or ``duration_s``) and return statistics.

    Parameters
    ----------
    recv : callable(timeout_s) -> Message or None, optional
        Source of received frames (e.g. ``bus.recv``); drained before every cycle
        and, in real time, while waiting for the next one.
    vehicle : EgoMotionSender, optional
        Sends 0x300/0x301 before each cycle; the node receives them directly too
        (a python-can bus does not deliver a sender's own frames back to it).
    """
    sinks = list(sinks)
    stats = RunStats()
    period = node.period_s
    total = node.scenario.duration_s if duration_s is None else duration_s
    n_cycles = int(total / period + 1e-9)
    current_t = [0.0]

    def poll(timeout: float) -> None:
        if recv is None:
            if timeout > 0:
                time.sleep(timeout)
            return
        msg = recv(timeout)
        while msg is not None:
            node.receive(msg, current_t[0])
            msg = recv(0.0)

    clock.start()
    wall0 = time.perf_counter()
    for k in range(n_cycles):
        if stop is not None and stop.is_set():
            break
        t = k * period
        clock.wait_until(t, poll)
        current_t[0] = t
        if clock.realtime:
            stats.cycle_start_s.append(time.perf_counter() - wall0)
        messages: list[can.Message] = []
        if vehicle is not None:
            ego_frames = vehicle.frames(t, clock.timestamp(t))
            for m in ego_frames:
                node.receive(m, t)
            messages += ego_frames
        # the radar's frames follow the vehicle's on the wire
        after = sum(frame_time_s(len(m.data), node.bitrate, worst_case=False) for m in messages)
        out = node.cycle(t, clock.timestamp(t) + after)
        messages += out.messages
        for m in messages:
            if clock.realtime:
                m.timestamp = clock.timestamp(t)
            for sink in sinks:
                sink(m)
        stats.cycles += 1
        stats.frames += len(messages)
        stats.bits += out.bits
        if on_cycle is not None:
            on_cycle(out)
    stats.duration_s = stats.cycles * period
    return stats
