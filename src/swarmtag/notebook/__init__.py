"""The notebook API (SPEC §8.5): several conditions in one call, results as DataFrames.

::

    import swarmtag

    result = swarmtag.simulate(profile="paper-sim", conditions=["proximity", "urgency:alpha=0.7"],
                               runs=10, seed=3, robots=3)
    result.kpis()        # one row per condition: pa, p95_latency, ... with _low/_high CIs
    result.compare()     # differences from the baseline with CIs and p-values
    result.events        # the event log (SPEC §8.1)
    result.plot_pa()     # PA curves with bands (matplotlib Axes)

``simulate`` is ``swarmtag simulate`` for a notebook: the same runs, the same
statistics (``swarmtag.analysis``), kept in a ``NotebookResult``. pandas
(the ``pandas`` extra) is imported when a DataFrame is first asked for,
matplotlib (the ``plot`` extra) when a plot is; see docs/notebook.md.
"""

from __future__ import annotations

from swarmtag.notebook._result import NotebookResult
from swarmtag.notebook._run import simulate

__all__ = ["NotebookResult", "simulate"]
