"""One advertising schedule: the simulator's radio channel and the virtual radio agree advert for advert."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmtag.policy import Proximity
from swarmtag.sim import Scenario, make_params
from swarmtag.sim.config.sensors import Radio
from swarmtag.sim.world.sensing import advertising
from swarmtag.tag import TagState, TagStatus
from swarmtag.tag.advertising import (
    advert_times,
    adverts_sent,
    microseconds,
    phase_microseconds,
)
from swarmtag.tag.backends.sim import SimScanner, SimTag

STATE = TagState(urgency=4, status=TagStatus.AWAITING_PICKUP, destination=1, marker=3)


def test_adverts_go_out_at_the_phase_then_every_interval():
    assert advert_times(100, 250, 0, 1000) == [100, 350, 600, 850]
    assert advert_times(100, 250, 100, 350) == [350]  # the window is (after, until]
    assert adverts_sent(100, 250, 0, 1000) == 4
    assert adverts_sent(100, 250, 99, 100) == 1
    assert adverts_sent(100, 250, 100, 349) == 0
    counts = adverts_sent(np.array([0, 100, 249]), 250, 0, 250)
    assert counts.tolist() == [1, 1, 1]


def test_phase_fractions_and_seconds_land_on_whole_microseconds():
    assert phase_microseconds(0.5, 250_000) == 125_000
    assert phase_microseconds(0.999_999_9, 250_000) == 249_999  # floor, below the interval
    assert phase_microseconds(np.array([0.0, 0.25]), 1000).tolist() == [0, 250]
    assert microseconds(0.1) == 100_000
    assert microseconds(3 * 0.1) == 300_000  # no float drift


@settings(max_examples=40, deadline=None)
@given(
    tick=st.sampled_from([0.05, 0.1, 0.2, 0.0333, 0.25]),
    interval=st.sampled_from([0.1, 0.25, 0.3, 0.7, 1.0]),
    fractions=st.lists(st.floats(0.0, 0.999_999), min_size=1, max_size=4),
)
def test_the_simulators_radio_and_the_virtual_radio_hear_the_same_ticks(tick, interval, fractions):
    """For each tick, a tag advertises in the simulator iff the virtual radio delivers an advert."""
    params = make_params(
        Scenario(tick=tick, perception="split", radio=Radio(interval=interval)), Proximity()
    )
    phases = phase_microseconds(np.array(fractions), params.advert_us)
    now = [0.0]
    tags = [
        SimTag(f"T{i}", STATE, distance=1.0, phase=int(phase) / 1e6)
        for i, phase in enumerate(phases)
    ]
    scanner = SimScanner(tags=tags, interval=interval, clock=lambda: now[0])
    scanner.start()
    for t in range(1, 60):
        before = scanner.sent
        scanner.advance(t * tick)
        window = (t - 1) * params.tick_us, t * params.tick_us
        counts = adverts_sent(phases, params.advert_us, *window)
        assert scanner.sent - before == int(counts.sum()), (t, phases)
        assert (advertising(phases, t, params) == (counts > 0)).all()


@pytest.mark.parametrize("interval", [0.1, 0.25, 1.0])
def test_a_drawn_phase_is_the_fraction_the_simulator_would_draw(interval):
    fraction = np.random.default_rng(3).random()
    scanner = SimScanner(
        tags=[SimTag("AA", STATE)], interval=interval, rng=np.random.default_rng(3)
    )
    assert scanner._phase["AA"] == phase_microseconds(fraction, microseconds(interval))
