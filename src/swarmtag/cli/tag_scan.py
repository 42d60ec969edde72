"""``swarmtag tag scan``: listen for tags for a while, then show every carrier in range.

The scan runs on the ``bleak`` backend (the ``ble`` extra). It ends after
``--timeout`` seconds, or on Ctrl-C: then the table of what was seen is
still printed, and the command exits 130 as every interrupted command does.
A radio that cannot be used (no adapter, no BlueZ, no permission) is one
line saying what is missing, exit 2. ``--adapter hci1`` picks a BlueZ
adapter (the simulated radio has none and ignores it). The hidden ``--backend sim`` hears a
bench of simulated tags, for demos and for tests that must not touch a radio.
"""

from __future__ import annotations

import json
import time

import click
from rich.table import Table

from swarmtag._interrupt import acknowledge, checkpoint
from swarmtag.cli._console import make_console
from swarmtag.cli._tag_options import adapter, seconds_between
from swarmtag.tag.backends import Scanner, Sighting, open_scanner

__all__ = ["scan_cmd"]

_TICK = 0.1
"""Seconds between two looks at the scanner (failure, simulated radio)."""
MAX_TIMEOUT = 86400.0
"""The longest scan asked for in one command: a day."""


def _open(backend: str, adapter: str | None) -> Scanner:
    """The scanner behind ``--backend`` on ``adapter`` (tests replace this function)."""
    if backend == "sim":
        from swarmtag.tag.backends.sim import bench_tags  # noqa: PLC0415 - only for --backend sim

        return open_scanner("sim", tags=bench_tags())
    return open_scanner(backend, adapter=adapter)


def _listen(scanner: Scanner, timeout: float) -> bool:
    """Scan until ``timeout`` passes or the radio fails; whether Ctrl-C ended it."""
    deadline = time.monotonic() + timeout
    try:
        with scanner:
            while True:
                scanner.poll()
                left = deadline - time.monotonic()
                if scanner.failure is not None or left <= 0:
                    return False
                time.sleep(min(_TICK, left))
                checkpoint()
    except KeyboardInterrupt:
        acknowledge()  # taken: the table of what was heard is shown, then the command ends
        return True


def _row(sighting: Sighting, now: float) -> dict[str, object]:
    state = sighting.state
    return {
        "marker": sighting.marker,
        "urgency": state.urgency,
        "status": state.status.name,
        "destination": state.destination,
        "rssi": sighting.rssi,
        "age_s": round(max(0.0, now - sighting.seen_at), 3),
        "address": sighting.address,
    }


def _table(rows: list[dict[str, object]]) -> Table:
    table = Table(title="tags in range")
    for name in ("marker", "urgency", "status", "destination", "RSSI (dBm)", "age (s)", "address"):
        table.add_column(name, justify="left" if name in ("status", "address") else "right")
    for row in rows:
        table.add_row(
            *(f"{value:.1f}" if key == "age_s" else str(value) for key, value in row.items())
        )
    return table


@click.command("scan")
@click.option(
    "--timeout",
    type=float,
    default=10.0,
    show_default=True,
    callback=seconds_between(0.0, MAX_TIMEOUT),
    metavar="S",
    help="Seconds to listen; Ctrl-C ends sooner (the table is still shown).",
)
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of a table.")
@click.option(
    "--adapter",
    metavar="hciN",
    callback=adapter,
    help="The BlueZ adapter to scan with (default: the system's first).",
)
@click.option("--backend", type=click.Choice(["bleak", "sim"]), default="bleak", hidden=True)
def scan_cmd(timeout: float, *, as_json: bool, adapter: str | None, backend: str) -> None:
    """Listen for swarmtag tags, then list each one in range (needs the ble extra).

    Shows marker, urgency, status, destination, RSSI and the age of the last
    advertisement heard from each carrier; other BLE devices are ignored.
    """
    scanner = _open(backend, adapter)
    interrupted = _listen(scanner, timeout)
    if scanner.failure is not None:
        raise scanner.failure
    now = scanner.now()
    rows = [_row(sighting, now) for sighting in scanner.states().values()]
    if as_json:
        counts = {"accepted": scanner.accepted, "foreign": scanner.foreign}
        counts["malformed"] = scanner.malformed
        click.echo(json.dumps({"backend": backend, "tags": rows, **counts}))
    else:
        if rows:
            make_console().print(_table(rows))
        else:
            click.echo("no tags in range")
        click.echo(
            f"heard {scanner.accepted} adverts of our tags; ignored {scanner.foreign} of other "
            f"devices; {scanner.malformed} malformed"
        )
    if interrupted:
        raise KeyboardInterrupt("scan ended by Ctrl-C; shown is what was heard")
