"""The world's phases around the controller (``swarmtag.sim.world.handling``), one call at a time.

Each test builds a hand-made state, sets the robot and tag fields a phase
reads, calls the phase alone and checks what it wrote. Defaults: carrier
half side 0.1775 m, robot radius 0.125 m, predock offset 0.3525 m.
"""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.errors import SimulationError
from swarmtag.sim import EventKind, Mode, Scene, TickEvents, TickInputs, initial_state
from swarmtag.sim.control.interface import Arrivals, Carrying, LiftAnswers, no_arrivals, no_carrying
from swarmtag.sim.world.handling import ROBOT_WRITE_ALLOWED, answer_lifts, break_down, deliver, dock
from swarmtag.tag import TagStatus
from tests.sim.helpers import params_for

IDLE, AWAITING, PICKED_UP = (int(s) for s in TagStatus)
ROBOTS = [(2.0, 1.0), (2.0, 2.0), (2.0, 3.0)]
CARRIERS = [(0.6, 2.0), (0.6, 1.0)]
T = 7


@pytest.fixture
def params():
    return params_for(robots=3, carriers=2)


def _state(params, runs=1, carriers=CARRIERS):
    scene = Scene.build(robots=ROBOTS, carriers=carriers, urgency=[7, 3])
    return initial_state(params, [scene] * runs, list(range(runs))).copy()


def _only(events, kind):
    """The single entry of ``kind`` in ``events`` (fails if there is none or several)."""
    entries = [e for e in events.entries if e.kind is kind]
    assert len(entries) == 1, [e.kind for e in events.entries]
    return entries[0]


def _kinds(events):
    return [e.kind for e in events.entries]


def _breakdown(params, fired):
    return TickInputs.fixed(1, params.robots, breakdown=[fired])


# --- break_down -----------------------------------------------------------------------------


def test_a_loaded_robot_keeps_its_carrier_and_the_event_names_it(params):
    s = _state(params)
    s.mode[0] = [Mode.TRANSPORT, Mode.CENTRE, Mode.WALK]
    s.target[0] = [0, 1, -1]
    s.face[0] = [-1, 2, -1]
    s.timer[0] = [0, 4, 0]
    events = TickEvents()
    break_down(s, _breakdown(params, [True, True, False]), events)
    assert s.mode[0].tolist() == [Mode.BROKEN, Mode.BROKEN, Mode.WALK]
    assert s.target[0].tolist() == [0, -1, -1]  # the loaded one still holds carrier 0
    assert s.face[0].tolist() == [-1, -1, -1]
    assert s.timer[0].tolist() == [0, 4, 0]  # the controller's memory: the world leaves it
    entry = _only(events, EventKind.BREAKDOWN)
    assert entry.mask[0].tolist() == [True, True, False]
    assert entry.carrier[0, :2].tolist() == [0, -1]  # the held carrier, none for the pursuer
    assert np.isnan(entry.value[0, :2]).all()
    assert _kinds(events) == [EventKind.BREAKDOWN]


@pytest.mark.parametrize("mode", [Mode.LIFT, Mode.RELEASE])
def test_every_loaded_mode_keeps_its_carrier(params, mode):
    s = _state(params)
    s.mode[0, 1] = mode
    s.target[0, 1] = 1
    events = TickEvents()
    break_down(s, _breakdown(params, [False, True, False]), events)
    assert s.target[0].tolist() == [-1, 1, -1]
    assert _only(events, EventKind.BREAKDOWN).carrier[0, 1] == 1


def test_an_unloaded_robot_loses_its_target(params):
    s = _state(params)
    s.mode[0] = [Mode.PREDOCK, Mode.DOCK, Mode.WALK]
    s.target[0] = [1, 0, -1]
    s.face[0] = [0, 3, -1]
    events = TickEvents()
    break_down(s, _breakdown(params, [True, True, True]), events)
    assert s.mode[0].tolist() == [Mode.BROKEN] * 3
    assert s.target[0].tolist() == [-1, -1, -1]
    assert _only(events, EventKind.BREAKDOWN).carrier[0].tolist() == [-1, -1, -1]
    assert s.status[0].tolist() == [AWAITING, AWAITING]  # the tags are not touched


