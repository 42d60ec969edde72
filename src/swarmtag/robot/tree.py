"""The robot's behaviour tree (SPEC §3.2), built from reusable subtrees, and its pictures.

::

    Robot (selector)
    ├── Fetch a carrier (sequence, with memory)
    │   ├── Find a carrier (selector): Select carrier, else Random walk
    │   ├── Pursue (sequence): Still awaiting?, Within timeout?, then
    │   │   Predock, then Dock and centre (Dock, Centre)
    │   ├── Lift
    │   ├── Transport and release (Transport, Release)
    │   └── Back to random walk
    └── Give up: back to random walk

A pursuit that is abandoned, times out or whose lift write is refused fails
the fetch; the robot's selector then falls back to random walk. Every
robot has its own tree and its own blackboard namespace.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import py_trees
from py_trees.composites import Selector, Sequence

from swarmtag._checks import check_instance, check_path_value, check_text, show
from swarmtag.errors import ConfigError
from swarmtag.robot.behaviours import (
    Centre,
    Dock,
    Lift,
    Predock,
    RandomWalk,
    Release,
    ResumeWalk,
    SelectCarrier,
    StillAwaiting,
    Transport,
    WithinTimeout,
)
from swarmtag.robot.config import ControllerConfig
from swarmtag.robot.io import RobotIO

__all__ = [
    "ascii_picture",
    "create_tree",
    "dot_picture",
    "find_carrier",
    "initialise_memory",
    "pursue",
    "transport_and_release",
]


def find_carrier(config: ControllerConfig, namespace: str) -> py_trees.behaviour.Behaviour:
    """Random walk until the policy selects a carrier among the candidates."""
    return Selector(
        "Find a carrier",
        memory=False,
        children=[
            SelectCarrier("Select carrier", config, namespace),
            RandomWalk("Random walk", config, namespace),
        ],
    )


def pursue(config: ControllerConfig, namespace: str) -> py_trees.behaviour.Behaviour:
    """Predock, dock and centre, guarded by the abandon and timeout rules."""
    return Sequence(
        "Pursue",
        memory=False,
        children=[
            StillAwaiting("Still awaiting?", config, namespace),
            WithinTimeout("Within timeout?", config, namespace),
            Sequence(
                "Approach",
                memory=True,
                children=[
                    Predock("Predock", config, namespace),
                    Sequence(
                        "Dock and centre",
                        memory=True,
                        children=[
                            Dock("Dock", config, namespace),
                            Centre("Centre", config, namespace),
                        ],
                    ),
                ],
            ),
        ],
    )


def transport_and_release(config: ControllerConfig, namespace: str) -> py_trees.behaviour.Behaviour:
    """Carry the load to the drop-off area and set it down."""
    return Sequence(
        "Transport and release",
        memory=True,
        children=[
            Transport("Transport", config, namespace),
            Release("Release", config, namespace),
        ],
    )


def create_tree(
    config: ControllerConfig, namespace: str = "/robot"
) -> py_trees.trees.BehaviourTree:
    """One robot's tree, its memory under ``namespace`` (connect it with ``setup(io=...)``)."""
    check_instance("config", config, ControllerConfig)
    if not check_text("namespace", namespace):
        raise ConfigError("namespace: the empty string names no blackboard namespace")
    fetch = Sequence(
        "Fetch a carrier",
        memory=True,
        children=[
            find_carrier(config, namespace),
            pursue(config, namespace),
            Lift("Lift", config, namespace),
            transport_and_release(config, namespace),
            ResumeWalk("Back to random walk", config, namespace),
        ],
    )
    root = Selector(
        "Robot", memory=False, children=[fetch, ResumeWalk("Give up", config, namespace)]
    )
    return py_trees.trees.BehaviourTree(root)


def initialise_memory(
    namespace: str, config: ControllerConfig, io: RobotIO
) -> py_trees.blackboard.Client:
    """Write a robot's starting memory under ``namespace``; returns the client that holds it."""
    memory = py_trees.blackboard.Client(name="memory", namespace=namespace)
    for key in ("target", "face", "pursuit_start", "timer", "redirect", "stuck"):
        memory.register_key(key=key, access=py_trees.common.Access.WRITE)
    for key in ("walk", "walk_clock", "blocked_until", "seek", "seek_ref", "curve", "look"):
        memory.register_key(key=key, access=py_trees.common.Access.WRITE)
    memory.target = memory.face = memory.pursuit_start = memory.seek = memory.look = -1
    memory.seek_ref = 0.0
    memory.curve = np.zeros(2)
    memory.timer = memory.stuck = memory.walk_clock = 0
    memory.redirect = False
    memory.walk = io.pose().heading.copy()
    memory.blocked_until = np.zeros(len(config.markers), dtype=np.int64)
    return memory


def ascii_picture(tree: py_trees.trees.BehaviourTree) -> str:
    """The tree as text (py_trees' ASCII rendering)."""
    check_instance("tree", tree, py_trees.trees.BehaviourTree)
    return py_trees.display.ascii_tree(tree.root)


def dot_picture(
    tree: py_trees.trees.BehaviourTree, folder: Path, name: str = "robot-tree"
) -> list[Path]:
    """Write the tree as Graphviz dot, and as PNG and SVG where Graphviz is installed.

    Returns the files written (``folder / name`` with .dot, .png, .svg).
    """
    check_instance("tree", tree, py_trees.trees.BehaviourTree)
    folder = Path(check_path_value("folder", folder))
    if not check_text("name", name) or "/" in name or "\0" in name or name in (".", ".."):
        raise ConfigError(f"name: {show(name)} is not a plain file name")
    if not folder.is_dir():
        raise ConfigError(f"folder: {show(str(folder))} is not an existing folder")
    graph = py_trees.display.dot_tree(tree.root)
    written = [folder / f"{name}.dot"]
    graph.write(str(written[0]), format="raw")
    if shutil.which("dot") is not None:
        for suffix in ("png", "svg"):
            target = folder / f"{name}.{suffix}"
            graph.write(str(target), format=suffix)
            written.append(target)
    return written
