"""The robot-I/O protocol: everything a controller may read from and do to its robot.

A controller (the behaviour tree of ``swarmtag.robot.tree``, or any other)
sees its robot only through ``RobotIO``; the simulator offers one view per
simulated robot (``swarmtag.robot.sim_io``), and a real robot would offer
the same from its drivers (docs/controller.md says what a ROS 2 node has to
provide). Carriers are indexed by marker id throughout.

The control loop consults the controller at three points of each tick
(``ControlStep``): after the sensors updated, after the robot moved, and
after the tags answered this tick's writes. Motion is commanded as motion
primitives (drive along a direction at full speed, drive to a point and
stop on it, stand still), the form in which a robot's motion controller
takes goals; lift and tag writes are one command each.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "Behaviour",
    "ControlStep",
    "Detections",
    "Pose",
    "RandomDraws",
    "Report",
    "RobotIO",
    "TagStates",
]

Float = NDArray[np.float64]


class ControlStep(IntEnum):
    """When in a tick the controller is consulted."""

    SENSED = 1
    """The sensors (radio, camera, bumper) were updated: decide."""
    MOVED = 2
    """The robot moved: progress, arrivals, lift writes."""
    ANSWERED = 3
    """The tags answered this tick's lift writes: lifting, transport, release."""


class Behaviour(IntEnum):
    """The behaviour the robot announces (its motion primitive); same numbers as ``sim.Mode``."""

    WALK = 0
    PREDOCK = 1
    DOCK = 2
    CENTRE = 3
    LIFT = 4
    TRANSPORT = 5
    RELEASE = 6


class Report(IntEnum):
    """What a controller reports about its decisions (the event log's controller events)."""

    ABANDON = 2
    TIMEOUT = 3
    SELECT = 4
    CANDIDATES = 5


@dataclass(frozen=True, eq=False)
class Pose:
    """Own pose: centre (m) and unit heading, each shape (2,)."""

    position: Float
    heading: Float


@dataclass(frozen=True, eq=False)
class TagStates:
    """The latest state heard from each tag (the BLE cache), each shape (C,).

    ``status`` is -1 for a tag never heard; ``age`` is ticks since it was
    last heard (-1 never). ``distance``: the robot's running estimate of
    each tag's distance from its RSSI (NaN never heard), where the robot
    ranges tags (BLE-led search); None where it does not. ``waited``:
    seconds since each carrier's order time, as the warehouse management
    system knows it (what a score rule of one's own may ask for as ``age``);
    None where the robot is not told.
    """

    status: NDArray[np.int8]
    urgency: NDArray[np.int8]
    age: NDArray[np.int64]
    distance: Float | None = None
    waited: Float | None = None


@dataclass(frozen=True, eq=False)
class Detections:
    """What the cameras tell about each carrier, by marker id.

    ``known`` (C,): its position is known now (seen, or remembered);
    ``distance`` (C,): the measured distance to it (camera noise included),
    the ``d`` of the selection score; ``position`` (C, 2): where it is, as
    the camera localises it while the robot approaches (used to navigate);
    ``free_faces`` (C, 4): which of its faces (east, north, west, south) a
    robot can stand in front of.
    """

    known: NDArray[np.bool_]
    distance: Float
    position: Float
    free_faces: NDArray[np.bool_]


@dataclass(frozen=True, eq=False)
class RandomDraws:
    """This tick's numbers of the robot's random source (docs/simulator.md's streams).

    ``walk`` and ``sidestep`` are unit directions (2,); ``turn`` is the walk
    turn as ``(cos, sin)``, or None when the walk does not turn.
    """

    walk: Float
    sidestep: Float
    turn: Float | None


class RobotIO(Protocol):
    """One robot's sensors and actuators, as its controller sees them."""

    @property
    def robot(self) -> int:
        """This robot's id."""
        ...

    @property
    def tick(self) -> int:
        """Elapsed time in ticks (the tick being run, from 1)."""
        ...

    @property
    def step(self) -> ControlStep:
        """Which control step of the tick this is."""
        ...

    # -- sensors
    def pose(self) -> Pose:
        """Own pose where known (odometry and markers)."""
        ...

    def odometry(self) -> Float:
        """How far the robot moved during this tick so far, (2,) metres."""
        ...

    def speed(self) -> float:
        """Own top speed, metres per tick."""
        ...

    def bumper(self) -> Float:
        """The range sensors' contact push of the last move (2,): zero when nothing touched."""
        ...

    def tag_states(self) -> TagStates:
        """The latest tag states with their age."""
        ...

    def detections(self) -> Detections:
        """The markers the cameras detect, with relative positions."""
        ...

    def neighbours(self) -> Float:
        """Centres (M, 2) of the other robots within camera sight."""
        ...

    def dock_occupied(self, carrier: int) -> bool:
        """Whether the range sensors see another robot under ``carrier``."""
        ...

    def lift_answer(self) -> bool | None:
        """The tag's answer to this tick's lift write: accepted, refused, or None (no write)."""
        ...

    def random(self) -> RandomDraws:
        """This tick's random numbers for this robot."""
        ...

    # -- actuators
    def walk(self, direction: Float | None = None) -> None:
        """Random walk: drive at full speed along ``direction`` (None: keep the last one)."""
        ...

    def approach(self, carrier: int, face: int) -> None:
        """Drive to the predock point of ``carrier``'s ``face`` and turn to face the carrier."""
        ...

    def look(self, since: int) -> None:
        """Stand and turn in place so the cameras sweep round, looking since tick ``since``.

        -1 stops looking (the walk goes on). While looking, ``detections``
        knows every carrier seen since then.
        """
        ...

    def dock(self) -> None:
        """Drive in under the carrier being approached, towards its centre."""
        ...

    def centre(self) -> None:
        """Stand centred under the carrier on its underside marker."""
        ...

    def lift(self) -> None:
        """Raise the lift: write PICKED_UP to the carrier's tag (answered at ``ANSWERED``)."""
        ...

    def hold(self) -> None:
        """Stand still with the lift rising."""
        ...

    def carry_to(self, goal: Float) -> None:
        """Drive with the load to ``goal`` (2,) and stop there."""
        ...

    def sidestep(self, direction: Float, ticks: int) -> None:
        """Drive along ``direction`` for ``ticks`` ticks (a loaded robot getting unstuck)."""
        ...

    def sidestep_left(self) -> int:
        """Ticks of the current sidestep still to drive."""
        ...

    def release(self) -> None:
        """Stand still lowering the load."""
        ...

    def lower(self) -> None:
        """Set the load down: write IDLE to its tag (the carrier is delivered)."""
        ...

    def report(self, kind: Report, carrier: int, value: float) -> None:
        """Log a decision (selection, candidates, abandon, timeout) in the event log."""
        ...
