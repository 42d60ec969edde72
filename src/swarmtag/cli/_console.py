"""The rich console every command prints tables through."""

from __future__ import annotations

import os

from rich.console import Console

__all__ = ["make_console"]

PIPE_WIDTH = 200
"""Width used when stdout is a file or a pipe, so tables are never wrapped there."""


def make_console() -> Console:
    """A console sized to the terminal, or wide enough for any table in a file or pipe.

    An exported ``COLUMNS`` wins in both cases (``COLUMNS=80 swarmtag ... | less``
    lays the tables out for 80 columns), as it does for rich itself.
    """
    console = Console(highlight=False)
    if not console.is_terminal and not os.environ.get("COLUMNS", "").isdigit():
        console = Console(highlight=False, width=PIPE_WIDTH)
    return console
