"""The built-in controller's ``arrive`` and ``carry`` steps (``swarmtag.sim.builtin.docking``) alone.

Each test sets the robots' fields by hand and calls one step. Defaults:
step 0.05 m per tick (a stuck tick is under 0.0125 m), carrier half side
0.1775 m, predock offset 0.3525 m, arrival tolerance 0.01 m,
dock = lift = release = 10 ticks, drop-off area x >= 3.0 (middle 3.375),
arena 3.75 m.
"""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.sim import Mode, Scene, initial_state
from swarmtag.sim.builtin.docking import arrive, carry
from swarmtag.sim.control.interface import LiftAnswers
from tests.sim.helpers import params_for

T = 12
CARRIERS = [(0.6, 0.6), (0.6, 1.6), (0.6, 2.6)]
EAST, NORTH, WEST, SOUTH = 0, 1, 2, 3
OFFSET = 0.3525


def _state(params):
    robots = [(2.0, 0.4 + 0.6 * i) for i in range(params.robots)]
    scene = Scene.build(robots=robots, carriers=CARRIERS[: params.carriers])
    return initial_state(params, [scene], [0]).copy()


def _setup(robots, carriers=3):
    params = params_for(robots=robots, carriers=carriers)
    before = _state(params)
    return params, before, before.copy()


def _answers(accepted=(), refused=(), robots=3):
    yes = np.zeros((1, robots), dtype=bool)
    no = yes.copy()
    yes[0, list(accepted)] = True
    no[0, list(refused)] = True
    return LiftAnswers(accepted=yes, refused=no)


def _predock(carrier, face):
    x, y = CARRIERS[carrier]
    nx, ny = [(1, 0), (0, 1), (-1, 0), (0, -1)][face]
    return (x + nx * OFFSET, y + ny * OFFSET), (-float(nx), -float(ny))


def _approach(s, robot, carrier, face, shift=(0.0, 0.0)):
    """Put ``robot`` in PREDOCK for ``carrier`` on its ``face`` point (plus ``shift``), facing it."""
    point, heading = _predock(carrier, face)
    s.mode[0, robot] = Mode.PREDOCK
    s.target[0, robot] = carrier
    s.face[0, robot] = face
    s.robot_pos[0, robot] = (point[0] + shift[0], point[1] + shift[1])
    s.heading[0, robot] = heading


# --- arrive ---------------------------------------------------------------------------------


def test_stuck_count_rises_only_for_a_transporting_robot_that_barely_moved():
    params, before, s = _setup(robots=5)
    s.mode[0] = [Mode.TRANSPORT, Mode.TRANSPORT, Mode.WALK, Mode.TRANSPORT, Mode.TRANSPORT]
    s.sidestep[0] = [0, 0, 0, 2, 0]
    s.stuck[0] = [2, 2, 2, 2, 2]
    s.speed[0, 4] = 0.025  # a slow robot: its stuck threshold is 0.00625 m
    moved = [0.01, 0.02, 0.0, 0.0, 0.01]
    s.robot_pos[0, :, 0] += moved
    before_pos = s.robot_pos.copy()
    arrive(before, s, params=params, t=T)
    # only robot 0 is driving to the drop-off area and made less than 0.0125 m
    assert s.stuck[0].tolist() == [3, 0, 0, 0, 0]
    np.testing.assert_array_equal(s.robot_pos, before_pos)


def test_timers_of_centring_lifting_and_releasing_robots_count_down():
    params, before, s = _setup(robots=6)
    s.mode[0] = [Mode.CENTRE, Mode.CENTRE, Mode.CENTRE, Mode.LIFT, Mode.RELEASE, Mode.TRANSPORT]
    s.target[0] = [0, 1, 2, 0, 1, 2]
    s.timer[0] = [5, 1, 0, 1, 10, 3]
    arrivals = arrive(before, s, params=params, t=T)
    assert s.timer[0].tolist() == [4, 0, 0, 0, 9, 3]
    assert s.mode[0].tolist() == [
        Mode.CENTRE,
        Mode.CENTRE,
        Mode.CENTRE,
        Mode.LIFT,
        Mode.RELEASE,
        Mode.TRANSPORT,
    ]
    # centring is over for robots 1 and 2: they write PICKED_UP to their carrier
    assert arrivals.lift[0].tolist() == [-1, 1, 2, -1, -1, -1]
    assert not arrivals.drive_in.any()
    assert not arrivals.centred.any()


