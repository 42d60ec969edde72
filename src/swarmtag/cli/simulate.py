"""``swarmtag simulate``: run conditions on a scenario, print KPIs, write logs and pictures."""

from __future__ import annotations

import json
import re
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Final

import click
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from swarmtag._checks import MAX_RUN_INDEX, MAX_SEED
from swarmtag._outputs import OutputPlan, Stage
from swarmtag._resources import check_memory
from swarmtag.cli._console import make_console
from swarmtag.cli._options import baseline_option, check_bootstrap_memory, resamples_option
from swarmtag.cli._scenario import (
    backend_option,
    build_scenario,
    note_compilation,
    scenario_options,
)
from swarmtag.cli.metrics import render_choices, render_report, summarize_with_choices
from swarmtag.errors import ConfigError
from swarmtag.io import CarrierLog, EventTable, write_event_log, write_event_table
from swarmtag.io.ros_types import require_rosbags
from swarmtag.policy import (
    Policy,
    Proximity,
    Urgency,
    Weighted,
    load_checked_rule,
    parse_policy,
)
from swarmtag.sim import Scenario, simulate
from swarmtag.sim.runner import LOG_BYTES_PER_CARRIER, batch_memory
from swarmtag.sim.simulation import backend_for

__all__ = ["DEFAULT_CONDITIONS", "run_conditions", "simulate_cmd"]

DEFAULT_CONDITIONS: Final = ("proximity", "urgency:alpha=0.7")
"""Conditions run when none is named: the published baseline and the proposed policy."""
CHUNK_RUNS: Final = 50
"""Runs simulated per call: bounds memory and paces the progress bar (results do not change)."""


def _policies(
    conditions: Sequence[str],
    policy: str | None,
    alpha: float | None,
    w: float | None,
    rule_files: Sequence[str] = (),
) -> list[Policy]:
    """The policies to run: ``--condition`` names or ``--policy/--alpha/--w``, then rule files."""
    if conditions and (policy or alpha is not None or w is not None):
        msg = "use either --condition (repeatable) or --policy with --alpha/--w, not both"
        raise click.UsageError(msg)
    if conditions:
        chosen = [parse_policy(name) for name in conditions]
    elif policy == "urgency":
        if alpha is None or w is not None:
            raise click.UsageError("--policy urgency takes --alpha (and no --w)")
        chosen = [Urgency(alpha=alpha)]
    elif policy == "weighted":
        if w is None or alpha is not None:
            raise click.UsageError("--policy weighted takes --w (and no --alpha)")
        chosen = [Weighted(w=w)]
    elif policy == "proximity":
        if alpha is not None or w is not None:
            raise click.UsageError("--policy proximity takes neither --alpha nor --w")
        chosen = [Proximity()]
    elif alpha is not None or w is not None:
        raise click.UsageError("--alpha and --w need --policy urgency or --policy weighted")
    else:
        chosen = [parse_policy(name) for name in DEFAULT_CONDITIONS]
    chosen += [load_checked_rule(spec) for spec in rule_files]
    names = [p.name for p in chosen]
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise click.UsageError(f"condition given twice: {', '.join(repeated)}")
    return chosen


def _per_condition(path: Path, policy: Policy, several: bool) -> Path:
    """``snap.png`` for one condition; ``snap-urgency-alpha-0.7.png`` per condition for several."""
    if not several or not path.name:  # "." or "": no file name, refused as a folder when planned
        return path
    slug = re.sub(r"[^A-Za-z0-9.]+", "-", policy.name).strip("-")
    return path.with_name(f"{path.stem}-{slug}{path.suffix}")


def _plan_outputs(
    plan: OutputPlan,
    policies: Sequence[Policy],
    outputs: Sequence[tuple[str, Path | None, tuple[str, ...], bool]],
) -> None:
    """Refuse bad output paths before any work; per-condition pictures are planned one by one."""
    several = len(policies) > 1
    for option, path, suffixes, per_condition in outputs:
        if path is None:
            continue
        targets = [_per_condition(path, p, several) for p in policies] if per_condition else [path]
        for target in targets:
            plan.file(option, target, suffixes=suffixes)


def _check_work(
    scenario: Scenario,
    conditions: int,
    runs: int,
    run_offset: int,
    *,
    record: bool = False,
    backend: str = "reference",
) -> None:
    """Refuse run counts whose logs (and a recorded run, ``record``) cannot fit in memory."""
    if run_offset + runs > MAX_RUN_INDEX:
        msg = f"--run-offset {run_offset} + --runs {runs} exceeds the largest run index 2**53"
        raise ConfigError(msg)
    check_memory(
        f"--runs {runs} of {conditions} condition(s) with {scenario.carriers} carriers",
        conditions * runs * scenario.carriers * LOG_BYTES_PER_CARRIER
        + max(
            batch_memory(scenario, min(runs, CHUNK_RUNS), backend=backend),
            batch_memory(scenario, 1, record=record, backend=backend),
        ),
        error=ConfigError,
    )


