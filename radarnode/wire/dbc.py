"""Locate and load the project's DBC files (compiled once, cached)."""

from __future__ import annotations

import functools
from importlib import resources
from pathlib import Path

import cantools

from radarnode.errors import WireError

ARS408_DBC = "ars408.dbc"
RADARNODE_DBC = "radarnode.dbc"
BUS_DBC = "radarnode_bus.dbc"       # generated from the two above by radarnode.wire.busdbc


def dbc_path(name: str = ARS408_DBC) -> Path:
    """Path of a DBC shipped with radarnode (wheel: ``radarnode/_dbc``; source checkout: ``dbc/``)."""
    packaged = resources.files("radarnode") / "_dbc" / name
    if packaged.is_file():
        return Path(str(packaged))
    source = Path(__file__).resolve().parents[2] / "dbc" / name
    if source.is_file():
        return source
    raise WireError(f"DBC file {name!r} not found in the installed package nor in {source.parent}")


@functools.lru_cache(maxsize=None)
def load_database(path: str | None = None) -> cantools.database.can.Database:
    """Load (once) the ARS 408 DBC, or any DBC file given by path."""
    p = Path(path) if path is not None else dbc_path()
    return _load(str(p))


@functools.lru_cache(maxsize=None)
def load_own_database() -> cantools.database.can.Database:
    """radarnode's own outputs (``dbc/radarnode.dbc``): road boundaries, E2E protected."""
    return _load(str(dbc_path(RADARNODE_DBC)))


def _load(p: str) -> cantools.database.can.Database:
    try:
        return cantools.database.load_file(str(p), strict=True)
    except (OSError, cantools.database.UnsupportedDatabaseFormatError) as exc:
        raise WireError(f"{p}: cannot load DBC: {exc}") from None


@functools.lru_cache(maxsize=None)
def load_bus_database() -> cantools.database.can.Database:
    """The whole bus in one file (``dbc/radarnode_bus.dbc``): every sensor ID's ARS 408 and own messages and
    the ECU's, generated from the two files above (:mod:`radarnode.wire.busdbc`)."""
    return _load(str(dbc_path(BUS_DBC)))
