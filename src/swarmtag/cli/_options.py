"""Options shared by every command that prints KPI statistics."""

from __future__ import annotations

import click

from swarmtag._checks import MAX_RESAMPLES
from swarmtag._resources import check_memory
from swarmtag.analysis.resampling import bootstrap_memory
from swarmtag.errors import StatisticsError

__all__ = ["baseline_option", "check_bootstrap_memory", "resamples_option"]

baseline_option = click.option(
    "--baseline",
    metavar="NAME",
    default=None,
    help="Condition to compare with [default: proximity if present, else the first in sorted "
    "order].",
)
resamples_option = click.option(
    "--resamples",
    type=click.IntRange(1, MAX_RESAMPLES),
    default=10_000,
    show_default=True,
    metavar="N",
    help="Bootstrap resamples of whole runs per condition.",
)


def check_bootstrap_memory(resamples: int, width: int, conditions: int) -> None:
    """Refuse ``--resamples`` whose bootstrap cannot fit in memory, before any other work.

    ``width`` bounds the values one resample spans (runs times carriers).
    """
    check_memory(
        f"--resamples {resamples} over {conditions} condition(s)",
        bootstrap_memory(resamples, conditions=conditions, width=max(1, width)),
        error=StatisticsError,
    )
