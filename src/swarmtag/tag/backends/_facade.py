"""The facade behind ``swarmtag.tag.backends``: backend names, lazy imports, one error."""

from __future__ import annotations

import importlib
from typing import Any, Final

from swarmtag.errors import ConfigError
from swarmtag.tag.backends.base import Scanner

__all__ = ["BACKENDS", "open_scanner", "scanner_class"]

BACKENDS: Final[dict[str, tuple[str, str]]] = {
    "bleak": ("swarmtag.tag.backends.bleak", "BleakTagScanner"),
    "sim": ("swarmtag.tag.backends.sim", "SimScanner"),
    "fake": ("swarmtag.tag.backends.fake", "FakeScanner"),
}
"""Backend name -> (module, ``Scanner`` class), imported on first use."""

_EXTRAS: Final = {"bleak": ("bleak", "ble")}
"""Backend -> (the package it needs, the extra that installs it)."""


def scanner_class(backend: str) -> type[Scanner]:
    """The ``Scanner`` class of ``backend``, imported now; ``ConfigError`` if unknown or missing."""
    if backend not in BACKENDS:
        known = ", ".join(sorted(BACKENDS))
        raise ConfigError(f"backend: {backend!r} is not a tag backend (choose one of {known})")
    module_name, class_name = BACKENDS[backend]
    try:
        module = importlib.import_module(module_name)
    except ImportError as error:
        package, extra = _EXTRAS.get(backend, (error.name or "?", "dev"))
        if error.name is None or error.name.split(".")[0] != package:
            raise
        raise ConfigError(
            f"backend {backend!r} needs the {package} package, which is not installed: "
            f"pip install 'swarmtag[{extra}]'"
        ) from None
    found: type[Scanner] = getattr(module, class_name)
    return found


def open_scanner(backend: str = "bleak", **options: Any) -> Scanner:  # noqa: ANN401 - per backend
    """A new, not yet started scanner of ``backend`` built with ``options``.

    ``ConfigError`` names an unknown backend, a missing package (and the
    extra that brings it), or an option the backend does not take.
    """
    cls = scanner_class(backend)
    try:
        return cls(**options)
    except TypeError as error:
        raise ConfigError(f"backend {backend!r}: {error}") from None
