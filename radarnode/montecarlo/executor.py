"""Run independent tasks in order-preserving parallel: in this process, on a local process pool, or on a Dask
cluster — the same function, the same tasks, the same results.

Results never depend on where a task runs: each task carries everything it needs (its random stream is derived
from the seed and the task's own key, :mod:`radarnode.montecarlo.seed001`), and results come back in the
order of the tasks. Dask is imported only when a scheduler address or a local Dask cluster is asked for.
"""

from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from radarnode.errors import RadarnodeError, UsageError

#: the address forms ``distributed.Client`` connects to: a host name, IPv4 or a bracketed IPv6 address, a port
SCHEDULER_ADDRESS = re.compile(r"^(tcp|tls|ws|wss|ucx)://([^\s/:\[\]]+|\[[0-9A-Fa-f:.]+\])(:(\d{1,5}))?/?$")


def valid_scheduler(address: object) -> bool:
    """Whether ``address`` is a scheduler address (:data:`SCHEDULER_ADDRESS`) with a port in 1..65535."""
    m = SCHEDULER_ADDRESS.match(address) if isinstance(address, str) else None
    return m is not None and (m.group(4) is None or 1 <= int(m.group(4)) <= 65535)


def default_workers() -> int:
    """All local cores (``os.cpu_count()``; 1 when unknown)."""
    return os.cpu_count() or 1


def check_scheduler(address: str) -> str:
    """The address as given, or UsageError naming ``--scheduler`` and the forms allowed."""
    if not valid_scheduler(address):
        raise UsageError(f"option --scheduler: value {address!r} is not allowed; expected a Dask scheduler address "
                         "such as tcp://host:8786 (tcp, tls, ws, wss or ucx)")
    return address


def limit_blas_threads(n: int = 1) -> bool:
    """Limit this process's OpenBLAS to ``n`` threads; True when a loaded OpenBLAS took the setting.

    The trials are tiny matrix products (12 × 1024 and smaller): a threaded BLAS gains nothing there and, on a
    machine whose cores are busy, its threads wait on each other — one 12-element beam scan went from 4 µs to
    10 ms on the shared 2-core machine. The processes of a sweep are the parallelism. numpy is already
    imported when a command runs, so the environment variable alone is too late for this process; the library's
    own setter is called through ctypes (what threadpoolctl does). The environment variables are set too, for
    processes started from here.
    """
    import ctypes
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = str(n)
    try:
        with open("/proc/self/maps") as f:
            paths = {ln.split()[-1] for ln in f if "openblas" in ln.lower() and ln.split()[-1].startswith("/")}
    except OSError:                                  # not Linux: the environment variables are all there is
        return False
    done = False
    for path in sorted(paths):
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for sym in ("scipy_openblas_set_num_threads64_", "scipy_openblas_set_num_threads",
                    "openblas_set_num_threads64_", "openblas_set_num_threads"):
            setter = getattr(lib, sym, None)
            if setter is not None:
                setter(ctypes.c_int(n))
                done = True
                break
    return done


def require_dask(option: str):
    """``dask.distributed``, or UsageError saying which extra installs it."""
    try:
        import dask.distributed as dd
    except ImportError:
        raise UsageError(f"option {option} needs dask.distributed, which is not installed: "
                         "pip install 'radarnode[dask]'") from None
    return dd


def run_tasks(fn: Callable[[Any], Any], tasks: Sequence[Any], *, workers: int = 1, scheduler: str | None = None,
              dask_local: int | None = None, on_done: Callable[[], None] | None = None) -> list[Any]:
    """``[fn(t) for t in tasks]``, computed where asked; ``on_done`` is called once per finished task.

    Parameters
    ----------
    fn : a picklable function of one task (module-level, or a ``functools.partial`` of one).
    workers : local processes (1: in this process). Ignored with ``scheduler`` or ``dask_local``.
    scheduler : a Dask scheduler address (``tcp://host:8786``): the cluster's workers run the tasks.
    dask_local : start a ``LocalCluster`` of this many single-threaded worker processes for the run.
    """
    return list(iter_tasks(fn, tasks, workers=workers, scheduler=scheduler, dask_local=dask_local, on_done=on_done))


