"""Moving and resolving collisions (``swarmtag.sim.world.motion``), one call at a time.

Defaults: step 0.05 m per tick, largest turn 9 degrees per tick, robot
radius 0.125 m, carrier half side 0.1775 m, predock offset 0.3525 m, arena
3.75 m.
"""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.sim import Mode, Scene, initial_state
from swarmtag.sim.world.motion import move, resolve
from swarmtag.tag import TagStatus
from tests.sim.helpers import params_for

CARRIER = (0.6, 2.0)
EAST, NORTH, WEST, SOUTH = 0, 1, 2, 3
EXACT = {"rtol": 0, "atol": 1e-12}


def _state(robots, carriers=(CARRIER,), **scene):
    params = params_for(robots=len(robots), carriers=len(carriers))
    built = Scene.build(robots=robots, carriers=list(carriers), **scene)
    return params, initial_state(params, [built], [0]).copy()


def _turned(params, sign=1.0):
    """Heading (1, 0) turned by one full step, counter-clockwise (+1) or clockwise (-1)."""
    return [params.turn_cos, sign * params.turn_sin]


# --- move -----------------------------------------------------------------------------------


def test_a_walker_drives_its_speed_along_its_walk_and_turns_one_step_towards_it():
    params, s = _state([(2.0, 1.0), (2.0, 2.0)], speed_factor=[1.0, 0.5])
    s.walk[0] = [(0.6, 0.8), (0.0, -1.0)]
    proposed = move(s, params)
    np.testing.assert_allclose(proposed[0], [[2.03, 1.04], [2.0, 1.975]], **EXACT)
    np.testing.assert_allclose(s.heading[0], [_turned(params), _turned(params, -1.0)], **EXACT)
    np.testing.assert_array_equal(s.robot_pos[0], [[2.0, 1.0], [2.0, 2.0]])  # only proposed


def test_predock_drives_straight_at_the_point_and_lands_on_it_when_nearer_than_a_step():
    params, s = _state([(1.5, 2.0), (0.9, 2.3525 + 0.4), (0.2475 + 0.03, 1.98)])
    s.mode[0] = Mode.PREDOCK
    s.target[0] = 0
    s.face[0] = [EAST, NORTH, WEST]
    s.heading[0] = [(0.0, 1.0), (0.0, -1.0), (params.turn_cos, params.turn_sin)]
    proposed = move(s, params)
    np.testing.assert_allclose(proposed[0, 0], [1.45, 2.0], **EXACT)
    np.testing.assert_allclose(proposed[0, 1], [0.87, 2.3525 + 0.36], **EXACT)  # 0.3, 0.4 away
    assert proposed[0, 2].tolist() == [0.6 - params.predock_offset, 2.0]  # 0.036 away: lands
    # the heading turns to face the carrier (the face's inward normal), not the travel
    np.testing.assert_allclose(s.heading[0, 0], [-params.turn_sin, params.turn_cos], **EXACT)
    assert s.heading[0, 1].tolist() == [0.0, -1.0]  # faces it already
    assert s.heading[0, 2].tolist() == [1.0, 0.0]  # one step away: exactly onto it


def test_dock_drives_at_the_carrier_centre_without_turning():
    params, s = _state([(0.6, 2.0 + 0.3525), (0.62, 2.0)])
    s.mode[0] = Mode.DOCK
    s.target[0] = 0
    s.face[0] = [NORTH, EAST]
    s.heading[0] = [(1.0, 0.0), (0.0, 1.0)]
    proposed = move(s, params)
    np.testing.assert_allclose(proposed[0, 0], [0.6, 2.3025], **EXACT)
    assert proposed[0, 1].tolist() == [0.6, 2.0]
    assert s.heading[0].tolist() == [[1.0, 0.0], [0.0, 1.0]]


def test_transport_drives_at_the_goal_or_along_the_sidestep_counting_it_down():
    robots = [(3.075, 1.9), (3.35, 1.0), (2.0, 2.0), (3.375, 3.0)]
    params, s = _state(robots, carriers=[(0.3, 0.3)] * 4)
    s.mode[0] = Mode.TRANSPORT
    s.target[0] = [0, 1, 2, 3]
    s.goal[0] = [(3.375, 2.3), (3.375, 1.0), (3.375, 2.0), (3.375, 3.0)]
    s.sidestep[0] = [0, 0, 3, 0]
    s.sidestep_dir[0, 2] = (0.0, -1.0)
    s.heading[0, 3] = (0.0, 1.0)
    proposed = move(s, params)
    np.testing.assert_allclose(proposed[0, 0], [3.105, 1.94], **EXACT)  # 0.3, 0.4 away
    assert proposed[0, 1].tolist() == [3.375, 1.0]  # 0.025 away: lands on it
    np.testing.assert_allclose(proposed[0, 2], [2.0, 1.95], **EXACT)  # sidestepping, not to goal
    assert proposed[0, 3].tolist() == [3.375, 3.0]  # at its goal: stays
    assert s.sidestep[0].tolist() == [0, 0, 2, 0]
    np.testing.assert_allclose(s.heading[0, 0], _turned(params), **EXACT)
    assert s.heading[0, 1].tolist() == [1.0, 0.0]  # drives along its heading
    np.testing.assert_allclose(s.heading[0, 2], _turned(params, -1.0), **EXACT)
    assert s.heading[0, 3].tolist() == [0.0, 1.0]  # did not move: does not turn


