"""The road-boundary estimator in a second process, for runs faster than real time (``radarnode log``).

At the object level the road-boundary estimator (``radarnode.perception.boundaries``) is about half of what a
cycle costs, and it depends on nothing the rest of the cycle computes after it: its input is the cycle's cluster
list and the ego motion, its output two frames of fixed length at the end of the cycle. A
:class:`BoundaryPipeline` forks a process that holds the nodes' estimators (copies made by the fork, before the first
cycle) and computes every cycle's estimate and its two frames there, in the cycles' order, while this process goes on
with the next cycles; :func:`radarnode.wire.runner.run_node` holds each cycle's frames until its boundary frames are
filled, so the frames go to the sinks in the same order, with the same bytes, as without the pipeline (the same
code computes them: :meth:`RadarNode.boundary_payloads <radarnode.wire.node.RadarNode.boundary_payloads>`).

It is for runs whose inputs do not depend on their outputs: no consumer ECU in the loop (whose path prediction reads
the boundaries and whose decisions may drive the ego), no real-time clock (a cycle is held until its process has
answered). :func:`pipeline_for` returns None where it does not pay (a run shorter than ``MIN_CYCLES``) or cannot
run — another operating system than Linux (the process is started by ``fork``, which copies the node as it is; ``spawn`` would import everything again,
some 0.2 s, more than a log of a minute saves) — and the run is then computed in one process, to the same frames.

The cycles go over in batches of ``BATCH`` (one pickle a batch, not a cycle), with at most ``MAX_IN_FLIGHT`` batches
unanswered, so neither process can block the other on a full pipe. While a node at the object level sends objects,
its cluster list is read by nobody but the estimator: the model's table of a block of cycles goes over once
(:meth:`submit_rows`, :meth:`ObjectModel.cluster_rows <radarnode.radar.object_model.ObjectModel.cluster_rows>`) and
each cycle names its rows in it, so this process builds no cluster list (the frame's stays empty); the process
answers a batch's boundary frames encoded a side at a time (:meth:`RadarNode.boundary_payloads_many
<radarnode.wire.node.RadarNode.boundary_payloads_many>`). The process ignores SIGINT and SIGTERM: a Ctrl-C
of the terminal reaches both processes, and the run, which ends after the current cycle, still needs the boundary
frames of the cycles it has computed; it ends when this process closes the pipe (:meth:`BoundaryPipeline.close`) or
exits, however it exits (it holds no copy of this process's end of the pipe, nor of its standard streams). An
exception there is raised here, when its batch is read; an answer that does not come for ``SLOW_ANSWER_S`` (a
stopped process) is warned of and waited for (a run blocked while it hands a batch over, more than the pipe's
buffer, waits without the warning), and a second Ctrl-C gives the run up as it always does.
"""

from __future__ import annotations

import atexit
import logging
import os
import signal
import sys
from collections import Counter, deque

import numpy as np

from radarnode.errors import RadarnodeError

#: cycles handed over in one message
BATCH = 32
#: batches sent and not yet answered, at most (a batch's answer is a few kB: they always fit in the pipe's buffer)
MAX_IN_FLIGHT = 4
#: a run shorter than this many cycles is computed in one process: the second one costs about 10 ms (import, fork,
#: close) and its last batch is computed after the run's last cycle, while it saves about 0.15 ms a cycle at the
#: object level (measured: a 1-s log 6 % slower with it, a 15-s log 2 % faster)
MIN_CYCLES = 4 * BATCH
#: a graceful close waits this long for the process to give the estimators back, else kills it
CLOSE_WAIT_S = 5.0
#: an answer not there after this long is warned of (once a wait), and waited for
SLOW_ANSWER_S = 10.0

logger = logging.getLogger(__name__)


class PipelineError(RadarnodeError, RuntimeError):
    """The boundary process ended without answering (killed, out of memory): the run cannot be completed."""


