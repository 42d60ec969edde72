"""Comparing the compiled backend with the reference: the same bytes, the same final state."""

from __future__ import annotations

from dataclasses import fields

import numpy as np

from swarmtag.policy import Policy
from swarmtag.sim import Scenario, SimResult, WorldState, simulate
from swarmtag.sim.determinism import run_csv
from swarmtag.sim.outputs.trajectories import Trajectories

TAG_CACHES = (
    "blocked_until",
    "known_status",
    "known_urgency",
    "heard_tick",
    "seen_tick",
    "seen_pos",
    "rssi",
)
"""``WorldState``'s arrays per robot and carrier: empty where the fast backend keeps sparse caches."""


def assert_same(reference: SimResult, fast: SimResult) -> None:
    """Identical event logs per run, identical final states and per-run counts."""
    assert reference.run_ids.tolist() == fast.run_ids.tolist()
    for run in reference.run_ids.tolist():
        assert run_csv(reference, run) == run_csv(fast, run), f"run {run} differs"
    assert reference.final_state.tick == fast.final_state.tick
    for field in fields(WorldState):
        ours = getattr(reference.final_state, field.name)
        theirs = getattr(fast.final_state, field.name)
        if field.name in TAG_CACHES and theirs.shape[2] == 0:  # sparse: nothing to compare
            assert ours.shape[:2] == theirs.shape[:2], field.name
            continue
        if isinstance(ours, np.ndarray):
            assert ours.dtype == theirs.dtype, field.name
            assert np.array_equal(ours, theirs, equal_nan=True), field.name
    for name in ("delivered", "undelivered", "stuck", "breakdowns", "end_tick"):
        assert getattr(reference, name).tolist() == getattr(fast, name).tolist(), name
    assert (reference.trajectories is None) == (fast.trajectories is None)
    if reference.trajectories is not None and fast.trajectories is not None:
        for field in fields(Trajectories):
            ours = getattr(reference.trajectories, field.name)
            theirs = getattr(fast.trajectories, field.name)
            if isinstance(ours, np.ndarray):
                assert ours.dtype == theirs.dtype, field.name
                assert ours.tobytes() == theirs.tobytes(), field.name
            else:
                assert ours == theirs, field.name


def compare(
    scenario: Scenario,
    policy: Policy,
    *,
    seed: int,
    runs: int,
    run_offset: int = 0,
    **options: object,
) -> SimResult:
    """Run both backends on the same runs, assert they agree (trajectories too); the fast result."""
    reference = simulate(
        scenario,
        policy,
        seed=seed,
        runs=runs,
        run_offset=run_offset,
        backend="reference",
        **options,
    )
    fast = simulate(
        scenario, policy, seed=seed, runs=runs, run_offset=run_offset, backend="fast", **options
    )
    assert_same(reference, fast)
    return fast
