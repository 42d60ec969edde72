"""Warehouses at scale: robot-ticks per second and deliveries, reference and compiled backends.

Run: ``.venv/bin/python benchmarks/bench_warehouse.py [--cases NAME ...] [--threads T ...]
[--reference-up-to N] [--out FILE.json]``. Every case simulates one seeded batch with
``swarmtag.sim.simulate`` (the whole call) under ``urgency:alpha=0.7`` on the ``lab``
profile with a fixed ``WORKLOAD`` (0.1 s ticks) and reports robot-ticks per second, the
orders that fell due, the deliveries and the mean latency (a sanity check that the floor
works, not a result).

- ``small``: the shipped ``small-warehouse`` map, 8 robots, 20 runs of 6000 ticks (10 min);
- ``hall``: the shipped ``warehouse-hall`` map, 60 robots, 4 runs of 6000 ticks;
- ``2k`` and ``10k``: one run on a generated map (``generated_map``: bays of a double
  shelf row between two aisles, three pick-up slots and two drop-off cells each, four
  destinations spread over the bays) with about four free cells per robot, 1200 ticks
  (2 min);
- ``100k`` (300 ticks) and ``1M`` (100 ticks): the same on larger generated maps. The
  time includes reading the map (routes to every destination) and the start state.

Order intervals are set so that the robots are busy without the pick-up area staying full
(about one order per robot per 400 s: the workload's robots drive 0.12 m/s and take
24 s to dock, ``WORKLOAD``). The first call compiles the kernel (cached
afterwards): it is timed separately. The rows go to ``benchmarks/results/``
(``_results.py``).
"""

from __future__ import annotations

import argparse
import math
import os
import tempfile
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from _results import begin

from swarmtag.policy import Urgency
from swarmtag.sim import Scenario, load_profile, simulate

SECONDS_PER_ORDER_PER_ROBOT = 400.0
"""One order per robot per this many seconds on average."""


def generated_map(robots: int) -> str:
    """A warehouse map text with about four free cells per robot (see the module docs).

    Bays of 12 x 4 cells: an aisle with three pick-up slots, two shelf rows, an aisle
    ending in two drop-off cells; bay ``b`` (row-major) serves destination ``b % 4``.
    """
    bays = max(1, math.ceil(robots * 4 / 28))
    across = max(1, math.ceil(math.sqrt(bays / 3)))  # bays are 3 times wider than tall
    down = math.ceil(bays / across)
    lines = []
    for row in range(down):
        top, shelves, bottom = "", "", ""
        for column in range(across):
            area = str((row * across + column) % 4)
            top += ".P...P...P.."
            shelves += ".##########."
            bottom += ".........." + area * 2
        lines += [top, shelves, shelves, bottom]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class Case:
    name: str
    robots: int
    runs: int
    ticks: int
    map: str

    def scenario(self, folder: Path) -> Scenario:
        source = self.map
        if source == "generated":
            path = folder / f"generated-{self.robots}.txt"
            path.write_text(generated_map(self.robots))
            source = os.fspath(path)
        part = {
            "map": source,
            "order_interval": SECONDS_PER_ORDER_PER_ROBOT / self.robots,
            "initial_orders": min(8, self.robots),
            "warmup": 0.0,
        }
        lab = load_profile("lab")
        layers = {"robots": self.robots, "ticks": self.ticks, "warehouse": part, **WORKLOAD}
        return lab.scenario(layers)


WORKLOAD = {
    "camera": {"range": 3.6, "fade": 0.0},
    "radio": {"search": False},
    "motion": {"speed": 0.1205},
    "timing": {"dock": 24.34},
}
"""A fixed workload on the lab profile, so that figures compare across changes of the profile:
a 3.6 m hard-disc camera without BLE-led search (the compiled kernel's tag lists, which a
million robots need) and the robots' speed and docking time these cases were sized for."""


CASES = (
    Case("small", 8, 20, 6000, "small-warehouse"),
    Case("hall", 60, 4, 6000, "warehouse-hall"),
    Case("2k", 2000, 1, 1200, "generated"),
    Case("10k", 10000, 1, 1200, "generated"),
    Case("100k", 100_000, 1, 300, "generated"),
    Case("1M", 1_000_000, 1, 100, "generated"),
)


def run(case: Case, scenario: Scenario, backend: str, threads: int) -> dict[str, float]:
    """One timed ``simulate`` call and what it delivered."""
    start = time.perf_counter()
    result = simulate(
        scenario, Urgency(alpha=0.7), seed=0, runs=case.runs, backend=backend, threads=threads
    )
    seconds = time.perf_counter() - start
    log = result.carriers
    done = ~np.isnan(log.delivery_time)
    latency = log.delivery_time[done] - log.order_time[done]
    stepped = int(result.end_tick.sum())
    return {
        "seconds": seconds,
        "rate": case.robots * stepped / seconds,
        "orders": float(len(log)),
        "delivered": float(done.sum()),
        "latency": float(latency.mean()) if latency.size else math.nan,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--cases", nargs="*", help="case names (default: all)")
    parser.add_argument("--threads", type=int, nargs="*", default=[1, 2])
    parser.add_argument("--reference-up-to", type=int, default=60, help="robots")
    options, record = begin(parser, __file__)
    chosen = [c for c in CASES if not options.cases or c.name in options.cases]
    with tempfile.TemporaryDirectory() as folder:
        start = time.perf_counter()
        warm = Case("warm", 4, 1, 10, "small-warehouse")
        run(warm, warm.scenario(Path(folder)), "fast", 1)
        if max(options.threads) > 1:  # one run split over threads: its own kernel calls
            split = Case("warm-split", 10_000, 1, 2, "generated")
            run(split, split.scenario(Path(folder)), "fast", 2)
        first = record.summary["first_calls_s"] = time.perf_counter() - start
        print(f"first fast calls (compile or load kernels): {first:.1f} s")
        print(
            "case      robots runs ticks backend   thr  robot-ticks/s   s     orders "
            "delivered mean latency (s)"
        )
        for case in chosen:
            scenario = case.scenario(Path(folder))
            plans = [("fast", t) for t in options.threads]
            if case.robots <= options.reference_up_to:
                plans.insert(0, ("reference", 1))
            for backend, threads in plans:
                out = run(case, scenario, backend, threads)
                print(
                    f"{case.name:9} {case.robots:6} {case.runs:4} {case.ticks:5} {backend:9} "
                    f"{threads:3} {out['rate']:14,.0f} {out['seconds']:6.1f} {out['orders']:7.0f} "
                    f"{out['delivered']:9.0f} {out['latency']:8.1f}",
                    flush=True,
                )
                record.row(
                    **asdict(case),
                    backend=backend,
                    threads=threads,
                    seconds=out["seconds"],
                    robot_ticks_per_s=out["rate"],
                    orders=int(out["orders"]),
                    delivered=int(out["delivered"]),
                    mean_latency_s=out["latency"],
                )
    record.save()


if __name__ == "__main__":
    main()
