"""Shared helpers for the simulator tests: hand-built scenes and scripted random inputs."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path

import numpy as np

from swarmtag.policy import Policy, Proximity
from swarmtag.sim import (
    Params,
    Scenario,
    Scene,
    SimResult,
    TickInputs,
    WorldState,
    initial_state,
    make_params,
    run_batch,
)
from swarmtag.sim.model.randomness import due_writes


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


# -- warehouses -------------------------------------------------------------------------------

NEVER = 10**9
"""A due tick no test run reaches: the order is allocated but never placed."""


def warehouse_params(
    map_file: Path,
    text: str,
    *,
    policy: Policy | None = None,
    warehouse: Mapping[str, object] | None = None,
    **scenario: object,
) -> Params:
    """Kernel parameters for a warehouse on map ``text`` (written to ``map_file``).

    The order stream defaults to no orders beyond ``initial_orders`` (0) in
    any run a test steps, so the scenario pre-allocates 7 carriers.
    """
    map_file.write_text(text, encoding="utf-8")
    part = {"map": str(map_file), "initial_orders": 0, "order_interval": 1e6}
    part.update(warehouse or {})
    return make_params(
        Scenario.from_mapping({**scenario, "warehouse": part}), policy or Proximity()
    )


def order_scene(
    params: Params,
    robots: Sequence[Sequence[float]],
    *,
    due: Sequence[int] = (),
    carriers: Sequence[Sequence[float]] = (),
    destination: Sequence[int] = (),
    slot: Sequence[int] = (),
    slot_pick: Sequence[float] = (),
    w0: Sequence[float] = (),
    heading: Sequence[Sequence[float]] | None = None,
) -> Scene:
    """A warehouse scene: the first orders as given, the rest never due (shorter lists pad).

    Carriers not given stand on the first pick-up slot (a placeholder until
    placed); ``w0`` is the growth base as the state holds it (the draw minus
    the due tick).
    """
    assert params.floor is not None
    c = params.carriers

    def padded(values: Sequence[float], fill: float, dtype: type) -> np.ndarray:
        out = np.full(c, fill, dtype=dtype)
        out[: len(values)] = values
        return out

    positions = np.repeat(params.floor.pickup_slots[:1], c, axis=0)
    if len(carriers):
        positions[: len(carriers)] = carriers
    scene = Scene.build(
        robots=robots, carriers=positions, w0=padded(w0, 0.0, np.float64), heading=heading
    )
    return replace(
        scene,
        due=padded(due, NEVER, np.int64),
        destination=padded(destination, 0, np.int64),
        slot=padded(slot, -1, np.int64),
        slot_pick=padded(slot_pick, 0.0, np.float64),
    )
