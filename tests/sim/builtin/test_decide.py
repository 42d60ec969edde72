"""The built-in controller's ``decide`` step (``swarmtag.sim.builtin.decide``) called alone.

Each test builds a state at the end of tick ``t - 1``, senses it as the
kernel does (``sense``, whose caches become the state's), calls ``decide``
and checks what it wrote. Defaults: disc perception of radius 1 m, predock
offset 0.3525 m, Proximity policy.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from swarmtag.errors import ConfigError
from swarmtag.policy import Urgency
from swarmtag.sim import (
    Camera,
    EventKind,
    Mode,
    Motion,
    Radio,
    Scenario,
    Scene,
    TickEvents,
    TickInputs,
    Timing,
    Walk,
    initial_state,
    simulate,
)
from swarmtag.sim.builtin.decide import decide
from swarmtag.sim.world.sensing import sense, sensed_state
from swarmtag.tag import TagStatus
from tests.sim.helpers import params_for

IDLE, AWAITING, PICKED_UP = (int(s) for s in TagStatus)
T = 40
EAST, NORTH, WEST, SOUTH = 0, 1, 2, 3


def _state(params, robots, carriers, **scene):
    built = Scene.build(robots=robots, carriers=carriers, **scene)
    return initial_state(params, [built], [0]).copy()


def _decide(before, params, inputs=None, t=T):
    """Sense ``before`` as the end of tick ``t - 1`` and decide tick ``t``: (state, events)."""
    before = replace(before, tick=t - 1)
    inputs = inputs if inputs is not None else TickInputs.fixed(1, params.robots)
    senses = sense(before, inputs, params)
    s = sensed_state(before, senses)
    events = TickEvents()
    decide(before, s, senses=senses, inputs=inputs, params=params, t=t, events=events)
    return s, events


def _only(events, kind):
    entries = [e for e in events.entries if e.kind is kind]
    assert len(entries) == 1, [e.kind for e in events.entries]
    return entries[0]


def _kinds(events):
    return [e.kind for e in events.entries]


# --- pursuit checks -------------------------------------------------------------------------


def test_a_pursuer_abandons_on_the_status_it_heard_and_does_not_select_in_the_same_tick():
    params = params_for(robots=4, carriers=2)
    before = _state(
        params, [(1.0, 1.5), (0.6, 1.0), (0.9525, 1.0), (2.5, 3.0)], [(0.6, 2.0), (0.6, 1.0)]
    )
    before.status[0, 0] = PICKED_UP  # another robot lifted carrier 0
    before.adv_status[0, :, 0] = PICKED_UP
    before.mode[0] = [Mode.PREDOCK, Mode.CENTRE, Mode.PREDOCK, Mode.WALK]
    before.target[0] = [0, 1, 1, -1]
    before.face[0] = [EAST, EAST, EAST, -1]
    before.timer[0] = [0, 4, 0, 0]
    before.pursuit_start[0] = [T - 5, T - 5, T - 5, -1]
    before.known_status[0, 1, 1] = IDLE  # robot 1's cache; it misses this tick's advertisement
    heard = np.ones((1, 4, 2), dtype=bool)
    heard[0, 1] = False
    inputs = replace(TickInputs.fixed(1, 4, walk=(0.0, -1.0)), heard=heard)
    s, events = _decide(before, params, inputs)

    entry = _only(events, EventKind.ABANDON)
    assert entry.mask[0].tolist() == [True, True, False, False]
    assert entry.carrier[0, :2].tolist() == [0, 1]
    assert entry.value[0, :2].tolist() == [float(PICKED_UP), float(IDLE)]
    assert _kinds(events) == [EventKind.ABANDON]  # robot 0 sees carrier 1 awaiting: no select
    assert s.mode[0].tolist() == [Mode.WALK, Mode.WALK, Mode.PREDOCK, Mode.WALK]
    assert s.target[0].tolist() == [-1, -1, 1, -1]
    assert s.face[0].tolist() == [-1, -1, EAST, -1]
    assert s.timer[0].tolist() == [0, 0, 0, 0]
    # back to walking: this tick's direction is taken at once and the request is used up
    assert s.walk[0].tolist() == [[0.0, -1.0], [0.0, -1.0], [1.0, 0.0], [1.0, 0.0]]
    assert not s.redirect.any()
    assert not s.blocked_until.any()


def test_a_pursuit_times_out_at_exactly_the_timeout_and_bars_the_carrier():
    params = params_for(robots=2, carriers=2, timing=Timing(pursuit_timeout=2.0, cooldown=1.5))
    assert (params.timeout_ticks, params.cooldown_ticks) == (20, 15)
    before = _state(params, [(0.9525, 2.0), (0.9525, 1.0)], [(0.6, 2.0), (0.6, 1.0)])
    before.mode[0] = Mode.PREDOCK
    before.target[0] = [0, 1]
    before.face[0] = EAST
    before.pursuit_start[0] = [T - 20, T - 19]
    s, events = _decide(before, params)

    entry = _only(events, EventKind.TIMEOUT)
    assert entry.mask[0].tolist() == [True, False]
    assert entry.carrier[0, 0] == 0
    assert np.isnan(entry.value[0, 0])
    assert _kinds(events) == [EventKind.TIMEOUT]
    assert s.blocked_until[0].tolist() == [[T + 15, 0], [0, 0]]
    assert s.mode[0].tolist() == [Mode.WALK, Mode.PREDOCK]
    assert s.target[0].tolist() == [-1, 1]
    assert s.pursuit_start[0, 1] == T - 19


# --- selection ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("blocked", "t", "chosen", "candidates"),
    [([T + 1, 0], T, 1, 1.0), ([T + 1, 0], T + 1, 0, 2.0), ([T + 1, T + 1], T, -1, 0.0)],
    ids=["cooling-down", "cool-down-over", "both-cooling-down"],
)
def test_a_carrier_cooling_down_for_the_robot_is_no_candidate_until_then(
    blocked, t, chosen, candidates
):
    params = params_for(robots=1, carriers=2)
    # carrier 0 is nearer (0.721 m against 0.849 m)
    before = _state(params, [(1.2, 1.6)], [(0.6, 2.0), (0.6, 1.0)])
    before.blocked_until[0, 0] = blocked
    s, events = _decide(before, params, t=t)
    if chosen < 0:
        assert events.entries == []
        assert s.mode[0, 0] == Mode.WALK
        return
    assert _only(events, EventKind.SELECT).carrier[0, 0] == chosen
    assert _only(events, EventKind.CANDIDATES).value[0, 0] == candidates
    assert (s.mode[0, 0], s.target[0, 0], s.pursuit_start[0, 0]) == (Mode.PREDOCK, chosen, t)


def test_select_records_the_heard_urgency_and_candidates_how_many_there_were():
    params = params_for(robots=3, carriers=3)
    before = _state(
        params,
        [(1.2, 1.6), (1.2, 2.6), (2.5, 0.5)],
        [(0.6, 2.0), (0.6, 1.0), (0.6, 3.0)],
        urgency=[7, 3, 5],
        status=[AWAITING, AWAITING, IDLE],
    )
    before.adv_urgency[0, :] = [4, 2, 6]  # what the tags advertised (not the true urgency)
    s, events = _decide(before, params)
    # robot 0 sees carriers 0 and 1, robot 1 carriers 0 and 2 (IDLE), robot 2 none
    select = _only(events, EventKind.SELECT)
    assert select.mask[0].tolist() == [True, True, False]
    assert select.carrier[0, :2].tolist() == [0, 0]
    assert select.value[0, :2].tolist() == [4.0, 4.0]
    counted = _only(events, EventKind.CANDIDATES)
    assert counted.mask[0].tolist() == [True, True, False]
    assert counted.value[0, :2].tolist() == [2.0, 1.0]
    assert _kinds(events) == [EventKind.SELECT, EventKind.CANDIDATES]
    assert s.mode[0].tolist() == [Mode.PREDOCK, Mode.PREDOCK, Mode.WALK]
    assert s.target[0].tolist() == [0, 0, -1]
    assert s.pursuit_start[0, :2].tolist() == [T, T]


@pytest.mark.parametrize(
    ("robot", "free", "face"),
    [
        ((1.25, 1.25), [True] * 4, EAST),  # E and N equally near: face order
        ((1.25, 1.25), [False, True, True, True], NORTH),
        ((0.75, 0.75), [True] * 4, WEST),  # W and S
        ((0.75, 0.75), [True, True, False, True], SOUTH),
        ((1.25, 0.75), [True] * 4, EAST),  # E and S
        ((0.75, 1.25), [True] * 4, NORTH),  # N and W
        ((1.1, 1.4), [True] * 4, NORTH),
        ((1.1, 1.4), [True, False, True, True], EAST),
        ((1.1, 1.4), [False] * 4, -1),  # no free face: no candidate
    ],
)
def test_the_chosen_face_is_the_nearest_free_one_ties_in_face_order(robot, free, face):
    params = params_for(robots=1, carriers=1)
    before = _state(params, [robot], [(1.0, 1.0)])
    before.free_face[0, 0] = free
    s, events = _decide(before, params)
    if face < 0:
        assert events.entries == []
        assert (s.mode[0, 0], s.face[0, 0]) == (Mode.WALK, -1)
        return
    assert (s.mode[0, 0], s.target[0, 0], s.face[0, 0]) == (Mode.PREDOCK, 0, face)


# --- walk directions and sidesteps ----------------------------------------------------------


def test_a_walker_that_touched_something_or_must_redirect_takes_this_ticks_direction():
    params = params_for(robots=6, carriers=1)
    robots = [(2.0, 0.5 + 0.5 * i) for i in range(6)]
    before = _state(params, robots, [(0.3, 0.3)], status=[IDLE])
    before.walk[0] = (0.8, -0.6)
    before.mode[0, 4] = Mode.TRANSPORT
    before.contact[0] = [(-0.01, 0), (0.02, -0.01), (0, 0), (0, 0), (0.01, 0), (0.01, -0.02)]
    before.redirect[0] = [False, False, True, False, True, False]
    walk = [(1.0, 0.0), (0.6, 0.8), (0.0, -1.0), (0.0, 1.0), (0.0, 1.0), (0.6, 0.8)]
    s, events = _decide(before, params, TickInputs.fixed(1, 6, walk=walk))
    assert events.entries == []
    assert s.walk[0].tolist() == [
        [-1.0, 0.0],  # into the push: reversed
        [0.6, 0.8],  # away from it (positive dot product): kept
        [0.0, -1.0],  # no contact, but asked to redirect
        [0.8, -0.6],  # neither: the old direction
        [0.8, -0.6],  # not walking
        [-0.6, -0.8],  # into the push
    ]
    assert s.redirect[0].tolist() == [False, False, False, False, True, False]


def test_a_transporter_stuck_long_enough_starts_a_sidestep_away_from_the_contact():
    params = params_for(robots=5, carriers=1, motion=Motion(stuck_time=0.3, sidestep_time=0.7))
    assert (params.stuck_ticks, params.sidestep_ticks) == (3, 7)
    robots = [(2.0, 0.5 + 0.6 * i) for i in range(5)]
    before = _state(params, robots, [(0.3, 0.3)], status=[IDLE])
    modes = [Mode.TRANSPORT] * 4 + [Mode.LIFT]
    before.mode[0] = modes
    before.stuck[0] = [3, 4, 2, 5, 3]
    before.sidestep[0] = [0, 0, 0, 2, 0]
    before.sidestep_dir[0, 3] = (1.0, 0.0)
    before.contact[0, 0] = (0.0, -0.01)
    sidestep = [(0.0, 1.0), (0.6, 0.8), (0.0, 1.0), (0.0, 1.0), (0.0, 1.0)]
    s, _ = _decide(before, params, TickInputs.fixed(1, 5, sidestep=sidestep))
    assert s.sidestep[0].tolist() == [7, 7, 0, 2, 0]
    assert s.stuck[0].tolist() == [0, 0, 2, 5, 3]
    assert s.sidestep_dir[0].tolist() == [
        [0.0, -1.0],  # the drawn direction pointed into the push
        [0.6, 0.8],
        [0.0, 0.0],
        [1.0, 0.0],  # already sidestepping: kept
        [0.0, 0.0],
    ]
    assert s.mode[0].tolist() == modes


def _turning(turn_interval):
    params = params_for(robots=4, carriers=1, walk=Walk(turn_interval=turn_interval))
    before = _state(params, [(2.0, 0.5 + 0.6 * i) for i in range(4)], [(0.3, 0.3)], status=[IDLE])
    before.walk[0] = [(0.6, 0.8), (0.6, 0.8), (0.6, 0.8), (0.6, 0.8)]
    before.walk_clock[0] = [2, 1, 2, 2]
    before.contact[0, 2] = (0.01, 0.0)
    before.mode[0, 3] = Mode.TRANSPORT
    turn = np.tile([0.0, 1.0], (1, 4, 1))  # 90 degrees counter-clockwise
    inputs = replace(TickInputs.fixed(1, 4, walk=(1.0, 0.0)), turn=turn)
    return params, *_decide(before, params, inputs)


def test_a_turning_walk_rotates_a_heading_kept_for_the_interval_by_the_drawn_turn():
    params, s, _ = _turning(0.3)
    assert params.walk_turn_ticks == 3
    np.testing.assert_allclose(
        s.walk[0], [[-0.8, 0.6], [0.6, 0.8], [1.0, 0.0], [0.6, 0.8]], rtol=0, atol=1e-12
    )
    # robot 0 turned (its clock restarts), robot 1 counts on, robot 2 bumped into
    # something and took the new direction instead, robot 3 is not walking
    assert s.walk_clock[0].tolist() == [0, 2, 0, 2]


def test_without_a_turn_interval_the_walk_is_not_turned():
    params, s, _ = _turning(0.0)
    assert params.walk_turn_ticks == 0
    assert s.walk[0, :2].tolist() == [[0.6, 0.8], [0.6, 0.8]]
    assert s.walk_clock[0, :2].tolist() == [2, 1]


def _curving(curve):
    params = params_for(robots=4, carriers=1, walk=Walk(curve=curve))
    before = _state(params, [(2.0, 0.5 + 0.6 * i) for i in range(4)], [(0.3, 0.3)], status=[IDLE])
    before.walk[0] = [(0.6, 0.8), (0.6, 0.8), (0.6, 0.8), (0.6, 0.8)]
    before.curve[0] = [(0.0, 1.0), (0.0, 0.0), (0.0, 1.0), (0.0, 1.0)]
    before.contact[0, 2] = (0.01, 0.0)
    before.mode[0, 3] = Mode.TRANSPORT
    turn = np.tile([0.6, -0.8], (1, 4, 1))  # this tick's draw
    inputs = replace(TickInputs.fixed(1, 4, walk=(1.0, 0.0)), turn=turn)
    return params, *_decide(before, params, inputs)


def test_a_curved_walk_turns_every_tick_by_its_legs_own_turn():
    params, s, _ = _curving(90.0)
    assert params.walk_curve == pytest.approx(np.radians(90.0) * 0.1)
    np.testing.assert_allclose(
        s.walk[0],
        [[-0.8, 0.6], [0.6 * 0.6 + 0.8 * 0.8, 0.8 * 0.6 - 0.6 * 0.8], [1.0, 0.0], [0.6, 0.8]],
        rtol=0,
        atol=1e-12,
    )
    # robot 0 turns by its leg's 90 degrees, robot 1 had no turn yet and takes this tick's,
    # robot 2 bumped into something: a new leg (new heading, this tick's turn), robot 3 carries
    assert s.curve[0].tolist() == [[0.0, 1.0], [0.6, -0.8], [0.6, -0.8], [0.0, 1.0]]


def test_without_a_curve_the_walk_keeps_its_heading():
    params, s, _ = _curving(0.0)
    assert params.walk_curve == 0
    assert s.walk[0, :2].tolist() == [[0.6, 0.8], [0.6, 0.8]]


def test_a_walk_cannot_both_turn_and_curve():
    with pytest.raises(ConfigError, match=r"walk.curve: 90.0 deg/s with walk.turn_interval 1.0 s"):
        Walk(curve=90.0, turn_interval=1.0)


def _searching(camera: float, search: bool) -> Scenario:
    mapping = Scenario.default(3, 7, profile="lab").to_mapping()
    mapping["camera"] |= {"range": camera, "occlusion": "carriers", "look_around": 0.0}
    mapping["radio"] = mapping.get("radio", {}) | {"search": search}
    mapping["motion"] |= {"speed": 0.5}
    mapping["urgency"] = {"model": "static"}
    return Scenario.from_mapping(mapping)


def test_ble_led_search_gives_robots_a_choice_with_a_short_camera():
    shares = {}
    for search in (False, True):
        result = simulate(_searching(1.0, search), Urgency(alpha=0.7), seed=3, runs=8)
        assert result.delivered.sum() >= 7 * 8 - 2  # seekers find their carriers
        events = result.events
        counts = events.value[events.kind == "candidates"]
        shares[search] = float(np.mean(counts >= 2))
    # switched off, a 1 m camera rarely shows two carriers; with search every heard tag counts
    assert shares[False] < 0.35
    assert shares[True] > 0.8


def test_a_searching_robot_seeks_an_unseen_tag_then_approaches_when_it_sees_it():
    params = params_for(
        robots=1,
        carriers=2,
        perception="split",
        camera=Camera(range=1.0),
        radio=Radio(search=True, shadowing=0.0, interval=0.1),
        timing=Timing(pursuit_timeout=2.0, cooldown=1.5),
    )
    # carrier 0 at 2.5 m (heard, not seen), carrier 1 at 2.9 m: proximity seeks carrier 0
    before = _state(params, [(0.5, 2.0)], [(3.0, 2.0), (3.0, 0.5)])
    s, events = _decide(before, params)
    assert _kinds(events) == [EventKind.SELECT, EventKind.CANDIDATES]
    assert _only(events, EventKind.CANDIDATES).value[0, 0] == 2.0
    assert (s.mode[0, 0], s.target[0, 0], s.seek[0, 0]) == (Mode.WALK, -1, 0)
    assert s.pursuit_start[0, 0] == T
    assert s.seek_ref[0, 0] == pytest.approx(2.5)

    # heard farther than the margin allows: a new heading (run and tumble)
    farther = s.copy()
    farther.robot_pos[0, 0] = (0.0, 2.0)
    farther.walk[0, 0] = (-1.0, 0.0)
    after, events = _decide(farther, params, TickInputs.fixed(1, 1, walk=(0.0, 1.0)), t=T + 1)
    assert _kinds(events) == []
    assert after.walk[0, 0].tolist() == [0.0, 1.0]
    assert after.seek_ref[0, 0] == pytest.approx(2.625)  # smoothing 0.25: 2.5 + (3 - 2.5) / 4

    # the camera sees it: the approach starts, no new selection, the pursuit's clock kept
    near = s.copy()
    near.robot_pos[0, 0] = (2.2, 2.0)
    after, events = _decide(near, params, t=T + 1)
    assert _kinds(events) == []
    assert (after.mode[0, 0], after.target[0, 0], after.seek[0, 0]) == (Mode.PREDOCK, 0, -1)
    assert after.pursuit_start[0, 0] == T

    # a seeker times out like a pursuit and cools the tag down
    late, events = _decide(s.copy(), params, t=T + 20)
    assert _kinds(events) == [EventKind.TIMEOUT, EventKind.SELECT, EventKind.CANDIDATES]
    assert late.blocked_until[0, 0, 0] == T + 20 + 15
    assert late.seek[0, 0] == 1  # it chose again at once, among what is left
