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
