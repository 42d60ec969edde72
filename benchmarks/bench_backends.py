"""Reference and compiled backends side by side: robot-ticks per second, memory per robot.

Run: ``.venv/bin/python benchmarks/bench_backends.py [--max-robots N] [--threads T ...]
[--reference-up-to N] [--cases NAME ...] [--repeat N] [--out FILE.json]``. Every case
simulates one seeded batch with ``swarmtag.sim.simulate`` (the whole call: scene sampling,
kernel, event logs) under ``urgency:alpha=0.7`` on the ``paper-sim`` profile and reports
robot-ticks per second of the ticks actually stepped, for the reference (numpy) backend
where it is affordable and for the fast (numba) backend on 1 and 2 threads; the same
process, the same runs.

- ``3x7`` and ``20x40``: the lab set-ups batched over runs (1000 and 100 runs, 3000 ticks);
- ``200``, ``2k``, ``20k``, ``200k``, ``1M``: one run of that many robots, 256 carriers
  (the marker is one byte), in a square arena sized for 0.05 robots per square metre
  (a third of it the drop-off area where they start), 200 ticks (100 from 200k on).

Memory per robot is the resident-set growth of the fast run divided by the robots. The
log-log slope of the cost per robot-tick against the robot count over the single-run
cases says how the cost grows (1.0: linear). Cases that do not fit in memory are
skipped with the estimate. The first calls compile the kernel (cached afterwards) or load
its machine code, the batched path's and the split path's (about 0.3 s each process): they
are timed separately.

A shared virtual machine's speed can move by a factor of two within an hour. So the script
times a plain Python loop (``_results.probe_seconds``) before and after, to say how fast it ran,
and ``--repeat N`` runs every row N times and reports the fastest run (the least disturbed)
and the median. Rows, probes, first-call time and slope go to ``benchmarks/results/``
(``_results.py``).
"""

from __future__ import annotations

import argparse
import math
import resource
import time
from dataclasses import asdict, dataclass

import numpy as np
from _results import PROBE, begin, probe_seconds

from swarmtag.policy import Urgency
from swarmtag.sim import Scenario, load_profile, simulate

DENSITY = 0.05
"""Robots per square metre of arena in the single-run cases."""
SPLIT_FROM = 10_000
"""Robots from which one run is split over threads (``sim/fast/_runner.py``)."""


@dataclass(frozen=True)
class Case:
    name: str
    robots: int
    carriers: int
    runs: int
    ticks: int

    def scenario(self) -> Scenario:
        profile = load_profile("paper-sim")
        if self.runs > 1:
            return profile.scenario(
                {"robots": self.robots, "carriers": self.carriers, "ticks": self.ticks}
            )
        side = max(20.0, math.sqrt(self.robots / DENSITY))
        return profile.scenario(
            {
                "robots": self.robots,
                "carriers": self.carriers,
                "ticks": self.ticks,
                "arena": {"size": side, "pickup_width": side / 3, "dropoff_width": side / 3},
            }
        )


CASES = [
    Case("3x7", 3, 7, 1000, 3000),
    Case("20x40", 20, 40, 100, 3000),
    Case("200", 200, 256, 1, 200),
    Case("2k", 2_000, 256, 1, 200),
    Case("20k", 20_000, 256, 1, 200),
    Case("200k", 200_000, 256, 1, 100),
    Case("1M", 1_000_000, 256, 1, 100),
]


