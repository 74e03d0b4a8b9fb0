"""Scenario checks (radarnode.radar.checks): numbers as the user meant them, actors on top of the ego, actors the
radar can never see, motion fields that contradict the waypoints; and report's "nothing to check"."""

from __future__ import annotations

import logging
import math
import re
from pathlib import Path

import pytest

from radarnode.errors import ScenarioError
from radarnode.radar.setup import load_scenario, parse_scenario
from tests.conftest import SCENARIOS

HEAD = "name: checks\nduration_s: 10\nseed: 1\nego: {speed_mps: 20.0}\n"


def _load(tmp_path, text: str):
    p = tmp_path / "s.yaml"
    p.write_text(text)
    return p, load_scenario(p)


def _error(tmp_path, text: str) -> tuple[str, str]:
    p = tmp_path / "s.yaml"
    p.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(p)
    return str(p), str(info.value)


@pytest.mark.parametrize("path", sorted(SCENARIOS.glob("*.yaml")), ids=lambda p: p.stem)
def test_shipped_scenarios_pass_every_check_without_a_warning(path, caplog):
    with caplog.at_level(logging.WARNING, logger="radarnode.radar.checks"):
        load_scenario(path)
    assert not caplog.records, [r.getMessage() for r in caplog.records]


@pytest.mark.parametrize("written,value", [("1e-5", 1e-5), ("1E-5", 1e-5), ("2e1", 20.0), ("1.0e1", 10.0),
                                           ("+3e1", 30.0), ("-1e-3", -1e-3), (".5e1", 5.0), ("1.0e-5", 1e-5)])
def test_numbers_yaml_1_1_reads_as_strings_are_the_numbers_meant(tmp_path, written, value):
    """YAML 1.1 reads 1e-5 (no dot) and 1.0e1 (no sign in the exponent) as strings; the scenarios README writes
    `pfa: 1e-5`. They are numbers here, as in YAML 1.2, JSON and every other reader; quoted text stays text."""
    import yaml

    from radarnode.schema import Loader
    _, sc = _load(tmp_path, HEAD + f"actors:\n  - {{id: a, class: car, x_m: 50.0, rcs_dbsm: {written}}}\n")
    assert sc.actors[0].rcs_dbsm == pytest.approx(value)
    assert yaml.load(f"x: {written}", Loader=Loader)["x"] == pytest.approx(value)
    assert yaml.load(f'x: "{written}"', Loader=Loader)["x"] == written
    assert yaml.load("x: [1e3, 12, 1.5, .inf, 0x1F, abc, 1e, e5]", Loader=Loader)["x"][:5] == [1000.0, 12, 1.5,
                                                                                              float("inf"), 31]
    assert yaml.load("x: [1e, e5, 1e5x]", Loader=Loader)["x"] == ["1e", "e5", "1e5x"]


@pytest.mark.parametrize("written,value", [("0o17", 15), ("0x1F", 31), ("012", 12), ("-7", -7), (".5", 0.5),
                                           ("-.inf", float("-inf")), ("true", True), ("FALSE", False), ("~", None),
                                           ("1:30", "1:30"), ("1_000", "1_000"), ("yes", "yes"), ("off", "off"),
                                           ("0b101", "0b101"), ("2001-12-14", "2001-12-14")])
def test_plain_scalars_are_read_by_yaml_1_2s_core_schema(written, value):
    """An independent tester's finding: `duration_s: 1:30` ran 90 s (YAML 1.1's base 60), `seed: 1_0` was 10, `0o7`
    (a YAML 1.2 integer) was refused, and yes/on/off were booleans. YAML 1.2 core: what it does not read as a number,
    boolean or null is text."""
    import yaml

    from radarnode.schema import Loader
    assert yaml.load(f"x: {written}", Loader=Loader)["x"] == value
    assert type(yaml.load(f"x: {written}", Loader=Loader)["x"]) is type(value)


@pytest.mark.parametrize("field,written,hint", [
    ("duration_s", "1:30", "this is text: YAML 1.2 has no base-60 numbers, where YAML 1.1 read 90; write the "
                           "number itself"),
    ("seed", "1_0", "this is text: YAML 1.2 numbers have no '_' separators; write the digits alone")])
def test_a_number_only_yaml_1_1_read_is_refused_as_text_saying_why(tmp_path, field, written, hint):
    p, msg = _error(tmp_path, HEAD.replace(f"{field}: {'10' if field == 'duration_s' else '1'}",
                                           f"{field}: {written}"))
    assert msg.startswith(f"{p}:{2 if field == 'duration_s' else 3}: field '{field}': value '{written}' is not "
                          "allowed") and msg.endswith(f"({hint})"), msg


