"""The compiled backend's driver: seeded runs through ``advance``, results as the reference's.

``simulate_fast`` takes the same start state and master seed as the
reference ``run_batch`` with a ``RandomSource`` and gives the same results:
the kernel draws from each run's own streams, the walk turns and RSSI
factors are drawn here (``randomness.walk_turns``, ``rssi_factors``),
operator writes are applied between kernel calls with
``wms.operator_writes`` (the kernel stops every run at each tick
that has writes), and events come out of the kernel's per-run buffers into
the same ``EventRecorder``. Groups of runs go to a pool of threads (the
kernel holds no GIL). Kernel calls are bounded in work, so Ctrl-C is seen
between them; a recorded (or checked) batch steps one tick per call so that
each tick can be looked at.
"""

from __future__ import annotations

from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, Final

import numpy as np

from swarmtag._interrupt import checkpoint
from swarmtag._threads import default_threads
from swarmtag.errors import SimulationError
from swarmtag.io import MISSING_ID
from swarmtag.sim.fast._docking import FAILURE_LOWERED, FAILURE_NOT_PICKED_UP
from swarmtag.sim.fast._draws import STREAMS
from swarmtag.sim.fast._layout import (
    Constants,
    World,
    cache_bound,
    cache_capacity_for,
    constants_of,
    state_of,
    world_of,
)
from swarmtag.sim.fast._pcg import STATE_WORDS, states_of
from swarmtag.sim.fast._scratch import EVENT_SLOTS, Scratch, scratch_for
from swarmtag.sim.fast._split import (
    SYNC_DRAWN,
    SYNC_INDEXED,
    split_sync,
    split_ticks,
    thread_scratch,
)
from swarmtag.sim.fast._sync import SYNC_ABORT
from swarmtag.sim.fast._tag_cache import FAILURE_CACHE_FULL
from swarmtag.sim.fast._tick import advance
from swarmtag.sim.model.events import EventKind, EventRecorder, RobotEvents, TickEvents
from swarmtag.sim.model.invariants import check_tick
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import (
    Stream,
    check_seed,
    due_writes,
    rssi_factors,
    rssi_on,
    stream,
    walk_drawn,
    walk_turns,
)
from swarmtag.sim.model.state import WorldState
from swarmtag.sim.outputs.trajectories import TrajectoryRecorder
from swarmtag.sim.world.wms import operator_writes

__all__ = ["TagCacheFull", "kernel_compiled", "simulate_fast"]

_WORK_PER_CALL: Final = 1_000_000
"""Robot-ticks per kernel call at most (0.1-0.25 s; at least a tick): bounds Ctrl-C latency."""
_MAX_TICKS_PER_CALL: Final = 4096
_GROUPS_PER_THREAD: Final = 4
"""Runs go to the threads in this many groups per thread (runs end at different ticks)."""
SPLIT_FROM: Final = 10_000
"""Robots of a run from which a batch of fewer runs than threads splits each tick's robots."""


class TagCacheFull(Exception):
    """A robot's sparse tag cache overflowed: the batch must start again with ``capacity``."""

    def __init__(self, capacity: int) -> None:
        super().__init__(f"a sparse tag cache needs {capacity} entries")
        self.capacity = capacity


def kernel_compiled() -> bool:
    """Whether this machine has the kernel's machine code cached (else the next run compiles).

    Reads numba's cache index of the kernel's entry point (its stamp must
    match the source); if that cannot be read, says True (no warning).
    """
    try:
        cache: Any = getattr(advance, "_cache", None)
        return bool(cache._cache_file._load_index())
    except Exception:  # noqa: BLE001 - numba's cache internals: any failure means "unknown"
        return True


def _capacity(robots: int, slots: int) -> int:
    """Rows of each run's event buffer (a run pauses when a tick could overflow it).

    A tick makes at most ``EVENT_SLOTS`` rows per robot and one arrival per pick-up slot.
    """
    return max(256, 4 * EVENT_SLOTS * (robots + slots))


