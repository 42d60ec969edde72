"""Time the bootstrap statistics of `swarmtag metrics` (a plain script; prints timings).

Default: 10,000 resamples of 100 runs x 4 conditions x 7 carriers, the size of the paper's
controller-selection study; the timings go to ``benchmarks/results/`` (``_results.py``). Usage:

    .venv/bin/python benchmarks/bench_bootstrap.py [--runs 100] [--resamples 10000] [--repeat 5]
        [--out FILE.json]
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np
from _results import Record, begin

from swarmtag.analysis import ConditionRuns, condition_kpis, run_values, summarize
from swarmtag.io import CarrierLog

CONDITIONS = ("proximity", "urgency:alpha=0.7", "urgency:alpha=3.0", "urgency:alpha=9.0")


def synthetic_log(runs: int, carriers: int, seed: int = 0) -> CarrierLog:
    """A simulated-looking log: 3000-tick runs, growing urgency, about 10 % undelivered."""
    rng = np.random.default_rng(seed)
    rows = len(CONDITIONS) * runs * carriers
    delivered = rng.random(rows) < 0.9
    delivery = np.where(delivered, rng.integers(1, 3001, rows).astype(float), np.nan)
    pickup = np.where(delivered, np.maximum(0.0, delivery - rng.integers(20, 200, rows)), np.nan)
    return CarrierLog(
        condition=np.repeat(CONDITIONS, runs * carriers),
        run=np.tile(np.repeat(np.arange(runs), carriers), len(CONDITIONS)),
        seed=np.zeros(rows, dtype=np.int64),
        carrier=np.tile(np.arange(carriers), runs * len(CONDITIONS)),
        urgency0=rng.integers(0, 10, rows),
        order_time=-rng.integers(0, 3000, rows).astype(float),
        pickup_time=pickup,
        delivery_time=delivery,
        robot=np.where(delivered, rng.integers(0, 3, rows), -1),
        time_unit="tick",
    )


def timed(record: Record, label: str, repeat: int, action) -> None:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    best, median = min(times), statistics.median(times)
    print(f"{label:<58} min {best:7.3f} s   median {median:7.3f} s")
    record.row(workload=label.strip(), repeat=repeat, min_s=best, median_s=median)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--carriers", type=int, default=7)
    parser.add_argument("--resamples", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=5)
    args, record = begin(parser, __file__)
    log = synthetic_log(args.runs, args.carriers)
    size = f"{args.runs} runs x {len(CONDITIONS)} conditions x {args.carriers} carriers"
    timed(
        record,
        f"summarize: {args.resamples} resamples, {size}",
        args.repeat,
        lambda: summarize(log, n_resamples=args.resamples),
    )
    timed(
        record,
        "  of which KPIs only (4 conditions, no bootstrap)",
        args.repeat,
        lambda: [condition_kpis(run_values(ConditionRuns.from_log(log, c))) for c in CONDITIONS],
    )
    big_runs = 100_000
    big = synthetic_log(big_runs, args.carriers)
    one = ConditionRuns.from_log(big, CONDITIONS[0])
    timed(
        record,
        f"KPIs of one condition of {big_runs} runs x {args.carriers} carriers",
        max(1, args.repeat // 2),
        lambda: condition_kpis(run_values(one)),
    )
    timed(
        record,
        f"summarize: 200 resamples, {big_runs} runs x 4 conditions",
        1,
        lambda: summarize(big, n_resamples=200),
    )
    record.save()


if __name__ == "__main__":
    main()
