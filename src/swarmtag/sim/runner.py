"""Running batches: ``run_batch`` (any start state and inputs), seeded starts, results.

The thin stateful wrapper around the pure kernel: it draws the scenes and
the per-tick random inputs (and the operator's scheduled writes), steps the
kernel tick by tick (a Python loop over ticks, everything else vectorised
over runs and robots), records events (and trajectories), and builds
the event logs of SPEC §8.1.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final, Protocol

import numpy as np

from swarmtag._checks import MAX_RUN_INDEX, check_int
from swarmtag._interrupt import checkpoint
from swarmtag.io import CarrierLog, EventTable
from swarmtag.sim.builtin.controller import BUILTIN
from swarmtag.sim.config.scenario import Scenario
from swarmtag.sim.control.interface import Controller
from swarmtag.sim.model.events import EventKind, EventRecorder
from swarmtag.sim.model.invariants import check_tick
from swarmtag.sim.model.params import FIRST_CACHE_CAPACITY, Params, sparse_tag_cache
from swarmtag.sim.model.randomness import TickInputs, check_seed
from swarmtag.sim.model.scene import sample_scene
from swarmtag.sim.model.state import Int, Mode, WorldState, initial_state
from swarmtag.sim.model.step import step
from swarmtag.sim.outputs.trajectories import Trajectories, TrajectoryRecorder
from swarmtag.sim.world.broad_phase import grid_pays
from swarmtag.tag import TagStatus

__all__ = [
    "LOG_BYTES_PER_CARRIER",
    "InputSource",
    "SimResult",
    "batch_memory",
    "batch_result",
    "carrier_log",
    "run_batch",
    "seeded_state",
]


class InputSource(Protocol):
    """Anything that hands out the random inputs of tick 1, 2, ... (``RandomSource``, scripts)."""

    def inputs(self, tick: int) -> TickInputs:
        """The inputs of ``tick``."""
        ...


@dataclass(frozen=True, eq=False)
class SimResult:
    """A batch's outcome: event logs, per-run counts, final state, optional trajectories.

    Per-run arrays follow ``run_ids``. ``stuck`` counts carriers left
    PICKED_UP on a broken-down robot; ``undelivered`` includes them.
    """

    carriers: CarrierLog
    events: EventTable
    run_ids: Int
    delivered: Int
    undelivered: Int
    stuck: Int
    breakdowns: Int
    end_tick: Int
    """Tick at which each run ended (last delivery or time limit), or the last tick run."""
    final_state: WorldState
    trajectories: Trajectories | None = None


def _run_ends(state: WorldState) -> Int:
    """(R,) the tick each run ended (its last delivery or time limit), or the last tick run."""
    end: Int = np.where(state.ended_at >= 0, state.ended_at, state.tick)
    return end


def carrier_log(state: WorldState, params: Params, *, seed: int) -> CarrierLog:
    """The per-carrier event log (SPEC §8.1) of ``state``: one row per carrier per run.

    Times are ticks, or seconds (ticks times ``tick``) when the scenario's
    ``time_unit`` is ``"s"``. ``run_end`` is when the run ended (every carrier
    delivered, or its time limit); ``urgency_end`` each carrier's urgency when
    delivered, or at the run's end. A warehouse run lists the orders due by
    its end (those due later were allocated but never entered the run).
    """
    runs, carriers = state.status.shape
    scale = params.time_scale
    end = _run_ends(state)
    keep = (state.due <= end[:, None]).reshape(-1)  # warehouse orders due later are not in the run

    def column(values: np.ndarray) -> np.ndarray:
        return values.reshape(-1)[keep]

    def times(ticks: Int) -> np.ndarray:
        return column(np.where(ticks >= 0, ticks.astype(np.float64) * scale, np.nan))

    rows = int(keep.sum())
    return CarrierLog(
        condition=np.full(rows, params.condition),
        run=column(np.repeat(state.run_ids, carriers)),
        seed=np.full(rows, seed, dtype=np.int64),
        carrier=column(np.tile(params.markers, runs)),
        urgency0=column(state.urgency0).astype(np.int64),
        order_time=column(state.order_time) * scale + 0.0,
        pickup_time=times(state.pickup_time),
        delivery_time=times(state.delivery_time),
        robot=column(state.deliverer),
        run_end=times(np.repeat(end, carriers)),
        urgency_end=column(
            np.where(state.delivery_urgency >= 0, state.delivery_urgency, state.urgency)
        ).astype(np.int64),
        time_unit=params.scenario.time_unit,
    )


def run_batch(
    state: WorldState,
    params: Params,
    source: InputSource,
    *,
    seed: int = 0,
    ticks: int | None = None,
    record: bool = False,
    check: bool = False,
    controller: Controller = BUILTIN,
) -> SimResult:
    """Step ``state`` until every run has ended, or for ``ticks`` ticks at most.

    ``seed`` is only written into the logs. ``check=True`` verifies the
    invariants of ``swarmtag.sim.model.invariants`` after every tick.
    ``controller`` decides for the robots (``swarmtag.sim.control.interface``).
    """
    limit = params.run_ticks - state.tick if ticks is None else check_int("ticks", ticks, low=0)
    events = EventRecorder()
    breakdowns = np.zeros(state.runs, dtype=np.int64)
    recorder = TrajectoryRecorder(state, limit) if record else None
    for _ in range(limit):
        checkpoint()  # a Ctrl-C that numpy swallowed during the last tick ends the run here
        if (state.ended_at >= 0).all():
            break
        t = state.tick + 1
        after, tick_events = step(state, source.inputs(t), params, controller)
        if check:
            check_tick(state, after, tick_events, params)
        events.add_tick(t, tick_events)
        breakdowns += tick_events.count(EventKind.BREAKDOWN, state.runs)
        if recorder is not None:
            recorder.add(after)
        state = after
    return batch_result(
        state, params, seed=seed, events=events, breakdowns=breakdowns, recorder=recorder
    )


def batch_result(
    state: WorldState,
    params: Params,
    *,
    seed: int,
    events: EventRecorder,
    breakdowns: Int,
    recorder: TrajectoryRecorder | None,
) -> SimResult:
    """The ``SimResult`` of a finished batch, whichever backend ran it."""
    delivered = (state.delivery_time >= 0).sum(axis=1)
    end = _run_ends(state)
    orders = (state.due <= end[:, None]).sum(axis=1)  # every carrier in the lab
    stuck = (
        (state.status == TagStatus.PICKED_UP)
        & (state.carried_by >= 0)
        & (
            np.take_along_axis(state.mode, np.maximum(state.carried_by, 0), axis=1)
            == int(Mode.BROKEN)
        )
    ).sum(axis=1)
    return SimResult(
        carriers=carrier_log(state, params, seed=seed),
        events=events.table(
            condition=params.condition,
            seed=seed,
            run_ids=state.run_ids,
            time_scale=params.time_scale,
            time_unit=params.scenario.time_unit,
        ),
        run_ids=state.run_ids.copy(),
        delivered=delivered.astype(np.int64),
        undelivered=(orders - delivered).astype(np.int64),
        stuck=stuck.astype(np.int64),
        breakdowns=breakdowns,
        end_tick=end,
        final_state=state,
        trajectories=None if recorder is None else recorder.finish(params, seed=seed, last=state),
    )


LOG_BYTES_PER_CARRIER: Final = 2200
"""Memory per carrier and run of logs kept until written: the carrier row (~120 B), its ~8
event rows (~1000 B) and the CSV text while writing (measured: docs/reliability.md)."""


def batch_memory(
    scenario: Scenario,
    runs: int,
    *,
    record: bool = False,
    backend: str = "reference",
    cache_capacity: int | None = None,
) -> float:
    """Estimated peak bytes of simulating ``runs`` runs of ``scenario`` in one batch.

    Reference: fitted to tracemalloc peaks (docs/reliability.md): the
    carrier-carrier line-of-sight tests (~650 B per pair), the robot-robot
    broad phase (~75-200 B per pair), robot-carrier distances, per-body
    state, the advertisement delay buffer and, when recording, every tick's
    poses. Fast: the state's robot-carrier arrays (42 B per pair) and the
    kernel's (24 B, 48 more with advertisement loss or camera noise), or
    with sparse tag caches 34 B per entry (``cache_capacity`` of them per
    robot, by default the first capacity the kernel tries), the start
    state's free-face test (~400 B per carrier pair, or ~1.8 kB per carrier
    with its grid, measured), per-body state, grids and event buffers
    (docs/performance.md measures it).
    """
    robots, carriers = scenario.robots, scenario.carriers
    if backend == "fast":
        realism = scenario.realism
        if sparse_tag_cache(scenario):
            entries = FIRST_CACHE_CAPACITY if cache_capacity is None else cache_capacity
            caches = 34.0 * robots * entries
        else:
            pair = 66.0 + (48.0 if realism.advertisement_loss or realism.detection_noise else 0.0)
            pair += 8.0 if scenario.camera.fade else 0.0  # this tick's sight draws
            caches = pair * robots * carriers
        free = (  # the start state's free faces: a grid from a few dozen carriers on
            2000.0 * carriers if grid_pays("free", 4 * carriers, carriers) else 400.0 * carriers**2
        )
        per_run = (
            caches
            + free
            + 1000.0 * robots
            + 600.0 * carriers
            + 24.0 * (realism.status_delay + 1) * carriers
        )
        if record:
            per_run += 48.0 * scenario.run_ticks * (robots + carriers)
        return runs * per_run
    per_run = (
        700.0 * carriers**2
        + 100.0 * robots**2
        + 64.0 * robots * carriers
        + 2000.0 * (robots + carriers)
        + 24.0 * (scenario.realism.status_delay + 1) * carriers
    )
    if record:
        per_run += 48.0 * scenario.run_ticks * (robots + carriers)
    return runs * per_run


def seeded_state(
    params: Params, *, seed: int, runs: int, run_offset: int = 0, backend: str = "reference"
) -> WorldState:
    """The start state of global runs ``run_offset .. run_offset + runs - 1`` of ``seed``.

    ``backend="fast"`` samples the scenes with the compiled sampler (the same scenes);
    warehouse scenes come from the reference sampler for both backends.
    """
    seed = check_seed(seed)
    runs = check_int("runs", runs, low=1, high=MAX_RUN_INDEX)
    run_offset = check_int("run_offset", run_offset, low=0, high=MAX_RUN_INDEX - runs)
    run_ids = np.arange(run_offset, run_offset + runs, dtype=np.int64)
    if backend == "fast" and params.floor is None:
        from swarmtag.sim.fast import seeded_scenes  # noqa: PLC0415 - numba is an extra

        scenes = seeded_scenes(params, seed=seed, run_ids=run_ids.tolist())
    else:
        scenes = [sample_scene(params, seed=seed, run=int(run)) for run in run_ids]
    sparse = backend == "fast" and params.sparse_tag_cache
    return initial_state(params, scenes, run_ids, dense_caches=not sparse)
