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

from swarmtag.analysis import choice_statistics, summarize
from swarmtag.cli._console import make_console
from swarmtag.cli._options import baseline_option, resamples_option
from swarmtag.cli._scenario import build_scenario, scenario_options
from swarmtag.cli.metrics import render_choices, render_report
from swarmtag.errors import ConfigError
from swarmtag.io import CarrierLog, EventTable, write_event_log, write_event_table
from swarmtag.policy import Policy, Proximity, Urgency, Weighted, parse_policy
from swarmtag.sim import Scenario, simulate

__all__ = ["DEFAULT_CONDITIONS", "run_conditions", "simulate_cmd"]

DEFAULT_CONDITIONS: Final = ("proximity", "urgency:alpha=0.7")
"""Conditions run when none is named: the published baseline and the proposed policy."""
CHUNK_RUNS: Final = 50
"""Runs simulated per call: bounds memory and paces the progress bar (results do not change)."""


def _policies(
    conditions: Sequence[str], policy: str | None, alpha: float | None, w: float | None
) -> list[Policy]:
    """The policies to run, from ``--condition`` names or ``--policy/--alpha/--w``."""
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
    names = [p.name for p in chosen]
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise click.UsageError(f"condition given twice: {', '.join(repeated)}")
    return chosen


def _per_condition(path: Path, policy: Policy, several: bool) -> Path:
    """``snap.png`` for one condition; ``snap-urgency-alpha-0.7.png`` per condition for several."""
    if not several:
        return path
    slug = re.sub(r"[^A-Za-z0-9.]+", "-", policy.name).strip("-")
    return path.with_name(f"{path.stem}-{slug}{path.suffix}")


def _check_outputs(outputs: Sequence[tuple[str, Path | None, tuple[str, ...]]]) -> None:
    """Refuse bad output paths before any work is done."""
    for option, path, suffixes in outputs:
        if path is None:
            continue
        if path.suffix.lower() not in suffixes:
            msg = f"{option}: {str(path)!r} must end in {' or '.join(suffixes)}"
            raise ConfigError(msg)
        if not path.parent.is_dir():
            msg = f"{option}: folder {str(path.parent)!r} does not exist"
            raise ConfigError(msg)


def run_conditions(
    scenario: Scenario,
    policies: Sequence[Policy],
    *,
    seed: int,
    runs: int,
    run_offset: int = 0,
    progress: bool = False,
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
                    scenario, policy, seed=seed, runs=count, run_offset=run_offset + start
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
) -> list[str]:
    """Re-run ``run`` of each condition recording it; draw and save it; say what was written."""
    from swarmtag.sim.render import animate, snapshot  # noqa: PLC0415 - matplotlib is an extra

    written = []
    several = len(policies) > 1
    for policy in policies:
        result = simulate(scenario, policy, seed=seed, runs=1, run_offset=run, record=True)
        traj = result.trajectories
        assert traj is not None
        if snapshot_path is not None:
            target = _per_condition(snapshot_path, policy, several)
            tick = snapshot(traj, target, run=run)
            written.append(f"snapshot of {policy.name} run {run} at tick {tick}: {target}")
        if animation_path is not None:
            target = _per_condition(animation_path, policy, several)
            frames = animate(traj, target, run=run)
            written.append(f"animation of {policy.name} run {run} ({frames} frames): {target}")
        if trajectories_path is not None:
            target = _per_condition(trajectories_path, policy, several)
            traj.save(target)
            written.append(
                f"trajectories of {policy.name} run {run} ({traj.ticks} ticks): {target}"
            )
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
    "--policy",
    type=click.Choice(["proximity", "urgency", "weighted"]),
    help="One condition by policy name (with --alpha or --w).",
)
@click.option("--alpha", type=float, help="alpha of --policy urgency (> 0).")
@click.option("--w", type=float, help="w of --policy weighted (0-1).")
@click.option(
    "--runs", type=click.IntRange(min=1), default=30, show_default=True, help="Runs per condition."
)
@click.option(
    "--run-offset",
    type=click.IntRange(min=0),
    default=0,
    show_default=True,
    help="Global index of the first run: run i gives the same rows alone or in any batch.",
)
@click.option(
    "--seed", type=click.IntRange(min=0), default=0, show_default=True, help="Master seed."
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
    "--draw-run",
    type=click.IntRange(min=0),
    help="Run to draw or save with --snapshot/--animate/--trajectories [default: the first run].",
)
@baseline_option
@resamples_option
@click.option("--json", "as_json", is_flag=True, help="Print the KPI JSON of SPEC §8.2.")
@click.option(
    "--progress/--no-progress",
    default=None,
    help="Show a progress bar [default: only on a terminal].",
)
def simulate_cmd(
    *,
    conditions: tuple[str, ...],
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
    draw_run: int | None,
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
    policies = _policies(conditions, policy, alpha, w)
    scenario = build_scenario(profile=profile, config=config, flags=flags, settings=settings)
    _check_outputs(
        [
            ("--events", events, (".csv", ".parquet")),
            ("--event-table", event_table, (".csv", ".parquet")),
            ("--snapshot", snapshot, (".png",)),
            ("--animate", animation, (".gif", ".mp4")),
            ("--trajectories", trajectories_out, (".npz",)),
        ]
    )
    console = make_console()
    show = sys.stderr.isatty() if progress is None else progress
    log, table = run_conditions(
        scenario, policies, seed=seed, runs=runs, run_offset=run_offset, progress=show
    )
    report = summarize(log, baseline=baseline, n_resamples=resamples, seed=seed)
    choices = choice_statistics(
        table,
        log=log,
        conditions=[c.condition for c in report.conditions],
        n_resamples=resamples,
        seed=seed,
    )
    notes = []
    if events is not None:
        write_event_log(log, events)
        notes.append(f"event log ({len(log)} rows): {events}")
    if event_table is not None:
        write_event_table(table, event_table)
        notes.append(f"event table ({len(table)} rows): {event_table}")
    if snapshot is not None or animation is not None or trajectories_out is not None:
        notes += _draw(
            scenario,
            policies,
            seed=seed,
            run=run_offset if draw_run is None else draw_run,
            snapshot_path=snapshot,
            animation_path=animation,
            trajectories_path=trajectories_out,
        )
    if as_json:
        document = {**report.to_json(), "choices": [c.to_json() for c in choices]}
        click.echo(json.dumps(document, allow_nan=False))
        for note in notes:
            click.echo(f"wrote {note}", err=True)
        return
    console.print(
        f"{scenario.robots} robots, {scenario.carriers} carriers, "
        f"{scenario.run_ticks} ticks of {scenario.tick:g} s ({scenario.urgency.model} urgency), "
        f"{scenario.perception_summary()}, profile {profile}, {runs} runs "
        f"from run {run_offset}, seed {seed}\n"
    )
    render_report(report, console)
    render_choices(choices, console)
    for note in notes:
        console.print(f"wrote {note}")
