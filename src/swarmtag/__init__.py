"""swarmtag: urgency-aware robot-swarm intralogistics.

Smart BLE tags on carriers broadcast how urgent their item is; robots hear
them and each decides on its own which carrier to fetch. This package holds
the tag protocol (``swarmtag.tag``), the selection policies
(``swarmtag.policy``) and the tools built on them.
"""

from __future__ import annotations

from importlib import metadata as _metadata

try:
    __version__ = _metadata.version("swarmtag")
except _metadata.PackageNotFoundError:  # pragma: no cover - source tree, not installed
    __version__ = "0+unknown"

__all__ = ["__version__"]
