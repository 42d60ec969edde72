"""Software-in-the-loop: every robot under its own behaviour tree gives the built-in event logs.

Sized for CI: 100 seeded runs of 3 robots / 7 carriers and 20 of 20 / 40,
realism off and on, on short runs (every run ``i`` of master seed 0 draws
from its own streams ``SeedSequence(0, spawn_key=(i, k))``, docs/simulator.md),
split between four policies, plus the perception and walk variants. The
longer mode (whole runs, more of them)::

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
from tests.robot.helpers import REALISM, differing_runs, scenario

pytest.importorskip("py_trees")

SEEDS = int(os.environ.get("SWARMTAG_SIL_SEEDS") or 100)
"""Seeded runs of the small swarm (the large one gets a fifth of them)."""
TICKS = int(os.environ.get("SWARMTAG_SIL_TICKS") or 400)
"""Ticks of a small-swarm run (the large one runs for three quarters of them)."""


def _compare(world: Scenario, runs: int, policies: list) -> dict[str, list[int]]:
    """The differing runs per policy; the runs are split between the policies."""
    found = {}
    share = -(-runs // len(policies))
    for index, policy in enumerate(policies):
        count = min(share, runs - index * share)
        if count <= 0:
            break
        diff = differing_runs(world, policy, seed=0, runs=count, run_offset=index * share)
        if diff:
            found[policy.name] = diff
    return found


POLICIES = [Urgency(alpha=0.7), Proximity(), Weighted(w=0.3), Urgency(alpha=2.0), Edf()]


@pytest.mark.parametrize("realism", [False, True], ids=["realism-off", "realism-on"])
def test_small_swarm_event_logs_are_identical(realism):
    changes = {"realism": REALISM} if realism else {}
    world = scenario(3, 7, ticks=TICKS, **changes)
    assert _compare(world, SEEDS, POLICIES) == {}


@pytest.mark.parametrize("realism", [False, True], ids=["realism-off", "realism-on"])
def test_large_swarm_event_logs_are_identical(realism):
    changes = {"realism": REALISM} if realism else {}
    world = scenario(20, 40, ticks=TICKS * 3 // 4, **changes)
    assert _compare(world, max(1, SEEDS // 5), POLICIES) == {}


@pytest.mark.parametrize(
    "world",
    [
        scenario(3, 7, "paper-sim", ticks=1500),
        scenario(3, 7, "lab", ticks=500, urgency={"model": "static"}),
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
        scenario(3, 7, "lab", ticks=900, urgency={"model": "static"}, walk={"curve": 90.0}),
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
            ticks=900,
            urgency={"model": "static"},
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
    assert _compare(world, 2, POLICIES[:2]) == {}


RULES = Path(__file__).parents[1] / "policy" / "rule_examples.py"


_PAPER = scenario(3, 7, "paper-sim", ticks=700)
_SEARCH = scenario(
    3,
    7,
    "lab",
    ticks=700,
    urgency={"model": "static"},
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
        assert differing_runs(world, rule, seed=3, runs=2) == []


def test_the_runs_exercise_the_whole_tree():
    # Lifts, deliveries, abandons and timeouts all happen in the compared runs, so every
    # behaviour of the tree is checked against the built-in controller.
    world = scenario(3, 7, ticks=TICKS, realism=REALISM)
    result = simulate(world, Urgency(alpha=0.7), seed=0, runs=25, controller="bt")
    kinds = set(result.events.kind.tolist())
    assert {"select", "candidates", "lift", "deliver", "abandon", "breakdown"} <= kinds
    assert result.delivered.sum() >= 25


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
