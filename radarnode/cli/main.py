"""``radarnode`` entry point: dispatch to the subcommands; ``--debug`` re-raises, otherwise ``error: …``."""

from __future__ import annotations

import argparse
import logging
import sys

from radarnode import __version__
from radarnode.cli import consume, decode, export, image, log, node, report, run
from radarnode.errors import RadarnodeError

logger = logging.getLogger(__name__)

SUBCOMMANDS = (run, node, consume, log, decode, export, image, report)


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


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="radarnode", description="ARS 408-21 compatible radar node emulator")
    parser.add_argument("--version", action="version", version=f"radarnode {__version__}")
    _add_global_options(parser, after=False)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in SUBCOMMANDS:
        module.add_subparser(sub)
    for sp in sub.choices.values():
        _add_global_options(sp, after=True)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    args.debug = args.debug or getattr(args, "debug_after", False)
    args.verbose += getattr(args, "verbose_after", 0)
    level = logging.WARNING - 10 * min(args.verbose, 2)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    logger.info("radarnode %s %s", __version__, args.command)
    logger.debug("options: %s", {k: v for k, v in vars(args).items() if k != "func"})
    try:
        return int(args.func(args) or 0)
    except RadarnodeError as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:  # output piped into `head` and the like
        import os
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
