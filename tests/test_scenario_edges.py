"""Scenarios at the edges of what the schema allows, end to end through the commands (an independent tester's
findings, session 28): the slowest radar cycle, runs shorter than one cycle, structures overhead at the start,
waypoints with the heading they have, expectation windows beyond the run."""

from __future__ import annotations

import re

import pytest

from tests.helpers import cli

SLOW = """name: slow
duration_s: 30.0
seed: 1
cycle_period_s: {period}
ego: {{speed_mps: 20.0}}
ecu: {{expect: {{no_fcw: true}}}}
actors:
  - {{id: a, class: car, x_m: 40, lane: 1, speed_mps: 20}}
"""


@pytest.mark.parametrize("period", [4.99, 5.0, 5.01, 10.0])
def test_the_slowest_radar_cycles_the_schema_allows_run_log_and_report(tmp_path, capsys, period):
    """The ECU's time guard took a step longer than 5 s for a discontinuity and refused a radar cycle above it: a cycle
    of 5.01–10 s (the schema allows 0.005–10 s) ended `run`, `log --ecu` and `report` in a traceback. Now every
    cycle is tracked: the ECU, fed one decoded cycle every period, skips none as a jump in time."""
    from radarnode.consumer.assembler import CycleAssembler
    from radarnode.consumer.evaluate import make_ecu
    from radarnode.radar.setup import load_scenario
    from radarnode.wire.node import EgoMotionSender, RadarNode
    from radarnode.wire.runner import SimulatedClock, run_node
    path = tmp_path / "slow.yaml"
    path.write_text(SLOW.format(period=period))
    for argv in (["run", path, "--fast", "--quiet"], ["log", path, "--ecu", "-o", tmp_path / "slow.blf"],
                 ["report", path, "--seeds", "1", "--workers", "1"]):
        rc, out, err = cli(capsys, *argv)
        assert rc == 0 and "Traceback" not in err, (argv, err[-400:])
    sc = load_scenario(path)
    node, asm = RadarNode(sc), CycleAssembler()
    ecu, decisions = make_ecu(sc, node.period_s), []

    def on_cycle(out) -> None:            # the ECU on what the assembler decoded of the cycle
        ecu.set_ego(out.t_s, asm.ego_speed_mps, asm.ego_yaw_rate_dps)
        decisions.extend(ecu.on_cycle(out.t_s, c) for c in asm.drain())

    run_node(node, clock=SimulatedClock(), sinks=[asm.on_message_received], vehicle=EgoMotionSender(node.scene),
             duration_s=6 * node.period_s, on_cycle=on_cycle)
    assert len(decisions) == 6 and all(d is not None for d in decisions), decisions
    assert ecu.stats.time_jumps == 0 and ecu.stats.rejected_time == 0, ecu.stats


def _write(tmp_path, name: str, head: str, actors: str) -> object:
    path = tmp_path / f"{name}.yaml"
    path.write_text(f"name: {name}\nseed: 1\n{head}\nego: {{speed_mps: 20.0}}\nactors:\n{actors}\n")
    return path


CAR = "  - {id: a, class: car, x_m: 40, lane: 1, speed_mps: 20}"


@pytest.mark.parametrize("duration, cycles", [(0.05, 0), (0.0719, 0), (0.072, 1), (0.073, 1), (0.144, 2)])
def test_a_run_shorter_than_one_cycle_is_refused_naming_duration(tmp_path, capsys, duration, cycles):
    """ars408_like's 72-ms cycle: a scenario of 0.05 s ran no cycle, `log` wrote an empty file (status 0) and `report`
    passed it. Now just below one cycle the file is refused naming duration_s, the cycle and where it comes from (no
    output file left); at one cycle and above the run writes that many cycles."""
    path = _write(tmp_path, "short", f"duration_s: {duration}\necu: {{expect: {{no_fcw: true}}}}", CAR)
    out = tmp_path / "short.blf"
    rc, _, err = cli(capsys, "log", path, "-o", out)
    if cycles == 0:
        assert rc == 1 and f"short.yaml:3: field 'duration_s': value {duration}" in err, err
        assert "shorter than one radar cycle (0.072 s, the ars408_like preset's cycle)" in err and not out.exists()
        rc, _, err = cli(capsys, "report", path, "--seeds", "1", "--workers", "1")
        assert rc != 0 and "field 'duration_s'" in err, err
    else:
        assert rc == 0 and f"in {cycles} complete cycles" in err, err


