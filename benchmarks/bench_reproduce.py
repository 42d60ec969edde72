"""What a full ``swarmtag reproduce`` costs warm, and where its time goes.

Run: ``.venv/bin/python benchmarks/bench_reproduce.py [--repeat K] [--out FILE.json]``.

- One untimed ``swarmtag reproduce --out DIR`` first (it compiles or loads the kernels and
  fills the page cache), then ``--repeat`` whole commands, each a fresh process into a new
  empty folder: every run is simulated, stored, summarised, exported and drawn again.
- Inside each timed command, wall time is split by what runs (exclusive: a statistic a
  figure computes counts as statistics): ``simulation`` (``simulate_chunk``),
  ``statistics`` (the bootstrap summaries, choice statistics, rankings and verdicts),
  ``figures`` (the PNGs: drawing them, or waiting for the worker processes that draw them),
  ``digest`` (the model's and the kernel's source digests), ``store`` (the results store:
  writing chunks, loading logs, exporting them) and ``rest`` (the whole command's time less
  those: start-up, imports, progress files, tables, the HTML page). CPU time likewise
  (``time.process_time``: all threads; it moves less than wall time on a shared machine),
  and the CPU time of its other processes apart (``workers``: the figure workers, and the
  process forked to import scipy.stats and run the Mann-Whitney tests).

Medians go to ``benchmarks/results/`` (``_results.py``). The target of issue 34: a full
reproduction under 10 s warm on two cores, dominated by simulation
(``summary.wall_s``, ``summary.simulation_share``).
"""

from __future__ import annotations

import argparse
import functools
import importlib
import json
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from _results import begin, children_cpu_s

CHILD = "--child"
"""First argument of the timed command: run reproduce in this process, write the split."""
PARTS: dict[str, tuple[str, ...]] = {
    "simulation": ("swarmtag.experiments.execute:simulate_chunk",),
    "statistics": (
        "swarmtag.experiments.runner:summarize",
        "swarmtag.experiments.report:summarize",
        "swarmtag.experiments.report:choice_statistics",
        "swarmtag.experiments.report:rank_conditions",
        "swarmtag.experiments.report:judge_reports",
        "swarmtag.experiments.reproduce:judge_study",
        "swarmtag.analysis.figures:latency_by_urgency",
    ),
    "figures": (
        "swarmtag.analysis.figures:write_figures",
        "swarmtag.analysis.figures:pareto_figure",
        "swarmtag.experiments.report:_Drawing.figures",
        "swarmtag.experiments.report:_Drawing.__exit__",
    ),
    "digest": (
        "swarmtag.experiments.spec:model_digest",
        "swarmtag.sim.fast._jit:_sources_digest",
    ),
    "store": (
        *(
            f"swarmtag.experiments.store:ResultsStore.{method}"
            for method in ("__init__", "close", "write_chunk", "load_log", "load_events", "export")
        ),
        "swarmtag.experiments.report:export_logs",
    ),
}
"""Each part of the split and the functions (``module:attribute``) whose time it takes."""
ORDER = (*PARTS, "rest")


class Split:
    """Exclusive wall and CPU time per part: entering a part pauses the one it was called from.

    CPU time (``time.process_time``: every thread of the process) moves less than wall time
    when other work shares the machine.
    """

    def __init__(self) -> None:
        self.seconds = {f"{part}{kind}": 0.0 for part in PARTS for kind in ("", "_cpu")}
        self.stack: list[tuple[str, float, float]] = []

    def _count(self, part: str, since: tuple[float, float], now: tuple[float, float]) -> None:
        self.seconds[part] += now[0] - since[0]
        self.seconds[f"{part}_cpu"] += now[1] - since[1]

    def wrap(self, part: str, function: Callable[..., Any]) -> Callable[..., Any]:
        """``function``, its time (less that of nested parts) counted to ``part``."""

        @functools.wraps(function)
        def timed(*args: Any, **kwargs: Any) -> Any:
            now = (time.perf_counter(), time.process_time())
            if self.stack:
                outer, *since = self.stack[-1]
                self._count(outer, (since[0], since[1]), now)
            self.stack.append((part, *now))
            try:
                return function(*args, **kwargs)
            finally:
                now = (time.perf_counter(), time.process_time())
                _, *since = self.stack.pop()
                self._count(part, (since[0], since[1]), now)
                if self.stack:
                    self.stack[-1] = (self.stack[-1][0], *now)

        return timed

    def install(self) -> None:
        """Wrap every function of ``PARTS`` where its callers look it up."""
        for part, targets in PARTS.items():
            for target in targets:
                module_name, _, path = target.partition(":")
                owner: Any = importlib.import_module(module_name)
                *outer, name = path.split(".")
                for attribute in outer:
                    owner = getattr(owner, attribute)
                setattr(owner, name, self.wrap(part, getattr(owner, name)))


