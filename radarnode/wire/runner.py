"""Pacing a node: simulated time (as fast as possible) or real time (frames on the deadline).

The runner owns the loop. Cycle k has the deadline ``k × period`` (scenario time); in real time that is
measured from the moment the first cycle is ready. The node computes each cycle *ahead* of its deadline:
right after cycle k−1 has gone out it takes the input received so far, adds the vehicle's ego-motion frames
if asked, computes cycle k, then waits for k's deadline — receiving input meanwhile, which therefore
takes effect in cycle k+1 — and sends the frames on the deadline. So the period does not depend on what a
scene costs, as long as a cycle costs less than a period.

Which cycle an input affects: a frame received before the node starts computing cycle k (i.e. before cycle
k−1 has been sent) takes effect in cycle k; one received after that, in cycle k+1. Input therefore takes
effect one to two periods after it arrives — the real sensor also applies what it received when it starts a
measurement cycle. In simulated time the same rule holds, with no wait between cycles.

A cycle that cannot go out within ``RealTimeClock.tolerance_s`` (2 ms) of its deadline — computed too late,
or the process woken too late by the operating system — is not sent late: it is dropped
and flagged (``RadarNode.missed_deadline``: a counter, MeasCounter moves on, RadarState's Temporary_Error). The
check is made just before the cycle is handed to the bus; a process preempted between the check and the bus
taking its frames sends that cycle late, which the node sees when the send returns and flags the same way
(``RadarNode.sent_late``: counted in ``cycles_sent_late``). What happens after the bus has taken a frame (the
kernel's queue, the receiver's scheduling) no sender sees.
When the model is slower than the cycle, the runner skips (and flags) the cycles whose deadline would pass
before they could be computed, so the cycles that do go out stay on the grid.

A stop request (Ctrl-C in the CLI) ends the run between cycles, so a log never ends in the middle of a cycle.
"""

from __future__ import annotations

import collections
import math
import statistics
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field

import can

from radarnode.wire.busload import STANDARD_BITS_NOMINAL
from radarnode.wire.node import CycleOutput, EgoMotionSender, RadarNode
from radarnode.wire.pipeline import BoundaryPipeline

Sink = Callable[[can.Message], None]

DEADLINE_TOLERANCE_S = 0.002   # a cycle ready later than this after its deadline is dropped and flagged
_SLEEP_MARGIN_S = 0.002        # stop polling the bus this long before a deadline, then sleep to it …
_SPIN_S = 0.0005               # … and spin the last half millisecond (a sleep's wake-up is late under load)
_STOP_CHECK_S = 0.05           # a wait for a deadline looks at the stop event this often
KEEP_CYCLES = 50_000          # RunStats keeps the send times of this many cycles (an hour at 72 ms)
_DRAIN_S = 0.004               # real time: the longest a poll(0) spends on queued input before computing a cycle
_MAX_UNREADABLE_IN_ROW = 64    # a poll gives up after this many frames in a row the bus could not read
_UNREADABLE = object()         # what a poll got instead of a frame the bus could not read


@dataclass
class RunStats:
    """What a run did, for the end-of-run summary and the benchmarks."""

    cycles: int = 0                 # cycles sent
    frames: int = 0
    bits: int = 0
    duration_s: float = 0.0
    missed: int = 0                 # cycles not sent because they were not ready in time (real time)
    sent_late: int = 0              # cycles whose frames the bus took later than the tolerance (real time: flagged)
    # real time, the last KEEP_CYCLES cycles sent (bounded, so that a node running for days does not grow):
    cycle_start_s: deque = field(default_factory=lambda: deque(maxlen=KEEP_CYCLES))  # send time from the origin
    send_error_s: deque = field(default_factory=lambda: deque(maxlen=KEEP_CYCLES))   # send time minus deadline
    rx_drain_cut: int = 0           # real time: polls that stopped with input still queued (a flooded bus)

    def bus_load(self, bitrate: int) -> float:
        return self.bits / (bitrate * self.duration_s) if self.duration_s > 0 else 0.0


class SimulatedClock:
    """Scenario time, no waiting; frame timestamps are ``epoch_s`` + scenario time."""

    realtime = False
    tolerance_s = math.inf

    def __init__(self, epoch_s: float = 0.0) -> None:
        self.epoch_s = epoch_s

    def start(self) -> None:
        pass

    def now(self) -> float:
        return 0.0

    def wait_until(self, t_s: float, poll: Callable[[float], None] | None,
                   stop: threading.Event | None = None) -> None:
        pass

    def timestamp(self, t_s: float) -> float:
        return self.epoch_s + t_s