def pipeline_for(node, cycles: int | None = None) -> BoundaryPipeline | None:
    """A started :class:`BoundaryPipeline` for ``node`` (a RadarNode or a RadarGroup), or None where it does not
    apply: no radar with a road-boundary estimator, no ``fork`` (see the module docstring), or a run of fewer than
    ``MIN_CYCLES`` ``cycles`` (None: any length)."""
    nodes = list(getattr(node, "nodes", [node]))
    if not sys.platform.startswith("linux") or not any(n.boundaries is not None for n in nodes):
        return None
    if cycles is not None and cycles < MIN_CYCLES:
        return None
    return BoundaryPipeline(nodes)


class BoundaryPipeline:
    """See the module docstring. ``nodes``: the RadarNodes whose boundaries are computed in the process (those
    without an estimator are left alone); each is told to hand its boundaries over
    (:meth:`RadarNode.defer_boundaries <radarnode.wire.node.RadarNode.defer_boundaries>`) until :meth:`close`, which
    gives them back their estimators as the process left them (or, if it could not answer, makes their next cycle
    an error: their estimates were lost with it)."""

    def __init__(self, nodes: list) -> None:
        self._nodes = nodes
        self.submitted = 0        # cycles' estimates handed over (a node's cycle each)
        self.done = 0             # of those, answered and filled in
        # per cycle of the batch: (node, clusters, (dt, sensor velocity, yaw rate, ID)[, block, first row, end]);
        # clusters: how many, their columns in _columns; −1: rows of a block (submit_rows)
        self._batch: list = []
        self._columns: list = []        # the batch's cluster columns, five a cycle, sent as one array
        self._blocks: list = []         # the blocks of rows first used in the batch, sent with it
        self._block_of: dict = {}       # per node: the block of rows it used last (sent already)
        self._in_flight = 0
        self._next_look = 0             # collect looks at the pipe when this many estimates are submitted
        self._waiting: deque = deque()   # per estimate submitted and not filled: its frames
        self._closed = False
        self._failed = False            # the process raised or is gone: nothing more comes from it
        self._process = None
        self._deferred = False          # the nodes hand their boundaries over
        for n in nodes:              # a node another pipeline has (or lost) cannot be handed over again
            if n.boundary_pipe is not None:
                raise PipelineError("a node handed to a BoundaryPipeline already (open, or closed without giving "
                                    "its estimator back) cannot be handed to another: make a new node")
        import multiprocessing
        import multiprocessing.util     # (registers its exit handler when first imported: before the one below)

        # closed at exit if the user does not: before multiprocessing's own exit handler (atexit runs the last
        # registered first), which would wait for a daemon that ignores its SIGTERM
        atexit.register(self.close, False)
        ctx = multiprocessing.get_context("fork")
        self._conn, child = ctx.Pipe()
        self._process = ctx.Process(target=_serve, args=(child, self._conn, nodes), name="radarnode-boundaries",
                                    daemon=True)
        # SIGINT/SIGTERM held while the process is made: it inherits them held and ignores them before it takes
        # them (no traceback of a half-made process); here they come when released, after the nodes are handed over
        held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        try:
            try:
                self._process.start()
            finally:
                child.close()
            self._deferred = True
            for k, n in enumerate(nodes):
                if n.boundaries is not None:
                    n.defer_boundaries(self, k)
        except BaseException:          # nothing left running, no node left handed over
            self.close(graceful=False)
            raise
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, held)

    # --- the node's side -------------------------------------------------------------------------------------
    def submit(self, index: int, columns: tuple, scalars: tuple) -> None:
        """Node ``index``'s cycle: the clusters' columns and the ego motion, as
        :meth:`RadarNode.boundary_payloads <radarnode.wire.node.RadarNode.boundary_payloads>` takes them."""
        if self._closed:
            raise PipelineError("this BoundaryPipeline is closed: its nodes compute their boundaries themselves")
        self._batch.append((index, len(columns[0]), scalars))
        self._columns.extend(columns)
        self._waiting.append(None)
        self.submitted += 1
        if len(self._batch) >= BATCH:
            self._send()

    def submit_rows(self, index: int, block: np.ndarray, a: int, b: int, scalars: tuple) -> None:
        """As :meth:`submit`, the clusters as rows a … b−1 of ``block`` (dist_long, dist_lat, vrel_long, vrel_lat;
        shape (4, m)): the object level's table of a block of cycles (:meth:`ObjectModel.cluster_rows
        <radarnode.radar.object_model.ObjectModel.cluster_rows>`), sent once, with the first cycle that uses it."""
        if self._closed:
            raise PipelineError("this BoundaryPipeline is closed: its nodes compute their boundaries themselves")
        new = -1
        if self._block_of.get(index) is not block:
            self._block_of[index] = block
            new = len(self._blocks)
            self._blocks.append(block)
        self._batch.append((index, -1, scalars, new, a, b))
        self._waiting.append(None)
        self.submitted += 1
        if len(self._batch) >= BATCH:
            self._send()

    def attach(self, messages: list) -> None:
        """The frames (blank) of the cycle last submitted: their data is filled in when it is answered."""
        self._waiting[-1] = messages

    # --- the runner's side -----------------------------------------------------------------------------------
    def collect(self, block: bool = False) -> int:
        """Fill in what the process has answered (with ``block``, everything submitted, waiting for it); returns
        :attr:`done`. Without ``block`` the pipe is looked at once a batch (an answer comes a batch at a time)."""
        if block:
            if self._batch:
                self._send()
            while self._in_flight:
                self._receive()
        elif self._in_flight and self.submitted >= self._next_look:
            self._next_look = self.submitted + BATCH
            while self._in_flight and self._conn.poll():
                self._receive()
        return self.done

    def close(self, graceful: bool = True) -> None:
        """End the process; idempotent. ``graceful`` (a run that ended normally): every estimate submitted is
        answered first and the nodes get their estimators back as the process left them, to go on in this
        process. Otherwise (an error, an interrupt, the interpreter's exit) the process is killed at once, and a
        node that cycles again gets a :class:`PipelineError`."""
        if self._closed:
            return
        self._closed = True
        atexit.unregister(self.close)
        states = None
        try:
            if graceful and not self._failed and self._process is not None and self._process.is_alive():
                try:
                    self.collect(block=True)
                    self._conn.send(None)
                    if self._conn.poll(CLOSE_WAIT_S):
                        kind, states = self._conn.recv()
                        states = states if kind == "state" else None
                except (PipelineError, OSError, EOFError):
                    states = None
        finally:
            self._stop_process(states is not None)
        if not self._deferred:
            return
        for k, n in enumerate(self._nodes):
            if n.boundaries is None:
                continue
            if states is not None:
                n.resume_boundaries(states[k])
            elif self.submitted == 0:    # nothing handed over yet: the node's own estimator is still its state
                n.defer_boundaries(None, 0)
            else:
                n.defer_boundaries(_Lost(), k)

    def _stop_process(self, ending: bool) -> None:
        """Join the process (it ends by itself when ``ending``), else kill it; close the pipe."""
        p = self._process
        if p is not None and p.pid is not None:
            if ending:
                p.join(timeout=CLOSE_WAIT_S)
            if p.is_alive():
                p.kill()
            p.join()
        if p is not None:
            self._conn.close()

    # --- the pipe ---------------------------------------------------------------------------------------------
    def _send(self) -> None:
        while self._in_flight >= MAX_IN_FLIGHT:
            self._receive()
        try:
            self._conn.send((self._batch, np.concatenate(self._columns) if self._columns else None, self._blocks))
        except OSError:          # the process is gone: what it answered before (an error?) says why
            while True:
                self._receive()
        self._batch, self._columns, self._blocks = [], [], []
        self._in_flight += 1

    def _receive(self) -> None:
        warned = False
        try:
            while not self._conn.poll(SLOW_ANSWER_S):
                if not warned:     # (stopped, or starved of CPU: a second Ctrl-C gives up the run)
                    logger.warning("the road-boundary process (pid %s) has not answered for %g s; waiting",
                                   self._process.pid, SLOW_ANSWER_S)
                    warned = True
            kind, answer = self._conn.recv()
        except (EOFError, OSError):
            self._failed = True
            self._process.join(timeout=1.0)
            raise PipelineError(f"the road-boundary process (pid {self._process.pid}) ended without answering "
                                f"(exit code {self._process.exitcode}); the run stops here") from None
        self._in_flight -= 1
        if kind == "error":
            self._failed = True
            raise answer
        payloads, saturated = answer
        for index, count in saturated:
            self._nodes[index].saturated.update(count)
        at = 0
        while at < len(payloads):
            messages = self._waiting.popleft()
            for m in messages:
                end = at + len(m.data)
                m.data = bytearray(payloads[at:end])
                at = end
            self.done += 1


