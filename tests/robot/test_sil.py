"""Software-in-the-loop: every robot under its own behaviour tree gives the built-in event logs.

Sized for CI: 80 seeded runs of 3 robots / 7 carriers at 300 ticks and 16
of 20 / 40 at 225, realism off and on (every run ``i`` of master seed 0
draws from its own streams ``SeedSequence(0, spawn_key=(i, k))``,
docs/simulator.md), split between five policies; plus the perception and
walk variants and pursuits that time out. Each comparison runs as long as
it takes to lift and deliver, and asserts the events it is there to
compare, so a run made too short fails. The long mode,
``SWARMTAG_LONG_TESTS=1`` (``tests/long_mode.py``), gives the sizes the
suite had before it was sized for two cores (100 and 20 runs of 400 and 300
ticks, the static-urgency variants until every carrier is delivered);
longer still (whole runs, more of them)::

    SWARMTAG_SIL_SEEDS=1000 SWARMTAG_SIL_TICKS=3000 \\
        pytest -q -p no:cacheprovider tests/robot/test_sil.py
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

import numpy as np
import pytest

from swarmtag.errors import BackendFallback, ConfigError
from swarmtag.policy import Edf, Proximity, Urgency, Weighted, load_rule
from swarmtag.sim import Scenario, simulate
from tests.long_mode import length
from tests.robot.helpers import REALISM, compare_controllers, scenario

pytest.importorskip("py_trees")

SEEDS = int(os.environ.get("SWARMTAG_SIL_SEEDS") or length(80, 100))
"""Seeded runs of the small swarm (the large one gets a fifth of them)."""
TICKS = int(os.environ.get("SWARMTAG_SIL_TICKS") or length(300, 400))
"""Ticks of a small-swarm run (the large one runs for three quarters of them)."""
STATIC_LIMIT = length(900, 6000)
"""``urgency.static_time_limit`` of the static-urgency runs below: past the lab profile's first
deliveries (from tick 560 on); 6000, the default, runs them until every carrier is delivered."""

TREE = frozenset({"select", "candidates", "lift", "deliver", "abandon"})
"""What the seeded comparisons must show: the tree's behaviours (and ``breakdown`` with realism),
so that each is checked against the built-in controller; timeouts, rare in these runs, have a
test of their own."""
HANDLING = frozenset({"select", "lift", "deliver"})
"""What every other comparison must show: a carrier chosen, lifted and delivered."""


def _compare(world: Scenario, runs: int, policies: list) -> tuple[dict[str, list[int]], set[str]]:
    """The differing runs per policy and the kinds of event seen; the runs split between policies.

    Also asserts that the runs delivered a carrier per run on average, so a
    comparison cannot pass on runs too short to do anything.
    """
    found, kinds, delivered = {}, set(), 0
    share = -(-runs // len(policies))
    for index, policy in enumerate(policies):
        count = min(share, runs - index * share)
        if count <= 0:
            break
        compared = compare_controllers(world, policy, seed=0, runs=count, run_offset=index * share)
        if compared.differing:
            found[policy.name] = compared.differing
        kinds |= compared.kinds
        delivered += compared.delivered
    assert delivered >= runs, f"{delivered} deliveries in {runs} runs: too short?"
    return found, kinds


POLICIES = [Urgency(alpha=0.7), Proximity(), Weighted(w=0.3), Urgency(alpha=2.0), Edf()]


@pytest.mark.first
@pytest.mark.parametrize("realism", [False, True], ids=["realism-off", "realism-on"])
def test_small_swarm_event_logs_are_identical(realism):
    changes = {"realism": REALISM} if realism else {}
    world = scenario(3, 7, ticks=TICKS, **changes)
    found, kinds = _compare(world, SEEDS, POLICIES)
    assert found == {}
    # lifts, deliveries, abandons (and breakdowns) all happen in the compared runs
    assert kinds >= (TREE | {"breakdown"} if realism else TREE), kinds


@pytest.mark.first
@pytest.mark.parametrize("realism", [False, True], ids=["realism-off", "realism-on"])
def test_large_swarm_event_logs_are_identical(realism):
    changes = {"realism": REALISM} if realism else {}
    world = scenario(20, 40, ticks=TICKS * 3 // 4, **changes)
    found, kinds = _compare(world, max(1, SEEDS // 5), POLICIES)
    assert found == {}
    assert kinds >= HANDLING | {"abandon"}, kinds


@pytest.mark.parametrize(
    "world",
    [
        scenario(3, 7, "paper-sim", ticks=length(800, 1500)),
        scenario(3, 7, "lab", urgency={"model": "static", "static_time_limit": STATIC_LIMIT}),
        scenario(
            7, 15, "paper-sim", ticks=800, camera={"memory": 3.0, "occlusion": "carriers+robots"}
        ),
        scenario(7, 15, "paper-sim", ticks=800, motion={"avoid_taken_faces": False}),
        scenario(
            3,
            7,
            ticks=800,
            walk={"turn_interval": 1.0, "turn_angle": 40.0},
            reprioritisations=[{"tick": 300, "carrier": 1, "urgency": 9}],
        ),
        scenario(3, 7, perception="disc", ticks=600),
        scenario(5, 10, "paper-sim", ticks=800, camera={"range": 1.5, "fade": 1.0}),
        scenario(
            5, 10, "paper-sim", ticks=800, camera={"range": 1.5, "fade": 1.0, "bearing": "dots"}
        ),
        scenario(
            3,
            7,
            "lab",
            urgency={"model": "static", "static_time_limit": STATIC_LIMIT},
            walk={"curve": 90.0},
        ),
        scenario(
            5,
            10,
            "paper-sim",
            ticks=800,
            camera={"range": 1.5, "fade": 1.0, "bearing": "dots", "look_around": 1.0},
        ),
        scenario(3, 7, "paper-sim", ticks=800, camera={"range": 1.5, "memory": 20.0, "drift": 0.3}),
        scenario(
            3,
            7,
            "lab",
            # at half speed the deliveries come later: 300 ticks more
            urgency={"model": "static", "static_time_limit": STATIC_LIMIT + length(300, 0)},
            camera={"range": 1.0, "look_around": 0.0},
            radio={"search": True},
            walk={"turn_interval": 1.0, "turn_angle": 40.0},
            motion={"speed": 0.5},
        ),
        scenario(
            5,
            10,
            "paper-sim",
            ticks=800,
            camera={"range": 0.8, "memory": 2.0},
            radio={"search": True, "shadowing": 0.0, "range": 2.5},
            realism={"advertisement_loss": 0.2},
        ),
    ],
    ids=[
        "paper-sim",
        "lab-static",
        "memory-occlusion",
        "no-face-avoidance",
        "turns-writes",
        "disc",
        "camera-fade",
        "camera-bearing",
        "curved-walk",
        "look-around",
        "memory-drift",
        "ble-search",
        "ble-search-exact-memory",
    ],
)
def test_perception_and_walk_variants_are_identical(world):
    found, kinds = _compare(world, 2, POLICIES[:2])
    assert found == {}
    assert kinds >= HANDLING, kinds


def test_pursuit_timeouts_and_cooldowns_are_identical():
    # the base profile's pursuits may last 30 s and seldom time out; 3 s makes them time out
    # in every policy, and a 2 s cooldown lets the robot choose the carrier again within the run
    world = scenario(3, 7, ticks=300, timing={"pursuit_timeout": 3.0, "cooldown": 2.0})
    found, kinds = _compare(world, 4, POLICIES[:2])
    assert found == {}
    assert kinds >= HANDLING | {"timeout"}, kinds


RULES = Path(__file__).parents[1] / "policy" / "rule_examples.py"


_PAPER = scenario(3, 7, "paper-sim", ticks=700)
_SEARCH = scenario(
    3,
    7,
    "lab",
    urgency={"model": "static", "static_time_limit": STATIC_LIMIT},
    camera={"range": 1.0, "look_around": 0.0},
    radio={"search": True},
)


@pytest.mark.parametrize(
    ("world", "name"),
    [(_PAPER, "oldest_first"), (_PAPER, "everything"), (_SEARCH, "oldest_first")],
    ids=["paper-sim-age", "paper-sim-context", "ble-search-age"],
)
def test_a_rule_of_ones_own_runs_identically_in_the_tree(world, name):
    rule = load_rule(f"{RULES}:{name}")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BackendFallback)  # the builtin side falls back
        compared = compare_controllers(world, rule, seed=3, runs=2)
    assert compared.differing == []
    assert compared.kinds >= HANDLING, compared.kinds


def test_recorded_trajectories_are_identical():
    world = scenario(3, 7, ticks=400, realism=REALISM)
    builtin = simulate(world, Urgency(alpha=0.7), seed=2, runs=2, record=True)
    trees = simulate(world, Urgency(alpha=0.7), seed=2, runs=2, record=True, controller="bt")
    assert builtin.trajectories is not None
    assert trees.trajectories is not None
    for name in ("robot_pos", "robot_heading", "robot_mode", "robot_target", "carrier_status"):
        np.testing.assert_array_equal(
            getattr(builtin.trajectories, name), getattr(trees.trajectories, name), err_msg=name
        )


def test_an_unknown_controller_is_refused():
    with pytest.raises(ConfigError, match="controller"):
        simulate(scenario(3, 7, ticks=10), Proximity(), seed=0, runs=1, controller="ros")


def test_without_py_trees_the_tree_controller_is_refused_in_one_line(monkeypatch):
    import sys

    for name in [m for m in sys.modules if m.startswith(("swarmtag.robot.", "py_trees"))]:
        if name not in ("swarmtag.robot.io", "swarmtag.robot.config"):
            monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, "py_trees", None)  # as if the robot extra were missing
    with pytest.raises(ConfigError, match=r"needs py_trees .*swarmtag\[robot\]"):
        simulate(scenario(3, 7, ticks=10), Proximity(), seed=0, runs=1, controller="bt")
