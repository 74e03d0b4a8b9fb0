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


#: :func:`main` under a name no submodule takes: importing ``radarnode.cli.main`` (the first command does) puts that
#: module in this package's namespace as ``main`` (an independent tester: a second :func:`program` in one process
#: called the module)
_command_line = main


def program() -> None:
    """The ``radarnode`` program (the console script, ``python -m radarnode``): :func:`main` on the process's command
    line, then the process ends with its status. The objects its start froze (radarnode.cli.heap) stay frozen: given
    back to the collector, Python's last collection at exit scanned them all once more, some 50 ms of a command that
    ran (``radarnode log`` of 300 s: 51–115 ms, median 65–75, from the command's return to the process's end; 17–28 ms
    with them frozen; argparse's ``--help``, ``--version`` and usage errors end before anything is frozen). Objects
    made by the command itself are collected at exit as before.

    What the command printed is written out here (:func:`_flushed`), where its failure is still an answer: output
    small enough to wait in the buffer for Python's own flush at exit met a closed pipe or a full disk there, and
    ended with Python's status 120 and "Exception ignored" (an independent tester: ``decode --max-cycles 1 … | head
    -0``, ``--version >/dev/full``; larger output had already failed inside the command, which ends quietly on a
    closed pipe and with one error line on a full disk)."""
    try:
        status = _command_line(ending=True)
    except SystemExit as stop:            # argparse: --help, --version, a usage error
        status = stop.code
        refused = stdout_refuses() if status in (0, None) else None
        if refused is not None:
            # argparse drops a failed write of its help or version (unbuffered output: PYTHONUNBUFFERED, as many
            # container images set it, ended `--help > /dev/full` with status 0 and nothing said)
            say_standard_output(refused)
            status = 1
    raise SystemExit(_flushed(status))


def stdout_refuses() -> OSError | None:
    """The error standard output gives an empty write (``> /dev/full``), or None where it takes writes, has no file
    descriptor (a stream in memory) or is a pipe its reader closed (ended quietly). A failed write of the command's
    own output has emptied the stream's buffer by then, so a flush would not tell. Where it refuses, its descriptor
    goes to /dev/null, so that the exit's flush does not fail again."""
    import sys
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, ValueError, OSError):      # io.UnsupportedOperation: no descriptor
        return None
    try:
        os.write(fd, b"")
    except BrokenPipeError:             # a reader that closed the pipe: quietly, as everywhere
        _to_devnull(sys.stdout)
    except OSError as exc:
        _to_devnull(sys.stdout)
        return exc
    return None


def say_standard_output(exc: OSError) -> None:
    """The one line that says standard output took no write (a full disk, ``> /dev/full``)."""
    import sys
    try:
        print(f"error: standard output: {exc.strerror or exc}", file=sys.stderr, flush=True)
    except OSError:
        pass


def _flushed(status):
    """``status`` once standard output and error are written out: a closed pipe ends quietly (the rest goes to
    /dev/null, as the command does for a large output); another failure (a full disk) is one error line and status 1
    where the command had succeeded."""
    import sys
    for stream in (sys.stdout, sys.stderr):
        try:
            if stream is not None:
                stream.flush()
        except BrokenPipeError:
            _to_devnull(stream)
        except OSError as exc:
            _to_devnull(stream)
            if stream is sys.stdout:
                say_standard_output(exc)
                if status in (0, None):
                    status = 1
    return status


def _to_devnull(stream) -> None:
    """``stream``'s file descriptor on /dev/null, so that what its buffer still holds goes nowhere, quietly."""
    import os
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, stream.fileno())
        os.close(devnull)
    except (OSError, ValueError):
        pass
