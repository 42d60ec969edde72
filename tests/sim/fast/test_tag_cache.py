"""Sparse tag caches (``sim/fast/_tag_cache.py``): warehouses give the reference's bytes.

A robot's list drops what cannot change its behaviour; these tests make the
lists small enough to purge and to overflow, and compare with the reference.
The hall runs for as long as the lists need to fill (``SWARMTAG_LONG_TESTS=1``,
``tests/long_mode.py``: the full 1,800 ticks).
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from swarmtag.policy import Proximity, Urgency
from swarmtag.sim import Camera, Radio, Realism, Reprioritisation, Scenario, load_profile, simulate
from swarmtag.sim import fast as fast_backend
from swarmtag.sim.fast import TagCacheFull, _layout, simulate_fast
from swarmtag.sim.model import params as params_module
from swarmtag.sim.model.params import make_params
from swarmtag.sim.runner import batch_result, seeded_state
from tests.long_mode import length
from tests.sim.fast.helpers import assert_same
from tests.sim.fast.test_equivalence import (
    CASES,
    EVENTS,
    OFFSET,
    ONE_RUN_EACH,
    POLICIES,
    RUNS,
    SEED,
)

POLICY = Urgency(alpha=0.7)


def _hall(ticks: int = 1800, interval: float = 3.0, **realism: float) -> Scenario:
    """The lab robots in the hall, a hard-disc camera choosing at once (lists are exact)."""
    part = {"map": "warehouse-hall", "order_interval": interval, "initial_orders": 20}
    layers = {"robots": 30, "ticks": ticks, "warehouse": part}
    layers |= {"camera": {"fade": 0.0, "look_around": 0.0}, "radio": {"search": False}}
    scenario = load_profile("lab").scenario(layers)
    return replace(scenario, realism=Realism(**realism)) if realism else scenario


THRESHOLD = params_module.SPARSE_FROM_PAIRS
HALL_TICKS = length(900, 1800)
"""Ticks of the hall runs that compare whole runs: past the first lifts (from tick 540 on)."""


@pytest.fixture(autouse=True)
def _lists_in_small_runs_too(monkeypatch):
    """Every run here whose lists are exact keeps lists, however few its pairs."""
    monkeypatch.setattr(params_module, "SPARSE_FROM_PAIRS", 0)


def test_lists_are_kept_where_exact_and_large(monkeypatch):
    monkeypatch.setattr(params_module, "SPARSE_FROM_PAIRS", THRESHOLD)
    lab = replace(Scenario.default(300, 256), ticks=10)  # 76,800 pairs: lists pay
    assert make_params(lab, POLICY).sparse_tag_cache
    assert not make_params(replace(lab, perception="disc"), POLICY).sparse_tag_cache
    assert not make_params(replace(lab, camera=Camera(memory=1.0)), POLICY).sparse_tag_cache
    realism = Realism(advertisement_loss=0.1)
    assert not make_params(replace(lab, realism=realism), POLICY).sparse_tag_cache
    assert not make_params(replace(lab, robots=255), POLICY).sparse_tag_cache  # 65,280 pairs
    assert make_params(replace(lab, robots=256), POLICY).sparse_tag_cache  # 65,536
    assert not make_params(_hall(), POLICY).sparse_tag_cache  # a small warehouse


def test_runs_without_memory_or_per_pair_draws_keep_sparse_caches():
    sparse = make_params(_hall(), POLICY)
    assert sparse.sparse_tag_cache
    assert not make_params(_hall(advertisement_loss=0.1), POLICY).sparse_tag_cache
    assert not make_params(_hall(detection_noise=0.01), POLICY).sparse_tag_cache
    lab = replace(Scenario.default(300, 256), ticks=10)
    small = replace(Scenario.default(3, 7), ticks=10)
    short = _hall(ticks=50)  # the shapes of the caches: a few ticks show them
    assert make_params(short, POLICY).sparse_tag_cache
    result = simulate(short, POLICY, seed=1, runs=1, backend="fast")
    assert result.final_state.known_status.shape == (1, 30, 0)
    assert simulate(
        short, POLICY, seed=1, runs=1, backend="reference"
    ).final_state.known_status.shape[:2] == (1, 30)
    assert _layout.cache_capacity_for(sparse) == len(sparse.floor.pickup_slots) + 2 == 44
    assert _layout.cache_capacity_for(make_params(lab, POLICY)) == 64
    assert _layout.cache_capacity_for(make_params(small, POLICY)) == 7 + 2
    disc = make_params(replace(small, perception="disc"), POLICY)
    assert _layout.cache_capacity_for(disc) == 0


LAB = replace(
    Scenario.default(40, 60),
    ticks=1500,
    radio=Radio(range=1.5, interval=0.3),
    realism=Realism(status_delay=2, speed_variation=0.2, breakdown=0.0003),
    reprioritisations=(Reprioritisation(tick=300, carrier=3, urgency=9),),
)
"""A lab run with a short radio, operator writes and breakdowns (a list fills and purges)."""


@pytest.mark.first
@pytest.mark.parametrize(
    ("scenario", "bound"),
    [(_hall(3000, 20.0, status_delay=2, speed_variation=0.2), 44), (LAB, 62)],
    ids=["warehouse", "lab"],
)
def test_every_capacity_overflows_or_gives_the_reference_bytes(scenario, bound):
    params = make_params(scenario, POLICY)
    assert params.sparse_tag_cache
    assert _layout.cache_bound(params) == bound
    reference = simulate(scenario, POLICY, seed=11, runs=2, backend="reference")
    assert reference.delivered.sum() > 0
    outcomes = {}
    for capacity in (1, 2, 4, 8, 12, 16, 24, 32, bound):
        state = seeded_state(params, seed=11, runs=2, backend="fast")
        try:
            final, events, breakdowns, _ = simulate_fast(
                state, params, seed=11, cache_capacity=capacity
            )
        except TagCacheFull as full:
            outcomes[capacity] = f"full, next {full.capacity}"
            continue
        result = batch_result(
            final, params, seed=11, events=events, breakdowns=breakdowns, recorder=None
        )
        assert_same(reference, result)
        outcomes[capacity] = "same"
    # small lists overflow, and a list smaller than the bound held (it purged) and agreed
    assert outcomes[1] == "full, next 2"
    assert outcomes[bound] == "same"
    assert any(outcomes[c] == "same" for c in (2, 4, 8, 12, 16, 24, 32)), outcomes


def test_a_batch_whose_caches_overflow_starts_again_with_the_same_bytes(monkeypatch):
    monkeypatch.setattr(_layout, "FIRST_CACHE_CAPACITY", 1)
    capacities: list[object] = []
    original = fast_backend.simulate_fast

    def counted(*args: object, **options: object):  # type: ignore[no-untyped-def]
        capacities.append(options["cache_capacity"])
        return original(*args, **options)

    monkeypatch.setattr(fast_backend, "simulate_fast", counted)
    scenario = _hall(HALL_TICKS)
    reference = simulate(scenario, POLICY, seed=3, runs=2, backend="reference")
    result = simulate(scenario, POLICY, seed=3, runs=2, backend="fast")
    assert_same(reference, result)
    assert capacities[:2] == [None, 2], capacities
    assert len(capacities) >= 3


def test_sparse_caches_split_over_threads_agree(monkeypatch):
    monkeypatch.setattr(fast_backend._runner, "SPLIT_FROM", 10)
    batch = fast_backend._runner._Batch
    original, split = batch._split_run, []

    def counted(self, *arguments):  # type: ignore[no-untyped-def]
        split.append(arguments[0])
        return original(self, *arguments)

    monkeypatch.setattr(batch, "_split_run", counted)
    scenario = _hall(HALL_TICKS)
    reference = simulate(scenario, POLICY, seed=5, runs=1, backend="reference")
    assert_same(reference, simulate(scenario, POLICY, seed=5, runs=1, backend="fast", threads=2))
    assert split, "the run did not take the split path"


LIST_CASES = [
    "paper-sim",
    "paper-sim-5x10",
    "robots-occlude",
    "no-occlusion-short-camera",
    "slow-radio",
    "turning-walk",
    "reprioritised",
    "quick-handling",
    "crowded-20x40",
]
"""``test_equivalence.CASES`` whose lists are exact (no memory, loss, noise, fade or search)."""


@pytest.mark.parametrize("policy", [Proximity(), Urgency(alpha=9.0)], ids=lambda p: p.name)
@pytest.mark.parametrize("case", LIST_CASES)
def test_lab_runs_with_lists_agree(case, policy, monkeypatch):
    # Lists against the kernel's dense caches on the runs test_backends_agree holds to the
    # reference's bytes (the same case, policy and runs): so lists give the reference's bytes,
    # without running the reference a second time.
    assert case not in ONE_RUN_EACH
    assert policy.name in {p.name for p in POLICIES}
    scenario = CASES[case]
    runs = {"seed": SEED, "runs": RUNS, "run_offset": OFFSET, "backend": "fast"}
    assert make_params(scenario, policy).sparse_tag_cache
    lists = simulate(scenario, policy, **runs)
    assert lists.final_state.known_status.shape[2] == 0
    monkeypatch.setattr(params_module, "SPARSE_FROM_PAIRS", THRESHOLD)
    dense = simulate(scenario, policy, **runs)
    assert dense.final_state.known_status.shape[2] == scenario.carriers
    assert_same(dense, lists)
    missing = EVENTS[case] - set(lists.events.kind.tolist())  # the case's events, on lists
    assert not missing, f"{case}: no {sorted(missing)} in the compared runs: too short?"
