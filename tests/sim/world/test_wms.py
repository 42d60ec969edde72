"""The operator-write phase (``swarmtag.sim.world.wms``): the last phase of ``step``, fed by inputs."""

from __future__ import annotations

import numpy as np

from swarmtag.policy import Proximity
from swarmtag.sim import (
    EventKind,
    Realism,
    Reprioritisation,
    Scenario,
    Scene,
    TickEvents,
    TickInputs,
    initial_state,
    make_params,
    step,
)
from swarmtag.sim.model.randomness import due_writes
from swarmtag.sim.world.wms import operator_writes
from swarmtag.tag import TagStatus


def _state(runs: int = 2, status_delay: int = 0):
    scenario = Scenario(robots=1, carriers=2, realism=Realism(status_delay=status_delay))
    params = make_params(scenario, Proximity())
    scene = Scene.build(
        robots=[(3.0, 2.0)], carriers=[(0.5, 1.0), (0.5, 2.5)], urgency=[2, 5], w0=[100.0, 50.0]
    )
    return params, initial_state(params, [scene] * runs, list(range(runs))).copy()


def test_a_write_sets_the_urgency_stops_growth_and_is_advertised_from_its_tick():
    _, s = _state(status_delay=2)
    events = TickEvents()
    operator_writes(s, (Reprioritisation(tick=7, carrier=1, urgency=9),), t=7, events=events)
    assert s.urgency.tolist() == [[2, 9], [2, 9]]
    assert np.isnan(s.w0[:, 1]).all()
    assert s.w0[:, 0].tolist() == [100.0, 100.0]  # the other carrier keeps growing
    assert s.adv_urgency[:, 7 % 3, 1].tolist() == [9, 9]  # the slot of tick 7
    assert s.urgency0.tolist() == [[2, 5], [2, 5]]  # the log's urgency at run start stays
    assert [(e.kind, e.run, e.carrier, e.value) for e in events.carrier_entries] == [
        (EventKind.REPRIORITISE, 0, 1, 9.0),
        (EventKind.REPRIORITISE, 1, 1, 9.0),
    ]


def test_each_run_has_its_own_operator_counter():
    _, s = _state()
    writes = (Reprioritisation(tick=3, carrier=0, urgency=4), Reprioritisation(3, 1, 0))
    operator_writes(s, writes, t=3, events=TickEvents())
    assert s.operator_counter.tolist() == [1, 1]  # counters 0 and 1 signed in each run
    s.ended_at[1] = 2  # run 1 ended before: it is frozen
    operator_writes(s, (Reprioritisation(tick=5, carrier=0, urgency=7),), t=5, events=TickEvents())
    assert s.operator_counter.tolist() == [2, 1]
    assert s.urgency[:, 0].tolist() == [7, 4]


def test_a_run_ending_in_this_tick_still_gets_its_write():
    _, s = _state()
    s.ended_at[:] = [4, -1]
    operator_writes(s, (Reprioritisation(tick=4, carrier=0, urgency=8),), t=4, events=TickEvents())
    assert s.urgency[:, 0].tolist() == [8, 8]


def test_the_tag_refuses_what_an_operator_may_not_do_and_the_state_stays():
    # an operator write carries only an urgency change: status stays as the tag had it
    _, s = _state(runs=1)
    s.status[0, 0] = TagStatus.PICKED_UP
    operator_writes(s, (Reprioritisation(tick=2, carrier=0, urgency=1),), t=2, events=TickEvents())
    assert s.status[0, 0] == TagStatus.PICKED_UP
    assert s.urgency[0, 0] == 1


def test_step_applies_the_writes_of_its_inputs_and_only_those():
    params, s = _state(runs=1)
    write = (Reprioritisation(tick=1, carrier=0, urgency=9),)
    after, events = step(s, TickInputs.fixed(1, 1, writes=write), params)
    assert after.urgency[0, 0] == 9
    assert [e.kind for e in events.carrier_entries] == [EventKind.REPRIORITISE]
    untouched, none = step(s, TickInputs.fixed(1, 1), params)
    assert untouched.urgency[0, 0] == 0  # grown from w0 = 100 of T = 3000 ticks: floor(0.3)
    assert not np.isnan(untouched.w0[0, 0])
    assert none.carrier_entries == []


def test_due_writes_are_the_schedule_of_that_tick():
    scenario = Scenario(
        reprioritisations=(
            Reprioritisation(tick=5, carrier=1, urgency=9),
            Reprioritisation(tick=9, carrier=2, urgency=0),
            Reprioritisation(tick=5, carrier=3, urgency=4),
        )
    )
    params = make_params(scenario, Proximity())
    assert [w.carrier for w in due_writes(params, 5)] == [1, 3]
    assert due_writes(params, 6) == ()
