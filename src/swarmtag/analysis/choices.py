"""Choice statistics (SPEC §4.2a) from the long-format event table: how the robots chose.

Per run, and per condition over its runs:

- **selections**: ``select`` events;
- **candidates**: each ``candidates`` event (same run, tick and robot as a
  ``select``, ``carrier`` = the chosen one, ``value`` = how many candidates
  the robot chose among, an integer >= 1) gives its selection's count;
  shares of selections among 1, 2 and 3+ candidates and the mean count are
  over the selections that have one, and *unknown* (``None``) where none
  has (tables without ``candidates`` events), never zero;
- **double pursuits**: a ``select`` of carrier c by robot r at time t while
  another robot is already pursuing c. A robot pursues c from its ``select``
  of c until the first of its own next ``abandon``, ``timeout`` or
  ``breakdown`` (they happen before the selection phase of their tick, so
  they end a pursuit before a same-tick ``select``), ``lift`` or
  ``lift_refused`` (after the selection phase: a robot lifting c at tick t
  was still pursuing c at the selections of tick t), or its next ``select``.
  Selections are processed in (time, robot) order, so of k robots selecting
  an unpursued carrier in one tick, k - 1 are double pursuits;
- **timeouts**, **abandons** and **refused lifts** (``lift_refused``).

The per-run means of double pursuits, timeouts, abandons and refused lifts
get a bootstrap-over-runs interval from the same seeded generator as the
KPIs (``swarmtag.analysis.resampling``): the same resampled runs. They are
drawn in bounded chunks, and a request that cannot fit in memory is refused
before any is drawn.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import check_array, check_instance, check_sequence, check_text, show
from swarmtag._resources import check_memory
from swarmtag.analysis._validation import check_options
from swarmtag.analysis.bootstrap import Estimate, percentile_interval
from swarmtag.analysis.resampling import (
    bootstrap_memory,
    condition_generator,
    iter_multiplicities,
    one_blas_thread,
)
from swarmtag.analysis.summary import JsonValue
from swarmtag.errors import StatisticsError
from swarmtag.io.tables import CarrierLog, EventTable

__all__ = [
    "CHOICE_COUNTS",
    "ConditionChoices",
    "choice_statistics",
    "double_pursuits",
]

CHOICE_COUNTS: Final = ("double_pursuits", "timeouts", "abandons", "lift_refused")
"""The per-run counts whose means get a bootstrap interval, in output order."""
_PHASES: Final = {
    "breakdown": 0,
    "abandon": 0,
    "timeout": 0,
    "select": 1,
    "lift": 2,
    "lift_refused": 2,
}
"""Where in a tick each pursuit event happens: ends before selection (0), selection, ends after."""
_COUNTED: Final = {"timeouts": "timeout", "abandons": "abandon", "lift_refused": "lift_refused"}


def double_pursuits(
    run: NDArray[np.int64],
    time: NDArray[np.float64],
    kind: NDArray[np.str_],
    carrier: NDArray[np.int64],
    robot: NDArray[np.int64],
) -> NDArray[np.bool_]:
    """For each event, whether it is a ``select`` made while another robot pursued its carrier.

    Events may come in any order; ``run`` tells runs apart (see the module
    docstring for the definition).

    >>> kind = np.array(["select", "select", "lift", "select"])
    >>> double_pursuits(np.zeros(4, np.int64), np.array([1.0, 1.0, 1.0, 2.0]), kind,
    ...     np.array([5, 5, 5, 5]), np.array([0, 1, 0, 2]))
    array([False,  True, False,  True])
    """
    run, carrier, robot = (
        check_array(name, value, integer=True, error=StatisticsError)
        for name, value in (("run", run), ("carrier", carrier), ("robot", robot))
    )
    time = check_array("time", time, error=StatisticsError)
    kind = np.asarray(kind)
    if kind.ndim != 1 or kind.dtype.kind != "U":
        raise StatisticsError(f"kind: {show(kind)} is not a 1-D sequence of event kinds")
    if len({len(run), len(time), len(kind), len(carrier), len(robot)}) != 1:
        raise StatisticsError("run, time, kind, carrier and robot differ in length")
    rows = np.flatnonzero(np.isin(kind, list(_PHASES)))
    result = np.zeros(len(kind), dtype=bool)
    if rows.size == 0:
        return result
    phase = np.zeros(rows.size, dtype=np.int64)
    for label, number in _PHASES.items():
        phase[kind[rows] == label] = number
    run_of, robot_of, carrier_of = run[rows], robot[rows], carrier[rows]
    # Position of each event in (run, time, phase, robot) order: the order things happen.
    position = np.empty(rows.size, dtype=np.int64)
    position[np.lexsort((robot_of, phase, time[rows], run_of))] = np.arange(rows.size)
    # A pursuit ends at the robot's next pursuit event (an end, or its next select).
    own = np.lexsort((position, robot_of, run_of))
    follows = (run_of[own][1:] == run_of[own][:-1]) & (robot_of[own][1:] == robot_of[own][:-1])
    end = np.full(rows.size, rows.size, dtype=np.int64)  # never ended: past every event
    end[own[:-1][follows]] = position[own[1:][follows]]
    selects = np.flatnonzero(phase == 1)
    if selects.size == 0:
        return result
    pairs = np.column_stack([run_of[selects], carrier_of[selects]])
    group = np.unique(pairs, axis=0, return_inverse=True)[1].reshape(-1).astype(np.int64)
    stride = rows.size + 1
    base = group * stride
    starts = np.sort(base + position[selects])
    ends = np.sort(base + end[selects])
    at = base + position[selects]
    begun = np.searchsorted(starts, at, side="left") - np.searchsorted(starts, base, side="left")
    ended = np.searchsorted(ends, at, side="right") - np.searchsorted(ends, base, side="left")
    result[rows[selects]] = begun - ended > 0
    return result


@dataclass(frozen=True, eq=False)
class ConditionChoices:
    """One condition's choice statistics: per-run counts (following ``run_ids``) and summaries."""

    condition: str
    run_ids: NDArray[np.int64]
    selections: NDArray[np.int64]
    known: NDArray[np.int64]
    """Selections with a ``candidates`` count."""
    among: NDArray[np.int64]
    """``(runs, 3)``: selections among 1, 2 and 3+ candidates."""
    candidates_sum: NDArray[np.int64]
    """Sum of the known candidate counts."""
    double_pursuits: NDArray[np.int64]
    timeouts: NDArray[np.int64]
    abandons: NDArray[np.int64]
    lift_refused: NDArray[np.int64]
    per_run: dict[str, Estimate]
    """Mean per run with its bootstrap interval, for each of ``CHOICE_COUNTS``."""
    n_resamples: int
    seed: int
    confidence_level: float

    @property
    def n_runs(self) -> int:
        """Number of runs."""
        return len(self.run_ids)

    def total(self, name: str) -> int:
        """Total over runs of a count: ``selections``, ``known`` or one of ``CHOICE_COUNTS``."""
        counts: NDArray[np.int64] = getattr(self, name)
        return int(counts.sum())

    @property
    def shares(self) -> tuple[float, float, float] | None:
        """Shares of known selections among 1, 2 and 3+ candidates; ``None`` if none is known."""
        known = self.total("known")
        if known == 0:
            return None
        among = self.among.sum(axis=0)
        return (float(among[0] / known), float(among[1] / known), float(among[2] / known))

    @property
    def mean_candidates(self) -> float | None:
        """Mean number of candidates per known selection; ``None`` if none is known."""
        known = self.total("known")
        return float(self.candidates_sum.sum() / known) if known else None

    def run_shares(self) -> NDArray[np.float64]:
        """``(runs, 3)`` shares per run; NaN for a run without a known selection (unknown)."""
        shares = np.full(self.among.shape, np.nan)
        some = self.known > 0
        shares[some] = self.among[some] / self.known[some, None]
        return shares

    def to_json(self) -> dict[str, JsonValue]:
        """One object of the ``choices`` list (docs/metrics.md); ``null`` where unknown."""
        shares = self.shares
        entry: dict[str, JsonValue] = {
            "condition": self.condition,
            "runs": self.n_runs,
            "selections": self.total("selections"),
            "selections_with_candidates": self.total("known"),
            "share_1_candidate": None if shares is None else shares[0],
            "share_2_candidates": None if shares is None else shares[1],
            "share_3plus_candidates": None if shares is None else shares[2],
            "mean_candidates": self.mean_candidates,
        }
        for name in CHOICE_COUNTS:
            estimate = self.per_run[name]
            interval = estimate.confidence_interval
            entry[f"{name}_per_run"] = {
                "value": estimate.value,
                "ci": [interval.low, interval.high],
            }
            entry[name] = self.total(name)
        return entry


