"""Scenarios and comparisons shared by the robot tests."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from swarmtag.policy import Policy
from swarmtag.sim import Scenario, simulate
from swarmtag.sim.determinism import run_csv

REALISM = {
    "advertisement_loss": 0.3,
    "status_delay": 7,
    "detection_noise": 0.05,
    "speed_variation": 0.2,
    "breakdown": 2e-4,
}
"""Every optional realism switched on."""


def scenario(robots: int, carriers: int, profile: str = "base", **changes: Any) -> Scenario:
    """A shipped profile's scenario with some keys changed (tables merged)."""
    mapping = Scenario.default(robots, carriers, profile=profile).to_mapping()
    for key, value in changes.items():
        if isinstance(value, dict):
            mapping.setdefault(key, {}).update(value)
        else:
            mapping[key] = value
    return Scenario.from_mapping(mapping)


@dataclass(frozen=True)
class Compared:
    """Two controllers' runs of one scenario: the runs whose logs differ, what happened in them."""

    differing: list[int]
    """Global run indices whose event logs (carrier rows and event rows) differ."""
    kinds: frozenset[str]
    """The kinds of event in the built-in controller's runs."""
    delivered: int
    """Carriers delivered in the built-in controller's runs."""


def compare_controllers(
    scenario: Scenario, policy: Policy, *, seed: int, runs: int, run_offset: int = 0
) -> Compared:
    """Run the built-in controller and the behaviour trees on the same runs and compare their logs.

    What happened is returned too, so that a test can assert that its runs
    compared what it is there to compare (lifts, deliveries, ...), not only
    that nothing differed.
    """
    builtin = simulate(scenario, policy, seed=seed, runs=runs, run_offset=run_offset)
    trees = simulate(scenario, policy, seed=seed, runs=runs, run_offset=run_offset, controller="bt")
    differing = [
        int(run)
        for i, run in enumerate(builtin.run_ids)
        if run_csv(builtin, i) != run_csv(trees, i)
    ]
    kinds = frozenset(builtin.events.kind.tolist())
    return Compared(differing, kinds, int(builtin.delivered.sum()))