def iter_tasks(fn: Callable[[Any], Any], tasks: Sequence[Any], *, workers: int = 1, scheduler: str | None = None,
               dask_local: int | None = None, on_done: Callable[[], None] | None = None) -> Iterator[Any]:
    """:func:`run_tasks`' results one at a time, in the order of the tasks, each as soon as it and every task before
    it are done (on a Dask cluster: all at the end), so that a caller can show them as they come and an interrupted
    run has shown what it finished. Closing the iterator early cancels the local tasks that have not started."""
    tasks = list(tasks)
    if scheduler is not None or dask_local is not None:
        yield from _run_dask(fn, tasks, scheduler, dask_local, on_done)
        return
    if workers <= 1 or len(tasks) <= 1:
        for t in tasks:
            result = fn(t)
            if on_done:
                on_done()
            yield result
        return
    import concurrent.futures as cf
    import multiprocessing
    # spawn: a fresh interpreter per worker (fork with tqdm's monitor thread alive may deadlock, and spawn is
    # what macOS and Windows do anyway)
    pool = cf.ProcessPoolExecutor(max_workers=min(workers, len(tasks)), mp_context=multiprocessing.get_context("spawn"),
                                  initializer=_pool_worker)
    finished = False
    try:
        # the workers start (in these submits) with SIGINT and SIGTERM blocked, which they inherit: a signal that
        # came while one started made its start-up code print a traceback (KeyboardInterrupt while importing, EOFError
        # when this process stopped writing its start-up data); here the signal waits until they have started
        with _signals_held():
            futures = [pool.submit(fn, t) for t in tasks]
        if on_done:            # as each finishes, whatever its place (the executor's thread calls it)
            for f in futures:
                f.add_done_callback(lambda _f: on_done())
        for f in futures:
            try:
                result = f.result()
            except cf.process.BrokenProcessPool:
                # a worker killed from outside (the kernel's out-of-memory killer, a kill -9): one line, not a trace
                raise RadarnodeError("a worker process ended abruptly (killed from outside, or out of memory); "
                                     "expected it to finish: try fewer --workers") from None
            yield result
        finished = True
    finally:
        if finished:
            pool.shutdown(wait=True)
        else:
            # a caller that stops early (an error, Ctrl-C, SIGTERM) waits neither for the tasks queued nor for those
            # running (a signal-level run takes minutes): the workers are killed, then the pool's own thread, which
            # finds them gone, is joined (left to the interpreter's exit, it raced with it: "Bad file descriptor").
            # (The workers ignore SIGINT: a Ctrl-C that reached them too left one holding the task queue's lock, and
            # the command hung at its exit waiting for it: an independent tester's finding.)
            for proc in list((getattr(pool, "_processes", None) or {}).values()):
                proc.kill()
                proc.join(timeout=10.0)
            pool.shutdown(wait=True)


@contextlib.contextmanager
def _signals_held():
    """SIGINT and SIGTERM held for the block and delivered when it ends: blocked at the operating system (the workers
    started in it inherit that) and, in the main thread, taken by a handler that only notes them (a signal that came
    just before the block runs its Python handler at the next instruction, which may lie inside a worker's start)."""
    import signal
    import threading
    held = (signal.SIGINT, signal.SIGTERM)
    noted: list[int] = []
    main = threading.current_thread() is threading.main_thread()
    before_handlers = {sig: signal.signal(sig, lambda signum, frame: noted.append(signum)) for sig in held} if main \
        else {}
    before_mask = signal.pthread_sigmask(signal.SIG_BLOCK, held) if hasattr(signal, "pthread_sigmask") else None
    try:
        yield
    finally:
        if before_mask is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, before_mask)
        for sig, handler in before_handlers.items():
            signal.signal(sig, signal.SIG_DFL if handler is None else handler)     # (None: one set outside Python)
        for sig in dict.fromkeys(noted):          # each once, in the order they came, to the handlers before
            signal.raise_signal(sig)


def _pool_worker() -> None:
    """A local pool's worker: SIGINT ignored (the parent, which the terminal's Ctrl-C reaches too, stops the pool),
    SIGINT and SIGTERM no longer blocked (they were while it started: :func:`_signals_held`), one BLAS thread
    (:func:`limit_blas_threads`)."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    limit_blas_threads()


def _run_dask(fn, tasks, scheduler, dask_local, on_done):
    import logging
    dd = require_dask("--scheduler" if scheduler is not None else "--dask-local")
    # distributed's loggers are set to INFO by its own configuration: a local cluster's scheduler, which runs in
    # this process, would print a dozen lines a run; they follow radarnode's -v instead (WARNING without it)
    logging.getLogger("distributed").setLevel(max(logging.getLogger().getEffectiveLevel(), logging.DEBUG))
    cluster = None
    if scheduler is not None:
        try:
            client = dd.Client(check_scheduler(scheduler), timeout="10s")
        except (OSError, TimeoutError) as exc:
            # the command line is right, the cluster is not there: exit status 1, as a bus that cannot be opened
            raise RadarnodeError(f"option --scheduler: cannot reach the Dask scheduler at {scheduler!r}: {exc}") \
                from None
    else:
        cluster = dd.LocalCluster(n_workers=dask_local, threads_per_worker=1, processes=True,
                                  dashboard_address=None)
        client = dd.Client(cluster)
    try:
        client.run(limit_blas_threads)
        # pure=False: every task runs (two equal tasks are still two points of the sweep)
        futures = client.map(fn, tasks, pure=False)
        for _ in dd.as_completed(futures):
            if on_done:
                on_done()
        return client.gather(futures)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


__all__ = ["run_tasks", "iter_tasks", "default_workers", "limit_blas_threads", "check_scheduler", "require_dask",
           "SCHEDULER_ADDRESS", "valid_scheduler"]