@pytest.mark.parametrize(
    ("face", "shift", "heading", "drives_in"),
    [
        (EAST, (0.0, 0.0), None, True),
        (NORTH, (0.0, 0.0), None, True),
        (WEST, (0.006, -0.0075), None, True),  # 0.0096 m away: within the tolerance
        (SOUTH, (0.0, 0.0), None, True),
        (EAST, (0.0, 0.0101), None, False),
        (EAST, (0.0, 0.0), (0.0, 1.0), False),  # on the point but not facing the carrier
        (EAST, (0.0, 0.0), (-0.9999875, 0.005), False),  # nearly facing it
    ],
)
def test_a_robot_on_its_predock_point_facing_the_carrier_drives_in(face, shift, heading, drives_in):
    params, before, s = _setup(robots=1)
    _approach(s, 0, 1, face, shift)
    if heading is not None:
        s.heading[0, 0] = heading
    arrivals = arrive(before, s, params=params, t=T)
    assert arrivals.drive_in[0].tolist() == [drives_in]
    assert s.mode[0, 0] == (Mode.DOCK if drives_in else Mode.PREDOCK)
    assert s.target[0, 0] == 1
    assert not arrivals.centred.any()
    assert arrivals.lift[0].tolist() == [-1]


@pytest.mark.parametrize("mode", [Mode.DOCK, Mode.CENTRE, Mode.LIFT])
def test_an_arriving_robot_waits_while_another_is_under_the_carrier(mode):
    params, before, s = _setup(robots=3)
    _approach(s, 0, 1, WEST)  # robot 0 arrives at carrier 1
    _approach(s, 2, 2, WEST)  # robot 2 arrives at carrier 2, where nobody is
    s.mode[0, 1] = mode  # robot 1 (a larger id) is under carrier 1
    s.target[0, 1] = 1
    s.robot_pos[0, 1] = (0.7, 1.6)  # 0.1 m from the centre: a DOCK robot does not centre yet
    s.timer[0, 1] = 0 if mode == Mode.DOCK else 5
    arrivals = arrive(before, s, params=params, t=T)
    assert arrivals.drive_in[0].tolist() == [False, False, True]
    assert s.mode[0].tolist() == [Mode.PREDOCK, mode, Mode.DOCK]


@pytest.mark.parametrize("mode", [Mode.WALK, Mode.PREDOCK, Mode.TRANSPORT, Mode.RELEASE])
def test_robots_not_docking_there_do_not_stop_an_arriving_one(mode):
    params, before, s = _setup(robots=2)
    _approach(s, 1, 1, EAST)
    s.mode[0, 0] = mode  # robot 0 is near carrier 1 but not docking, centring or lifting
    s.target[0, 0] = 1
    s.face[0, 0] = NORTH
    s.robot_pos[0, 0] = (0.6, 1.6)
    s.timer[0, 0] = 5
    arrivals = arrive(before, s, params=params, t=T)
    assert arrivals.drive_in[0].tolist() == [False, True]
    assert s.mode[0, 1] == Mode.DOCK


def test_of_two_arriving_at_one_carrier_in_a_tick_the_smaller_id_goes_in():
    params, before, s = _setup(robots=4)
    _approach(s, 0, 1, EAST)
    _approach(s, 1, 0, NORTH)
    _approach(s, 2, 0, SOUTH)
    _approach(s, 3, 1, WEST)
    arrivals = arrive(before, s, params=params, t=T)
    assert arrivals.drive_in[0].tolist() == [True, True, False, False]
    assert s.mode[0].tolist() == [Mode.DOCK, Mode.DOCK, Mode.PREDOCK, Mode.PREDOCK]


def test_a_docking_robot_at_the_centre_starts_centring():
    params, before, s = _setup(robots=3)
    s.mode[0] = [Mode.DOCK, Mode.DOCK, Mode.DOCK]
    s.target[0] = [0, 1, 2]
    s.robot_pos[0] = [(0.6, 0.6), (0.607, 1.607), (0.6, 2.611)]  # 0, 0.0099, 0.011 m off
    arrivals = arrive(before, s, params=params, t=T)
    assert arrivals.centred[0].tolist() == [True, True, False]
    assert s.mode[0].tolist() == [Mode.CENTRE, Mode.CENTRE, Mode.DOCK]
    assert s.timer[0].tolist() == [10, 10, 0]
    assert arrivals.lift[0].tolist() == [-1, -1, -1]  # centring has only begun
    assert not arrivals.drive_in.any()


