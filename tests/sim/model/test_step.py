"""The step kernel as a whole (``swarmtag.sim.model.step.step``): purity, ticks, run ends.

Defaults: disc perception of radius 1 m, growing urgency over T = 3000
ticks, drop-off area x >= 3.0 (middle 3.375), dock = lift = release = 10
ticks.
"""

from __future__ import annotations

from dataclasses import fields, replace

import numpy as np
import pytest

from swarmtag.sim import EventKind, Mode, Realism, Scene, TickInputs, initial_state, step
from swarmtag.tag import TagStatus
from tests.sim.helpers import params_for

IDLE, AWAITING, PICKED_UP = (int(s) for s in TagStatus)


def _arrays(state):
    return {
        f.name: getattr(state, f.name)
        for f in fields(state)
        if isinstance(getattr(state, f.name), np.ndarray)
    }


def _busy(runs=1, tick=7, **scenario):
    """A batch in which one tick selects, lifts, delivers, collides and grows an urgency.

    Robot 0 walks near carrier 0; robot 1 ends its centring under carrier 1;
    robot 2 ends its release of carrier 2 in the drop-off area; robots 3 and
    4 walk into each other; carrier 0's urgency grows from 3 to 4 at tick 8.
    """
    params = params_for(robots=5, carriers=3, **scenario)
    scene = Scene.build(
        robots=[(1.2, 2.0), (0.6, 1.0), (3.375, 3.0), (2.0, 0.5), (2.2, 0.5)],
        carriers=[(0.6, 2.0), (0.6, 1.0), (3.375, 3.0)],
        urgency=[3, 5, 8],
        w0=[1326.0, np.nan, np.nan],
        status=[AWAITING, AWAITING, PICKED_UP],
    )
    s = replace(initial_state(params, [scene] * runs, list(range(runs))).copy(), tick=tick)
    s.mode[:, 1:3] = [Mode.CENTRE, Mode.RELEASE]
    s.target[:, 1:3] = [1, 2]
    s.face[:, 1] = 0
    s.timer[:, 1:3] = 1
    s.ghost[:, 1] = 1
    s.pursuit_start[:, 1] = tick - 20
    s.carried_by[:, 2] = 2
    return params, s


def _inputs(params, runs=1):
    return TickInputs.fixed(runs, params.robots, walk=[(1.0, 0.0)] * 3 + [(1.0, 0.0), (-1.0, 0.0)])


def test_a_copy_has_fresh_arrays_and_takes_the_changes_it_is_given():
    _, state = _busy(runs=2)
    rssi = np.full_like(state.rssi, 2.5)
    copied = state.copy(tick=9, rssi=rssi)
    assert copied.tick == 9
    assert copied.rssi is rssi
    for name, array in _arrays(state).items():
        if name != "rssi":
            np.testing.assert_array_equal(getattr(copied, name), array, err_msg=name)
            assert not np.shares_memory(getattr(copied, name), array), name


@pytest.mark.parametrize("ended_at", [[-1, -1], [3, -1]], ids=["running", "one-run-ended"])
def test_step_leaves_the_state_it_is_given_untouched(ended_at):
    params, state = _busy(runs=2)
    state.ended_at[:] = ended_at
    kept = state.copy()
    new, _ = step(state, _inputs(params, runs=2), params)
    for name, array in _arrays(kept).items():
        np.testing.assert_array_equal(getattr(state, name), array, err_msg=name)
        assert not np.shares_memory(getattr(new, name), getattr(state, name)), name
    # and the tick did happen in the running run: a lift, a delivery, a selection
    assert new.status[1].tolist() == [AWAITING, PICKED_UP, IDLE]
    assert new.mode[1, :3].tolist() == [Mode.PREDOCK, Mode.LIFT, Mode.WALK]


def test_the_returned_state_is_one_tick_later_and_the_tick_is_the_one_decided_in():
    params, state = _busy(tick=41)
    new, events = step(state, _inputs(params), params)
    assert new.tick == 42
    assert new.pursuit_start[0, 0] == 42  # robot 0 selected in tick 42
    assert new.pickup_time[0].tolist() == [-1, 42, -1]
    assert new.delivery_time[0].tolist() == [-1, -1, 42]
    assert [e.kind for e in events.entries] == [
        EventKind.SELECT,
        EventKind.CANDIDATES,
        EventKind.LIFT,
        EventKind.DELIVER,
    ]


