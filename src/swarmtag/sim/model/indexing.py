"""Small indexing and mode helpers shared by the kernel phases."""

from __future__ import annotations

import functools
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.model.params import Params
from swarmtag.sim.model.state import Int, Mode, WorldState
from swarmtag.sim.world.floor import inside_area

__all__ = [
    "LOADED_MODES",
    "PURSUIT_MODES",
    "STILL_MODES",
    "at_robots",
    "grid",
    "in_dropoff",
    "in_modes",
    "is_loaded",
    "own",
    "to_walk",
]

PURSUIT_MODES: Final = (Mode.PREDOCK, Mode.DOCK, Mode.CENTRE)
"""Modes of a robot pursuing its selected carrier (abandon and timeout apply)."""
LOADED_MODES: Final = (Mode.LIFT, Mode.TRANSPORT, Mode.RELEASE)
"""Modes of a robot holding its carrier."""
STILL_MODES: Final = (Mode.CENTRE, Mode.LIFT, Mode.RELEASE, Mode.BROKEN)
"""Modes of a robot that stands still and cannot be pushed (anchored)."""


def grid(runs: int, robots: int) -> tuple[Int, Int]:
    """Index arrays ``(R, 1)`` and ``(1, N)`` for picking one entry per robot."""
    return np.arange(runs)[:, None], np.arange(robots)[None, :]


@functools.cache
def _mode_table(modes: tuple[Mode, ...]) -> NDArray[np.bool_]:
    """A table indexed by mode value: True for the ``modes`` (made once per set of modes)."""
    table = np.zeros(len(Mode), dtype=bool)
    table[[int(m) for m in modes]] = True
    table.flags.writeable = False
    return table


def in_modes(mode: NDArray[np.int8], modes: tuple[Mode, ...]) -> NDArray[np.bool_]:
    """Robots whose mode is one of ``modes`` (a new array).

    One lookup in a table of the modes rather than a comparison per mode:
    on a small swarm each numpy call costs more than its work. Elsewhere the
    reference compares mode arrays with ``int(Mode.X)``, never the enum
    member: numpy asks an operand's class for ``__array_ufunc__``, which Python
    3.11 answers through ``EnumType.__getattr__`` (2.6 µs a comparison).
    """
    found: NDArray[np.bool_] = _mode_table(modes)[mode]
    return found


def is_loaded(mode: NDArray[np.int8], target: Int) -> NDArray[np.bool_]:
    """Robots holding a carrier: lifting, transporting, releasing, or broken down with it."""
    loaded: NDArray[np.bool_] = in_modes(mode, (*LOADED_MODES, Mode.BROKEN)) & (target >= 0)
    return loaded


def at_robots(carrier_values: NDArray[Any], index: Int) -> NDArray[Any]:
    """``carrier_values`` (R, C, ...) at each robot's carrier ``index`` (R, N).

    An index of -1 (none) reads carrier 0; callers mask those entries.
    """
    rows = np.arange(index.shape[0])[:, None]
    return carrier_values[rows, np.maximum(index, 0)]


def own(robot_carrier: NDArray[Any], index: Int) -> NDArray[Any]:
    """``robot_carrier`` (R, N, C) at each robot's own carrier ``index`` (R, N)."""
    rows, robots = grid(*index.shape)
    return robot_carrier[rows, robots, np.maximum(index, 0)]


def to_walk(state: WorldState, mask: NDArray[np.bool_]) -> None:
    """Send the robots in ``mask`` back to random walk (in place), with a fresh direction."""
    state.mode[mask] = Mode.WALK
    state.target[mask] = -1
    state.face[mask] = -1
    state.timer[mask] = 0
    state.redirect[mask] = True
    state.seek[mask] = -1


def in_dropoff(s: WorldState, params: Params, carrier: Int) -> NDArray[np.bool_]:
    """(R, N) robots whose load ``carrier`` would lie wholly inside its drop-off area.

    The lab: ``x - carrier_half >= dropoff_left``; a warehouse: the carrier's
    square inside the cells of its destination's area (``floor_motion``).
    """
    x = s.robot_pos[..., 0]
    if params.floor is None:
        inside: NDArray[np.bool_] = x - params.carrier_half >= params.dropoff_left
        return inside
    area_ids = np.asarray(params.floor.destinations, dtype=np.int64)
    area = area_ids[at_robots(s.destination, carrier)]
    return inside_area(x, s.robot_pos[..., 1], params.carrier_half, area, params.floor)
