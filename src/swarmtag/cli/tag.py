"""``swarmtag tag encode|decode|render`` (payload, E-ink picture); keygen/scan/write/emulate too."""

from __future__ import annotations

import json
import string
from collections.abc import Callable
from pathlib import Path

import click

from swarmtag._outputs import OutputPlan
from swarmtag.cli._tag_options import status
from swarmtag.errors import PayloadError
from swarmtag.tag import COMPANY_ID, TagState, TagStatus, decode, encode

__all__ = ["tag"]

_SEPARATORS = str.maketrans("", "", ":- \t")


def parse_hex(text: str) -> bytes:
    """Read hex with an optional ``0x`` prefix and ``:``/``-``/space separators."""
    digits = text.strip().lower().removeprefix("0x").translate(_SEPARATORS)
    if not digits or any(char not in string.hexdigits for char in digits) or len(digits) % 2:
        raise PayloadError(f"{text!r} is not a hex byte string (expected e.g. ffff0701030c)")
    return bytes.fromhex(digits)


def _state_options(command: Callable[..., None]) -> Callable[..., None]:
    """The four fields of a tag state as required options (encode, render)."""
    options = (
        click.option("--urgency", required=True, type=click.IntRange(0, 9), help="Urgency 0-9."),
        click.option(
            "--status",
            required=True,
            metavar="STATUS",
            callback=status,
            help="idle, awaiting_pickup or picked_up (any case), or 0-2.",
        ),
        click.option(
            "--destination", required=True, type=click.IntRange(0, 255), help="Destination 0-255."
        ),
        click.option(
            "--marker", required=True, type=click.IntRange(0, 255), help="ArUco marker id 0-255."
        ),
    )
    for option in reversed(options):
        command = option(command)
    return command


@click.group()
def tag() -> None:
    """The smart tag: its payload, its E-ink picture, site key files, scanning, a software tag."""


@tag.command("encode")
@_state_options
def encode_cmd(urgency: int, status: TagStatus, destination: int, marker: int) -> None:
    """Print the payload as lowercase hex, e.g. ffff0701030c."""
    state = TagState(urgency=urgency, status=status, destination=destination, marker=marker)
    click.echo(encode(state).hex())


@tag.command("decode")
@click.argument("hex_payload", metavar="HEX")
@click.option("--json", "as_json", is_flag=True, help="Print the fields as one JSON object.")
def decode_cmd(hex_payload: str, *, as_json: bool) -> None:
    """Print the fields of a 6-byte payload given as HEX (e.g. ffff0701030c)."""
    state = decode(parse_hex(hex_payload))
    fields = {
        "company_id": COMPANY_ID,
        "urgency": state.urgency,
        "status": state.status.name,
        "destination": state.destination,
        "marker": state.marker,
    }
    if as_json:
        click.echo(json.dumps(fields))
        return
    width = max(map(len, fields))
    for name, value in fields.items():
        shown = f"0x{value:04x}" if name == "company_id" else value
        click.echo(f"{name:<{width}}  {shown}")


@tag.command("render")
@_state_options
@click.option(
    "--out",
    required=True,
    type=click.Path(path_type=Path),
    metavar="PNG",
    help="The .png file to write (its folder must exist).",
)
def render_cmd(urgency: int, status: TagStatus, destination: int, marker: int, out: Path) -> None:
    """Write the tag's E-ink picture (250 x 122, 1-bit PNG) for the given state."""
    from swarmtag.tag.eink import save_png  # noqa: PLC0415 - Pillow, the eink extra

    state = TagState(urgency=urgency, status=status, destination=destination, marker=marker)
    plan = OutputPlan()
    target = plan.file("--out", out, suffixes=(".png",))
    with plan.writing() as stage:
        save_png(state, stage.path(target))
    click.echo(f"wrote E-ink picture: {out}")


from swarmtag.cli.tag_emulate import emulate_cmd  # noqa: E402 - a command of this group, in its module
from swarmtag.cli.tag_keys import keygen_cmd  # noqa: E402 - a command of this group, in its module
from swarmtag.cli.tag_scan import scan_cmd  # noqa: E402 - a command of this group, in its module
from swarmtag.cli.tag_write import write_cmd  # noqa: E402 - a command of this group, in its module

tag.add_command(emulate_cmd)
tag.add_command(keygen_cmd)
tag.add_command(scan_cmd)
tag.add_command(write_cmd)
