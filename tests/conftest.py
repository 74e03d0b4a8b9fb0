from __future__ import annotations

import atexit
import os
import shutil
import tempfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

# the detection statistic's table cache (radarnode.radar.tables) of this test run, not the user's: every test
# process and the CLI runs it starts share it, and it starts empty
if "RADARNODE_CACHE_DIR" not in os.environ:
    os.environ["RADARNODE_CACHE_DIR"] = tempfile.mkdtemp(prefix="radarnode-test-cache-")
    atexit.register(shutil.rmtree, os.environ["RADARNODE_CACHE_DIR"], ignore_errors=True)
SHARED = ROOT.parent / "shared"
REFERENCE = SHARED / "reference" / "ars408"
SCENARIOS = ROOT / "scenarios"


@pytest.fixture(scope="session")
def reference_dir() -> Path:
    if not (REFERENCE / "ARS408_id0.dbc").is_file():
        pytest.skip(f"the reference ARS 408 files are not present at {REFERENCE} (../shared is absent)")
    return REFERENCE


@pytest.fixture(scope="session")
def reference_db(reference_dir):
    import cantools
    return cantools.database.load_file(str(reference_dir / "ARS408_id0.dbc"), encoding="latin-1", strict=False)


@pytest.fixture(scope="session")
def db():
    from radarnode.wire.dbc import load_database
    return load_database()