def test_a_yaml_1_1_boolean_is_refused_as_text_saying_why(tmp_path):
    p, msg = _error(tmp_path, HEAD + "radar: {preset: ars408_like, send_quality: yes}\n")
    assert msg == (f"{p}:5: field 'radar.send_quality': value 'yes' is not allowed; expected true or false (YAML 1.2, "
                   "which scenarios are read by, reads yes as text)")


def test_an_octal_seed_is_the_number_yaml_1_2_reads(tmp_path):
    _, sc = _load(tmp_path, HEAD.replace("seed: 1", "seed: 0o7"))
    assert sc.seed == 7


def test_the_readme_example_pfa_1e_5_loads_and_reaches_the_preset(tmp_path):
    from radarnode.radar.setup import radar_config
    _, sc = _load(tmp_path, HEAD + "radar: {preset: mimo12, overrides: {tx_power_dbm: 5, pfa: 1e-5}}\n")
    assert radar_config(sc).preset.pfa == 1e-5


def test_a_number_in_quotes_is_named_as_text(tmp_path):
    p, msg = _error(tmp_path, HEAD.replace("duration_s: 10", 'duration_s: "10"'))
    assert msg == (f"{p}:2: field 'duration_s': value '10' is not allowed; expected a number in (0, 86400] (this is "
                   "text: write the number without quotes)")


def test_a_file_that_is_not_utf8_is_named_with_the_byte(tmp_path):
    p = tmp_path / "latin1.yaml"
    p.write_bytes((HEAD + "description: Überholer\n").encode("latin-1"))
    with pytest.raises(ScenarioError, match=r"latin1\.yaml: not a scenario file: byte 0xdc at offset \d+ is not UTF-8 "
                                            r"text; expected a YAML scenario in UTF-8"):
        load_scenario(p)


def test_a_value_read_from_a_whole_file_is_cut_in_the_message(tmp_path):
    p = tmp_path / "csv.yaml"
    p.write_text("timestamp,arbitration_id,extended,remote,error,dlc,data\n" + "0.0,0x300,0,0,0,2,AAA=\n" * 500)
    with pytest.raises(ScenarioError) as info:
        load_scenario(p)
    assert len(str(info.value)) < 300 and "expected a mapping of the scenario's fields" in str(info.value)


# --- an actor on top of the ego --------------------------------------------------------------------------


@pytest.mark.parametrize("actor", [
    "{id: a, class: car, x_m: 2.0}",                        # inside the ego
    "{id: a, class: car, x_m: 5.0}",                        # its rear overlaps the ego's front (3.7 m)
    "{id: a, class: truck, x_m: -6.0}",                     # behind, reaching into the ego
    "{id: a, class: pedestrian, x_m: 1.0, y_m: 0.5}",
    "{id: a, class: car, x_m: 0.0, y_m: 1.5}",              # half a car to the side: still overlapping
])
def test_an_actor_overlapping_the_ego_at_the_start_is_an_error_naming_its_line(tmp_path, actor):
    p, msg = _error(tmp_path, HEAD + f"actors:\n  - {{id: far, class: car, x_m: 60.0}}\n  - {actor}\n")
    assert msg.startswith(f"{p}:7: actor 'a' (actors[1]) overlaps the ego at t = 0: "), msg
    assert "expected it clear of the ego, e.g. x_m >= " in msg


@pytest.mark.parametrize("actor", [
    "{id: a, class: car, x_m: 6.5}",                        # just ahead of the ego's front (3.7 m + 2.25 m)
    "{id: a, class: car, x_m: 0.0, lane: 0}",               # beside the ego, in the next lane
    "{id: a, class: car, x_m: -8.0, speed_mps: 30.0}",      # behind, catching up
])
def test_an_actor_clear_of_the_ego_is_fine(tmp_path, actor):
    _load(tmp_path, HEAD + f"actors:\n  - {actor}\n")


def test_a_waypoint_actor_overlapping_the_ego_names_its_waypoints(tmp_path):
    p, msg = _error(tmp_path, HEAD + "actors:\n  - id: w\n    class: car\n    waypoints:\n"
                                     "      - {t_s: 0.0, x_m: 1.0, y_m: 0.0}\n      - {t_s: 5.0, x_m: 100.0, y_m: 0.0}\n")
    assert msg.startswith(f"{p}:9: actor 'w' (actors[0]) overlaps the ego"), msg


