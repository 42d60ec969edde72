"""The tag's E-ink panel (SPEC §2.4): one 250 x 122 black/white picture of a tag's state.

The simulator's pictures, the software tag, the dashboard and ``swarmtag tag
render`` all draw with ``render``, so every view of a tag shows the same pixels.
The picture is 1-bit (mode ``"1"``) like the panel: no grey, no anti-aliasing.
Text uses the font built into Pillow (Aileron, ``ImageFont.load_default(size=...)``,
Pillow >= 10.1), never a system font, so one state and one Pillow version give
the same bytes on every machine.

Layout (the urgency is what a person walking past must read first)::

    +----------+------------------+
    | URGENCY  | MARKER           |
    |          | 12               |
    |    7     +------------------+
    |          | DESTINATION      |
    |          | 3                |
    +----------+------------------+
    |###### AWAITING PICKUP ######|   white on black
    +-----------------------------+

Pillow is the ``eink`` extra and is imported on first use only.
"""

# ruff: noqa: PLC0415 - Pillow (the eink extra) is imported on first use only

from __future__ import annotations

import io
import os
from typing import TYPE_CHECKING, Final

from swarmtag._atomic import atomic_write_bytes
from swarmtag.errors import ConfigError
from swarmtag.tag._arguments import check_type
from swarmtag.tag.codec import TagState
from swarmtag.tag.status import TagStatus

if TYPE_CHECKING:
    from PIL import Image, ImageDraw, ImageFont

__all__ = ["HEIGHT", "WIDTH", "png_bytes", "render", "save_png", "status_label"]

WIDTH: Final = 250
"""Panel width in pixels (2.13-inch panel, landscape)."""
HEIGHT: Final = 122
"""Panel height in pixels."""

_NEEDS_EXTRA: Final = "the E-ink picture needs the 'eink' extra: pip install 'swarmtag[eink]'"
_BLACK: Final = 0
_WHITE: Final = 1
_COLUMN: Final = 86  # x of the line between the urgency and the marker/destination column
_BAR: Final = 92  # y of the top of the status bar
_SPLIT: Final = 46  # y of the line between marker and destination
_MARGIN: Final = 6  # space between a line or edge and the text next to it


def _require_pillow() -> None:
    """Refuse with a ConfigError naming the extra when Pillow (with FreeType) is missing."""
    try:
        from PIL import features
    except ImportError:
        raise ConfigError(_NEEDS_EXTRA) from None
    if not features.check_module("freetype2"):  # the sized built-in font needs FreeType
        msg = "the E-ink picture needs a Pillow built with FreeType (the PyPI wheels are)"
        raise ConfigError(msg)


def _font(size: int) -> ImageFont.FreeTypeFont:
    """Pillow's built-in font at ``size`` pixels (no system font, same on every machine)."""
    from PIL import ImageFont

    font = ImageFont.load_default(size=size)
    assert isinstance(font, ImageFont.FreeTypeFont)  # _require_pillow checked FreeType
    return font


_Pieces = list[tuple[float, str]]  # (x offset, text) of the runs a text is drawn in


def _pieces(text: str, font: ImageFont.FreeTypeFont, tracking: int) -> _Pieces:
    """``text`` as one run, or letter by letter ``tracking`` pixels apart (bold text breathes)."""
    if not tracking:
        return [(0.0, text)]
    pieces, x = [], 0.0
    for letter in text:
        pieces.append((x, letter))
        x += font.getlength(letter) + tracking
    return pieces


def _ink(
    draw: ImageDraw.ImageDraw, pieces: _Pieces, font: ImageFont.FreeTypeFont, stroke: int
) -> tuple[float, float, float, float]:
    """The bounding box (left, top, right, bottom) of the ink of ``pieces`` drawn at 0, 0."""
    boxes = [draw.textbbox((x, 0), run, font=font, stroke_width=stroke) for x, run in pieces]
    lefts, tops, rights, bottoms = zip(*boxes, strict=True)
    return min(lefts), min(tops), max(rights), max(bottoms)


def _fitted(
    draw: ImageDraw.ImageDraw,
    texts: tuple[str, ...],
    size: int,
    box: tuple[int, int],
    *,
    stroke: int = 0,
    tracking: int = 0,
) -> ImageFont.FreeTypeFont:
    """The font at ``size``, or smaller until each of ``texts`` fits ``box`` (width, height).

    Given every text a place can show (each digit, each status), all get one size.
    """
    while True:
        font = _font(size)
        boxes = [_ink(draw, _pieces(text, font, tracking), font, stroke) for text in texts]
        if all(r - x <= box[0] and b - y <= box[1] for x, y, r, b in boxes) or size <= 8:
            return font
        size -= 1


