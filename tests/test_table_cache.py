"""The detection statistic's table cache (radarnode.radar.tables): the same tables, loaded instead of computed."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from radarnode.dsp import detection_stats
from radarnode.radar import tables
from radarnode.radar.chain import DspConfig, detection_statistic


def _fresh(pfa: float = 1e-6):
    """A statistic built as the chain builds it, but not the chain's memoised one (no tables, no cache)."""
    cfg = DspConfig(pfa=pfa)
    stat = detection_statistic.__wrapped__(cfg, 12, 64, 64)
    stat.on_table_built = None
    for name in ("_mask_tables", "_ring_tables", "_response_tables"):
        stat.__dict__.pop(name, None)
    stat._pd_tables.clear()
    return stat


def _use(stat) -> None:
    """What a level asks of the statistic: Pd of both Swerling cases, masking, the ring kernel, the edge-cut rings."""
    stat.pd_of_snr(np.array([10.0, 20.0]), 0)
    stat.pd_of_snr(np.array([10.0, 20.0]), 1)
    stat.masking_factor(np.array([15.0]), np.array([50.0]), 1)
    stat.ring_kernel(np.array([3.25]), np.array([-7.5]))
    stat.ring_cut(np.array([0, 3, 250, 255]), 256)
    stat.response("r", np.array([0.25]))
    stat.response("d", np.array([-1.5]))


def test_a_second_run_loads_the_tables_the_first_computed_bit_for_bit(tmp_path, monkeypatch):
    monkeypatch.setenv(tables.CACHE_ENV, str(tmp_path))
    first = _fresh()
    assert tables.warm(first) == "empty"
    _use(first)
    assert len(list(tmp_path.glob("*.npz"))) == 1            # written as the tables were built
    second = _fresh()
    assert tables.warm(second) == "loaded"

    def no_computing(*args, **kwargs):
        raise AssertionError("a cached table was computed again")
    monkeypatch.setattr(detection_stats, "sf_swerling1", no_computing)
    monkeypatch.setattr(detection_stats, "sf_swerling0", no_computing)
    monkeypatch.setattr(detection_stats.DetectionStatistic, "_box_sum", no_computing)
    rho = np.linspace(-5.0, 40.0, 50)
    for swerling in (0, 1):
        assert np.array_equal(second.pd_of_snr(rho, swerling), first.pd_of_snr(rho, swerling))
    assert np.array_equal(second.masking_factor(rho, np.full(50, 80.0)), first.masking_factor(rho, np.full(50, 80.0)))
    d = np.linspace(-30.0, 30.0, 101)
    assert np.array_equal(second.ring_kernel(d, d[::-1]), first.ring_kernel(d, d[::-1]))
    monkeypatch.setattr(detection_stats, "ca_alpha", no_computing)
    edge = np.array([0, 3, 250, 255])
    assert all(np.array_equal(x, y) for x, y in zip(second.ring_cut(edge, 256), first.ring_cut(edge, 256)))
    # the windows' response tables (the lobe tests'): taken from the file, not computed (2–7 ms an axis)
    assert set(second.__dict__["_response_tables"]) == {"r", "d"}
    for axis in ("r", "d"):
        x = np.linspace(-5.0, 5.0, 777)
        assert np.array_equal(second.response(axis, x), first.response(axis, x))
    a, b = first.export_tables(), second.export_tables()
    assert a.keys() == b.keys() and all(np.array_equal(a[k], b[k]) for k in a)
    assert {"response_r", "response_d"} <= a.keys()


@pytest.mark.parametrize("bad", ["short", "beyond one", "nan"])
def test_a_response_table_not_of_this_statistic_is_refused_and_nothing_taken(bad):
    good = _fresh()
    good.response("r", np.array([0.0]))
    arrays = good.export_tables()
    table = arrays["response_r"]
    arrays["response_r"] = {"short": table[:-1], "beyond one": table * 1.5,
                            "nan": np.where(np.arange(table.size) == 3, np.nan, table)}[bad]
    fresh = _fresh()
    with pytest.raises(ValueError, match="response_r"):
        fresh.import_tables(arrays)
    assert "r" not in fresh.__dict__.get("_response_tables", {})


def test_another_configuration_has_its_own_file(tmp_path, monkeypatch):
    monkeypatch.setenv(tables.CACHE_ENV, str(tmp_path))
    one, other = _fresh(1e-6), _fresh(1e-4)
    assert tables.cache_file(one, tmp_path) != tables.cache_file(other, tmp_path)
    tables.warm(one)
    one.pd_of_snr(np.array([10.0]), 1)
    assert tables.warm(other) == "empty"


@pytest.mark.parametrize("damage", ["garbage", "truncated", "wrong shape", "nan", "one array (np.save)",
                                    "another configuration's file", "an edited table", "no key"])