@pytest.mark.parametrize("road,actor", [
    ("", "{id: g, class: guardrail, x_m: -10.0, y_m: 0.5, length_m: 30.0}"),          # along the lane, through the ego
    ("road: {lanes: 2, ego_lane: 1, curvature_1pm: 0.02}\n",                      # on a 50-m bend, through the ego
     "{id: g, class: guardrail, x_m: -5.0, y_m: -0.4, length_m: 20.0}"),
    ("", "{id: g, class: guardrail, x_m: 2.0, y_m: -4.0, heading_deg: 90, length_m: 8.0}"),   # across the lane
])
def test_a_guardrail_overlapping_the_ego_is_named_by_a_post_inside_the_ego(tmp_path, road, actor):
    """The error described a guardrail by its straight box, centred where none of its posts need be (on a bend the
    posts follow the road): it names a post, which the ego's box holds (checked here against the numbers printed)."""
    import re
    p, msg = _error(tmp_path, HEAD + road + f"actors:\n  - {actor}\n")
    assert msg.startswith(f"{p}:") and "actor 'g' (actors[0]) overlaps the ego at t = 0: its posts" in msg, msg
    m = re.search(r"include one at x (-?[\d.]+) m, y (-?[\d.]+) m, inside the ego's \(x (-?[\d.]+) to (-?[\d.]+) m, "
                  r"y (-?[\d.]+) to (-?[\d.]+) m\)", msg)
    assert m, msg
    x, y, x0, x1, y0, y1 = map(float, m.groups())
    assert x0 < x < x1 and y0 < y < y1, msg
    assert "expected every post clear of the ego" in msg


def test_an_empty_waypoint_list_is_named_not_taken_for_an_actor_at_the_origin(tmp_path):
    """``waypoints: []`` was read as no waypoints: the actor stood at x 0 and the error said it overlapped the ego
    (an independent tester's finding)."""
    p, msg = _error(tmp_path, HEAD + "actors:\n  - {id: w, class: car, waypoints: [], speed_mps: 10.0}\n")
    assert "field 'actors[0].waypoints': value [] is not allowed; expected two waypoints or more" in msg, msg
    assert "overlaps" not in msg


@pytest.mark.parametrize("section,line", [("road:", "road:"), ("ecu:", "ecu:"), ("ego:", "ego:"),
                                          ("radar:", "radar:"), ("waypoints", "    waypoints:"),
                                          ("accel", "    accel:")])
def test_a_section_left_empty_is_named_not_a_traceback(tmp_path, section, line):
    """A third tester's finding: ``road:`` (or ``ecu:``, ``ego:``, ``radar:``) with nothing after it is YAML's null,
    and crashed with an AttributeError traceback; ``waypoints:``/``accel:`` left empty gave Python's own words."""
    key = section.rstrip(":").strip()
    if section.endswith(":"):
        text = "\n".join(ln for ln in HEAD.splitlines() if not ln.startswith(key + ":")) + f"\n{line}\n"
    else:
        text = HEAD + f"actors:\n  - id: a\n    class: car\n    x_m: 40.0\n{line}\n"
    p, msg = _error(tmp_path, text)
    assert f"{key}': value null" in msg and "is not allowed" in msg and "Traceback" not in msg, msg


# --- an actor the radar can never see -------------------------------------------------------------------------


@pytest.mark.parametrize("actor,reason", [
    ("{id: far, class: car, x_m: 10000.0, speed_mps: 20.0}", "no nearer than 99"),    # 10 km, not 100 m
    ("{id: side, class: car, x_m: 30.0, y_m: -200.0}", "azimuth"),                    # beside the road
    ("{id: behind, class: car, x_m: -60.0, speed_mps: 20.0}", "azimuth 180.0°"),       # behind, never catches up
])
def test_an_actor_never_in_the_field_of_view_is_a_warning_with_its_line(tmp_path, caplog, actor, reason):
    with caplog.at_level(logging.WARNING, logger="radarnode.radar.checks"):
        p, sc = _load(tmp_path, HEAD + f"actors:\n  - {{id: lead, class: car, x_m: 60.0, speed_mps: 20.0}}\n"
                                       f"  - {actor}\n")
    assert len(sc.actors) == 2
    (record,) = caplog.records
    msg = record.getMessage()
    assert msg.startswith(f"{p}:7: actor '{sc.actors[1].id}' (actors[1]) is never in the radar's field of view "
                          "during the scenario's 10 s: preset ars408_like sees"), msg
    assert reason in msg and "so the radar never reports it" in msg


def test_an_actor_that_enters_the_field_of_view_later_is_no_warning(tmp_path, caplog):
    """"Never seen" is over the whole run: a car overtaking from behind, one the ego closes in on, a pedestrian
    stepping out from 40 m to the side."""
    with caplog.at_level(logging.WARNING, logger="radarnode.radar.checks"):
        _load(tmp_path, HEAD + "actors:\n"
                               "  - {id: overtaker, class: car, x_m: -40.0, lane: 0, speed_mps: 30.0}\n"
                               "  - {id: closing, class: car, x_m: 400.0, speed_mps: 5.0}\n"
                               "  - id: walker\n    class: pedestrian\n"
                               "    waypoints: [{t_s: 0.0, x_m: 120.0, y_m: -40.0}, {t_s: 9.0, x_m: 120.0, y_m: 0.0}]\n")
    assert not caplog.records, [r.getMessage() for r in caplog.records]


