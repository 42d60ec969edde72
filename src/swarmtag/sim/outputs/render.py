"""Pictures of simulated runs: snapshots in the published figure's style, and animations.

Drawn from ``Trajectories`` alone: the arena in metres with axes, the
pick-up and drop-off areas shaded, carriers as squares showing their urgency
digit (coloured by urgency while AWAITING_PICKUP, grey otherwise), the
perception ranges dotted (disc model: a circle of radius R around every
carrier that can be heard; split model: each robot's camera range around it,
and its radio range dash-dotted where it falls inside the picture), robots
as circles with a heading tick, and a dashed line from each pursuing robot
to its chosen carrier. Matplotlib is imported lazily (the ``plot`` extra).
"""

# Matplotlib is an optional extra: every import of it is deferred to first use.
# ruff: noqa: PLC0415

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from swarmtag._atomic import atomic_path
from swarmtag._plotting import pyplot
from swarmtag.errors import ConfigError
from swarmtag.sim.model.state import Mode
from swarmtag.sim.outputs.trajectories import Geometry, Trajectories
from swarmtag.tag import TagStatus

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

__all__ = ["ANIMATION_FORMATS", "animate", "default_snapshot_tick", "snapshot"]

ANIMATION_FORMATS: Final = (".gif", ".mp4")
_PURSUING: Final = (Mode.PREDOCK, Mode.DOCK, Mode.CENTRE)
_LOADED: Final = (Mode.LIFT, Mode.TRANSPORT, Mode.RELEASE)
_PICKUP_COLOUR: Final = "#dbe9f6"
_DROPOFF_COLOUR: Final = "#dff0d8"
_SHELF_COLOUR: Final = "0.55"
_RANGES_UP_TO: Final = 12
"""Most robots (or carriers, disc perception) whose perception ranges a picture draws."""
_ROBOT_COLOUR: Final = "tab:blue"
_BROKEN_COLOUR: Final = "0.35"


def _check_run(traj: Trajectories, run: int) -> int:
    matches = np.flatnonzero(traj.run_ids == run)
    if matches.size == 0:
        shown = ", ".join(map(str, traj.run_ids[:10].tolist()))
        msg = f"run: {run} was not recorded (recorded runs: {shown})"
        raise ConfigError(msg)
    return int(matches[0])


def default_snapshot_tick(traj: Trajectories, run: int) -> int:
    """The tick that shows most: most different carriers pursued or carried, earliest on ties.

    Counting carriers rather than robots shows the swarm spread over its
    work rather than the first tick, when all robots may head for one carrier.
    """
    row = _check_run(traj, run)
    mode = traj.robot_mode[row]
    target = traj.robot_target[row].astype(np.int64)
    busy = np.isin(mode, np.array((*_PURSUING, *_LOADED), dtype=mode.dtype)) & (target >= 0)
    carriers = traj.carrier_pos.shape[2]
    engaged = np.zeros((mode.shape[0], carriers + 1), dtype=bool)
    ticks = np.arange(mode.shape[0])[:, None]
    engaged[ticks, np.where(busy, target, carriers)] = True
    shown = engaged[:, :carriers].sum(axis=1)
    return int(traj.time[int(np.argmax(shown))])


def _draw_floor(ax: Axes, geo: Geometry) -> None:
    """A warehouse map: shelves dark, pick-up and drop-off cells tinted, areas numbered."""
    from matplotlib.patches import Rectangle

    lines = geo.floor_text.splitlines()
    cell, rows = geo.floor_cell, len(lines)
    labelled: set[str] = set()
    for line, text in enumerate(lines):
        y = (rows - 1 - line) * cell
        for column, char in enumerate(text):
            colour = {"#": _SHELF_COLOUR, "P": _PICKUP_COLOUR}.get(
                char, _DROPOFF_COLOUR if char.isdigit() else None
            )
            if colour is None:
                continue
            ax.add_patch(Rectangle((column * cell, y), cell, cell, color=colour, zorder=0))
            if char.isdigit() and char not in labelled:
                labelled.add(char)
                ax.text((column + 0.5) * cell, y + 0.5 * cell, char, ha="center", va="center",
                        fontsize=7, color="0.3", zorder=0)  # fmt: skip