def _text(
    draw: ImageDraw.ImageDraw,
    text: str,
    font: ImageFont.FreeTypeFont,
    *,
    at: tuple[int, int],
    centred: bool = False,
    fill: int = _BLACK,
    stroke: int = 0,
    tracking: int = 0,
) -> None:
    """Draw ``text`` with its ink's top left (or centre) at ``at``, on whole pixels."""
    pieces = _pieces(text, font, tracking)
    left, top, right, bottom = _ink(draw, pieces, font, stroke)
    x, y = at[0] - left, at[1] - top
    if centred:
        x -= (right - left) // 2
        y -= (bottom - top) // 2
    for offset, run in pieces:
        where = (round(x + offset), round(y))
        draw.text(where, run, font=font, fill=fill, stroke_width=stroke, stroke_fill=fill)


def _label(status: TagStatus) -> str:
    return status.name.replace("_", " ")


def status_label(state: TagState) -> str:
    """The status as the panel shows it: ``AWAITING PICKUP``, ``PICKED UP`` or ``IDLE``.

    >>> status_label(TagState(urgency=1, status=TagStatus.PICKED_UP, destination=0, marker=0))
    'PICKED UP'
    """
    check_type("state", state, TagState)
    return _label(state.status)


def render(state: TagState) -> Image.Image:
    """The 250 x 122 mode-``"1"`` picture the tag's panel shows for ``state``.

    >>> picture = render(TagState(urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3,
    ...                           marker=12))
    >>> picture.size, picture.mode
    ((250, 122), '1')
    """
    check_type("state", state, TagState)
    _require_pillow()
    from PIL import Image, ImageDraw

    image = Image.new("1", (WIDTH, HEIGHT), _WHITE)
    draw = ImageDraw.Draw(image)
    draw.fontmode = "1"  # no anti-aliasing: every pixel is black or white, as on the panel

    draw.rectangle((0, 0, WIDTH - 1, HEIGHT - 1), outline=_BLACK)
    draw.line((_COLUMN, 0, _COLUMN, _BAR), fill=_BLACK, width=2)
    draw.line((_COLUMN, _SPLIT, WIDTH - 1, _SPLIT), fill=_BLACK, width=1)

    # The urgency: one large, emboldened digit under a small label.
    _text(draw, "URGENCY", _font(12), at=(_COLUMN // 2, 10), centred=True)
    digits = tuple("0123456789")
    high, low = 19, _BAR - 4  # the digit's rows, below the label
    digit_font = _fitted(draw, digits, 110, (_COLUMN - 2 * _MARGIN, low - high), stroke=2)
    centre = (_COLUMN // 2, (high + low) // 2)
    _text(draw, digits[state.urgency], digit_font, at=centre, centred=True, stroke=2)

    # Marker and destination: a small label, then the number, in the right column.
    label_font, value_font = _font(11), _font(28)
    x = _COLUMN + _MARGIN + 2
    for top, label, value in (
        (0, "MARKER", state.marker),
        (_SPLIT, "DESTINATION", state.destination),
    ):
        _text(draw, label, label_font, at=(x, top + 5))
        _text(draw, str(value), value_font, at=(x, top + 18), stroke=1, tracking=2)

    # The status: white on a black bar across the bottom, so it reads at a glance.
    draw.rectangle((0, _BAR, WIDTH - 1, HEIGHT - 1), fill=_BLACK)
    labels = tuple(map(_label, TagStatus))
    bar_box = (WIDTH - 4 * _MARGIN, HEIGHT - _BAR - _MARGIN)
    status_font = _fitted(draw, labels, 20, bar_box, stroke=1, tracking=2)
    centre = (WIDTH // 2, (_BAR + HEIGHT) // 2)
    label = status_label(state)
    _text(draw, label, status_font, at=centre, centred=True, fill=_WHITE, stroke=1, tracking=2)
    return image


def png_bytes(state: TagState) -> bytes:
    """``render(state)`` as a 1-bit PNG file's bytes (no metadata, so byte-stable)."""
    buffer = io.BytesIO()
    render(state).save(buffer, format="PNG")
    return buffer.getvalue()


def save_png(state: TagState, path: str | os.PathLike[str]) -> None:
    """Write ``render(state)`` to ``path`` as a 1-bit PNG, atomically (its folder must exist)."""
    atomic_write_bytes(path, png_bytes(state))