def test_broken_robots_do_not_break_again(params):
    s = _state(params)
    s.mode[0] = [Mode.BROKEN, Mode.BROKEN, Mode.WALK]
    s.target[0] = [0, -1, -1]
    s.timer[0] = [0, 0, 0]
    before = s.copy()
    events = TickEvents()
    break_down(s, _breakdown(params, [True, True, False]), events)
    assert events.entries == []
    np.testing.assert_array_equal(s.mode, before.mode)
    np.testing.assert_array_equal(s.target, before.target)

    break_down(s, _breakdown(params, [True, False, True]), events)
    assert _only(events, EventKind.BREAKDOWN).mask[0].tolist() == [False, False, True]
    assert s.target[0, 0] == 0  # the old breakdown's carrier stays held


# --- dock -----------------------------------------------------------------------------------


def test_drive_in_lets_the_robot_overlap_its_target(params):
    s = _state(params)
    s.target[0] = [1, 0, -1]
    s.ghost[0] = [-1, -1, 1]  # robot 2 is still driving out from under carrier 1
    arrivals = no_arrivals((1, 3))
    arrivals = Arrivals(
        drive_in=np.array([[True, False, False]]), centred=arrivals.centred, lift=arrivals.lift
    )
    before = s.robot_pos.copy()
    dock(s, arrivals)
    assert s.ghost[0].tolist() == [1, -1, 1]
    np.testing.assert_array_equal(s.robot_pos, before)  # driving in moves nobody


def test_centred_robots_stand_exactly_on_the_carrier_centre(params):
    s = _state(params)
    s.target[0] = [0, 1, -1]
    s.robot_pos[0, 0] = (0.6071, 2.0033)  # within the arrival tolerance of carrier 0
    s.robot_pos[0, 1] = (0.6049, 1.0052)
    arrivals = no_arrivals((1, 3))
    arrivals = Arrivals(
        drive_in=arrivals.drive_in, centred=np.array([[True, False, False]]), lift=arrivals.lift
    )
    dock(s, arrivals)
    assert s.robot_pos[0, 0].tolist() == [0.6, 2.0]
    assert s.robot_pos[0, 1].tolist() == [0.6049, 1.0052]
    assert s.robot_pos[0, 2].tolist() == list(ROBOTS[2])
    assert s.ghost[0].tolist() == [-1, -1, -1]


# --- answer_lifts ---------------------------------------------------------------------------


def _put_under(s, robots, carriers):
    """Stand each robot centred under its carrier (it drove in: the ghost is the carrier)."""
    for robot, carrier in zip(robots, carriers, strict=True):
        s.ghost[:, robot] = carrier
        s.robot_pos[:, robot] = s.carrier_pos[:, carrier]


def test_the_write_table_is_the_two_robot_transitions():
    allowed = {(int(a), int(b)) for a, b in zip(*np.nonzero(ROBOT_WRITE_ALLOWED), strict=True)}
    assert allowed == {(AWAITING, PICKED_UP), (PICKED_UP, IDLE)}


@pytest.mark.parametrize(
    ("status", "present", "carried_by", "accepted"),
    [
        (AWAITING, True, -1, True),
        (IDLE, True, -1, False),
        (PICKED_UP, True, -1, False),
        (AWAITING, False, -1, False),
        (AWAITING, True, 2, False),
    ],
    ids=["awaiting", "idle", "picked-up", "delivered", "carried"],
)
def test_a_lift_is_accepted_only_from_an_awaiting_present_uncarried_tag(
    params, status, present, carried_by, accepted
):
    s = _state(params)
    _put_under(s, [1], [1])
    s.status[0, 1] = status
    s.present[0, 1] = present
    s.carried_by[0, 1] = carried_by
    events = TickEvents()
    answers = answer_lifts(s, np.array([[-1, 1, -1]]), params=params, t=T, events=events)
    assert answers.accepted[0].tolist() == [False, accepted, False]
    assert answers.refused[0].tolist() == [False, not accepted, False]
    if accepted:
        assert s.status[0].tolist() == [AWAITING, PICKED_UP]
        assert s.carried_by[0].tolist() == [-1, 1]
        assert s.pickup_time[0].tolist() == [-1, T]
        entry = _only(events, EventKind.LIFT)
        assert entry.value[0, 1] == 3.0  # carrier 1's urgency
        assert _kinds(events) == [EventKind.LIFT]
    else:
        assert s.status[0].tolist() == [AWAITING, status]
        assert s.carried_by[0].tolist() == [-1, carried_by]
        assert s.pickup_time[0].tolist() == [-1, -1]
        entry = _only(events, EventKind.LIFT_REFUSED)
        assert entry.carrier[0, 1] == 1
        assert entry.value[0, 1] == float(status)
        assert _kinds(events) == [EventKind.LIFT_REFUSED]