# --- carry ----------------------------------------------------------------------------------


def test_a_refused_lift_sends_the_robot_back_to_walking():
    params, _, s = _setup(robots=3)
    s.mode[0] = [Mode.CENTRE, Mode.CENTRE, Mode.CENTRE]
    s.target[0] = [0, 0, 1]
    s.face[0] = [EAST, WEST, SOUTH]
    carrying = carry(s, _answers(accepted=[0], refused=[1]), params=params, t=T)
    assert s.mode[0].tolist() == [Mode.LIFT, Mode.WALK, Mode.CENTRE]
    assert s.target[0].tolist() == [0, -1, 1]
    assert s.face[0].tolist() == [EAST, -1, SOUTH]
    assert s.redirect[0].tolist() == [False, True, False]
    assert s.timer[0].tolist() == [10, 0, 0]  # the accepted one holds for lift_ticks
    assert not carrying.raised.any()
    assert carrying.lower[0].tolist() == [-1, -1, -1]


@pytest.mark.parametrize(
    ("y", "goal_y"),
    [(2.0, 2.0), (0.1, 0.1775), (3.7, 3.75 - 0.1775)],
    ids=["middle", "near-south-wall", "near-north-wall"],
)
def test_a_robot_whose_lift_is_up_heads_for_the_drop_off_area(y, goal_y):
    params, _, s = _setup(robots=2)
    s.mode[0] = [Mode.LIFT, Mode.LIFT]
    s.target[0] = [0, 1]
    s.timer[0] = [0, 3]
    s.stuck[0] = [4, 0]
    s.sidestep[0] = [2, 0]
    s.robot_pos[0] = [(0.6, y), (0.6, 1.6)]
    carrying = carry(s, _answers(robots=2), params=params, t=T)
    assert carrying.raised[0].tolist() == [True, False]
    assert s.mode[0].tolist() == [Mode.TRANSPORT, Mode.LIFT]
    assert s.goal[0, 0].tolist() == [3.375, goal_y]
    assert s.goal[0, 1].tolist() == [0.0, 0.0]  # still lifting: no goal yet
    assert s.stuck[0].tolist() == [0, 0]
    assert s.sidestep[0].tolist() == [0, 0]
    assert s.target[0].tolist() == [0, 1]
    assert carrying.lower[0].tolist() == [-1, -1]


def test_a_transporting_robot_whose_load_is_in_the_drop_off_area_releases_it():
    params, _, s = _setup(robots=3)
    s.mode[0] = [Mode.TRANSPORT, Mode.TRANSPORT, Mode.WALK]
    s.target[0] = [0, 1, -1]
    s.robot_pos[0] = [(3.18, 1.0), (3.17, 2.0), (3.5, 3.0)]  # left edges 3.0025, 2.9925
    carrying = carry(s, _answers(), params=params, t=T)
    assert s.mode[0].tolist() == [Mode.RELEASE, Mode.TRANSPORT, Mode.WALK]
    assert s.timer[0].tolist() == [10, 0, 0]
    assert carrying.lower[0].tolist() == [-1, -1, -1]  # releasing takes release_ticks
    assert not carrying.raised.any()


def test_a_robot_whose_release_is_over_lowers_its_carrier_and_walks():
    params, _, s = _setup(robots=2)
    s.mode[0] = [Mode.RELEASE, Mode.RELEASE]
    s.target[0] = [2, 1]
    s.timer[0] = [0, 4]
    s.robot_pos[0] = [(3.3, 1.0), (3.3, 2.0)]
    carrying = carry(s, _answers(robots=2), params=params, t=T)
    assert carrying.lower[0].tolist() == [2, -1]
    assert s.mode[0].tolist() == [Mode.WALK, Mode.RELEASE]
    assert s.target[0].tolist() == [-1, 1]
    assert s.redirect[0].tolist() == [True, False]
    assert s.timer[0].tolist() == [0, 4]  # carry does not count down (arrive does)
    assert not carrying.raised.any()
