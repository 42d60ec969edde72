"""The controller interface (``swarmtag.sim.control.interface``): ``step`` and ``run_batch`` with others.

Controllers written here wrap the built-in one (``BUILTIN``) and leave out
one of its steps; the world (sensing, motion, docking physics, the tags)
still runs, so what changes is what the controller no longer asks for.
Defaults: step 0.05 m per tick, detection radius 1 m, predock offset
0.3525 m; with the built-in controller a robot on the east predock point
facing the carrier selects it at tick 1 and lifts it at tick 18.
"""

from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest

from swarmtag.sim import Mode, Scene, TickInputs, WorldState, initial_state, run_batch, step
from swarmtag.sim.builtin.controller import BUILTIN, BuiltinController
from swarmtag.sim.control.interface import COMMAND_FIELDS, MEMORY_FIELDS, no_arrivals, no_carrying
from swarmtag.tag import TagStatus
from tests.sim.helpers import Script, event_rows, params_for, start

CARRIER = (0.6, 2.0)
EAST_PREDOCK = (0.6 + 0.3525, 2.0)
WORLD_ROBOT_FIELDS = (
    "robot_pos",
    "heading",
    "speed",
    "ghost",
    "contact",
    "known_status",
    "known_urgency",
    "heard_tick",
    "seen_tick",
    "seen_pos",
    "rssi",
    "odometry",
    "odometry_at",
)
"""Robot fields the world keeps: bodies, perception, the carrier a robot may overlap."""


class NoSelection:
    """The built-in controller without its ``decide`` step: walking robots never select."""

    def decide(self, before, s, *, senses, inputs, params, t, events):
        pass

    def arrive(self, before, s, *, params, t):
        return BUILTIN.arrive(before, s, params=params, t=t)

    def carry(self, s, answers, *, params, t):
        return BUILTIN.carry(s, answers, params=params, t=t)


class NoDocking(BuiltinController):
    """The built-in controller that never asks to drive in, centre, lift or lower."""

    def arrive(self, before, s, *, params, t):
        return no_arrivals(s.mode.shape)

    def carry(self, s, answers, *, params, t):
        return no_carrying(s.mode.shape)


class Recording(BuiltinController):
    """The built-in controller, noting what each step is given."""

    def __init__(self):
        self.calls = []

    def decide(self, before, s, *, senses, inputs, params, t, events):
        self.calls.append(("decide", before, s, t))
        super().decide(before, s, senses=senses, inputs=inputs, params=params, t=t, events=events)

    def arrive(self, before, s, *, params, t):
        self.calls.append(("arrive", before, s, t))
        return super().arrive(before, s, params=params, t=t)

    def carry(self, s, answers, *, params, t):
        self.calls.append(("carry", answers, s, t))
        return super().carry(s, answers, params=params, t=t)


def _walking_scene():
    # the carrier is 0.9 m away, in detection range: the built-in controller selects it
    return Scene.build(robots=[(1.5, 2.0)], heading=[(-1.0, 0.0)], carriers=[CARRIER], urgency=[5])


def _docking_scene():
    return Scene.build(
        robots=[EAST_PREDOCK], heading=[(-1.0, 0.0)], carriers=[CARRIER], urgency=[5]
    )


def _run(scene, ticks, controller, **script):
    params = params_for(robots=1, carriers=1)
    return run_batch(
        start(params, scene),
        params,
        Script(params, **script),
        ticks=ticks,
        check=True,
        controller=controller,
    )


# --- the fields -----------------------------------------------------------------------------


def _robot_fields():
    """Fields of ``WorldState`` with one entry per robot (leading shape (R, N))."""
    params = params_for(robots=3, carriers=5)
    scene = Scene.build(robots=[(2.0, 1.0), (2.0, 2.0), (2.0, 3.0)], carriers=[(0.5, 0.5)] * 5)
    state = initial_state(params, [scene, scene], [0, 1])
    names = set()
    for f in fields(WorldState):
        value = getattr(state, f.name)
        if isinstance(value, np.ndarray) and value.shape[:2] == (2, 3):
            names.add(f.name)
    return names


def test_command_and_memory_fields_are_disjoint_robot_fields_of_the_state():
    names = {f.name for f in fields(WorldState)}
    robot = _robot_fields()
    assert len(set(COMMAND_FIELDS)) == len(COMMAND_FIELDS)
    assert len(set(MEMORY_FIELDS)) == len(MEMORY_FIELDS)
    assert not set(COMMAND_FIELDS) & set(MEMORY_FIELDS)
    assert set(COMMAND_FIELDS) <= names
    assert set(MEMORY_FIELDS) <= names
    assert set(COMMAND_FIELDS) | set(MEMORY_FIELDS) <= robot


