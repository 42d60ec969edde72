"""The simulator's robot-I/O view: sensors read the world as the built-in controller does."""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.policy import Urgency
from swarmtag.robot import ControlStep, Report
from swarmtag.robot.sim_io import SimRobotIO, StepContext
from swarmtag.sim import Mode, RandomSource, Scenario, make_params
from swarmtag.sim.runner import seeded_state
from swarmtag.sim.world.sensing import sense, sensed_state


@pytest.fixture
def setting():
    params = make_params(Scenario.default(3, 7), Urgency(alpha=0.7))
    before = seeded_state(params, seed=4, runs=2)
    inputs = RandomSource(params, seed=4, run_ids=before.run_ids).inputs(1)
    senses = sense(before, inputs, params)
    return params, before, senses, inputs


def _context(setting, step=ControlStep.SENSED, **extra):
    """The context of a control step of tick 1, as the kernel builds it."""
    params, before, senses, inputs = setting
    s = sensed_state(before, senses)
    return StepContext(step, 1, before, s, params, senses, inputs, **extra)


def test_sensors_are_the_numbers_the_built_in_controller_reads(setting):
    context = _context(setting)
    _, _, senses, inputs = setting
    view = SimRobotIO(1, 2, context)
    assert (view.robot, view.tick, view.step) == (2, 1, ControlStep.SENSED)
    np.testing.assert_array_equal(view.pose().position, context.s.robot_pos[1, 2])
    np.testing.assert_array_equal(view.pose().heading, context.s.heading[1, 2])
    tags = view.tag_states()
    np.testing.assert_array_equal(tags.status, senses.known_status[1, 2])
    np.testing.assert_array_equal(tags.urgency, senses.known_urgency[1, 2])
    heard = senses.heard_tick[1, 2] >= 0
    np.testing.assert_array_equal(tags.age, np.where(heard, 0, -1))  # heard this tick: age 0
    seen = view.detections()
    np.testing.assert_array_equal(seen.known, senses.known[1, 2])
    np.testing.assert_array_equal(seen.distance, senses.distance[1, 2])
    np.testing.assert_array_equal(seen.position, context.s.carrier_pos[1])
    np.testing.assert_array_equal(seen.free_faces, context.s.free_face[1])
    draws = view.random()
    np.testing.assert_array_equal(draws.walk, inputs.walk[1, 2])
    np.testing.assert_array_equal(draws.sidestep, inputs.sidestep[1, 2])
    assert draws.turn is None  # the default walk does not turn
    assert view.speed() == context.s.speed[1, 2]
    np.testing.assert_array_equal(view.odometry(), [0.0, 0.0])
    assert view.lift_answer() is None


def test_neighbours_are_the_other_robots_within_sight(setting):
    context = _context(setting)
    s = context.s
    sight = context.params.detection_radius
    s.robot_pos[0] = [(1.0, 1.0), (1.0, 1.0 + sight), (1.0 + sight + 1e-9, 1.0)]
    found = SimRobotIO(0, 0, context).neighbours()
    np.testing.assert_array_equal(found, [[1.0, 1.0 + sight]])  # at sight: seen; beyond: not


def test_actuators_set_the_command_registers_and_the_requests(setting):
    context = _context(setting, ControlStep.MOVED)
    s = context.s
    view = SimRobotIO(0, 1, context)
    view.approach(3, 2)
    assert (s.mode[0, 1], s.target[0, 1], s.face[0, 1]) == (Mode.PREDOCK, 3, 2)
    view.dock()
    assert s.mode[0, 1] == Mode.DOCK
    assert context.drive_in[0, 1]
    view.centre()
    assert s.mode[0, 1] == Mode.CENTRE
    assert context.centred[0, 1]
    view.lift()
    assert context.lift.tolist() == [[-1, 3, -1], [-1, -1, -1]]
    view.hold()
    assert s.mode[0, 1] == Mode.LIFT
    view.carry_to(np.array([3.0, 1.5]))
    assert s.mode[0, 1] == Mode.TRANSPORT
    assert context.raised[0, 1]
    np.testing.assert_array_equal(s.goal[0, 1], [3.0, 1.5])
    view.sidestep(np.array([0.0, 1.0]), 5)
    assert view.sidestep_left() == 5
    view.release()
    assert s.mode[0, 1] == Mode.RELEASE
    view.lower()
    assert context.lower.tolist() == [[-1, 3, -1], [-1, -1, -1]]
    view.walk(np.array([0.0, -1.0]))
    assert (s.mode[0, 1], s.target[0, 1], s.face[0, 1]) == (Mode.WALK, -1, -1)
    np.testing.assert_array_equal(s.walk[0, 1], [0.0, -1.0])
    view.report(Report.SELECT, 4, 9.0)
    assert context.reports == [(Report.SELECT, 0, 1, 4, 9.0)]


def test_dock_occupied_sees_other_robots_under_the_carrier_only(setting):
    context = _context(setting, ControlStep.MOVED)
    s = context.s
    s.mode[0] = [Mode.CENTRE, Mode.PREDOCK, Mode.WALK]
    s.target[0] = [5, 5, -1]
    assert SimRobotIO(0, 1, context).dock_occupied(5)
    assert not SimRobotIO(0, 1, context).dock_occupied(4)
    assert not SimRobotIO(0, 0, context).dock_occupied(5)  # itself does not count
    s.mode[0, 0] = Mode.BROKEN
    assert not SimRobotIO(0, 1, context).dock_occupied(5)


def test_lift_answers_are_read_per_robot(setting):
    accepted = np.array([[True, False, False], [False, False, False]])
    refused = np.array([[False, True, False], [False, False, False]])
    context = _context(setting, ControlStep.ANSWERED, accepted=accepted, refused=refused)
    assert [SimRobotIO(0, n, context).lift_answer() for n in range(3)] == [True, False, None]


def test_the_announced_behaviours_are_the_simulator_modes():
    from swarmtag.robot import Behaviour

    assert {b.name: int(b) for b in Behaviour} == {
        m.name: int(m) for m in Mode if m is not Mode.BROKEN
    }