class RealTimeClock:
    """Wall-clock pacing against absolute deadlines (no drift); timestamps are wall-clock.

    Parameters
    ----------
    tolerance_s : float
        How late after its deadline a cycle may still be sent; a later one is dropped and flagged.
    timer, sleep, wall : callables, optional
        Monotonic seconds, sleeping, and wall-clock seconds (``time.perf_counter``, ``time.sleep``,
        ``time.time``); replaceable so that tests can drive the clock without waiting.
    """

    realtime = True

    def __init__(self, tolerance_s: float = DEADLINE_TOLERANCE_S, *, timer: Callable[[], float] = time.perf_counter,
                 sleep: Callable[[float], None] = time.sleep, wall: Callable[[], float] = time.time) -> None:
        if not tolerance_s >= 0.0:
            raise ValueError(f"tolerance_s: value {tolerance_s!r} is not allowed; expected a number >= 0")
        self.tolerance_s = tolerance_s
        self._timer, self._sleep, self._wall = timer, sleep, wall
        self._spin = timer is time.perf_counter      # an injected timer does not advance by itself
        self._t0 = 0.0
        self._wall0 = 0.0

    def start(self) -> None:
        self._t0 = self._timer()
        self._wall0 = self._wall()

    def now(self) -> float:
        """Seconds since ``start``."""
        return self._timer() - self._t0

    def wait_until(self, t_s: float, poll: Callable[[float], None] | None,
                   stop: threading.Event | None = None) -> None:
        """Return at ``t_s`` seconds after ``start``, letting ``poll(timeout)`` receive until just before; or as soon
        as ``stop`` is set (within ``_STOP_CHECK_S``: a radar cycling every 10 s took up to 10 s to end on Ctrl-C)."""
        while True:
            remaining = t_s - self.now()
            if remaining <= 0.0 or (stop is not None and stop.is_set()):
                return
            if poll is not None and remaining > 1.05 * _SLEEP_MARGIN_S:
                # the bus's timeout is coarse; the last milliseconds are slept, not polled
                poll(min(remaining - _SLEEP_MARGIN_S, 0.05))
                continue
            if not self._spin:                 # an injected clock (tests): its sleep moves it
                self._sleep(remaining)
                return
            if stop is not None and remaining > _SPIN_S + _STOP_CHECK_S:
                self._sleep(_STOP_CHECK_S)
                continue
            if remaining > _SPIN_S:
                self._sleep(remaining - _SPIN_S)
            while self.now() < t_s:
                pass
            return

    def timestamp(self, t_s: float) -> float:
        return self._wall0 + self.now()


