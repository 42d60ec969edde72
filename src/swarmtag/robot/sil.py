"""Software-in-the-loop: every simulated robot runs its own behaviour tree.

``TreeController`` is a ``swarmtag.sim.control.interface.Controller``: at each control
step it binds each robot's ``SimRobotIO`` view to the step and ticks the
robot's tree, robots of a run in id order (a robot sees the behaviour the
smaller ids announced in the same step, as its range sensors would), runs
that have ended and broken robots skipped. Trees are made on the first
tick of a batch, one per robot with its own blackboard namespace, by a
factory (``swarmtag.robot.tree.create_tree`` unless another is given), and
connected with ``setup(io=view)``.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Final

import numpy as np
import py_trees

from swarmtag.robot.config import ControllerConfig
from swarmtag.robot.io import ControlStep, Report
from swarmtag.robot.sim_io import SimRobotIO, StepContext
from swarmtag.robot.tree import create_tree, initialise_memory
from swarmtag.sim.control.interface import Arrivals, Carrying, LiftAnswers
from swarmtag.sim.model.events import EventKind, TickEvents
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import Mode, WorldState
from swarmtag.sim.world.sensing import Senses

__all__ = ["TreeController", "TreeFactory"]

TreeFactory = Callable[[ControllerConfig, str], py_trees.trees.BehaviourTree]
"""Makes one robot's tree: (configuration, blackboard namespace) -> tree."""

_KINDS: Final = {
    Report.ABANDON: EventKind.ABANDON,
    Report.TIMEOUT: EventKind.TIMEOUT,
    Report.SELECT: EventKind.SELECT,
    Report.CANDIDATES: EventKind.CANDIDATES,
}
_batches = itertools.count()


class TreeController:
    """Drives every robot of a batch with its own behaviour tree (``simulate(controller="bt")``).

    One instance serves one batch (``run_batch`` call); ``close()`` removes its
    trees' blackboard entries.
    """

    name = "bt"

    def __init__(self, factory: TreeFactory = create_tree) -> None:
        self._factory = factory
        self._trees: dict[tuple[int, int], py_trees.trees.BehaviourTree] = {}
        self._views: dict[tuple[int, int], SimRobotIO] = {}
        self._memories: list[py_trees.blackboard.Client] = []
        self._prefix = f"/swarmtag/batch{next(_batches)}"
        self._senses: Senses | None = None
        self._inputs: TickInputs | None = None
        self._before: WorldState | None = None

    def _connect(self, context: StepContext) -> None:
        """Make, set up and remember a tree per robot of the batch (first tick only)."""
        config = ControllerConfig.from_params(context.params)
        runs, robots = context.s.mode.shape
        for row in range(runs):
            for robot in range(robots):
                namespace = f"{self._prefix}/run{int(context.s.run_ids[row])}/robot{robot}"
                view = SimRobotIO(row, robot, context)
                self._memories.append(initialise_memory(namespace, config, view))
                tree = self._factory(config, namespace)
                tree.setup(io=view)
                self._trees[row, robot] = tree
                self._views[row, robot] = view

    def _tick(self, context: StepContext) -> None:
        if not self._trees:
            self._connect(context)
        before, s = context.before, context.s
        # The working robots found once a tick: Mode.BROKEN looked up for every robot (the
        # enum class's __getattr__ on Python 3.11) was 9 % of the Python calls of a tick.
        rows, robots = np.nonzero((before.ended_at < 0)[:, None] & (s.mode != Mode.BROKEN))
        for row, robot in zip(rows.tolist(), robots.tolist(), strict=True):  # row by row
            self._views[row, robot].context = context
            # the root alone: the tree's own tick adds visitors and handlers, unused here
            self._trees[row, robot].root.tick_once()

    def _report(self, context: StepContext, events: TickEvents) -> None:
        """The reported decisions as the step's events, one entry per kind."""
        shape = context.s.mode.shape
        for report, kind in _KINDS.items():
            rows = [entry for entry in context.reports if entry[0] == report]
            if not rows:
                continue
            mask = np.zeros(shape, dtype=bool)
            carrier = np.full(shape, -1, dtype=np.int64)
            value = np.full(shape, np.nan)
            for _, row, robot, target, number in rows:
                mask[row, robot] = True
                carrier[row, robot] = target
                value[row, robot] = number
            events.add(kind, mask, carrier, value)

    def decide(
        self,
        before: WorldState,
        s: WorldState,
        *,
        senses: Senses,
        inputs: TickInputs,
        params: Params,
        t: int,
        events: TickEvents,
    ) -> None:
        """Tick every tree at the sensed step."""
        context = StepContext(ControlStep.SENSED, t, before, s, params, senses, inputs)
        self._senses, self._inputs = senses, inputs
        self._tick(context)
        self._report(context, events)

    def arrive(self, before: WorldState, s: WorldState, *, params: Params, t: int) -> Arrivals:
        """Tick every tree at the moved step; their requests."""
        context = StepContext(ControlStep.MOVED, t, before, s, params, self._senses, self._inputs)
        self._before = before
        self._tick(context)
        return Arrivals(drive_in=context.drive_in, centred=context.centred, lift=context.lift)

    def carry(self, s: WorldState, answers: LiftAnswers, *, params: Params, t: int) -> Carrying:
        """Tick every tree at the answered step; their requests."""
        if self._before is None:
            msg = "carry before arrive"
            raise RuntimeError(msg)
        context = StepContext(
            ControlStep.ANSWERED,
            t,
            self._before,
            s,
            params,
            self._senses,
            self._inputs,
            accepted=answers.accepted,
            refused=answers.refused,
        )
        self._tick(context)
        return Carrying(raised=context.raised, lower=context.lower)

    def close(self) -> None:
        """Remove the trees and their blackboard entries."""
        for tree in self._trees.values():
            tree.shutdown()
            for node in tree.root.iterate():
                for client in node.blackboards:
                    client.unregister(clear=True)
        for memory in self._memories:
            memory.unregister(clear=True)
        self._trees.clear()
        self._views.clear()
        self._memories.clear()
