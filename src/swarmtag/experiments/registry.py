"""The studies shipped with swarmtag (one TOML file each in ``studies/``) and study lookup.

``STUDIES`` maps each shipped study's name to its file name; a test checks
that it and the folder agree, so a new study file is registered on purpose.
``REPRODUCED`` names those ``swarmtag reproduce`` runs by default (SPEC §6);
the others run by name (``swarmtag study run warehouse``).
``load_study`` takes a shipped study's name or the path of a user's file.
"""

from __future__ import annotations

import os
from importlib import resources
from pathlib import Path
from types import MappingProxyType
from typing import Final

from swarmtag._checks import check_path_value, check_text
from swarmtag._inputs import is_regular_file
from swarmtag.errors import StudyError
from swarmtag.experiments.spec import Study, read_study_file

__all__ = ["REPRODUCED", "STUDIES", "load_study", "study_path"]

STUDIES: Final = MappingProxyType(
    {
        "preliminary-sweep": "preliminary-sweep.toml",
        "candidate-alphas": "candidate-alphas.toml",
        "controller-selection": "controller-selection.toml",
        "physical-style": "physical-style.toml",
        "scalability": "scalability.toml",
        "warehouse": "warehouse.toml",
        "allocators": "allocators.toml",
    }
)
"""Shipped studies: SPEC §6's in the order of its table, then the others; name -> file."""
REPRODUCED: Final = (
    "preliminary-sweep",
    "candidate-alphas",
    "controller-selection",
    "physical-style",
    "scalability",
)
"""The studies of SPEC §6, which ``swarmtag reproduce`` runs by default.

The warehouse study is left out: its hall runs dozens of robots for minutes
of robot time, which would multiply the time of a quick reproduction. So is
the allocators study (docs/allocators.md), which compares other rules.
"""


def study_path(name: str) -> Path:
    """The file of the shipped study ``name``; ``StudyError`` listing the names otherwise."""
    name = check_text("name", name, error=StudyError)
    if name not in STUDIES:
        msg = f"study {name!r}: no such shipped study (shipped: {', '.join(STUDIES)})"
        raise StudyError(msg)
    folder = resources.files("swarmtag.experiments") / "studies"
    return Path(str(folder / STUDIES[name]))


def load_study(name_or_path: str | os.PathLike[str]) -> Study:
    """A shipped study by name (``"scalability"``) or a study file by path (``"my.toml"``).

    A string that names an existing file, or ends in ``.toml``, is read as a
    path; any other string must be a shipped study's name.
    """
    text = check_path_value("name_or_path", name_or_path, error=StudyError)
    if isinstance(name_or_path, os.PathLike) or text.endswith(".toml") or is_regular_file(text):
        return read_study_file(text)
    return read_study_file(study_path(text))
