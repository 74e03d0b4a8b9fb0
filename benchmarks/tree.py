"""``--root DIR`` for the benchmarks that time another version of radarnode with the same script.

``python benchmarks/X.py --root DIR`` (DIR e.g. from ``git archive REV | tar -x -C DIR``) imports radarnode from DIR;
without it, from this checkout. The scenarios are always this checkout's (``ROOT``).
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def use_tree(argv: list[str] = sys.argv) -> Path:
    """Put the tree radarnode is to be imported from first on sys.path — ``--root DIR`` from ``argv``, read before
    radarnode is imported, else this checkout — and return it."""
    tree = Path(argv[argv.index("--root") + 1]).resolve() if "--root" in argv[:-1] else ROOT
    sys.path.insert(0, str(tree))
    return tree
