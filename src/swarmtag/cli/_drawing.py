"""The drawn run of ``swarmtag simulate``: its file names, its check, its drawing with progress.

``--snapshot``, ``--animate``, ``--trajectories`` and ``--mcap`` record one
run (``--draw-run``) of each condition again and save it. With one
condition the file is the name given; with several, one file per condition,
``STEM-<condition>.SUFFIX`` with the condition's name made file-safe
(``run.mcap`` -> ``run-proximity.mcap``, ``run-urgency-alpha-0.7.mcap``). The
event log and event table hold every condition in one file.

Drawing (a GIF above all) takes longer than simulating a hundred runs, so
``swarmtag simulate`` prints its tables first and draws after, with a
progress line on stderr.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from swarmtag._outputs import OutputPlan, Stage
from swarmtag.policy import Policy
from swarmtag.sim import Scenario, simulate

__all__ = ["PER_CONDITION_HELP", "Drawn", "draw", "per_condition", "plan_outputs", "progress_bar"]

PER_CONDITION_HELP: Final = "With several conditions, one file per condition: STEM-<condition>{}."
"""The sentence each per-condition option's help ends with (formatted with its suffix)."""


def progress_bar(*, show: bool, unit: str) -> Progress:
    """A transient progress line on stderr: what, bar, done/total ``unit``, elapsed, ETA."""
    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn(unit),
        TimeElapsedColumn(),
        TextColumn("ETA"),
        TimeRemainingColumn(),
        console=Console(stderr=True),
        disable=not show,
        transient=True,
    )


def per_condition(path: Path, policy: Policy, several: bool) -> Path:
    """``snap.png`` for one condition; ``snap-urgency-alpha-0.7.png`` per condition for several."""
    if not several or not path.name:  # "." or "": no file name, refused as a folder when planned
        return path
    slug = re.sub(r"[^A-Za-z0-9.]+", "-", policy.name).strip("-")
    return path.with_name(f"{path.stem}-{slug}{path.suffix}")


def plan_outputs(
    plan: OutputPlan,
    policies: Sequence[Policy],
    outputs: Sequence[tuple[str, Path | None, tuple[str, ...], bool]],
) -> None:
    """Refuse bad output paths before any work; per-condition files are planned one by one."""
    several = len(policies) > 1
    for option, path, suffixes, one_each in outputs:
        if path is None:
            continue
        targets = [per_condition(path, p, several) for p in policies] if one_each else [path]
        for target in targets:
            plan.file(option, target, suffixes=suffixes)


@dataclass(frozen=True)
class Drawn:
    """Where the drawn run goes: each output's path, or ``None`` where not asked for."""

    snapshot: Path | None = None
    animation: Path | None = None
    trajectories: Path | None = None
    mcap: Path | None = None

    @property
    def count(self) -> int:
        """How many outputs each condition's drawn run gives."""
        return sum(
            p is not None for p in (self.snapshot, self.animation, self.trajectories, self.mcap)
        )


def draw(
    scenario: Scenario,
    policies: Sequence[Policy],
    drawn: Drawn,
    *,
    seed: int,
    run: int,
    stage: Stage,
    controller: str,
    backend: str | None,
    progress: bool = False,
) -> list[str]:
    """Re-run ``run`` of each condition recording it; draw and save it; say what was written."""
    from swarmtag.sim.outputs.render import animate, snapshot  # noqa: PLC0415 - matplotlib is an extra

    written = []
    several = len(policies) > 1
    with progress_bar(show=progress, unit="steps") as bar:
        task = bar.add_task("drawing", total=len(policies) * (1 + drawn.count))
        for policy in policies:
            bar.update(task, description=f"recording run {run} of {policy.name}")
            result = simulate(
                scenario,
                policy,
                seed=seed,
                runs=1,
                run_offset=run,
                record=True,
                controller=controller,
                backend=backend,
            )
            bar.advance(task)
            traj = result.trajectories
            assert traj is not None
            if drawn.snapshot is not None:
                bar.update(task, description=f"drawing the snapshot of {policy.name}")
                target = per_condition(drawn.snapshot, policy, several)
                tick = snapshot(traj, stage.path(target), run=run)
                written.append(f"snapshot of {policy.name} run {run} at tick {tick}: {target}")
                bar.advance(task)
            if drawn.animation is not None:
                bar.update(task, description=f"animating {policy.name}")
                target = per_condition(drawn.animation, policy, several)
                frames = animate(traj, stage.path(target), run=run)
                written.append(f"animation of {policy.name} run {run} ({frames} frames): {target}")
                bar.advance(task)
            if drawn.trajectories is not None:
                target = per_condition(drawn.trajectories, policy, several)
                traj.save(stage.path(target))
                written.append(
                    f"trajectories of {policy.name} run {run} ({traj.ticks} ticks): {target}"
                )
                bar.advance(task)
            if drawn.mcap is not None:
                from swarmtag.sim.outputs.mcap import write_mcap  # noqa: PLC0415 - rosbags extra

                bar.update(task, description=f"writing the MCAP of {policy.name}")
                target = per_condition(drawn.mcap, policy, several)
                ticks = write_mcap(
                    stage.path(target), traj, result.carriers, result.events, run=run
                )
                written.append(f"MCAP of {policy.name} run {run} ({ticks} ticks): {target}")
                bar.advance(task)
    return written
