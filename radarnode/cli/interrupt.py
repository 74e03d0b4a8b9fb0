"""Ctrl-C and SIGTERM while a module is being imported: held back and sent again a moment later.

Python raises KeyboardInterrupt (radarnode's handler: :class:`radarnode.errors.Terminated`) wherever the main thread
is when the signal arrives. Inside a library's import-time code that is unsafe: an exception raised while a class
body's ``__set_name__`` runs comes out as a RuntimeError, and libraries that import their parts inside ``try: …
except Exception`` swallow that. A Ctrl-C in the first few tenths of a second of ``radarnode log``, while its modules
load, then printed a traceback and ended with 1 (inside cantools' ``DbcComments``: 1 of 15 tries), or was lost and
the run went on to its end with 0 (once in a full test run). The command's handlers therefore hold a signal that
finds the main thread importing and send it again :data:`RETRY_S` later, until it lands in the command's own code.

Python cannot raise at all where it runs a weakref callback or a finalizer (``__del__``, a garbage collection's
callbacks): the exception comes out as "Exception ignored in …" with its traceback, and is gone. A Ctrl-C that landed
in ``WeakSet._remove`` while ``radarnode log`` started printed that and the run went on to its end with 0 (once in a
full test run on a loaded machine). :func:`unraisable` is the command's ``sys.unraisablehook``: such a signal's
exception is sent again as the signal, the same way, and nothing is printed.
"""

from __future__ import annotations

import os
import signal
import sys
import threading

#: a held signal is sent again after this long (s): imports take milliseconds, a person's Ctrl-C waits for 50 ms
RETRY_S = 0.05
_IMPORT_FILES = frozenset({"<frozen importlib._bootstrap>", "<frozen importlib._bootstrap_external>"})
_pending: dict[int, threading.Timer] = {}
#: taken by a send and by :func:`cancel` (never by :func:`held`, which a signal handler runs)
_lock = threading.Lock()


def importing(frame) -> bool:
    """Whether ``frame`` (a signal handler's) or one of its callers is the import machinery's: a module is loading."""
    while frame is not None:
        if frame.f_code.co_filename in _IMPORT_FILES:
            return True
        frame = frame.f_back
    return False


def held(signum: int, frame) -> bool:
    """True when the signal finds the main thread importing; it is then sent again :data:`RETRY_S` later (once,
    however often it arrives meanwhile). A handler that gets True returns without raising."""
    if not importing(frame):
        return False
    _later(signum)
    return True


def _later(signum: int) -> None:
    """Send ``signum`` again :data:`RETRY_S` from now (once, however often it is asked for meanwhile)."""
    timer = _pending.get(signum)
    if timer is None or not timer.is_alive():
        own: list = []
        timer = threading.Timer(RETRY_S, _send, (signum, own))
        own.append(timer)
        timer.daemon = True
        _pending[signum] = timer
        timer.start()


def _send(signum: int, own: list) -> None:
    """A held signal's send (its timer's thread): taken off the pending ones first, so that the signal, if it finds
    the main thread importing still, is held again and sent once more. Taken off after the send, as before
    2026-12-04, it could be handled while its timer was still alive — held, and nothing sent again: the Ctrl-C was
    lost (once in a full test run on a loaded machine). Not sent if :func:`cancel` came first."""
    with _lock:
        if _pending.get(signum) is not own[0]:
            return
        del _pending[signum]
        os.kill(os.getpid(), signum)


def cancel() -> int | None:
    """Stop the sends not yet made (the command is ending); the signal of one that was still to come, else None."""
    late = None
    with _lock:
        for signum, timer in list(_pending.items()):
            if timer.is_alive():
                timer.cancel()
                late = signum
        _pending.clear()
    return late


def on_sigint(signum: int, frame) -> None:
    """SIGINT's handler while a command loads and runs: Python's KeyboardInterrupt, held while a module imports."""
    if held(signum, frame):
        return
    raise KeyboardInterrupt


def unraisable(args) -> None:
    """``sys.unraisablehook`` while a command runs: a KeyboardInterrupt or :class:`~radarnode.errors.Terminated` that
    a signal handler raised where Python cannot raise (a weakref callback, a finalizer) is sent again as its signal
    :data:`RETRY_S` later, printing nothing; anything else goes to the hook that was there before
    (:func:`install_unraisable`)."""
    exc = args.exc_value
    signum = signal.SIGINT if isinstance(exc, KeyboardInterrupt) else getattr(exc, "signum", None)
    if signum is not None and isinstance(exc, BaseException) and not isinstance(exc, Exception):
        _later(int(signum))
        return
    _previous_hook(args)


_previous_hook = sys.unraisablehook


def install_unraisable() -> object:
    """Make :func:`unraisable` ``sys.unraisablehook``; returns the hook it replaced (for the caller to restore)."""
    global _previous_hook
    before = sys.unraisablehook
    if before is not unraisable:
        _previous_hook = before
        sys.unraisablehook = unraisable
    return before
