"""The published 3/7 baseline against the idealised search-limited process.

Run: ``.venv/bin/python docs/calibration/constant_rate.py`` — every carrier is
found and delivered at a constant rate (exponential delivery times of mean
``m`` ticks, cut off at the 3000-tick run end), its waiting time at run
start is ``w0 ~ U[0, 3000]`` (the growing urgency model), and the KPIs of
SPEC §5 are computed exactly as ``swarmtag metrics`` does, with the
project's own functions, for 20,000 runs per mean. This is the process
whose delivered fractions match the published 5/10, 10/20 and 20/40
baselines (docs/calibration.md); it bounds what a model with the published
latencies can give as throughput.
"""

from __future__ import annotations

import numpy as np

from swarmtag.analysis.kpis import condition_kpis, run_values
from swarmtag.analysis.runs import ConditionRuns
from swarmtag.io import CarrierLog

RUNS, CARRIERS, T = 20_000, 7, 3000.0


def kpis(mean: float, seed: int = 0) -> tuple[float, float, float, float]:
    """P95, mean latency, throughput and delivered share of the constant-rate process."""
    rng = np.random.default_rng(seed)
    w0 = rng.random((RUNS, CARRIERS)) * T
    found = rng.exponential(mean, (RUNS, CARRIERS))
    delivered = found < T
    delivery = np.where(delivered, np.ceil(found), np.nan)
    rows = RUNS * CARRIERS
    log = CarrierLog(
        condition=np.full(rows, "constant-rate"),
        run=np.repeat(np.arange(RUNS), CARRIERS),
        seed=np.zeros(rows, dtype=np.int64),
        carrier=np.tile(np.arange(CARRIERS), RUNS),
        urgency0=np.minimum(9, np.floor(9 * w0 / T)).astype(np.int64).reshape(-1),
        order_time=-w0.reshape(-1),
        pickup_time=delivery.reshape(-1),
        delivery_time=delivery.reshape(-1),
        robot=np.where(delivered, 0, -1).reshape(-1),
        time_unit="tick",
    )
    k = condition_kpis(run_values(ConditionRuns.from_log(log, "constant-rate")))
    assert k.p95_latency is not None and k.mean_latency is not None and k.throughput is not None
    return k.p95_latency, k.mean_latency, k.throughput, float(delivered.mean())


def main() -> None:
    """A Markdown table over the mean time to delivery."""
    print("| mean time to delivery (ticks) | P95 | mean latency | throughput /100 | delivered |")
    print("|---|---|---|---|---|")
    for mean in (1500, 1800, 2100, 2400, 2700, 3000):
        p95, mean_latency, throughput, share = kpis(mean)
        print(f"| {mean} | {p95:.0f} | {mean_latency:.0f} | {throughput:.3f} | {share:.1%} |")
    print("| published 3/7 proximity | 4979 [4640, 5086] | 2638 [2531, 2738] | 0.266 [0.250, 0.285] | - |")


if __name__ == "__main__":
    main()
