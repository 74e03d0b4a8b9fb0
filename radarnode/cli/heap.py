"""The command line's garbage collector: off while the modules load, then the loaded heap frozen.

A command's start imports numpy, python-can, cantools and radarnode (some hundred thousand objects that live until
the process ends) and builds its model. Python's cyclic collector ran a dozen times during that start, once over the
whole heap (about 25 ms of a 0.3-s start here), to find no garbage: a module's objects do not die. So a command runs
with the collector off until its modules are loaded and its options parsed (:func:`start`), then moves everything
alive into the permanent generation, which the collector never scans (``gc.freeze``), and turns it on again
(:func:`settled`), with a larger first threshold for the commands that render as fast as they can: a cycle of the
object level allocates a few hundred containers that mostly die by reference counting, and a collection every
``GEN0_THRESHOLD`` allocations instead of Python's 700 costs a ``radarnode log`` of 300 s about 40 ms less
(measured in its run's process: 40–48 ms of collections before, one of them over the whole heap; about 3 ms after).
The real-time commands keep Python's thresholds (``REAL_TIME_COMMANDS``). A process that ``radarnode log`` forks for
the road boundaries (:mod:`radarnode.wire.pipeline`) inherits the frozen heap, and its collections leave the parent's
pages alone (as Python's documentation of ``gc.freeze`` advises before a fork).

Garbage with reference cycles is still collected: a collection of the youngest generation every ``GEN0_THRESHOLD``
net allocations of containers, of all of them every 100 such (the thresholds' two others, 10 and 10). :func:`restore`
gives the collector back as it was (thresholds, on or off, the frozen objects unfrozen unless the caller had frozen
some), for a caller that runs :func:`radarnode.cli.main` inside its own process (the tests do, hundreds of times).
The ``radarnode`` program itself (:func:`radarnode.cli.program`) ends with the start's objects still frozen: Python's
last collection at exit then leaves them alone (handed back, they cost every command some 50 ms more at its end).
"""

from __future__ import annotations

import gc

#: allocations of containers (less deallocations) between two collections of the youngest generation (Python's: 700)
GEN0_THRESHOLD = 10_000
#: the commands that keep Python's thresholds: on a bus in real time, where a collection of 10,000 young objects
#: can delay a frame past its deadline; the frozen heap alone takes their full collection over every module's objects
#: away (``radarnode node scenarios/guardrail_traffic.yaml -i virtual --fidelity detection --send-ego-motion`` for
#: 60 s: the longest pause 18.6 ms before, the one full collection; 1.7 ms with the heap frozen and Python's
#: thresholds; 2.4 ms with the larger one)
REAL_TIME_COMMANDS = ("node", "run", "consume")

_saved: tuple[bool, tuple[int, int, int], int] | None = None


def start() -> None:
    """The collector off until :func:`settled` (its state kept for :func:`restore`)."""
    global _saved
    if _saved is None:
        _saved = (gc.isenabled(), gc.get_threshold(), gc.get_freeze_count())
    gc.disable()


def settled(command: str | None = None) -> None:
    """The start is over: what is alive now frozen, the collector on again (if it was on); with the larger first
    threshold for a command that renders as fast as it can, with the one it had for one on a bus in real time
    (``REAL_TIME_COMMANDS``: a collection pauses the process for as long as it scans)."""
    if _saved is None:
        return
    gc.freeze()
    if command not in REAL_TIME_COMMANDS:
        gc.set_threshold(GEN0_THRESHOLD, 10, 10)
    if _saved[0]:
        gc.enable()


def restore(unfreeze: bool = True) -> None:
    """The collector as :func:`start` found it; the frozen objects back in the oldest generation (unless the caller had
    frozen some: Python cannot tell its from the command's, and its must stay frozen; or ``unfreeze`` is False: the
    process ends with the command, :func:`radarnode.cli.program`)."""
    global _saved
    if _saved is None:
        return
    enabled, threshold, frozen = _saved
    _saved = None
    # (a caller that froze objects of its own keeps them frozen, and the command's with them)
    if unfreeze and not frozen:
        gc.unfreeze()
    gc.set_threshold(*threshold)
    if enabled:
        gc.enable()
    else:
        gc.disable()
