"""The E-ink picture (SPEC §2.4): 250 x 122, 1-bit, legible, deterministic."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from swarmtag.errors import ConfigError, FieldRangeError
from swarmtag.tag import TagState, TagStatus
from swarmtag.tag.eink import HEIGHT, WIDTH, png_bytes, render, save_png, status_label


def state(urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3, marker=12) -> TagState:
    return TagState(urgency=urgency, status=status, destination=destination, marker=marker)


def black(image) -> np.ndarray:
    """True where the pixel is black."""
    return ~np.asarray(image, dtype=bool)


def test_size_and_mode_are_the_panels():
    image = render(state())
    assert (WIDTH, HEIGHT) == (250, 122)
    assert image.size == (250, 122)
    assert image.mode == "1"
    values = set(np.unique(np.asarray(image.convert("L"))))
    assert values == {0, 255}  # black and white only: no grey from anti-aliasing


def test_png_on_disk_reads_back_as_1_bit(tmp_path):
    from PIL import Image

    path = tmp_path / "tag.png"
    save_png(state(), path)
    data = path.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    assert data[12:16] == b"IHDR"
    assert (data[24], data[25]) == (1, 0)  # bit depth 1, greyscale: a true 1-bit file
    with Image.open(path) as image:
        assert image.format == "PNG"
        assert image.size == (250, 122)
        assert image.mode == "1"
        assert np.array_equal(black(image), black(render(state())))
    assert [p.name for p in tmp_path.iterdir()] == ["tag.png"]  # no temporary left


@pytest.mark.parametrize(
    "other",
    [
        state(urgency=8),
        state(status=TagStatus.PICKED_UP),
        state(status=TagStatus.IDLE),
        state(destination=4),
        state(marker=13),
    ],
    ids=["urgency", "picked-up", "idle", "destination", "marker"],
)
def test_each_field_changes_the_picture(other):
    assert not np.array_equal(black(render(state())), black(render(other)))


def test_all_urgencies_and_statuses_give_distinct_pictures():
    pictures = {png_bytes(state(urgency=u, status=s)) for u in range(10) for s in TagStatus}
    assert len(pictures) == 30


def test_the_urgency_digit_is_large():
    for urgency in range(10):
        pixels = black(render(state(urgency=urgency)))
        region = pixels[17:90, 3:84]  # the urgency column, below its label, above the status bar
        rows = np.nonzero(region.any(axis=1))[0]
        columns = np.nonzero(region.any(axis=0))[0]
        height = rows.max() - rows.min() + 1
        assert height > HEIGHT // 2, (urgency, height)
        assert columns.max() - columns.min() + 1 >= 25  # even the narrow "1"
        assert region.sum() > 600  # a big block of black, not a hairline


def test_status_reads_white_on_a_black_bar():
    pixels = black(render(state()))
    bar = pixels[95:121, 1:249]
    assert bar.mean() > 0.6  # mostly black, with the white letters in it
    assert not bar.all()


def test_status_labels():
    assert status_label(state(status=TagStatus.AWAITING_PICKUP)) == "AWAITING PICKUP"
    assert status_label(state(status=TagStatus.PICKED_UP)) == "PICKED UP"
    assert status_label(state(status=TagStatus.IDLE)) == "IDLE"


def test_rendering_is_deterministic(tmp_path):
    first, second = tmp_path / "a.png", tmp_path / "b.png"
    save_png(state(urgency=9, marker=200), first)
    save_png(state(urgency=9, marker=200), second)
    assert first.read_bytes() == second.read_bytes() == png_bytes(state(urgency=9, marker=200))
    assert render(state()).tobytes() == render(state()).tobytes()


@pytest.mark.parametrize("bad", [None, (7, 1, 3, 12), b"\xff\xff\x07\x01\x03\x0c"])
def test_not_a_state_is_refused(bad):
    with pytest.raises(FieldRangeError, match="state: expected a TagState"):
        render(bad)


def test_missing_pillow_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "PIL", None)  # from PIL import ... now fails
    with pytest.raises(ConfigError, match=r"pip install 'swarmtag\[eink\]'"):
        render(state())
    with pytest.raises(ConfigError, match="eink"):
        png_bytes(state())


def test_missing_folder_is_an_error_and_leaves_nothing(tmp_path):
    with pytest.raises(FileNotFoundError):
        save_png(state(), tmp_path / "missing" / "tag.png")
    assert list(tmp_path.iterdir()) == []
