"""Help and output name the docs pages that explain them, never a SPEC section (none ships)."""

from __future__ import annotations

from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from swarmtag.cli._main import app

CLI = Path(__file__).parents[2] / "src" / "swarmtag" / "cli"


def _paths(group: click.Group, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    found = [prefix]
    for name, command in group.commands.items():
        if isinstance(command, click.Group):
            found += _paths(command, (*prefix, name))
        else:
            found.append((*prefix, name))
    return found


@pytest.mark.parametrize("path", _paths(app), ids=lambda path: " ".join(path) or "swarmtag")
def test_no_help_text_cites_a_spec_section(path):
    result = CliRunner().invoke(app, [*path, "--help"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    assert "SPEC" not in result.output


def test_no_command_prints_a_spec_section():
    # what the commands print (titles, notes, messages) is written in these modules
    cited = [
        f"{path.name}:{number}"
        for path in sorted(CLI.glob("*.py"))
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), start=1)
        if "SPEC §" in line
    ]
    assert cited == []
