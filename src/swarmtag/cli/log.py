"""``swarmtag log import BAG --events OUT`` and ``log mapping``: trial logs from ROS 2 bags."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from swarmtag._outputs import OutputPlan
from swarmtag.io import write_event_log, write_event_table
from swarmtag.io.bag_mapping import BagMapping, default_mapping
from swarmtag.io.bags import read_bag

__all__ = ["log_group"]

_TABLES = (".csv", ".parquet")


@click.group("log")
def log_group() -> None:
    """Trial logs: event logs from ROS 2 bags of physical (or simulated) trials."""


@log_group.command("import")
@click.argument("bag", metavar="BAG", type=click.Path(path_type=Path))
@click.option(
    "--events",
    required=True,
    type=click.Path(path_type=Path),
    metavar="FILE",
    help="Write the event log (.csv or .parquet), one row per carrier per trial.",
)
@click.option(
    "--event-table",
    type=click.Path(path_type=Path),
    metavar="FILE",
    help="Also write the long-format event table from the robot events (.csv or .parquet).",
)
@click.option(
    "--mapping",
    type=click.Path(path_type=Path),
    metavar="FILE",
    help="The bag's topics and fields (TOML, see 'swarmtag log mapping') "
    "[default: the swarmtag_msgs layout].",
)
def import_cmd(bag: Path, *, events: Path, event_table: Path | None, mapping: Path | None) -> None:
    """Turn the trials in a ROS 2 bag BAG into an event log (docs/trial-logs.md; the bags extra).

    BAG is a rosbag2 folder (sqlite3 or MCAP storage), a .db3 file or an .mcap file
    (from ros2 bag record, or swarmtag simulate --mcap). Times are relative to each
    trial's start: seconds, or ticks for simulated runs.
    """
    plan = OutputPlan()
    plan.input("BAG", bag)
    if mapping is not None:
        plan.input("--mapping", mapping)
    plan.file("--events", events, suffixes=_TABLES)
    if event_table is not None:
        plan.file("--event-table", event_table, suffixes=_TABLES)
    layout = BagMapping.default() if mapping is None else BagMapping.load(mapping)
    logs = read_bag(bag, layout, with_events=event_table is not None)
    with plan.writing() as stage:
        write_event_log(logs.carriers, stage.path(events))
        if event_table is not None and logs.events is not None:
            write_event_table(logs.events, stage.path(event_table))
    carriers = logs.carriers
    delivered = int(np.count_nonzero(~np.isnan(carriers.delivery_time)))
    unit = {"s": "seconds", "tick": "ticks"}.get(carriers.time_unit or "s", "seconds")
    click.echo(
        f"{bag}: {logs.trials} trial(s), {len(carriers)} carrier rows ({delivered} delivered), "
        f"times in {unit}, conditions {', '.join(carriers.conditions)}"
    )
    click.echo(f"wrote event log: {events}")
    if event_table is not None and logs.events is not None:
        click.echo(f"wrote event table ({len(logs.events)} rows): {event_table}")


@log_group.command("mapping")
def mapping_cmd() -> None:
    """Print the default bag mapping (TOML): copy it and edit topics and fields for your bags."""
    click.echo(default_mapping().read_text(encoding="utf-8"), nl=False)
