"""``swarmtag profiles``: the shipped profiles side by side, or one profile in full.

The human form is a table of every value plus each profile's description and
calibration record, wrapped to the terminal's width; ``--json`` prints the
same facts for scripts (docs/simulator.md, "Profiles").
"""

from __future__ import annotations

import datetime
import json
import math
from collections.abc import Mapping, Sequence
from typing import Any

import click
from rich.console import Console
from rich.table import Table
from rich.text import Text

from swarmtag.cli._console import make_console
from swarmtag.sim.config.mapping import flat_keys
from swarmtag.sim.config.profiles import (
    DEFAULT_PROFILE,
    PROFILES,
    Profile,
    load_profile,
    profile_path,
)

__all__ = ["profile_record", "profiles_cmd"]

_SKIPPED = ("robots", "carriers", "ticks", "reprioritisations", "arena")
"""Keys a study or the command line sets, not a profile (the arena follows the density rule)."""


def _resolved(profile: Profile) -> dict[str, Any]:
    """Every scenario value of ``profile`` (its own and the defaults), as dotted keys.

    The keys in ``_SKIPPED`` are left out unless the profile sets them itself.
    """
    mapping = profile.scenario().to_mapping()
    own = flat_keys(profile.values)
    return {
        key: value
        for key, value in flat_keys(mapping).items()
        if key.split(".")[0] not in _SKIPPED or key in own
    }


def _is_shipped(profile: Profile, name: str | None) -> bool:
    """Whether ``profile`` was loaded by a shipped name (not from a file of the user's)."""
    if name is None:
        return True
    return name in PROFILES and profile.source == str(profile_path(name))


def _plain(value: Any) -> Any:  # noqa: ANN401 - any TOML value
    """``value`` as JSON can hold it: tables and arrays recursively, dates as ISO text.

    Non-finite floats (possible in a calibration record) become the text ``"inf"``,
    ``"-inf"`` or ``"nan"``, so that the output stays strict JSON.
    """
    if isinstance(value, Mapping):
        return {str(key): _plain(item) for key, item in value.items()}
    if isinstance(value, Sequence) and not isinstance(value, str):
        return [_plain(item) for item in value]
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, datetime.date | datetime.time):
        return value.isoformat()
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return str(value)


def profile_record(profile: Profile, *, shipped: bool) -> dict[str, Any]:
    """The ``--json`` object of one profile: what the table and the notes under it show.

    ``values`` holds every scenario value the table lists (dotted keys, the profile's
    own and the defaults), ``set_by_profile`` the keys the profile sets itself (bold in
    the table), ``calibration`` the record ``swarmtag calibrate`` left (``{}`` if none);
    ``file`` is the profile file for one of the user's, ``null`` for a shipped one.
    """
    values = _resolved(profile)
    own = flat_keys(profile.values)
    return {
        "name": profile.name,
        "default": shipped and profile.name == DEFAULT_PROFILE,
        "shipped": shipped,
        "file": None if shipped else profile.source,
        "description": profile.description,
        "values": _plain(values),
        "set_by_profile": [key for key in values if key in own],
        "calibration": _plain(profile.calibration),
    }


def _shown(value: Any) -> str:  # noqa: ANN401 - any TOML value
    """One calibration value as text: arrays as their items joined by commas."""
    if isinstance(value, Sequence) and not isinstance(value, str):
        return ", ".join(str(item) for item in value)
    return str(value)


def _wrapped(console: Console, head: str, body: str, *, indent: int) -> Text:
    """``head`` (bold) and ``body`` as one paragraph wrapped to the console's width.

    The first line starts ``indent`` spaces in, the lines after it two more.
    """
    first, rest = " " * indent, " " * (indent + 2)
    text = click.wrap_text(
        f"{head}{body}",
        width=max(console.width, 20),
        initial_indent=first,
        subsequent_indent=rest,
        preserve_paragraphs=False,
    )
    paragraph = Text(text)
    paragraph.stylize("bold", indent, indent + len(head.rstrip(": ")))
    return paragraph


def _table(chosen: Sequence[Profile], shipped: Sequence[bool]) -> Table:
    """Every value of each profile, one column per profile, its own values in bold."""
    table = Table(title="Profiles (bold: set by the profile; others: scenario defaults)")
    table.add_column("key")
    for profile, is_shipped in zip(chosen, shipped, strict=True):
        default = is_shipped and profile.name == DEFAULT_PROFILE
        table.add_column(profile.name + (" (default)" if default else ""), justify="right")
    resolved = [_resolved(profile) for profile in chosen]
    own = [flat_keys(profile.values) for profile in chosen]
    keys = list(dict.fromkeys(key for values in resolved for key in values))
    for key in keys:
        cells = []
        for values, mine in zip(resolved, own, strict=True):
            text = str(values.get(key, ""))
            cells.append(Text(text, style="bold") if key in mine else Text(text))
        table.add_row(key, *cells)
    return table


@click.command("profiles")
@click.argument("name", required=False, metavar="[NAME|FILE]")
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help='Print {"profiles": [...]} instead: per profile its name, description, every value '
    "and its calibration record (docs/simulator.md).",
)
def profiles_cmd(name: str | None, *, as_json: bool) -> None:
    """List the shipped profiles with their values, or show one profile (a name or a file).

    Values a profile sets itself are in bold; the rest are the scenario defaults.
    Under the table, each profile's description and how it was calibrated.
    """
    chosen = [load_profile(name)] if name else [load_profile(n) for n in PROFILES]
    shipped = [_is_shipped(profile, name) for profile in chosen]
    if as_json:
        records = [profile_record(p, shipped=s) for p, s in zip(chosen, shipped, strict=True)]
        click.echo(json.dumps({"profiles": records}, allow_nan=False))
        return
    console = make_console()
    console.print(_table(chosen, shipped))
    for profile in chosen:
        console.print(_wrapped(console, f"{profile.name}: ", profile.description, indent=0))
        if profile.calibration:
            fitted = flat_keys(profile.calibration)
            shown = "; ".join(f"{key} = {_shown(value)}" for key, value in fitted.items())
            console.print(_wrapped(console, "calibration: ", shown, indent=2))
