"""One recorded run as a matplotlib figure: the arena drawn once, the moving bodies per tick.

``Picture`` builds the still parts (axes, labels, floor or areas, the key
below the axes) once and one artist per robot and carrier part; ``show``
only moves and recolours those artists, so a snapshot is one ``show`` and a
``savefig``, and an animation's frames are blitted (``frames``): the still
background is rendered once and copied back before each frame's moving
artists are drawn over it, in the order a full redraw would use; texts
that did not change are copied from where they were drawn (``_Stamps``),
and the title's still part from its tick (``_SplitTitle``). Frames stay
pixel-identical to full redraws at a fraction of their cost. Matplotlib is
imported lazily (the ``plot`` extra).
"""

# Matplotlib is an optional extra: every import of it is deferred to first use.
# ruff: noqa: PLC0415

from __future__ import annotations

from collections.abc import Iterable, Iterator
from operator import methodcaller
from typing import TYPE_CHECKING, Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._plotting import pyplot
from swarmtag.sim.model.state import Mode
from swarmtag.sim.outputs.trajectories import Geometry, Trajectories
from swarmtag.tag import TagStatus

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Rectangle
    from matplotlib.text import Text

__all__ = ["PURSUING", "RANGES_UP_TO", "Picture", "draws_ranges"]

PURSUING: Final = (Mode.PREDOCK, Mode.DOCK, Mode.CENTRE)
"""Modes in which a robot heads for its chosen carrier (drawn as a dashed line to it)."""
_PICKUP_COLOUR: Final = "#dbe9f6"
_DROPOFF_COLOUR: Final = "#dff0d8"
_SHELF_COLOUR: Final = "0.55"
_IDLE_CARRIER_COLOUR: Final = "0.82"
RANGES_UP_TO: Final = 12
"""Most robots (or carriers, disc perception) whose perception ranges a picture draws."""
_ROBOT_COLOUR: Final = "tab:blue"
_BROKEN_COLOUR: Final = "0.35"
_LAYOUT: Final = (0.0, 0.03, 1.0, 1.0)
"""``tight_layout``'s rectangle: the bottom 3 % holds the key below the axes."""


def draws_ranges(traj: Trajectories) -> bool:
    """Whether the perception ranges are drawn: not around more than ``RANGES_UP_TO`` bodies."""
    bodies = (
        traj.robot_pos.shape[2] if traj.geometry.radio_range > 0.0 else traj.carrier_pos.shape[2]
    )
    return bool(bodies <= RANGES_UP_TO)


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


def _draw_arena(ax: Axes, geo: Geometry) -> None:
    """The still parts inside the axes: limits, axis labels, the floor map or the two areas."""
    from matplotlib.patches import Rectangle

    ax.set_xlim(0, geo.arena)
    ax.set_ylim(0, geo.extent_y)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if geo.floor_text:
        _draw_floor(ax, geo)
        return
    for left, right, colour, label in (
        (0.0, geo.pickup_right, _PICKUP_COLOUR, "pick-up"),
        (geo.dropoff_left, geo.arena, _DROPOFF_COLOUR, "drop-off"),
    ):
        ax.add_patch(Rectangle((left, 0), right - left, geo.arena, color=colour, zorder=0))
        ax.text((left + right) / 2, geo.arena * 0.99, label, ha="center", va="top", fontsize=8)


def _key(traj: Trajectories) -> str:
    """The two lines below the axes that say what the shapes and line styles mean."""
    geo = traj.geometry
    ranges = (
        f"dotted: camera range {geo.detection_radius:g} m, dash-dot: radio {geo.radio_range:g} m"
        if geo.radio_range > 0.0
        else f"dotted: detection range R = {geo.detection_radius:g} m"
    )
    if not draws_ranges(traj):
        ranges = f"perception ranges not drawn for more than {RANGES_UP_TO} bodies"
    return f"robots: circles (dashed: chosen carrier)   carriers: squares with urgency\n{ranges}"


