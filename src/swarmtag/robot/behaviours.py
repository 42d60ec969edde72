"""The behaviours of SPEC §3.2 as py_trees behaviours, acting only through ``RobotIO``.

Each behaviour reads its robot's sensors and commands its actuators through
the ``RobotIO`` it is given in ``setup(io=...)`` (the hardware is connected
there, not in ``__init__``), and keeps what it must remember on the robot's
own blackboard namespace. Time is the robot's tick count (``io.tick``),
never a wall clock. A behaviour acts at the control step it belongs to
(``ControlStep``) and is quiet (RUNNING) at the others.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import py_trees
from py_trees.common import Access, Status

from swarmtag.policy import select
from swarmtag.robot.config import ControllerConfig
from swarmtag.robot.io import ControlStep, Detections, Float, Report, RobotIO
from swarmtag.robot.search import (
    candidate_distances,
    give_up_seeking,
    seek_tumbles,
    start_seeking,
)
from swarmtag.sim.control.rules import STUCK_PROGRESS, away_from
from swarmtag.sim.model.geometry import FACE_NORMALS, length
from swarmtag.sim.world.predock import nearest_free_face, taken_faces
from swarmtag.tag import TagStatus

__all__ = [
    "BLACKBOARD_KEYS",
    "Centre",
    "Dock",
    "Lift",
    "Predock",
    "RandomWalk",
    "Release",
    "ResumeWalk",
    "RobotBehaviour",
    "SelectCarrier",
    "StillAwaiting",
    "Transport",
    "WithinTimeout",
]

_AWAITING = int(TagStatus.AWAITING_PICKUP)

BLACKBOARD_KEYS = (
    "target",
    "face",
    "pursuit_start",
    "timer",
    "redirect",
    "stuck",
    "walk",
    "walk_clock",
    "blocked_until",
    "seek",
    "seek_ref",
    "curve",
    "look",
)
"""The robot's memory, one blackboard namespace per robot."""


class RobotBehaviour(py_trees.behaviour.Behaviour):
    """A behaviour of one robot: its configuration, its I/O (from ``setup``), its blackboard."""

    keys: tuple[str, ...] = ()
    """Blackboard keys this behaviour writes."""

    def __init__(self, name: str, config: ControllerConfig, namespace: str) -> None:
        super().__init__(name)
        self.config = config
        self.memory: Any = self.attach_blackboard_client(name=name, namespace=namespace)
        for key in self.keys:
            self.memory.register_key(key=key, access=Access.WRITE)
        self._io: RobotIO | None = None
        self._started: tuple[int, ControlStep] | None = None

    def setup(self, **kwargs: Any) -> None:  # noqa: ANN401 - py_trees passes setup's keywords on
        """Connect the robot: ``io`` is its ``RobotIO``."""
        io = kwargs.get("io")
        if io is None:
            msg = f"{self.name}: setup needs io=RobotIO"
            raise KeyError(msg)
        self._io = io

    @property
    def io(self) -> RobotIO:
        """The robot's I/O (set by ``setup``)."""
        if self._io is None:
            msg = f"{self.name}: not set up (call the tree's setup(io=...))"
            raise RuntimeError(msg)
        return self._io

    def initialise(self) -> None:
        """Note when the behaviour started (it does not act again in that control step)."""
        self._started = (self.io.tick, self.io.step)
        self.start()

    def start(self) -> None:
        """What the behaviour does when it starts (override)."""

    def just_started(self) -> bool:
        """Whether the behaviour started in the current control step."""
        return self._started == (self.io.tick, self.io.step)

    def update(self) -> Status:
        """Dispatch to the handler of the current control step."""
        step = self.io.step
        if step == ControlStep.SENSED:
            return self.sensed()
        if step == ControlStep.MOVED:
            return self.moved()
        return self.answered()

    def sensed(self) -> Status:
        """After the sensors updated (override)."""
        return Status.RUNNING

    def moved(self) -> Status:
        """After the robot moved (override)."""
        return Status.RUNNING

    def answered(self) -> Status:
        """After the tags answered this tick's writes (override)."""
        return Status.RUNNING


def _taken(io: RobotIO, centre: Float, config: ControllerConfig) -> np.ndarray:
    """(4,): the predock points of the carrier at ``centre`` that the robot sees taken."""
    bodies = np.concatenate((io.pose().position[None, :], io.neighbours()))[None]
    centres = np.broadcast_to(centre, bodies.shape).copy()
    taken = taken_faces(
        bodies,
        centres,
        config.predock_offset,
        body=2 * config.robot_radius,
        sight=config.detection_radius,
    )
    return np.asarray(taken[0, 0])


