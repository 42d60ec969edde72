"""``swarmtag tag keygen``: make a site key file, or derive a writer's key file; never show a key.

``--out FILE`` alone makes a new random site key (``swarmtag.tag.keys``: a
``swarmtag-site-key-v1`` line, then 64 hex digits); it goes to the tags and
to whoever provisions them. ``--role robot --writer ID --from SITE.key --out
FILE`` derives robot ID's own key (``derive_robot_key``) into a robot key
file: the only key that robot's computer gets, so a stolen robot signs
neither an operator's write nor another robot's. ``--role operator --from
SITE.key`` derives the operator key, shared by operators and the WMS.
``--role robot --shared`` derives the legacy key shared by all robots, for
tags still set to accept it (docs/tag-protocol.md §4).
"""

from __future__ import annotations

from pathlib import Path

import click

from swarmtag.errors import KeyFileError
from swarmtag.tag import (
    Role,
    derive_robot_key,
    derive_role_key,
    generate_site_key,
    read_key_file,
    write_key_file,
    write_robot_key_file,
    write_role_key_file,
)

__all__ = ["keygen_cmd"]

_EXIT_BAD_INPUT = 2
"""As ``swarmtag.cli._main.EXIT_BAD_INPUT``: every refused input exits with 2."""


class _Refused(click.ClickException):
    """A refusal that exits with 2 on its own, as through the ``swarmtag`` error boundary."""

    exit_code = _EXIT_BAD_INPUT


def _check_options(
    role: str | None, site_file: Path | None, writer: int | None, shared: bool
) -> None:
    """Refuse option combinations that name no key, before any file is touched."""
    if (role is None) != (site_file is None):
        given, missing = ("--role", "--from") if site_file is None else ("--from", "--role")
        raise click.UsageError(
            f"{given} needs {missing} (a writer's key is derived from a site key)"
        )
    if role != "robot" and (writer is not None or shared):
        flag = "--writer" if writer is not None else "--shared"
        raise click.UsageError(f"{flag} is for robot keys (--role robot)")
    if role == "robot" and (writer is None) == (not shared):
        raise click.UsageError(
            "--role robot needs --writer ID (this robot's own key)"
            if writer is None
            else "--writer and --shared exclude each other: a robot key is its own or shared"
        )


@click.command("keygen")
@click.option(
    "--out",
    "out",
    required=True,
    metavar="FILE",
    type=click.Path(dir_okay=False, path_type=Path),
    help="The new key file; it must not exist yet, its folder must.",
)
@click.option(
    "--role",
    type=click.Choice(["robot", "operator"]),
    help="Derive a writer's key of this role (needs --from) instead of making a site key.",
)
@click.option(
    "--writer",
    type=click.IntRange(0, 0xFFFF),
    metavar="ID",
    help="With --role robot: the robot's writer id 0-65535; its key signs only for that id.",
)
@click.option(
    "--shared",
    is_flag=True,
    help="With --role robot: the legacy key shared by all robots (only for tags set to take it).",
)
@click.option(
    "--from",
    "site_file",
    metavar="SITE.key",
    type=click.Path(dir_okay=False, path_type=Path),
    help="The site key file to derive the --role key from.",
)
def keygen_cmd(
    out: Path, role: str | None, writer: int | None, *, shared: bool, site_file: Path | None
) -> None:
    """Write a new site key, or a writer's key derived from one, to FILE (mode 0600).

    Without --role: a new random 32-byte site key. With --role robot --writer
    ID --from SITE.key: robot ID's own key, for that robot's computer only.
    With --role operator --from SITE.key: the operator key, for operators and
    the WMS. The key is never printed and an existing FILE is never
    overwritten. Tags and the provisioning computer need the site key.
    """
    _check_options(role, site_file, writer, shared)
    try:
        if role is None or site_file is None:
            path = write_key_file(out, generate_site_key())
            click.echo(f"wrote a new site key to {path} (mode 0600); keep it private")
            return
        site_key = read_key_file(site_file)
        if writer is not None:
            path = write_robot_key_file(out, writer, derive_robot_key(site_key, writer))
            whose, give = f"robot {writer}'s key", f"robot {writer}'s computer"
        else:
            chosen = Role[role.upper()]
            path = write_role_key_file(out, chosen, derive_role_key(site_key, chosen))
            shared_one = " (legacy, shared by all robots)" if shared else ""
            whose, give = f"the {role} key{shared_one}", f"{role} machines"
    except KeyFileError as error:
        raise _Refused(str(error)) from None
    click.echo(
        f"wrote {whose} derived from {site_file} to {path} (mode 0600); give it only to {give}"
    )
