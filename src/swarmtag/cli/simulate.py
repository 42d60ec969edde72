"""``swarmtag simulate``: run conditions on a scenario, print KPIs, write logs and pictures."""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Sequence
from contextlib import nullcontext
from pathlib import Path
from typing import Final

import click
from rich.console import Console

from swarmtag._beside import beside, can_fork
from swarmtag._checks import MAX_RUN_INDEX, MAX_SEED
from swarmtag._outputs import OutputPlan
from swarmtag._resources import check_memory, memory_limit
from swarmtag._threads import default_threads
from swarmtag.cli._console import make_console
from swarmtag.cli._drawing import (
    PER_CONDITION_HELP,
    Drawing,
    Drawn,
    finish_drawing,
    plan_outputs,
    progress_bar,
)
from swarmtag.cli._options import baseline_option, check_bootstrap_memory, resamples_option
from swarmtag.cli._report import render_choices, render_report
from swarmtag.cli._scenario import (
    backend_option,
    build_scenario,
    note_compilation,
    scenario_options,
)
from swarmtag.cli._testing import tests_beside
from swarmtag.cli.metrics import summarize_with_choices
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

__all__ = ["DEFAULT_CONDITIONS", "compile_pending", "run_conditions", "simulate_cmd"]

DEFAULT_CONDITIONS: Final = ("proximity", "urgency:alpha=0.7")
"""Conditions run when none is named: the published baseline and the proposed policy."""
CHUNK_RUNS: Final = 50
"""Runs simulated per call: bounds memory and paces the progress bar (results do not change)."""
RECORDED_COPIES_HERE: Final = 2
"""A recorded run sent to a drawing process: the command's and its pickle."""
RECORDED_COPIES_A_DRAWER: Final = 3
"""In each drawing process: the pickle received, the run, and the one drawn before it."""
COMPILE_NOTE: Final = "compiling the fast kernel (first run only, about 1-2 min)"
"""The progress line while numba compiles the kernel (measured: 1.5-3 min on one core)."""


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


def _work_bytes(
    scenario: Scenario, conditions: int, runs: int, *, record: bool, drawers: int, backend: str
) -> float:
    """Bytes the command plans: every condition's log, and a batch or the recorded runs.

    A run is recorded after the batches; drawn in ``drawers`` forked
    processes (``swarmtag._beside``; 0: drawn here) it is sent there, and
    each holds copies of its own.
    """
    recorded = batch_memory(scenario, 1, record=record, backend=backend)
    copies = RECORDED_COPIES_HERE + RECORDED_COPIES_A_DRAWER * drawers if drawers else 1
    return conditions * runs * scenario.carriers * LOG_BYTES_PER_CARRIER + max(
        batch_memory(scenario, min(runs, CHUNK_RUNS), backend=backend), copies * recorded
    )


def _drawers(scenario: Scenario, conditions: int, runs: int, drawn: Drawn, *, backend: str) -> int:
    """How many forked processes draw (0: drawn here, after the batches).

    One a condition, up to the usable cores: each loads matplotlib while the
    batches run. As many as can fork and whose copies of the recorded runs
    fit in memory.
    """
    if not drawn.count or not can_fork():
        return 0
    for count in range(min(conditions, default_threads()), 0, -1):
        planned = _work_bytes(
            scenario, conditions, runs, record=True, drawers=count, backend=backend
        )
        if planned <= memory_limit():
            return count
    return 0


def _check_work(
    scenario: Scenario,
    conditions: int,
    runs: int,
    run_offset: int,
    *,
    record: bool = False,
    drawers: int = 0,
    backend: str = "reference",
) -> None:
    """Refuse run counts whose logs (and a recorded run, ``record``) cannot fit in memory."""
    if run_offset + runs > MAX_RUN_INDEX:
        msg = f"--run-offset {run_offset} + --runs {runs} exceeds the largest run index 2**53"
        raise ConfigError(msg)
    check_memory(
        f"--runs {runs} of {conditions} condition(s) with {scenario.carriers} carriers",
        _work_bytes(scenario, conditions, runs, record=record, drawers=drawers, backend=backend),
        error=ConfigError,
    )


