"""Snapshots and animations drawn from recorded trajectories."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from swarmtag.errors import ConfigError
from swarmtag.policy import Urgency
from swarmtag.sim import Mode, Scenario, simulate
from swarmtag.sim.config.profiles import load_profile
from swarmtag.sim.outputs.picture import Picture, draws_ranges
from swarmtag.sim.outputs.render import animate, default_snapshot_tick, snapshot
from swarmtag.tag import TagStatus

SIZE = (594, 616)
"""Pixels (width, height) of a square arena's picture: 5.4 x 5.6 inches at 110 dpi."""


def record(scenario: Scenario, **options):
    result = simulate(scenario, Urgency(alpha=0.7), record=True, **options)
    assert result.trajectories is not None
    return result.trajectories


@pytest.fixture(scope="module")
def traj():
    """The disc model (the base world), runs 5 and 6 of seed 3."""
    return record(Scenario(ticks=300), seed=3, runs=2, run_offset=5)


@pytest.fixture(scope="module")
def split():
    """Split perception (paper-sim): camera and radio ranges drawn around each robot."""
    return record(load_profile("paper-sim").scenario({"ticks": 400}), seed=1, runs=1)


def frames_of(path) -> list[np.ndarray]:
    with Image.open(path) as movie:
        frames = []
        for k in range(movie.n_frames):
            movie.seek(k)
            frames.append(np.asarray(movie.convert("RGB")).astype(np.int16))
        return frames


def full_redraw(picture: Picture, index: int) -> np.ndarray:
    """Tick ``index`` drawn the plain way: the whole figure, as a snapshot draws it."""
    picture.show(index)
    picture.figure.canvas.draw()
    return np.asarray(picture.figure.canvas.buffer_rgba())[:, :, :3].astype(np.int16)


def pixel(picture: Picture, height: int, x: float, y: float) -> tuple[int, int]:
    """The (row, column) of the image where data point (x, y) lies."""
    px, py = picture.axes.transData.transform((x, y))
    return int(height - py), int(px)


def test_default_tick_shows_the_most_carriers_being_pursued_or_carried(traj):
    tick = default_snapshot_tick(traj, 6)
    modes, targets = traj.robot_mode[1], traj.robot_target[1]
    busy = (modes >= Mode.PREDOCK) & (modes <= Mode.RELEASE) & (targets >= 0)
    engaged = np.array([len(set(targets[t][busy[t]].tolist())) for t in range(len(modes))])
    assert engaged[tick] == engaged.max() >= 2
    assert tick == int(np.flatnonzero(engaged == engaged.max())[0])  # earliest on ties


def test_snapshot_writes_a_png_at_the_asked_tick(traj, tmp_path):
    path = tmp_path / "s.png"
    assert snapshot(traj, path, run=5, tick=0) == 0
    with Image.open(path) as image:
        assert image.format == "PNG"
        assert image.size == SIZE