def _steer(behaviour: RobotBehaviour) -> None:
    """The walk direction of a walking robot (a fresh one after contact or a new start, turns)."""
    io, memory, config = behaviour.io, behaviour.memory, behaviour.config
    bumper = io.bumper()
    draws = io.random()
    fresh = bool(memory.redirect) or bool((bumper != 0).any())
    seeking = config.radio_search and memory.seek >= 0
    if seeking:
        fresh = seek_tumbles(io, memory, config, fresh)
    if fresh:
        memory.walk = away_from(draws.walk, bumper)
        io.walk(memory.walk)
        memory.redirect = False
    if config.walk_curve > 0 and draws.turn is not None:
        _curve(behaviour, draws.turn, fresh=fresh, seeking=seeking)
    if config.walk_turn_ticks > 0 and draws.turn is not None:
        if fresh:
            memory.walk_clock = 0
            return
        if seeking:  # a seeker keeps its heading between hearings
            return
        memory.walk_clock += 1
        if memory.walk_clock >= config.walk_turn_ticks:
            _turn_walk(behaviour, draws.turn)
            memory.walk_clock = 0


def _turn_walk(behaviour: RobotBehaviour, turn: Float) -> None:
    """Rotate the walk direction by ``turn`` ``(cos, sin)``, renormalised, and drive along it."""
    memory = behaviour.memory
    x, y = memory.walk[0], memory.walk[1]
    c, n = turn[0], turn[1]
    rx = x * c - y * n
    ry = x * n + y * c
    norm = np.sqrt(rx * rx + ry * ry)
    memory.walk = np.array([rx / norm, ry / norm])
    behaviour.io.walk(memory.walk)


def _curve(behaviour: RobotBehaviour, turn: Float, *, fresh: bool, seeking: bool) -> None:
    """A curved walk: a new leg takes this tick's ``turn``; the leg turns by it every tick.

    ``decide._curve_walk`` for one robot; a seeker keeps its heading between hearings.
    """
    memory = behaviour.memory
    unset = memory.curve[0] == 0 and memory.curve[1] == 0
    if fresh or (unset and not seeking):
        memory.curve = np.array(turn, dtype=np.float64)
    if fresh or seeking:
        return
    _turn_walk(behaviour, memory.curve)


class SelectCarrier(RobotBehaviour):
    """Select carrier: among the candidates, the active policy's choice (SPEC §3.2, §3.3).

    A candidate is a carrier whose position the cameras know, last heard
    AWAITING_PICKUP, not cooling down and with a free face. SUCCESS with a
    choice (approach starts), FAILURE without. With BLE-led search every tag
    heard so is a candidate, and a chosen one not seen is sought first
    (``swarmtag.robot.search``): FAILURE until a camera sees it.
    """

    keys = (
        "target",
        "face",
        "pursuit_start",
        "blocked_until",
        "seek",
        "seek_ref",
        "timer",
        "redirect",
        "look",
    )

    def update(self) -> Status:
        """Choose at the sensed step only."""
        io, config, memory = self.io, self.config, self.memory
        if io.step != ControlStep.SENSED:
            return Status.FAILURE
        searching = config.radio_search
        if searching and memory.seek >= 0 and not give_up_seeking(io, memory, config):
            return self._confirm()
        tags, seen = io.tag_states(), io.detections()
        available = (
            (tags.status == _AWAITING)
            & (memory.blocked_until <= io.tick)
            & seen.free_faces.any(axis=-1)
        )
        if not searching:
            available &= seen.known
            if config.look_ticks > 0 and not self._looked_round(bool(available.any())):
                available &= False  # looking round: nothing chosen yet
        if not available.any():
            return Status.FAILURE
        choice = int(
            select(
                config.policy,
                urgency=tags.urgency,
                distance=candidate_distances(tags, seen) if searching else seen.distance,
                marker=config.markers,
                available=available,
                context={} if tags.waited is None else {"age": tags.waited},
            )
        )
        if choice < 0:
            return Status.FAILURE
        io.report(Report.SELECT, choice, float(tags.urgency[choice]))
        io.report(Report.CANDIDATES, choice, float(available.sum()))
        memory.pursuit_start = io.tick
        if not seen.known[choice]:  # BLE-led search: seek the tag first
            start_seeking(memory, choice, tags)
            return Status.FAILURE
        self._approach(choice, seen)
        return Status.SUCCESS

    def _looked_round(self, candidates: bool) -> bool:
        """Whether to choose now: a look round before choosing ends (``decide._look_round``).

        Not looking, a robot with ``candidates`` begins to look (stands and
        turns) and chooses nothing yet.
        """
        io, memory = self.io, self.memory
        if memory.look < 0:
            if candidates:
                memory.look = io.tick
                io.look(io.tick)
            return False
        if io.tick - memory.look < self.config.look_ticks:
            return False
        memory.look = -1
        io.look(-1)
        return True

    def _confirm(self) -> Status:
        """A seeker approaches its carrier once a camera sees it (still a candidate)."""
        io, memory = self.io, self.memory
        sought = int(memory.seek)
        tags, seen = io.tag_states(), io.detections()
        if not (
            seen.known[sought]
            and tags.status[sought] == _AWAITING
            and memory.blocked_until[sought] <= io.tick
            and seen.free_faces[sought].any()
        ):
            return Status.FAILURE
        memory.seek = -1
        self._approach(sought, seen)
        return Status.SUCCESS

    def _approach(self, choice: int, seen: Detections) -> None:
        """Start the approach of ``choice`` at its nearest free face (one not taken if any)."""
        io, config = self.io, self.config
        position, centre = io.pose().position, seen.position[choice]
        free = seen.free_faces[choice]
        face = int(nearest_free_face(position, centre, free, config.predock_offset))
        if config.avoid_taken_faces:
            open_face = int(
                nearest_free_face(
                    position, centre, free & ~_taken(io, centre, config), config.predock_offset
                )
            )
            face = open_face if open_face >= 0 else face
        io.approach(choice, face)
        self.memory.target, self.memory.face = choice, face


