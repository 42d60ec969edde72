"""Option callbacks the tag commands share: ``--status``, timeouts in seconds, ``--adapter``."""

from __future__ import annotations

import math
from collections.abc import Callable

import click

from swarmtag.errors import ConfigError, FieldRangeError
from swarmtag.tag import TagStatus
from swarmtag.tag.backends.base import check_adapter

__all__ = ["adapter", "seconds_between", "status"]


def status(_ctx: click.Context, _param: click.Parameter, value: str | None) -> TagStatus | None:
    """Parse ``--status`` by name in any case (``awaiting_pickup``) or number (0-2), if given."""
    if value is None:
        return None
    try:
        return TagStatus.parse(value)
    except FieldRangeError as error:
        raise click.BadParameter(str(error).removeprefix("status: ")) from None


def seconds_between(
    low: float, high: float
) -> Callable[[click.Context, click.Parameter, float | None], float | None]:
    """A callback refusing NaN, infinities and seconds outside ``low``-``high``."""

    def check(_ctx: click.Context, _param: click.Parameter, value: float | None) -> float | None:
        if value is not None and not (math.isfinite(value) and low <= value <= high):
            raise click.BadParameter(f"{value!r} is not a number of seconds in {low:g}-{high:g}")
        return value

    return check


def adapter(_ctx: click.Context, _param: click.Parameter, value: str | None) -> str | None:
    """Check ``--adapter`` (a BlueZ adapter name such as ``hci1``)."""
    try:
        return check_adapter(value)
    except ConfigError as error:
        raise click.BadParameter(str(error).removeprefix("adapter: ")) from None
