"""Tables on the terminal: the first layout that shows every name and number whole."""

from __future__ import annotations

import io

import pytest
from rich.console import Console

from swarmtag.cli._report import Grid, condition_labels, print_grid

CI = "0.4643 [0.4467, 0.4816]"
NAMES = ("proximity", "urgency:alpha=0.7", "urgency:alpha=9.0")


def _printed(grid: Grid, width: int) -> list[str]:
    console = Console(width=width, file=io.StringIO(), color_system=None, highlight=False)
    print_grid(console, grid)
    output = console.file
    assert isinstance(output, io.StringIO)
    return [line.rstrip() for line in output.getvalue().splitlines()]


def _grid(names=NAMES, cell=CI) -> Grid:
    rows = (
        ("Throughput (per 100 ticks)", *[cell] * len(names)),
        ("PA (5-50 %)", *[cell] * len(names)),
        ("Runs", *["20"] * len(names)),
    )
    return Grid(title="Metrics", corner="Metric", names=tuple(names), rows=rows)


def test_labels_run_past_z():
    assert condition_labels(3) == ["A", "B", "C"]
    assert condition_labels(53)[25:28] == ["Z", "AA", "AB"]
    assert condition_labels(53)[-1] == "BA"


def test_wide_by_name_where_it_fits():
    lines = _printed(_grid(), 120)
    assert lines[1].split() == ["Metric", *NAMES]
    assert lines[3].startswith("Throughput (per 100 ticks)")
    assert lines[3].count(CI) == 3


def test_long_names_give_labels_and_a_legend():
    names = ("cbaa:comm_range=5,loss=0.1", "cbaa:comm_range=50,loss=0.25", "oracle:alpha=0.7")
    lines = _printed(_grid(names, cell="0.4643"), 60)
    assert lines[0].startswith("Conditions: A = cbaa:comm_range=5,loss=0.1;")
    legend = " ".join(line.strip() for line in lines[:2] if not line.startswith("Metrics"))
    for label, name in zip("ABC", names, strict=True):
        assert f"{label} = {name}" in legend
    header = next(line for line in lines if line.startswith("Metric "))
    assert header.split() == ["Metric", "A", "B", "C"]
    assert all(len(line) <= 60 for line in lines)


def test_intervals_too_wide_to_sit_side_by_side_go_one_row_per_condition():
    lines = _printed(_grid(), 80)
    assert lines[1].split() == ["Metric", "Condition", "Value"]
    body = lines[3:]
    assert [line.split("   ")[0] for line in body[:3]] == ["Throughput (per 100 ticks)", "", ""]
    assert [line.split()[-4] for line in body[:3]] == list(NAMES)
    assert all(line.endswith(CI) for line in body[:3])
    assert all(len(line) <= 80 for line in lines)


@pytest.mark.parametrize("width", [50, 80, 100, 200])
def test_no_cell_is_ever_cut_or_wrapped_where_a_layout_fits(width):
    lines = _printed(_grid(), width)
    text = "\n".join(lines)
    assert "\N{HORIZONTAL ELLIPSIS}" not in text
    assert text.count(CI) == 6
    assert all(line.count("[") == line.count("]") for line in lines)
    assert all(len(line) <= width for line in lines)


def test_a_console_narrower_than_any_layout_still_prints_within_its_width():
    lines = _printed(_grid(), 30)  # less than a metric word, a label and an interval
    assert all(len(line) <= 30 for line in lines)
    assert lines[0].startswith("Conditions: A = proximity;")
