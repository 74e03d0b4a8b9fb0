"""One-way data flow: ``radarnode/dsp`` holds pure array functions and imports no other stage."""

from __future__ import annotations

import ast
from pathlib import Path

import radarnode

PACKAGE = Path(radarnode.__file__).parent
LATER_STAGES = ("radarnode.radar", "radarnode.scene", "radarnode.perception", "radarnode.wire",
                "radarnode.consumer", "radarnode.cli")


def _imports(path: Path) -> set[str]:
    names = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module:
            names.add(node.module)
    return names


def test_dsp_imports_nothing_but_numpy_scipy_and_the_errors():
    files = sorted((PACKAGE / "dsp").glob("*.py"))
    assert len(files) >= 7
    for path in files:
        bad = {m for m in _imports(path) if m.startswith(LATER_STAGES)}
        assert not bad, f"{path.name} imports {sorted(bad)}"


def test_scene_imports_neither_the_radar_nor_the_dsp():
    files = sorted((PACKAGE / "scene").glob("*.py"))
    assert len(files) >= 4
    for path in files:
        bad = {m for m in _imports(path) if m.startswith(LATER_STAGES[:1] + ("radarnode.dsp",) + LATER_STAGES[2:])
               and not m.startswith("radarnode.scene")}
        assert not bad, f"{path.name} imports {sorted(bad)}"


def test_radar_options_in_a_scenario_are_checked_by_the_radar_with_file_and_line(tmp_path):
    from radarnode.errors import ScenarioError
    from radarnode.radar.setup import load_scenario
    from radarnode.scene.scenario import read_scenario

    p = tmp_path / "bad.yaml"
    p.write_text("name: x\nduration_s: 1\nseed: 0\nradar:\n  preset: mimo12\n  overrides: {pfa: 2.0}\n"
                 "signal:\n  dsp: {cfar: median}\n")
    sc = read_scenario(p)  # the scene alone is fine
    assert sc.signal == {"dsp": {"cfar": "median"}}
    try:
        load_scenario(p)
    except ScenarioError as exc:
        msg = str(exc)
    else:
        raise AssertionError("an impossible pfa override was accepted")
    assert msg.startswith(f"{p}:6: field 'radar.overrides.pfa': value 2.0"), msg
    p.write_text("name: x\nduration_s: 1\nseed: 0\nsignal:\n  dsp: {cfar: median}\n")
    try:
        load_scenario(p)
    except ScenarioError as exc:
        msg = str(exc)
    assert msg.startswith(f"{p}:5: field 'signal.dsp.cfar': value 'median'"), msg
    p.write_text("name: x\nduration_s: 1\nseed: 0\nradar: {preset: nope}\n")
    try:
        load_scenario(p)
    except ScenarioError as exc:
        msg = str(exc)
    assert "field 'radar.preset': value 'nope'" in msg and "mimo12" in msg, msg