def test_the_radar_s_max_distance_counts(tmp_path, caplog):
    with caplog.at_level(logging.WARNING, logger="radarnode.radar.checks"):
        _load(tmp_path, HEAD + "radar: {max_distance_m: 100}\nactors:\n  - {id: a, class: car, x_m: 200.0, "
                               "speed_mps: 20.0}\n")
    # every sector with its range, the farthest cut at max_distance_m
    assert "sees from 0.2 m to 100 m within ±9°, to 70 m within ±45°, to 20 m within ±60°" \
        in caplog.records[0].getMessage(), caplog.records[0].getMessage()


def test_the_warning_shows_on_the_command_line(tmp_path):
    import subprocess
    import sys
    from tests.conftest import ROOT
    p = tmp_path / "far.yaml"
    p.write_text(HEAD + "actors:\n  - {id: far, class: car, x_m: 10000.0, speed_mps: 20.0}\n")
    r = subprocess.run([sys.executable, "-m", "radarnode", "run", str(p), "--fast", "--duration", "0.2", "--quiet"],
                       capture_output=True, text=True, cwd=ROOT, timeout=120)
    assert r.returncode == 0, r.stderr
    assert f"WARNING radarnode.radar.checks: {p}:6: actor 'far' (actors[0]) is never in the radar's field of view" \
        in r.stderr


# --- conflicting motion fields ----------------------------------------------------------------------------------

WAYPOINTS = "    waypoints:\n      - {t_s: 0.0, x_m: 20.0, y_m: 3.5}\n      - {t_s: 4.0, x_m: 144.0, y_m: 3.5}\n" \
            "      - {t_s: 7.0, x_m: 236.0, y_m: 0.0}\n"


@pytest.mark.parametrize("field,line,says", [
    ("speed_mps: 25.0", 8, "value 25.0 conflicts with 'actors[0].waypoints' (an actor with waypoints moves along "
                           "them: they move it at 31.00, 30.69 m/s); expected it left out, or equal"),
    ("heading_deg: 90.0", 8, "value 90.0 conflicts with 'actors[0].waypoints' (an actor with waypoints moves along "
                             "them: they head 0.0, -2.2°)"),
    ("x_m: 50.0", 8, "value 50.0 conflicts with 'actors[0].waypoints' (an actor with waypoints moves along them: it "
                     "starts at the first waypoint, x_m 20.0)"),
    ("lane: 0", 8, "value 0 conflicts with 'actors[0].waypoints' (an actor with waypoints moves along them: it starts "
                   "at the first waypoint, y_m 3.5, and lane 0 is y -3.50 m)"),
])
def test_motion_fields_that_contradict_the_waypoints_are_errors(tmp_path, field, line, says):
    key = field.split(":")[0]
    p, msg = _error(tmp_path, HEAD + f"actors:\n  - id: cutter\n    class: car\n    {field}\n" + WAYPOINTS)
    assert msg.startswith(f"{p}:{line}: field 'actors[0].{key}': {says}"), msg


@pytest.mark.parametrize("field", ["speed_mps: 31.0", "speed_mps: 30.7", "heading_deg: -2.0", "x_m: 20.0",
                                   "y_m: 3.5", "lane: 2"])
def test_motion_fields_that_agree_with_the_waypoints_are_taken_as_notes(tmp_path, field):
    """highway_cut_in.yaml gives its cutter `speed_mps: 31.0` beside waypoints at 31 m/s: what the user meant."""
    _, sc = _load(tmp_path, HEAD + f"actors:\n  - id: cutter\n    class: car\n    {field}\n" + WAYPOINTS)
    assert len(sc.actors[0].waypoints) == 3


def test_accel_beside_timed_waypoints_stays_an_error(tmp_path):
    _, msg = _error(tmp_path, HEAD + "actors:\n  - id: c\n    class: car\n    accel: [{t_s: 1.0, accel_mps2: -2.0}]\n"
                    + WAYPOINTS)
    assert "no accel with timed waypoints" in msg and "actors[0].accel" in msg


def test_checks_run_on_scenarios_built_from_text_too():
    with pytest.raises(ScenarioError, match="overlaps the ego"):
        parse_scenario(HEAD + "actors:\n  - {id: a, class: car, x_m: 1.0}\n")


# --- consume --json: Obj_4_Warning's regions ----------------------------------------------------------------------


