"""The ``swarmtag`` command line.

Each command group lives in its own module; ``_main`` assembles them and turns
every refusal (bad input, usage errors of the CLI framework) into one line on
stderr and exit status 2.
"""

from __future__ import annotations

from swarmtag.cli._main import app, main

__all__ = ["app", "main"]