def test_of_two_robots_writing_one_carrier_the_smaller_id_wins(params):
    # run 0: robots 1 and 2 write carrier 0, robot 0 carrier 1;
    # run 1: robot 2 alone writes carrier 0 (run 0's claims are no rivals of it)
    s = _state(params, runs=2)
    _put_under(s, [0, 1, 2], [1, 0, 0])
    lift = np.array([[1, 0, 0], [-1, -1, 0]])
    events = TickEvents()
    answers = answer_lifts(s, lift, params=params, t=T, events=events)
    assert answers.accepted.tolist() == [[True, True, False], [False, False, True]]
    assert answers.refused.tolist() == [[False, False, True], [False, False, False]]
    assert s.status.tolist() == [[PICKED_UP, PICKED_UP], [PICKED_UP, AWAITING]]
    assert s.carried_by.tolist() == [[1, 0], [2, -1]]
    assert s.pickup_time.tolist() == [[T, T], [T, -1]]
    assert _kinds(events) == [EventKind.LIFT_REFUSED, EventKind.LIFT]
    refused = _only(events, EventKind.LIFT_REFUSED)
    assert refused.mask.tolist() == [[False, False, True], [False, False, False]]
    assert refused.carrier[0, 2] == 0
    assert refused.value[0, 2] == float(AWAITING)  # the status before this tick's lift
    lifted = _only(events, EventKind.LIFT)
    assert lifted.value[0, :2].tolist() == [3.0, 7.0]
    assert lifted.value[1, 2] == 7.0


def test_no_lift_writes_change_nothing(params):
    s = _state(params)
    before = s.copy()
    events = TickEvents()
    answers = answer_lifts(s, np.full((1, 3), -1), params=params, t=T, events=events)
    assert not answers.accepted.any()
    assert not answers.refused.any()
    assert events.entries == []
    np.testing.assert_array_equal(s.status, before.status)
    np.testing.assert_array_equal(s.carried_by, before.carried_by)


@pytest.mark.parametrize(
    ("ghost", "offset", "accepted"),
    [(1, 0.0, True), (1, 0.0101, False), (-1, 0.0, False), (0, 0.0, False)],
    ids=["centred-under", "off-centre", "not-driven-in", "under-another"],
)
def test_the_lift_raises_only_a_carrier_the_robot_stands_centred_under(
    params, ghost, offset, accepted
):
    s = _state(params)
    s.ghost[0, 1] = ghost
    s.robot_pos[0, 1] = s.carrier_pos[0, 1] + [offset, 0.0]  # tolerance 0.01 m
    events = TickEvents()
    answers = answer_lifts(s, np.array([[-1, 1, -1]]), params=params, t=T, events=events)
    assert answers.accepted[0].tolist() == [False, accepted, False]
    assert answers.refused[0].tolist() == [False, not accepted, False]
    assert s.status[0, 1] == (PICKED_UP if accepted else AWAITING)


# --- deliver --------------------------------------------------------------------------------


def _none_answered(shape=(1, 3)):
    none = np.zeros(shape, dtype=bool)
    return LiftAnswers(accepted=none, refused=none.copy())


