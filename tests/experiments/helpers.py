"""Small studies for the experiments tests: a few short runs, so each test takes seconds."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from swarmtag.experiments import Study

SMALL: dict[str, Any] = {
    "name": "small",
    "conditions": ["proximity", "urgency:alpha=0.7"],
    "runs": 6,
    "quick_runs": 2,
    "ticks": 150,
    "chunk_runs": 2,
    "resamples": 50,
    "profile": "base",  # the machinery is under test, not the model: the fast base world
    "scenario": {"robots": 3, "carriers": 7},
}

SMALL_TOML = """\
name = "small"
conditions = ["proximity", "urgency:alpha=0.7"]
runs = 6
quick_runs = 2
ticks = 150
chunk_runs = 2
resamples = 50
profile = "base"

[scenario]
robots = 3
carriers = 7
"""


def small_study(**changes: Any) -> Study:
    return Study.from_mapping({**SMALL, **changes})


def write_study(folder: Path, text: str = SMALL_TOML, name: str = "study.toml") -> Path:
    path = folder / name
    path.write_text(text, encoding="utf-8")
    return path
