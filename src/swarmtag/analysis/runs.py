"""One condition's carriers grouped by run: the input of every KPI and of the bootstrap.

Runs are ordered by their run id; ``run_index`` says which run each carrier
row belongs to. Row order inside the log does not matter anywhere downstream.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import check_instance, check_text
from swarmtag.errors import StatisticsError
from swarmtag.io.tables import CarrierLog

__all__ = ["ConditionRuns", "split_conditions"]


_T = TypeVar("_T", bound=np.generic)


def _frozen(array: NDArray[_T]) -> NDArray[_T]:
    array = np.ascontiguousarray(array)
    array.flags.writeable = False
    return array


@dataclass(frozen=True, eq=False)
class ConditionRuns:
    """The carrier rows of one condition, with the run each belongs to.

    >>> nan = float("nan")
    >>> log = CarrierLog(condition=["proximity"] * 3, run=[5, 2, 5], seed=[0] * 3,
    ...     carrier=[1, 1, 2], urgency0=[9, 0, 4], order_time=[-10.0, -5.0, -1.0],
    ...     pickup_time=[1.0, nan, 2.0], delivery_time=[8.0, nan, 9.0], robot=[0, -1, 1])
    >>> runs = ConditionRuns.from_log(log, "proximity")
    >>> runs.run_ids, runs.run_index
    (array([2, 5]), array([1, 0, 1]))
    """

    condition: str
    run_ids: NDArray[np.int64]
    """Run ids present, ascending: per-run arrays follow this order."""
    run_index: NDArray[np.intp]
    """For each carrier row, the position of its run in ``run_ids``."""
    carrier: NDArray[np.int64]
    urgency0: NDArray[np.int64]
    order_time: NDArray[np.float64]
    delivery_time: NDArray[np.float64]
    """NaN for carriers never delivered."""
    pickup_time: NDArray[np.float64]
    """NaN for carriers never picked up."""
    run_end: NDArray[np.float64]
    """The log's ``run_end`` of each row's run; NaN where the log has none."""
    urgency_end: NDArray[np.int64]
    """The log's ``urgency_end``; ``MISSING_ID`` (-1) where the log has none."""

    @classmethod
    def from_log(cls, log: CarrierLog, condition: str) -> ConditionRuns:
        """The rows of ``condition`` in ``log``; an error if there are none."""
        check_instance("log", log, CarrierLog, error=StatisticsError)
        check_text("condition", condition, error=StatisticsError)
        rows = np.flatnonzero(log.condition == condition)
        if rows.size == 0:
            raise StatisticsError(
                f"the log has no rows for condition {condition!r}; "
                f"it has {', '.join(log.conditions) or 'none'}"
            )
        run_ids, run_index = np.unique(log.run[rows], return_inverse=True)
        return cls(
            condition=condition,
            run_ids=_frozen(run_ids),
            run_index=_frozen(run_index.astype(np.intp)),
            carrier=_frozen(log.carrier[rows]),
            urgency0=_frozen(log.urgency0[rows]),
            order_time=_frozen(log.order_time[rows]),
            delivery_time=_frozen(log.delivery_time[rows]),
            pickup_time=_frozen(log.pickup_time[rows]),
            run_end=_frozen(log.run_end[rows]),
            urgency_end=_frozen(log.urgency_end[rows]),
        )

    @property
    def n_runs(self) -> int:
        """Number of runs of the condition."""
        return len(self.run_ids)

    @property
    def delivered(self) -> NDArray[np.bool_]:
        """Which carrier rows were delivered."""
        return ~np.isnan(self.delivery_time)

    def carriers_per_run(self) -> NDArray[np.int64]:
        """Rows (carriers, delivered or not) in each run."""
        return np.bincount(self.run_index, minlength=self.n_runs).astype(np.int64)

    def run_starts(self) -> NDArray[np.int64]:
        """Where each run's block starts once rows are sorted by run."""
        counts = self.carriers_per_run()
        return (np.cumsum(counts) - counts).astype(np.int64)


def split_conditions(log: CarrierLog) -> dict[str, ConditionRuns]:
    """Every condition of the log, in sorted order of their names."""
    check_instance("log", log, CarrierLog, error=StatisticsError)
    return {name: ConditionRuns.from_log(log, name) for name in log.conditions}
