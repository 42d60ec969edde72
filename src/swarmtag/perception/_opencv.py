"""Lazy access to OpenCV (the ``vision`` extra): imported on first use, one line if missing."""

# ruff: noqa: PLC0415 - OpenCV is imported on first use only

from __future__ import annotations

from typing import Any, Final

from swarmtag.errors import ConfigError

__all__ = ["NEEDS_EXTRA", "opencv"]

NEEDS_EXTRA: Final = (
    "ArUco detection and camera images need the 'vision' extra: pip install 'swarmtag[vision]'"
)
"""The one line a missing OpenCV is refused with."""


def opencv() -> Any:  # noqa: ANN401 - the cv2 module (OpenCV ships no type stubs for mypy)
    """The ``cv2`` module with its ``aruco`` part, or ``ConfigError`` naming the extra."""
    try:
        import cv2
    except ImportError:
        raise ConfigError(NEEDS_EXTRA) from None
    if not hasattr(cv2, "aruco") or not hasattr(cv2.aruco, "ArucoDetector"):
        msg = f"OpenCV {cv2.__version__} has no cv2.aruco.ArucoDetector (4.7 or later has it); "
        msg += "pip install 'swarmtag[vision]'"
        raise ConfigError(msg)
    return cv2
