"""The result of ``swarmtag.simulate``: the runs, their report, and DataFrame and plot views.

The object keeps what ``swarmtag simulate`` computes (the event logs and the
``MetricsReport``) and lays it out for a notebook on request: pandas on the
first DataFrame asked for, matplotlib on the first plot.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

from swarmtag._checks import show
from swarmtag.analysis import Comparison, MetricsReport, choose_baseline, compare_all
from swarmtag.errors import StatisticsError
from swarmtag.io import CarrierLog, EventTable
from swarmtag.sim import Scenario

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from pandas import DataFrame

__all__ = ["PANDAS_HINT", "NotebookResult", "check_baseline"]

PANDAS_HINT: Final = "the notebook API needs pandas: pip install 'swarmtag[pandas]'"
"""The refusal where pandas (the ``pandas`` extra) is missing."""

_PLOT_HINT: Final = "plots need matplotlib: pip install 'swarmtag[plot]'"


def check_baseline(conditions: Sequence[str], baseline: object) -> str:
    """``baseline`` if it is one of ``conditions``; ``None``: ``proximity``, else the first sorted.

    Refused in one short ``StatisticsError`` (a ``ValueError``) that lists the conditions.
    """
    if baseline is None:
        return choose_baseline(conditions)
    known = ", ".join(conditions)
    if not isinstance(baseline, str):
        kind = type(baseline).__name__
        msg = f"baseline: a condition is named by a str, not a {kind}; the conditions are {known}"
        raise StatisticsError(msg)
    if baseline not in conditions:
        msg = f"baseline {show(baseline)} is not one of the conditions: {known}"
        raise StatisticsError(msg)
    return baseline


def _new_axes() -> Axes:
    """Axes on a new figure of the user's matplotlib (inline in a notebook)."""
    try:
        import matplotlib.pyplot as plt  # noqa: PLC0415 - the plot extra, on first use
    except ImportError:  # pragma: no cover - the test environment has the extra
        raise ImportError(_PLOT_HINT) from None
    return plt.figure(figsize=(6.4, 4.2)).add_subplot()


@dataclass(frozen=True, eq=False, repr=False)
class NotebookResult:
    """Several conditions simulated on one scenario, with their statistics (SPEC §8.5).

    ``report`` is the ``swarmtag.analysis.MetricsReport`` (the numbers of
    ``swarmtag simulate --json``), ``log`` the per-carrier event log and
    ``table`` the long-format event table (``swarmtag.io``); ``kpis()``,
    ``compare()``, ``events`` and ``event_table`` give them as DataFrames.
    """

    report: MetricsReport
    log: CarrierLog
    table: EventTable
    scenario: Scenario
    profile: str
    """The name of the profile the scenario was built on."""
    conditions: tuple[str, ...]
    """The canonical condition names, in the order given (the DataFrames' order)."""
    runs: int
    seed: int
    run_offset: int

    def __repr__(self) -> str:
        return (
            f"NotebookResult(conditions={self.conditions!r}, runs={self.runs}, "
            f"run_offset={self.run_offset}, seed={self.seed}, profile={self.profile!r})"
        )

    def kpis(self) -> DataFrame:
        """One row per condition (index ``condition``): each KPI with ``_low``/``_high`` 95 % CI.

        Columns: ``runs``, ``p95_latency``, ``mean_latency``, ``throughput``,
        ``pa``, ``deliveries_per_run`` (each with its interval),
        ``total_deliveries``, ``undelivered``, then the censoring-aware
        latencies and ``pa_at_delivery`` (docs/metrics.md); NaN where a figure
        is undefined.
        """
        from swarmtag.notebook._frames import kpi_frame  # noqa: PLC0415 - pandas, on first use

        return kpi_frame(self.report, self.conditions)

    def compare(self, baseline: str | None = None) -> DataFrame:
        """Each other condition minus ``baseline``, one row per condition and metric.

        Columns: ``condition``, ``baseline``, ``metric``, ``diff``, ``ci_low``,
        ``ci_high``, ``p_bootstrap``, ``p_mannwhitney``, ``underpowered`` (fewer
        than 10 runs a side: read Mann-Whitney), ``smallest_p_mannwhitney``,
        ``undelivered_differs``. ``baseline``: default the report's
        (``proximity``, else the first in sorted order, or the one given to
        ``simulate``).
        """
        from swarmtag.notebook._frames import comparison_frame  # noqa: PLC0415 - pandas

        return comparison_frame(self.comparisons(baseline))

    def comparisons(self, baseline: str | None = None) -> tuple[Comparison, ...]:
        """The ``Comparison`` objects behind ``compare`` (with their bootstrap values)."""
        chosen = self.report.baseline if baseline is None else baseline
        chosen = check_baseline(self.conditions, chosen)
        if chosen == self.report.baseline:
            position = {name: i for i, name in enumerate(self.conditions)}
            return tuple(sorted(self.report.comparisons, key=lambda c: position[c.condition]))
        base = self.report.condition(chosen)
        return tuple(
            comparison
            for name in self.conditions
            if name != chosen
            for comparison in compare_all(self.report.condition(name), base)
        )

    @property
    def events(self) -> DataFrame:
        """The event log (SPEC §8.1), one row per carrier per run, as a new DataFrame."""
        from swarmtag.notebook._frames import table_frame  # noqa: PLC0415 - pandas

        return table_frame(self.log)

    @property
    def event_table(self) -> DataFrame:
        """The long-format event table (selections, lifts, ...), as a new DataFrame."""
        from swarmtag.notebook._frames import table_frame  # noqa: PLC0415 - pandas

        return table_frame(self.table)

    def plot_pa(self, ax: Axes | None = None) -> Axes:
        """PA(p) against the threshold p, one line and 95 % band per condition, on ``ax``."""
        return self._curves(ax, pa=True)

    def plot_latency(self, ax: Axes | None = None) -> Axes:
        """Pooled latency against the percentile, one line and 95 % band per condition."""
        return self._curves(ax, pa=False)

    def _curves(self, ax: Axes | None, *, pa: bool) -> Axes:
        from swarmtag.analysis.figures import draw_curves  # noqa: PLC0415 - beside matplotlib

        target = _new_axes() if ax is None else ax
        draw_curves(target, self.report, pa=pa)
        return target
