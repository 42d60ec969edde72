"""``swarmtag log import BAG --events OUT`` and ``log mapping``: trial logs from ROS 2 bags.

``swarmtag simulate --mcap run.mcap`` with several conditions writes one file per
condition (``run-proximity.mcap``, ``run-urgency-alpha-0.7.mcap``), so ``log import
run.mcap`` of a name that does not exist reads every ``run-*.mcap`` beside it into
one event log: each file holds its own condition, and one log of all of them is what
``swarmtag metrics`` compares.
"""

from __future__ import annotations

import glob
import os
from collections.abc import Sequence
from pathlib import Path

import click
import numpy as np

from swarmtag._inputs import check_path
from swarmtag._outputs import OutputPlan
from swarmtag.errors import BagError, EventLogError
from swarmtag.io import CarrierLog, EventTable, write_event_log, write_event_table
from swarmtag.io.bag_mapping import BagMapping, default_mapping
from swarmtag.io.bags import BAG_SUFFIXES, BagLogs, read_bag

__all__ = ["bag_files", "log_group"]

_TABLES = (".csv", ".parquet")


def bag_files(bag: Path) -> list[Path]:
    """The bags that the name ``bag`` stands for: itself, or the per-condition files.

    A bag that exists (a folder or a file) is itself. A missing ``run.mcap`` (or ``.db3``)
    stands for the files ``run-*.mcap`` beside it, which ``swarmtag simulate --mcap
    run.mcap`` writes for several conditions, in sorted order; with none, it stays
    itself and reading it says that there is no such bag.
    """
    check_path(bag, what="bag", error=BagError)
    if os.path.lexists(bag) or bag.suffix.lower() not in BAG_SUFFIXES or not bag.stem:
        return [bag]
    pattern = bag.with_name(f"{glob.escape(bag.stem)}-*{glob.escape(bag.suffix)}")
    found = sorted(Path(name) for name in glob.glob(str(pattern)))  # noqa: PTH207 - escaped stem
    return [path for path in found if path.is_file()] or [bag]


def _combined(bags: Sequence[Path], logs: Sequence[BagLogs]) -> BagLogs:
    """The logs of several bags as one, ordered by condition, run and carrier.

    Refused in one line naming the files when they cannot form one log: the same run of
    a condition in two files, or times in seconds in one and ticks in another.
    """
    if len(logs) == 1:
        return logs[0]
    names = ", ".join(str(bag) for bag in bags)
    try:
        carriers = CarrierLog.concat([log.carriers for log in logs])
        tables = [log.events for log in logs if log.events is not None]
        events = EventTable.concat(tables) if len(tables) == len(logs) else None
    except EventLogError as error:
        msg = f"{names}: cannot be imported as one event log ({error}); import each on its own"
        raise BagError(msg) from None
    if events is not None:  # grouped by condition like the carriers, in time order within
        codes = np.unique(events.condition, return_inverse=True)[1]
        events = events.take(np.argsort(codes, kind="stable"))
    return BagLogs(
        carriers=carriers.sorted(),
        events=events,
        trials=sum(one.trials for one in logs),
        skipped=tuple(topic for one in logs for topic in one.skipped),
    )


def _summary(bag: Path, logs: BagLogs) -> str:
    """What one bag held, in one line."""
    carriers = logs.carriers
    delivered = int(np.count_nonzero(~np.isnan(carriers.delivery_time)))
    unit = {"s": "seconds", "tick": "ticks"}.get(carriers.time_unit or "s", "seconds")
    return (
        f"{bag}: {logs.trials} trial(s), {len(carriers)} carrier rows ({delivered} delivered), "
        f"times in {unit}, conditions {', '.join(carriers.conditions)}"
    )


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
    trial's start: seconds, or ticks for simulated runs. A BAG such as run.mcap that
    does not exist reads every run-*.mcap beside it into one log: the files simulate
    --mcap run.mcap writes, one per condition. Only the mapped topics are read; topics of
    service events or foreign encodings are reported as skipped. MCAP checksums and each
    topic's message count are verified: a damaged bag or one read short is refused.
    """
    plan = OutputPlan()
    bags = bag_files(bag)
    for found in bags:
        plan.input("BAG", found)
    if mapping is not None:
        plan.input("--mapping", mapping)
    plan.file("--events", events, suffixes=_TABLES)
    if event_table is not None:
        plan.file("--event-table", event_table, suffixes=_TABLES)
    layout = BagMapping.default() if mapping is None else BagMapping.load(mapping)
    read = [read_bag(found, layout, with_events=event_table is not None) for found in bags]
    logs = _combined(bags, read)
    with plan.writing() as stage:
        write_event_log(logs.carriers, stage.path(events))
        if event_table is not None and logs.events is not None:
            write_event_table(logs.events, stage.path(event_table))
    if len(bags) > 1:
        click.echo(
            f"{bag}: no such file; read the {len(bags)} files {bag.stem}-*{bag.suffix} beside it "
            "(one per condition, as simulate --mcap writes them) into one event log:"
        )
    for found, log in zip(bags, read, strict=True):
        click.echo(_summary(found, log))
        if log.skipped:
            click.echo(
                f"{found}: skipped {len(log.skipped)} topic(s) that hold no plain messages "
                f"(not read): {', '.join(log.skipped)}"
            )
    click.echo(f"wrote event log: {events}")
    if event_table is not None and logs.events is not None:
        click.echo(f"wrote event table ({len(logs.events)} rows): {event_table}")


@log_group.command("mapping")
def mapping_cmd() -> None:
    """Print the default bag mapping (TOML): copy it and edit topics and fields for your bags."""
    click.echo(default_mapping().read_text(encoding="utf-8"), nl=False)