@pytest.mark.parametrize(
    ("kwargs", "words"), [({"run": 0}, "run: 0"), ({"run": 5, "tick": 301}, "tick: 301")]
)
def test_snapshot_refuses_what_was_not_recorded(traj, tmp_path, kwargs, words):
    with pytest.raises(ConfigError, match=words):
        snapshot(traj, tmp_path / "s.png", **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_snapshot_draws_each_carrier_robot_and_area_where_it_is(traj, tmp_path):
    """Key pixels of the published style: urgency faces, grey when not awaiting, blue robots."""
    from matplotlib import colormaps

    tick = snapshot(traj, tmp_path / "s.png", run=6)
    image = np.asarray(Image.open(tmp_path / "s.png").convert("RGB")).astype(int)
    geo, row = traj.geometry, 1
    with Picture(traj, row) as picture:
        picture.lay_out(tick)
        at = lambda x, y: tuple(image[pixel(picture, SIZE[1], x, y)])  # noqa: E731
        awaiting = 0
        for c in np.flatnonzero(traj.carrier_present[row, tick]):
            x, y = traj.carrier_pos[row, tick, c]
            corner = at(x - 0.35 * geo.carrier_size, y - 0.35 * geo.carrier_size)  # off the digit
            if traj.carrier_status[row, tick, c] == TagStatus.AWAITING_PICKUP:
                u = int(traj.carrier_urgency[row, tick, c])
                face = colormaps["YlOrRd"](0.15 + 0.85 * u / 9)[:3]
                assert corner == tuple(round(255 * v) for v in face)
                awaiting += 1
            elif not np.any(np.hypot(*(traj.robot_pos[row, tick] - (x, y)).T) < geo.carrier_size):
                assert corner == (209, 209, 209)  # 0.82 grey, unless a robot sits on it
        assert awaiting >= 1
        for r, (x, y) in enumerate(traj.robot_pos[row, tick]):
            hx, hy = traj.robot_heading[row, tick, r]
            red, green, blue = at(x - 0.5 * geo.robot_radius * hx, y - 0.5 * geo.robot_radius * hy)
            assert blue > red + 80  # tab:blue at alpha 0.9, behind the heading tick
            assert blue > green + 30
        for left, right, tint in (
            (0.0, geo.pickup_right, (219, 233, 246)),  # #dbe9f6
            (geo.pickup_right, geo.dropoff_left, (255, 255, 255)),
            (geo.dropoff_left, geo.arena, (223, 240, 216)),  # #dff0d8
        ):
            assert at(*clear_point(traj, row, tick, left, right)) == tint
        assert image[2, 2].tolist() == [255, 255, 255]  # the figure's white margin


def clear_point(traj, row: int, tick: int, left: float, right: float) -> tuple[float, float]:
    """A point of the strip ``left <= x <= right`` clear of every body, range and dashed line."""
    geo = traj.geometry
    bodies = np.concatenate([traj.robot_pos[row, tick], traj.carrier_pos[row, tick]])
    awaiting = traj.carrier_status[row, tick] == TagStatus.AWAITING_PICKUP
    rings = traj.carrier_pos[row, tick][awaiting & traj.carrier_present[row, tick]]
    chases = [
        (traj.robot_pos[row, tick, r], traj.carrier_pos[row, tick, target])
        for r, target in enumerate(traj.robot_target[row, tick].tolist())
        if target >= 0 and traj.robot_mode[row, tick, r] in (Mode.PREDOCK, Mode.DOCK, Mode.CENTRE)
    ]
    for x in np.linspace(left + 0.1, right - 0.1, 8):
        for y in np.linspace(0.1, geo.extent_y - 0.3, 12):  # below the area labels
            point = np.array([x, y])
            if np.hypot(*(bodies - point).T).min() < 0.35:
                continue
            ring_gaps = np.abs(np.hypot(*(rings - point).T) - geo.detection_radius)
            if ring_gaps.size and ring_gaps.min() < 0.08:
                continue
            if any(_distance_to_segment(point, a, b) < 0.08 for a, b in chases):
                continue
            return float(x), float(y)
    raise AssertionError("no clear point")  # pragma: no cover


def _distance_to_segment(p, a, b) -> float:
    ab = b - a
    t = 0.0 if not ab.any() else float(np.clip(np.dot(p - a, ab) / np.dot(ab, ab), 0.0, 1.0))
    return float(np.hypot(*(p - (a + t * ab))))


def test_animation_frames_cover_the_run(traj, tmp_path):
    path = tmp_path / "a.gif"
    frames = animate(traj, path, run=5, every=50)
    end = traj.ended_at[0] if traj.ended_at[0] >= 0 else traj.ticks
    assert frames == len(range(0, int(end) + 1, 50)) + (int(end) % 50 != 0)
    with Image.open(path) as movie:
        assert movie.n_frames == frames
        assert movie.size == SIZE
        assert movie.info["loop"] == 0
        durations = []
        for k in range(frames):
            movie.seek(k)
            durations.append(movie.info["duration"])
        assert durations == [100] * frames  # fps 10


@pytest.mark.parametrize("which", ["traj", "split"])
def test_blitted_frames_are_the_full_redraws_pixel_for_pixel(which, request):
    """Drawing only the moving artists over the kept background changes nothing."""
    recorded = request.getfixturevalue(which)
    indices = list(range(0, recorded.ticks + 1, 40))
    with Picture(recorded, 0) as picture:
        picture.lay_out(0)
        # in two passes, as animate draws its palette's samples first
        passes = [*picture.frames(indices[::3]), *picture.frames(indices[1::3] + indices[2::3])]
        order = indices[::3] + indices[1::3] + indices[2::3]
        by_index = dict(zip(order, passes, strict=True))
        blitted = [by_index[i][:, :, :3].astype(np.int16) for i in indices]
        for index, frame in zip(indices, blitted, strict=True):
            np.testing.assert_array_equal(frame, full_redraw(picture, index))
    assert len({f.tobytes() for f in blitted}) == len(indices)  # every tick looks different


@pytest.mark.first
def test_gif_frames_are_the_full_redraws_through_one_palette(split, tmp_path):
    path = tmp_path / "a.gif"
    count = animate(split, path, every=50)
    gif = frames_of(path)
    with Image.open(path) as movie:
        palette = {tuple(rgb) for rgb in np.reshape(movie.getpalette() or [], (-1, 3)).tolist()}
    ticks = [*range(0, split.ticks + 1, 50)]
    ticks += [] if ticks[-1] == split.ticks else [split.ticks]
    assert len(gif) == count == len(ticks)
    with Picture(split, 0) as picture:
        picture.lay_out(0)
        for tick, frame in zip(ticks, gif, strict=True):
            exact = full_redraw(picture, tick)
            flat = np.array([tuple(p) in palette for p in exact.reshape(-1, 3).tolist()])
            assert flat.mean() > 0.975  # fills, text and most edges (98.5 % here) are exact
            np.testing.assert_array_equal(frame.reshape(-1, 3)[flat], exact.reshape(-1, 3)[flat])
            assert np.abs(frame - exact).mean() < 0.1  # the rest: near colours (0.03 here)


def test_gif_frames_change_where_robots_moved_and_nowhere_outside_the_arena(traj, tmp_path):
    path = tmp_path / "a.gif"
    animate(traj, path, run=5, every=25)
    gif = frames_of(path)
    geo = traj.geometry
    with Picture(traj, 0) as picture:
        picture.lay_out(0)
        (left, bottom), (right, top) = picture.axes.transData.transform(
            [(0, 0), (geo.arena, geo.extent_y)]
        )
        title_bottom = SIZE[1] - picture.axes.title.get_window_extent().y0
        moved = 0
        for k in range(len(gif) - 1):
            tick = 25 * k
            for r, (x, y) in enumerate(traj.robot_pos[0, tick]):
                step = np.hypot(*(traj.robot_pos[0, tick + 25, r] - (x, y)))
                if step > 3 * geo.robot_radius:
                    hx, hy = traj.robot_heading[0, tick, r]
                    where = pixel(picture, SIZE[1], x - 0.5 * geo.robot_radius * hx,
                                  y - 0.5 * geo.robot_radius * hy)  # fmt: skip
                    assert gif[k][where].tolist() != gif[k + 1][where].tolist()
                    moved += 1
        assert moved >= 3
    outside = np.ones(gif[0].shape[:2], dtype=bool)
    outside[: int(title_bottom) + 4] = False  # the title's tick changes (glyphs reach lower)
    rows = slice(int(SIZE[1] - top) - 2, int(SIZE[1] - bottom) + 3)
    outside[rows, int(left) - 2 : int(right) + 3] = False  # the arena
    for frame in gif[1:]:  # ticks, tick labels, axis labels, the key: still
        np.testing.assert_array_equal(frame[outside], gif[0][outside])
    assert not np.array_equal(gif[0][: int(title_bottom)], gif[1][: int(title_bottom)])


def test_same_seed_same_gif_bytes(traj, tmp_path):
    again = record(Scenario(ticks=300), seed=3, runs=2, run_offset=5)
    animate(traj, tmp_path / "a.gif", run=6, every=30)
    animate(again, tmp_path / "b.gif", run=6, every=30)
    assert (tmp_path / "a.gif").read_bytes() == (tmp_path / "b.gif").read_bytes()


def test_animation_format_checked_first(traj, tmp_path):
    with pytest.raises(ConfigError, match=r"\.gif or \.mp4"):
        animate(traj, tmp_path / "a.avi", run=5)
    assert list(tmp_path.iterdir()) == []


def test_mp4_without_ffmpeg_says_how_to_get_it_and_writes_nothing(traj, tmp_path, monkeypatch):
    import sys

    from matplotlib.animation import FFMpegWriter

    monkeypatch.setattr(FFMpegWriter, "isAvailable", classmethod(lambda cls: False))
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)  # importing it fails
    with pytest.raises(ConfigError, match="MP4 animations need ffmpeg"):
        animate(traj, tmp_path / "a.mp4", run=5)
    assert list(tmp_path.iterdir()) == []


