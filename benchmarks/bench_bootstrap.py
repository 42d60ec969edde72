"""Time the bootstrap statistics of `swarmtag metrics` against the simulations they summarise.

Default: 10,000 resamples of 100 runs x 4 conditions x 7 carriers, the size of the paper's
controller-selection study; the timings go to ``benchmarks/results/`` (``_results.py``).
Side by side in one run:

- ``summarize`` on a synthetic log, with the compiled (numba) and the numpy kernels (and,
  with ``--old-src DIR``, the ``src`` folder of another checkout, that code);
- simulating 100 runs x 4 conditions of 3 robots / 7 carriers (``swarmtag.sim.simulate``, fast
  backend, warm) against ``summarize`` on the log those runs wrote, alternately (and that
  code's ``summarize`` of the same log);
- whole ``swarmtag simulate`` calls in fresh processes (``--robots 20 --carriers 40 --runs
  100``, two conditions; and the default call), split into simulation and statistics, and
  the same calls run by that code, alternately with this one; the 20/40 call also alternately
  with its simulations run warm in this process (the ratio of the medians: at most 2 is the
  target);
- importing ``scipy.stats`` (which the Mann-Whitney test loads) in a fresh process.

Usage:

    .venv/bin/python benchmarks/bench_bootstrap.py [--runs 100] [--resamples 10000]
        [--repeat 5] [--cli-repeat 3] [--big-runs 100000] [--old-src DIR] [--out FILE.json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from _results import ROOT, Record, begin

from swarmtag.analysis import ConditionRuns, condition_kpis, run_values, summarize
from swarmtag.io import CarrierLog, write_event_log
from swarmtag.policy import parse_policy
from swarmtag.sim import load_profile, simulate

CONDITIONS = ("proximity", "urgency:alpha=0.7", "urgency:alpha=3.0", "urgency:alpha=9.0")
CLI_CALLS = {
    "20x40": [
        "simulate",
        "--robots",
        "20",
        "--carriers",
        "40",
        "--runs",
        "100",
        "--condition",
        "proximity",
        "--condition",
        "urgency:alpha=0.7",
        "--json",
    ],
    "default": ["simulate", "--json"],
}
"""``swarmtag`` calls timed whole: issue 34's 20/40 call and the default 3/7 call (30 runs)."""

PROBE = """
import contextlib, io, json, sys, time
started = time.perf_counter()
import swarmtag.cli.metrics as metrics, swarmtag.cli.simulate as command
from swarmtag.cli import main
spent = {"simulation_s": 0.0, "statistics_s": 0.0, "summarize_s": 0.0}
def timed(function, key):
    def wrapper(*args, **kwargs):
        began = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            spent[key] += time.perf_counter() - began
    return wrapper
command.run_conditions = timed(command.run_conditions, "simulation_s")
command.summarize_with_choices = timed(command.summarize_with_choices, "statistics_s")
metrics.summarize = timed(metrics.summarize, "summarize_s")
sys.argv = ["swarmtag", *sys.argv[1:]]
with contextlib.redirect_stdout(io.StringIO()):
    try:
        main()
    except SystemExit as end:
        assert not end.code, end.code
spent["in_process_s"] = time.perf_counter() - started
print(json.dumps(spent))
"""
"""Runs one ``swarmtag`` call in this fresh process and prints where its time went."""

SUMMARIZE = """
import json, sys, time
from swarmtag.analysis import summarize
from swarmtag.io import read_event_log
log = read_event_log(sys.argv[1])
resamples, repeat = int(sys.argv[2]), int(sys.argv[3])
summarize(log, n_resamples=resamples)
times = []
for _ in range(repeat):
    began = time.perf_counter()
    summarize(log, n_resamples=resamples)
    times.append(time.perf_counter() - began)
print(json.dumps(times))
"""
"""Times ``summarize`` of a log file, warm, with whichever code ``PYTHONPATH`` finds."""


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


def timed(record: Record, label: str, repeat: int, action) -> list[float]:
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        action()
        times.append(time.perf_counter() - start)
    report(record, label, times)
    return times