class _Carrier:
    """One carrier's artists: its detection circle (disc model), square and urgency digit."""

    def __init__(self, ax: Axes, geo: Geometry, *, ring: bool) -> None:
        from matplotlib.patches import Circle, Rectangle

        self.ring: Circle | None = None
        if ring:
            self.ring = Circle((0, 0), geo.detection_radius, fill=False, linestyle=":",
                               linewidth=0.8, edgecolor="0.45", zorder=1)  # fmt: skip
            ax.add_patch(self.ring)
        self.square: Rectangle = Rectangle((0, 0), geo.carrier_size, geo.carrier_size,
                                           edgecolor="black", linewidth=1.0, zorder=3)  # fmt: skip
        ax.add_patch(self.square)
        self.digit: Text = ax.text(0, 0, "", ha="center", va="center", fontsize=9,
                                   fontweight="bold", zorder=4)  # fmt: skip

    def artists(self) -> list[Artist]:
        """This carrier's artists, in the order they were added to the axes."""
        return [a for a in (self.ring, self.square, self.digit) if a is not None]


class _Robot:
    """One robot's artists: the dashed line to its carrier, its ranges, body and heading tick."""

    def __init__(self, ax: Axes, geo: Geometry, *, ranges: bool) -> None:
        from matplotlib.patches import Circle

        (self.chase,) = ax.plot([], [], color=_ROBOT_COLOUR, linewidth=1.0, linestyle="--",
                                zorder=2)  # fmt: skip
        self.ranges: list[Circle] = []
        if ranges:
            for radius, style in ((geo.detection_radius, ":"), (geo.radio_range, "-.")):
                circle = Circle((0, 0), radius, fill=False, linestyle=style, linewidth=0.8,
                                edgecolor=_ROBOT_COLOUR, alpha=0.6, zorder=1)  # fmt: skip
                ax.add_patch(circle)
                self.ranges.append(circle)
        self.body: Circle = Circle((0, 0), geo.robot_radius, edgecolor="black", linewidth=1.0,
                                   alpha=0.9, zorder=5)  # fmt: skip
        ax.add_patch(self.body)
        self.heading: Line2D
        (self.heading,) = ax.plot([], [], color="white", linewidth=1.5, zorder=6)

    def artists(self) -> list[Artist]:
        """This robot's artists, in the order they were added to the axes."""
        return [self.chase, *self.ranges, self.body, self.heading]