class _Streams:
    """Each run's generators of the kernel's streams, and of the numbers drawn outside it."""

    def __init__(self, params: Params, seed: int, run_ids: list[int]) -> None:
        on = {
            Stream.MOTION: True,
            Stream.BREAKDOWN: params.breakdown > 0,
            Stream.RADIO: params.advertisement_loss > 0,
            Stream.CAMERA: params.detection_noise > 0,
            Stream.SIGHT: params.camera_fade > 0,
        }
        self.states = np.zeros((len(run_ids), len(STREAMS), STATE_WORDS), dtype=np.uint64)
        """(runs, streams, words): the kernel's generator states (``_pcg``), advanced in place."""
        for row, purpose in enumerate(STREAMS):
            if on[purpose]:  # a stream that is off is never drawn from
                generators = [stream(seed, run, purpose) for run in run_ids]
                self.states[:, row] = states_of(generators)
        self._walk = (
            [stream(seed, run, Stream.WALK) for run in run_ids] if walk_drawn(params) else None
        )
        self._rssi = (
            [stream(seed, run, Stream.RSSI) for run in run_ids] if rssi_on(params) else None
        )
        self._odometry = (
            [stream(seed, run, Stream.ODOMETRY) for run in run_ids]
            if params.odometry_drift > 0
            else None
        )
        self._params = params
        self._runs = len(run_ids)

    @property
    def columns(self) -> int:
        """Numbers per robot and tick that ``outside`` holds (its last axis)."""
        return 4 + (self._params.carriers if self._rssi is not None else 0)

    def outside(self, ticks: int) -> np.ndarray:
        """The next ``ticks`` ticks' numbers drawn outside the kernel (``_tick.outside_row``).

        Shape (runs, ticks, robots, columns): each robot's walk turn
        ``(cos, sin)``, its odometry numbers, then its RSSI error factor per
        carrier; one row of zeros when there are none.
        """
        robots = self._params.robots
        if self._walk is None and self._rssi is None and self._odometry is None:
            return np.zeros((self._runs, 1, robots, 4))
        numbers = np.zeros((self._runs, ticks, robots, self.columns))
        if self._walk is not None:
            uniform = np.stack([g.random((ticks, robots)) for g in self._walk])
            numbers[..., 0:2] = walk_turns(uniform, self._params)
        if self._odometry is not None:
            numbers[..., 2:4] = np.stack(
                [g.standard_normal((ticks, robots, 2)) for g in self._odometry]
            )
        if self._rssi is not None:
            shape = (ticks, robots, self._params.carriers)
            gaussians = np.stack([g.standard_normal(shape) for g in self._rssi])
            numbers[..., 4:] = rssi_factors(gaussians, self._params)
        return numbers


def _flush(x: Scratch, recorder: EventRecorder, breakdowns: np.ndarray) -> None:
    """Move the kernel's buffered events into ``recorder`` and empty the buffers."""
    counts = x.event_count
    if not counts.any():
        return
    # each run's first rows, run by run: O(events), however large the buffers
    runs = np.repeat(np.arange(counts.shape[0]), counts)
    rows = np.arange(runs.shape[0]) - np.repeat(np.cumsum(counts) - counts, counts)
    kinds = x.event_kind[runs, rows].astype(np.int64)
    recorder.add_rows(
        runs,
        x.event_tick[runs, rows],
        kinds,
        carriers=x.event_carrier[runs, rows],
        robots=x.event_robot[runs, rows],
        values=x.event_value[runs, rows],
    )
    breakdowns += np.bincount(runs[kinds == EventKind.BREAKDOWN], minlength=breakdowns.shape[0])
    counts[:] = 0


def _tick_events(x: Scratch, shape: tuple[int, int]) -> TickEvents:
    """The buffered events of one tick as ``TickEvents`` (checking mode)."""
    result = TickEvents()
    for kind in range(1, EVENT_SLOTS + 1):
        mask = np.zeros(shape, dtype=bool)
        carrier = np.full(shape, -1, dtype=np.int64)
        value = np.full(shape, np.nan)
        for run in range(shape[0]):
            for row in range(int(x.event_count[run])):
                if x.event_kind[run, row] == kind:
                    robot = int(x.event_robot[run, row])
                    mask[run, robot] = True
                    carrier[run, robot] = x.event_carrier[run, row]
                    value[run, robot] = x.event_value[run, row]
        if mask.any():
            result.entries.append(RobotEvents(EventKind(kind), mask, carrier, value))
    return result


