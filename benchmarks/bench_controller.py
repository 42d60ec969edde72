"""Speed of the two controllers: built-in (vectorised) vs behaviour trees (software-in-the-loop).

Run: ``.venv/bin/python benchmarks/bench_controller.py [--quick] [--repeat N]
[--backend reference|fast] [--out FILE.json]`` — for each case (robots / carriers, profile,
ticks, runs in one batch) calls ``simulate(..., controller="builtin")`` and
``simulate(..., controller="bt")`` in this one process and prints the wall seconds of the
whole call (scene sampling, kernel, controller and event logs included; best of
``--repeat``), robot-ticks per second (robots times the ticks each run actually stepped,
``result.end_tick``, summed over runs), the ratio builtin/bt of those rates, and whether
every run's carrier and event logs (``run_csv``) came out byte-identical under both
controllers; the rows go to ``benchmarks/results/`` (``_results.py``). The trees always run
on the reference (numpy) world; the built-in controller runs there too unless ``--backend
fast`` (the compiled kernel, the default of ``simulate``) is given, so by default the two
controllers are compared on the same world. ``--quick`` runs shorter, smaller batches (a
smoke test, not a measurement). Both controllers are warmed up on a tiny batch first, so
one-off imports (py_trees) and the compiled kernel's loading are not timed.
"""

from __future__ import annotations

import argparse
import time
from typing import NamedTuple

from _results import begin

from swarmtag.policy import Urgency
from swarmtag.sim import Scenario, SimResult, simulate
from swarmtag.sim.determinism import run_csv


class Case(NamedTuple):
    """One benchmark case: world size, profile, run length and batch size."""

    name: str
    robots: int
    carriers: int
    profile: str
    ticks: int
    runs: int


CASES = [
    Case("a", 3, 7, "base", 1500, 20),
    Case("b", 3, 7, "paper-sim", 3000, 5),
    Case("c", 20, 40, "base", 600, 2),
    Case("d", 20, 40, "paper-sim", 1000, 1),
]
QUICK = [
    Case("a", 3, 7, "base", 300, 4),
    Case("b", 3, 7, "paper-sim", 300, 2),
    Case("c", 20, 40, "base", 100, 1),
    Case("d", 20, 40, "paper-sim", 100, 1),
]
CONTROLLERS = ("builtin", "bt")
POLICY = Urgency(alpha=0.7)
SEED = 0


def scenario_of(case: Case) -> Scenario:
    """The scenario of ``case``: its profile's default world, run length ``ticks``."""
    base = Scenario.default(case.robots, case.carriers, profile=case.profile)
    return Scenario.from_mapping({**base.to_mapping(), "ticks": case.ticks})


def timed(case: Case, controller: str, repeat: int, backend: str) -> tuple[float, SimResult]:
    """Best wall seconds of ``simulate`` over ``repeat`` batches, and the last result."""
    scenario = scenario_of(case)
    best = float("inf")
    result = None
    for _ in range(repeat):
        start = time.perf_counter()
        result = simulate(
            scenario, POLICY, seed=SEED, runs=case.runs, controller=controller, backend=backend
        )
        best = min(best, time.perf_counter() - start)
    assert result is not None
    return best, result


def robot_ticks(case: Case, result: SimResult) -> int:
    """Robots times the ticks each run actually stepped, summed over the batch."""
    return case.robots * int(result.end_tick.sum())


def same_logs(first: SimResult, second: SimResult) -> bool:
    """Whether every run's carrier and event CSV bytes agree between two results."""
    if list(first.run_ids) != list(second.run_ids):
        return False
    return all(run_csv(first, int(i)) == run_csv(second, int(i)) for i in first.run_ids)


def backend_of(controller: str, builtin_backend: str) -> str:
    """The world a controller runs on: the trees always on the reference one."""
    return builtin_backend if controller == "builtin" else "reference"


def warm_up(builtin_backend: str) -> None:
    """One tiny batch per controller, so imports and first-call costs are not timed."""
    case = Case("warm-up", 3, 7, "base", 20, 1)
    for controller in CONTROLLERS:
        timed(case, controller, 1, backend_of(controller, builtin_backend))


HEADER = ("case", "robots", "carriers", "profile", "ticks", "runs", "controller")
HEADER += ("wall s", "robot-ticks", "robot-ticks/s", "builtin/bt", "logs identical")
WIDTHS = (4, 6, 8, 9, 5, 4, 10, 8, 11, 13, 10, 14)


def row(*cells: object) -> str:
    """One table line, every cell right-aligned to its column."""
    return " ".join(f"{cell!s:>{width}}" for cell, width in zip(cells, WIDTHS, strict=True))


def main() -> None:
    """Print wall time and robot-ticks per second of both controllers for each case."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true", help="small, short cases (smoke test)")
    parser.add_argument("--repeat", type=int, default=1, help="batches per case, best kept")
    parser.add_argument(
        "--backend",
        choices=("reference", "fast"),
        default="reference",
        help="the built-in controller's world (the trees always run on the reference one)",
    )
    args, record = begin(parser, __file__)
    if args.repeat < 1:
        parser.error("--repeat must be at least 1")
    warm_up(args.backend)
    print(row(*HEADER))
    all_same = True
    for case in QUICK if args.quick else CASES:
        measured = {
            c: timed(case, c, args.repeat, backend_of(c, args.backend)) for c in CONTROLLERS
        }
        rates = {c: robot_ticks(case, r) / wall for c, (wall, r) in measured.items()}
        same = same_logs(measured["builtin"][1], measured["bt"][1])
        all_same &= same
        for controller, (wall, result) in measured.items():
            is_bt = controller == "bt"
            ratio = f"{rates['builtin'] / rates['bt']:.1f}x" if is_bt else "-"
            print(
                row(
                    case.name,
                    case.robots,
                    case.carriers,
                    case.profile,
                    case.ticks,
                    case.runs,
                    controller,
                    f"{wall:.2f}",
                    f"{robot_ticks(case, result):,}",
                    f"{rates[controller]:,.0f}",
                    ratio,
                    ("yes" if same else "NO") if is_bt else "-",
                )
            )
            record.row(
                **case._asdict(),
                controller=controller,
                backend=backend_of(controller, args.backend),
                wall_s=wall,
                robot_ticks=robot_ticks(case, result),
                robot_ticks_per_s=rates[controller],
                logs_identical=same,
            )
    print(f"event logs identical in every case: {'yes' if all_same else 'NO'}")
    record.summary["logs_identical"] = all_same
    record.save()


if __name__ == "__main__":
    main()