def run_conditions(
    scenario: Scenario,
    policies: Sequence[Policy],
    *,
    seed: int,
    runs: int,
    run_offset: int = 0,
    progress: bool = False,
    controller: str = "builtin",
    backend: str | None = None,
) -> tuple[CarrierLog, EventTable]:
    """Simulate every condition in chunks of runs; the logs of all conditions, concatenated."""
    logs: list[CarrierLog] = []
    tables: list[EventTable] = []
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("runs"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, disable=not progress, transient=True) as bar:
        task = bar.add_task("simulating", total=runs * len(policies))
        for policy in policies:
            bar.update(task, description=policy.name)
            for start in range(0, runs, CHUNK_RUNS):
                count = min(CHUNK_RUNS, runs - start)
                result = simulate(
                    scenario,
                    policy,
                    seed=seed,
                    runs=count,
                    run_offset=run_offset + start,
                    controller=controller,
                    backend=backend,
                )
                logs.append(result.carriers)
                tables.append(result.events)
                bar.advance(task, count)
    return CarrierLog.concat(logs), EventTable.concat(tables)


def _draw(
    scenario: Scenario,
    policies: Sequence[Policy],
    *,
    seed: int,
    run: int,
    snapshot_path: Path | None,
    animation_path: Path | None,
    trajectories_path: Path | None,
    mcap_path: Path | None,
    stage: Stage,
    controller: str,
    backend: str | None,
) -> list[str]:
    """Re-run ``run`` of each condition recording it; draw and save it; say what was written."""
    from swarmtag.sim.outputs.render import animate, snapshot  # noqa: PLC0415 - matplotlib is an extra

    written = []
    several = len(policies) > 1
    for policy in policies:
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
        traj = result.trajectories
        assert traj is not None
        if snapshot_path is not None:
            target = _per_condition(snapshot_path, policy, several)
            tick = snapshot(traj, stage.path(target), run=run)
            written.append(f"snapshot of {policy.name} run {run} at tick {tick}: {target}")
        if animation_path is not None:
            target = _per_condition(animation_path, policy, several)
            frames = animate(traj, stage.path(target), run=run)
            written.append(f"animation of {policy.name} run {run} ({frames} frames): {target}")
        if trajectories_path is not None:
            target = _per_condition(trajectories_path, policy, several)
            traj.save(stage.path(target))
            written.append(
                f"trajectories of {policy.name} run {run} ({traj.ticks} ticks): {target}"
            )
        if mcap_path is not None:
            from swarmtag.sim.outputs.mcap import write_mcap  # noqa: PLC0415 - rosbags is an extra

            target = _per_condition(mcap_path, policy, several)
            ticks = write_mcap(stage.path(target), traj, result.carriers, result.events, run=run)
            written.append(f"MCAP of {policy.name} run {run} ({ticks} ticks): {target}")
    return written