class Picture:
    """Run ``row`` of ``traj`` as a figure whose moving artists ``show`` sets to one tick.

    Use as a context manager (the figure is closed on exit). Artists are made
    in the order a per-tick drawing would add them (per carrier, then per
    robot), so bodies overlap exactly as in one drawn from scratch.
    """

    def __init__(self, traj: Trajectories, row: int) -> None:
        """Make the figure, the still arena and one artist per moving part (placed by ``show``)."""
        from matplotlib import colormaps

        self._traj, self._row = traj, row
        geo = traj.geometry
        self._plt: Any = pyplot()
        aspect = geo.extent_y / geo.arena
        width = 5.4 if aspect >= 0.8 else 8.0
        self.figure: Figure
        self.figure, self.axes = self._plt.subplots(figsize=(width, 0.2 + width * aspect), dpi=110)
        ax: Axes = self.axes
        self.figure.text(0.5, 0.01, _key(traj), ha="center", fontsize=7, color="0.3")
        _draw_arena(ax, geo)
        ranges = draws_ranges(traj)
        self._carriers = [
            _Carrier(ax, geo, ring=ranges and geo.radio_range == 0.0)
            for _ in range(traj.carrier_pos.shape[2])
        ]
        self._robots = [
            _Robot(ax, geo, ranges=ranges and geo.radio_range > 0.0)
            for _ in range(traj.robot_pos.shape[2])
        ]
        self._title: Text = ax.set_title("", fontsize=9)
        self._faces = [colormaps["YlOrRd"](0.15 + 0.85 * u / 9) for u in range(10)]

    def __enter__(self) -> Picture:
        """The picture itself; its figure is closed on leaving the block."""
        return self

    def __exit__(self, *exc: object) -> None:
        """Close the figure (pyplot keeps every open one)."""
        self._plt.close(self.figure)

    def face_colours(self) -> list[tuple[int, int, int]]:
        """The carriers' urgency colours as 8-bit RGB (what Agg paints for a flat face)."""
        return [(round(r * 255), round(g * 255), round(b * 255)) for r, g, b, _ in self._faces]

    def moving(self) -> list[Artist]:
        """The artists ``show`` changes, the title included."""
        carriers = [a for c in self._carriers for a in c.artists()]
        return [*carriers, *(a for r in self._robots for a in r.artists()), self._title]

    def show(self, index: int) -> None:
        """Set every moving artist to recorded time step ``index``."""
        traj, row, geo = self._traj, self._row, self._traj.geometry
        half = geo.carrier_size / 2
        status = traj.carrier_status[row, index]
        urgency = traj.carrier_urgency[row, index]
        present = traj.carrier_present[row, index]
        carrier_pos = traj.carrier_pos[row, index]
        for c, carrier in enumerate(self._carriers):
            x, y = (float(v) for v in carrier_pos[c])
            u = int(urgency[c])
            awaiting = bool(status[c] == TagStatus.AWAITING_PICKUP)
            if carrier.ring is not None:
                carrier.ring.set_center((x, y))
                carrier.ring.set_visible(bool(present[c]) and awaiting)
            carrier.square.set_xy((x - half, y - half))
            carrier.square.set_facecolor(self._faces[u] if awaiting else _IDLE_CARRIER_COLOUR)
            carrier.digit.set_position((x, y))
            carrier.digit.set_text(str(u))
            carrier.digit.set_color("white" if awaiting and u >= 7 else "black")  # dark faces
            for artist in (carrier.square, carrier.digit):
                artist.set_visible(bool(present[c]))
        for r, robot in enumerate(self._robots):
            x, y = (float(v) for v in traj.robot_pos[row, index, r])
            mode = int(traj.robot_mode[row, index, r])
            target = int(traj.robot_target[row, index, r])
            chasing = target >= 0 and mode in PURSUING
            if chasing:
                tx, ty = (float(v) for v in carrier_pos[target])
                robot.chase.set_data([x, tx], [y, ty])
            robot.chase.set_visible(chasing)
            for circle in robot.ranges:
                circle.set_center((x, y))
            robot.body.set_center((x, y))
            robot.body.set_facecolor(_BROKEN_COLOUR if mode == Mode.BROKEN else _ROBOT_COLOUR)
            hx, hy = (float(v) for v in traj.robot_heading[row, index, r])
            robot.heading.set_data([x, x + hx * geo.robot_radius], [y, y + hy * geo.robot_radius])
        tick = int(traj.time[index])
        self._title.set_text(
            f"{traj.condition}, run {int(traj.run_ids[row])}: tick {tick} "
            f"({tick * geo.tick_seconds:.1f} s)"
        )

    def lay_out(self, index: int) -> None:
        """Show ``index`` and fit the axes around it (tick labels, title, the key below)."""
        self.show(index)
        self.figure.tight_layout(rect=_LAYOUT)

    def frames(self, indices: Iterable[int]) -> Iterator[NDArray[np.uint8]]:
        """RGBA arrays (height, width, 4) of the time steps ``indices``, blitted.

        Call after ``lay_out``. The background holds every artist below the
        lowest moving one (areas, floor, axes' ticks and labels, the key);
        the rest of the axes' artists (the moving ones, the title, the
        spines and the area labels, which lie over moving bodies) are
        drawn per frame in the zorder a full redraw would use. Tick marks
        point outwards, clear of the bodies clipped to the axes. Texts,
        most of a frame's cost, are stamped where they were drawn before
        (``_Stamps``).
        """
        from matplotlib.axis import Axis
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.text import Text

        canvas = self.figure.canvas
        if not isinstance(canvas, FigureCanvasAgg):  # pragma: no cover - pyplot() chose Agg
            msg = f"pictures need matplotlib's Agg canvas, not {type(canvas).__name__}"
            raise TypeError(msg)
        agg: Any = canvas  # backend_agg has no type annotations
        ax = self.axes
        title = _SplitTitle(ax, self._title)
        lowest = min(a.get_zorder() for a in self.moving())
        for artist in ax.get_children():
            below = artist is ax.patch or isinstance(artist, Axis) or artist.get_zorder() < lowest
            artist.set_animated(not below)
        try:
            agg.draw()
            background = agg.copy_from_bbox(self.figure.bbox)
            order = sorted(
                (a for a in ax.get_children() if a.get_animated() and a is not self._title),
                key=methodcaller("get_zorder"),
            )  # the title's two parts stand in for it
            stamps = _Stamps(ax, agg)
            for index in indices:
                self.show(index)
                title.follow(agg.get_renderer())
                agg.restore_region(background)
                pixels = np.asarray(agg.buffer_rgba())
                for artist in order:
                    if not artist.get_visible():
                        continue
                    if isinstance(artist, Text):
                        stamps.draw(artist, pixels)
                    else:
                        ax.draw_artist(artist)
                yield pixels.copy()
        finally:
            title.remove()
            for artist in ax.get_children():
                artist.set_animated(False)