def test_an_ended_run_is_frozen_while_the_other_run_goes_on():
    params, state = _busy(runs=2)
    state.ended_at[0] = 5
    new, events = step(state, _inputs(params, runs=2), params)
    assert new.tick == state.tick + 1
    for name, array in _arrays(state).items():
        np.testing.assert_array_equal(getattr(new, name)[0], array[0], err_msg=name)
    assert events.entries  # run 1 had its events, run 0 none
    for entry in events.entries:
        assert not entry.mask[0].any(), entry.kind
        assert entry.mask[1].any(), entry.kind
    assert new.status[1].tolist() == [AWAITING, PICKED_UP, IDLE]
    assert new.robot_pos[1, 0].tolist() != state.robot_pos[1, 0].tolist()
    assert new.ended_at.tolist() == [5, -1]


@pytest.mark.parametrize(
    ("other_present", "ended_at"), [(False, 8), (True, -1)], ids=["last", "one-left"]
)
def test_a_run_ends_in_the_tick_its_last_carrier_is_delivered(other_present, ended_at):
    params = params_for(robots=1, carriers=2)
    scene = Scene.build(robots=[(3.375, 2.0)], carriers=[(3.375, 2.0), (0.6, 2.0)])
    state = replace(initial_state(params, [scene], [0]).copy(), tick=7)
    state.mode[0, 0] = Mode.RELEASE
    state.target[0, 0] = 0
    state.timer[0, 0] = 1
    state.status[0, 0] = PICKED_UP
    state.carried_by[0, 0] = 0
    state.present[0, 1] = other_present
    new, _ = step(state, TickInputs.fixed(1, 1), params)
    assert new.present[0].tolist() == [False, other_present]
    assert new.ended_at.tolist() == [ended_at]


@pytest.mark.parametrize(("tick", "ended_at"), [(48, -1), (49, 50)])
def test_a_run_ends_at_its_time_limit(tick, ended_at):
    params = params_for(robots=1, carriers=1, ticks=50)
    assert params.run_ticks == 50
    scene = Scene.build(robots=[(3.375, 2.0)], carriers=[(0.6, 2.0)])
    state = replace(initial_state(params, [scene], [0]), tick=tick)
    new, _ = step(state, TickInputs.fixed(1, 1), params)
    assert new.ended_at.tolist() == [ended_at]


def test_growing_urgencies_are_updated_at_the_end_of_the_tick():
    # u = floor(9 * (1326 + t) / 3000): 3 at tick 7, 4 at tick 8
    params, state = _busy()
    new, events = step(state, _inputs(params), params)
    assert new.urgency[0].tolist() == [4, 5, 8]  # carriers 1 and 2 do not grow (w0 NaN)
    select = next(e for e in events.entries if e.kind is EventKind.SELECT)
    assert select.value[0, 0] == 3.0  # the robot chose on what was advertised before
    assert new.urgency0[0].tolist() == [3, 5, 8]


def test_the_history_slot_of_the_tick_holds_its_status_and_urgency():
    params, state = _busy(realism=Realism(status_delay=2))
    state.adv_status[0] = [[AWAITING, AWAITING, PICKED_UP]] * 3
    state.adv_urgency[0] = [[1, 2, 3], [3, 5, 8], [6, 7, 9]]  # slot 1 is tick 7's
    new, _ = step(state, _inputs(params), params)
    # tick 8 writes slot 8 % 3 = 2; the older slots are the delayed adverts
    assert new.adv_status[0].tolist() == [
        [AWAITING, AWAITING, PICKED_UP],
        [AWAITING, AWAITING, PICKED_UP],
        [AWAITING, PICKED_UP, IDLE],
    ]
    assert new.adv_urgency[0].tolist() == [[1, 2, 3], [3, 5, 8], [4, 5, 8]]
