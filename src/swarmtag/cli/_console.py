"""The rich console every command prints tables through."""

from __future__ import annotations

from rich.console import Console

__all__ = ["make_console"]

PIPE_WIDTH = 200
"""Width used when stdout is a file or a pipe, so tables are never wrapped there."""


def make_console() -> Console:
    """A console sized to the terminal, or wide enough for any table in a file or pipe."""
    console = Console(highlight=False)
    if not console.is_terminal:
        console = Console(highlight=False, width=PIPE_WIDTH)
    return console
