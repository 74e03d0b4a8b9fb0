"""radarnode: an ARS 408-21 compatible automotive radar node emulator on a CAN bus.

A synthetic road scene (``radarnode.scene``) is observed by a radar model
(``radarnode.radar``), turned into object and cluster lists
(``radarnode.perception``), encoded as ARS 408-21 CAN frames and scheduled on a
python-can bus (``radarnode.wire``), and decoded again by a consumer
(``radarnode.consumer``).
"""

from radarnode.errors import ConfigError, RadarnodeError, ScenarioError, WireError

__version__ = "0.1.0"

__all__ = ["ConfigError", "RadarnodeError", "ScenarioError", "WireError", "__version__"]
