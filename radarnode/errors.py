"""One error hierarchy for the whole package.

Every message names the input (file, field or signal), the offending value and
what would have been allowed, so a user can fix the input without reading code.
"""

from __future__ import annotations

import base64
import math
import re

#: the longest ``repr`` of a value an error message quotes (a whole file read as one string must not become the
#: message)
MAX_VALUE_REPR = 80


def _cut(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters with an ellipsis."""
    return text if len(text) <= limit else text[: limit - 1] + "…"


def short_repr(value: object, limit: int = MAX_VALUE_REPR) -> str:
    """``repr(value)``, cut to ``limit`` characters with an ellipsis, on one line."""
    return _cut(repr(value), limit)


#: a mapping key shown as it is (the loader keeps a key's text, not its quotes): no space, quote or flow character
_PLAIN_KEY = re.compile(r"[^\s'\"{}\[\],:#&*!|>%@`]+")


def yaml_repr(value: object, limit: int = MAX_VALUE_REPR) -> str:
    """:func:`short_repr` of a value read from YAML, its ``null``, ``true``, ``false``, ``.nan`` and ``.inf`` and its
    plain mapping keys spelt as the file spells them (a scenario error showed ``None`` and ``True``: an independent
    tester's finding; ``nan`` and ``{'speed_mps': …}``: noticed after it)."""
    def spell(v: object) -> str:
        if v is None or isinstance(v, bool):
            return {None: "null", True: "true", False: "false"}[v]
        if isinstance(v, float) and not math.isfinite(v):             # YAML's .nan, .inf, -.inf
            return ".nan" if math.isnan(v) else ".inf" if v > 0 else "-.inf"
        if isinstance(v, (bytes, bytearray)):                         # YAML's !!binary, as the file writes it
            return "!!binary " + (base64.b64encode(bytes(v)).decode("ascii") or '""')
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(spell(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{" + ", ".join(f"{key(k)}: {spell(x)}" for k, x in v.items()) + "}"
        return repr(v)

    def key(k: object) -> str:                                         # a plain key as the file spells it: speed_mps
        return k if isinstance(k, str) and _PLAIN_KEY.fullmatch(k) else spell(k)
    return _cut(spell(value), limit)


class RadarnodeError(Exception):
    """Base class of every error radarnode raises on purpose.

    The command line exits with status 2 for a :class:`UsageError` (the command as typed cannot run) and 1 for
    every other one (a file, a scenario, a bus, the run itself).
    """


class FieldError(RadarnodeError, ValueError):
    """A configuration value is out of its allowed domain.

    Raised by the frozen configuration dataclasses; loaders add the file name,
    the path of the field and its line and re-raise it as a ``ScenarioError``.
    """

    def __init__(self, field: str, value: object, allowed: str) -> None:
        self.field = field
        self.value = value
        self.allowed = allowed
        super().__init__(f"field '{field}': value {short_repr(value)} is not allowed; expected {allowed}")


class ScenarioError(RadarnodeError, ValueError):
    """A scenario file cannot be used as written."""


class ConfigError(RadarnodeError, ValueError):
    """A programmatic configuration (CLI option, preset override) is invalid."""


class UsageError(ConfigError):
    """The command line cannot run as typed: an option value outside what is allowed, a file name whose suffix
    names no format radarnode reads or writes, an option that needs an optional extra that is not installed.
    Found without opening any input (exit status 2)."""


class FileError(RadarnodeError):
    """A file named on the command line cannot be used: missing, a directory, unreadable, empty, damaged, of
    another format than its suffix says, or an output that cannot be written (exit status 1)."""


class BusError(RadarnodeError):
    """A CAN bus cannot be opened or used (exit status 1)."""


class WireError(RadarnodeError):
    """A DBC file or a CAN frame does not match what the protocol requires."""


class Terminated(BaseException):
    """SIGTERM (or another signal) asks the command to end: unwinds like KeyboardInterrupt does for SIGINT."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = int(signum)