@pytest.mark.parametrize("mode", [Mode.CENTRE, Mode.LIFT, Mode.RELEASE, Mode.BROKEN])
def test_centring_lifting_releasing_and_broken_robots_stand_still(mode):
    params, s = _state([(2.0, 2.0)])
    s.mode[0, 0] = mode
    s.target[0, 0] = 0
    s.walk[0, 0] = (0.6, 0.8)
    s.heading[0, 0] = (0.0, 1.0)
    s.goal[0, 0] = (3.375, 1.0)
    s.sidestep[0, 0] = 2
    s.sidestep_dir[0, 0] = (1.0, 0.0)
    proposed = move(s, params)
    assert proposed[0, 0].tolist() == [2.0, 2.0]
    assert s.heading[0, 0].tolist() == [0.0, 1.0]
    assert s.sidestep[0, 0] == 2


# --- resolve --------------------------------------------------------------------------------


def test_two_overlapping_walkers_are_pushed_apart_half_and_half():
    params, s = _state([(1.9, 2.0), (2.3, 2.0)])
    proposed = np.array([[[2.0, 2.0], [2.2, 2.0]]])  # 0.2 apart: 0.05 overlap
    resolve(s, proposed, params)
    np.testing.assert_allclose(s.robot_pos[0], [[1.975, 2.0], [2.225, 2.0]], **EXACT)
    np.testing.assert_allclose(s.contact[0], [[-0.025, 0.0], [0.025, 0.0]], **EXACT)


@pytest.mark.parametrize("still", [Mode.CENTRE, Mode.BROKEN])
def test_a_robot_standing_still_is_not_moved_and_the_other_takes_the_whole_push(still):
    params, s = _state([(2.0, 2.0), (2.3, 2.0)])
    s.mode[0, 0] = still
    proposed = np.array([[[2.0, 2.0], [2.2, 2.0]]])
    resolve(s, proposed, params)
    assert s.robot_pos[0, 0].tolist() == [2.0, 2.0]
    np.testing.assert_allclose(s.robot_pos[0, 1], [2.25, 2.0], **EXACT)
    assert s.contact[0, 0].tolist() == [0.0, 0.0]
    np.testing.assert_allclose(s.contact[0, 1], [0.05, 0.0], **EXACT)


def test_robots_are_clamped_inside_the_walls_and_a_carried_carrier_follows_its_robot():
    params, s = _state([(3.6, 0.2), (3.5, 3.5)], carriers=[(3.5, 3.5)])
    s.mode[0, 1] = Mode.TRANSPORT
    s.target[0, 1] = 0
    s.carried_by[0, 0] = 1
    s.status[0, 0] = TagStatus.PICKED_UP
    proposed = np.array([[[3.7, 0.05], [3.7, 3.7]]])
    resolve(s, proposed, params)
    assert s.robot_pos[0, 0].tolist() == [3.625, 0.125]  # a disc of radius 0.125
    edge = params.arena - params.carrier_half  # a loaded robot is its carrier's square
    assert s.robot_pos[0, 1].tolist() == [edge, edge]
    assert s.carrier_pos[0, 0].tolist() == [edge, edge]
    np.testing.assert_allclose(s.contact[0, 0], [-0.075, 0.075], **EXACT)
    np.testing.assert_allclose(s.contact[0, 1], [edge - 3.7, edge - 3.7], **EXACT)


def test_a_carrier_pushes_a_walker_out_but_not_the_robot_under_it():
    params, s = _state([(0.95, 2.0), (0.5, 2.0)])
    s.mode[0, 1] = Mode.DOCK
    s.target[0, 1] = 0
    s.ghost[0, 1] = 0
    proposed = np.array([[[0.8775, 2.0], [0.5, 2.0]]])  # 0.1 from the east face: 0.025 deep
    resolve(s, proposed, params)
    np.testing.assert_allclose(s.robot_pos[0, 0], [0.9025, 2.0], **EXACT)
    np.testing.assert_allclose(s.contact[0, 0], [0.025, 0.0], **EXACT)
    assert s.robot_pos[0, 1].tolist() == [0.5, 2.0]
    assert s.contact[0, 1].tolist() == [0.0, 0.0]


def test_the_ghost_is_forgotten_once_a_robot_not_docking_or_centring_is_clear_of_it():
    # clear of the carrier's square at 0.1775 + 0.125 = 0.3025 from its centre
    robots = [(0.92, 2.0), (0.6, 2.25), (0.28, 2.0), (0.6, 1.68)]
    params, s = _state(robots)
    s.mode[0] = [Mode.WALK, Mode.WALK, Mode.DOCK, Mode.CENTRE]
    s.target[0] = [-1, -1, 0, 0]
    s.ghost[0] = 0
    proposed = s.robot_pos.copy()
    resolve(s, proposed, params)
    assert s.ghost[0].tolist() == [-1, 0, 0, 0]
    np.testing.assert_array_equal(s.robot_pos, proposed)  # the overlapping one is let be
    assert not s.contact.any()
