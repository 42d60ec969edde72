"""Shared helpers for the simulator tests: hand-built scenes and scripted random inputs."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from swarmtag.policy import Policy, Proximity
from swarmtag.sim import (
    Params,
    Scenario,
    Scene,
    SimResult,
    TickInputs,
    WorldState,
    due_writes,
    initial_state,
    make_params,
    run_batch,
)


def params_for(policy: Policy | None = None, **scenario: object) -> Params:
    """Kernel parameters for a scenario given as keywords (robots/carriers must match the scene)."""
    return make_params(Scenario(**scenario), policy or Proximity())


def start(params: Params, scene: Scene) -> WorldState:
    """A batch of one run starting from ``scene``."""
    return initial_state(params, [scene], [0])


class Script:
    """Scripted tick inputs: fixed walk/sidestep directions, breakdowns at given ticks."""

    def __init__(
        self,
        params: Params,
        *,
        walk: Sequence[Sequence[float]] | Sequence[float] = (1.0, 0.0),
        sidestep: Sequence[float] = (0.0, 1.0),
        breakdowns: Mapping[int, Sequence[int]] | None = None,
        runs: int = 1,
    ) -> None:
        self._params = params
        self._runs = runs
        self._walk = np.asarray(walk, dtype=np.float64)
        self._sidestep = np.asarray(sidestep, dtype=np.float64)
        self._breakdowns = dict(breakdowns or {})
        self.asked: list[int] = []

    def inputs(self, tick: int) -> TickInputs:
        self.asked.append(tick)
        breakdown = np.zeros((self._runs, self._params.robots), dtype=bool)
        breakdown[:, list(self._breakdowns.get(tick, ()))] = True
        return TickInputs.fixed(
            self._runs,
            self._params.robots,
            walk=self._walk,
            sidestep=self._sidestep,
            breakdown=breakdown,
            writes=due_writes(self._params, tick),
        )


def run_script(params: Params, scene: Scene, ticks: int, **script: object) -> SimResult:
    """Run one hand-built run for ``ticks`` ticks with invariant checks on."""
    return run_batch(
        start(params, scene), params, Script(params, **script), ticks=ticks, check=True
    )


def event_rows(result: SimResult, *, candidates: bool = False) -> list[tuple[int, str, int, int]]:
    """(time, kind, robot, carrier) of every event, in table order.

    ``candidates`` events (one with every ``select``) are left out unless asked for.
    """
    events = result.events
    rows = zip(
        events.time.astype(int).tolist(),
        events.kind.tolist(),
        events.robot.tolist(),
        events.carrier.tolist(),
        strict=True,
    )
    return [row for row in rows if candidates or row[1] != "candidates"]