def test_mp4_has_every_frame_where_ffmpeg_is_installed(traj, tmp_path):
    import subprocess

    from swarmtag.sim.outputs.movie import require_ffmpeg

    try:
        ffmpeg = require_ffmpeg()
    except ConfigError:
        pytest.skip("no ffmpeg here")
    frames = animate(traj, tmp_path / "a.mp4", run=5, every=50)
    decoded = subprocess.run(
        [ffmpeg, "-v", "error", "-i", str(tmp_path / "a.mp4"), "-f", "rawvideo",
         "-pix_fmt", "rgb24", "-"],
        capture_output=True, check=True,
    ).stdout  # fmt: skip
    even = (SIZE[0] + SIZE[0] % 2) * (SIZE[1] + SIZE[1] % 2) * 3  # padded to even sides
    assert len(decoded) == frames * even


@pytest.mark.parametrize(("robots", "drawn"), [(12, True), (13, False)])
def test_perception_ranges_are_drawn_around_a_dozen_robots_at_most(robots, drawn, tmp_path):
    # split perception: one range pair per robot
    scenario = load_profile("paper-sim").scenario({"robots": robots, "carriers": 7, "ticks": 5})
    recorded = record(scenario, seed=0, runs=1)
    assert draws_ranges(recorded) is drawn
    snapshot(recorded, tmp_path / "crowd.png", tick=1)
    assert (tmp_path / "crowd.png").stat().st_size > 0
