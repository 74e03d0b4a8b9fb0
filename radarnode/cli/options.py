"""Checked option types for argparse, and the parser that prints one ``error: …`` line.

Every numeric option is parsed by one of these types, so a value outside its domain (text, NaN, ±inf, out of
range) is refused while the command line is parsed, before any file is read: one line naming the option, the
value as typed and what is allowed, exit status 2 (a usage error).
"""

from __future__ import annotations

import argparse
import re
import sys

from radarnode import validate
from radarnode.errors import FieldError
from radarnode.wire.bus import bitrate_option


class Parser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one ``error: …`` line (exit status 2), like radarnode's own errors.

    argparse prints the usage and ``prog: error: argument --x: …``; here it is ``error: option --x: value … is not
    allowed; expected …`` (``argument X`` for a positional), so every usage error of every subcommand looks the
    same. ``--help`` shows the usage. Options are never abbreviated: ``report --seed 7`` would otherwise be taken
    for ``--seeds 7`` and run seeds 1–7 instead of seed 7.
    """

    def __init__(self, *args, **kwargs) -> None:
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def parse_args(self, args=None, namespace=None):  # noqa: D102 - argparse's; the words kept for _did_you_mean
        self._words = self._glued(list(sys.argv[1:] if args is None else args))
        return super().parse_args(self._words, namespace)

    def _glued(self, words: list[str]) -> list[str]:
        """``--duration -1e3`` as ``--duration=-1e3``: argparse takes a value that begins with ``-`` and is not a
        plain negative number (``-1e3``, ``-inf``, ``-nan``, ``-5,0,5``, ``-10:20:2``) for an option, and says only
        "expected one argument"; glued to its option, the value reaches the option's own check, which names it and
        what is allowed."""
        takes_value = {o for p in self._parsers() for a in p._actions if a.option_strings and a.nargs is None
                       and a.const is None and not isinstance(a, argparse._HelpAction) for o in a.option_strings}
        out: list[str] = []
        i = 0
        while i < len(words):
            w = words[i]
            if w in takes_value and i + 1 < len(words) and _negative_value(words[i + 1]):
                out.append(f"{w}={words[i + 1]}")
                i += 2
                continue
            out.append(w)
            i += 1
        return out

    def _parsers(self) -> list[argparse.ArgumentParser]:
        """This parser and its subcommands'."""
        out = [self]
        for action in self._actions:
            if isinstance(action, argparse._SubParsersAction):
                out += list(action.choices.values())
        return out

    def error(self, message: str) -> None:  # noqa: D102 - argparse's hook
        if message.startswith("argument -"):
            message = "option " + message[len("argument "):]
        if message.startswith("unrecognized arguments: "):
            message += self._did_you_mean(message[len("unrecognized arguments: "):].split())
        choice = re.search(r"invalid choice: (.*) \(choose from (.*)\)$", message)
        if choice:
            allowed = ", ".join(c.strip().strip("'") for c in choice.group(2).split(","))
            message = message[:choice.start()] + f"value {choice.group(1)} is not allowed; expected one of {allowed}"
        print(f"error: {message}", file=sys.stderr)
        sys.exit(2)

    def _did_you_mean(self, words: list[str]) -> str:
        """``; did you mean --seeds?`` for an unknown option that begins one of this parser's options or is close to
        one (options are not abbreviated: an abbreviation is refused, with the option it would have been)."""
        import difflib
        parsers = [self]
        for action in self._actions:        # argparse reports a subcommand's unknown options from the main parser
            if isinstance(action, argparse._SubParsersAction):
                parsers += [p for name, p in action.choices.items() if name in getattr(self, "_words", ())][:1]
        # (each option once: the global ones are on the main parser and, under the same names, on each subcommand)
        known = list(dict.fromkeys(o for p in parsers for a in p._actions for o in a.option_strings
                                   if o.startswith("--")))
        for w in words:
            if w.startswith("--"):
                name = w.split("=", 1)[0]
                near = [o for o in known if o.startswith(name)] or difflib.get_close_matches(name, known, n=1)
                if near:
                    return f"; did you mean {' or '.join(near[:3])}?"
        return ""