@click.command("simulate")
@click.option(
    "--condition",
    "conditions",
    multiple=True,
    metavar="NAME",
    help="Condition to run, repeatable: proximity, urgency:alpha=0.7, weighted:w=0.3. "
    "[default: proximity and urgency:alpha=0.7]",
)
@click.option(
    "--policy-file",
    "rule_files",
    multiple=True,
    metavar="FILE.py:FUNCTION",
    help="A score rule of your own, repeatable: adds a condition named after the function "
    "(docs/policy.md; runs on the reference backend).",
)
@click.option(
    "--policy",
    type=click.Choice(["proximity", "urgency", "weighted"]),
    help="One condition by policy name (with --alpha or --w).",
)
@click.option("--alpha", type=float, help="alpha of --policy urgency (> 0).")
@click.option("--w", type=float, help="w of --policy weighted (0-1).")
@click.option(
    "--runs",
    type=click.IntRange(1, MAX_RUN_INDEX),
    default=30,
    show_default=True,
    help="Runs per condition.",
)
@click.option(
    "--run-offset",
    type=click.IntRange(0, MAX_RUN_INDEX),
    default=0,
    show_default=True,
    help="Global index of the first run: run i gives the same rows alone or in any batch.",
)
@click.option(
    "--seed", type=click.IntRange(0, MAX_SEED), default=0, show_default=True, help="Master seed."
)
@scenario_options
@click.option(
    "--events", type=click.Path(path_type=Path), help="Write the event log (.csv or .parquet)."
)
@click.option(
    "--event-table",
    type=click.Path(path_type=Path),
    help="Write the long-format event table (.csv or .parquet).",
)
@click.option("--snapshot", type=click.Path(path_type=Path), help="Draw a run to a PNG.")
@click.option(
    "--animate",
    "animation",
    type=click.Path(path_type=Path),
    help="Animate a run (.gif or .mp4).",
)
@click.option(
    "--trajectories",
    "trajectories_out",
    type=click.Path(path_type=Path),
    help="Save the drawn run's per-tick trajectories for replay (.npz).",
)
@click.option(
    "--mcap",
    type=click.Path(path_type=Path),
    help="Write the drawn run as MCAP with ROS 2 messages (.mcap): for Foxglove, and "
    "'swarmtag log import' gives its event log back (the bags extra).",
)
@click.option(
    "--draw-run",
    type=click.IntRange(0, MAX_RUN_INDEX - 1),  # a run index: below 2**53, as --run-offset + i
    help="Run to draw or save with --snapshot/--animate/--trajectories/--mcap "
    "[default: the first run].",
)
@click.option(
    "--controller",
    default="builtin",
    show_default=True,
    help="Who decides for the robots: builtin (the vectorised built-in controller), bt (a "
    "behaviour tree per robot; the robot extra), or a controller a package registers under "
    "the swarmtag.controllers entry point. All give the same event logs.",
)
@backend_option
@baseline_option
@resamples_option
@click.option("--json", "as_json", is_flag=True, help="Print the KPI JSON (docs/metrics.md).")
@click.option(
    "--progress/--no-progress",
    default=None,
    help="Show a progress bar [default: only on a terminal].",
)
def simulate_cmd(
    *,
    conditions: tuple[str, ...],
    rule_files: tuple[str, ...],
    policy: str | None,
    alpha: float | None,
    w: float | None,
    runs: int,
    run_offset: int,
    seed: int,
    profile: str,
    config: Path | None,
    settings: tuple[str, ...],
    events: Path | None,
    event_table: Path | None,
    snapshot: Path | None,
    animation: Path | None,
    trajectories_out: Path | None,
    mcap: Path | None,
    draw_run: int | None,
    controller: str,
    backend: str | None,
    baseline: str | None,
    resamples: int,
    as_json: bool,
    progress: bool | None,
    **flags: object,
) -> None:
    """Simulate conditions on a scenario and print their KPIs with 95 % CIs.

    Run i of master seed S is the same in every condition (same initial
    scene) and gives the same rows whether run alone (--run-offset i --runs 1)
    or inside a batch.
    """
    policies = _policies(conditions, policy, alpha, w, rule_files)
    scenario = build_scenario(profile=profile, config=config, flags=flags, settings=settings)
    plan = OutputPlan()
    for option, source in (("--config", config), ("--profile", Path(profile))):
        if source is not None and source.is_file():
            plan.input(option, source)
    _plan_outputs(
        plan,
        policies,
        [
            ("--events", events, (".csv", ".parquet"), False),
            ("--event-table", event_table, (".csv", ".parquet"), False),
            ("--snapshot", snapshot, (".png",), True),
            ("--animate", animation, (".gif", ".mp4"), True),
            ("--trajectories", trajectories_out, (".npz",), True),
            ("--mcap", mcap, (".mcap",), True),
        ],
    )
    drawn = (snapshot, animation, trajectories_out, mcap)
    if mcap is not None:
        require_rosbags()  # the missing extra is named before any work
    recorded = any(path is not None for path in drawn)
    resolved = backend_for(controller, backend).name
    if resolved == "fast" and all(not p.compiled for p in policies):
        resolved = "reference"  # every condition falls back (simulate says so)
    _check_work(scenario, len(policies), runs, run_offset, record=recorded, backend=resolved)
    check_bootstrap_memory(resamples, runs * scenario.carriers, len(policies))
    console = make_console()
    show = sys.stderr.isatty() if progress is None else progress
    note_compilation(resolved)
    with plan.writing() as stage:
        log, table = run_conditions(
            scenario,
            policies,
            seed=seed,
            runs=runs,
            run_offset=run_offset,
            progress=show,
            controller=controller,
            backend=backend,
        )
        report, choices = summarize_with_choices(
            log, table, baseline=baseline, resamples=resamples, seed=seed
        )
        notes = []
        if events is not None:
            write_event_log(log, stage.path(events))
            notes.append(f"event log ({len(log)} rows): {events}")
        if event_table is not None:
            write_event_table(table, stage.path(event_table))
            notes.append(f"event table ({len(table)} rows): {event_table}")
        if recorded:
            notes += _draw(
                scenario,
                policies,
                seed=seed,
                run=run_offset if draw_run is None else draw_run,
                snapshot_path=snapshot,
                animation_path=animation,
                trajectories_path=trajectories_out,
                mcap_path=mcap,
                stage=stage,
                controller=controller,
                backend=backend,
            )
    if as_json:
        document = {**report.to_json(), "choices": [c.to_json() for c in choices]}
        click.echo(json.dumps(document, allow_nan=False))
        for note in notes:
            click.echo(f"wrote {note}", err=True)
        return
    bodies = (
        f"{scenario.carriers} carriers"
        if scenario.warehouse is None
        else scenario.warehouse.summary()
    )
    console.print(
        f"{scenario.robots} robots, {bodies}, "
        f"{scenario.run_ticks} ticks of {scenario.tick:g} s ({scenario.urgency.model} urgency), "
        f"{scenario.perception_summary()}, profile {profile}, {runs} runs "
        f"from run {run_offset}, seed {seed}"
        + ("" if controller == "builtin" else f", {controller} controller")
        + "\n"
    )
    render_report(report, console)
    render_choices(choices, console)
    for note in notes:
        console.print(f"wrote {note}")