def _raise_failure(x: Scratch, world: World, k: Constants, bound: int) -> None:
    """A ``SimulationError`` for a run in which the kernel refused a release.

    ``TagCacheFull`` where a sparse tag cache overflowed instead (twice the room,
    at most ``bound``).
    """
    failed = np.flatnonzero(x.failure)
    if failed.size == 0:
        return
    if (x.failure == FAILURE_CACHE_FULL).any():
        if k.cache_capacity >= bound:  # never: at most a carrier per place and the target stay
            msg = f"a tag cache of {k.cache_capacity} entries overflowed (bound {bound})"
            raise SimulationError(msg)
        raise TagCacheFull(min(2 * k.cache_capacity, bound))
    row = int(failed[0])
    tick = int(world.run_tick[row]) + 1
    if x.failure[row] == FAILURE_NOT_PICKED_UP:
        msg = f"tick {tick}: a robot released a carrier whose tag is not PICKED_UP"
    else:
        assert x.failure[row] == FAILURE_LOWERED
        msg = (
            f"tick {tick}: a robot lowered a carrier it does not hold, or outside the "
            "drop-off area (the model delivers only into the drop-off area)"
        )
    raise SimulationError(msg)


class _Batch:
    """One seeded batch in the compiled kernel: its arrays, streams, events and threads."""

    def __init__(
        self,
        state: WorldState,
        params: Params,
        seed: int,
        threads: int,
        *,
        adopt: bool,
        cache_capacity: int,
    ) -> None:
        runs, robots = state.runs, params.robots
        self.template = state
        self.params = params
        self.world = world_of(state, copy=not adopt, cache_capacity=cache_capacity)
        self.constants = constants_of(params, cache_capacity)
        k = self.constants
        self.scratch = scratch_for(runs, k, _capacity(robots, k.pickup_slots.shape[0]))
        self.streams = _Streams(params, seed, [int(run) for run in state.run_ids])
        self.events = EventRecorder()
        self.breakdowns = np.zeros(runs, dtype=np.int64)
        # fewer runs than threads, many robots: each tick's robots are split over the threads
        self.split = threads > runs and robots >= SPLIT_FROM
        self.thread_scratch = [self.scratch]
        self.drawn = np.full(runs, -1, dtype=np.int64)
        """Split runs: the tick whose random numbers the buffers hold (``_split_run``)."""
        self.indexed = np.full(runs, -1, dtype=np.int64)
        """Split runs: the tick whose robots' index the scratch holds (``_split_run``)."""
        if self.split:
            self.thread_scratch += [thread_scratch(self.scratch) for _ in range(threads - 1)]
        else:
            threads = max(1, min(threads, runs))
        count = min(runs, threads * _GROUPS_PER_THREAD) if threads > 1 else 1
        # contiguous blocks of runs: a thread's runs share cache lines with few of another's
        self.groups = [block.astype(np.int64) for block in np.array_split(np.arange(runs), count)]
        self.pool = ThreadPoolExecutor(threads) if threads > 1 else None

    def close(self) -> None:
        """Stop the threads (each finishes its bounded kernel call)."""
        if self.pool is not None:
            self.pool.shutdown()

    def _kernel(self, rows: np.ndarray, stop: int, outside: np.ndarray, first: int) -> None:
        s = self.streams
        advance(
            rows,
            stop,
            outside,
            first,
            s.states,
            self.world,
            self.constants,
            self.scratch,
        )

    def _split_run(self, r: int, stop: int, outside: np.ndarray, first: int) -> None:
        """Run ``r`` tick by tick to ``stop``, its end, or a full event buffer (``_split``).

        Every thread runs ``split_ticks`` at once, this one part 0. If this
        thread cannot run its part (Ctrl-C before the call), the others are
        told (``SYNC_ABORT``) and return at their next barrier. ``self.drawn[r]``
        is the tick whose random numbers the buffers hold, ``self.indexed[r]`` the
        tick whose robots' index the scratch holds, both kept when the run pauses.
        """
        assert self.pool is not None
        s = self.streams
        parts = len(self.thread_scratch)
        sync = split_sync(int(self.drawn[r]), int(self.indexed[r]))
        calls = [
            (
                part,
                parts,
                r,
                stop,
                outside,
                first,
                s.states,
                sync,
                self.world,
                self.constants,
                scratch,
            )
            for part, scratch in enumerate(self.thread_scratch)
        ]
        futures: list[Future[None]] = []
        try:
            futures.extend(self.pool.submit(split_ticks, *arguments) for arguments in calls[1:])
            split_ticks(*calls[0])
        except BaseException:
            sync[SYNC_ABORT] = 1
            raise
        finally:
            for future in futures:
                future.result()
        self.drawn[r] = sync[SYNC_DRAWN]
        self.indexed[r] = sync[SYNC_INDEXED]

    def advance_to(self, stop: int, outside: np.ndarray, first: int) -> None:
        """Every running run to tick ``stop`` (empties buffers a run filled on the way)."""
        world = self.world
        while True:
            if self.split:
                for r in range(world.run_tick.shape[0]):
                    self._split_run(r, stop, outside, first)
            elif self.pool is None:
                self._kernel(self.groups[0], stop, outside, first)
            else:
                futures = [
                    self.pool.submit(self._kernel, rows, stop, outside, first)
                    for rows in self.groups
                ]
                for future in futures:
                    future.result()
            _raise_failure(self.scratch, world, self.constants, cache_bound(self.params))
            if not ((world.ended_at < 0) & (world.run_tick < stop)).any():
                return
            self.flush()  # a run paused with a full event buffer

    def flush(self) -> None:
        """Move buffered events into the recorder."""
        _flush(self.scratch, self.events, self.breakdowns)

    def state(self) -> WorldState:
        """The batch's arrays as a ``WorldState`` (no copy)."""
        return state_of(self.world, self.template)

    def write(self, t: int, tick_events: TickEvents | None) -> None:
        """Apply the operator writes due at tick ``t`` (every running run is at ``t``)."""
        writes = due_writes(self.params, t)
        if not writes:
            return
        done = TickEvents()
        operator_writes(self.state(), writes, t=t, events=done)
        for event in done.carrier_entries:
            self.events.add_rows(
                np.array([event.run]),
                np.array([t]),
                np.array([int(event.kind)]),
                carriers=np.array([event.carrier]),
                robots=np.array([MISSING_ID]),
                values=np.array([event.value]),
            )
        if tick_events is not None:
            tick_events.carrier_entries.extend(done.carrier_entries)


