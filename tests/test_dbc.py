"""Our dbc/ars408.dbc against the public ARS 408-21 DBC, and our vectorised codec against cantools."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from radarnode.wire import ars408 as P
from radarnode.wire.codec import MessageCodec

NODE_SENDS = [P.RADAR_STATE, P.VERSION_ID, P.OBJ_STATUS, P.OBJ_GENERAL, P.OBJ_QUALITY, P.OBJ_EXTENDED,
              P.CLUSTER_STATUS, P.CLUSTER_GENERAL, P.CLUSTER_QUALITY]
ALL_IDS = [0x200, 0x201, 0x202, 0x203, 0x204, 0x300, 0x301, 0x400, 0x401, 0x402, 0x408, 0x600, 0x701, 0x702,
           0x60A, 0x60B, 0x60C, 0x60D, 0x60E, 0x700, 0x008]


def _raw_values(message, data, mux=None):
    """Draw raw integers for every signal (of one multiplexer value) and scale them to physical values."""
    values = {}
    for sig in message.signals:
        if sig.multiplexer_ids is not None and mux not in sig.multiplexer_ids:
            continue
        if sig.is_multiplexer:
            values[sig.name] = mux
            continue
        lo = round((sig.minimum - sig.offset) / sig.scale) if sig.minimum is not None else 0
        hi = round((sig.maximum - sig.offset) / sig.scale) if sig.maximum is not None else (1 << sig.length) - 1
        raw = data.draw(st.integers(min_value=max(lo, 0), max_value=min(hi, (1 << sig.length) - 1)), label=sig.name)
        values[sig.name] = raw * sig.scale + sig.offset
    return values


def test_every_message_of_the_design_is_present(db):
    ids = sorted(m.frame_id for m in db.messages)
    assert ids == sorted(ALL_IDS)
    for fid in NODE_SENDS:
        assert db.get_message_by_frame_id(fid).cycle_time in (72, 1000)


def test_cycle_times_and_value_tables(db):
    assert db.get_message_by_frame_id(P.RADAR_STATE).cycle_time == 1000
    assert db.get_message_by_frame_id(P.OBJ_GENERAL).cycle_time == 72
    dyn = db.get_message_by_frame_id(P.OBJ_GENERAL).get_signal_by_name("Obj_DynProp")
    assert str(dyn.choices[2]) == "Oncoming" and str(dyn.choices[7]) == "Stopped"
    cls = db.get_message_by_frame_id(P.OBJ_EXTENDED).get_signal_by_name("Obj_Class")
    assert [str(cls.choices[i]) for i in range(7)] == ["Point", "Car", "Truck", "Pedestrian", "Motorcycle",
                                                       "Bicycle", "Wide"]


@pytest.mark.parametrize("frame_id", ALL_IDS, ids=hex)
@settings(max_examples=150, deadline=None)
@given(data=st.data())
def test_identical_bytes_under_our_dbc_and_the_reference(frame_id, data, db, reference_db):
    ours = db.get_message_by_frame_id(frame_id)
    ref = reference_db.get_message_by_frame_id(frame_id)
    assert ours.length == ref.length
    if ours.is_multiplexed():
        mux_signal = next(s for s in ours.signals if s.is_multiplexer)
        ref_muxes = {m for s in ref.signals if s.multiplexer_ids for m in s.multiplexer_ids}
        mux = data.draw(st.sampled_from(sorted(ref_muxes)), label="mux")
        values = _raw_values(ours, data, mux)
        values[mux_signal.name] = mux
        # the reference may lack a signal of this multiplexer value: compare what both define
        ref_names = {s.name for s in ref.signals if s.multiplexer_ids is None or mux in s.multiplexer_ids}
        values = {k: v for k, v in values.items() if k in ref_names}
        ours_bytes = ours.encode(values, strict=False)
    else:
        values = _raw_values(ours, data)
        ours_bytes = ours.encode(values, strict=True)
    assert ref.encode(values, strict=False) == ours_bytes


@pytest.mark.parametrize("frame_id", [i for i in ALL_IDS if i not in (0x202, 0x204)], ids=hex)
@settings(max_examples=100, deadline=None)
@given(data=st.data())
def test_vectorised_codec_matches_cantools(frame_id, data, db):
    message = db.get_message_by_frame_id(frame_id)
    codec = MessageCodec(message)
    rows = [_raw_values(message, data) for _ in range(data.draw(st.integers(1, 5), label="n"))]
    columns = {name: np.array([r[name] for r in rows]) for name in codec.signal_names}
    payload = codec.encode(columns)
    for k, row in enumerate(rows):
        assert payload[k].tobytes() == message.encode(row, strict=True)
    decoded = codec.decode(payload)
    for name in codec.signal_names:
        np.testing.assert_allclose(decoded[name], columns[name], atol=1e-9)
    assert sum(codec.saturated.values()) == 0


def test_codec_saturates_and_counts(db):
    codec = MessageCodec(db.get_message_by_frame_id(P.OBJ_GENERAL))
    values = {"Obj_ID": [1, 2], "Obj_DistLong": [2000.0, 10.0], "Obj_DistLat": [0.0, -300.0],
              "Obj_VrelLong": [0.0, 0.0], "Obj_VrelLat": [0.0, 0.0], "Obj_DynProp": [0, 0], "Obj_RCS": [0.0, 0.0]}
    out = codec.decode(codec.encode(values))
    assert out["Obj_DistLong"][0] == pytest.approx(1138.2)
    assert out["Obj_DistLat"][1] == pytest.approx(-204.6)
    assert codec.saturated == {"Obj_DistLong": 1, "Obj_DistLat": 1}


def test_codec_rejects_nan_with_the_signal_name(db):
    from radarnode.errors import WireError
    codec = MessageCodec(db.get_message_by_frame_id(P.OBJ_STATUS))
    with pytest.raises(WireError, match="Obj_MeasCounter.*NaN"):
        codec.encode({"Obj_NofObjects": 1, "Obj_MeasCounter": float("nan"), "Obj_InterfaceVersion": 1})


def test_sensor_id_shift():
    assert P.shifted(P.OBJ_GENERAL, 3) == 0x63B
    assert P.shifted(P.COLL_DET_RELAY, 5) == 0x008
    assert P.unshifted(0x63B) == (0x60B, 3)
    assert P.unshifted(0x711) == (0x701, 1)


def test_sigma_codes_round_trip_to_the_table_bounds():
    sig = np.array([0.001, 0.0051, 0.1, 1.0, 9.9, 50.0, np.nan])
    code = P.sigma_to_code(sig)
    assert code.tolist() == [0, 1, 12, 21, 30, 30, 31]
    bound = P.code_to_sigma(code)
    finite = np.isfinite(sig[:5]) & (sig[:5] > 0.005)
    assert np.all(bound[:5][finite] > sig[:5][finite])   # the code's bound is above σ ...
    assert np.all(P.code_to_sigma(code[:5][finite] - 1) <= sig[:5][finite])   # ... and the next lower is not


@pytest.mark.parametrize("frame_id", [i for i in ALL_IDS if i not in (0x202, 0x204)], ids=hex)
@settings(max_examples=60, deadline=None)
@given(data=st.data())
def test_one_frame_of_scalars_is_encoded_as_the_columns_are(frame_id, data, db):
    """Scalars take the one-frame path (Python numbers); its bytes and saturation counts are the columns' for
    any value: inside the range, beyond it, and exactly half an LSB between two raw values (ties to even)."""
    message = db.get_message_by_frame_id(frame_id)
    scalar, column = MessageCodec(message), MessageCodec(message)
    values = {}
    for f in scalar.fields:
        span = f.maximum - f.minimum
        kind = data.draw(st.sampled_from(["inside", "beyond", "tie"]), label=f.name)
        if kind == "tie":
            raw = data.draw(st.integers(0, max(int(round(span / f.scale)) - 1, 0)), label=f"{f.name} raw")
            values[f.name] = f.offset + (raw + 0.5) * f.scale
        else:
            lo, hi = (f.minimum, f.maximum) if kind == "inside" else (f.minimum - span, f.maximum + span)
            values[f.name] = data.draw(st.floats(lo, hi, allow_nan=False), label=f.name)
    one = scalar.encode(values)
    assert one.shape == (1, message.length) and one.dtype == np.uint8
    assert one.tobytes() == column.encode({k: np.array([v]) for k, v in values.items()}).tobytes()
    assert scalar.saturated == column.saturated