def _draw(ax: Axes, traj: Trajectories, row: int, index: int) -> None:
    from matplotlib import colormaps
    from matplotlib.patches import Circle, Rectangle

    geo = traj.geometry
    ax.clear()
    ax.set_xlim(0, geo.arena)
    ax.set_ylim(0, geo.extent_y)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if geo.floor_text:
        _draw_floor(ax, geo)
    else:
        for left, right, colour, label in (
            (0.0, geo.pickup_right, _PICKUP_COLOUR, "pick-up"),
            (geo.dropoff_left, geo.arena, _DROPOFF_COLOUR, "drop-off"),
        ):
            ax.add_patch(Rectangle((left, 0), right - left, geo.arena, color=colour, zorder=0))
            ax.text((left + right) / 2, geo.arena * 0.99, label, ha="center", va="top", fontsize=8)
    cmap = colormaps["YlOrRd"]
    half = geo.carrier_size / 2
    status = traj.carrier_status[row, index]
    urgency = traj.carrier_urgency[row, index]
    carrier_pos = traj.carrier_pos[row, index]
    for c in np.flatnonzero(traj.carrier_present[row, index]):
        x, y = carrier_pos[c]
        u = int(urgency[c])
        awaiting = status[c] == TagStatus.AWAITING_PICKUP
        if awaiting and geo.radio_range == 0.0 and _draws_ranges(traj):
            ax.add_patch(
                Circle((x, y), geo.detection_radius, fill=False, linestyle=":", linewidth=0.8,
                       edgecolor="0.45", zorder=1)
            )  # fmt: skip
        face = cmap(0.15 + 0.85 * u / 9) if awaiting else "0.82"
        ax.add_patch(
            Rectangle((x - half, y - half), geo.carrier_size, geo.carrier_size, facecolor=face,
                      edgecolor="black", linewidth=1.0, zorder=3)
        )  # fmt: skip
        ax.text(x, y, str(u), ha="center", va="center", fontsize=9, fontweight="bold",
                color="white" if awaiting and u >= 7 else "black", zorder=4)  # fmt: skip
    robot_pos = traj.robot_pos[row, index]
    for r, (x, y) in enumerate(robot_pos):
        mode = int(traj.robot_mode[row, index, r])
        target = int(traj.robot_target[row, index, r])
        if target >= 0 and mode in _PURSUING:
            tx, ty = carrier_pos[target]
            ax.plot([x, tx], [y, ty], color=_ROBOT_COLOUR, linewidth=1.0, linestyle="--", zorder=2)
        colour = _BROKEN_COLOUR if mode == Mode.BROKEN else _ROBOT_COLOUR
        if geo.radio_range > 0.0 and _draws_ranges(traj):
            for radius, style in ((geo.detection_radius, ":"), (geo.radio_range, "-.")):
                ax.add_patch(
                    Circle((x, y), radius, fill=False, linestyle=style, linewidth=0.8,
                           edgecolor=_ROBOT_COLOUR, alpha=0.6, zorder=1)
                )  # fmt: skip
        ax.add_patch(Circle((x, y), geo.robot_radius, facecolor=colour, edgecolor="black",
                            linewidth=1.0, alpha=0.9, zorder=5))  # fmt: skip
        hx, hy = traj.robot_heading[row, index, r]
        ax.plot([x, x + hx * geo.robot_radius], [y, y + hy * geo.robot_radius], color="white",
                linewidth=1.5, zorder=6)  # fmt: skip
    tick = int(traj.time[index])
    ax.set_title(
        f"{traj.condition}, run {int(traj.run_ids[row])}: tick {tick} "
        f"({tick * geo.tick_seconds:.1f} s)",
        fontsize=9,
    )


