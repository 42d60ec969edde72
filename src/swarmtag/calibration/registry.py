"""The target files shipped with swarmtag (one TOML file each in ``targets/``) and their lookup.

``TARGETS`` maps each shipped baseline's name to its file name; a test checks
that it and the folder agree, so a new target file is registered on purpose.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Final

from swarmtag._checks import check_text
from swarmtag.errors import CalibrationError

__all__ = ["TARGETS", "target_path"]

TARGETS: Final = MappingProxyType(
    {
        "paper-sim": "paper-sim.toml",
        "lab": "lab.toml",
    }
)
"""Shipped baselines (SPEC §4.6): name -> file in ``targets/``."""


def target_path(name: str) -> Path:
    """The file of the shipped baseline ``name``; ``CalibrationError`` listing the names otherwise.

    >>> target_path("lab").name
    'lab.toml'
    """
    check_text("--baseline", name, error=CalibrationError)
    if name not in TARGETS:
        msg = f"--baseline {name!r}: not a file, and no shipped baseline has that name "
        msg += f"(shipped: {', '.join(TARGETS)})"
        raise CalibrationError(msg)
    return Path(str(resources.files("swarmtag.calibration") / "targets" / TARGETS[name]))
