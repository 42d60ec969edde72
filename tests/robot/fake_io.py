"""A scripted robot for behaviour tests: a ``RobotIO`` whose sensors the test sets by hand."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from swarmtag.robot import (
    Behaviour,
    ControlStep,
    Detections,
    Pose,
    RandomDraws,
    Report,
    TagStates,
)


@dataclass(eq=False)
class FakeIO:
    """One robot in an empty world: sensors are attributes, actuator calls are recorded."""

    carriers: int
    position: np.ndarray = field(default_factory=lambda: np.array([2.0, 2.0]))
    heading: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0]))
    tick: int = 0
    step: ControlStep = ControlStep.SENSED
    robot: int = 0
    status: np.ndarray = field(init=False)
    urgency: np.ndarray = field(init=False)
    known: np.ndarray = field(init=False)
    carrier_pos: np.ndarray = field(init=False)
    free: np.ndarray = field(init=False)
    contact: np.ndarray = field(default_factory=lambda: np.zeros(2))
    answer: bool | None = None
    occupied: bool = False
    walk_draw: np.ndarray = field(default_factory=lambda: np.array([0.0, 1.0]))
    sidestep_draw: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0]))
    # what the controller did
    behaviour: Behaviour = Behaviour.WALK
    target: int = -1
    face: int = -1
    walk_direction: np.ndarray | None = None
    writes: list[tuple[str, int]] = field(default_factory=list)
    reports: list[tuple[Report, int, float]] = field(default_factory=list)
    goal: np.ndarray | None = None
    sidestep_ticks: int = 0

    def __post_init__(self) -> None:
        self.status = np.full(self.carriers, -1, dtype=np.int8)
        self.urgency = np.zeros(self.carriers, dtype=np.int8)
        self.known = np.zeros(self.carriers, dtype=bool)
        self.carrier_pos = np.zeros((self.carriers, 2))
        self.free = np.ones((self.carriers, 4), dtype=bool)

    def pose(self) -> Pose:
        return Pose(position=self.position, heading=self.heading)

    def odometry(self) -> np.ndarray:
        return np.zeros(2)

    def speed(self) -> float:
        return 0.05

    def bumper(self) -> np.ndarray:
        return self.contact

    def tag_states(self) -> TagStates:
        return TagStates(
            status=self.status, urgency=self.urgency, age=np.zeros(self.carriers, dtype=np.int64)
        )

    def detections(self) -> Detections:
        distance = np.sqrt(((self.carrier_pos - self.position) ** 2).sum(axis=-1))
        return Detections(
            known=self.known, distance=distance, position=self.carrier_pos, free_faces=self.free
        )

    def neighbours(self) -> np.ndarray:
        return np.zeros((0, 2))

    def dock_occupied(self, carrier: int) -> bool:
        return self.occupied

    def lift_answer(self) -> bool | None:
        return self.answer

    def random(self) -> RandomDraws:
        return RandomDraws(walk=self.walk_draw, sidestep=self.sidestep_draw, turn=None)

    def walk(self, direction: np.ndarray | None = None) -> None:
        self.behaviour, self.target, self.face = Behaviour.WALK, -1, -1
        if direction is not None:
            self.walk_direction = np.array(direction)

    def approach(self, carrier: int, face: int) -> None:
        self.behaviour, self.target, self.face = Behaviour.PREDOCK, carrier, face

    def dock(self) -> None:
        self.behaviour = Behaviour.DOCK

    def centre(self) -> None:
        self.behaviour = Behaviour.CENTRE

    def lift(self) -> None:
        self.writes.append(("lift", self.target))

    def hold(self) -> None:
        self.behaviour = Behaviour.LIFT

    def carry_to(self, goal: np.ndarray) -> None:
        self.behaviour, self.goal = Behaviour.TRANSPORT, np.array(goal)

    def sidestep(self, direction: np.ndarray, ticks: int) -> None:
        self.sidestep_ticks = ticks

    def sidestep_left(self) -> int:
        return self.sidestep_ticks

    def release(self) -> None:
        self.behaviour = Behaviour.RELEASE

    def lower(self) -> None:
        self.writes.append(("lower", self.target))

    def report(self, kind: Report, carrier: int, value: float) -> None:
        self.reports.append((kind, carrier, value))
