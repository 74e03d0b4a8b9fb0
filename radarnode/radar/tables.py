"""A disk cache of the detection statistic's tables, so that a run starts without computing them.

The Pd, masking and ring tables of :class:`radarnode.dsp.detection_stats.DetectionStatistic` cost about
0.2–0.4 s to compute (numerical integrals over the CFAR's training sum), once per process and chain
configuration — more than the object level spends on a minute of simulated driving. They depend only on
the statistic's inputs (:meth:`~radarnode.dsp.detection_stats.DetectionStatistic.table_key`), the code that
computes them and the numpy/scipy versions, so they are kept in one ``.npz`` file per key under
``$RADARNODE_CACHE_DIR`` (default ``$XDG_CACHE_HOME/radarnode``, else ``~/.cache/radarnode``):

- a run finds its file and loads it (a few milliseconds), bit for bit the tables it would compute (the file holds
  the key it was written for and a digest of its tables, both checked; the key includes the processor, whose BLAS
  kernels differ in the last bits);
- a table not in the file is computed when first needed, as without a cache, and the file written again with
  it (under a temporary name, then renamed, so that no process reads half a file); a malformed file is
  ignored and replaced;
- ``RADARNODE_CACHE_DIR=off`` (or empty, ``0``, ``no``, ``none``, ``false``) turns the cache off: the tables are
  then computed when needed, every run.

Deleting the directory is always safe.
"""

from __future__ import annotations

import hashlib
import logging
import os
import platform
import tempfile
import time
import zipfile
from pathlib import Path

import numpy as np

from radarnode.dsp import detection_stats

logger = logging.getLogger(__name__)

CACHE_ENV = "RADARNODE_CACHE_DIR"
#: values of RADARNODE_CACHE_DIR that turn the cache off (any case, surrounding blanks ignored)
OFF_VALUES = ("", "off", "0", "none", "no", "false")
#: a temporary file older than this is a write that was killed (SIGKILL, power loss): removed by the next write
STALE_TMP_S = 600.0
#: the names of the arrays that identify a file: the key it was written for and a digest of its tables
KEY_NAME, DIGEST_NAME = "_key", "_digest"


def cache_dir() -> Path | None:
    """Where the tables are kept; None when the cache is turned off."""
    value = os.environ.get(CACHE_ENV)
    if value is not None:
        return None if value.strip().lower() in OFF_VALUES else Path(value).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "radarnode"


def _machine() -> str:
    """The processor the tables were computed on: the BLAS kernels numpy picks differ in the last bits between
    processors (and with OPENBLAS_CORETYPE), so a cache shared between machines keeps one file per processor."""
    model = ""
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as f:
            model = next((line.split(":", 1)[1].strip() for line in f if line.startswith("model name")), "")
    except OSError:
        pass
    return f"{platform.machine()}|{model}|{os.environ.get('OPENBLAS_CORETYPE', '')}"


def cache_key(stat: detection_stats.DetectionStatistic) -> str:
    """The hex digest of everything this statistic's tables depend on: its inputs, the code that computes them,
    the library versions and the processor."""
    from radarnode import __version__
    h = hashlib.sha256(stat.table_key())
    h.update(Path(detection_stats.__file__).read_bytes())
    h.update(f"|{np.__version__}|{_scipy_version()}|{__version__}|{_machine()}".encode())
    return h.hexdigest()


def _scipy_version() -> str:
    """SciPy's version, from its installed metadata where it has some (importing SciPy for it took some 5 ms of a
    command's start, when the tables come from the cache and need nothing of SciPy)."""
    import importlib.metadata
    try:
        return importlib.metadata.version("scipy")
    except importlib.metadata.PackageNotFoundError:
        import scipy
        return scipy.__version__


def cache_file(stat: detection_stats.DetectionStatistic, directory: Path, key: str | None = None) -> Path:
    """The file of this statistic's tables (named by the first 32 digits of its :func:`cache_key`)."""
    return directory / f"detection-statistic-{(key or cache_key(stat))[:32]}.npz"


def _digest(arrays: dict[str, np.ndarray]) -> np.ndarray:
    """A SHA-256 of the tables (names, shapes, dtypes and bytes, in name order), as 32 bytes."""
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(f"{name}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return np.frombuffer(h.digest(), dtype=np.uint8)


def _read(path: Path, key: str) -> dict[str, np.ndarray]:
    """The tables of a cache file, checked: written for this key, and the tables the writer wrote. Raises
    ValueError (or OSError, zipfile's errors) for anything else: another key's file, an edited or damaged one,
    a single array saved with np.save."""
    with open(path, "rb") as f:
        data = np.load(f, allow_pickle=False)
        if not isinstance(data, np.lib.npyio.NpzFile):
            raise ValueError("not a .npz archive")
        with data:
            arrays = {name: data[name] for name in data.files}
    stored_key = arrays.pop(KEY_NAME, None)
    stored_digest = arrays.pop(DIGEST_NAME, None)
    if stored_key is None or stored_key.tobytes() != key.encode():
        raise ValueError("written for another configuration")
    if stored_digest is None or not np.array_equal(stored_digest, _digest(arrays)):
        raise ValueError("its tables are not the ones written")
    return arrays


def warm(stat: detection_stats.DetectionStatistic) -> str:
    """Give ``stat`` the tables the cache holds for it, and keep each table it builds later.

    Nothing is built ahead: a table not in the cache is computed when a level first needs it, as without a
    cache, and the file is then written again with it. Returns ``"loaded"`` (some tables came from the cache),
    ``"empty"`` (none yet: no file, or one that is not usable, which the next write replaces) or ``"off"``.
    """
    directory = cache_dir()
    if directory is None:
        return "off"
    try:
        key = cache_key(stat)
    except OSError as exc:                    # the code's own file unreadable: no key, no cache
        logger.debug("table cache off: %s", exc)
        return "off"
    path = cache_file(stat, directory, key)
    state = "empty"
    try:
        stat.import_tables(_read(path, key))
        state = "loaded"
    except FileNotFoundError:
        pass
    except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile) as exc:
        logger.info("table cache %s is not usable (%s): its tables are computed again", path, exc)
    stat.on_table_built = lambda: store(stat, path, key)
    return state


def store(stat: detection_stats.DetectionStatistic, path: Path, key: str) -> bool:
    """Write every table ``stat`` has to ``path``, with its key and digest (under a temporary name, then renamed).
    False where the directory cannot be written (a read-only home, a full disk): the run goes on without the
    cache. Temporary files that a killed write left are removed."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        now = time.time()
        for old in path.parent.glob(".tables-*.npz"):
            try:
                if now - old.stat().st_mtime > STALE_TMP_S:
                    old.unlink()
            except OSError:
                pass
        arrays = stat.export_tables()
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tables-", suffix=".npz")
        try:
            with os.fdopen(fd, "wb") as out:
                np.savez(out, **arrays, **{KEY_NAME: np.frombuffer(key.encode(), dtype=np.uint8),
                                          DIGEST_NAME: _digest(arrays)})
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
    except OSError as exc:
        logger.debug("table cache %s not written: %s", path, exc)
        return False
    return True