@pytest.mark.parametrize("settle, ok", [(4.896, True), (4.9, False), (10.0, False)])
def test_a_gap_settle_time_after_the_runs_last_cycle_is_refused(tmp_path, capsys, settle, ok):
    """A 5-s run's last cycle is at 4.896 s: a time gap checked from 10 s failed with "off by up to inf s"; now from
    just after the last cycle on it is an error naming the field and the last cycle's time."""
    path = _write(tmp_path, "settle", "duration_s: 5.0\necu: {acc_enabled: true, expect: {lead: a, gap_settle_s: "
                  f"{settle}, gap_tolerance: 0.5}}}}", CAR)
    rc, out, err = cli(capsys, "report", path, "--seeds", "1", "--workers", "1")
    if ok:
        assert "field 'ecu.expect.gap_settle_s'" not in err and "Traceback" not in err, err
    else:
        assert rc != 0 and f"field 'ecu.expect.gap_settle_s': value {settle}" in err and "4.896 s" in err, err


@pytest.mark.parametrize("duration, ok", [(1.5, False), (2.0, False), (2.1, True)])
def test_acc_follows_needs_a_run_past_its_window(tmp_path, capsys, duration, ok):
    """`acc_follows` is checked from 2 s where no gap_settle_s is given: a 1.5-s run failed with "ACC followed a in 0 %
    of the cycles". A run whose last cycle comes before 2 s is refused naming the field (2.0 s: its last cycle is at
    1.944 s); one beyond it is checked."""
    path = _write(tmp_path, "follows", f"duration_s: {duration}\necu: {{acc_enabled: true, expect: "
                  "{acc_follows: a}}", CAR)
    rc, out, err = cli(capsys, "report", path, "--seeds", "1", "--workers", "1")
    if ok:
        assert "field 'ecu.expect.acc_follows'" not in err and "Traceback" not in err, err
    else:
        assert rc != 0 and "field 'ecu.expect.acc_follows': value 'a'" in err and "checked from 2 s" in err, err


@pytest.mark.parametrize("actor, ok", [
    ("{id: br, class: bridge, x_m: 0.0}", True),                          # a deck 5 m up: the run starts under it
    ("{id: g, class: gantry, x_m: 1.0}", True),
    ("{id: s, class: sign, x_m: 2.0, z_m: 5.0, height_m: 1.0}", True),
    ("{id: s, class: sign, x_m: 2.0, z_m: 2.01, height_m: 1.0}", True),    # just above, at and just below EGO_HEIGHT_M
    ("{id: s, class: sign, x_m: 2.0, z_m: 2.0, height_m: 1.0}", True),
    ("{id: s, class: sign, x_m: 2.0, z_m: 1.99, height_m: 1.0}", False),
    ("{id: s, class: sign, x_m: 2.0, height_m: 1.0}", False),              # on the ground
    ("{id: c, class: car, x_m: 2.0, lane: 1}", False),
])
def test_structures_overhead_may_stand_over_the_ego_at_the_start(tmp_path, capsys, actor, ok):
    """A bridge, a gantry or a sign 5 m up at x 0–2 m was refused as "overlaps the ego at t = 0": a run could not start
    under a bridge. An actor whose bottom is 2 m (EGO_HEIGHT_M) or more above the road now passes over the ego; one
    lower, or on the ground, on top of it is still an error."""
    from radarnode.scene.world import EGO_HEIGHT_M
    assert EGO_HEIGHT_M == 2.0
    path = _write(tmp_path, "over", "duration_s: 1.0", f"  - {actor}")
    rc, _, err = cli(capsys, "log", path, "-o", tmp_path / "over.blf")
    assert (rc == 0) == ok and (("overlaps the ego at t = 0" in err) != ok), err


