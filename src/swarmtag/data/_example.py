"""Where the example trial log lives, as a resource and as a path."""

from __future__ import annotations

from importlib.resources import files
from importlib.resources.abc import Traversable
from pathlib import Path
from typing import Final

from swarmtag.errors import EventLogError

__all__ = ["EXAMPLE_TRIAL", "example_trial", "example_trial_path", "example_trial_text"]

EXAMPLE_TRIAL: Final = "example_trial.csv"
"""File name of the example trial log inside ``swarmtag.data``."""


def example_trial() -> Traversable:
    """The example trial log as an ``importlib.resources`` resource (works from any install)."""
    return files("swarmtag.data").joinpath(EXAMPLE_TRIAL)


def example_trial_path() -> Path:
    """The example trial log's path on disk (the package is installed as files, not zipped).

    >>> example_trial_path().name
    'example_trial.csv'
    """
    resource = example_trial()
    if not isinstance(resource, Path):
        raise EventLogError(
            f"{EXAMPLE_TRIAL} is inside a zipped install and has no path; "
            "use example_trial_text() instead"
        )
    return resource


def example_trial_text() -> str:
    """The example trial log's CSV text.

    >>> example_trial_text().splitlines()[0]
    'condition,run,seed,carrier,urgency0,order_time,pickup_time,delivery_time,robot,time_unit,notes'
    """
    return example_trial().read_text(encoding="utf-8")
