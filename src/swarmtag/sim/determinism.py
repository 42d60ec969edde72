"""Checks users can run on their own scenarios and policies (like Gymnasium's env checker).

``check_determinism`` runs a batch and then every run again alone, and
compares the canonical CSV bytes of each run's rows in both event tables
(SPEC §4.5: a run is a pure function of scenario, policy, seed and index).
``check_common_scenes`` confirms that run ``i`` starts from the same scene
under every policy (common random numbers). Both raise ``DeterminismError``
naming the first run that differs. ``run_csv`` gives the bytes compared.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from swarmtag.errors import DeterminismError
from swarmtag.io import format_csv
from swarmtag.policy import Policy
from swarmtag.sim.config.scenario import Scenario
from swarmtag.sim.model.params import make_params
from swarmtag.sim.runner import SimResult, seeded_state
from swarmtag.sim.simulation import simulate

__all__ = ["check_common_scenes", "check_determinism", "run_csv"]

_SCENE_FIELDS = (
    "robot_pos",
    "heading",
    "speed",
    "carrier_pos",
    "urgency0",
    "order_time",
    "w0",
    "due",
    "destination",
    "slot",
    "slot_pick",
)


def run_csv(result: SimResult, run: int) -> tuple[bytes, bytes]:
    """The canonical CSV bytes of global run ``run``'s carrier rows and event rows."""
    carriers = result.carriers.take(result.carriers.run == run)
    events = result.events.take(result.events.run == run)
    return format_csv(carriers).encode(), format_csv(events).encode()


def check_determinism(
    scenario: Scenario,
    policy: Policy,
    *,
    seed: int,
    runs: int,
    run_offset: int = 0,
    check_invariants: bool = False,
) -> SimResult:
    """Raise ``DeterminismError`` unless each run gives the same bytes alone and in the batch.

    Returns the batch's result. ``check_invariants`` also verifies the world
    invariants every tick of the batch.

    >>> from swarmtag.policy import Proximity
    >>> result = check_determinism(Scenario(ticks=300), Proximity(), seed=3, runs=2)
    >>> result.run_ids
    array([0, 1])
    """
    batch = simulate(
        scenario, policy, seed=seed, runs=runs, run_offset=run_offset, check=check_invariants
    )
    for run in batch.run_ids.tolist():
        alone = simulate(scenario, policy, seed=seed, runs=1, run_offset=run)
        for name, together, single in zip(
            ("carrier log", "event table"), run_csv(batch, run), run_csv(alone, run), strict=True
        ):
            if together != single:
                msg = (
                    f"run {run} of seed {seed} under {policy.name}: its {name} differs between "
                    f"a batch of {runs} and a batch of one"
                )
                raise DeterminismError(msg)
    return batch


def check_common_scenes(
    scenario: Scenario,
    policies: Sequence[Policy],
    *,
    seed: int,
    runs: int,
    run_offset: int = 0,
) -> None:
    """Raise ``DeterminismError`` unless every policy starts run ``i`` from the same scene.

    >>> from swarmtag.policy import Proximity, Urgency
    >>> check_common_scenes(Scenario(), [Proximity(), Urgency(alpha=3.0)], seed=0, runs=3)
    """
    states = [
        seeded_state(make_params(scenario, policy), seed=seed, runs=runs, run_offset=run_offset)
        for policy in policies
    ]
    for policy, state in zip(policies[1:], states[1:], strict=True):
        for name in _SCENE_FIELDS:
            first, other = getattr(states[0], name), getattr(state, name)
            same = np.array_equal(first, other, equal_nan=first.dtype.kind == "f")
            if not same:
                msg = (
                    f"seed {seed}: {name} of the initial scene differs between "
                    f"{policies[0].name} and {policy.name}"
                )
                raise DeterminismError(msg)
