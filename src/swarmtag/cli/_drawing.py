"""The drawn run of ``swarmtag simulate``: its file names, its check, its drawing with progress.

``--snapshot``, ``--animate``, ``--trajectories`` and ``--mcap`` record one
run (``--draw-run``) of each condition again and save it. With one
condition the file is the name given; with several, one file per condition,
``STEM-<condition>.SUFFIX`` with the condition's name made file-safe
(``run.mcap`` -> ``run-proximity.mcap``, ``run-urgency-alpha-0.7.mcap``). The
event log and event table hold every condition in one file.

Drawing (a GIF above all) takes longer than simulating a hundred runs, so
``swarmtag simulate`` prints its tables first and draws after, with a
progress line on stderr: in forked processes (``swarmtag._beside``, one a
condition up to the cores) that loaded matplotlib while the runs were
simulated, where it can.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Iterator, Sequence
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

from swarmtag._beside import Beside, finish_all
from swarmtag._outputs import OutputPlan, Stage
from swarmtag._plotting import pyplot
from swarmtag.policy import Policy
from swarmtag.sim import Scenario, SimResult, simulate

__all__ = [
    "PER_CONDITION_HELP",
    "Drawing",
    "Drawn",
    "finish_drawing",
    "per_condition",
    "plan_outputs",
    "progress_bar",
]

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


class Drawing:
    """Record ``run`` of each condition again and save its outputs (a ``swarmtag._beside.Job``).

    ``recorded`` records the runs, one condition at a time; ``finish`` draws
    and saves each (in forked processes, ``prepare`` loads matplotlib while
    the command simulates).
    """

    def __init__(
        self,
        scenario: Scenario,
        policies: Sequence[Policy],
        drawn: Drawn,
        *,
        seed: int,
        run: int,
        stage: Stage,
        controller: str,
        backend: str | None,
    ) -> None:
        """Draw ``drawn`` of ``run`` for each of ``policies``, into ``stage``'s paths."""
        self._scenario, self._policies, self._drawn = scenario, list(policies), drawn
        self._seed, self._run, self._stage = seed, run, stage
        self._controller, self._backend = controller, backend

    @property
    def steps(self) -> int:
        """How many steps are reported: a recording and each output, per condition."""
        return len(self._policies) * (1 + self._drawn.count)

    def recorded(self, step: Callable[[str], None]) -> Iterator[SimResult]:
        """Each condition's ``run``, recorded, in the order of the policies."""
        for policy in self._policies:
            step(f"recording run {self._run} of {policy.name}")
            yield simulate(
                self._scenario,
                policy,
                seed=self._seed,
                runs=1,
                run_offset=self._run,
                record=True,
                controller=self._controller,
                backend=self._backend,
            )

    def prepare(self) -> None:
        """Load matplotlib if pictures are asked for."""
        if self._drawn.snapshot is not None or self._drawn.animation is not None:
            pyplot()

    def finish(
        self, items: Iterable[tuple[int, SimResult]], step: Callable[[str], None]
    ) -> list[str]:
        """Draw and save the outputs of each (condition index, recorded run); their notes.

        ``step`` is called as each output starts; ``Drawn.count`` notes a
        run, in the order of ``items``.
        """
        from swarmtag.sim.outputs.render import animate, snapshot  # noqa: PLC0415 - plot extra

        drawn, run, stage = self._drawn, self._run, self._stage
        several = len(self._policies) > 1
        written = []
        for index, result in items:
            policy = self._policies[index]
            traj = result.trajectories
            assert traj is not None
            if drawn.snapshot is not None:
                step(f"drawing the snapshot of {policy.name}")
                target = per_condition(drawn.snapshot, policy, several)
                tick = snapshot(traj, stage.path(target), run=run)
                written.append(f"snapshot of {policy.name} run {run} at tick {tick}: {target}")
            if drawn.animation is not None:
                step(f"animating {policy.name}")
                target = per_condition(drawn.animation, policy, several)
                frames = animate(traj, stage.path(target), run=run)
                written.append(f"animation of {policy.name} run {run} ({frames} frames): {target}")
            if drawn.trajectories is not None:
                step(f"saving the trajectories of {policy.name}")
                target = per_condition(drawn.trajectories, policy, several)
                traj.save(stage.path(target))
                written.append(
                    f"trajectories of {policy.name} run {run} ({traj.ticks} ticks): {target}"
                )
            if drawn.mcap is not None:
                from swarmtag.sim.outputs.mcap import write_mcap  # noqa: PLC0415 - rosbags extra

                step(f"writing the MCAP of {policy.name}")
                target = per_condition(drawn.mcap, policy, several)
                ticks = write_mcap(
                    stage.path(target), traj, result.carriers, result.events, run=run
                )
                written.append(f"MCAP of {policy.name} run {run} ({ticks} ticks): {target}")
        return written

    def in_order(self, by_drawer: Sequence[list[str]]) -> list[str]:
        """The notes of the drawers (condition ``i`` sent to drawer ``i % n``) by condition."""
        per, drawers = self._drawn.count, len(by_drawer)
        chunks: dict[int, list[str]] = {}
        for drawer, notes in enumerate(by_drawer):
            indices = range(drawer, len(self._policies), drawers)
            for k, index in enumerate(indices):
                chunks[index] = notes[k * per : (k + 1) * per]
        return [note for index in sorted(chunks) for note in chunks[index]]


def finish_drawing(drawing: Drawing, drawers: Sequence[Beside], *, progress: bool) -> list[str]:
    """Record the drawn runs here and draw them in the ``drawers``, with a progress line.

    Condition ``i`` goes to drawer ``i % n``; with no drawers, it is drawn here.
    """
    with progress_bar(show=progress, unit="steps") as bar:
        task = bar.add_task("drawing", total=drawing.steps)
        started = False

        def step(what: str) -> None:
            nonlocal started
            if started:
                bar.advance(task)
            started = True
            bar.update(task, description=what)

        if not drawers:
            drawing.prepare()
            return drawing.finish(enumerate(drawing.recorded(step)), step)
        for index, result in enumerate(drawing.recorded(step)):
            drawers[index % len(drawers)].send((index, result), step)
        return drawing.in_order(finish_all(drawers, step))
