"""Options shared by every command that prints KPI statistics."""

from __future__ import annotations

import click

__all__ = ["baseline_option", "resamples_option"]

baseline_option = click.option(
    "--baseline",
    metavar="NAME",
    default=None,
    help="Condition to compare with [default: proximity if present, else the first in sorted "
    "order].",
)
resamples_option = click.option(
    "--resamples",
    type=click.IntRange(min=1),
    default=10_000,
    show_default=True,
    metavar="N",
    help="Bootstrap resamples of whole runs per condition.",
)
