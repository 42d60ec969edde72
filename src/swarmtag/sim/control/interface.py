"""The controller interface: what robots decide, at the three control steps of a tick.

The simulator is two sides. The **world** (bodies and collisions, tags,
breakdowns, radio and camera, docking physics, operator writes) lives in
``sense``, ``motion``, ``world`` and ``kernel``; the **controller** (what a
robot decides from what it perceives) is behind this interface. A tick
consults the controller three times, as a robot's control loop runs
between sensor updates:

1. ``decide``: after sensing (and the world's breakdowns): pursuit checks,
   selection, walk and sidestep directions;
2. ``arrive``: after the move and the collisions: progress, timers,
   arrivals at the predock point and the centre, lift requests;
3. ``carry``: after the tags answered the lift writes: lifting, transport,
   arrival in the drop-off area, release requests.

A controller acts through the robots' command registers of ``WorldState``
(``mode``: the behaviour and motion primitive the robot runs, ``target``,
``face``, ``goal``, ``walk``, ``sidestep``, ``sidestep_dir``, ``look``) and the
requests it returns (tag writes, driving in under a carrier, centring);
the built-in controller also keeps its own memory in the state's other
robot fields (``timer``, ``pursuit_start``, ``redirect``, ``stuck``,
``blocked_until``, ``walk_clock``, ``seek``, ``seek_ref``, ``curve``).
``BUILTIN`` is the vectorised built-in controller; ``swarmtag.robot`` has
the behaviour tree, which gives identical event logs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final, Protocol

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.model.events import TickEvents
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import Int, WorldState
from swarmtag.sim.world.sensing import Senses

__all__ = [
    "COMMAND_FIELDS",
    "MEMORY_FIELDS",
    "Arrivals",
    "Carrying",
    "Controller",
    "LiftAnswers",
    "no_arrivals",
    "no_carrying",
]

COMMAND_FIELDS: Final = (
    "mode",
    "target",
    "face",
    "goal",
    "walk",
    "sidestep",
    "sidestep_dir",
    "look",
)
"""Robot fields a controller sets and the world reads (the command registers)."""
MEMORY_FIELDS: Final = (
    "timer",
    "pursuit_start",
    "redirect",
    "stuck",
    "blocked_until",
    "walk_clock",
    "seek",
    "seek_ref",
    "curve",
)
"""Robot fields only the built-in controller reads and writes (its own memory)."""


@dataclass(frozen=True, eq=False)
class Arrivals:
    """Requests of the ``arrive`` step, each (R, N).

    ``drive_in``: robots that drive in under their target now (the world
    lets them overlap it); ``centred``: robots that start centring (the
    world puts them on the carrier's centre); ``lift``: the carrier each
    robot writes PICKED_UP to (its lift request), -1 none.
    """

    drive_in: NDArray[np.bool_]
    centred: NDArray[np.bool_]
    lift: Int


@dataclass(frozen=True, eq=False)
class LiftAnswers:
    """The tags' answers to this tick's lift requests, each (R, N): accepted or refused."""

    accepted: NDArray[np.bool_]
    refused: NDArray[np.bool_]


@dataclass(frozen=True, eq=False)
class Carrying:
    """Requests of the ``carry`` step, each (R, N).

    ``raised``: robots whose lift is up and that drive off with their
    carrier; ``lower``: the carrier each robot sets down and writes IDLE to
    (delivered), -1 none.
    """

    raised: NDArray[np.bool_]
    lower: Int


def no_arrivals(shape: tuple[int, int]) -> Arrivals:
    """Requests of a step in which no robot asks for anything."""
    none = np.zeros(shape, dtype=bool)
    return Arrivals(drive_in=none, centred=none.copy(), lift=np.full(shape, -1, dtype=np.int64))


def no_carrying(shape: tuple[int, int]) -> Carrying:
    """Carry requests of a step in which no robot asks for anything."""
    return Carrying(raised=np.zeros(shape, dtype=bool), lower=np.full(shape, -1, dtype=np.int64))


class Controller(Protocol):
    """The robots' decisions for a batch, at the three control steps of a tick.

    Each step changes the robots' fields of ``s`` (the state being built for
    tick ``t``) in place and adds the controller's events (``abandon``,
    ``timeout``, ``select``, ``candidates``) to ``events``. Broken robots
    (``Mode.BROKEN``) are the world's: a controller leaves them alone.
    """

    def decide(
        self,
        before: WorldState,
        s: WorldState,
        *,
        senses: Senses,
        inputs: TickInputs,
        params: Params,
        t: int,
        events: TickEvents,
    ) -> None:
        """Pursuit checks, selection, walk and sidestep directions (``before``: tick start)."""
        ...

    def arrive(self, before: WorldState, s: WorldState, *, params: Params, t: int) -> Arrivals:
        """Progress, timers, arrivals and lift requests, from the positions after the move."""
        ...

    def carry(self, s: WorldState, answers: LiftAnswers, *, params: Params, t: int) -> Carrying:
        """Lifting, transport and release, after the tags answered the lift requests."""
        ...