def test_a_refused_max_distance_gets_its_error_and_no_warning_computed_from_it(tmp_path, capsys):
    """`radar.max_distance_m: 4` printed a warning that the car is never in view (computed from the 4 m it then
    refused) before the error; now the error alone, and both READMEs give the same range (10 m up)."""
    from tests.conftest import ROOT
    path = _write(tmp_path, "maxd", "duration_s: 1.0\nradar: {preset: ars408_like, max_distance_m: 4}", CAR)
    rc, _, err = cli(capsys, "log", path, "-o", tmp_path / "maxd.blf")
    assert rc == 1 and "field 'radar.max_distance_m': value 4" in err and "never" not in err, err
    assert "10…the preset's max range" in (ROOT / "scenarios" / "README.md").read_text()


@pytest.mark.parametrize("line, field, shown", [
    ("ego: {speed_mps: null}", "ego.speed_mps", "null"),
    ("ego: {speed_mps: ~}", "ego.speed_mps", "null"),
    ("ego: {speed_mps: true}", "ego.speed_mps", "true"),
    ("ego: {speed_mps: False}", "ego.speed_mps", "false"),
    ("road: {lanes: [1, null, true]}", "road.lanes", "[1, null, true]"),
    ("radar: {preset: null}", "radar.preset", "null"),
    ("ego: {speed_mps: .nan}", "ego.speed_mps", ".nan"),
    ("ego: {speed_mps: .inf}", "ego.speed_mps", ".inf"),
    ("ego: {speed_mps: -.Inf}", "ego.speed_mps", "-.inf"),
    ("road: {lanes: [2, .NaN]}", "road.lanes", "[2, .nan]"),
    ("road: {lanes: {count: 2, wide: .inf}}", "road.lanes", "{count: 2, wide: .inf}"),
    ("ego: {speed_mps: !!binary aGVsbG8=}", "ego.speed_mps", "!!binary aGVsbG8="),
    ("ego: {speed_mps: !!binary ''}", "ego.speed_mps", '!!binary ""')])
def test_a_refused_yaml_null_or_boolean_is_shown_as_the_file_spells_it(tmp_path, capsys, line, field, shown):
    """A scenario error showed YAML's null and true as Python's None and True (an independent tester's finding), and
    .nan, .inf and a mapping's keys as Python's nan, inf and 'count'."""
    path = tmp_path / "s.yaml"
    path.write_text(f"name: s\nduration_s: 2\nseed: 1\n{line}\n")
    rc, _, err = cli(capsys, "run", path)
    assert rc == 1 and f"s.yaml:4: field '{field}': value {shown} is not allowed" in err, err
    assert "None" not in err and "True" not in err and "False" not in err, err
    assert not re.search(r"value (-?inf|nan)\b", err) and "'count'" not in err and "b'" not in err, err


@pytest.mark.parametrize("line, where, what", [("? [a, b]\n: 1", "the top level", "a list"),
                                               ("ego: {[1]: 2}", "field 'ego'", "a list"),
                                               ("road: {{lanes: 2}: 1}", "field 'road'", "a mapping")])
def test_a_list_or_mapping_as_a_key_is_an_error_not_a_traceback(tmp_path, capsys, line, where, what):
    """``{[a, b]: 1}`` ended in ``TypeError: unhashable type: 'list'`` from inside the loader (an independent tester's
    finding)."""
    path = tmp_path / "s.yaml"
    path.write_text(f"name: s\nduration_s: 2\nseed: 1\n{line}\n")
    rc, _, err = cli(capsys, "run", path)
    assert rc == 1 and f"s.yaml:4: a key of {where} is {what}; expected a field name" in err, err
    assert "Traceback" not in err


def test_a_mapping_key_is_shown_as_the_file_spells_it(tmp_path, capsys):
    """A refused mapping's keys kept Python's quotes where they were not identifiers: {'x-y': 1, '2': 3}."""
    path = tmp_path / "s.yaml"
    path.write_text("name: s\nduration_s: 2\nseed: 1\nroad: {lanes: {x-y: 1, 2: 3, a.b: .nan}}\n")
    rc, _, err = cli(capsys, "run", path)
    assert rc == 1 and "value {x-y: 1, 2: 3, a.b: .nan} is not allowed" in err, err