def _run_ids(
    events: EventTable, log: CarrierLog | None, names: Sequence[str]
) -> dict[str, NDArray[np.int64]]:
    """Each condition's runs: the log's if given (runs without events count), else the table's."""
    if log is None:
        return {name: np.unique(events.run[events.condition == name]) for name in names}
    if None not in (events.time_unit, log.time_unit) and events.time_unit != log.time_unit:
        msg = (
            f"the event table is in {events.time_unit!r} but the event log in "
            f"{log.time_unit!r}: they are not from the same runs"
        )
        raise StatisticsError(msg)
    result = {}
    for name in names:
        in_log = log.condition == name
        run_ids, first = np.unique(log.run[in_log], return_index=True)
        mine = np.flatnonzero(events.condition == name)
        if run_ids.size == 0:
            result[name] = run_ids  # refused by the caller: a condition without runs
            continue
        where = np.minimum(np.searchsorted(run_ids, events.run[mine]), run_ids.size - 1)
        unknown = run_ids[where] != events.run[mine]
        if unknown.any():
            row = int(mine[np.flatnonzero(unknown)[0]])
            msg = (
                f"event table row {row + 1}: run {int(events.run[row])} of {name} is not in "
                "the event log; are the two files from the same simulation?"
            )
            raise StatisticsError(msg)
        seeds = log.seed[in_log][first][where]
        other = np.flatnonzero(seeds != events.seed[mine])
        if other.size:
            row = int(mine[other[0]])
            msg = (
                f"event table row {row + 1}: seed {int(events.seed[row])} of run "
                f"{int(events.run[row])} of {name} differs from the event log's "
                f"{int(seeds[other[0]])}; are the two files from the same simulation?"
            )
            raise StatisticsError(msg)
        result[name] = run_ids
    return result


