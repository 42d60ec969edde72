"""CBAA: a conflict-free assignment in a static world, the sequential greedy auction's."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmtag.errors import BackendFallback
from swarmtag.policy import parse_policy
from swarmtag.sim import Scenario, simulate
from swarmtag.sim.allocators.cbaa import bid_phase, merge_tables
from swarmtag.sim.determinism import check_determinism


def auction(scores: np.ndarray, link: np.ndarray, rounds: int) -> tuple[np.ndarray, int]:
    """CBAA in a static world: (each robot's table of winners, rounds to agree)."""
    robots, tasks = scores.shape
    bid = np.full((1, robots, tasks), -np.inf)
    winner = np.full((1, robots, tasks), -1, dtype=np.int64)
    stamp = np.zeros((1, robots, tasks), dtype=np.int64)
    offers = scores[None].astype(np.float64)
    everything = np.ones((1, robots, tasks), dtype=bool)
    for done in range(1, rounds + 1):
        start = (bid.copy(), winner.copy())
        holding = (winner[0] == np.arange(robots)[:, None]).any(axis=1)
        bid_phase(
            offers, bid, winner, stamp, available=everything & ~holding[None, :, None],
            distance=np.zeros((1, robots, tasks)), markers=np.arange(tasks), t=done,
        )  # fmt: skip
        bid, winner, stamp = merge_tables(bid, winner, stamp, link[None])
        if np.array_equal(start[0], bid) and np.array_equal(start[1], winner):
            return winner[0], done  # a round changed nothing: every robot is settled
    return winner[0], rounds


def greedy(scores: np.ndarray) -> dict[int, int]:
    """The sequential greedy auction: the largest bid left wins, robot and task leave."""
    scores = scores.astype(float).copy()
    robots, tasks = scores.shape
    won = {}
    for _ in range(min(robots, tasks)):
        r, c = np.unravel_index(np.argmax(scores), scores.shape)
        won[int(c)] = int(r)
        scores[r, :] = -np.inf
        scores[:, c] = -np.inf
    return won


def connected(robots: int, kind: str) -> np.ndarray:
    if kind == "all":
        return ~np.eye(robots, dtype=bool)
    link = np.zeros((robots, robots), dtype=bool)  # a line: each robot hears its neighbours
    for i in range(robots - 1):
        link[i, i + 1] = link[i + 1, i] = True
    return link


@settings(max_examples=120, deadline=None)
@given(
    robots=st.integers(1, 5),
    tasks=st.integers(1, 5),
    seed=st.integers(0, 2**32 - 1),
    kind=st.sampled_from(["all", "line"]),
)
def test_a_static_world_agrees_on_the_greedy_auctions_assignment(robots, tasks, seed, kind):
    scores = np.random.default_rng(seed).permutation(robots * tasks).reshape(robots, tasks) + 1.0
    tables, rounds = auction(scores, connected(robots, kind), rounds=4 * robots * (robots + 1))
    assert (tables == tables[0]).all(), "every robot's table agrees"
    agreed = {int(c): int(r) for c, r in enumerate(tables[0]) if r >= 0}
    assert len(set(agreed.values())) == len(agreed), "no robot holds two tasks"
    assert agreed == greedy(scores)
    assert rounds < 4 * robots * (robots + 1)


def test_equal_bids_go_to_the_smaller_robot_id():
    scores = np.array([[5.0], [5.0], [5.0]])
    tables, _ = auction(scores, connected(3, "line"), rounds=30)
    assert tables[:, 0].tolist() == [0, 0, 0]


WORLD = Scenario.from_mapping(
    {**Scenario.default(3, 7, profile="paper-sim").to_mapping(), "ticks": 900}
)


def test_runs_are_the_same_alone_and_in_a_batch_and_count_their_messages():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BackendFallback)
        policy = parse_policy("cbaa:comm_range=10,loss=0.3")
        result = check_determinism(WORLD, policy, seed=4, runs=3, check_invariants=True)
    messages = result.events.take(result.events.kind == "messages")
    assert (messages.value > 0).all()
    assert (messages.carrier == -1).all()
    assert messages.value.sum() > 100


def test_robots_out_of_range_send_nothing_and_lose_nothing_to_the_auction():
    policy = parse_policy("cbaa:comm_range=0.01,loss=0")
    result = simulate(WORLD, policy, seed=4, runs=2, backend="reference")
    assert not (result.events.kind == "messages").any()


@pytest.mark.parametrize("loss", [0.0, 0.9])
def test_lost_messages_come_from_the_runs_own_stream(loss):
    policy = parse_policy(f"cbaa:comm_range=10,loss={loss}")
    one = simulate(WORLD, policy, seed=6, runs=1, backend="reference")
    two = simulate(WORLD, policy, seed=6, runs=1, backend="reference")
    assert one.events.value.tolist() == two.events.value.tolist()