@pytest.mark.parametrize("line, shown, where", [('"": 3', "''", "at the top level"),
                                                ("? |\n  block\n: 3", r"'block\n'", "at the top level"),
                                                ('ego: {speed_mps: 10, "a b": 1}', "'a b'", "in field 'ego'"),
                                                # a terminal's escape and an invisible character, escaped
                                                ('ego: {speed_mps: 10, "a\\ex": 1}', r"'a\x1bx'", "in field 'ego'"),
                                                ('ego: {speed_mps: 10, "\\u200bspeed_mps": 1}', r"'\u200bspeed_mps'",
                                                 "in field 'ego'")])
def test_an_unknown_key_that_is_not_a_plain_name_is_shown_on_one_line_with_its_line(tmp_path, capsys, line, shown,
                                                                                      where):
    """A block scalar as a key put its line break into the message (two lines), an empty top-level key's error
    named no line, and a key's terminal escape (ESC) reached the terminal raw (a tester's findings)."""
    path = tmp_path / "s.yaml"
    path.write_text(f"name: s\nduration_s: 2\nseed: 1\n{line}\n")
    rc, _, err = cli(capsys, "run", path)
    assert rc == 1 and re.search(rf"s\.yaml:[4-6]: unknown field {re.escape(shown)} \({where}\); allowed here: ", err), err
    assert len(err.strip().splitlines()) == 1 and "\x1b" not in err and "\u200b" not in err, err


def test_report_seeds_1_is_seed_1_and_without_seeds_the_scenarios_own(tmp_path, capsys):
    """An independent tester's finding: `report --seeds 1` ran the scenario's own seed (7 here), so a report of one
    seed and one of several did not share a run, and a CI test case changed its name with N. Now `--seeds N` is
    seeds 1…N; without it the scenario runs once with its own seed."""
    path = tmp_path / "own.yaml"
    path.write_text("name: own\nseed: 7\nduration_s: 0.5\nego: {speed_mps: 20.0}\necu: {expect: {no_fcw: true}}\n"
                    "actors:\n" + CAR + "\n")
    seeds = {}
    for argv in ((), ("--seeds", "1"), ("--seeds", "2")):
        rc, out, err = cli(capsys, "report", path, "--workers", "1", *argv)
        assert rc == 0, err
        seeds[argv] = [int(m) for m in re.findall(r"^\| own \| (\d+) \|", out, flags=re.M)]
    assert seeds == {(): [7], ("--seeds", "1"): [1], ("--seeds", "2"): [1, 2]}, seeds


def test_report_tells_two_files_of_one_scenario_name_apart(tmp_path, capsys):
    """An independent tester's finding: two scenario files of one `name:` gave two table blocks and two JUnit suites
    and test cases of the same name, told apart only by a property. Now each is labelled with its file."""
    import xml.etree.ElementTree as ET
    paths = []
    for d in ("a", "b"):
        (tmp_path / d).mkdir()
        path = tmp_path / d / "same.yaml"
        path.write_text("name: same\nseed: 1\nduration_s: 0.5\nego: {speed_mps: 20.0}\necu: {expect: {no_fcw: true}}\n"
                        "actors:\n" + CAR + "\n")
        paths.append(path)
    junit = tmp_path / "j.xml"
    rc, out, err = cli(capsys, "report", *paths, "--workers", "1", "--junit", junit)
    assert rc == 0, err
    rows = re.findall(r"^\| (same[^|]*) \| 1 \|", out, flags=re.M)
    assert len(rows) == 2 and len(set(rows)) == 2 and all(str(p) in r for p, r in zip(paths, rows)), rows
    names = [s.get("name") for s in ET.parse(junit).getroot()]
    cases = [c.get("name") for s in ET.parse(junit).getroot() for c in s.iter("testcase")]
    assert len(set(names)) == 2 and len(set(cases)) == 2, (names, cases)
