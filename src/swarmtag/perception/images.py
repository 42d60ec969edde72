"""Reading a camera image from a file: its size checked from the header before anything is decoded.

An image file is untrusted input: a 69-byte PNG can claim 100,000 x 100,000
pixels, and a PNG of under a megabyte can inflate to gigabytes (a
decompression bomb). ``read_image`` reads only the header first (Pillow's
lazy ``Image.open``: PNG IHDR, JPEG SOF, BMP, TIFF, WebP, PNM, ...) and
refuses, in one line naming the file, an image of more than
``MAX_IMAGE_PIXELS`` pixels, one whose decoding and detection would not fit
the memory limit (``swarmtag._resources``), and one of another size than the
camera's, all before decoding. Only then does OpenCV decode it (to 8-bit
grey, as ``detect_markers`` takes it), in a helper thread that Ctrl-C does
not wait for. libpng prints its complaints about a damaged file straight to
the process's stderr, which OpenCV cannot silence: they are kept off it while
OpenCV decodes, and the damage is reported in the one line of the error.
"""

# ruff: noqa: PLC0415 - Pillow and OpenCV are imported on first use only

from __future__ import annotations

import contextlib
import os
import tempfile
import warnings
from collections.abc import Iterator
from pathlib import Path
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag import _interrupt
from swarmtag._inputs import regular_file
from swarmtag._resources import check_memory
from swarmtag.errors import ConfigError, PerceptionError
from swarmtag.perception._opencv import opencv
from swarmtag.perception.camera import MAX_PIXELS, Camera

__all__ = [
    "DETECT_BYTES_PER_PIXEL",
    "MAX_IMAGE_PIXELS",
    "check_camera",
    "image_size",
    "read_image",
]

MAX_IMAGE_PIXELS: Final = MAX_PIXELS * MAX_PIXELS
"""Most pixels an image may have (400 million): the largest camera a camera file may give."""
DETECT_BYTES_PER_PIXEL: Final = 16
"""Memory per pixel of decoding and searching an image, besides the decoded image: 7 measured
(OpenCV's thresholded copies and contours on an 8000 x 8000 image of random blocks), doubled."""
_FORMATS: Final = "PNG, JPEG, BMP, TIFF, WebP, PNM"
_NEEDS_PILLOW: Final = (
    "reading camera images needs Pillow, part of the 'vision' extra: pip install 'swarmtag[vision]'"
)


def image_size(path: Path) -> tuple[int, int, int]:
    """(width, height, channels) from the file's header, without decoding its pixels."""
    try:
        from PIL import Image, UnidentifiedImageError
    except ImportError:
        raise ConfigError(_NEEDS_PILLOW) from None
    limit = Image.MAX_IMAGE_PIXELS
    try:
        # Pillow's own bomb check refuses a header without saying its size; only the
        # header is read here, and ``read_image`` applies this project's limits.
        Image.MAX_IMAGE_PIXELS = None
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            with Image.open(path) as image:
                width, height = image.size
                channels = len(image.getbands())
    except UnidentifiedImageError:
        msg = f"{path}: not an image whose size can be read before decoding ({_FORMATS})"
        raise PerceptionError(msg) from None
    except OSError as problem:
        reason = problem.strerror or str(problem) or type(problem).__name__
        msg = f"{path}: cannot read the image's header ({reason})"
        raise PerceptionError(msg) from None
    except (SyntaxError, ValueError, TypeError, IndexError, KeyError, EOFError) as problem:
        # Pillow's plugins report a damaged header with whatever their parser raised.
        msg = f"{path}: a damaged image header ({problem or type(problem).__name__})"
        raise PerceptionError(msg) from None
    finally:
        Image.MAX_IMAGE_PIXELS = limit
    return int(width), int(height), int(channels)


def check_camera(camera: Camera, source: str) -> None:
    """Refuse, before any image is read, a camera whose images would not fit the memory limit.

    ``source`` names the camera file in the message.
    """
    lens = camera.intrinsics
    check_memory(
        f"{source}: camera {camera.name!r}: width x height {lens.width}x{lens.height} "
        "(decoding and searching one of its colour images)",
        lens.width * lens.height * (3 + DETECT_BYTES_PER_PIXEL),
        error=PerceptionError,
    )


def _check_size(path: Path, size: tuple[int, int, int], camera: Camera) -> None:
    width, height, channels = size
    pixels = width * height
    if pixels > MAX_IMAGE_PIXELS:
        msg = (
            f"{path}: the image is {width}x{height} pixels ({pixels:,}); at most "
            f"{MAX_IMAGE_PIXELS:,} are read (the largest camera a camera file may give)"
        )
        raise PerceptionError(msg)
    check_memory(
        f"{path}: decoding and searching a {width}x{height} image of {channels} channel(s)",
        pixels * (max(channels, 1) + DETECT_BYTES_PER_PIXEL),
        error=PerceptionError,
    )
    lens = camera.intrinsics
    if (width, height) != (lens.width, lens.height):
        msg = f"{path}: the image is {width}x{height} but camera {camera.name!r} is "
        msg += f"{lens.width}x{lens.height}; give the camera file of the camera that took it"
        raise PerceptionError(msg)


@contextlib.contextmanager
def _quiet_stderr() -> Iterator[None]:
    """Keep what compiled code writes to file descriptor 2 (libpng's complaints) off stderr.

    Lines that are not libpng's or OpenCV's own log are written back afterwards.
    """
    cv2 = opencv()
    level = cv2.utils.logging.getLogLevel()
    cv2.utils.logging.setLogLevel(cv2.utils.logging.LOG_LEVEL_SILENT)
    with tempfile.TemporaryFile() as capture:
        saved = os.dup(2)
        try:
            os.dup2(capture.fileno(), 2)
            yield
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            cv2.utils.logging.setLogLevel(level)
            capture.seek(0)
            kept = [
                line
                for line in capture.read().decode(errors="replace").splitlines(keepends=True)
                if not line.startswith(("libpng ", "[ WARN", "[ERROR"))
            ]
            if kept:
                os.write(2, "".join(kept).encode())


def read_image(path: str | os.PathLike[str], camera: Camera) -> NDArray[np.uint8]:
    """The image file ``path`` as 8-bit grey, checked against ``camera`` before decoding.

    Every refusal is a ``PerceptionError`` naming the file (see the module docs).
    """
    cv2 = opencv()
    file = regular_file(path, what="image", error=PerceptionError)
    _check_size(file, image_size(file), camera)
    try:
        data = file.read_bytes()
    except OSError as problem:
        msg = f"{file}: cannot read the image ({problem.strerror})"
        raise PerceptionError(msg) from None
    buffer = np.frombuffer(data, dtype=np.uint8)
    try:
        with _quiet_stderr():
            image = _interrupt.in_thread(lambda: cv2.imdecode(buffer, cv2.IMREAD_GRAYSCALE))
    except cv2.error as problem:
        reason = str(problem.err) if hasattr(problem, "err") else "OpenCV refused it"
        msg = f"{file}: a damaged image: OpenCV could not decode it ({reason.strip()})"
        raise PerceptionError(msg) from None
    if image is None:
        msg = f"{file}: a damaged image: OpenCV could not decode it ({_FORMATS})"
        raise PerceptionError(msg)
    decoded: NDArray[np.uint8] = image
    if decoded.shape != (camera.intrinsics.height, camera.intrinsics.width):  # EXIF rotation
        _check_size(file, (decoded.shape[1], decoded.shape[0], 1), camera)
    return decoded