def _candidate_counts(
    events: EventTable, rows: NDArray[np.intp], position: NDArray[np.intp], n_runs: int
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Known selections, the (runs, 3) counts among 1/2/3+ and the candidate sums per run."""
    kind = events.kind[rows]
    pick = np.flatnonzero((kind == "select") | (kind == "candidates"))
    is_candidates = kind[pick] == "candidates"
    known = np.zeros(n_runs, dtype=np.int64)
    among = np.zeros((n_runs, 3), dtype=np.int64)
    sums = np.zeros(n_runs, dtype=np.int64)
    if not is_candidates.any():
        return known, among, sums
    taken = rows[pick]
    order = np.lexsort((is_candidates, events.robot[taken], events.time[taken], position[pick]))
    taken, is_candidates, runs = taken[order], is_candidates[order], position[pick][order]
    # In (run, time, robot) order a candidates event follows the select it belongs to.
    at = np.flatnonzero(is_candidates)
    before = np.maximum(at - 1, 0)
    row, prior = taken[at], taken[before]
    matched = (
        (at > 0)
        & ~is_candidates[before]
        & (runs[before] == runs[at])
        & (events.time[prior] == events.time[row])
        & (events.robot[prior] == events.robot[row])
        & (events.carrier[prior] == events.carrier[row])
    )
    value = events.value[row]
    integral = np.isfinite(value) & (value >= 1) & (value == np.round(value))
    for bad, problem in (
        (~matched, "a candidates event without a select of that carrier by that robot"),
        (~integral, "candidates value {value!r} is not an integer >= 1"),
    ):
        if bad.any():
            first = int(row[np.flatnonzero(bad)[0]])
            msg = (
                f"event table row {first + 1} ({events.condition[first]} run "
                f"{int(events.run[first])}, time {float(events.time[first])!r}, robot "
                f"{int(events.robot[first])}): " + problem.format(value=float(events.value[first]))
            )
            raise StatisticsError(msg)
    counts = value.astype(np.int64)
    run_of = runs[at]
    np.add.at(known, run_of, 1)
    np.add.at(among, (run_of, np.minimum(counts, 3) - 1), 1)
    np.add.at(sums, run_of, counts)
    return known, among, sums


def _condition(
    events: EventTable,
    name: str,
    run_ids: NDArray[np.int64],
    *,
    n_resamples: int,
    seed: int,
    confidence_level: float,
) -> ConditionChoices:
    rows = np.flatnonzero(events.condition == name)
    n_runs = run_ids.size
    position = np.searchsorted(run_ids, events.run[rows])
    kind = events.kind[rows]
    selects = kind == "select"
    bad = np.flatnonzero(selects & (events.carrier[rows] < 0))
    if bad.size:
        msg = f"event table row {int(rows[bad[0]]) + 1}: a select event names no carrier"
        raise StatisticsError(msg)
    bad = np.flatnonzero(np.isin(kind, list(_PHASES)) & (events.robot[rows] < 0))
    if bad.size:
        row = int(rows[bad[0]])
        msg = f"event table row {row + 1}: a {events.kind[row]} event names no robot"
        raise StatisticsError(msg)

    def per_run(mask: NDArray[np.bool_]) -> NDArray[np.int64]:
        return np.bincount(position[mask], minlength=n_runs).astype(np.int64)

    doubles = double_pursuits(
        position.astype(np.int64), events.time[rows], kind, events.carrier[rows], events.robot[rows]
    )
    counts = {"double_pursuits": per_run(doubles)}
    counts.update({count: per_run(kind == label) for count, label in _COUNTED.items()})
    known, among, sums = _candidate_counts(events, rows, position, n_runs)
    table = np.column_stack([counts[name] for name in CHOICE_COUNTS]).astype(np.float64)
    replicates = [np.empty(n_resamples) for _ in CHOICE_COUNTS]  # kept, never copied
    start = 0
    rng = condition_generator(seed, name)
    with one_blas_thread():  # products of chunks too small for BLAS threads
        for weights in iter_multiplicities(rng, n_runs, n_resamples, width=n_runs):
            stop = start + len(weights)
            means = weights @ table / n_runs
            for column, replicate in enumerate(replicates):
                replicate[start:stop] = means[:, column]
            start = stop
    estimates = {}
    for column, count in enumerate(CHOICE_COUNTS):
        values = replicates[column]
        values.flags.writeable = False
        estimates[count] = Estimate(
            value=float(table[:, column].mean()),
            confidence_interval=percentile_interval(values, confidence_level=confidence_level),
            bootstrap_distribution=values,
        )
    arrays = [run_ids, per_run(selects), known, among, sums, *counts.values()]
    for array in arrays:
        array.flags.writeable = False
    return ConditionChoices(
        condition=name,
        run_ids=run_ids,
        selections=arrays[1],
        known=known,
        among=among,
        candidates_sum=sums,
        double_pursuits=counts["double_pursuits"],
        timeouts=counts["timeouts"],
        abandons=counts["abandons"],
        lift_refused=counts["lift_refused"],
        per_run=estimates,
        n_resamples=n_resamples,
        seed=seed,
        confidence_level=confidence_level,
    )


def choice_statistics(
    events: EventTable,
    *,
    log: CarrierLog | None = None,
    conditions: Sequence[str] | None = None,
    n_resamples: int = 10_000,
    seed: int = 0,
    confidence_level: float = 0.95,
) -> tuple[ConditionChoices, ...]:
    """Choice statistics of every condition (see the module docstring for the definitions).

    With ``log`` (the carrier log of the same runs) a condition's runs are
    the log's, so runs without any event count, and an event of a run the
    log lacks is an error; without it, the runs are those with events.
    ``conditions`` gives the order (default: sorted; with ``log``, the log's
    conditions, else the table's).

    >>> table = EventTable(condition=["c"] * 4, seed=[0] * 4, run=[0, 0, 0, 0],
    ...     time=[3.0, 3.0, 3.0, 3.0], kind=["select", "candidates", "select", "candidates"],
    ...     carrier=[2, 2, 2, 2], robot=[0, 0, 1, 1], value=[9.0, 1.0, 9.0, 2.0])
    >>> (choices,) = choice_statistics(table, n_resamples=10)
    >>> choices.total("selections"), choices.shares, choices.total("double_pursuits")
    (2, (0.5, 0.5, 0.0), 1)
    """
    check_instance("events", events, EventTable, error=StatisticsError)
    if log is not None:
        check_instance("log", log, CarrierLog, error=StatisticsError)
    if conditions is not None:
        conditions = [
            check_text("conditions", name, error=StatisticsError)
            for name in check_sequence("conditions", conditions, error=StatisticsError)
        ]
    check_options(n_resamples=n_resamples, seed=seed, confidence_level=confidence_level)
    present = log.conditions if log is not None else tuple(np.unique(events.condition).tolist())
    names = list(present) if conditions is None else list(conditions)
    strays = sorted(set(events.condition.tolist()) - set(names))
    if strays:
        msg = (
            f"the event table has condition {strays[0]!r}, which is not among "
            f"{', '.join(names) or 'none'}"
        )
        raise StatisticsError(msg)
    run_ids = _run_ids(events, log, names)
    empty = [name for name in names if run_ids[name].size == 0]
    if empty:
        source = "the event table" if log is None else "the event log"
        msg = f"condition {empty[0]!r} has no runs in {source}"
        raise StatisticsError(msg)
    estimate = bootstrap_memory(
        n_resamples,
        conditions=len(names),
        width=max((run_ids[name].size for name in names), default=1),
        metrics=len(CHOICE_COUNTS),
        curve_points=0,
        comparisons=0,
    )
    plural = "" if len(names) == 1 else "s"
    check_memory(f"--resamples {n_resamples} over {len(names)} condition{plural}", estimate)
    return tuple(
        _condition(
            events,
            name,
            run_ids[name],
            n_resamples=n_resamples,
            seed=seed,
            confidence_level=confidence_level,
        )
        for name in names
    )