def test_consume_json_carries_the_collision_regions_when_the_cycle_has_them():
    import json

    import numpy as np

    from radarnode.cli.consume import cycle_to_json
    from radarnode.consumer.assembler import ObjectCycle
    from radarnode.perception.types import ObjectList
    objects = ObjectList.empty(2)
    objects.id[:] = [4, 9]
    plain = json.loads(cycle_to_json(ObjectCycle(7, 1.5, objects, True, True)))
    assert "collision_regions" not in plain["objects"][0]
    warned = json.loads(cycle_to_json(ObjectCycle(7, 1.5, objects, True, True, has_warning=True,
                                                  collision_regions=np.array([0b101, 0], dtype=np.uint8))))
    assert warned["objects"][0]["collision_regions"] == [0, 2] and warned["objects"][0]["coll_det_region_bitfield"] == 5
    assert warned["objects"][1]["collision_regions"] == []


def test_heading_beside_waypoints_that_never_move_orients_the_standing_body(tmp_path):
    # an independent tester took it for ignored: a stationary path has no heading of its own, and heading_deg is the
    # body's orientation there (speed_mps other than 0 is the error, as those waypoints never move it)
    import math

    from radarnode.scene.world import Scene
    path = "waypoints: [{t_s: 0, x_m: 30.0, y_m: 0.0}, {t_s: 3, x_m: 30.0, y_m: 0.0}]"
    angles = []
    for extra in ("", ", heading_deg: 45"):
        _, sc = _load(tmp_path, HEAD + f"actors:\n  - {{id: a, class: car, {path}{extra}}}\n")
        angles.append(math.degrees(Scene(sc).view(1.0).orientation_rad[0]))
    assert angles == pytest.approx([0.0, 45.0])
    _, msg = _error(tmp_path, HEAD + f"actors:\n  - {{id: a, class: car, {path}, speed_mps: 30}}\n")
    assert "they never move it" in msg


@pytest.mark.parametrize("char,kind", [("\x07", "a control character"), ("\x1b", "a control character"),
                                       ("\x7f", "a control character")])
def test_a_character_yaml_does_not_allow_is_one_line_with_its_line(tmp_path, char, kind):
    # an independent tester's finding: PyYAML's message came on two lines, without the line number
    p, msg = _error(tmp_path, HEAD + f"description: a{char}b\n")
    assert msg == (f"{p}:5: not valid YAML: character U+{ord(char):04X} is not allowed in a YAML file ({kind}); "
                   "expected printable text") and "\n" not in msg


def test_a_gap_tolerance_without_its_settle_time_is_refused(tmp_path):
    p, msg = _error(tmp_path, HEAD + "ecu: {expect: {no_fcw: true, gap_tolerance: 0.2}}\n")
    assert msg == (f"{p}:5: field 'ecu.expect.gap_tolerance': value 0.2 is not allowed without "
                   "'ecu.expect.gap_settle_s': it is the tolerance of the time gap from that time on; expected "
                   "gap_settle_s beside it, or it left out")
    _, sc = _load(tmp_path, HEAD + "ecu: {expect: {lead: a, gap_settle_s: 5, gap_tolerance: 0.2}}\n"
                                   "actors:\n  - {id: a, class: car, x_m: 40.0, speed_mps: 20.0}\n")
    assert sc.ecu.expect.gap_tolerance == 0.2


@pytest.mark.parametrize("criterion", ["min_gap_m: 500.0", "fcw_ttc_min_s: 19.0", "fcw_before_impact_s: 1.0",
                                       "gap_settle_s: 5.0", "ttc_with_lead_decel: true"])
def test_a_criterion_measured_to_the_lead_without_a_lead_is_refused(tmp_path, criterion):
    """``min_gap_m: 500`` without ``lead`` measured no gap and passed (with the lead named, the run failed at
    37.4 m; an independent tester's finding); so did ``fcw_ttc_min_s: 19`` and ``fcw_before_impact_s``."""
    key, value = criterion.split(": ")
    p, msg = _error(tmp_path, HEAD + f"ecu: {{expect: {{{criterion}}}}}\n"
                                     "actors:\n  - {id: lead_car, class: car, x_m: 40.0, speed_mps: 20.0}\n")
    assert msg.startswith(f"{p}:5: field 'ecu.expect.{key}': value ") and "without 'ecu.expect.lead'" in msg, msg
    assert msg.endswith("expected lead naming the actor (one of 'lead_car')"), msg
    _, sc = _load(tmp_path, HEAD + f"ecu: {{expect: {{lead: lead_car, {criterion}}}}}\n"
                                   "actors:\n  - {id: lead_car, class: car, x_m: 40.0, speed_mps: 20.0}\n")
    assert sc.ecu.expect.lead == "lead_car"