class RandomWalk(RobotBehaviour):
    """Random walk: drive on a random heading until something is met, then take a new one."""

    keys = ("redirect", "walk", "walk_clock", "seek", "seek_ref", "curve")

    def sensed(self) -> Status:
        """Steer."""
        _steer(self)
        return Status.RUNNING


class ResumeWalk(RobotBehaviour):
    """Back to random walk (after a delivery, or giving a pursuit up): a fresh heading."""

    keys = (
        "target",
        "face",
        "timer",
        "redirect",
        "walk",
        "walk_clock",
        "seek",
        "seek_ref",
        "curve",
    )

    def update(self) -> Status:
        """Walk again; the new heading is taken at the next sensed step (now, if this is one)."""
        self.io.walk()
        self.memory.target = self.memory.face = self.memory.seek = -1
        self.memory.timer = 0
        self.memory.redirect = True
        if self.io.step == ControlStep.SENSED:
            _steer(self)
        return Status.SUCCESS


class StillAwaiting(RobotBehaviour):
    """Guard of a pursuit: abandon at once when the target is heard not AWAITING_PICKUP."""

    keys = ("target", "pursuit_start")

    def update(self) -> Status:
        """Checked at the sensed step of every tick after the selection."""
        io = self.io
        if io.step != ControlStep.SENSED or self.memory.pursuit_start == io.tick:
            return Status.SUCCESS
        target = self.memory.target
        heard = int(io.tag_states().status[target])
        if heard != _AWAITING:
            io.report(Report.ABANDON, target, float(heard))
            return Status.FAILURE
        return Status.SUCCESS


class WithinTimeout(RobotBehaviour):
    """Guard of a pursuit: give up after the timeout; the carrier then cools down for this robot."""

    keys = ("target", "pursuit_start", "blocked_until")

    def update(self) -> Status:
        """Checked at the sensed step of every tick after the selection."""
        io, config = self.io, self.config
        if io.step != ControlStep.SENSED or self.memory.pursuit_start == io.tick:
            return Status.SUCCESS
        if io.tick - self.memory.pursuit_start < config.timeout_ticks:
            return Status.SUCCESS
        target = self.memory.target
        io.report(Report.TIMEOUT, target, float("nan"))
        self.memory.blocked_until[target] = io.tick + config.cooldown_ticks
        return Status.FAILURE


class Predock(RobotBehaviour):
    """Predock: drive to the point in front of the chosen face and turn to face the carrier.

    With ``avoid_taken_faces`` a face another robot stands on is traded for
    the nearest free one not taken. SUCCESS once on the point, facing the
    carrier, with nobody under it (the robot then drives in).
    """

    keys = ("target", "face")

    def sensed(self) -> Status:
        """Move on to another face if this one is taken."""
        io, config, memory = self.io, self.config, self.memory
        if self.just_started() or not config.avoid_taken_faces:
            return Status.RUNNING
        seen = io.detections()
        centre = seen.position[memory.target]
        taken = _taken(io, centre, config)
        if not taken[memory.face]:
            return Status.RUNNING
        free = seen.free_faces[memory.target] & ~taken
        other = int(nearest_free_face(io.pose().position, centre, free, config.predock_offset))
        if other >= 0:
            memory.face = other
            io.approach(memory.target, other)
        return Status.RUNNING

    def moved(self) -> Status:
        """Arrived, facing the carrier, and the space under it free: drive in."""
        io, config, memory = self.io, self.config, self.memory
        centre = io.detections().position[memory.target]
        normal = FACE_NORMALS[memory.face]
        point = centre + normal * config.predock_offset
        pose = io.pose()
        arrived = bool(length(pose.position - point) <= config.arrival_tolerance)
        if (
            arrived
            and bool((pose.heading == -normal).all())
            and not io.dock_occupied(memory.target)
        ):
            io.dock()
            return Status.SUCCESS
        return Status.RUNNING


