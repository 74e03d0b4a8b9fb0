"""`radarnode log --ecu`: the consumer ECU's decisions in the log, next to the radar's frames (issue 10 item 9)."""

from __future__ import annotations

import re
from pathlib import Path

import can

from radarnode.cli.main import main
from radarnode.consumer.evaluate import simulate
from radarnode.radar.setup import load_scenario
from radarnode.wire.dbc import load_own_database
from radarnode.wire.ids import FCW_STATUS

SCENARIO = Path(__file__).resolve().parents[1] / "scenarios" / "nhtsa_lead_stopped.yaml"


def test_the_logged_ecu_frames_carry_the_warning_when_report_sees_it(tmp_path, capsys):
    out = tmp_path / "run.blf"
    assert main(["log", str(SCENARIO), "-o", str(out), "--ecu"]) == 0
    # the summary's count is every frame in the file, the ECU's too (it left them out: an independent tester)
    wrote = re.search(r"wrote (\d+) frames in", capsys.readouterr().err)
    assert wrote and int(wrote.group(1)) == sum(1 for _ in can.LogReader(str(out)))
    db = load_own_database()
    fcw = [(m.timestamp, db.decode_message(m.arbitration_id, m.data, decode_choices=False))
           for m in can.LogReader(str(out))
           if m.arbitration_id == FCW_STATUS]
    sc = load_scenario(SCENARIO)
    assert len(fcw) == sc.num_cycles
    first = next(t for t, s in fcw if s["FCW_WarningLevel"] == 2)
    r = simulate(sc)
    assert abs(first - r.warning_time_s) < 1e-6           # the same decision, stamped when it was produced
    # without --ecu the log holds no ECU frame
    plain = tmp_path / "plain.blf"
    assert main(["log", str(SCENARIO), "-o", str(plain)]) == 0
    assert not any(m.arbitration_id == FCW_STATUS for m in can.LogReader(str(plain)))


def test_the_ecu_decides_once_a_cycle_at_every_level_on_a_cluster_radar_too(tmp_path):
    """highway_mimo12's radar sends cluster lists: the logged ECU decides on each of them (one AccStatus and one
    FcwStatus a cycle, as on an object radar), not on its radar-unavailable timer; at every fidelity level."""
    from radarnode.wire.ids import ACC_STATUS
    scenario = SCENARIO.parent / "highway_mimo12.yaml"
    for fidelity in ("object", "detection", "signal"):
        out = tmp_path / f"{fidelity}.blf"
        assert main(["log", str(scenario), "--fidelity", fidelity, "--duration", "0.5", "--ecu", "-o", str(out)]) == 0
        frames = list(can.LogReader(str(out)))
        n_cycles = sum(m.arbitration_id == 0x600 for m in frames)          # Cluster_0_Status of sensor 0
        acc = [m for m in frames if m.arbitration_id == ACC_STATUS]
        fcw = [m for m in frames if m.arbitration_id == FCW_STATUS]
        assert n_cycles == 6 and len(acc) == len(fcw) == n_cycles, (fidelity, n_cycles, len(acc), len(fcw))
        db = load_own_database()
        assert any(db.decode_message(ACC_STATUS, bytes(m.data))["ACC_Fault"] == 0 for m in acc), fidelity
