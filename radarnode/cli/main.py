"""``radarnode`` entry point: dispatch to the subcommands; ``--debug`` re-raises, otherwise ``error: …``."""

from __future__ import annotations

import argparse
import importlib
import logging
import signal
import sys
import traceback

from radarnode import __version__
from radarnode.cli import heap, interrupt, say_standard_output, stdout_refuses
from radarnode.errors import RadarnodeError, Terminated, UsageError

# (the subcommands' and the parser's modules, which import numpy, python-can and the rest, are imported inside
# main(): a Ctrl-C while they load ends the command quietly with 130, not with a traceback)

logger = logging.getLogger(__name__)

#: the subcommands in the order ``--help`` lists them; each is the module ``radarnode.cli.<name>``
COMMANDS = ("run", "node", "consume", "log", "decode", "export", "image", "report", "montecarlo")


def _add_global_options(parser: argparse.ArgumentParser, after: bool) -> None:
    """``--debug`` and ``-v`` on the main parser and, under their own names, on every subcommand, so they are
    accepted before and after the subcommand (``radarnode -v log …`` and ``radarnode log … -v``); the two
    counts add up. SUPPRESS keeps a subcommand's parser from resetting what was given before it."""
    suffix, default = ("_after", argparse.SUPPRESS) if after else ("", None)
    parser.add_argument("--debug", action="store_true", dest="debug" + suffix,
                        default=default if after else False,
                        help="show tracebacks instead of one-line errors")
    parser.add_argument("-v", "--verbose", action="count", dest="verbose" + suffix,
                        default=default if after else 0, help="more log output (-v info, -vv debug)")


def _command_in(argv: list[str]) -> str | None:
    """The subcommand a command line names, when nothing before it asks for the main parser's help or version;
    None otherwise (then every subcommand is set up). The main parser's options take no value, so the first
    word that is not an option is the subcommand."""
    for word in argv:
        if word in ("-h", "--help", "--version") or word.startswith("--help") or word == "--":
            return None
        if not word.startswith("-"):
            return word if word in COMMANDS else None
    return None


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The command-line parser; with ``only``, that subcommand's module alone is imported and set up (the
    others are named, with no options of their own), so that a command does not pay for the imports of the
    eight others (``radarnode log`` starts without the consumer's, the image's or Monte Carlo's)."""
    from radarnode.cli.options import Parser
    parser = Parser(prog="radarnode", description="ARS 408-21 compatible radar node emulator",
                    epilog="exit status: 0 done; 1 a file, scenario, bus or run failed (or report: a scenario "
                           "failed); 2 usage: the command line cannot run as typed; 130/143 stopped by "
                           "SIGINT/SIGTERM (files written so far are complete)")
    parser.add_argument("--version", action="version", version=f"radarnode {__version__}")
    _add_global_options(parser, after=False)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in COMMANDS:
        if only is None or name == only:
            importlib.import_module(f"radarnode.cli.{name}").add_subparser(sub)
        else:
            sub.add_parser(name)
    for sp in sub.choices.values():
        _add_global_options(sp, after=True)
    return parser


def _terminate(signum, frame) -> None:
    if interrupt.held(signum, frame):       # a module is loading: sent again a moment later
        return
    raise Terminated(signum)


def main(argv: list[str] | None = None) -> int:
    """Run one command; the exit status is 0 (done), 1 (a file, scenario, bus or the run failed), 2 (usage: the
    command line cannot run as typed), 128 + the signal (130 SIGINT, 143 SIGTERM) when stopped."""
    standard_streams()
    if not threading_main():
        return _quiet(argv)
    # SIGTERM unwinds like Ctrl-C (temporary files removed, finished files closed) instead of killing the
    # process where it stands; commands that run until stopped install their own handler (stop_on_signals)
    previous = signal.signal(signal.SIGTERM, _terminate)
    try:
        return _quiet(argv)
    finally:
        signal.signal(signal.SIGTERM, previous)


def standard_streams() -> None:
    """Standard input, output and error that the caller closed (``2>&-``, a service started without them): each
    opened on /dev/null, as daemons do, and Python's streams for them (None) on those. Python gives such a stream as
    None, so that the first message (the progress bar asked stderr whether it is a terminal) failed the command before
    it wrote anything; and the file descriptor stays free, so that the first file the command opens would take its
    number and receive whatever a library writes to it."""
    import os
    for fd, name in ((0, "stdin"), (1, "stdout"), (2, "stderr")):
        try:
            os.fstat(fd)
            continue
        except OSError:
            pass
        got = os.open(os.devnull, os.O_RDONLY if fd == 0 else os.O_WRONLY)      # the lowest free number: fd
        if got != fd:
            os.dup2(got, fd)
            os.close(got)
        if getattr(sys, name) is None:
            setattr(sys, name, open(fd, "r" if fd == 0 else "w", closefd=False))


def _quiet(argv: list[str] | None) -> int:
    """:func:`_main`, and a signal that comes before a command runs (while its modules load) ends it quietly too."""
    try:
        return _main(argv)
    except KeyboardInterrupt:
        return 128 + signal.SIGINT
    except Terminated as exc:
        return 128 + exc.signum


def _main(argv: list[str] | None) -> int:
    parser = build_parser(_command_in(sys.argv[1:] if argv is None else list(argv)))
    args = parser.parse_args(argv)
    args.debug = args.debug or getattr(args, "debug_after", False)
    args.verbose += getattr(args, "verbose_after", 0)
    level = logging.WARNING - 10 * min(args.verbose, 2)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    logger.info("radarnode %s %s", __version__, args.command)
    logger.debug("options: %s", {k: v for k, v in vars(args).items() if k != "func"})
    heap.settled(args.command)      # the modules are loaded: the heap frozen, the collector on again (radarnode.cli.heap)
    try:
        return int(args.func(args) or 0)
    except RadarnodeError as exc:
        if args.debug:          # the traceback too, but the same exit status: a usage error stays 2
            traceback.print_exc(file=sys.stderr)
        else:
            print(f"error: {exc}", file=sys.stderr)
        return 2 if isinstance(exc, UsageError) else 1
    except KeyboardInterrupt:
        return 128 + signal.SIGINT
    except Terminated as exc:
        return 128 + exc.signum
    except MemoryError:      # what the checks before the run could not foresee: one line, not a trace
        if args.debug:
            traceback.print_exc(file=sys.stderr)
        print(f"error: {args.command}: out of memory (this machine's memory did not hold what the run asked for); "
              "expected a smaller scenario, frame or run (--fidelity, radar.overrides, --duration)", file=sys.stderr)
        return 1
    except BrokenPipeError:  # output piped into `head` and the like: end quietly
        from radarnode.cli import _to_devnull
        _to_devnull(sys.stdout)
        return 0
    except OSError as exc:   # a write that failed mid-way (a full disk, a vanished directory): one line, not a trace
        if args.debug:
            traceback.print_exc(file=sys.stderr)
            return 1
        if not exc.filename and stdout_refuses() is not None:
            # the command's own output that could not be written (`> /dev/full`): say so, as the final flush does
            say_standard_output(exc)
            return 1
        where = f": {exc.filename!r}" if exc.filename else ""
        print(f"error: {exc.strerror or exc}{where}", file=sys.stderr)
        return 1


def threading_main() -> bool:
    import threading
    return threading.current_thread() is threading.main_thread()
