"""The ``radarnode`` command line: one module per subcommand (``add_subparser`` and ``cmd``).

The command line's linear algebra is small (a CFAR ring's 248 × 248 correlation, 3 × 3 solves, beams of 12
elements): OpenBLAS's worker threads only spin after each threaded call and, on a loaded two-core machine,
made one 248 × 248 ``eigvalsh`` take 0.46 s instead of 0.02 s. The commands therefore run OpenBLAS on one
thread unless ``OPENBLAS_NUM_THREADS`` says otherwise (it must be set before numpy is first imported).
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def main(argv: list[str] | None = None, *, ending: bool = False) -> int:
    """The ``radarnode`` command (:func:`radarnode.cli.main.main`). The command line's modules (argparse, logging
    and the rest, some 20 ms) load inside this call, so a Ctrl-C while they load ends the command quietly with 130
    instead of Python's traceback, as one while this function puts its handler in place does: only the interpreter's
    own start-up and the console script's import of this package come before. A
    Ctrl-C that finds a module importing is sent again a moment later (:mod:`radarnode.cli.interrupt`): a library's
    import-time code can turn it into another error or swallow it.

    ``ending``: the process ends with the command (:func:`program`): the start's objects stay frozen."""
    try:
        import signal
        import threading

        from radarnode.cli import heap, interrupt

        heap.start()            # no cyclic collection while the modules load (radarnode.cli.heap)

        # Python's own handler only (a SIGINT ignored, as a job in the background of a shell inherits it, stays
        # ignored)
        ours = (threading.current_thread() is threading.main_thread()
                and signal.getsignal(signal.SIGINT) is signal.default_int_handler)
        if ours:
            signal.signal(signal.SIGINT, interrupt.on_sigint)
        hook = interrupt.install_unraisable()   # a signal raised in a weakref callback: sent again, not lost
    except KeyboardInterrupt:       # a Ctrl-C before the handler is in place (an independent tester: 36 of 100
        _restore_heap()             # Ctrl-Cs in the first 25 ms printed Python's traceback from here)
        return 130
    try:
        try:
            from radarnode.cli.main import main as command
        except KeyboardInterrupt:
            return 130
        status = command(argv)
    finally:
        late = interrupt.cancel()
        heap.restore(unfreeze=not ending)
        if ours:
            signal.signal(signal.SIGINT, signal.default_int_handler)
        import sys
        sys.unraisablehook = hook
    # a signal held while the command's last module loaded, and the command ended before it came again
    return 128 + late if late is not None else status


def _restore_heap() -> None:
    """The garbage collector as :func:`main` found it, if it had been turned off (:mod:`radarnode.cli.heap`)."""
    import sys
    heap = sys.modules.get("radarnode.cli.heap")
    if heap is not None:
        heap.restore()


def program() -> None:
    """The ``radarnode`` program (the console script, ``python -m radarnode``): :func:`main` on the process's command
    line, then the process ends with its status. The objects its start froze (radarnode.cli.heap) stay frozen: given
    back to the collector, Python's last collection at exit scanned them all once more, some 50 ms of every command
    (``radarnode log`` of 300 s: 58–117 ms, median 75, from the command's return to the process's end; 18–21 ms with
    them frozen). Objects made by the command itself are collected at exit as before."""
    raise SystemExit(main(ending=True))
