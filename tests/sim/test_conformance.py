"""The conformance kit: the tree passes, deliberately broken trees are caught where they break."""

from __future__ import annotations

from dataclasses import replace

import pytest

from swarmtag.errors import ConformanceError
from swarmtag.policy import Proximity, Urgency
from swarmtag.robot import (
    ControllerConfig,
    Divergence,
    TreeController,
    check_controller,
    create_tree,
)
from swarmtag.sim import BUILTIN
from tests.robot.helpers import REALISM, scenario

pytest.importorskip("py_trees")

WORLD = scenario(3, 7, ticks=400)
CHOICES = scenario(3, 7, "paper-sim", ticks=800)
"""The default world: the camera sees across the arena, so robots have choices to make."""


def ignores_urgency(config: ControllerConfig, namespace: str):
    """A tree whose selection ignores urgency (proximity whatever the policy)."""
    return create_tree(replace(config, policy=Proximity()), namespace)


def never_times_out(config: ControllerConfig, namespace: str):
    """A tree whose pursuits never time out."""
    return create_tree(replace(config, timeout_ticks=10**9), namespace)


def test_the_behaviour_tree_conforms():
    assert check_controller(TreeController, WORLD, Urgency(alpha=0.7), seeds=[0, 1], runs=2) is None
    with_realism = scenario(3, 7, ticks=300, realism=REALISM)
    assert check_controller(TreeController, with_realism, Urgency(alpha=0.7), seeds=[3]) is None


def test_the_built_in_controller_conforms_to_itself():
    assert check_controller(lambda: BUILTIN, WORLD, Proximity(), seeds=[0]) is None


@pytest.mark.first
def test_a_selection_that_ignores_urgency_is_caught_at_its_first_wrong_choice():
    found = check_controller(
        lambda: TreeController(ignores_urgency),
        CHOICES,
        Urgency(alpha=0.7),
        seeds=[0],
        runs=4,
        strict=False,
    )
    assert isinstance(found, Divergence)
    assert found.field == "target"  # the command register: the robot pursues another carrier
    assert found.robot is not None
    assert found.tick >= 1
    # Up to that tick the broken tree agreed: the same check stops there.
    assert (
        check_controller(
            lambda: TreeController(ignores_urgency),
            CHOICES,
            Urgency(alpha=0.7),
            seeds=[0],
            runs=4,
            ticks=found.tick - 1,
        )
        is None
    )
    # Under proximity the two selections agree, so the tree conforms there.
    assert check_controller(lambda: TreeController(ignores_urgency), CHOICES, Proximity()) is None


def test_strict_mode_raises_with_the_place_in_the_message():
    with pytest.raises(ConformanceError, match=r"seed 0, run \d+, tick \d+, robot \d+: target is"):
        check_controller(
            lambda: TreeController(ignores_urgency), CHOICES, Urgency(alpha=0.7), runs=4
        )


def test_a_missing_timeout_is_caught_when_the_built_in_robot_gives_up():
    world = scenario(3, 7, ticks=1500, timing={"pursuit_timeout": 5.0})
    found = check_controller(
        lambda: TreeController(never_times_out), world, Urgency(alpha=0.7), runs=8, strict=False
    )
    assert found is not None
    assert found.field in {"mode", "target", "face", "events"}


def test_bad_arguments_are_refused():
    from swarmtag.errors import ConfigError

    with pytest.raises(ConfigError, match="runs"):
        check_controller(TreeController, WORLD, Proximity(), runs=0)
    with pytest.raises(ConfigError, match="seed"):
        check_controller(TreeController, WORLD, Proximity(), seeds=[-1])
