"""``swarmtag policies``: every selection rule with its definition, parameters and reference."""

from __future__ import annotations

import click
from rich.table import Table

from swarmtag.cli._console import make_console
from swarmtag.policy import CATALOGUE

__all__ = ["policies_cmd"]


@click.command("policies")
def policies_cmd() -> None:
    """List the selection rules: name, kind, definition, parameter, reference, backends.

    A condition name is the rule's name with its parameter, e.g.
    ``--condition urgency:alpha=0.7`` (docs/policy.md).
    """
    table = Table(title="Selection rules (conditions: NAME or NAME:PARAMETER=VALUE)")
    for column in ("name", "kind", "definition", "parameter", "reference", "runs on", "talks"):
        table.add_column(column, overflow="fold")
    for info in CATALOGUE:
        parameter = f"{info.parameter}: {info.allowed}" if info.parameter else "-"
        table.add_row(
            info.form,
            info.kind,
            info.definition,
            parameter,
            info.reference,
            ", ".join(info.backends),
            "yes" if info.communication else "no",
        )
    make_console().print(table)