def child(out: str, times: str) -> None:
    """The timed command: ``swarmtag reproduce --out OUT``, its split written to ``times``."""
    split = Split()
    split.install()
    from swarmtag.cli import main  # noqa: PLC0415 - after the wrappers, as the command runs

    try:
        main(["reproduce", "--out", out])
    except SystemExit as done:
        if done.code:
            raise
    # the other processes' CPU time: ended by now
    seconds = {**split.seconds, "workers_cpu": children_cpu_s()}
    Path(times).write_text(json.dumps(seconds), encoding="utf-8")


def timed_run(scratch: Path, index: int) -> dict[str, float]:
    """One whole command in a fresh process: its wall and CPU time and the split of both."""
    out, times = scratch / f"run{index}", scratch / f"run{index}.json"
    cpu, start = children_cpu_s(), time.perf_counter()
    subprocess.run(
        [sys.executable, __file__, CHILD, str(out), str(times)], check=True, capture_output=True
    )
    wall, cpu = time.perf_counter() - start, children_cpu_s() - cpu
    seconds: dict[str, float] = json.loads(times.read_text(encoding="utf-8"))
    parts = [seconds[part] for part in PARTS]
    parts_cpu = [seconds[f"{part}_cpu"] for part in PARTS]
    return {
        "wall": wall,
        "cpu": cpu,
        **seconds,
        "rest": wall - sum(parts),
        "rest_cpu": cpu - sum(parts_cpu) - seconds["workers_cpu"],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=5, help="timed commands (default 5)")
    args, record = begin(parser, __file__)
    with tempfile.TemporaryDirectory() as folder:
        scratch = Path(folder)
        warm = [sys.executable, "-c", "from swarmtag.cli import main; main()"]
        subprocess.run(
            [*warm, "reproduce", "--out", str(scratch / "warm")], check=True, capture_output=True
        )
        runs = [timed_run(scratch, index) for index in range(args.repeat)]
    columns = [f"{part}{kind}" for part in ("wall", *ORDER) for kind in ("", "_cpu")]
    columns[1] = "cpu"  # the whole command's CPU time
    columns.append("workers_cpu")
    for index, run in enumerate(runs):
        record.row(run=index, **{f"{column}_s": run[column] for column in columns})
    medians = {column: statistics.median(run[column] for run in runs) for column in columns}
    print(f"{'':<11} {'wall':>8} {'share':>6} {'CPU':>8}")
    for part in ORDER:
        wall, cpu = medians[part], medians[f"{part}_cpu"]
        record.summary[f"{part}_s"] = wall
        record.summary[f"{part}_cpu_s"] = cpu
        print(f"{part:<11} {wall:6.2f} s {wall / medians['wall']:6.1%} {cpu:6.2f} s")
    record.summary["wall_s"] = medians["wall"]
    record.summary["cpu_s"] = medians["cpu"]
    record.summary["workers_cpu_s"] = medians["workers_cpu"]
    record.summary["simulation_share"] = medians["simulation"] / medians["wall"]
    print(f"{'workers':<11} {'':>8} {'':>6} {medians['workers_cpu']:6.2f} s (figures, tests)")
    print(f"{'whole':<11} {medians['wall']:6.2f} s {'':>6} {medians['cpu']:6.2f} s (target: 10 s)")
    record.save()


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == CHILD:
        child(sys.argv[2], sys.argv[3])
    else:
        main()
