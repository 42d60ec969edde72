"""GIF palettes and frames: exact flat colours, nearest edges, one palette, no dither."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from swarmtag.sim.outputs.movie import (
    PALETTE_SAMPLES,
    GifDrawing,
    gif_indices,
    gif_palette,
    write_gif,
    write_gif_drawn,
)

WHITE, TINT, BLUE, RED = (255, 255, 255), (219, 233, 246), (31, 119, 180), (200, 20, 30)


def canvas(*fills: tuple[tuple[int, int, int], int]) -> np.ndarray:
    """One row of opaque RGBA pixels: each colour repeated its count of times."""
    return np.array([[(*c, 255) for c, n in fills for _ in range(n)]], dtype=np.uint8)


def test_the_palette_holds_kept_then_frequent_colours_exactly():
    frame = canvas((WHITE, 500), (TINT, 300), (BLUE, 40))
    palette = gif_palette([frame], keep=[RED])
    assert [tuple(c) for c in palette[:4].tolist()] == [RED, WHITE, TINT, BLUE]
    assert len(palette) == len({tuple(c) for c in palette.tolist()}) <= 255


def test_rare_colours_still_get_entries_near_them():
    """Thin translucent lines are rare pixels: the octree part of the palette covers them."""
    many = [(x, 255 - x, (7 * x) % 256) for x in range(256)]  # 256 colours, a few pixels each
    frame = canvas((WHITE, 100_000), *((c, 3) for c in many))
    palette = gif_palette([frame]).astype(int)
    nearest = np.sqrt(((np.array(many)[:, None, :] - palette[None]) ** 2).sum(axis=2)).min(axis=1)
    assert nearest.mean() < 12


def test_palette_colours_map_exactly_and_others_to_the_nearest():
    """Exact even among near-whites, where Pillow's own mapping (a coarse colour cube) slips."""
    near = (252, 252, 252)
    palette = np.array([near, WHITE, TINT, BLUE], dtype=np.uint8)
    frame = canvas((WHITE, 2), (TINT, 1), ((250, 250, 250), 1), ((40, 120, 170), 1), (near, 1))
    (indices,) = gif_indices([frame], palette)
    assert indices.tolist() == [[1, 1, 2, 0, 3, 0]]


def test_frames_must_be_rgba_bytes():
    with pytest.raises(ValueError, match=r"RGBA bytes"):
        next(gif_indices([np.zeros((2, 2, 3), dtype=np.uint8)], np.zeros((1, 3), dtype=np.uint8)))


def test_a_palette_of_more_than_255_colours_is_refused():
    with pytest.raises(ValueError, match="1 to 255"):
        next(gif_indices([canvas((WHITE, 1))], np.zeros((256, 3), dtype=np.uint8)))


def test_written_frames_read_back_exactly(tmp_path):
    frames = [np.full((6, 8, 4), (*WHITE, 255), dtype=np.uint8) for _ in range(3)]
    frames[1][2:4, 2:4, :3] = BLUE
    frames[2][0:2, 5:8, :3] = TINT
    palette = gif_palette(frames)
    write_gif(iter(frames), tmp_path / "m.gif", palette=palette, fps=5)
    with Image.open(tmp_path / "m.gif") as movie:
        assert movie.n_frames == 3
        for k, frame in enumerate(frames):
            movie.seek(k)
            assert movie.info["duration"] == 200
            np.testing.assert_array_equal(np.asarray(movie.convert("RGB")), frame[:, :, :3])


@pytest.mark.parametrize("count", [1, 2, 8, 9, 23])
def test_frames_drawn_samples_first_make_the_gif_of_the_frames_in_order(tmp_path, count):
    rng = np.random.default_rng(count)
    frames = []
    for k in range(count):
        frame = np.full((10, 12, 4), (*WHITE, 255), dtype=np.uint8)
        frame[k % 10, : 1 + k % 12, :3] = rng.integers(0, 256, 3)  # a line of its own colour
        frames.append(frame)
    gif = GifDrawing(str(tmp_path / "drawn.gif"), count, keep=(RED,), fps=4)
    order = gif.drawing_order()
    assert sorted(order) == list(range(count))
    assert order[: len(gif.sampled)] == list(gif.sampled)
    assert len(gif.sampled) == min(count, PALETTE_SAMPLES)
    assert {0, count - 1} <= set(gif.sampled)
    palette = gif_palette([frames[i] for i in gif.sampled], keep=[RED])
    write_gif(iter(frames), tmp_path / "in-order.gif", palette=palette, fps=4)
    expected = (tmp_path / "in-order.gif").read_bytes()
    gif.write(frames[i] for i in order)
    assert (tmp_path / "drawn.gif").read_bytes() == expected
    (tmp_path / "drawn.gif").unlink()
    write_gif_drawn(gif, (frames[i] for i in order))  # written in a forked process on Linux
    assert (tmp_path / "drawn.gif").read_bytes() == expected
