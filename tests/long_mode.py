"""The suite's long mode: ``SWARMTAG_LONG_TESTS=1`` runs the simulation-heavy tests at full length.

The normal suite runs the backend-equivalence, software-in-the-loop,
tag-cache and allocator comparisons on runs shortened to where every
behaviour they compare has happened (each of those tests asserts that its
runs show those events, so a run made too short fails instead of comparing
nothing). The long mode gives them the lengths they had before the suite
was sized for two cores (docs/performance.md, "The test suite")::

    SWARMTAG_LONG_TESTS=1 pytest -q -p no:cacheprovider tests/sim/fast tests/robot/test_sil.py
"""

from __future__ import annotations

import os
from typing import Final

LONG: Final = os.environ.get("SWARMTAG_LONG_TESTS", "") not in ("", "0")
"""Whether ``SWARMTAG_LONG_TESTS`` asks for the long mode (any value but empty or ``0``)."""


def length(normal: int, long: int) -> int:
    """``long`` in the long mode, else ``normal`` (ticks, runs or examples)."""
    return long if LONG else normal
