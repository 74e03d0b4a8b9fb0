"""``radarnode`` entry point: dispatch to the subcommands; ``--debug`` re-raises, otherwise ``error: …``."""

from __future__ import annotations

import argparse
import logging
import sys

from radarnode import __version__
from radarnode.cli import consume, decode, image, log, node, report, run
from radarnode.errors import RadarnodeError

SUBCOMMANDS = (run, node, consume, log, decode, image, report)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="radarnode", description="ARS 408-21 compatible radar node emulator")
    parser.add_argument("--version", action="version", version=f"radarnode {__version__}")
    parser.add_argument("--debug", action="store_true", help="show tracebacks instead of one-line errors")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output (-v info, -vv debug)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in SUBCOMMANDS:
        module.add_subparser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    level = logging.WARNING - 10 * min(args.verbose, 2)
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
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
