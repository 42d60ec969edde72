"""``swarmtag tag keygen --out FILE``: make a new site key file, never showing the key.

The file (``swarmtag.tag.keys``: a ``swarmtag-site-key-v1`` line, then 64 hex
digits) goes to the tags and to whoever provisions them. Writers get only
their role's key, derived from it (``derive_role_key``), so a stolen robot
cannot sign an operator's write.
"""

from __future__ import annotations

from pathlib import Path

import click

from swarmtag.errors import KeyFileError
from swarmtag.tag import generate_site_key, write_key_file

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
def keygen_cmd(out: Path) -> None:
    """Write a new random 32-byte site key to FILE (mode 0600); the key is never printed.

    An existing FILE is never overwritten. Keep the file private: tags and the
    provisioning computer need it, robots and operators only their role keys.
    """
    try:
        path = write_key_file(out, generate_site_key())
    except KeyFileError as error:
        raise _Refused(str(error)) from None
    click.echo(f"wrote a new site key to {path} (mode 0600); keep it private")