def test_commands_memory_and_the_worlds_fields_cover_every_robot_field():
    robot = _robot_fields()
    world = set(WORLD_ROBOT_FIELDS)
    assert not world & (set(COMMAND_FIELDS) | set(MEMORY_FIELDS))
    assert set(COMMAND_FIELDS) | set(MEMORY_FIELDS) | world == robot


# --- controllers given to step and run_batch ------------------------------------------------


def test_a_controller_that_never_selects_leaves_the_world_moving_the_robots():
    builtin = _run(_walking_scene(), 5, BUILTIN, walk=(-1.0, 0.0))
    assert event_rows(builtin) == [(1, "select", 0, 0)]

    result = _run(_walking_scene(), 5, NoSelection(), walk=(-1.0, 0.0))
    assert event_rows(result, candidates=True) == []  # no select, hence no lift ever
    state = result.final_state
    first = start(params_for(robots=1, carriers=1), _walking_scene())
    # the world drives the robot along its walk direction, 0.05 m a tick
    assert state.robot_pos[0, 0] == pytest.approx((1.5 - 5 * 0.05, 2.0), abs=1e-12)
    assert state.known_status[0, 0, 0] == TagStatus.AWAITING_PICKUP  # it still hears the tag
    assert state.status[0].tolist() == [TagStatus.AWAITING_PICKUP]
    for name in COMMAND_FIELDS + MEMORY_FIELDS:  # nobody touched the controller's fields
        np.testing.assert_array_equal(getattr(state, name), getattr(first, name), err_msg=name)


def test_a_controller_that_asks_for_nothing_leaves_docking_to_nobody():
    builtin = _run(_docking_scene(), 25, BUILTIN)
    assert event_rows(builtin) == [(1, "select", 0, 0), (18, "lift", 0, 0)]

    result = _run(_docking_scene(), 25, NoDocking())
    assert event_rows(result) == [(1, "select", 0, 0)]  # it selects, as decide is built in
    state = result.final_state
    # no drive-in request: it stays in PREDOCK on its point, and may not overlap the carrier
    assert state.mode[0, 0] == Mode.PREDOCK
    assert state.ghost[0, 0] == -1
    assert state.robot_pos[0, 0].tolist() == pytest.approx(list(EAST_PREDOCK), abs=1e-12)
    assert state.status[0].tolist() == [TagStatus.AWAITING_PICKUP]
    assert state.carried_by[0].tolist() == [-1]
    assert state.pickup_time[0].tolist() == [-1]


def test_step_gives_each_controller_step_the_tick_start_and_the_state_being_built():
    params = params_for(robots=1, carriers=1)
    state = start(params, _docking_scene())
    recording = Recording()
    for t in range(1, 19):
        recording.calls.clear()
        inputs = TickInputs.fixed(1, 1)
        after, _ = step(state, inputs, params, controller=recording)
        assert [call[0] for call in recording.calls] == ["decide", "arrive", "carry"]
        assert [call[3] for call in recording.calls] == [t, t, t]
        (_, decide_before, built, _), (_, arrive_before, *_), (_, answers, *_) = recording.calls
        assert decide_before is state
        assert arrive_before is state
        assert all(call[2] is built for call in recording.calls)
        assert built is not state
        assert built is after  # the run is not frozen: the built state is the next one
        assert after.tick == t
        # the tags answer the lift write of tick 18 (centred at tick 8, 10 ticks of centring)
        assert answers.accepted.tolist() == [[t == 18]]
        assert not answers.refused.any()
        state = after
    assert state.mode[0, 0] == Mode.LIFT
    assert state.status[0].tolist() == [TagStatus.PICKED_UP]


def test_the_default_controller_is_the_builtin_one():
    params = params_for(robots=1, carriers=1)
    state = start(params, _walking_scene())
    inputs = TickInputs.fixed(1, 1, walk=(-1.0, 0.0))
    default, _ = step(state, inputs, params)
    explicit, _ = step(state, inputs, params, controller=BuiltinController())
    other, _ = step(state, inputs, params, controller=NoSelection())
    for f in fields(WorldState):
        np.testing.assert_array_equal(
            getattr(default, f.name), getattr(explicit, f.name), err_msg=f.name
        )
    assert default.mode[0, 0] == Mode.PREDOCK
    assert other.mode[0, 0] == Mode.WALK
