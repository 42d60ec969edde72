"""Throughput of batched carrier selection, the per-tick decision of every robot.

Run: ``.venv/bin/python benchmarks/bench_select.py [--repeat N] [--out FILE.json]`` — prints
milliseconds per call and robot-decisions per second for (runs, robots, carriers) batches like
the simulator's, and writes them to ``benchmarks/results/`` (``_results.py``).
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from _results import begin

from swarmtag.policy import Proximity, Urgency, Weighted, select

SHAPES = [(1, 3, 7), (100, 3, 7), (1000, 3, 7), (100, 20, 40), (10, 200, 400)]


def bench(shape: tuple[int, int, int], repeat: int) -> dict[str, float]:
    """Best-of-``repeat`` seconds per call for each policy on one random batch."""
    rng = np.random.default_rng(0)
    runs, _robots, carriers = shape
    urgency = rng.integers(0, 10, size=(runs, 1, carriers))
    distance = rng.uniform(0.0, 5.0, size=shape)
    marker = np.arange(carriers)
    available = rng.random(size=shape) < 0.5
    timings = {}
    for policy in (Proximity(), Urgency(alpha=0.7), Weighted(w=0.5)):
        best = float("inf")
        for _ in range(repeat):
            start = time.perf_counter()
            select(policy, urgency=urgency, distance=distance, marker=marker, available=available)
            best = min(best, time.perf_counter() - start)
        timings[policy.name] = best
    return timings


def main() -> None:
    """Print a table of seconds per call and robot-decisions per second."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=7, help="calls per measurement, best kept")
    args, record = begin(parser, __file__)
    print(f"{'runs x robots x carriers':>26}  {'policy':<18} {'ms/call':>9} {'decisions/s':>13}")
    for shape in SHAPES:
        for name, seconds in bench(shape, args.repeat).items():
            decisions = shape[0] * shape[1] / seconds
            label = " x ".join(map(str, shape))
            print(f"{label:>26}  {name:<18} {seconds * 1e3:9.3f} {decisions:13.3g}")
            runs, robots, carriers = shape
            record.row(
                runs=runs,
                robots=robots,
                carriers=carriers,
                policy=name,
                ms_per_call=seconds * 1e3,
                decisions_per_s=decisions,
            )
    record.save()


if __name__ == "__main__":
    main()
