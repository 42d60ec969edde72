"""swarmtag: urgency-aware robot-swarm intralogistics.

Smart BLE tags on carriers broadcast how urgent their item is; robots hear
them and each decides on its own which carrier to fetch. This package holds
the tag protocol (``swarmtag.tag``), the selection policies
(``swarmtag.policy``) and the tools built on them.
"""

from __future__ import annotations

__all__ = ["__version__"]

__version__: str
"""The installed version, looked up on first use (see ``__getattr__``)."""


def __getattr__(name: str) -> str:
    """``__version__``, read from the package metadata when first asked for.

    Lazy because ``importlib.metadata`` takes tens of milliseconds to import,
    and until ``swarmtag.cli.main`` has installed its SIGINT handler a Ctrl-C
    ends in a traceback: the command line must reach it as fast as it can.
    """
    if name != "__version__":
        msg = f"module {__name__!r} has no attribute {name!r}"
        raise AttributeError(msg)
    from importlib import metadata  # noqa: PLC0415 - see above

    try:
        version = metadata.version("swarmtag")
    except metadata.PackageNotFoundError:  # pragma: no cover - source tree, not installed
        version = "0+unknown"
    globals()["__version__"] = version
    return version
