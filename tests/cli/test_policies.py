"""``swarmtag policies``: the catalogue of selection rules on the command line."""

from __future__ import annotations

from click.testing import CliRunner

from swarmtag.cli._main import app
from swarmtag.policy import CATALOGUE, parse_policy


def test_every_rule_is_listed_with_its_form_reference_and_backends():
    result = CliRunner().invoke(app, ["policies"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    for info in CATALOGUE:
        line = next(row for row in result.output.splitlines() if f"│ {info.form} " in row)
        assert info.kind in line
        assert "reference, fast, bt" in line
        assert info.reference[:12] in result.output  # the column may fold the rest
    assert [info.form for info in CATALOGUE] == [
        "proximity",
        "urgency:alpha=A",
        "edf",
        "weighted:w=W",
    ]


def test_the_catalogue_is_what_condition_names_accept():
    for info in CATALOGUE:
        name = info.name if info.parameter is None else f"{info.name}:{info.parameter}=0.5"
        assert parse_policy(name).name.split(":")[0] == info.name