def run_node(node: RadarNode, *, clock: SimulatedClock | RealTimeClock, sinks: Iterable[Sink],
             recv: Callable[[float], can.Message | None] | None = None,
             vehicle: EgoMotionSender | None = None, duration_s: float | None = None,
             on_cycle: Callable[[CycleOutput], None] | None = None,
             stop: threading.Event | None = None, pipeline: BoundaryPipeline | None = None,
             echoes_own: bool = False) -> RunStats:
    """Run ``node`` for the scenario's duration (or ``duration_s``) and return statistics.

    Parameters
    ----------
    recv : callable(timeout_s) -> Message or None, optional
        Source of received frames (e.g. ``bus.recv``); drained before every cycle is computed and, in real
        time, while waiting for a deadline (see the module docstring for which cycle they affect).
    vehicle : EgoMotionSender, optional
        Sends 0x300/0x301 for each cycle just before the node computes it; the node receives them directly
        too (a python-can bus does not deliver a sender's own frames back to it). Both clocks put the same
        frames in the same order on the wire, so real time and simulated time give the same payloads.
    on_cycle : callable(CycleOutput), optional
        Called after each cycle sent (not for a cycle dropped at its deadline).
    echoes_own : bool
        The bus gives back the frames this process sends (udp_multicast; :func:`radarnode.wire.bus.echoes_own`):
        ``vehicle``'s frames, which the node takes as they are sent, are not taken again when they come back (each
        one sent skips one identical frame received; counted in the node's ``rx_own_echo``).
    pipeline : BoundaryPipeline, optional
        The process that computes the node's road boundaries (:mod:`radarnode.wire.pipeline`; simulated time only):
        each cycle goes to the sinks, whole and in order, once its boundary frames are filled in.
    """
    if pipeline is not None and clock.realtime:
        raise ValueError("a BoundaryPipeline holds cycles until their boundaries are computed: not in real time")
    for one in getattr(node, "nodes", [node]):
        if isinstance(one.boundary_pipe, BoundaryPipeline) and one.boundary_pipe is not pipeline:
            raise ValueError("the node hands its road boundaries to a BoundaryPipeline: pass it as pipeline= (or "
                             "close it first), else its boundary frames would go out blank")
    sinks = list(sinks)
    stats = RunStats()
    period = node.period_s
    total = node.scenario.duration_s if duration_s is None else duration_s
    n_cycles = int(total / period + 1e-9)
    for one in getattr(node, "nodes", [node]):         # every radar of a group
        for model in (one.model, getattr(one.model, "object", None)):
            if hasattr(model, "planned_cycles"):   # the object level computes its cycles in chunks: none past the end
                model.planned_cycles = n_cycles
    bitrate = float(node.bitrate)     # (frame_time_s's division: a frame's nominal time on the wire)
    rx_t = [0.0]       # scenario time given to received frames: the last cycle computed
    busy_until = [-math.inf]   # simulated time: when the last frame computed leaves the bus
    echoes: collections.Counter = collections.Counter()    # the vehicle frames sent, as the bus returns them

    def poll(timeout: float) -> None:
        """Receive for up to ``timeout`` seconds: whatever is queued, then what arrives until then.

        The time is bounded whatever arrives (a bus flooded faster than frames can be handled must not hold
        the node past its deadline): in real time it drains for at most ``timeout`` (``_DRAIN_S`` when
        ``timeout`` is 0) and what is left waits for the next poll (or is dropped by the bus's own queue). In
        simulated time it drains everything queued, so that a run stays deterministic."""
        if recv is None:
            if timeout > 0:
                time.sleep(timeout)
            return
        end = time.perf_counter() + max(timeout, _DRAIN_S)
        msg = receive(timeout)
        unreadable_in_row = 0
        while msg is not None:
            if msg is _UNREADABLE:
                unreadable_in_row += 1
                if unreadable_in_row >= _MAX_UNREADABLE_IN_ROW:     # a bus that only raises: try next time
                    return
            else:
                unreadable_in_row = 0
                key = (msg.arbitration_id, bytes(msg.data))
                if echoes.get(key):
                    # the bus gave back a frame this run sent (udp_multicast loops its datagrams back to the sender):
                    # the node took it when it was sent (an independent tester found 0x300/0x301 taken twice)
                    echoes[key] -= 1
                    node.counters["rx_own_echo"] += 1
                else:
                    node.receive(msg, rx_t[0])
            if clock.realtime and time.perf_counter() >= end:
                stats.rx_drain_cut += 1
                return
            msg = receive(0.0)

    def receive(timeout: float) -> can.Message | object | None:
        """One frame from the bus; one the bus cannot read (a corrupt datagram on udp_multicast, a frame
        python-can's checks refuse) is counted in the node's ``rx_unreadable`` and skipped, never raised."""
        try:
            return recv(timeout)
        except (can.CanError, ValueError, TypeError) as exc:
            node.counters["rx_unreadable"] += 1
            node.warn_once("rx_unreadable", "a frame the bus could not read was skipped (%s); counted in "
                           "rx_unreadable, warned once", exc)
            return _UNREADABLE

    def send(messages: list[can.Message]) -> None:
        for m in messages:
            if clock.realtime:
                m.timestamp = clock.timestamp(0.0)
            for sink in sinks:
                try:
                    sink(m)
                except can.CanError as exc:
                    # the bus did not take the frame (a full transmit queue: on a physical bus with no other node
                    # to acknowledge, socketcan's ENOBUFS; a send timeout): lost, counted, and the node goes on, as
                    # a controller drops what it cannot send (it ended the node with a traceback)
                    node.counters["tx_failed"] += 1
                    node.warn_once("tx_failed", "the bus did not take a frame (%s); it is lost, counted in "
                                   "tx_failed, warned once", exc)

    def prepare(k: int) -> CycleOutput:
        """Take the input received so far, send the vehicle's frames, compute cycle k."""
        t = k * period
        if recv is not None:
            poll(0.0)
        after = 0.0
        start = clock.timestamp(t)
        if not clock.realtime and start < busy_until[0]:
            # the bus still carries the cycle before (more frames than a period holds, at a low bit rate): this one's
            # frames follow them, never stamped before them (an independent tester's log ran backwards)
            start = busy_until[0]
        if vehicle is not None:
            ego_frames = vehicle.frames(t, start)
            for m in ego_frames:
                node.receive(m, t)
            if echoes_own:          # what the bus will give back of them
                echoes.update((m.arbitration_id, bytes(m.data)) for m in ego_frames)
            if pipeline is not None:             # behind the held cycles
                held.append((pipeline.submitted, ego_frames, None))
            else:
                send(ego_frames)
            stats.frames += len(ego_frames)
            # the radar's frames follow the vehicle's on the wire
            after = sum([STANDARD_BITS_NOMINAL[len(m.data)] / bitrate for m in ego_frames])
        out = node.cycle(t, start + after)
        if out.messages:
            last = out.messages[-1]
            busy_until[0] = last.timestamp + STANDARD_BITS_NOMINAL[len(last.data)] / bitrate
        rx_t[0] = t
        return out

    def sent(out: CycleOutput) -> None:
        stats.cycles += 1
        stats.frames += len(out.messages)
        stats.bits += out.bits
        if on_cycle is not None:
            on_cycle(out)

    # with a pipeline, what waits to be sent in order: (the boundary estimates it needs, frames, its cycle or None)
    held: deque[tuple[int, list[can.Message], CycleOutput | None]] = deque()

    def release(block: bool = False) -> None:
        """Send what is held up to the first cycle whose boundary frames are not in yet (with ``block``: all)."""
        done = pipeline.collect(block)
        while held and held[0][0] <= done:
            _, messages, out = held.popleft()
            send(messages)
            if out is not None:
                sent(out)

    def stopped() -> bool:
        return stop is not None and stop.is_set()

    clock.start()
    k = 0
    pending = prepare(0) if n_cycles and not stopped() else None
    origin = clock.now()            # real time: the schedule starts when the first cycle is ready
    costs: deque[float] = deque(maxlen=8)   # what the last cycles took to compute (the first, warming up, not)
    while pending is not None:
        out = pending
        pending = None
        deadline = origin + k * period
        clock.wait_until(deadline, poll if recv is not None else None, stop)
        late = clock.now() - deadline
        if stopped():
            node.withdraw(out)
            break
        if late > clock.tolerance_s:
            # not ready in time: dropped and flagged, never sent late
            node.withdraw(out)
            node.missed_deadline(out.t_s, late)
            stats.missed += 1
        else:
            if clock.realtime:
                stats.cycle_start_s.append(clock.now() - origin)
                stats.send_error_s.append(late)
                # the process can be preempted between the check above and the bus taking the header: a cycle
                # whose header was handed over later than the tolerance went out late, and is flagged as one (it
                # cannot be recalled; the frames after the header take their own time on any bus)
                lead = out.lead or len(out.messages)
                send(out.messages[:lead])
                handed = clock.now() - deadline
                if handed > clock.tolerance_s:
                    node.sent_late(out.t_s, handed)
                    stats.sent_late += 1
                send(out.messages[lead:])
                sent(out)
            elif pipeline is not None:          # held until its boundary frames are in
                held.append((pipeline.submitted, out.messages, out))
                release()
            else:
                send(out.messages)
                sent(out)
        k += 1
        if clock.realtime and len(costs) >= 3:
            # a model slower than the cycle: skip the cycles whose deadline comes before a cycle could be
            # computed (the median of the last few: one slow cycle is no reason to skip), so the ones that go
            # out stay on the grid and none is computed in vain
            ready = clock.now() + statistics.median(costs)
            first = max(k, math.ceil((ready - origin) / period - 1e-9))
            if first > k:
                skipped = min(first, n_cycles) - k
                node.missed_deadline(k * period, ready - (origin + k * period), skipped=skipped, computed=False)
                stats.missed += skipped
                k = first
        if k < n_cycles and not stopped():
            begin = clock.now()
            pending = prepare(k)
            costs.append(clock.now() - begin)
    if pipeline is not None:
        release(block=True)
    stats.duration_s = min(k, n_cycles) * period
    return stats
