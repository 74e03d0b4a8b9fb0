"""The command line's garbage collector: off while the modules load, then the loaded heap frozen.

A command's start imports numpy, python-can, cantools and radarnode (some hundred thousand objects that live until
the process ends) and builds its model. Python's cyclic collector ran a dozen times during that start, once over the
whole heap (about 25 ms of a 0.3-s start here), to find no garbage: a module's objects do not die. So a command runs
with the collector off until its modules are loaded and its options parsed (:func:`start`), then moves everything
alive into the permanent generation, which the collector never scans (``gc.freeze``), and turns it on again with a
larger first threshold (:func:`settled`): a cycle of the object level allocates a few hundred containers that mostly
die by reference counting, and a collection every ``GEN0_THRESHOLD`` allocations instead of Python's 700 costs a
``radarnode log`` of 300 s about 40 ms less (measured: 55–60 ms of collections before, under 1 ms after). A process
that ``radarnode log`` forks for the road boundaries (:mod:`radarnode.wire.pipeline`) inherits the frozen heap, and its
collections leave the parent's pages alone (as Python's documentation of ``gc.freeze`` advises before a fork).

Garbage with reference cycles is still collected: a collection of the youngest generation every ``GEN0_THRESHOLD``
net allocations of containers, of all of them every 100 such (the thresholds' two others, 10 and 10). :func:`restore`
gives the collector back as it was (thresholds, on or off, the frozen objects unfrozen), for a caller that runs
:func:`radarnode.cli.main` inside its own process (the tests do, hundreds of times).
"""

from __future__ import annotations

import gc

#: allocations of containers (less deallocations) between two collections of the youngest generation (Python's: 700)
GEN0_THRESHOLD = 10_000

_saved: tuple[bool, tuple[int, int, int]] | None = None


def start() -> None:
    """The collector off until :func:`settled` (its state kept for :func:`restore`)."""
    global _saved
    if _saved is None:
        _saved = (gc.isenabled(), gc.get_threshold())
    gc.disable()


def settled() -> None:
    """The start is over: what is alive now frozen, the collector on again (if it was on) with the larger threshold."""
    if _saved is None:
        return
    gc.freeze()
    gc.set_threshold(GEN0_THRESHOLD, 10, 10)
    if _saved[0]:
        gc.enable()


def restore() -> None:
    """The collector as :func:`start` found it; the frozen objects back in the oldest generation."""
    global _saved
    if _saved is None:
        return
    enabled, threshold = _saved
    _saved = None
    gc.unfreeze()
    gc.set_threshold(*threshold)
    if enabled:
        gc.enable()
    else:
        gc.disable()