# --- a speed a single-ramp radar wraps unknowingly -------------------------------------------------------------


@pytest.mark.parametrize("ego, oncoming, warned", [(100.0, 45.0, True), (100.0, 32.0, False), (80.0, 53.0, True)])
def test_a_closing_speed_beyond_acc_lrrs_single_ramp_is_a_warning_naming_the_actor(tmp_path, caplog, ego, oncoming,
                                                                                     warned):
    """acc_lrr's one chirp sequence measures ±132.7 m/s and calls every speed unambiguous, as such a sensor does;
    the schema allows an ego at 100 m/s and an oncoming car at 45 m/s (145 m/s closing), which it then reports at
    +120.3 m/s flagged 'unambiguous' (an independent tester's finding). The loader says so; 132 m/s closing is fine."""
    with caplog.at_level(logging.WARNING, logger="radarnode.radar.checks"):
        p, sc = _load(tmp_path, f"name: fast\nduration_s: 2\nseed: 1\nego: {{speed_mps: {ego}}}\n"
                                "radar: {preset: acc_lrr}\nactors:\n"
                                f"  - {{id: oncoming, class: car, x_m: 150.0, y_m: 3.5, speed_mps: {oncoming}, "
                                "heading_deg: 180}\n")
    msgs = [r.getMessage() for r in caplog.records]
    if not warned:
        assert not msgs, msgs
        return
    (msg,) = msgs
    import re
    closing = ego + oncoming
    assert msg.startswith(f"{p}:7: actor 'oncoming' (actors[0]) reaches a range rate of "), msg
    rate = float(re.search(r"range rate of ([-+0-9.]+) m/s", msg).group(1))
    alias = float(re.search(r"reported at ([-+0-9.]+) m/s", msg).group(1))
    assert rate == pytest.approx(-closing, abs=0.2) and alias == pytest.approx(2 * 132.66 - closing, abs=0.2), msg
    assert "beyond the ±132.7 m/s that preset acc_lrr's single chirp sequence measures" in msg, msg
    assert "AmbigState 3" in msg, msg


@pytest.mark.parametrize("x1, t1, ok", [(179.0, 1.0, True), (180.0, 1.0, True), (181.0, 1.0, False),
                                        (330.0, 1.0, False), (30.0 + 1e-10, 1e-12, True), (60.0, 1e-12, False)])
def test_timed_waypoints_faster_than_an_actor_may_move_are_refused(tmp_path, x1, t1, ok):
    """speed_mps is held to 150 m/s, but timed waypoints 2000 m apart in 1 s (or 30 m in 1e-12 s) passed silently
    (an independent tester's finding): each leg's speed is held to the same limit, just below, at, above it and at
    twice it; the error names the waypoint, its values and the speed."""
    text = HEAD + (f"actors:\n  - {{id: a, class: car, waypoints: [{{t_s: 0, x_m: 30, y_m: 0}}, "
                   f"{{t_s: {t1!r}, x_m: {x1!r}, y_m: 0}}]}}\n")
    if ok:
        _load(tmp_path, text)
        return
    _, msg = _error(tmp_path, text)
    assert "actors[0].waypoints[1]" in msg and "at most 150 m/s" in msg and "m/s here" in msg, msg


def test_a_section_written_as_null_is_named_as_written(tmp_path):
    """``guardrails: null`` — the scenarios README said null meant none, the loader refuses null for every section
    (``road:`` with nothing after it is YAML's null, not the defaults): the README now says to leave the field out,
    and the message no longer says there was nothing after the key when null was written."""
    _, msg = _error(tmp_path, HEAD + "road: {guardrails: null}\n")
    assert "road.guardrails': value null (written as null, ~ or nothing after 'guardrails:')" in msg, msg
    readme = (Path(__file__).resolve().parents[1] / "scenarios" / "README.md").read_text()
    assert "null for none" not in readme


@pytest.mark.parametrize("name", ["''", "' x'", "'x '", '"a\\nb"', '"a\\tb"', '"a\\rb"', "x" * 201])
def test_a_name_that_would_break_a_table_row_or_name_no_file_is_refused(tmp_path, name):
    # a newline in the name broke report's Markdown row and wrote a plot file with a line break in its name; an empty
    # name wrote '_seed1.png' (an independent tester's findings)
    where, message = _error(tmp_path, f"name: {name}\nduration_s: 1\nseed: 1\n")
    assert message.startswith(f"{where}:1: field 'name'") and "is not allowed" in message, message
    assert "1 to 200 printable characters (no line break or tab)" in message


@pytest.mark.parametrize("name", ["x" * 200, "follow_R+250_v30", "crossing_10_5.5_20", "'Übergang 2 km'", "'a.b'",
                                  "'ego 30 m/s, truck left, dv +2 m/s'", "'../../x'", "'a|b'", "'..'"])
