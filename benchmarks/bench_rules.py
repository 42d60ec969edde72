"""What a score rule of one's own costs: whole ``swarmtag simulate`` commands against built-ins.

Run: ``.venv/bin/python benchmarks/bench_rules.py [--runs N] [--repeat K] [--out FILE.json]`` —
times, as a user waits for them (fresh processes, statistics included), one condition of
``--runs`` runs at 3 robots and 7 carriers (profile paper-sim):

- ``edf`` on the compiled backend (the default);
- ``edf`` on the reference backend;
- the rule ``urgency_first`` (``urgency * 100 - distance``: edf's ranking, the same runs)
  from a file, which falls back to the reference backend.

Writes the medians to ``benchmarks/results/`` (``_results.py``).
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _results import begin

RULE = '''import numpy as np


def urgency_first(urgency, distance):
    """Most urgent first, the nearer among equals."""
    return urgency * 100.0 - np.minimum(distance, 99.0)
'''


def timed(argv: list[str]) -> float:
    """Seconds of one whole command (a fresh process)."""
    start = time.perf_counter()
    subprocess.run(argv, check=True, capture_output=True)
    return time.perf_counter() - start


def main() -> None:
    """Print and record the median seconds of each command."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--runs", type=int, default=40, help="runs of the one condition")
    parser.add_argument("--repeat", type=int, default=3, help="times each command runs")
    args, record = begin(parser, __file__)
    swarmtag = str(Path(sys.executable).with_name("swarmtag"))
    common = [swarmtag, "simulate", "--runs", str(args.runs), "--resamples", "1000"]
    with tempfile.TemporaryDirectory() as folder:
        rules = Path(folder) / "rules.py"
        rules.write_text(RULE)
        cases = {
            "edf, fast": [*common, "--condition", "edf"],
            "edf, reference": [*common, "--condition", "edf", "--backend", "reference"],
            "rule file (reference)": [
                *common,
                "--policy",
                "proximity",
                "--policy-file",
                f"{rules}:urgency_first",
            ],
            "proximity, fast": [*common, "--policy", "proximity"],
        }
        timed(cases["edf, fast"])  # the compiled kernel is in numba's cache from here on
        medians = {}
        for name, argv in cases.items():
            medians[name] = statistics.median(timed(argv) for _ in range(args.repeat))
            print(f"{name:<24} {medians[name]:8.2f} s")
    rule_alone = medians["rule file (reference)"] - medians["proximity, fast"]
    record.summary["rule_condition_s"] = rule_alone
    record.summary["rule_over_fast"] = rule_alone / medians["edf, fast"]
    for name, seconds in medians.items():
        record.row(case=name, runs=args.runs, seconds=seconds)
    print(f"the rule's condition alone: {rule_alone:.2f} s")
    record.save()


if __name__ == "__main__":
    main()