def test_lowering_a_carrier_delivers_it(params):
    s = _state(params)
    s.status[0, 0] = PICKED_UP
    s.carried_by[0, 0] = 1
    s.urgency[0, 0] = 8
    s.robot_pos[0, 1] = s.carrier_pos[0, 0] = (params.dropoff_left + params.carrier_half, 2.0)
    carrying = Carrying(raised=np.zeros((1, 3), dtype=bool), lower=np.array([[-1, 0, -1]]))
    events = TickEvents()
    deliver(s, carrying, answers=_none_answered(), params=params, t=T, events=events)
    assert s.status[0].tolist() == [IDLE, AWAITING]
    assert s.present[0].tolist() == [False, True]
    assert s.carried_by[0].tolist() == [-1, -1]
    assert s.delivery_time[0].tolist() == [T, -1]
    assert s.deliverer[0].tolist() == [1, -1]
    assert s.delivery_urgency[0].tolist() == [8, -1]
    entry = _only(events, EventKind.DELIVER)
    assert entry.mask[0].tolist() == [False, True, False]
    assert entry.carrier[0, 1] == 0
    assert entry.value[0, 1] == 8.0
    assert _kinds(events) == [EventKind.DELIVER]


def test_lowering_a_carrier_whose_tag_is_not_picked_up_is_an_error(params):
    s = _state(params)
    carrying = Carrying(raised=np.zeros((1, 3), dtype=bool), lower=np.array([[0, -1, -1]]))
    with pytest.raises(SimulationError, match="not PICKED_UP"):
        deliver(s, carrying, answers=_none_answered(), params=params, t=T, events=TickEvents())


@pytest.mark.parametrize(("holder", "x"), [(2, 3.5), (1, 2.0)], ids=["not-its-load", "outside"])
def test_lowering_what_the_model_cannot_deliver_is_an_error(params, holder, x):
    s = _state(params)
    s.status[0, 0] = PICKED_UP
    s.carried_by[0, 0] = holder
    s.robot_pos[0, 1] = (x, 2.0)
    carrying = Carrying(raised=np.zeros((1, 3), dtype=bool), lower=np.array([[-1, 0, -1]]))
    with pytest.raises(SimulationError, match="does not hold, or outside"):
        deliver(s, carrying, answers=_none_answered(), params=params, t=T, events=TickEvents())
    assert s.present[0].tolist() == [True, True]  # nothing was delivered


def test_a_raised_robot_no_longer_overlaps_anything(params):
    s = _state(params)
    s.ghost[0] = [0, 1, -1]
    carrying = Carrying(raised=np.array([[True, False, False]]), lower=np.full((1, 3), -1))
    events = TickEvents()
    deliver(s, carrying, answers=_none_answered(), params=params, t=T, events=events)
    assert s.ghost[0].tolist() == [-1, 1, -1]
    assert events.entries == []
    assert s.present[0].tolist() == [True, True]


def test_free_faces_are_recomputed_only_in_runs_where_a_lift_was_accepted(params):
    # carrier 1 at x = 1.2 blocks carrier 0's east predock point (0.9525 + 0.125 > 1.0225)
    # and carrier 0 blocks carrier 1's west one (0.8475 - 0.125 < 0.7775)
    s = _state(params, runs=2, carriers=[(0.6, 2.0), (1.2, 2.0)])
    assert s.free_face[:, 0].tolist() == [[False, True, True, True]] * 2
    assert s.free_face[:, 1].tolist() == [[True, True, False, True]] * 2
    # carrier 1 is lifted in both runs, but only run 0's lift was answered this tick
    s.carried_by[:, 1] = 2
    s.status[:, 1] = PICKED_UP
    accepted = np.array([[False, False, True], [False, False, False]])
    answers = LiftAnswers(accepted=accepted, refused=np.zeros((2, 3), dtype=bool))
    deliver(s, no_carrying((2, 3)), answers=answers, params=params, t=T, events=TickEvents())
    assert s.free_face[0, 0].tolist() == [True, True, True, True]  # one obstacle fewer
    assert s.free_face[0, 1].tolist() == [True, True, False, True]  # carrier 0 still blocks
    assert s.free_face[1, 0].tolist() == [False, True, True, True]  # not recomputed