def _draws_ranges(traj: Trajectories) -> bool:
    """Whether the perception ranges are drawn: not around more than ``_RANGES_UP_TO`` bodies."""
    bodies = (
        traj.robot_pos.shape[2] if traj.geometry.radio_range > 0.0 else traj.carrier_pos.shape[2]
    )
    return bool(bodies <= _RANGES_UP_TO)


def _figure(traj: Trajectories) -> tuple[Any, Figure, Axes]:
    plt = pyplot()
    geo = traj.geometry
    aspect = geo.extent_y / geo.arena
    width = 5.4 if aspect >= 0.8 else 8.0
    fig, ax = plt.subplots(figsize=(width, 0.2 + width * aspect), dpi=110)
    ranges = (
        f"dotted: camera range {geo.detection_radius:g} m, dash-dot: radio {geo.radio_range:g} m"
        if geo.radio_range > 0.0
        else f"dotted: detection range R = {geo.detection_radius:g} m"
    )
    if not _draws_ranges(traj):
        ranges = f"perception ranges not drawn for more than {_RANGES_UP_TO} bodies"
    fig.text(
        0.5, 0.01,
        f"robots: circles (dashed: chosen carrier)   carriers: squares with urgency\n{ranges}",
        ha="center", fontsize=7, color="0.3",
    )  # fmt: skip
    return plt, fig, ax


def snapshot(
    traj: Trajectories, path: str | os.PathLike[str], *, run: int = 0, tick: int | None = None
) -> int:
    """Draw ``run`` at ``tick`` (default: ``default_snapshot_tick``) to a PNG; return the tick."""
    row = _check_run(traj, run)
    chosen = default_snapshot_tick(traj, run) if tick is None else tick
    if not 0 <= chosen <= traj.ticks:
        msg = f"tick: {chosen} is outside the recorded ticks 0-{traj.ticks}"
        raise ConfigError(msg)
    plt, fig, ax = _figure(traj)
    try:
        _draw(ax, traj, row, chosen)
        fig.tight_layout(rect=(0, 0.03, 1, 1))
        with atomic_path(path) as temp:
            fig.savefig(temp, format="png")
    finally:
        plt.close(fig)
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
    0.1 s, 52 of the paper-sim profile's 0.01934 s). ``.gif`` uses Pillow
    (comes with matplotlib); ``.mp4`` needs an ffmpeg executable, e.g. from
    ``pip install imageio-ffmpeg``.
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
    row = _check_run(traj, run)
    end = int(traj.ended_at[row]) if traj.ended_at[row] >= 0 else traj.ticks
    frames = list(range(0, end + 1, every))
    if frames[-1] != end:
        frames.append(end)
    plt, fig, ax = _figure(traj)
    from matplotlib.animation import FFMpegWriter, FuncAnimation, PillowWriter

    writer: Any
    if suffix == ".gif":
        writer = PillowWriter(fps=fps)
    else:
        writer = FFMpegWriter(fps=fps, codec="h264")
        if not FFMpegWriter.isAvailable():
            plt.close(fig)
            msg = "MP4 animations need ffmpeg: pip install imageio-ffmpeg, or write a .gif"
            raise ConfigError(msg)
    movie = FuncAnimation(
        fig, lambda i: _draw(ax, traj, row, frames[i]), frames=len(frames), blit=False
    )
    try:
        _draw(ax, traj, row, frames[0])  # lay out around a drawn frame, labels included
        fig.tight_layout(rect=(0, 0.03, 1, 1))
        with atomic_path(path) as temp:
            staged = temp.with_suffix(suffix)  # the writers pick the format by extension
            try:
                movie.save(str(staged), writer=writer)
                staged.replace(temp)
            finally:
                staged.unlink(missing_ok=True)
    finally:
        plt.close(fig)
    return len(frames)