def test_names_up_to_the_limit_with_any_printable_character_are_taken(tmp_path, name):
    # a name is free text ('m/s' in benchmarks/side_pass.py's): report makes its plot files' names safe itself
    _, sc = _load(tmp_path, f"name: {name}\nduration_s: 1\nseed: 1\n")
    assert sc.name == name.strip("'")


# --- range bins that end inside the field of view -------------------------------------------------------------


@pytest.mark.parametrize("overrides, end, says", [
    ("{num_samples: 64}", "57.28 m", "anti-alias filter"),                       # real sampling: the target vanishes
    ("{num_samples: 64, complex_sampling: true}", "114.56 m", "folds"),          # complex: it folds
    ("{num_samples: 256}", "229.12 m", "anti-alias filter"),                     # inside 250 m too
    ("{num_samples: 512}", None, None)])                                          # the preset's own: 458 m
def test_range_bins_that_end_inside_the_field_of_view_are_a_warning(tmp_path, caplog, overrides, end, says):
    """ars408_like with 64 samples a chirp sees to 250 m, but its bins end at 57.28 m (real sampling): a target at
    80 m was not reported at any level and nothing was said (a tester's finding)."""
    with caplog.at_level(logging.WARNING, logger="radarnode.radar.checks"):
        p, _ = _load(tmp_path, HEAD + f"radar: {{preset: ars408_like, overrides: {overrides}}}\nactors: []\n")
    msgs = [r.getMessage() for r in caplog.records]
    if end is None:
        assert not msgs, msgs
        return
    (msg,) = msgs
    assert msg.startswith(f"{p}:5: preset ars408_like's range bins end at {end}") and says in msg, msg


LOOP = ("name: loop\nduration_s: {dur}\nseed: 1\nradar: {{preset: ars408_like}}\nego: {{speed_mps: 10.0}}\n"
        "road: {{lanes: 2, lane_width_m: 3.5, ego_lane: 0, {road}}}\n"
        "actors:\n  - {{id: lead, class: car, x_m: {x}, lane: 0, speed_mps: {v}}}\n")
R20 = "curvature_1pm: 0.05"        # the tightest road allowed: a loop is 2π·20 = 125.7 m long


@pytest.mark.parametrize("x_m,refused", [(115.0, False), (126.5, True), (150.0, True), (251.0, True), (-150.0, True)])
def test_an_actor_placed_a_loop_or_more_along_a_circular_road_is_refused(tmp_path, x_m, refused):
    # a lead 150 m along a road of radius 20 m (a loop of 125.7 m) stood 24 m along it, where the radar saw it, while
    # report measured 150 m: a wrong verdict, and nothing said (a tester's finding). Under a loop (115 m: the actor
    # 10 m behind the ego in the world; at 124–125 m it sits on the ego, which the overlap check refuses) is a scene;
    # from a loop on it is refused, ahead or behind (126.5 m: just past the ego's rear axle, refused as a loop)
    text = LOOP.format(dur=3, road=R20, x=x_m, v=10.0)
    if not refused:
        _load(tmp_path, text)
        return
    path, msg = _error(tmp_path, text)
    side = "ahead of" if x_m > 0 else "behind"
    assert msg.startswith(f"{path}:8: actor 'lead' (actors[0]) starts {abs(x_m):.1f} m {side} the ego along a road "
                          "of radius 20 m (road.curvature_1pm), whose lane is a loop of 125.7 m: it stands where "
                          f"{abs(x_m) % (2 * math.pi * 20):.1f} m would put it"), msg
    assert msg.endswith(f"report would measure its gap as {abs(x_m):.1f} m; expected it less than one loop from the "
                        "ego (125.7 m)"), msg


def test_only_the_placement_on_a_circular_road_is_checked_not_the_run():
    """The first form of the check followed the scenario's plan over the whole run and the road's net turn: it
    refused a closed-loop follow round a 250-m bend for ten minutes (the plan drove the ego through the lead), a car
    parked beside a test track, an oncoming car, an unwinding clothoid, and missed an S-bend that crosses itself and
    a lead lapping a closed-loop ego (an independent tester's findings). Where the actors go depends on the run; the
    placement alone is checked, on a circular road alone."""
    # driving round a loop for a minute, the lead near (nearly five loops); a lead that pulls away past a loop
    parse_scenario(LOOP.format(dur=60, road=R20, x=30.0, v=10.0))
    parse_scenario(LOOP.format(dur=5, road=R20, x=100.0, v=20.0))
    # a road of segments turning 395° between the ego and the lead: not checked
    segments = "segments: [{type: straight, length_m: 50}, {type: arc, length_m: 300, curvature_1pm: 0.03}]"
    parse_scenario(LOOP.format(dur=3, road=segments, x=280.0, v=10.0))
    # the shipped bend follow made ten minutes long: a scene
    text = (SCENARIOS / "acc_follow_bend_250.yaml").read_text()
    parse_scenario(re.sub(r"duration_s: [\d.]+", "duration_s: 600", text))


