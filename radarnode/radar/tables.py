"""A disk cache of the detection statistic's tables, so that a run starts without computing them.

The Pd, masking and ring tables of :class:`radarnode.dsp.detection_stats.DetectionStatistic` cost about
0.2–0.4 s to compute (numerical integrals over the CFAR's training sum), once per process and chain
configuration — more than the object level spends on a minute of simulated driving. They depend only on
the statistic's inputs (:meth:`~radarnode.dsp.detection_stats.DetectionStatistic.table_key`), the code that
computes them and the numpy/scipy versions, so they are kept in one ``.npz`` file per key under
``$RADARNODE_CACHE_DIR`` (default ``$XDG_CACHE_HOME/radarnode``, else ``~/.cache/radarnode``):

- a run finds its file and loads it (a few milliseconds), bit for bit the tables it would compute;
- a table not in the file is computed when first needed, as without a cache, and the file written again with
  it (under a temporary name, then renamed, so that no process reads half a file); a malformed file is
  ignored and replaced;
- ``RADARNODE_CACHE_DIR=off`` (or empty) turns the cache off: the tables are then computed lazily, as needed.

Deleting the directory is always safe.
"""

from __future__ import annotations

import hashlib
import logging
import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np

from radarnode.dsp import detection_stats

logger = logging.getLogger(__name__)

CACHE_ENV = "RADARNODE_CACHE_DIR"


def cache_dir() -> Path | None:
    """Where the tables are kept; None when the cache is turned off."""
    value = os.environ.get(CACHE_ENV)
    if value is not None:
        return None if value.strip().lower() in ("", "off", "0", "none") else Path(value).expanduser()
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "radarnode"


def cache_file(stat: detection_stats.DetectionStatistic, directory: Path) -> Path:
    """The file of this statistic's tables: its key, the computing code and the library versions, hashed."""
    import scipy

    from radarnode import __version__
    h = hashlib.sha256(stat.table_key())
    h.update(Path(detection_stats.__file__).read_bytes())
    h.update(f"|{np.__version__}|{scipy.__version__}|{__version__}".encode())
    return directory / f"detection-statistic-{h.hexdigest()[:32]}.npz"


def warm(stat: detection_stats.DetectionStatistic) -> str:
    """Give ``stat`` the tables the cache holds for it, and keep each table it builds later.

    Nothing is built ahead: a table not in the cache is computed when a level first needs it, as without a
    cache, and the file is then written again with it. Returns ``"loaded"`` (some tables came from the cache),
    ``"empty"`` (none yet) or ``"off"``.
    """
    directory = cache_dir()
    if directory is None:
        return "off"
    try:
        path = cache_file(stat, directory)
    except OSError as exc:                    # the code's own file unreadable: no key, no cache
        logger.debug("table cache off: %s", exc)
        return "off"
    state = "empty"
    try:
        with np.load(path, allow_pickle=False) as f:
            stat.import_tables({name: f[name] for name in f.files})
        state = "loaded"
    except FileNotFoundError:
        pass
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as exc:
        logger.info("table cache %s is not usable (%s): its tables are computed again", path, exc)
    stat.on_table_built = lambda: store(stat, path)
    return state


def store(stat: detection_stats.DetectionStatistic, path: Path) -> bool:
    """Write every table ``stat`` has to ``path`` (under a temporary name, then renamed). False where the
    directory cannot be written (a read-only home, a full disk): the run goes on without the cache."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tables-", suffix=".npz")
        try:
            with os.fdopen(fd, "wb") as out:
                np.savez(out, **stat.export_tables())
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
    except OSError as exc:
        logger.debug("table cache %s not written: %s", path, exc)
        return False
    return True
