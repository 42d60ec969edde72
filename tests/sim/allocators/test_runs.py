"""Allocators in whole runs: deterministic, on the reference backend, built-in controller only.

The runs last until the allocators' first deliveries (``SWARMTAG_LONG_TESTS=1``,
``tests/long_mode.py``: 900 ticks).
"""

from __future__ import annotations

import warnings

import pytest

from swarmtag.errors import BackendFallback, ConfigError
from swarmtag.policy import parse_policy
from swarmtag.sim import Scenario, simulate
from swarmtag.sim.backends import fast_available
from swarmtag.sim.determinism import check_determinism, run_csv
from tests.long_mode import length

ALLOCATORS = ["threshold:theta=5", "oracle:alpha=0.7", "adaptive:gain=0.5"]
WORLD = Scenario.from_mapping(
    {**Scenario.default(3, 7, profile="paper-sim").to_mapping(), "ticks": length(700, 900)}
)


@pytest.mark.parametrize("name", ALLOCATORS)
def test_each_run_is_the_same_alone_and_in_a_batch(name):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BackendFallback)
        result = check_determinism(WORLD, parse_policy(name), seed=4, runs=3, check_invariants=True)
    assert len(result.carriers) == 3 * 7
    # the runs compared alone and in a batch allocate, lift and deliver
    assert {"select", "lift", "deliver"} <= set(result.events.kind.tolist())


@pytest.mark.parametrize("name", ALLOCATORS)
def test_the_fast_backend_falls_back_with_a_note(name):
    policy = parse_policy(name)
    reference = simulate(WORLD, policy, seed=2, runs=1, backend="reference")
    if fast_available():
        with pytest.warns(BackendFallback, match="is an allocator"):
            result = simulate(WORLD, policy, seed=2, runs=1, backend="fast")
        assert run_csv(result, 0) == run_csv(reference, 0)


def test_another_controller_is_refused():
    with pytest.raises(ConfigError, match="runs with the built-in controller, not 'bt'"):
        simulate(WORLD, parse_policy("oracle:alpha=0.7"), seed=0, runs=1, controller="bt",
                 backend="reference")  # fmt: skip


def test_the_oracle_delivers_faster_than_proximity():
    # a central system with global knowledge: every carrier is assigned as soon as a robot is idle
    world, runs = Scenario.default(3, 7, profile="paper-sim"), 12
    logs = {
        name: simulate(world, parse_policy(name), seed=8, runs=runs, backend=backend).carriers
        for name, backend in (("proximity", None), ("oracle:alpha=0.7", "reference"))
    }
    mean = {name: float((log.delivery_time - log.order_time).mean()) for name, log in logs.items()}
    assert mean["oracle:alpha=0.7"] < mean["proximity"]


def test_claims_keep_other_robots_off_a_claimed_carrier_and_count_their_writes():
    world = Scenario.from_mapping(
        {**Scenario.default(7, 15, profile="paper-sim").to_mapping(), "ticks": 900}
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BackendFallback)
        check_determinism(world, parse_policy("claim:hold=30,loss=0.2"), seed=3, runs=2)
    claims = simulate(world, parse_policy("claim:hold=30,loss=0"), seed=3, runs=4,
                      backend="reference").events  # fmt: skip
    plain = simulate(world, parse_policy("urgency:alpha=0.7"), seed=3, runs=4).events
    writes = claims.take(claims.kind == "messages")
    selects = claims.take(claims.kind == "select")
    assert writes.value.sum() >= len(selects)  # a write for every choice (refused ones too)
    # double pursuits end in an abandon: claims leave fewer of them than the plain policy
    assert (claims.kind == "abandon").sum() < (plain.kind == "abandon").sum()
