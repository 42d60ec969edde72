"""Lazy access to matplotlib (the ``plot`` extra), headless, for every picture swarmtag draws."""

# ruff: noqa: PLC0415 - matplotlib is imported on first use only

from __future__ import annotations

from typing import Any

from swarmtag.errors import ConfigError

__all__ = ["pyplot"]


def pyplot() -> Any:  # noqa: ANN401 - the matplotlib.pyplot module
    """``matplotlib.pyplot`` with the non-interactive Agg backend, or a clear error."""
    try:
        import matplotlib as mpl
    except ImportError:  # pragma: no cover - the test environment has the extra
        msg = "pictures need the 'plot' extra: pip install 'swarmtag[plot]'"
        raise ConfigError(msg) from None
    mpl.use("Agg")
    import matplotlib.pyplot as plt

    return plt
