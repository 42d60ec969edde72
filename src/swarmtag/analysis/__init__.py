"""Metrics and statistics of SPEC §5: KPIs, bootstrap over runs, comparisons, curves.

Pure functions on in-memory event logs (``swarmtag.io.CarrierLog``): no
files, no global state. ``summarize`` does everything ``swarmtag metrics``
shows; the pieces are public for studies and reports:

- ``ConditionRuns`` groups one condition's rows by run;
- ``run_values`` / ``condition_kpis`` give per-run values and point figures;
- ``priority_alignment`` gives PA(p) per run, ``latency_by_urgency`` the
  latency per urgency level;
- ``choice_statistics`` gives the choice statistics of an event table
  (selections, candidates, double pursuits, timeouts, abandons);
- ``censored_latencies`` / ``km_quantile`` give the censoring-aware latency
  (undelivered carriers right-censored at run end) and its Kaplan-Meier P95;
- ``condition_statistics`` adds bootstrap intervals and the PA and latency
  curves with bands; ``compare`` / ``compare_all`` give differences with a
  bootstrap CI, the bootstrap p-value and Mann-Whitney U;
- ``trim_warmup`` keeps the orders placed after a warm-up: the KPIs of
  continuous (warehouse) operation are those of the trimmed log.
"""

from __future__ import annotations

from swarmtag.analysis.alignment import (
    CURVE_THRESHOLDS,
    PA_THRESHOLDS,
    alignment_k,
    priority_alignment,
)
from swarmtag.analysis.bootstrap import (
    ConditionStatistics,
    ConfidenceInterval,
    Estimate,
    condition_statistics,
    percentile_interval,
)
from swarmtag.analysis.censoring import (
    KM_TOLERANCE,
    CensoredLatencies,
    censored_latencies,
    km_quantile,
    run_ends,
)
from swarmtag.analysis.choices import (
    CHOICE_COUNTS,
    ConditionChoices,
    choice_statistics,
    double_pursuits,
)
from swarmtag.analysis.compare import (
    Comparison,
    bootstrap_p_value,
    compare,
    compare_all,
    mann_whitney_p,
    undelivered_differs,
)
from swarmtag.analysis.curves import LATENCY_PERCENTILES, Curve
from swarmtag.analysis.kpis import (
    CENSORED_METRICS,
    CORE_METRICS,
    METRICS,
    OPTIONAL_METRICS,
    ConditionKPIs,
    RunValues,
    condition_kpis,
    run_values,
)
from swarmtag.analysis.latency import UrgencyLatency, latency_by_urgency
from swarmtag.analysis.resampling import condition_seed_sequence
from swarmtag.analysis.runs import ConditionRuns, split_conditions
from swarmtag.analysis.summary import DEFAULT_BASELINE, MetricsReport, choose_baseline, summarize
from swarmtag.analysis.window import trim_warmup

__all__ = [
    "CENSORED_METRICS",
    "CHOICE_COUNTS",
    "CORE_METRICS",
    "CURVE_THRESHOLDS",
    "DEFAULT_BASELINE",
    "KM_TOLERANCE",
    "LATENCY_PERCENTILES",
    "METRICS",
    "OPTIONAL_METRICS",
    "PA_THRESHOLDS",
    "CensoredLatencies",
    "Comparison",
    "ConditionChoices",
    "ConditionKPIs",
    "ConditionRuns",
    "ConditionStatistics",
    "ConfidenceInterval",
    "Curve",
    "Estimate",
    "MetricsReport",
    "RunValues",
    "UrgencyLatency",
    "alignment_k",
    "bootstrap_p_value",
    "censored_latencies",
    "choice_statistics",
    "choose_baseline",
    "compare",
    "compare_all",
    "condition_kpis",
    "condition_seed_sequence",
    "condition_statistics",
    "double_pursuits",
    "km_quantile",
    "latency_by_urgency",
    "mann_whitney_p",
    "percentile_interval",
    "priority_alignment",
    "run_ends",
    "run_values",
    "split_conditions",
    "summarize",
    "trim_warmup",
    "undelivered_differs",
]
