"""Speed of the numpy (reference) simulation kernel: robot-ticks per second, batched over runs.

Run: ``.venv/bin/python benchmarks/bench_sim.py [--profile NAME ...] [--repeat N]
[--out FILE.json]`` — steps a fixed number of ticks for 3, 20 and 200 robots under each
profile (default: ``base`` and ``paper-sim``) and prints robot-ticks per second of
``run_batch`` (random draws, kernel, event recording; scene sampling excluded), best of
``--repeat`` batches, and writes them to ``benchmarks/results/`` (``_results.py``). Rates
count the ticks actually stepped, so a batch whose runs all end early is still measured
fairly. Then the reference's scene sampler alone: seconds per scene of ``--scenes`` runs
for an uncrowded 3 x 7 scene and a 20 x 40 one whose pick-up area is crowded to the grid
fallback (every placement gives up 100 times first).
"""

from __future__ import annotations

import argparse
import time
from dataclasses import replace

from _results import begin

from swarmtag.policy import Urgency
from swarmtag.sim import RandomSource, Scenario, load_profile, make_params, run_batch
from swarmtag.sim.model.scene import sample_scene
from swarmtag.sim.runner import seeded_state

# (robots, carriers, runs, ticks): carriers per the density rule; runs fill the batch.
CASES = [
    (3, 7, 1, 300),
    (3, 7, 100, 300),
    (3, 7, 1000, 100),
    (20, 40, 100, 200),
    (200, 256, 4, 100),
]


def bench(profile: str, case: tuple[int, int, int, int], repeat: int) -> float:
    """Best robot-ticks per second over ``repeat`` batches."""
    robots, carriers, runs, ticks = case
    scenario = load_profile(profile).scenario(
        {"robots": robots, "carriers": carriers, "ticks": 10 * ticks}
    )
    params = make_params(scenario, Urgency(alpha=0.7))
    best = 0.0
    for _ in range(repeat):
        state = seeded_state(params, seed=0, runs=runs)
        source = RandomSource(params, seed=0, run_ids=state.run_ids)
        start = time.perf_counter()
        result = run_batch(state, params, source, ticks=ticks)
        elapsed = time.perf_counter() - start
        stepped = int(result.final_state.tick)
        best = max(best, runs * robots * stepped / elapsed)
    return best


SCENES = {
    "3x7": Scenario.default(3, 7),
    "20x40 grid fallback": replace(Scenario.default(20, 40), arena=None, arena_scaling=0.3),
}
"""The scene sampler's cases: the first places at once, the second gives up 100 times."""


def bench_scenes(name: str, scenes: int) -> float:
    """Seconds per scene of runs ``0 .. scenes - 1`` of seed 11."""
    params = make_params(SCENES[name], Urgency(alpha=0.7))
    start = time.perf_counter()
    for run in range(scenes):
        sample_scene(params, seed=11, run=run)
    return (time.perf_counter() - start) / scenes


def main() -> None:
    """Print robot-ticks per second for each case."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--repeat", type=int, default=3, help="batches per case, best kept")
    parser.add_argument("--profile", action="append", help="profile(s) to measure")
    parser.add_argument("--scenes", type=int, default=8, help="scenes sampled per scene case")
    args, record = begin(parser, __file__)
    header = ("profile", "robots", "carriers", "runs", "ticks", "robot-ticks/s")
    print(
        " ".join(
            f"{name:>{width}}" for name, width in zip(header, (10, 6, 8, 5, 5, 14), strict=True)
        )
    )
    for profile in args.profile or ["base", "paper-sim"]:
        for case in CASES:
            rate = bench(profile, case, args.repeat)
            robots, carriers, runs, ticks = case
            print(f"{profile:>10} {robots:>6} {carriers:>8} {runs:>5} {ticks:>5} {rate:>14,.0f}")
            record.row(
                profile=profile,
                robots=robots,
                carriers=carriers,
                runs=runs,
                ticks=ticks,
                robot_ticks_per_s=rate,
            )
    for name in SCENES:
        seconds = bench_scenes(name, args.scenes)
        print(f"scene {name}: {seconds * 1000:.2f} ms a scene ({args.scenes} scenes)")
        record.row(scene=name, scenes=args.scenes, seconds_per_scene=seconds)
    record.save()


if __name__ == "__main__":
    main()
