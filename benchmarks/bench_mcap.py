"""Time `simulate --mcap` (writing one recorded run) and `log import` of it (a plain script).

For each case: simulate one run with recording, write it as MCAP, read the event log back,
and check that it is the run's own. Prints ticks written, seconds, file size, and writes
them to ``benchmarks/results/`` (``_results.py``). Usage:

    .venv/bin/python benchmarks/bench_mcap.py [--quick] [--out FILE.json]
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from _results import begin

from swarmtag.io.bags import read_bag
from swarmtag.policy import Urgency
from swarmtag.sim import Scenario, simulate
from swarmtag.sim.outputs.mcap import write_mcap

CASES = [(3, 7, "paper-sim", 3000), (20, 40, "paper-sim", 1000), (3, 7, "lab", 3000)]
QUICK = [(3, 7, "paper-sim", 300), (20, 40, "paper-sim", 100)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="short runs (a smoke test)")
    args, record = begin(parser, __file__)
    print("robots/carriers profile ticks | written ticks | write s | import s | MiB | same log")
    for robots, carriers, profile, ticks in QUICK if args.quick else CASES:
        base = Scenario.default(robots, carriers, profile=profile)
        scenario = Scenario.from_mapping({**base.to_mapping(), "ticks": ticks})
        result = simulate(scenario, Urgency(alpha=0.7), seed=0, runs=1, record=True)
        assert result.trajectories is not None
        with tempfile.TemporaryDirectory() as folder:
            path = Path(folder) / "run.mcap"
            start = time.perf_counter()
            written = write_mcap(path, result.trajectories, result.carriers, result.events, run=0)
            wrote = time.perf_counter() - start
            start = time.perf_counter()
            logs = read_bag(path, with_events=True)
            read = time.perf_counter() - start
            size = path.stat().st_size / 2**20
        same = logs.carriers == result.carriers and logs.events == result.events
        print(
            f"{robots}/{carriers} {profile} {ticks} | {written} | {wrote:.2f} | {read:.2f} | "
            f"{size:.2f} | {same}"
        )
        record.row(
            robots=robots,
            carriers=carriers,
            profile=profile,
            ticks=ticks,
            ticks_written=written,
            write_s=wrote,
            import_s=read,
            mib=size,
            same_log=same,
        )
    record.save()


if __name__ == "__main__":
    main()