def compile_pending(backend: str) -> bool:
    """Whether the next run on ``backend`` compiles the fast kernel first (once per machine)."""
    if backend != "fast":
        return False
    from swarmtag.sim import fast  # noqa: PLC0415 - numba is an extra

    return not fast.kernel_compiled()


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
    compiling: bool = False,
) -> tuple[CarrierLog, EventTable]:
    """Simulate every condition in chunks of runs; the logs of all conditions, concatenated.

    With ``compiling`` (``compile_pending``), the progress line says so, with
    the elapsed time, while the first compiled condition's first chunk runs
    (numba compiles then), and a line on stderr says how long it took.
    """
    logs: list[CarrierLog] = []
    tables: list[EventTable] = []
    with progress_bar(show=progress, unit="runs") as bar:
        task = bar.add_task("simulating", total=runs * len(policies))
        for policy in policies:
            bar.update(task, description=policy.name)
            for start in range(0, runs, CHUNK_RUNS):
                count = min(CHUNK_RUNS, runs - start)
                compiles = compiling and policy.compiled
                if compiles:
                    bar.update(task, description=COMPILE_NOTE)
                began = time.monotonic()
                result = simulate(
                    scenario,
                    policy,
                    seed=seed,
                    runs=count,
                    run_offset=run_offset + start,
                    controller=controller,
                    backend=backend,
                )
                if compiles:
                    compiling = False
                    took = f"swarmtag: compiled the fast kernel in {time.monotonic() - began:.0f} s"
                    if progress:
                        bar.console.print(took, highlight=False, markup=False)
                    else:
                        click.echo(took, err=True)
                    bar.update(task, description=policy.name)
                logs.append(result.carriers)
                tables.append(result.events)
                bar.advance(task, count)
    return CarrierLog.concat(logs), EventTable.concat(tables)


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
    "--events",
    type=click.Path(path_type=Path),
    help="Write the event log of every condition, in one file (.csv or .parquet).",
)
@click.option(
    "--event-table",
    type=click.Path(path_type=Path),
    help="Write the long-format event table of every condition, in one file (.csv or .parquet).",
)
@click.option(
    "--snapshot",
    type=click.Path(path_type=Path),
    help="Draw a run to a PNG. " + PER_CONDITION_HELP.format(".png"),
)
@click.option(
    "--animate",
    "animation",
    type=click.Path(path_type=Path),
    help="Animate a run (.gif or .mp4). " + PER_CONDITION_HELP.format(".gif or .mp4"),
)
@click.option(
    "--trajectories",
    "trajectories_out",
    type=click.Path(path_type=Path),
    help="Save the drawn run's per-tick trajectories for replay (.npz). "
    + PER_CONDITION_HELP.format(".npz"),
)
@click.option(
    "--mcap",
    type=click.Path(path_type=Path),
    help="Write the drawn run as MCAP with ROS 2 messages (.mcap): for Foxglove, and "
    "'swarmtag log import' gives its event log back (the bags extra). "
    + PER_CONDITION_HELP.format(".mcap"),
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
    plan_outputs(
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
    drawn = Drawn(snapshot, animation, trajectories_out, mcap)
    if mcap is not None:
        require_rosbags()  # the missing extra is named before any work
        from swarmtag.sim.outputs.mcap import check_mcap_carriers  # noqa: PLC0415 - rosbags

        check_mcap_carriers(scenario.carriers)
    resolved = backend_for(controller, backend).name
    if resolved == "fast" and all(not p.compiled for p in policies):
        resolved = "reference"  # every condition falls back (simulate says so)
    drawers = _drawers(scenario, len(policies), runs, drawn, backend=resolved)
    _check_work(
        scenario,
        len(policies),
        runs,
        run_offset,
        record=drawn.count > 0,
        drawers=drawers,
        backend=resolved,
    )
    check_bootstrap_memory(resamples, runs * scenario.carriers, len(policies))
    console = make_console()
    show = sys.stderr.isatty() if progress is None else progress
    # forked before the kernel loads: scipy.stats is imported beside it
    with tests_beside(comparing=len(policies) > 1), plan.writing() as stage:
        compiling = compile_pending(resolved)
        if compiling and not show:
            note_compilation(resolved)  # without a progress line, one line says why it waits
        drawing = Drawing(
            scenario,
            policies,
            drawn,
            seed=seed,
            run=run_offset if draw_run is None else draw_run,
            stage=stage,
            controller=controller,
            backend=backend,
        )
        with beside(drawing, drawers) as drawing_processes:
            log, table = run_conditions(
                scenario,
                policies,
                seed=seed,
                runs=runs,
                run_offset=run_offset,
                progress=show,
                controller=controller,
                backend=backend,
                compiling=compiling,
            )
            status = Console(stderr=True).status(f"bootstrapping {resamples} resamples")
            with status if show else nullcontext():
                report, choices = summarize_with_choices(
                    log, table, baseline=baseline, resamples=resamples, seed=seed
                )
            if not as_json:  # the results first: drawing (a GIF above all) takes longer
                line = _scenario_line(
                    scenario,
                    profile=profile,
                    runs=runs,
                    run_offset=run_offset,
                    seed=seed,
                    controller=controller,
                )
                console.print(line, markup=False)
                render_report(report, console)
                render_choices(choices, console)
            notes = []
            if events is not None:
                write_event_log(log, stage.path(events))
                notes.append(f"event log ({len(log)} rows): {events}")
            if event_table is not None:
                write_event_table(table, stage.path(event_table))
                notes.append(f"event table ({len(table)} rows): {event_table}")
            if drawn.count:
                notes += finish_drawing(drawing, drawing_processes, progress=show)
    if as_json:
        document = {**report.to_json(), "choices": [c.to_json() for c in choices]}
        click.echo(json.dumps(document, allow_nan=False))
        for note in notes:
            click.echo(f"wrote {note}", err=True)
        return
    for note in notes:
        console.print(f"wrote {note}", markup=False)


def _scenario_line(
    scenario: Scenario, *, profile: str, runs: int, run_offset: int, seed: int, controller: str
) -> str:
    """What was simulated, in one sentence (then a blank line)."""
    bodies = (
        f"{scenario.carriers} carriers"
        if scenario.warehouse is None
        else scenario.warehouse.summary()
    )
    return (
        f"{scenario.robots} robots, {bodies}, "
        f"{scenario.run_ticks} ticks of {scenario.tick:g} s ({scenario.urgency.model} urgency), "
        f"{scenario.perception_summary()}, profile {profile}, {runs} runs "
        f"from run {run_offset}, seed {seed}"
        + ("" if controller == "builtin" else f", {controller} controller")
        + "\n"
    )
