"""Help and output name the docs pages that explain them, never a SPEC section (none ships)."""

from __future__ import annotations

from pathlib import Path

import click
import pytest
from click.testing import CliRunner

from swarmtag.cli._main import COMMANDS, app

CLI = Path(__file__).parents[2] / "src" / "swarmtag" / "cli"


def _paths(group: click.Group, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    found = [prefix]
    context = click.Context(group)
    for name in group.list_commands(context):
        command = group.get_command(context, name)
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


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_the_root_help_lists_each_command_by_its_own_first_sentence(name):
    # swarmtag --help lists the commands without importing them: from COMMANDS
    command = app.get_command(click.Context(app), name)
    assert command is not None
    assert command.name == name
    assert command.get_short_help_str(limit=1000) == COMMANDS[name].summary


def test_the_root_help_imports_no_command(tmp_path):
    import subprocess
    import sys

    probe = (
        "import sys; from swarmtag.cli import main\n"
        "try:\n    main(['--help'])\nexcept SystemExit:\n    pass\n"
        "print(sorted(m for m in sys.modules if m.startswith(('swarmtag.cli.', 'numpy'))))"
    )
    result = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True
    )
    assert result.stdout.strip().splitlines()[-1] == "['swarmtag.cli._main']"