@pytest.mark.parametrize("preset,cycle,refused", [("mimo12", 0.0076, True), ("mimo12", 0.0077, False),
                                                  ("ars408_like", 0.0137, True), ("ars408_like", 0.0138, False),
                                                  ("ars408_like", 0.005, True)])
def test_a_cycle_shorter_than_the_radars_frame_is_refused(tmp_path, preset, cycle, refused):
    # a 5-ms cycle ran on presets whose frame of chirps takes 7.7 ms (mimo12) and 13.7 ms (ars408_like's two
    # sequences, 6.4 + 7.3 ms): a timing no radar has (an independent tester's finding)
    text = f"{HEAD}radar: {{preset: {preset}}}\ncycle_period_s: {cycle}\nactors: []\n"
    if not refused:
        _load(tmp_path, text)
        return
    path, msg = _error(tmp_path, text)
    frame = {"mimo12": "7.6907 ms", "ars408_like": "13.7143 ms (its two chirp sequences, 6.400 + 7.314 ms)"}[preset]
    need = {"mimo12": "0.007691", "ars408_like": "0.013715"}[preset]
    assert msg.startswith(f"{path}:6: field 'cycle_period_s': value {cycle} is not allowed: one frame of the {preset} "
                          f"radar's chirps takes {frame}, longer than the cycle of {cycle * 1e3:g} ms"), msg
    # the least cycle suggested is taken (rounded up: 0.01371 was suggested for a 13.7143-ms frame, and refused)
    assert msg.endswith(f"expected at least {need}"), msg
    _load(tmp_path, text.replace(f"cycle_period_s: {cycle}", f"cycle_period_s: {need}"))


def test_overrides_that_make_the_frame_longer_than_the_cycle_are_refused(tmp_path):
    path, msg = _error(tmp_path, f"{HEAD}radar: {{preset: mimo12, overrides: {{num_chirps: 8192}}}}\nactors: []\n")
    assert msg.startswith(f"{path}:5: field 'radar.overrides': one frame of the mimo12 radar's chirps takes 246.1019 "
                          "ms, longer than the cycle of 72 ms that reports it; expected fewer chirps"), msg
    # several radars: the field that set the cycle (the first radar's overrides), or the radar whose overrides
    # lengthened its frame, with the cycle's source (the error named a radar's overrides it did not have: a tester's
    # finding)
    path, msg = _error(tmp_path, HEAD + "radars:\n  - {preset: srr_corner, sensor_id: 0, overrides: {cycle_period_s: "
                                        "0.01}}\n  - {preset: ars408_like, sensor_id: 1}\nactors: []\n")
    assert msg.startswith(f"{path}:6: field 'radars[0].overrides': cycle_period_s 0.01 is not allowed here: one frame "
                          "of the ars408_like radar's chirps takes 13.7143 ms"), msg
    path, msg = _error(tmp_path, HEAD + "radars:\n  - {preset: srr_corner, sensor_id: 0}\n  - {preset: ars408_like, "
                                        "sensor_id: 1, overrides: {num_chirps: 512}}\nactors: []\n")
    assert msg.startswith(f"{path}:7: field 'radars[1].overrides': one frame of the ars408_like radar's chirps takes "
                          "54.8571 ms") and "(the cycle of srr_corner, radars[0], the scenario's)" in msg, msg
    # … and a cycle long enough takes them
    _load(tmp_path, f"{HEAD}radar: {{preset: mimo12, overrides: {{num_chirps: 8192}}}}\ncycle_period_s: 0.25\n"
                    "actors: []\n")


@pytest.mark.parametrize("actor_id,ok", [("", False), (" lead", False), ("lead\tcar", False), ("x" * 201, False),
                                         ("lead car", True), ("x" * 200, True)])
def test_an_actor_id_is_a_name(tmp_path, actor_id, ok):
    # an empty id was taken (a tester's finding): warnings, errors and ecu.expect then named an actor ''
    text = HEAD + f"actors:\n  - {{id: {actor_id!r}, class: car, x_m: 40.0, speed_mps: 20.0}}\n".replace("'", '"')
    if ok:
        _load(tmp_path, text)
        return
    path, msg = _error(tmp_path, text)
    assert msg.startswith(f"{path}:6: field 'actors[0].id'") and "printable characters" in msg, msg
