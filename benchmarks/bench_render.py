"""What pictures cost: a one-run ``swarmtag simulate`` with and without ``--animate``, and the GIF.

Run: ``.venv/bin/python benchmarks/bench_render.py [--repeat K] [--before REV] [--out FILE.json]``.

- Whole commands, as a user waits for them (fresh processes, statistics included), run
  alternately ``--repeat`` times: ``simulate --runs 1 --condition urgency:alpha=0.7``
  (profile paper-sim, 3 robots, 7 carriers, 42 frames) alone, with ``--animate run.gif``,
  and with ``--animate`` drawn by the renderer of git revision ``--before`` (the
  full matplotlib redraw per frame it replaced; ``--before none`` skips it).
- ``animate`` alone on the same recorded run, now and at ``--before``.
- The demo's three conditions (100 runs each, ``make demo``'s first call) without and with
  ``--snapshot`` and ``--animate`` (a picture and a GIF a condition; ``--no-demo`` skips them).

Medians of wall time and of CPU time (user + system: steadier on a shared machine) go to
``benchmarks/results/`` (``_results.py``). The target: ``--animate`` adds at most the
command's own time (``summary.added_over_command`` at most 1).
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

from _results import ROOT, begin, children_cpu_s

from swarmtag.policy import Urgency
from swarmtag.sim import Scenario, simulate
from swarmtag.sim.outputs import render

RENDER = "src/swarmtag/sim/outputs/render.py"
COMMAND = ["simulate", "--runs", "1", "--condition", "urgency:alpha=0.7"]
DEMO = ["simulate", "--runs", "100", "--condition", "proximity", "--condition", "urgency:alpha=0.7"]
DEMO += ["--condition", "urgency:alpha=9"]
LAUNCH_BEFORE = """import importlib.util, sys
spec = importlib.util.spec_from_file_location("swarmtag.sim.outputs.render", sys.argv.pop(1))
module = importlib.util.module_from_spec(spec)
sys.modules[spec.name] = module  # simulate's --animate imports the renderer late: this one
spec.loader.exec_module(module)
from swarmtag.cli import main
main()
"""
"""Runs ``swarmtag`` with the renderer file named first on its command line."""


def timed(argv: list[str]) -> tuple[float, float]:
    """Wall and CPU seconds of one whole command (a fresh process)."""
    cpu, start = children_cpu_s(), time.perf_counter()
    subprocess.run(argv, check=True, capture_output=True)
    return time.perf_counter() - start, children_cpu_s() - cpu


def timed_call(call: Callable[[], object]) -> tuple[float, float]:
    """Wall and CPU seconds of one call in this process."""
    cpu, start = time.process_time(), time.perf_counter()
    call()
    return time.perf_counter() - start, time.process_time() - cpu


def old_renderer(revision: str, folder: Path) -> Path | None:
    """``render.py`` as it was at git ``revision``, written into ``folder``; None if absent."""
    done = subprocess.run(
        ["git", "show", f"{revision}:{RENDER}"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    if done.returncode != 0:
        print(f"no {RENDER} at {revision}: {done.stderr.strip()}")
        return None
    path = folder / "render_before.py"
    path.write_text(done.stdout, encoding="utf-8")
    return path


def load(path: Path) -> ModuleType:
    """The renderer at ``path`` as a module of its own."""
    spec = importlib.util.spec_from_file_location("render_before", path)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def command_cases(
    swarmtag: str, folder: Path, before: Path | None, *, demo: bool
) -> dict[str, list[str]]:
    """Each whole command timed, by its case's name (outputs go to ``folder``)."""
    gif = str(folder / "run.gif")
    cases = {
        "command": [swarmtag, *COMMAND],
        "command --animate": [swarmtag, *COMMAND, "--animate", gif],
    }
    if before is not None:
        launch = [sys.executable, "-c", LAUNCH_BEFORE, str(before)]
        cases["command --animate, before"] = [*launch, *COMMAND, "--animate", gif]
    if demo:
        pictures = ["--snapshot", str(folder / "snap.png"), "--animate", gif]
        cases["demo conditions"] = [swarmtag, *DEMO]
        cases["demo conditions, pictures"] = [swarmtag, *DEMO, *pictures]
    return cases


