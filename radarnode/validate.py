"""Small value checks shared by the configuration dataclasses.

They reject what numpy would silently accept (NaN, infinities, booleans used as
numbers, strings) and raise :class:`FieldError` naming the field, the value
and what is allowed.
"""

from __future__ import annotations

import math
from collections.abc import Collection

from radarnode.errors import FieldError


def number(field: str, value: object, *, lo: float | None = None, hi: float | None = None,
           lo_open: bool = False, hi_open: bool = False) -> float:
    """Return ``value`` as a finite float inside the given interval, or raise."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise FieldError(field, value, f"a number{_interval(lo, hi, lo_open, hi_open)}")
    v = float(value)
    if not math.isfinite(v):
        raise FieldError(field, value, f"a finite number{_interval(lo, hi, lo_open, hi_open)}")
    bad_lo = lo is not None and (v <= lo if lo_open else v < lo)
    bad_hi = hi is not None and (v >= hi if hi_open else v > hi)
    if bad_lo or bad_hi:
        raise FieldError(field, value, f"a number{_interval(lo, hi, lo_open, hi_open)}")
    return v


def integer(field: str, value: object, *, lo: int | None = None, hi: int | None = None) -> int:
    """Return ``value`` as an int inside ``[lo, hi]``, or raise."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise FieldError(field, value, f"an integer{_interval(lo, hi, False, False)}")
    if (lo is not None and value < lo) or (hi is not None and value > hi):
        raise FieldError(field, value, f"an integer{_interval(lo, hi, False, False)}")
    return value


def boolean(field: str, value: object) -> bool:
    if not isinstance(value, bool):
        yaml11 = isinstance(value, str) and value.lower() in ("yes", "no", "on", "off", "y", "n")
        raise FieldError(field, value, "true or false" + (" (YAML 1.2, which scenarios are read by, reads "
                                                          f"{value} as text)" if yaml11 else ""))
    return value


def choice(field: str, value: object, allowed: Collection[str]) -> str:
    if not isinstance(value, str) or value not in allowed:
        raise FieldError(field, value, "one of " + ", ".join(sorted(allowed)))
    return value


def text(field: str, value: object) -> str:
    if not isinstance(value, str):
        raise FieldError(field, value, "a string")
    return value


#: the longest name :func:`name` takes (a file name holds 255 bytes; ``report --plots`` writes NAME_seedN.png)
NAME_MAX_CHARS = 200


def name(field: str, value: object, names: str = "report's rows and plot files") -> str:
    """A name that also titles table rows and plot files (``names``: what it names, for the error): 1 to
    NAME_MAX_CHARS printable characters (no line break or tab) and no space at either end."""
    text(field, value)
    if not 0 < len(value) <= NAME_MAX_CHARS or value != value.strip() or not value.isprintable():
        raise FieldError(field, value, f"1 to {NAME_MAX_CHARS} printable characters (no line break or tab) and no "
                                       f"space at either end (it names {names})")
    return value


def _interval(lo: float | None, hi: float | None, lo_open: bool, hi_open: bool) -> str:
    if lo is None and hi is None:
        return ""
    if hi is None:
        return f" {'>' if lo_open else '>='} {_num(lo)}"
    if lo is None:
        return f" {'<' if hi_open else '<='} {_num(hi)}"
    return f" in {'(' if lo_open else '['}{_num(lo)}, {_num(hi)}{')' if hi_open else ']'}"


def _num(v: float) -> str:
    """A bound as a user writes it: whole numbers in full (1000000, not 1e+06; an integer bound always, 2**63 − 1 as
    9223372036854775807, not 9.22337e+18), others short."""
    if isinstance(v, int) and not isinstance(v, bool):
        return str(v)
    return str(int(v)) if float(v).is_integer() and abs(v) < 1e15 else f"{v:g}"
