"""Priority alignment PA(p) (SPEC §5): how far the most urgent carriers were delivered first.

For a run of ``n`` carriers and an integer threshold ``p`` percent,
``k = max(1, ceil(p * n / 100))`` in exact integer arithmetic. The top-k are
the k carriers most urgent at run start (ties: earlier order time, then
smaller marker id); the first-k are the first k delivered (by delivery time,
ties by marker id; fewer than k if fewer were delivered).
``PA(p) = |top-k ∩ first-k| / k``. PA (5-50 %) is the mean of PA(p) over
p = 5, 10, ..., 50 in each run, then the mean over runs. PA at delivery, a
comparison aid, is the same with the urgency when delivered (``urgency_end``)
in place of the urgency at run start.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from swarmtag._checks import check_array, check_instance, show
from swarmtag.analysis._validation import check_thresholds
from swarmtag.analysis.runs import ConditionRuns
from swarmtag.errors import StatisticsError

__all__ = [
    "CURVE_THRESHOLDS",
    "PA_THRESHOLDS",
    "alignment_k",
    "priority_alignment",
    "within_run_ranks",
]

PA_THRESHOLDS: Final = tuple(range(5, 51, 5))
"""The thresholds (percent) averaged into PA (5-50 %)."""
CURVE_THRESHOLDS: Final = tuple(range(5, 101, 5))
"""The thresholds (percent) of the PA curve."""


def alignment_k(p: int, n: ArrayLike) -> NDArray[np.int64]:
    """``k = max(1, ceil(p * n / 100))`` in exact integer arithmetic.

    Floating point can land just above an integer: ``35 * 0.01 * 20`` is
    ``7.000000000000001``, whose ceiling is 8; exactly, 35 % of 20 is 7.

    >>> alignment_k(35, [20, 7, 1])
    array([7, 3, 1])
    """
    if isinstance(p, bool) or not isinstance(p, int | np.integer) or not 0 <= p <= 100:
        raise StatisticsError(f"PA threshold {show(p)} is not an integer percentage in 0-100")
    counts: NDArray[np.int64] = check_array("n", n, integer=True, low=0, error=StatisticsError)
    return np.maximum(1, -((-int(p) * counts) // 100))


def within_run_ranks(
    runs: ConditionRuns, urgency: NDArray[np.int64] | None = None
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Each carrier's 0-based rank in its run by urgency and by delivery.

    Urgency rank: urgency (at run start unless ``urgency`` gives one per row)
    descending, then order time, then marker id. Delivery rank: delivery time
    ascending, then marker id; carriers never delivered rank after every
    delivered one.
    """
    n_rows = len(runs.run_index)
    starts = runs.run_starts()[runs.run_index]
    positions = np.arange(n_rows, dtype=np.int64)
    ranked = runs.urgency0 if urgency is None else urgency
    by_urgency = np.lexsort((runs.carrier, runs.order_time, -ranked, runs.run_index))
    urgency_rank = np.empty(n_rows, dtype=np.int64)
    urgency_rank[by_urgency] = positions - starts[by_urgency]
    delivery = np.where(runs.delivered, runs.delivery_time, np.inf)
    by_delivery = np.lexsort((runs.carrier, delivery, runs.run_index))
    delivery_rank = np.empty(n_rows, dtype=np.int64)
    delivery_rank[by_delivery] = positions - starts[by_delivery]
    return urgency_rank, delivery_rank


def priority_alignment(
    runs: ConditionRuns,
    thresholds: Sequence[int] = PA_THRESHOLDS,
    *,
    urgency: NDArray[np.int64] | None = None,
) -> NDArray[np.float64]:
    """PA(p) of every run (rows, in run-id order) at every threshold (columns).

    ``urgency`` (one per carrier row) ranks in place of ``urgency0``: PA at
    delivery passes ``runs.urgency_end``.

    >>> from swarmtag.io import CarrierLog
    >>> nan = float("nan")
    >>> log = CarrierLog(condition=["c"] * 4, run=[0] * 4, seed=[0] * 4, carrier=[1, 2, 3, 4],
    ...     urgency0=[9, 5, 5, 0], order_time=[-9.0, -5.0, -6.0, 0.0],
    ...     pickup_time=[1.0, 1.0, 1.0, nan], delivery_time=[30.0, 10.0, 20.0, nan],
    ...     robot=[0, 1, 2, -1])
    >>> priority_alignment(ConditionRuns.from_log(log, "c"), [25, 50, 75, 100])
    array([[0.  , 0.5 , 1.  , 0.75]])
    """
    check_instance("runs", runs, ConditionRuns, error=StatisticsError)
    thresholds = check_thresholds("thresholds", thresholds)
    if urgency is not None:
        urgency = check_array("urgency", urgency, integer=True, error=StatisticsError)
        if urgency.shape != runs.urgency0.shape:
            raise StatisticsError(
                f"urgency: {urgency.size} values for {runs.urgency0.size} carrier rows"
            )
    urgency_rank, delivery_rank = within_run_ranks(runs, urgency)
    per_run = runs.carriers_per_run()
    delivered = runs.delivered
    result = np.empty((runs.n_runs, len(thresholds)), dtype=np.float64)
    for column, p in enumerate(thresholds):
        k = alignment_k(p, per_run)
        k_of_row = k[runs.run_index]
        hit = (urgency_rank < k_of_row) & delivered & (delivery_rank < k_of_row)
        both = np.bincount(runs.run_index, weights=hit, minlength=runs.n_runs)
        result[:, column] = both / k
    return result