def simulate_fast(
    state: WorldState,
    params: Params,
    *,
    seed: int,
    ticks: int | None = None,
    record: bool = False,
    check: bool = False,
    threads: int | None = None,
    adopt: bool = False,
    cache_capacity: int | None = None,
) -> tuple[WorldState, EventRecorder, np.ndarray, TrajectoryRecorder | None]:
    """Run the seeded batch ``state`` with the compiled kernel on ``threads`` threads.

    Returns the final state, the events, the breakdowns per run and, with
    ``record``, the trajectories recorded tick by tick (as ``run_batch``).
    ``adopt``: step ``state``'s own arrays instead of a copy (the caller
    gives it up; large swarms need the memory). ``cache_capacity``: entries
    of a sparse tag cache (``_tag_cache``; default ``cache_capacity_for``);
    raises ``TagCacheFull`` if that is too few (start again with more).
    """
    seed = check_seed(seed)
    start = state.tick
    end = params.run_ticks if ticks is None else start + ticks
    batch = _Batch(
        state,
        params,
        seed,
        default_threads() if threads is None else threads,
        adopt=adopt,
        cache_capacity=cache_capacity_for(params) if cache_capacity is None else cache_capacity,
    )
    trajectories = TrajectoryRecorder(state, end - start) if record else None
    write_ticks = sorted({w.tick for w in params.scenario.reprioritisations})
    stepwise = record or check
    per_call = max(
        1,
        min(
            _MAX_TICKS_PER_CALL,
            _WORK_PER_CALL // max(1, state.runs * params.robots * (batch.streams.columns - 1)),
        ),
    )
    position = start
    current = state
    # The batch's arrays as a state, made once: the kernel writes them in place, so this
    # view shows every tick (all but its ``tick``, which recording does not read).
    view = batch.state() if trajectories is not None else None
    try:
        while position < end and (batch.world.ended_at < 0).any():
            checkpoint()  # Ctrl-C between kernel calls
            stop = min(end, position + (1 if stepwise else per_call))
            stop = min([stop, *(t for t in write_ticks if t > position)])
            before = current.copy() if check else None
            batch.advance_to(stop, batch.streams.outside(stop - position), position + 1)
            tick_events = (
                _tick_events(batch.scratch, (state.runs, params.robots)) if check else None
            )
            batch.write(stop, tick_events)
            batch.flush()
            if before is not None and tick_events is not None:
                current = batch.state()
                check_tick(before, current, tick_events, params)
            if trajectories is not None and view is not None:
                trajectories.add(view)
            position = stop
    finally:
        batch.close()
    if position != start:
        current = batch.state()
    return current, batch.events, batch.breakdowns, trajectories
