"""The robot's controller: the robot-I/O protocol, the behaviour tree, software-in-the-loop.

- ``RobotIO`` and its data types: what a controller may read and do
  (``swarmtag.robot.io``); the simulator offers one view per robot, a real
  robot its drivers (docs/controller.md);
- ``ControllerConfig``: the mission rules and site geometry;
- ``TagCache`` / ``tag_states`` / ``Ranging``: a BLE scanner's sightings as the
  ``tag_states`` sensor, ranged by RSSI for BLE-led search (``swarmtag.robot.tag_cache``);
- ``create_tree`` and the subtree factories (py_trees, the ``robot``
  extra): SPEC §3.2 as a behaviour tree;
- ``SimRobotIO``: one simulated robot through ``RobotIO`` (the simulator's view);
- ``TreeController``: every simulated robot under its own tree
  (``simulate(..., controller="bt")``);
- ``check_controller``: a conformance check against the built-in controller.

The modules that need py_trees are imported on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from swarmtag.robot.config import ControllerConfig
from swarmtag.robot.io import (
    Behaviour,
    ControlStep,
    Detections,
    Pose,
    RandomDraws,
    Report,
    RobotIO,
    TagStates,
)
from swarmtag.robot.tag_cache import Ranging, TagCache, tag_states

if TYPE_CHECKING:
    from swarmtag.robot.sil import TreeController, TreeFactory
    from swarmtag.robot.sim_io import SimRobotIO, StepContext
    from swarmtag.robot.tree import ascii_picture, create_tree, dot_picture
    from swarmtag.sim.conformance import Divergence, check_controller

__all__ = [
    "Behaviour",
    "ControlStep",
    "ControllerConfig",
    "Detections",
    "Divergence",
    "Pose",
    "RandomDraws",
    "Ranging",
    "Report",
    "RobotIO",
    "SimRobotIO",
    "StepContext",
    "TagCache",
    "TagStates",
    "TreeController",
    "TreeFactory",
    "ascii_picture",
    "check_controller",
    "create_tree",
    "dot_picture",
    "tag_states",
]

_LAZY = {
    "Divergence": "swarmtag.sim.conformance",
    "check_controller": "swarmtag.sim.conformance",
    "SimRobotIO": "swarmtag.robot.sim_io",
    "StepContext": "swarmtag.robot.sim_io",
    "TreeController": "swarmtag.robot.sil",
    "TreeFactory": "swarmtag.robot.sil",
    "ascii_picture": "swarmtag.robot.tree",
    "create_tree": "swarmtag.robot.tree",
    "dot_picture": "swarmtag.robot.tree",
}


def __getattr__(name: str) -> object:
    """Import the py_trees parts on first use."""
    module = _LAZY.get(name)
    if module is None:
        msg = f"module 'swarmtag.robot' has no attribute {name!r}"
        raise AttributeError(msg)
    return getattr(importlib.import_module(module), name)
