"""A conformance check for controllers: the first tick, robot and field where one departs.

In the manner of Gymnasium's ``env_checker``: ``check_controller`` runs a
scenario under the built-in controller and under the controller given, in
lockstep from the same seeded start and random inputs, and compares after
every tick the world state (bodies, carriers, tags), the robots' command
registers (``swarmtag.sim.control.interface.COMMAND_FIELDS``) and the tick's events.
The built-in controller's own memory fields are not compared: another
controller keeps its memory its own way.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, fields
from typing import Any

import numpy as np

from swarmtag._checks import check_int
from swarmtag.errors import ConformanceError
from swarmtag.policy import Policy
from swarmtag.sim.builtin.controller import BUILTIN
from swarmtag.sim.config.scenario import Scenario
from swarmtag.sim.control.interface import COMMAND_FIELDS, MEMORY_FIELDS, Controller
from swarmtag.sim.model.events import EventKind, TickEvents
from swarmtag.sim.model.params import make_params
from swarmtag.sim.model.randomness import RandomSource, check_seed
from swarmtag.sim.model.state import WorldState
from swarmtag.sim.model.step import step
from swarmtag.sim.runner import seeded_state

__all__ = ["Divergence", "check_controller"]

_SKIPPED = frozenset(MEMORY_FIELDS) | {"tick", "run_ids"}


@dataclass(frozen=True)
class Divergence:
    """Where a controller first departed from the built-in one.

    ``robot`` is None for a carrier's or a run's field (then ``carrier``
    names the carrier where there is one); ``field`` is a state field or
    ``events``.
    """

    seed: int
    run: int
    tick: int
    robot: int | None
    carrier: int | None
    field: str
    expected: str
    actual: str

    def __str__(self) -> str:
        """One line: where, which field, the built-in value and the other."""
        where = f"seed {self.seed}, run {self.run}, tick {self.tick}"
        if self.robot is not None:
            where += f", robot {self.robot}"
        if self.carrier is not None:
            where += f", carrier {self.carrier}"
        return (
            f"{where}: {self.field} is {self.actual}, the built-in controller's is {self.expected}"
        )


def _event_rows(events: TickEvents, runs: int) -> list[list[tuple[Any, ...]]]:
    """Each run's events of a tick as sorted (kind, robot, carrier, value) rows."""
    rows: list[list[tuple[Any, ...]]] = [[] for _ in range(runs)]
    for event in events.carrier_entries:
        rows[event.run].append((event.kind.label, -1, event.carrier, repr(event.value)))
    for entry in events.entries:
        for run, robot in zip(*np.nonzero(entry.mask), strict=True):
            value = float(entry.value[run, robot])
            rows[int(run)].append(
                (
                    EventKind(entry.kind).label,
                    int(robot),
                    int(entry.carrier[run, robot]),
                    "nan" if np.isnan(value) else repr(value),
                )
            )
    return [sorted(run_rows) for run_rows in rows]


_ROBOT_CARRIER_FIELDS = frozenset(
    {"blocked_until", "known_status", "known_urgency", "heard_tick", "seen_tick", "seen_pos"}
)
_CARRIER_FIELDS = frozenset(
    {
        "carrier_pos",
        "status",
        "urgency",
        "present",
        "carried_by",
        "w0",
        "urgency0",
        "order_time",
        "free_face",
        "advert_phase",
        "pickup_time",
        "delivery_time",
        "deliverer",
        "delivery_urgency",
    }
)


def _axes(name: str) -> tuple[str, ...]:
    """What the axes after the run axis of a state field index."""
    if name in _ROBOT_CARRIER_FIELDS:
        return ("robot", "carrier")
    if name in _CARRIER_FIELDS:
        return ("carrier",)
    if name in ("adv_status", "adv_urgency"):
        return ("slot", "carrier")
    if name in ("ended_at", "operator_counter"):
        return ()
    return ("robot",)


