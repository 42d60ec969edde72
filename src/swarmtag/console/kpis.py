"""The KPIs of an event log so far (SPEC §5), as the console shows them.

One function for every source that has an event log: the live simulation
(its runs so far) and a replay (its runs up to the time shown). Times come
out in seconds: a log in ticks is scaled by ``tick_seconds``.
"""

from __future__ import annotations

from typing import Any

from swarmtag.io import CarrierLog

__all__ = ["log_kpis"]


def log_kpis(log: CarrierLog, condition: str, tick_seconds: float) -> dict[str, Any]:
    """Deliveries, P95 and mean latency (s), PA, throughput (per 100 s) of ``condition``'s runs."""
    from swarmtag.analysis.kpis import condition_kpis, run_values  # noqa: PLC0415 - heavy
    from swarmtag.analysis.runs import ConditionRuns  # noqa: PLC0415 - heavy

    k = condition_kpis(run_values(ConditionRuns.from_log(log, condition)))
    scale = tick_seconds if log.time_unit == "tick" else 1.0

    def seconds(value: float | None) -> float | None:
        return None if value is None else round(value * scale, 3)

    return {
        "kind": "deliveries",
        "condition": k.condition,
        "runs": k.runs,
        "deliveries": k.total_deliveries,
        "waiting": k.undelivered,
        "p95_latency": seconds(k.p95_latency),
        "mean_latency": seconds(k.mean_latency),
        "pa": round(k.pa, 4),
        "throughput": None if k.throughput is None else round(k.throughput / scale, 3),
        "units": {"latency": "s", "throughput": "deliveries per 100 s"},
    }