def report(record: Record, label: str, times: list[float], **fields: object) -> None:
    best, median = min(times), statistics.median(times)
    print(f"{label:<66} min {best:7.3f} s   median {median:7.3f} s")
    record.row(workload=label.strip(), repeat=len(times), min_s=best, median_s=median, **fields)


def simulate_conditions(runs: int) -> CarrierLog:
    """``runs`` runs of every condition, 3 robots and 7 carriers (``paper-sim``), fast backend."""
    scenario = load_profile("paper-sim").scenario({"robots": 3, "carriers": 7})
    logs = [
        simulate(scenario, parse_policy(name), seed=0, runs=runs, backend="fast").carriers
        for name in CONDITIONS
    ]
    return CarrierLog.concat(logs)


def environment_of(source: Path | None) -> dict[str, str]:
    """This process's environment, with ``PYTHONPATH`` naming ``source`` if given."""
    environment = dict(os.environ)
    if source is not None:
        environment["PYTHONPATH"] = str(source)
    return environment


def summarize_elsewhere(log: CarrierLog, source: Path, args: argparse.Namespace) -> list[float]:
    """Seconds of ``summarize`` of ``log`` run by the code in ``source`` (``SUMMARIZE``)."""
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "log.csv"
        write_event_log(log, path)
        done = subprocess.run(
            [sys.executable, "-c", SUMMARIZE, str(path), str(args.resamples), str(args.repeat)],
            capture_output=True,
            text=True,
            check=True,
            cwd=ROOT,
            env=environment_of(source),
        )
    times: list[float] = json.loads(done.stdout.strip().splitlines()[-1])
    return times


def statistics_against_simulation(record: Record, args: argparse.Namespace) -> None:
    """Simulating the runs and summarising them, alternately in this process (both warm)."""
    simulate_conditions(2)  # load the compiled kernel
    log = simulate_conditions(args.runs)
    summarize(log, n_resamples=200)  # load the compiled statistics kernels
    simulated, summarised, numpy_only = [], [], []
    for _ in range(args.repeat):
        start = time.perf_counter()
        simulate_conditions(args.runs)
        simulated.append(time.perf_counter() - start)
        start = time.perf_counter()
        summarize(log, n_resamples=args.resamples)
        summarised.append(time.perf_counter() - start)
        start = time.perf_counter()
        summarize(log, n_resamples=args.resamples, compiled=False)
        numpy_only.append(time.perf_counter() - start)
    size = f"{args.runs} runs x {len(CONDITIONS)} conditions of 3/7"
    report(record, f"simulate {size} (fast backend)", simulated)
    report(record, f"summarize those runs: {args.resamples} resamples", summarised)
    report(record, "  the same with the numpy kernels", numpy_only)
    if args.old_src is not None:
        report(record, "  the same with the old code", summarize_elsewhere(log, args.old_src, args))
    ratios = [s / t for s, t in zip(summarised, simulated, strict=True)]
    record.summary["statistics_over_simulation"] = statistics.median(ratios)
    print(f"statistics / simulation (median of pairs): {statistics.median(ratios):.3f}")


def probe(arguments: list[str], source: Path | None) -> dict[str, float]:
    """One ``swarmtag`` call in a fresh process: wall time and its parts (``PROBE``)."""
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", PROBE, *arguments],
        capture_output=True,
        text=True,
        check=True,
        cwd=ROOT,
        env=environment_of(source),
    )
    wall = time.perf_counter() - start
    parts: dict[str, float] = json.loads(done.stdout.strip().splitlines()[-1])
    return {"wall_s": wall, **parts}


def warm_simulations() -> float:
    """Seconds for issue 34's 20/40 call's simulations in this (warm) process: 2 x 100 runs."""
    scenario = load_profile("paper-sim").scenario({"robots": 20, "carriers": 40})
    began = time.perf_counter()
    for name in ("proximity", "urgency:alpha=0.7"):
        simulate(scenario, parse_policy(name), seed=0, runs=100, backend="fast")
    return time.perf_counter() - began