def _order() -> list[str]:
    """Compared fields, the command registers first (the likeliest first sign)."""
    names = [f.name for f in fields(WorldState) if f.name not in _SKIPPED]
    return [*COMMAND_FIELDS, *(n for n in names if n not in COMMAND_FIELDS)]


def _first_difference(
    expected: WorldState, actual: WorldState, seed: int, tick: int
) -> Divergence | None:
    """The first differing entry of the compared fields, by run, then field order."""
    for row in range(expected.runs):
        for name in _order():
            want = np.asarray(getattr(expected, name)[row])
            got = np.asarray(getattr(actual, name)[row])
            floating = want.dtype.kind == "f"
            if np.array_equal(want, got, equal_nan=floating):
                continue
            same = want == got
            if floating:
                same |= np.isnan(want) & np.isnan(got)
            index = [int(i) for i in np.argwhere(~same)[0]] if want.ndim else []
            axes = _axes(name)
            cell = tuple(index[: len(axes)])
            found = dict(zip(axes, cell, strict=False))
            return Divergence(
                seed=seed,
                run=int(expected.run_ids[row]),
                tick=tick,
                robot=found.get("robot"),
                carrier=found.get("carrier"),
                field=name,
                expected=np.array2string(want[cell], precision=17),
                actual=np.array2string(got[cell], precision=17),
            )
    return None


def _compare_seed(
    make: Callable[[], Controller],
    scenario: Scenario,
    policy: Policy,
    *,
    seed: int,
    runs: int,
    ticks: int,
) -> Divergence | None:
    params = make_params(scenario, policy)
    expected = seeded_state(params, seed=seed, runs=runs)
    actual = expected.copy()
    sources = [RandomSource(params, seed=seed, run_ids=expected.run_ids) for _ in range(2)]
    controller = make()
    try:
        for _ in range(ticks):
            if (expected.ended_at >= 0).all():
                break
            t = expected.tick + 1
            expected, want = step(expected, sources[0].inputs(t), params, BUILTIN)
            actual, got = step(actual, sources[1].inputs(t), params, controller)
            found = _first_difference(expected, actual, seed, t)
            for row, (a, b) in enumerate(
                zip(_event_rows(want, runs), _event_rows(got, runs), strict=True)
            ):
                if a != b and (found is None or found.run > int(expected.run_ids[row])):
                    extra, missing = sorted(set(b) - set(a)), sorted(set(a) - set(b))
                    return Divergence(
                        seed=seed,
                        run=int(expected.run_ids[row]),
                        tick=t,
                        robot=(extra or missing)[0][1],
                        carrier=None,
                        field="events",
                        expected=str(missing),
                        actual=str(extra),
                    )
            if found is not None:
                return found
    finally:
        close = getattr(controller, "close", None)
        if callable(close):
            close()
    return None


def check_controller(
    controller: Callable[[], Controller],
    scenario: Scenario,
    policy: Policy,
    *,
    seeds: Iterable[int] = (0,),
    runs: int = 1,
    ticks: int | None = None,
    strict: bool = True,
) -> Divergence | None:
    """Compare ``controller`` with the built-in controller on ``scenario`` tick by tick.

    ``controller`` makes a fresh controller for one batch (e.g.
    ``swarmtag.robot.TreeController``, or ``lambda: TreeController(my_factory)``).
    Each seed runs ``runs`` runs for ``ticks`` ticks (default: the scenario's
    run length). Returns None when they agree throughout; at the first
    divergence raises ``ConformanceError`` naming the seed, run, tick, robot
    and field (``strict=False``: returns the ``Divergence``).
    """
    runs = check_int("runs", runs, low=1, high=10_000)
    limit = scenario.run_ticks if ticks is None else check_int("ticks", ticks, low=1)
    checked: Sequence[int] = [check_seed(seed) for seed in seeds]
    for seed in checked:
        divergence = _compare_seed(controller, scenario, policy, seed=seed, runs=runs, ticks=limit)
        if divergence is not None:
            if strict:
                raise ConformanceError(str(divergence))
            return divergence
    return None
