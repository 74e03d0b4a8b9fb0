"""One DBC for the whole bus: ``dbc/radarnode_bus.dbc``, generated from ``dbc/ars408.dbc`` and ``dbc/radarnode.dbc``.

Tools that take a single DBC (``cantools decode``/``monitor``, SavvyCAN, BusMaster, a vendor's bench tool)
decode a whole radarnode bus with it: the ARS 408-21 messages and radarnode's own of **every** sensor ID
0…7, the consumer ECU's AccStatus/FcwStatus, and the unshifted CollDetRelayCtrl 0x008, on the IDs of the
plan in :mod:`radarnode.wire.ids`. Sensor 0's messages keep their names (so the file is a drop-in for
anything written against the ARS 408 names); sensor s > 0's are named ``<name>_S<s>`` (``Obj_1_General_S3``
on 0x63B), as a DBC needs unique message names. Signals, scaling, value tables, comments, cycle times and
start values are copied unchanged from the two source files.

The two source files stay the reference; regenerate after editing either::

    python -m radarnode.wire.busdbc > dbc/radarnode_bus.dbc      # or: make dbc

``tests/test_bus_dbc.py`` fails when the committed file differs from what this module generates.
"""

from __future__ import annotations

import copy
import decimal
import math
from collections import OrderedDict
import re
import sys
from dataclasses import dataclass

import cantools
from cantools.database.can import Bus, Database
from cantools.database.can.formats.dbc import DbcSpecifics

from radarnode.wire import ars408 as P
from radarnode.wire import ids
from radarnode.wire.dbc import load_database, load_own_database

BUS_DBC = "radarnode_bus.dbc"
VERSION = "radarnode whole bus 1.0"
COMMENT = (
    "Every message on a radarnode bus in one file, generated from ars408.dbc and radarnode.dbc by "
    "radarnode.wire.busdbc (do not edit; regenerate). ARS 408-21 messages for SensorID s = 0..7 on their base ID + "
    "0x10*s (CollDetRelayCtrl 0x008 is not shifted); sensor 0's keep the ARS 408 names, sensor s > 0's are named "
    "<name>_S<s>. radarnode's own messages of sensor s on 0x680 + 8*s + slot (RoadBoundary_Left slot 0, "
    "RoadBoundary_Right slot 1), NOT shifted by 0x10*s; the consumer ECU's AccStatus 0x6C0 and FcwStatus 0x6C1, "
    "one per bus. Own messages carry an AUTOSAR E2E Profile 2 CRC (byte 0) and alive counter (low nibble of "
    "byte 1) whose Data ID names the message and the sensor, see radarnode.dbc.")


@dataclass(frozen=True)
class FrameInfo:
    """What a CAN ID on a radarnode bus carries."""

    message: cantools.database.can.Message   # as named in the bus DBC
    base_name: str                           # the name in ars408.dbc / radarnode.dbc
    sensor_id: int | None                    # None: the ECU's or the unshifted 0x008, no one sensor's


def message_name(base_name: str, sensor_id: int | None) -> str:
    """The bus DBC's name of message ``base_name`` of sensor ``sensor_id`` (unchanged for 0 and None)."""
    return base_name if not sensor_id else f"{base_name}_S{sensor_id}"


def _plan() -> list[tuple[cantools.database.can.Message, int, int | None]]:
    """(source message, CAN ID, sensor ID or None) for every message on the bus, in ID order."""
    rows = []
    for m in load_database().messages:
        if m.frame_id == P.COLL_DET_RELAY:
            rows.append((m, m.frame_id, None))
            continue
        for s in range(ids.NUM_SENSORS):
            rows.append((m, ids.ars408_id(m.frame_id, s), s))
    for m in load_own_database().messages:
        if ids.is_sensor_message(m.frame_id):
            for s in range(ids.NUM_SENSORS):
                rows.append((m, ids.own_id(m.frame_id, s), s))
        else:
            rows.append((m, m.frame_id, None))
    return sorted(rows, key=lambda r: r[1])


def build_bus_database() -> Database:
    """The whole-bus database, built from the two source DBCs and the ID plan."""
    ars, own = load_database(), load_own_database()
    messages = []
    for src, can_id, sensor in _plan():
        m = copy.deepcopy(src)
        m.frame_id = can_id
        m.name = message_name(src.name, sensor)
        messages.append(m)
    definitions = OrderedDict(ars.dbc.attribute_definitions)
    definitions.update(own.dbc.attribute_definitions)
    attributes = OrderedDict(own.dbc.attributes)
    attributes.update(ars.dbc.attributes)                    # BusType CAN, Baudrate 500000
    db = Database(messages=messages, nodes=copy.deepcopy(ars.nodes), buses=[Bus("", comment=COMMENT, baudrate=ars.buses[0].baudrate)],
                  version=VERSION, strict=True,
                  dbc_specifics=DbcSpecifics(attributes=attributes, attribute_definitions=definitions))
    db.refresh()
    return db


def bus_dbc_text() -> str:
    """The text of ``dbc/radarnode_bus.dbc``."""
    text = build_bus_database().as_dbc_string().replace("\r\n", "\n")     # the repository's line ends
    # cantools writes start values as floats ("2048.0") although GenSigStartValue is an INT attribute;
    # stricter DBC parsers reject that, so write the integers the source files hold
    return re.sub(r'^(BA_ "GenSigStartValue" SG_ \d+ \w+ )(-?\d+)\.0;$', r"\1\2;", text, flags=re.M)


def frame_table(database: Database | None = None) -> dict[int, FrameInfo]:
    """CAN ID -> :class:`FrameInfo` for every message of the bus DBC (default: the shipped file)."""
    from radarnode.wire.dbc import load_bus_database
    db = database if database is not None else load_bus_database()
    by_id = {m.frame_id: m for m in db.messages}
    return {can_id: FrameInfo(by_id[can_id], src.name, sensor) for src, can_id, sensor in _plan()
            if can_id in by_id}


def main() -> int:
    sys.stdout.write(bus_dbc_text())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())


def _decimals(x: float) -> int:
    """The decimal places of a DBC factor or offset as written (0.05 → 2, 0.2 → 1, 1 → 0)."""
    exponent = decimal.Decimal(repr(float(x))).normalize().as_tuple().exponent
    return max(0, -int(exponent))


def signal_value(sig, v: float) -> float | int:
    """A decoded signal value at the signal's resolution: rounded to the decimals of its DBC scale and offset,
    so ``scale × raw + offset`` carries no binary noise (FCW_RequiredDecel 3.65, not 3.6500000000000004);
    an int for a signal of whole steps, a float (-2.0, not -2) for a scaled one, so a field keeps its type."""
    v = float(v)
    if not math.isfinite(v):
        return v
    places = max(_decimals(sig.scale), _decimals(sig.offset))
    v = round(v, places) + 0.0
    return int(v) if places == 0 and v.is_integer() else v