def test_a_damaged_or_foreign_file_is_ignored_and_replaced(tmp_path, monkeypatch, damage):
    monkeypatch.setenv(tables.CACHE_ENV, str(tmp_path))
    good = _fresh()
    tables.warm(good)
    good.pd_of_snr(np.array([10.0]), 1)
    path = tables.cache_file(good, tmp_path)
    want = good.pd_of_snr(np.linspace(0, 30, 7), 1)
    if damage == "garbage":
        path.write_bytes(b"not a numpy file")
    elif damage == "truncated":
        path.write_bytes(path.read_bytes()[:200])
    elif damage == "one array (np.save)":
        with open(path, "wb") as f:
            np.save(f, np.arange(5.0))
    elif damage == "another configuration's file":
        other = _fresh(1e-4)
        tables.warm(other)
        other.pd_of_snr(np.array([10.0]), 1)              # a valid file of its own key …
        tables.cache_file(other, tmp_path).replace(path)  # … under this key's name
    else:
        arrays = dict(np.load(path))
        if damage == "wrong shape":
            arrays["pd1"] = arrays["pd1"][:-3]
        elif damage == "nan":
            arrays["pd1"] = np.full_like(arrays["pd1"], np.nan)
        elif damage == "an edited table":
            arrays["pd1"] = arrays["pd1"] * 0.5          # well formed, still in [0, 1]: only the digest tells
        else:
            del arrays[tables.KEY_NAME]
        np.savez(path, **arrays)
    again = _fresh()
    assert tables.warm(again) == "empty"
    assert again.export_tables() == {}                      # nothing half-taken from the bad file
    assert np.array_equal(again.pd_of_snr(np.linspace(0, 30, 7), 1), want)
    assert tables.warm(_fresh()) == "loaded"                # and the file is good again


def test_a_killed_writes_temporary_file_is_removed_by_the_next_write(tmp_path, monkeypatch):
    monkeypatch.setenv(tables.CACHE_ENV, str(tmp_path))
    stale, fresh = tmp_path / ".tables-killed.npz", tmp_path / ".tables-writing.npz"
    stale.write_bytes(b"half")
    fresh.write_bytes(b"half")
    old = time.time() - tables.STALE_TMP_S - 60
    os.utime(stale, (old, old))
    stat = _fresh()
    tables.warm(stat)
    stat.pd_of_snr(np.array([10.0]), 1)
    assert not stale.exists() and fresh.exists()            # another process may still be writing the fresh one
    assert [p.name for p in tmp_path.glob("detection-statistic-*.npz")] == [tables.cache_file(stat, tmp_path).name]


@pytest.mark.parametrize("off", ["off", "OFF", "", " ", "0", "no", "none", "False"])
def test_the_words_that_turn_it_off(monkeypatch, off):
    monkeypatch.setenv(tables.CACHE_ENV, off)
    assert tables.cache_dir() is None


def test_turned_off_nothing_is_written_and_unwritable_is_no_error(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv(tables.CACHE_ENV, "off")
    stat = _fresh()
    assert tables.warm(stat) == "off"
    _use(stat)
    assert list(tmp_path.iterdir()) == []
    blocked = tmp_path / "file"
    blocked.write_text("a file where the cache directory should be")
    monkeypatch.setenv(tables.CACHE_ENV, str(blocked / "cache"))
    stat = _fresh()
    assert tables.warm(stat) == "empty"
    _use(stat)                                               # the tables are built; writing them fails quietly
    assert not (blocked / "cache").exists()
    monkeypatch.delenv(tables.CACHE_ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert tables.cache_dir() == tmp_path / "xdg" / "radarnode"


def test_an_object_level_log_with_its_tables_cached_imports_no_heavy_scipy_module(tmp_path):
    """The start-up of what users run most: with the tables cached, `radarnode log` at the object level never needs
    scipy.special, scipy.fft or scipy.linalg (together about 0.25 s of imports)."""
    import os
    import subprocess
    import sys

    from tests.conftest import SCENARIOS
    code = ("import sys; from radarnode.cli.main import main; "
            f"main(['log', {str(SCENARIOS / 'ncap_ccrs.yaml')!r}, '--fidelity', 'object', '--duration', '1', "
            f"'-o', {str(tmp_path / 'x.blf')!r}]); "
            "print(sorted(m for m in ('scipy.special', 'scipy.fft', 'scipy.linalg', 'scipy.stats') "
            "if m in sys.modules))")
    env = {**os.environ, tables.CACHE_ENV: str(tmp_path / "cache")}
    runs = [subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True).stdout
            for _ in range(2)]
    # the first run computes its tables: the steady target's Pd table too (ars408_like's second chirp sequence, given
    # the first, averages it over a fluctuating target's draws), whose non-central χ² is scipy.stats'
    assert "scipy.special" in runs[0]
    assert runs[1].strip().endswith("[]")                       # the second loads them


def test_the_key_changes_with_the_processors_blas_kernel(monkeypatch):
    stat = _fresh()
    monkeypatch.delenv("OPENBLAS_CORETYPE", raising=False)
    here = tables.cache_key(stat)
    monkeypatch.setenv("OPENBLAS_CORETYPE", "Prescott")
    assert tables.cache_key(stat) != here