class _SplitTitle:
    """An animation's title as two texts: the run's name, still, and the tick, which changes.

    The title's glyphs are most of a frame's drawing; split, the still part
    is stamped (``_Stamps``) and only the tick's few glyphs are drawn. The
    two parts sit where the one title's glyphs do: the still part from its
    left end, the tick part up to its right end, on its baseline. The title
    itself stays (animated, so a full draw skips it) with its text: matplotlib
    places it by its extent, and would move a hidden one.
    """

    _AT: Final = ": tick "
    """Where the title splits: the still part ends with this."""

    def __init__(self, ax: Axes, title: Text) -> None:
        """Add the two parts of ``title`` (whose text ``Picture.show`` sets) to ``ax``."""
        from matplotlib.transforms import IdentityTransform, blended_transform_factory

        self._title = title
        place = blended_transform_factory(IdentityTransform(), title.get_transform())
        style: dict[str, Any] = {
            "transform": place,
            "fontproperties": title.get_fontproperties(),
            "va": title.get_verticalalignment(),
            "color": title.get_color(),
            "zorder": title.get_zorder(),
        }
        self.still: Text = ax.text(0, 0, "", ha="left", **style)
        self.tick: Text = ax.text(0, 0, "", ha="right", **style)

    def follow(self, renderer: Any) -> None:  # noqa: ANN401 - an untyped Agg renderer
        """Set the two parts to the title's text, laid out as the title would be."""
        text = self._title.get_text()
        head, at, tail = text.rpartition(self._AT)
        still, tick = (head + at, tail) if at else (text, "")
        x, y = self._title.get_position()
        centre = self._title.get_transform().transform((x, y))[0]
        font = self._title.get_fontproperties()
        width = renderer.get_text_width_height_descent(text, font, ismath=False)[0]
        self.still.set_text(still)
        self.still.set_position((centre - width / 2, y))
        self.tick.set_text(tick)
        self.tick.set_position((centre + width / 2, y))

    def remove(self) -> None:
        """Take the parts away: the one title is drawn again."""
        self.still.remove()
        self.tick.remove()


class _Stamps:
    """Texts drawn by copying the pixels they made last time, where that gives the same pixels.

    A text is redrawn when its string, colour or place changed; otherwise,
    if the pixels under it are what they were when it was last drawn, the
    pixels it made then are copied back, which is exactly what drawing it
    again would make (Agg's blending depends on nothing else) at a
    fraction of the cost of laying out and rasterising the glyphs.
    """

    _MARGIN: Final = 3
    """Pixels around a text's extent also copied: anti-aliased edges of glyphs."""

    def __init__(self, ax: Axes, canvas: Any) -> None:  # noqa: ANN401 - an untyped Agg canvas
        """Stamp into ``canvas`` (a ``FigureCanvasAgg``), drawing on ``ax``."""
        self._ax, self._canvas = ax, canvas
        self._last: dict[int, tuple[object, ...]] = {}
        self._made: dict[int, tuple[tuple[slice, slice], NDArray[np.uint8], NDArray[np.uint8]]] = {}

    def draw(self, text: Text, pixels: NDArray[np.uint8]) -> None:
        """Draw ``text`` into ``pixels`` (the canvas' RGBA buffer), copied where it can be."""
        if not text.get_visible() or not text.get_text():
            return
        key = (text.get_text(), str(text.get_color()), tuple(text.get_position()))
        same = self._last.get(id(text)) == key
        self._last[id(text)] = key
        if not same:  # changed (or first seen): draw it, and copy it only if it stays
            self._made.pop(id(text), None)
            self._ax.draw_artist(text)
            return
        made = self._made.get(id(text))
        if made is not None and np.array_equal(pixels[made[0]], made[1]):
            pixels[made[0]] = made[2]
            return
        block = made[0] if made is not None else self._block(text, pixels.shape)
        before = pixels[block].copy()
        self._ax.draw_artist(text)
        self._made[id(text)] = (block, before, pixels[block].copy())

    def _block(self, text: Text, shape: tuple[int, ...]) -> tuple[slice, slice]:
        """The rows and columns of ``pixels`` that ``text`` may change."""
        box = text.get_window_extent(self._canvas.get_renderer())
        m, height, width = self._MARGIN, shape[0], shape[1]
        rows = slice(max(0, int(height - box.y1) - m), min(height, int(height - box.y0) + m + 1))
        columns = slice(max(0, int(box.x0) - m), min(width, int(box.x1) + m + 1))
        return rows, columns
