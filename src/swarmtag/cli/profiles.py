"""``swarmtag profiles``: the shipped profiles side by side, or one profile in full."""

from __future__ import annotations

from typing import Any

import click
from rich.table import Table

from swarmtag.cli._console import make_console
from swarmtag.sim.config.mapping import flat_keys
from swarmtag.sim.config.profiles import DEFAULT_PROFILE, PROFILES, Profile, load_profile

__all__ = ["profiles_cmd"]

_SKIPPED = ("robots", "carriers", "ticks", "reprioritisations", "arena")
"""Keys a study or the command line sets, not a profile (the arena follows the density rule)."""


def _resolved(profile: Profile) -> dict[str, Any]:
    """Every scenario value of ``profile`` (its own and the defaults), as dotted keys."""
    mapping = profile.scenario().to_mapping()
    return {
        key: value for key, value in flat_keys(mapping).items() if key.split(".")[0] not in _SKIPPED
    }


@click.command("profiles")
@click.argument("name", required=False, metavar="[NAME|FILE]")
def profiles_cmd(name: str | None) -> None:
    """List the shipped profiles with their values, or show one profile (a name or a file).

    Values a profile sets itself are in bold; the rest are the scenario defaults.
    """
    console = make_console()
    chosen = [load_profile(name)] if name else [load_profile(n) for n in PROFILES]
    table = Table(title="Profiles (bold: set by the profile; others: scenario defaults)")
    table.add_column("key")
    for profile in chosen:
        label = profile.name + (" (default)" if profile.name == DEFAULT_PROFILE else "")
        table.add_column(label, justify="right")
    resolved = [_resolved(profile) for profile in chosen]
    own = [flat_keys(profile.values) for profile in chosen]
    for key in resolved[0]:
        cells = []
        for values, mine in zip(resolved, own, strict=True):
            text = str(values[key])
            cells.append(f"[bold]{text}[/bold]" if key in mine else text)
        table.add_row(key, *cells)
    console.print(table)
    for profile in chosen:
        console.print(f"[bold]{profile.name}[/bold]: {profile.description}")
        if profile.calibration:
            fitted = flat_keys(profile.calibration)
            shown = ", ".join(f"{key} = {value}" for key, value in fitted.items())
            console.print(f"  calibration: {shown}")