class _Lost:
    """A node's pipe after its process ended without giving its estimator back."""

    def submit(self, index, columns, scalars) -> None:
        raise PipelineError("this node's road-boundary estimator was in a BoundaryPipeline's process that ended "
                            "without giving it back (an error or an interrupt): make a new node to run again")


def _serve(conn, parent_end, nodes: list) -> None:
    """The process: each batch's estimates in order, answered with their frames (see the module docstring); at the
    end (None) the estimators' state, so that the nodes go on in the run's process."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})     # (held by the fork)
    parent_end.close()        # so that the run's process ending, however it ends, is an end of file here
    devnull = os.open(os.devnull, os.O_RDWR)
    for fd in (0, 1, 2):      # nor does this process hold the caller's pipes open (a harness waits for them)
        os.dup2(devnull, fd)
    for n in nodes:
        n.saturated.clear()
    blocks: dict = {}        # per node: the block of rows its cycles read (submit_rows)
    while True:
        try:
            batch = conn.recv()
        except (EOFError, OSError):          # the run's process is gone
            return
        if batch is None:
            conn.send(("state", [n.boundary_state() for n in nodes]))
            return
        try:
            cycles, columns, new_blocks = batch
            at = 0
            by_node: dict = {}          # per node: (the cycle's place in the batch, its inputs), in order
            for place, (index, n, scalars, *rows) in enumerate(cycles):
                if n >= 0:
                    cols = [columns[at + k * n:at + (k + 1) * n] for k in range(5)]
                    at += 5 * n
                else:                  # rows a … b−1 of a block (a new one, or the node's last)
                    new, a, b = rows
                    if new >= 0:
                        blocks[index] = new_blocks[new]
                    x, y, vx, vy = blocks[index][:, a:b]
                    cols = [x, y, vx, vy, None]     # (the range: RadarNode.boundary_payloads_many computes it)
                by_node.setdefault(index, []).append((place, (cols, *scalars)))
            answers = [b""] * len(cycles)
            for index, items in by_node.items():       # each node's cycles in their order, a node at a time
                for (place, _), p in zip(items, nodes[index].boundary_payloads_many([c for _, c in items])):
                    answers[place] = p
            payloads = b"".join(answers)
            saturated = [(k, Counter(n.saturated)) for k, n in enumerate(nodes) if n.saturated]
            for n in nodes:
                n.saturated.clear()
            conn.send(("ok", (payloads, saturated)))
        except BaseException as exc:                 # noqa: BLE001 - handed to the run's process, which raises it
            try:
                conn.send(("error", exc))
            except Exception:                         # noqa: BLE001 - an exception that does not pickle
                conn.send(("error", RuntimeError(f"road-boundary process: {exc!r}")))
            return
