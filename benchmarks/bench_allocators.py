"""What the allocators cost: the quick allocators study as a user runs it, and their runs.

Run: ``.venv/bin/python benchmarks/bench_allocators.py [--repeat K] [--out FILE.json]`` —
times ``swarmtag study run allocators --quick`` (a fresh process and output folder each
time, every core; the median of ``--repeat``), then 20 runs of 3 robots and 7 carriers
(profile lab, 3000 ticks, one batch) of every condition of the study in this process:
the built-in rules on the compiled backend, the allocators on the reference backend.
Writes both to ``benchmarks/results/`` (``_results.py``).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path

from _results import begin

from swarmtag.errors import BackendFallback
from swarmtag.experiments import load_study
from swarmtag.sim import simulate


def main() -> None:
    """Print and record the quick study's wall time and each condition's simulation time."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=2, help="times the quick study runs")
    args, record = begin(parser, __file__)
    swarmtag = str(Path(sys.executable).with_name("swarmtag"))
    walls = []
    for _ in range(args.repeat):
        with tempfile.TemporaryDirectory() as folder:
            start = time.perf_counter()
            argv = [swarmtag, "study", "run", "allocators", "--quick", "--out", folder]
            subprocess.run(argv, check=True, capture_output=True)
            walls.append(time.perf_counter() - start)
    record.summary["quick_study_s"] = statistics.median(walls)
    print(f"study run allocators --quick: {statistics.median(walls):.1f} s (median)")
    study = load_study("allocators")
    scenario = study.scale("3x7").scenario
    for policy in study.policies():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", BackendFallback)
            simulate(scenario, policy, seed=0, runs=1)  # warm: the compiled kernel loaded
            start = time.perf_counter()
            simulate(scenario, policy, seed=0, runs=20)
            seconds = time.perf_counter() - start
        backend = "fast" if policy.compiled else "reference"
        print(f"{policy.name:<32} {backend:<9} {seconds:7.2f} s for 20 runs")
        record.row(condition=policy.name, backend=backend, runs=20, seconds=seconds)
    record.save()


if __name__ == "__main__":
    main()
