"""dbc/radarnode_bus.dbc: one DBC for the whole bus, in step with dbc/ars408.dbc and dbc/radarnode.dbc."""

from __future__ import annotations

import subprocess
import sys

import cantools
import can
import pytest

from radarnode.wire import ids
from radarnode.wire.busdbc import bus_dbc_text, message_name
from radarnode.wire.dbc import load_database, load_own_database
from tests.conftest import ROOT, SCENARIOS

BUS = ROOT / "dbc" / "radarnode_bus.dbc"


@pytest.fixture(scope="module")
def bus_db():
    # loaded from the committed file alone, as a user's tool would
    return cantools.database.load_file(str(BUS), strict=True)


def _expected():
    """(source message, CAN ID, sensor or None) from the two source files and the ID plan, not from the generator."""
    rows = []
    for m in load_database().messages:
        sensors = [None] if m.frame_id == 0x008 else range(ids.NUM_SENSORS)
        rows += [(m, m.frame_id if s is None else ids.ars408_id(m.frame_id, s), s) for s in sensors]
    for m in load_own_database().messages:
        sensors = range(ids.NUM_SENSORS) if ids.is_sensor_message(m.frame_id) else [None]
        rows += [(m, m.frame_id if s is None else ids.own_id(m.frame_id, s), s) for s in sensors]
    return rows


def _signal_key(s):
    return (s.name, s.start, s.length, s.byte_order, s.is_signed, s.scale, s.offset, s.minimum, s.maximum,
            s.unit or "", s.is_multiplexer, s.multiplexer_ids, s.multiplexer_signal, s.raw_initial,
            {int(k): str(v) for k, v in (s.choices or {}).items()}, s.comment)


def test_the_committed_file_is_what_the_generator_writes():
    assert BUS.read_text() == bus_dbc_text(), \
        "dbc/radarnode_bus.dbc is stale: regenerate with `python -m radarnode.wire.busdbc > dbc/radarnode_bus.dbc`"


def test_every_message_of_every_sensor_with_the_source_files_signals_and_scaling(bus_db):
    expected = _expected()
    assert sorted(m.frame_id for m in bus_db.messages) == sorted(can_id for _, can_id, _ in expected)
    assert len(expected) == 20 * 8 + 1 + 2 * 8 + 2
    for src, can_id, sensor in expected:
        m = bus_db.get_message_by_frame_id(can_id)
        assert m.name == message_name(src.name, sensor)
        assert (m.length, m.cycle_time, m.senders, m.comment, m.is_extended_frame) == \
               (src.length, src.cycle_time, src.senders, src.comment, src.is_extended_frame), m.name
        assert sorted(map(_signal_key, m.signals), key=str) == sorted(map(_signal_key, src.signals), key=str), m.name


def test_ids_names_and_the_comment_document_the_plan(bus_db):
    assert bus_db.get_message_by_frame_id(0x60B).name == "Obj_1_General"
    assert bus_db.get_message_by_frame_id(0x63B).name == "Obj_1_General_S3"
    assert bus_db.get_message_by_frame_id(0x689).name == "RoadBoundary_Right_S1"
    assert bus_db.get_message_by_frame_id(0x6C1).name == "FcwStatus"
    assert len({m.name for m in bus_db.messages}) == len(bus_db.messages)
    assert "0x680 + 8*s + slot" in bus_db.buses[0].comment and "0x10*s" in bus_db.buses[0].comment


def _log(tmp_path, sensor_id: int):
    text = (SCENARIOS / "highway_cut_in.yaml").read_text().replace("sensor_id: 0", f"sensor_id: {sensor_id}")
    sc = tmp_path / f"sensor{sensor_id}.yaml"
    sc.write_text(text)
    out = tmp_path / f"sensor{sensor_id}.log"
    r = subprocess.run([sys.executable, "-m", "radarnode", "log", str(sc), "-o", str(out), "--duration", "1.5"],
                       capture_output=True, text=True, timeout=120, cwd=ROOT)
    assert r.returncode == 0, r.stderr
    return out


@pytest.mark.parametrize("sensor_id", [0, 5])
def test_a_whole_log_decodes_from_the_bus_dbc_alone(tmp_path, sensor_id, bus_db):
    out = _log(tmp_path, sensor_id)
    frames = list(can.LogReader(str(out)))
    seen = set()
    ars, own = load_database(), load_own_database()
    for msg in frames:
        m = bus_db.get_message_by_frame_id(msg.arbitration_id)         # KeyError: a frame the file lacks
        decoded = m.decode(msg.data, decode_choices=False)
        # the same values as the separate file decodes on the unshifted ID
        base = msg.arbitration_id - 0x10 * sensor_id if msg.arbitration_id < 0x680 or msg.arbitration_id >= 0x700 \
            else msg.arbitration_id - 8 * sensor_id
        src = (own if 0x680 <= msg.arbitration_id < 0x700 else ars).get_message_by_frame_id(base)
        assert decoded == src.decode(msg.data, decode_choices=False)
        assert m.name == message_name(src.name, sensor_id)
        seen.add(src.name)
    assert {"Obj_0_Status", "Obj_1_General", "Obj_2_Quality", "Obj_3_Extended", "RadarState", "VersionID",
            "SpeedInformation", "YawRateInformation", "RoadBoundary_Left", "RoadBoundary_Right"} <= seen
    # and cantools' own command line decodes every frame with that one file
    r = subprocess.run([sys.executable, "-m", "cantools", "decode", "--single-line", str(BUS)],
                       stdin=out.open(), capture_output=True, text=True, timeout=120, cwd=ROOT)
    lines = r.stdout.splitlines()
    assert r.returncode == 0 and len(lines) == len(frames)
    assert all(" :: " in line and "Unknown" not in line for line in lines)


def test_the_ecu_frames_decode_from_the_bus_dbc(bus_db):
    from radarnode.consumer.evaluate import make_ecu
    from radarnode.radar.setup import load_scenario
    sc = load_scenario(SCENARIOS / "nhtsa_lead_stopped.yaml")
    ecu = make_ecu(sc, 0.072)
    frames = ecu.frames(ecu.tick(0.0))
    assert {f.arbitration_id for f in frames} == {0x6C0, 0x6C1}
    own = load_own_database()
    for f in frames:
        assert bus_db.decode_message(f.arbitration_id, f.data) == own.decode_message(f.arbitration_id, f.data)