def _negative_value(text: str) -> bool:
    """Whether ``text`` is a value that begins with ``-`` — a number (``-1e3``, ``-inf``, ``-nan``) or a list or range
    that starts with one (``-5,0,5``, ``-10:20:2``) — rather than an option (no option of radarnode's is ``-`` and a
    digit)."""
    return text.startswith("-") and (_is_number(text) or re.match(r"-\.?\d", text) is not None)


def _is_number(text: str) -> bool:
    """Whether ``text`` reads as a number (``-1e3``, ``-inf``, ``-nan`` too)."""
    try:
        float(text)
    except ValueError:
        return False
    return True


def _shown(text: str) -> str:
    """The value as typed: a number bare, anything else quoted (so an empty or odd string is visible)."""
    try:
        float(text)
    except ValueError:
        return repr(text)
    return text.strip()


def number(*, lo: float | None = None, hi: float | None = None, lo_open: bool = False, hi_open: bool = False):
    """An argparse type: a finite float in the interval, else an error naming the value and the interval."""
    def parse(text: str) -> float:
        try:
            value = float(text) if "_" not in text else text     # (Python reads 0.1_5 as 0.15: a typo here)
        except ValueError:
            value = text
        try:
            return validate.number("", value, lo=lo, hi=hi, lo_open=lo_open, hi_open=hi_open)
        except FieldError as exc:
            raise argparse.ArgumentTypeError(f"value {_shown(text)} is not allowed; expected {exc.allowed}") from None
    parse.__name__ = "number"
    return parse


def integer(*, lo: int | None = None, hi: int | None = None):
    """An argparse type: an integer (decimal) in [lo, hi]."""
    def parse(text: str) -> int:
        try:
            # (ASCII digits only: int() reads '١' and '１' as 1)
            value: object = int(text.strip(), 10) if "_" not in text and text.isascii() else text
        except ValueError:
            value = text
        try:
            return validate.integer("", value, lo=lo, hi=hi)
        except FieldError as exc:
            raise argparse.ArgumentTypeError(f"value {_shown(text)} is not allowed; expected {exc.allowed}") from None
    parse.__name__ = "integer"
    return parse


def name(what: str, max_len: int = 64):
    """An argparse type: a non-empty name without spaces or control characters (it goes into log lines)."""
    def parse(text: str) -> str:
        if not text or len(text) > max_len or any(c.isspace() or not c.isprintable() for c in text):
            raise argparse.ArgumentTypeError(f"value {text!r} is not allowed; expected {what}: 1 to {max_len} "
                                             "printable characters without spaces")
        return text
    parse.__name__ = "name"
    return parse


#: bit rates a CAN controller runs at (python-can passes the value to the interface): one check for every -b
BITRATE = bitrate_option
#: a scenario seed, as the scenario's own ``seed`` field
SEED = integer(lo=0, hi=2**63 - 1)
#: a scenario duration override, as the scenario's own ``duration_s`` field
DURATION = number(lo=0.0, hi=86_400.0, lo_open=True)
#: a timestamp to start a log at (s since the epoch: up to the year 2286; 0 for scenario time)
START_TIME = number(lo=0.0, hi=1e10)
SENSOR_ID = integer(lo=0, hi=7)
PORT = integer(lo=0, hi=65535)
COUNT = integer(lo=0)
POSITIVE_COUNT = integer(lo=1)
#: seconds of silence before ``consume`` gives up (0: never); at most a day
TIMEOUT = number(lo=0.0, hi=86_400.0)
#: the signal chain's angle estimators (radarnode.dsp.doa.DOA_METHODS; written out so that the parser does not import
#: the DSP at start-up — tests/test_cli.py checks the two agree)
DOA_CHOICES = ("fft", "capon", "esprit", "music", "root_music", "unitary_music")