def _rss_mib() -> float:
    """Peak resident set size of this process so far, MiB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def run(case: Case, backend: str, threads: int) -> tuple[float, float, int]:
    """Seconds of one ``simulate`` call, robot-ticks stepped, and the peak memory growth."""
    before = _rss_mib()
    start = time.perf_counter()
    result = simulate(
        case.scenario(),
        Urgency(alpha=0.7),
        seed=0,
        runs=case.runs,
        backend=backend,
        threads=threads if backend == "fast" else None,
    )
    elapsed = time.perf_counter() - start
    stepped = int(result.end_tick.sum()) * case.robots
    return elapsed, stepped, int(max(0.0, _rss_mib() - before) * 2**20)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cases", nargs="*", help="case names (default: all that fit)")
    parser.add_argument("--max-robots", type=int, default=1_000_000)
    parser.add_argument("--reference-up-to", type=int, default=2_000, help="robots")
    parser.add_argument("--threads", type=int, nargs="*", default=[1, 2])
    parser.add_argument("--repeat", type=int, default=1, help="runs of each row (best, median)")
    args, record = begin(parser, __file__)
    if args.repeat < 1:
        parser.error(f"--repeat: {args.repeat} is not a positive number of runs")
    cases = [c for c in CASES if c.robots <= args.max_robots]
    if args.cases:
        cases = [c for c in cases if c.name in args.cases]
    print(f"probe: a Python loop of {PROBE:,} additions takes {record.machine['probe_s']:.2f} s")
    start = time.perf_counter()
    simulate(Scenario.default(3, 7), Urgency(alpha=0.7), seed=0, runs=1, backend="fast")
    if max(args.threads) > 1:  # one run split over threads: its own kernel calls
        warm = Case("warm", SPLIT_FROM, 256, 1, 2).scenario()
        simulate(warm, Urgency(alpha=0.7), seed=0, runs=1, backend="fast", threads=2)
    first = record.summary["first_calls_s"] = time.perf_counter() - start
    print(f"first fast calls (compile or load the kernels): {first:.1f} s")
    print(
        f"{'case':>6} {'robots':>9} {'runs':>5} {'ticks':>6} {'backend':>10} {'threads':>7} "
        f"{'seconds':>8} {'robot-ticks/s':>14} {'B/robot':>8} {'median s':>8}"
    )
    costs: list[tuple[int, float]] = []
    for case in cases:
        rows = []
        if case.robots <= args.reference_up_to:
            rows.append(("reference", 1))
        rows += [("fast", t) for t in args.threads]
        for backend, threads in rows:
            seconds, stepped, grown = run(case, backend, threads)  # memory: the first run's
            times = [seconds] + [run(case, backend, threads)[0] for _ in range(args.repeat - 1)]
            seconds = min(times)
            rate = stepped / seconds
            per_robot = grown / case.robots / case.runs if backend == "fast" else float("nan")
            print(
                f"{case.name:>6} {case.robots:>9,} {case.runs:>5} {case.ticks:>6} "
                f"{backend:>10} {threads:>7} {seconds:>8.2f} {rate:>14,.0f} {per_robot:>8,.0f} "
                f"{float(np.median(times)):>8.2f}",
                flush=True,
            )
            record.row(
                **asdict(case),
                backend=backend,
                threads=threads,
                seconds=seconds,
                median_seconds=float(np.median(times)),
                robot_ticks=stepped,
                robot_ticks_per_s=rate,
                bytes_per_robot=per_robot,
            )
            if backend == "fast" and threads == max(args.threads) and case.runs == 1:
                costs.append((case.robots, seconds / stepped))
    if len(costs) >= 2:
        x = np.log([c[0] for c in costs])
        y = np.log([c[0] * c[1] for c in costs])  # cost per tick of the whole swarm
        slope = float(np.polyfit(x, y, 1)[0])
        ratio = costs[-1][1] / costs[0][1]
        print(f"log-log slope of the cost of a tick against robots (1.0 = linear): {slope:.2f}")
        print(f"cost per robot-tick, largest vs smallest single run: {ratio:.2f}x")
        record.summary.update(slope=slope, cost_ratio_largest_smallest=ratio)
    probe = record.summary["probe_after_s"] = probe_seconds()
    print(f"probe again: {probe:.2f} s")
    record.save()


if __name__ == "__main__":
    main()