class Dock(RobotBehaviour):
    """Dock: drive in under the carrier until on its centre."""

    keys = ("target",)

    def start(self) -> None:
        """Drive in."""
        self.io.dock()

    def moved(self) -> Status:
        """On the centre: SUCCESS (centring starts)."""
        if self.just_started():
            return Status.RUNNING
        centre = self.io.detections().position[self.memory.target]
        near = length(self.io.pose().position - centre) <= self.config.arrival_tolerance
        return Status.SUCCESS if bool(near) else Status.RUNNING


def _count_down(memory: Any) -> None:  # noqa: ANN401 - a py_trees blackboard client
    if memory.timer > 0:
        memory.timer -= 1


class Centre(RobotBehaviour):
    """Centre on the underside marker for the docking time, then raise the lift (a tag write).

    SUCCESS when the tag accepts the write, FAILURE when it refuses it.
    """

    keys = ("timer",)

    def start(self) -> None:
        """Stand centred."""
        self.io.centre()
        self.memory.timer = self.config.dock_ticks

    def moved(self) -> Status:
        """Count the centring down; when it is over, write PICKED_UP."""
        if not self.just_started():
            _count_down(self.memory)
        if self.memory.timer == 0:
            self.io.lift()
        return Status.RUNNING

    def answered(self) -> Status:
        """The tag's answer decides."""
        answer = self.io.lift_answer()
        if answer is None:
            return Status.RUNNING
        return Status.SUCCESS if answer else Status.FAILURE


class Lift(RobotBehaviour):
    """Hold still while the lift rises (the lift time)."""

    keys = ("timer",)

    def start(self) -> None:
        """Hold."""
        self.io.hold()
        self.memory.timer = self.config.lift_ticks

    def moved(self) -> Status:
        """Count down."""
        _count_down(self.memory)
        return Status.RUNNING

    def answered(self) -> Status:
        """Up: SUCCESS."""
        return Status.SUCCESS if self.memory.timer == 0 else Status.RUNNING


class Transport(RobotBehaviour):
    """Transport: drive the load to the drop-off area; sidestep when stuck."""

    keys = ("stuck",)

    def start(self) -> None:
        """Head for the drop-off area at the robot's own y (clear of the walls)."""
        config = self.config
        y = np.clip(
            self.io.pose().position[1], config.carrier_half, config.arena - config.carrier_half
        )
        self.io.carry_to(np.array([config.transport_x, y]))
        self.memory.stuck = 0

    def sensed(self) -> Status:
        """Stuck for long enough: sidestep along this tick's random direction."""
        io, config = self.io, self.config
        if self.memory.stuck >= config.stuck_ticks and io.sidestep_left() == 0:
            io.sidestep(away_from(io.random().sidestep, io.bumper()), config.sidestep_ticks)
            self.memory.stuck = 0
        return Status.RUNNING

    def moved(self) -> Status:
        """Count the ticks of too little progress."""
        io = self.io
        slow = bool(length(io.odometry()) < STUCK_PROGRESS * io.speed())
        self.memory.stuck = self.memory.stuck + 1 if io.sidestep_left() == 0 and slow else 0
        return Status.RUNNING

    def answered(self) -> Status:
        """The load wholly inside the drop-off area: SUCCESS."""
        inside = self.io.pose().position[0] - self.config.carrier_half >= self.config.dropoff_left
        return Status.SUCCESS if bool(inside) else Status.RUNNING


class Release(RobotBehaviour):
    """Release: lower the load for the release time, then write IDLE (delivered)."""

    keys = ("timer",)

    def start(self) -> None:
        """Stand and lower."""
        self.io.release()
        self.memory.timer = self.config.release_ticks

    def moved(self) -> Status:
        """Count down."""
        _count_down(self.memory)
        return Status.RUNNING

    def answered(self) -> Status:
        """Down: set the carrier down and write IDLE."""
        if self.memory.timer != 0:
            return Status.RUNNING
        self.io.lower()
        return Status.SUCCESS
