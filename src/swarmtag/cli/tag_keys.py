"""``swarmtag tag keygen``: make a site key file, or derive a role key file; never show a key.

``--out FILE`` alone makes a new random site key (``swarmtag.tag.keys``: a
``swarmtag-site-key-v1`` line, then 64 hex digits); it goes to the tags and
to whoever provisions them. ``--role robot|operator --from SITE.key --out
FILE`` derives that role's key (``derive_role_key``) into a role key file
(``swarmtag-robot-key-v1`` / ``swarmtag-operator-key-v1``): the only key a
writer's machine gets, so a stolen robot cannot sign an operator's write.
"""

from __future__ import annotations

from pathlib import Path

import click

from swarmtag.errors import KeyFileError
from swarmtag.tag import (
    Role,
    derive_role_key,
    generate_site_key,
    read_key_file,
    write_key_file,
    write_role_key_file,
)

__all__ = ["keygen_cmd"]

_EXIT_BAD_INPUT = 2
"""As ``swarmtag.cli._main.EXIT_BAD_INPUT``: every refused input exits with 2."""


class _Refused(click.ClickException):
    """A refusal that exits with 2 on its own, as through the ``swarmtag`` error boundary."""

    exit_code = _EXIT_BAD_INPUT


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
    help="Derive this role's key (needs --from) instead of making a site key.",
)
@click.option(
    "--from",
    "site_file",
    metavar="SITE.key",
    type=click.Path(dir_okay=False, path_type=Path),
    help="The site key file to derive the --role key from.",
)
def keygen_cmd(out: Path, role: str | None, site_file: Path | None) -> None:
    """Write a new site key, or a role key derived from one, to FILE (mode 0600).

    Without --role: a new random 32-byte site key. With --role robot|operator
    --from SITE.key: that role's key, for the writers of that role. The key is
    never printed and an existing FILE is never overwritten. Tags and the
    provisioning computer need the site key; robots only the robot key,
    operators only the operator key.
    """
    if (role is None) != (site_file is None):
        given, missing = ("--role", "--from") if site_file is None else ("--from", "--role")
        raise click.UsageError(f"{given} needs {missing} (a role key is derived from a site key)")
    try:
        if role is None or site_file is None:
            path = write_key_file(out, generate_site_key())
            click.echo(f"wrote a new site key to {path} (mode 0600); keep it private")
            return
        chosen = Role[role.upper()]
        key = derive_role_key(read_key_file(site_file), chosen)
        path = write_role_key_file(out, chosen, key)
    except KeyFileError as error:
        raise _Refused(str(error)) from None
    click.echo(
        f"wrote the {role} key derived from {site_file} to {path} (mode 0600); "
        f"give it only to {role} machines"
    )