def whole_calls(record: Record, args: argparse.Namespace) -> None:
    """The CLI calls of ``CLI_CALLS``, this code and (``--old-src``) the other, alternately.

    The 20/40 call alternates with its own simulations run warm in this process
    (``warm_simulations``): the ratio of the medians is the issue's target (at most 2).
    """
    sources: dict[str, Path | None] = {"this": None}
    if args.old_src is not None:
        sources["old"] = args.old_src
    warm_simulations()  # the kernel loaded here
    for name, arguments in CLI_CALLS.items():
        for source in sources.values():
            probe(arguments, source)  # caches warm (the compiled kernels, the files)
        samples: dict[str, list[dict[str, float]]] = {code: [] for code in sources}
        warm: list[float] = []
        for _ in range(args.cli_repeat):
            for code, source in sources.items():
                samples[code].append(probe(arguments, source))
            if name == "20x40":
                warm.append(warm_simulations())
        for code, runs in samples.items():
            parts = {key: statistics.median(run[key] for run in runs) for key in runs[0]}
            label = f"swarmtag {' '.join(arguments)} ({code} code)"
            report(record, label, [run["wall_s"] for run in runs], **parts)
            print(
                f"    simulation {parts['simulation_s']:.3f} s, statistics "
                f"{parts['statistics_s']:.3f} s (summarize {parts['summarize_s']:.3f} s)"
            )
            record.summary[f"cli_{name}_{code}"] = parts
        if warm:
            report(record, "  its simulations, warm in this process", warm)
            ratio = statistics.median(run["wall_s"] for run in samples["this"]) / statistics.median(
                warm
            )
            record.summary["cli_20x40_over_warm_simulations"] = ratio
            print(f"    the whole call / its warm simulations (medians): {ratio:.2f} (target 2)")


def scipy_import(record: Record, repeat: int) -> None:
    """Seconds to import scipy.stats in a fresh process (the Mann-Whitney test loads it)."""
    code = (
        "import time; t = time.perf_counter(); import scipy.stats; print(time.perf_counter() - t)"
    )
    times = []
    for _ in range(repeat):
        done = subprocess.run(
            [sys.executable, "-c", code], capture_output=True, text=True, check=True
        )
        times.append(float(done.stdout))
    report(record, "import scipy.stats (fresh process)", times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=100)
    parser.add_argument("--carriers", type=int, default=7)
    parser.add_argument("--resamples", type=int, default=10_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--cli-repeat", type=int, default=3, help="runs of each whole call")
    parser.add_argument("--big-runs", type=int, default=100_000, help="0 leaves the case out")
    parser.add_argument("--old-src", type=Path, default=None, metavar="DIR")
    args, record = begin(parser, __file__)
    if args.old_src is not None:
        args.old_src = args.old_src.resolve()
    log = synthetic_log(args.runs, args.carriers)
    size = f"{args.runs} runs x {len(CONDITIONS)} conditions x {args.carriers} carriers"
    summarize(log, n_resamples=200)  # load the compiled kernels before timing
    timed(
        record,
        f"summarize: {args.resamples} resamples, {size}",
        args.repeat,
        lambda: summarize(log, n_resamples=args.resamples),
    )
    timed(
        record,
        "  the same with the numpy kernels",
        args.repeat,
        lambda: summarize(log, n_resamples=args.resamples, compiled=False),
    )
    if args.old_src is not None:
        report(record, "  the same with the old code", summarize_elsewhere(log, args.old_src, args))
    timed(
        record,
        "  of which KPIs only (4 conditions, no bootstrap)",
        args.repeat,
        lambda: [condition_kpis(run_values(ConditionRuns.from_log(log, c))) for c in CONDITIONS],
    )
    statistics_against_simulation(record, args)
    whole_calls(record, args)
    scipy_import(record, 3)
    if args.big_runs:
        big = synthetic_log(args.big_runs, args.carriers)
        one = ConditionRuns.from_log(big, CONDITIONS[0])
        timed(
            record,
            f"KPIs of one condition of {args.big_runs} runs x {args.carriers} carriers",
            max(1, args.repeat // 2),
            lambda: condition_kpis(run_values(one)),
        )
        timed(
            record,
            f"summarize: 200 resamples, {args.big_runs} runs x 4 conditions",
            1,
            lambda: summarize(big, n_resamples=200),
        )
    record.save()


if __name__ == "__main__":
    main()
