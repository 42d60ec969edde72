"""``swarmtag demo``: a tour of what exists — tag payloads, authenticated writes, selection."""

from __future__ import annotations

import click
import numpy as np
from rich.console import Console
from rich.table import Table

from swarmtag.analysis import summarize
from swarmtag.cli._console import make_console
from swarmtag.cli.metrics import render_report
from swarmtag.data import example_trial_path
from swarmtag.errors import WriteRejected
from swarmtag.io import read_event_log
from swarmtag.policy import Policy, Proximity, Urgency, Weighted, select
from swarmtag.tag import (
    Change,
    MemoryStore,
    Role,
    TagModel,
    TagState,
    TagStatus,
    WriteSigner,
    decode,
    derive_robot_key,
    encode,
    encode_manufacturer_data,
)

__all__ = ["demo"]

# An example scene in the 3.75 m lab arena: one robot, five carriers.
_ROBOT_XY = (1.2, 1.9)
_CARRIERS = (  # marker, urgency, status, x, y
    (3, 2, TagStatus.AWAITING_PICKUP, 0.4, 1.6),
    (5, 9, TagStatus.AWAITING_PICKUP, 0.4, 0.5),
    (8, 6, TagStatus.AWAITING_PICKUP, 0.4, 3.3),
    (11, 0, TagStatus.AWAITING_PICKUP, 0.9, 2.5),
    (14, 9, TagStatus.PICKED_UP, 2.8, 1.9),
)
_POLICIES: tuple[Policy, ...] = (
    Proximity(),
    Urgency(alpha=0.7),
    Urgency(alpha=3.0),
    Urgency(alpha=9.0),
    Weighted(w=0.5),
)
_SHORT = {
    policy.name: label
    for policy, label in zip(_POLICIES, ("prox", "u a=.7", "u a=3", "u a=9", "w=.5"), strict=True)
}
_SITE_KEY = bytes.fromhex("00112233445566778899aabbccddeeff")


def _payloads(console: Console) -> None:
    table = Table(title="Tag advertisements (docs/tag-protocol.md)")
    for column in ("marker", "urgency", "status", "payload hex", "mapping form (bleak)"):
        table.add_column(column, no_wrap=True)
    for marker, urgency, status, _x, _y in _CARRIERS:
        state = TagState(urgency=urgency, status=status, destination=0, marker=marker)
        payload = encode(state)
        assert decode(payload) == state
        mapping = ", ".join(
            f"0x{k:04x}: {v.hex()}" for k, v in encode_manufacturer_data(state).items()
        )
        table.add_row(str(marker), str(urgency), status.name, payload.hex(), f"{{{mapping}}}")
    console.print(table)


def _writes(console: Console) -> None:
    console.print("\n[bold]Authenticated writes (docs/tag-protocol.md)[/bold] on tag 5:")
    store = MemoryStore()
    start = TagState(urgency=9, status=TagStatus.AWAITING_PICKUP, destination=0, marker=5)
    tag = TagModel.provision(start, site_key=_SITE_KEY, store=store)
    robot_key = derive_robot_key(_SITE_KEY, 1)  # a robot holds only its own key (writer 1)
    robot = WriteSigner(writer=1, role=Role.ROBOT, key=robot_key)
    stolen = WriteSigner(writer=1, role=Role.OPERATOR, key=robot_key)
    intruder = WriteSigner(writer=900, role=Role.OPERATOR, key=b"a phone's guessed operator key!!")
    lift = robot.sign(5, Change(status=TagStatus.PICKED_UP))
    steps = (
        ("robot lifts the carrier", lift),
        ("the same bytes replayed", lift),
        ("robot tries to set urgency 0", robot.sign(5, Change(urgency=0))),
        ("robot key signs as an operator", stolen.sign(5, Change(urgency=0))),
        ("phone with a guessed key sets IDLE", intruder.sign(5, Change(status=TagStatus.IDLE))),
        ("robot releases in the drop-off area", robot.sign(5, Change(status=TagStatus.IDLE))),
    )
    for label, message in steps:
        try:
            state = tag.apply(message)
            outcome = f"[green]accepted[/green], tag now {state.status.name}"
        except WriteRejected as error:
            outcome = f"[red]refused[/red] ({type(error).__name__}): {error.reason}"
        console.print(f"  {label:<36} [dim]{message.hex()}[/dim]")
        console.print(f"      {outcome}")
    rebooted = TagModel.boot(site_key=_SITE_KEY, store=store)
    console.print(
        f"  after a power cycle: status {rebooted.state.status.name}, "
        f"counters {dict(rebooted.counters)}"
    )


def _selection(console: Console) -> None:
    markers = np.array([c[0] for c in _CARRIERS])
    urgency = np.array([c[1] for c in _CARRIERS])
    available = np.array([c[2] is TagStatus.AWAITING_PICKUP for c in _CARRIERS])
    dx = np.array([c[3] for c in _CARRIERS]) - _ROBOT_XY[0]
    dy = np.array([c[4] for c in _CARRIERS]) - _ROBOT_XY[1]
    distance = np.sqrt(dx * dx + dy * dy)
    table = Table(title=f"Carrier selection (docs/policy.md) for a robot at {_ROBOT_XY} m")
    table.add_column("marker", no_wrap=True)
    table.add_column("urgency")
    table.add_column("dist m")
    for policy in _POLICIES:
        table.add_column(_SHORT[policy.name], justify="right", no_wrap=True)
    chosen = {
        policy.name: int(
            select(policy, urgency=urgency, distance=distance, marker=markers, available=available)
        )
        for policy in _POLICIES
    }
    for index, (marker, u, _status, _x, _y) in enumerate(_CARRIERS):
        cells = []
        for policy in _POLICIES:
            score = float(policy.score(u, distance[index]))
            mark = "*" if chosen[policy.name] == index else " "
            cells.append(f"{score:.2f}{mark}" if available[index] else "-")
        label = str(marker) if available[index] else f"{marker} (lifted)"
        table.add_row(label, str(u), f"{distance[index]:.2f}", *cells)
    console.print()
    console.print(table)
    console.print("  * marks each policy's choice; - = not AWAITING_PICKUP, so not selectable.")
    console.print("  columns: " + ", ".join(f"{_SHORT[p.name]} = {p.name}" for p in _POLICIES))


def _metrics(console: Console) -> None:
    path = example_trial_path()
    console.print(f"\n[bold]Metrics of a physical-style trial log (docs/metrics.md)[/bold]: {path}")
    console.print(f"  the same as: swarmtag metrics {path}\n")
    report = summarize(read_event_log(path), baseline=None, n_resamples=10_000, seed=0)
    render_report(report, console)


@click.command()
def demo() -> None:
    """A tour of the building blocks: tag payloads, writes, selection, trial-log metrics."""
    console = make_console()
    _payloads(console)
    _writes(console)
    _selection(console)
    _metrics(console)
