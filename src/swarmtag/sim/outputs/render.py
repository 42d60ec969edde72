"""Pictures of simulated runs: snapshots in the published figure's style, and animations.

Drawn from ``Trajectories`` alone: the arena in metres with axes, the
pick-up and drop-off areas shaded, carriers as squares showing their urgency
digit (coloured by urgency while AWAITING_PICKUP, grey otherwise), the
perception ranges dotted (disc model: a circle of radius R around every
carrier that can be heard; split model: each robot's camera range around it,
and its radio range dash-dotted where it falls inside the picture), robots
as circles with a heading tick, and a dashed line from each pursuing robot
to its chosen carrier. The figure is built once (``picture.Picture``);
an animation redraws only the moving bodies per frame and writes the GIF
with Pillow (in a forked process beside the drawing, where it can) or the
MP4 through ffmpeg (``movie``). Matplotlib is imported
lazily (the ``plot`` extra).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Final

import numpy as np

from swarmtag._atomic import atomic_path
from swarmtag.errors import ConfigError
from swarmtag.sim.model.state import Mode
from swarmtag.sim.outputs.movie import GifDrawing, require_ffmpeg, write_gif_drawn, write_mp4
from swarmtag.sim.outputs.picture import PURSUING, Picture
from swarmtag.sim.outputs.trajectories import Trajectories

__all__ = ["ANIMATION_FORMATS", "animate", "default_snapshot_tick", "snapshot"]

ANIMATION_FORMATS: Final = (".gif", ".mp4")
_LOADED: Final = (Mode.LIFT, Mode.TRANSPORT, Mode.RELEASE)


def _check_run(traj: Trajectories, run: int) -> int:
    matches = np.flatnonzero(traj.run_ids == run)
    if matches.size == 0:
        shown = ", ".join(map(str, traj.run_ids[:10].tolist()))
        msg = f"run: {run} was not recorded (recorded runs: {shown})"
        raise ConfigError(msg)
    return int(matches[0])


def default_snapshot_tick(traj: Trajectories, run: int) -> int:
    """The tick that shows most: most different carriers pursued or carried, earliest on ties.

    One still picture should show the swarm at work: counting the distinct
    carriers that robots pursue (pre-dock, dock, centre) or carry (lift,
    transport, release) rather than busy robots skips the first ticks, when
    every robot may head for the same carrier, and the earliest of the ties
    keeps the choice reproducible and early in the run.
    """
    row = _check_run(traj, run)
    mode = traj.robot_mode[row]
    target = traj.robot_target[row].astype(np.int64)
    busy = np.isin(mode, np.array((*PURSUING, *_LOADED), dtype=mode.dtype)) & (target >= 0)
    carriers = traj.carrier_pos.shape[2]
    engaged = np.zeros((mode.shape[0], carriers + 1), dtype=bool)
    ticks = np.arange(mode.shape[0])[:, None]
    engaged[ticks, np.where(busy, target, carriers)] = True
    shown = engaged[:, :carriers].sum(axis=1)
    return int(traj.time[int(np.argmax(shown))])


def snapshot(
    traj: Trajectories, path: str | os.PathLike[str], *, run: int = 0, tick: int | None = None
) -> int:
    """Draw ``run`` at ``tick`` (default: ``default_snapshot_tick``) to a PNG; return the tick."""
    row = _check_run(traj, run)
    chosen = default_snapshot_tick(traj, run) if tick is None else tick
    if not 0 <= chosen <= traj.ticks:
        msg = f"tick: {chosen} is outside the recorded ticks 0-{traj.ticks}"
        raise ConfigError(msg)
    with Picture(traj, row) as picture:
        picture.lay_out(chosen)
        with atomic_path(path) as temp:
            picture.figure.savefig(temp, format="png")
    return chosen


def animate(
    traj: Trajectories,
    path: str | os.PathLike[str],
    *,
    run: int = 0,
    every: int | None = None,
    fps: int = 10,
) -> int:
    """Write an animation of ``run`` (one frame every ``every`` ticks); return the frame count.

    ``every`` defaults to one frame per second of robot time (10 ticks of
    0.1 s, 52 of the paper-sim profile's 0.01934 s); the run's last tick is
    always a frame. ``.gif`` uses Pillow (comes with matplotlib), one palette
    for all frames; ``.mp4`` needs an ffmpeg executable (on the PATH, or
    from ``pip install imageio-ffmpeg``).
    """
    if every is None:
        every = max(1, round(1.0 / traj.geometry.tick_seconds))
    suffix = Path(path).suffix.lower()
    if suffix not in ANIMATION_FORMATS:
        msg = f"animation: {os.fspath(path)!r} must end in .gif or .mp4"
        raise ConfigError(msg)
    if every < 1 or fps < 1:
        msg = f"animation: every ({every}) and fps ({fps}) must be integers >= 1"
        raise ConfigError(msg)
    if suffix == ".mp4":
        require_ffmpeg()  # before drawing anything
    row = _check_run(traj, run)
    end = int(traj.ended_at[row]) if traj.ended_at[row] >= 0 else traj.ticks
    frames = list(range(0, end + 1, every))
    if frames[-1] != end:
        frames.append(end)
    with Picture(traj, row) as picture:
        picture.lay_out(frames[0])  # lay out around a drawn frame, labels included
        with atomic_path(path) as temp:
            if suffix == ".gif":
                keep = tuple(picture.face_colours())
                gif = GifDrawing(os.fspath(temp), len(frames), keep, fps)
                order = [frames[i] for i in gif.drawing_order()]
                write_gif_drawn(gif, picture.frames(order))
            else:
                width, height = picture.figure.canvas.get_width_height()
                write_mp4(picture.frames(frames), temp, size=(width, height), fps=fps)
    return len(frames)
