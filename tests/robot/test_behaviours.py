"""The tree's behaviours against a scripted robot (no simulator): SPEC §3.2 rule by rule."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from swarmtag.policy import Proximity, Urgency
from swarmtag.robot import Behaviour, ControllerConfig, ControlStep, Report, create_tree
from swarmtag.robot.tree import initialise_memory
from swarmtag.sim import Scenario, make_params
from tests.robot.fake_io import FakeIO

py_trees = pytest.importorskip("py_trees")

AWAITING, PICKED_UP = 1, 2


@pytest.fixture
def config():
    params = make_params(Scenario(ticks=1000), Urgency(alpha=0.7))
    return replace(ControllerConfig.from_params(params), avoid_taken_faces=False)


class Robot:
    """A tree on a fake robot, ticked through the three control steps of each tick."""

    _count = 0

    def __init__(self, config: ControllerConfig, io: FakeIO) -> None:
        Robot._count += 1
        self.namespace = f"/test/robot{Robot._count}"
        self.io = io
        self.memory = initialise_memory(self.namespace, config, io)
        self.tree = create_tree(config, self.namespace)
        self.tree.setup(io=io)

    def step(self, step: ControlStep) -> None:
        self.io.step = step
        self.tree.root.tick_once()

    def tick(self, *, answer: bool | None = None) -> None:
        self.io.tick += 1
        self.io.answer = None
        self.step(ControlStep.SENSED)
        self.step(ControlStep.MOVED)
        self.io.answer = answer
        self.step(ControlStep.ANSWERED)

    def close(self) -> None:
        for node in self.tree.root.iterate():
            for client in node.blackboards:
                client.unregister(clear=True)
        self.memory.unregister(clear=True)


@pytest.fixture
def robot(config):
    made = []

    def make(io: FakeIO, changes: dict | None = None) -> Robot:
        markers = np.arange(io.carriers, dtype=np.int64)
        made.append(Robot(replace(config, markers=markers, **(changes or {})), io))
        return made[-1]

    yield make
    for item in made:
        item.close()


def _two_carriers(io: FakeIO) -> None:
    """Carrier 0 near and not urgent, carrier 1 far and urgent, both seen and awaiting."""
    io.carrier_pos[:] = [(2.5, 2.0), (0.5, 2.0)]
    io.known[:] = True
    io.status[:] = AWAITING
    io.urgency[:] = [1, 9]


def _one_carrier(io: FakeIO, position=(1.0, 2.0)) -> None:
    """One carrier, seen and heard awaiting pickup."""
    io.carrier_pos[:] = [position]
    io.known[:] = True
    io.status[:] = AWAITING


def test_a_robot_with_no_candidate_walks(robot):
    io = FakeIO(carriers=2)
    bot = robot(io)
    bot.tick()
    assert io.behaviour is Behaviour.WALK
    assert io.reports == []


def test_the_policy_chooses_and_the_robot_approaches_the_nearest_free_face(robot, config):
    io = FakeIO(carriers=2)
    _two_carriers(io)
    robot(io).tick()
    assert (io.behaviour, io.target) == (Behaviour.PREDOCK, 1)  # urgency 9 over distance
    assert io.face == 0  # the east face looks at the robot
    assert io.reports == [(Report.SELECT, 1, 9.0), (Report.CANDIDATES, 1, 2.0)]
    near = FakeIO(carriers=2)
    _two_carriers(near)
    robot(near, {"policy": Proximity()}).tick()
    assert near.target == 0


def test_a_carrier_heard_picked_up_is_abandoned_at_once(robot):
    io = FakeIO(carriers=2)
    _two_carriers(io)
    bot = robot(io)
    bot.tick()
    io.status[1] = PICKED_UP
    io.walk_draw = np.array([0.0, -1.0])
    bot.tick()
    assert io.reports[-1] == (Report.ABANDON, 1, float(PICKED_UP))
    assert io.behaviour is Behaviour.WALK
    np.testing.assert_array_equal(io.walk_direction, [0.0, -1.0])  # a fresh heading now


def test_a_timed_out_pursuit_cools_down_before_the_carrier_is_chosen_again(robot):
    io = FakeIO(carriers=1)
    _one_carrier(io, (0.5, 2.0))
    bot = robot(io, {"timeout_ticks": 5, "cooldown_ticks": 8})
    bot.tick()  # tick 1: select
    for _ in range(4):
        bot.tick()
    assert io.behaviour is Behaviour.PREDOCK
    bot.tick()  # tick 6: 6 - 1 >= 5
    assert io.reports[-1][0] is Report.TIMEOUT
    assert io.behaviour is Behaviour.WALK
    for _ in range(7):  # ticks 7-13: barred until tick 14
        bot.tick()
        assert io.behaviour is Behaviour.WALK
    bot.tick()
    assert (io.behaviour, io.target) == (Behaviour.PREDOCK, 0)


def test_the_whole_cycle_writes_picked_up_then_idle(robot, config):
    io = FakeIO(carriers=1)
    _one_carrier(io)
    bot = robot(io, {"dock_ticks": 2, "lift_ticks": 1, "release_ticks": 1})
    bot.tick()
    assert io.behaviour is Behaviour.PREDOCK
    # stand on the east predock point, facing west: the robot drives in
    io.position = io.carrier_pos[0] + [config.predock_offset, 0.0]
    io.heading = np.array([-1.0, 0.0])
    bot.tick()
    assert io.behaviour is Behaviour.DOCK
    io.position = io.carrier_pos[0].copy()
    bot.tick()
    assert io.behaviour is Behaviour.CENTRE
    bot.tick()
    assert io.writes == []  # centring: 2 ticks
    bot.tick(answer=True)
    assert io.writes == [("lift", 0)]
    assert io.behaviour is Behaviour.LIFT
    bot.tick()
    assert io.behaviour is Behaviour.TRANSPORT
    np.testing.assert_array_equal(io.goal, [config.transport_x, 2.0])
    io.position = np.array([config.transport_x, 2.0])
    bot.tick()
    assert io.behaviour is Behaviour.RELEASE
    bot.tick()
    assert io.writes == [("lift", 0), ("lower", 0)]
    assert io.behaviour is Behaviour.WALK


def test_a_refused_lift_sends_the_robot_back_to_walk(robot, config):
    io = FakeIO(carriers=1)
    _one_carrier(io)
    bot = robot(io, {"dock_ticks": 0})
    bot.tick()
    io.position = io.carrier_pos[0] + [config.predock_offset, 0.0]
    io.heading = np.array([-1.0, 0.0])
    bot.tick()
    io.position = io.carrier_pos[0].copy()
    bot.tick(answer=False)
    assert io.writes == [("lift", 0)]
    assert io.behaviour is Behaviour.WALK


def test_a_robot_waits_at_its_point_while_another_is_under_the_carrier(robot, config):
    io = FakeIO(carriers=1)
    _one_carrier(io)
    bot = robot(io)
    bot.tick()
    io.position = io.carrier_pos[0] + [config.predock_offset, 0.0]
    io.heading = np.array([-1.0, 0.0])
    io.occupied = True
    bot.tick()
    assert io.behaviour is Behaviour.PREDOCK
    io.occupied = False
    bot.tick()
    assert io.behaviour is Behaviour.DOCK


def test_trees_keep_their_memories_apart(robot):
    first, second = FakeIO(carriers=1), FakeIO(carriers=1)
    for io in (first, second):
        _one_carrier(io, (0.5, 2.0))
    a, b = robot(first), robot(second)
    a.tick()
    assert a.memory.target == 0
    assert b.memory.target == -1


def test_a_tree_needs_its_robot_at_setup(config):
    tree = create_tree(config, "/test/unconnected")
    with pytest.raises(KeyError, match="setup needs io"):
        tree.setup()
    for node in tree.root.iterate():
        for client in node.blackboards:
            client.unregister(clear=True)


def test_no_wall_clock_is_read_while_the_tree_runs(robot, monkeypatch):
    import time

    io = FakeIO(carriers=2)
    _two_carriers(io)
    bot = robot(io)

    def forbidden() -> float:
        raise AssertionError("the tree read the wall clock")

    for name in ("time", "monotonic", "perf_counter"):
        monkeypatch.setattr(time, name, forbidden)
    for _ in range(3):
        bot.tick()
    assert (io.behaviour, io.target) == (Behaviour.PREDOCK, 1)
