"""The simulator's robot-I/O view: one simulated robot as ``swarmtag.robot.RobotIO`` sees it.

The view reads the world state of the tick being built (``s``) and the
tick's senses and random inputs, and turns actuator commands into the
robot's command registers and the step's requests (``control.Arrivals``,
``control.Carrying``). Sensors return exactly the numbers the built-in
controller reads (the random source hands out this tick's rows of the
run's streams), which is what makes the two controllers' event logs
identical.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from swarmtag.robot.io import (
    ControlStep,
    Detections,
    Float,
    Pose,
    RandomDraws,
    Report,
    RobotIO,
    TagStates,
)
from swarmtag.sim.model.geometry import length
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import Int, Mode, WorldState
from swarmtag.sim.world.sensing import Senses
from swarmtag.sim.world.urgency import waited

__all__ = ["SimRobotIO", "StepContext"]

_UNDER = (Mode.DOCK, Mode.CENTRE, Mode.LIFT)


@dataclass(eq=False)
class StepContext:
    """What the views of one control step share: the batch, and the requests being collected."""

    step: ControlStep
    t: int
    before: WorldState
    s: WorldState
    params: Params
    senses: Senses | None = None
    inputs: TickInputs | None = None
    accepted: NDArray[np.bool_] | None = None
    refused: NDArray[np.bool_] | None = None
    drive_in: NDArray[np.bool_] = field(init=False)
    centred: NDArray[np.bool_] = field(init=False)
    lift: Int = field(init=False)
    raised: NDArray[np.bool_] = field(init=False)
    lower: Int = field(init=False)
    """The requests being collected, (R, N) each (see ``swarmtag.sim.control.interface``)."""
    reports: list[tuple[Report, int, int, int, float]] = field(init=False, default_factory=list)
    """(kind, row, robot, carrier, value) in the order reported."""

    def __post_init__(self) -> None:
        shape = self.s.mode.shape
        self.drive_in = np.zeros(shape, dtype=bool)
        self.centred = np.zeros(shape, dtype=bool)
        self.lift = np.full(shape, -1, dtype=np.int64)
        self.raised = np.zeros(shape, dtype=bool)
        self.lower = np.full(shape, -1, dtype=np.int64)


class SimRobotIO:
    """Robot ``robot`` of batch row ``row``, through the current ``StepContext``."""

    def __init__(self, row: int, robot: int, context: StepContext) -> None:
        self.row = row
        self._robot = robot
        self.context = context

    # -- what the controller knows about time
    @property
    def robot(self) -> int:
        """This robot's id."""
        return self._robot

    @property
    def tick(self) -> int:
        """The tick being run."""
        return self.context.t

    @property
    def step(self) -> ControlStep:
        """The control step."""
        return self.context.step

    def _senses(self) -> Senses:
        senses = self.context.senses
        if senses is None:  # pragma: no cover - the controller always binds them
            msg = "no senses bound to this control step"
            raise RuntimeError(msg)
        return senses

    def _inputs(self) -> TickInputs:
        inputs = self.context.inputs
        if inputs is None:  # pragma: no cover - the controller always binds them
            msg = "no random inputs bound to this control step"
            raise RuntimeError(msg)
        return inputs

    # -- sensors
    def pose(self) -> Pose:
        """Position and heading now."""
        s, r, n = self.context.s, self.row, self._robot
        return Pose(position=s.robot_pos[r, n], heading=s.heading[r, n])

    def odometry(self) -> Float:
        """Displacement during this tick so far."""
        r, n = self.row, self._robot
        moved: Float = self.context.s.robot_pos[r, n] - self.context.before.robot_pos[r, n]
        return moved

    def speed(self) -> float:
        """Top speed, metres per tick."""
        return float(self.context.s.speed[self.row, self._robot])

    def bumper(self) -> Float:
        """Last move's contact push."""
        push: Float = self.context.s.contact[self.row, self._robot]
        return push

    def tag_states(self) -> TagStates:
        """The BLE cache after this tick's advertisements (with BLE-led search, RSSI ranging)."""
        s, r, n = self.context.s, self.row, self._robot
        heard = s.heard_tick[r, n]
        ranged = self.context.params.radio_search
        return TagStates(
            status=s.known_status[r, n],
            urgency=s.known_urgency[r, n],
            age=np.where(heard >= 0, self.context.t - heard, -1),
            distance=np.where(heard >= 0, s.rssi[r, n], np.nan) if ranged else None,
            waited=waited(s.order_time[r], self.context.t, self.context.params.scenario.tick),
        )

    def detections(self) -> Detections:
        """Known carrier positions, measured distances, localised positions, free faces."""
        senses, s, r, n = self._senses(), self.context.s, self.row, self._robot
        return Detections(
            known=senses.known[r, n],
            distance=senses.distance[r, n],
            position=s.carrier_pos[r],
            free_faces=s.free_face[r],
        )

    def neighbours(self) -> Float:
        """The other robots within sight."""
        s, r, n = self.context.s, self.row, self._robot
        positions = s.robot_pos[r]
        apart = length(positions[n][None, :] - positions)
        near = apart <= self.context.params.detection_radius
        near[n] = False
        found: Float = positions[near]
        return found

    def dock_occupied(self, carrier: int) -> bool:
        """Another robot docking, centring or lifting under ``carrier``."""
        s, r = self.context.s, self.row
        mode, target = s.mode[r], s.target[r]
        under = (mode == _UNDER[0]) | (mode == _UNDER[1]) | (mode == _UNDER[2])
        under &= target == carrier
        under[self._robot] = False
        return bool(under.any())

    def lift_answer(self) -> bool | None:
        """Accepted, refused, or None without a write this tick."""
        accepted, refused = self.context.accepted, self.context.refused
        if accepted is None or refused is None:
            return None
        r, n = self.row, self._robot
        if accepted[r, n]:
            return True
        if refused[r, n]:
            return False
        return None

    def random(self) -> RandomDraws:
        """This tick's draws of the run's streams for this robot."""
        inputs, r, n = self._inputs(), self.row, self._robot
        return RandomDraws(
            walk=inputs.walk[r, n],
            sidestep=inputs.sidestep[r, n],
            turn=None if inputs.turn is None else inputs.turn[r, n],
        )

    # -- actuators
    def _set_mode(self, mode: Mode) -> None:
        self.context.s.mode[self.row, self._robot] = mode

    def walk(self, direction: Float | None = None) -> None:
        """Random walk along ``direction`` (or the last one)."""
        s, r, n = self.context.s, self.row, self._robot
        self._set_mode(Mode.WALK)
        s.target[r, n] = -1
        s.face[r, n] = -1
        if direction is not None:
            s.walk[r, n] = direction

    def look(self, since: int) -> None:
        """Look round (stand and turn) since tick ``since``; -1 stops."""
        self.context.s.look[self.row, self._robot] = since

    def approach(self, carrier: int, face: int) -> None:
        """Drive to the predock point of ``face``."""
        s, r, n = self.context.s, self.row, self._robot
        self._set_mode(Mode.PREDOCK)
        s.target[r, n] = carrier
        s.face[r, n] = face

    def dock(self) -> None:
        """Drive in under the target."""
        self._set_mode(Mode.DOCK)
        self.context.drive_in[self.row, self._robot] = True

    def centre(self) -> None:
        """Centre under the target."""
        self._set_mode(Mode.CENTRE)
        self.context.centred[self.row, self._robot] = True

    def lift(self) -> None:
        """Write PICKED_UP to the target's tag."""
        r, n = self.row, self._robot
        self.context.lift[r, n] = self.context.s.target[r, n]

    def hold(self) -> None:
        """Stand with the lift rising."""
        self._set_mode(Mode.LIFT)

    def carry_to(self, goal: Float) -> None:
        """Transport to ``goal``."""
        s, r, n = self.context.s, self.row, self._robot
        self._set_mode(Mode.TRANSPORT)
        s.goal[r, n] = goal
        s.sidestep[r, n] = 0
        self.context.raised[r, n] = True

    def sidestep(self, direction: Float, ticks: int) -> None:
        """Sidestep along ``direction`` for ``ticks`` ticks."""
        s, r, n = self.context.s, self.row, self._robot
        s.sidestep_dir[r, n] = direction
        s.sidestep[r, n] = ticks

    def sidestep_left(self) -> int:
        """Ticks of sidestep left."""
        return int(self.context.s.sidestep[self.row, self._robot])

    def release(self) -> None:
        """Stand lowering the load."""
        self._set_mode(Mode.RELEASE)

    def lower(self) -> None:
        """Set the load down and write IDLE."""
        r, n = self.row, self._robot
        self.context.lower[r, n] = self.context.s.target[r, n]

    def report(self, kind: Report, carrier: int, value: float) -> None:
        """Log a decision."""
        self.context.reports.append((kind, self.row, self._robot, carrier, value))


if TYPE_CHECKING:

    def _is_robot_io(view: SimRobotIO) -> RobotIO:
        """The type checker's proof that the view implements the protocol."""
        return view