def medians(samples: list[tuple[float, float]]) -> tuple[float, float]:
    """Median wall and median CPU seconds."""
    return (
        statistics.median(wall for wall, _ in samples),
        statistics.median(cpu for _, cpu in samples),
    )


def main() -> None:
    """Print and record the medians."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5, help="times each case runs")
    parser.add_argument(
        "--before",
        default="c9b9eba",
        help="git revision of the renderer to compare with (default: the full redraw); none: skip",
    )
    parser.add_argument(
        "--demo",
        action=argparse.BooleanOptionalAction,
        default=True,
        help="also time the demo's three conditions with and without pictures",
    )
    args, record = begin(parser, __file__)
    swarmtag = str(Path(sys.executable).with_name("swarmtag"))
    with tempfile.TemporaryDirectory() as name:
        folder = Path(name)
        before = None if args.before == "none" else old_renderer(args.before, folder)
        gif = str(folder / "run.gif")
        cases = command_cases(swarmtag, folder, before, demo=args.demo)
        timed(cases["command"])  # the compiled kernel is in numba's cache from here on
        samples: dict[str, list[tuple[float, float]]] = {case: [] for case in cases}
        for _ in range(args.repeat):  # alternately, so a slow phase of the machine hits all
            for case, argv in cases.items():
                samples[case].append(timed(argv))
        traj = simulate(Scenario.default(), Urgency(alpha=0.7), seed=0, runs=1, record=True)
        assert traj.trajectories is not None
        recorded = traj.trajectories
        renderers = {"animate alone": render.animate}
        if before is not None:
            renderers["animate alone, before"] = load(before).animate
        sizes = {}
        for case, animate in renderers.items():
            animate(recorded, gif)  # fonts and caches warm
            samples[case] = [
                timed_call(lambda animate=animate: animate(recorded, gif))
                for _ in range(args.repeat)
            ]
            sizes[case] = Path(gif).stat().st_size
        frames = render.animate(recorded, gif)
        size = Path(gif).stat().st_size
    print(f"{'case':<28} {'wall s':>8} {'CPU s':>8}")
    result = {}
    for case, measured in samples.items():
        wall, cpu = result[case] = medians(measured)
        print(f"{case:<28} {wall:8.2f} {cpu:8.2f}")
        record.row(case=case, repeat=len(measured), wall_s=wall, cpu_s=cpu, frames=frames)
    plain, animated = result["command"], result["command --animate"]
    added = [animated[k] - plain[k] for k in (0, 1)]
    record.summary.update(
        frames=frames,
        gif_bytes=size,
        animate_added_wall_s=added[0],
        animate_added_cpu_s=added[1],
        added_over_command=added[0] / plain[0],
        added_over_command_cpu=added[1] / plain[1],
    )
    print(
        f"--animate adds {added[0]:.2f} s wall ({added[0] / plain[0]:.2f} of the command), "
        f"{added[1]:.2f} s CPU ({added[1] / plain[1]:.2f}); GIF {frames} frames, {size} bytes"
    )
    if args.demo:
        demo = result["demo conditions, pictures"][0] - result["demo conditions"][0]
        record.summary.update(demo_pictures_added_wall_s=demo)
        print(f"the demo's pictures add {demo:.2f} s wall")
    if "animate alone, before" in result:
        old, new = result["animate alone, before"], result["animate alone"]
        was = result["command --animate, before"]
        record.summary.update(
            gif_speedup_wall=old[0] / new[0],
            gif_speedup_cpu=old[1] / new[1],
            gif_bytes_before=sizes["animate alone, before"],
            before_added_over_command=(was[0] - plain[0]) / plain[0],
            before_added_over_command_cpu=(was[1] - plain[1]) / plain[1],
        )
        print(
            f"the GIF alone: {old[0] / new[0]:.1f}x faster (CPU {old[1] / new[1]:.1f}x); "
            f"{sizes['animate alone, before']} bytes before"
        )
    record.save()


if __name__ == "__main__":
    main()
