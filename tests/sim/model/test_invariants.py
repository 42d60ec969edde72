"""Checking mode: world invariants hold every tick across many seeds, and violations are caught."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from swarmtag.errors import InvariantError
from swarmtag.policy import Proximity, Urgency, Weighted
from swarmtag.sim import (
    Realism,
    Reprioritisation,
    Scenario,
    Scene,
    TickEvents,
    UrgencyModel,
    simulate,
)
from swarmtag.sim.model.invariants import OVERLAP_TOLERANCE, check_tick
from swarmtag.tag import TagStatus
from tests.sim.helpers import params_for, start

SCENARIOS = {
    "lab": Scenario(ticks=400),
    "static": Scenario(urgency=UrgencyModel(model="static", static_time_limit=400)),
    "realism": Scenario(
        ticks=400,
        realism=Realism(
            advertisement_loss=0.3,
            status_delay=4,
            detection_noise=0.05,
            speed_variation=0.2,
            breakdown=0.0005,
        ),
        reprioritisations=(Reprioritisation(tick=50, carrier=2, urgency=9),),
    ),
    "crowd": Scenario(robots=10, carriers=20, ticks=300),
    "far-sight": Scenario(ticks=400, detection_radius=3.0),
}


@pytest.mark.parametrize("name", sorted(SCENARIOS))
@pytest.mark.parametrize("policy", [Proximity(), Urgency(alpha=9.0), Weighted(w=0.5)], ids=str)
def test_invariants_hold_every_tick_across_seeds(name, policy):
    scenario = SCENARIOS[name]
    for seed in (0, 1):
        result = simulate(scenario, policy, seed=seed, runs=5, check=True)
        events = result.events
        for run in result.run_ids.tolist():
            times = events.time[events.run == run]
            assert (np.diff(times) >= 0).all()
        log = result.carriers
        delivered = ~np.isnan(log.delivery_time)
        assert (log.pickup_time[delivered] < log.delivery_time[delivered]).all()
        lifts = events.take(events.kind == "lift")
        keys = list(zip(lifts.run.tolist(), lifts.carrier.tolist(), strict=True))
        assert len(keys) == len(set(keys))  # each carrier lifted (and so delivered) at most once


def _two_robots(**scene):
    params = params_for(robots=2, carriers=1)
    base = {"robots": [(1.0, 1.0), (2.0, 2.0)], "carriers": [(0.5, 3.0)]}
    return params, start(params, Scene.build(**{**base, **scene}))


def test_checker_catches_overlapping_robots():
    params, before = _two_robots()
    after = replace(before.copy(), tick=1)
    after.robot_pos[0, 1] = (1.0 + 0.25 - 2 * OVERLAP_TOLERANCE, 1.0)
    with pytest.raises(InvariantError, match="run 0, tick 1: two robots overlap"):
        check_tick(before, after, TickEvents(), params)


def test_checker_catches_a_robot_outside_the_arena():
    params, before = _two_robots()
    after = replace(before.copy(), tick=1)
    after.robot_pos[0, 0] = (0.1, 1.0)
    with pytest.raises(InvariantError, match="outside the arena"):
        check_tick(before, after, TickEvents(), params)


def test_checker_catches_an_illegal_status_change():
    params, before = _two_robots(status=[TagStatus.IDLE])
    after = replace(before.copy(), tick=1)
    after.status[0, 0] = TagStatus.AWAITING_PICKUP  # only an operator may do this
    with pytest.raises(InvariantError, match="no lifecycle transition"):
        check_tick(before, after, TickEvents(), params)


def test_checker_catches_a_second_delivery_and_skipped_ticks():
    params, before = _two_robots()
    delivered = replace(before.copy(), tick=1)
    delivered.delivery_time[0, 0] = 1
    delivered.present[0, 0] = False
    again = replace(delivered.copy(), tick=2)
    again.delivery_time[0, 0] = 2
    with pytest.raises(InvariantError, match="delivered twice"):
        check_tick(delivered, again, TickEvents(), params)
    with pytest.raises(InvariantError, match="tick went from 0 to 2"):
        check_tick(before, again, TickEvents(), params)


def test_checker_catches_a_carrier_left_behind():
    params, before = _two_robots()
    after = replace(before.copy(), tick=1)
    after.mode[0, 0] = 5  # TRANSPORT
    after.target[0, 0] = 0
    after.carried_by[0, 0] = 0
    after.status[0, 0] = TagStatus.PICKED_UP
    after.robot_pos[0, 0] = (1.0, 1.5)  # the carrier stayed at (0.5, 3.0)
    with pytest.raises(InvariantError, match="not with its robot"):
        check_tick(before, after, TickEvents(), params)
