"""``swarmtag calibrate``: fit free parameters to a baseline, write the profile and the fit report.

The work is in ``swarmtag.calibration``; this module reads the options,
refuses bad ones (and bad output paths) before any simulation, shows a
progress bar, and prints the fit table. See docs/calibration.md.
"""

from __future__ import annotations

import os
import shlex
import sys
from collections.abc import Sequence
from pathlib import Path

import click
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskID,
    TextColumn,
    TimeRemainingColumn,
)
from rich.table import Table

from swarmtag._atomic import atomic_write_bytes
from swarmtag._checks import MAX_WORKERS
from swarmtag._inputs import is_regular_file
from swarmtag._outputs import OutputPlan
from swarmtag.calibration import (
    DEFAULT_EVALUATIONS,
    FIT_COLUMNS,
    CalibrationProblem,
    EvaluationCache,
    calibrate,
    check_evaluations,
    default_cache_path,
    fit_table,
    load_baseline,
    markdown_report,
    parse_free_list,
)
from swarmtag.calibration.evaluate import Evaluation
from swarmtag.calibration.report import format_number, summary_line
from swarmtag.cli._console import make_console
from swarmtag.cli._scenario import parse_set
from swarmtag.errors import CalibrationError
from swarmtag.sim.config.profiles import DEFAULT_PROFILE, load_profile, write_profile_file

__all__ = ["calibrate_cmd", "command_line"]


def _plan_outputs(
    baseline: str, profile: str, out: Path, report: Path | None, cache_path: Path | None
) -> tuple[OutputPlan, Path]:
    """Refuse output paths before any work; the cache (appended while working) is checked too.

    Returns the plan and the cache file (by default named after ``out``, once that is checked).
    """
    plan = OutputPlan(error=CalibrationError)
    for option, source in (("--baseline", baseline), ("--profile", profile)):
        if is_regular_file(source):
            plan.input(option, Path(source))
    plan.file("--out", out, suffixes=(".toml",))
    cache_file = cache_path if cache_path is not None else default_cache_path(out)
    if report is not None:
        plan.file("--report", report, suffixes=(".md",))
    try:
        if not cache_file.parent.is_dir():
            raise CalibrationError(f"--cache: folder {str(cache_file.parent)!r} does not exist")
        if cache_file.exists() and not cache_file.is_file():
            raise CalibrationError(f"--cache: {str(cache_file)!r} is not a regular file")
    except OSError as problem:  # a name too long for the platform
        msg = f"--cache: {str(cache_file)!r} cannot be checked ({problem.strerror})"
        raise CalibrationError(msg) from None
    plan.appended("--cache", cache_file)
    return plan, cache_file


def command_line(
    *,
    baseline: str,
    free: Sequence[str],
    profile: str,
    out: Path,
    name: str | None,
    runs: int | None,
    seed: int | None,
    evaluations: int | None,
    settings: Sequence[str],
    condition: str | None,
) -> str:
    """The command that re-creates the profile (options that change no result left out).

    >>> command_line(baseline="lab", free=["tick=0.02:0.2"], profile="base",
    ...     out=Path("p.toml"), name=None, runs=None, seed=3, evaluations=None,
    ...     settings=[], condition=None)
    'swarmtag calibrate --baseline lab --free tick=0.02:0.2 --profile base --out p.toml --seed 3'
    """
    words = ["swarmtag", "calibrate", "--baseline", baseline]
    for spec in free:
        words += ["--free", spec]
    words += ["--profile", profile, "--out", str(out)]
    for option, value in (
        ("--name", name),
        ("--condition", condition),
        ("--runs", runs),
        ("--seed", seed),
        ("--evaluations", evaluations),
    ):
        if value is not None:
            words += [option, str(value)]
    for text in settings:
        words += ["--set", text]
    return shlex.join(words)


def _progress_bar(show: bool, total: int) -> tuple[Progress, TaskID]:
    columns = (
        TextColumn("calibrating"),
        BarColumn(),
        MofNCompleteColumn(),
        TextColumn("evaluations, best objective {task.fields[best]}"),
        TimeRemainingColumn(),
    )
    bar = Progress(*columns, disable=not show, transient=True)
    return bar, bar.add_task("calibrating", total=total, best="-")


@click.command("calibrate")
@click.option(
    "--baseline",
    required=True,
    metavar="EVENTS|TARGETS.toml|NAME",
    help="An event log of trials (.csv, .parquet), a target file, or a shipped baseline "
    "(paper-sim, lab).",
)
@click.option(
    "--free",
    "free",
    multiple=True,
    metavar="NAME=LO:HI[:log]",
    help="A scenario key to fit within bounds, repeatable (default: the target file's).",
)
@click.option(
    "--profile",
    default=DEFAULT_PROFILE,
    show_default=True,
    metavar="NAME|FILE",
    help="Base profile: its values are kept, the fitted ones substituted.",
)
@click.option(
    "--out",
    required=True,
    type=click.Path(path_type=Path),
    help="Profile TOML file to write.",
)
@click.option("--name", help="Name of the written profile [default: the target file's, or OUT's].")
@click.option(
    "--condition", metavar="NAME", help="Condition of an event log to calibrate on [proximity]."
)
@click.option("--runs", type=int, help="Runs per set-up and evaluation [default: the baseline's].")
@click.option(
    "--seed",
    type=int,
    help="Master seed of the runs and of the design [default: the target file's, else 0].",
)
@click.option(
    "--evaluations",
    type=int,
    help=f"Points the search evaluates [default: the target file's, else {DEFAULT_EVALUATIONS}].",
)
@click.option(
    "--workers",
    type=click.IntRange(1, MAX_WORKERS),
    help="Worker processes [default: one per CPU]; results do not depend on it.",
)
@click.option(
    "--cache",
    "cache_path",
    type=click.Path(path_type=Path),
    help="Cache of evaluated points [default: OUT's name with .cache.jsonl].",
)
@click.option("--report", type=click.Path(path_type=Path), help="Write the fit report (.md).")
@click.option(
    "--set",
    "settings",
    multiple=True,
    metavar="KEY=VALUE",
    help="Fix a scenario key in the base profile, repeatable: --set time_unit=s.",
)
@click.option(
    "--progress/--no-progress", default=None, help="Progress bar [default: on a terminal]."
)
def calibrate_cmd(
    *,
    baseline: str,
    free: tuple[str, ...],
    profile: str,
    out: Path,
    name: str | None,
    condition: str | None,
    runs: int | None,
    seed: int | None,
    evaluations: int | None,
    workers: int | None,
    cache_path: Path | None,
    report: Path | None,
    settings: tuple[str, ...],
    progress: bool | None,
) -> None:
    """Fit free parameters within bounds to a baseline; write the profile and the fit report.

    Every evaluation simulates the same runs (common random numbers); a
    Sobol design and bounded Nelder-Mead search the bounds; evaluated points
    are cached, so an interrupted or repeated calibration resumes.
    """
    plan, cache_file = _plan_outputs(baseline, profile, out, report, cache_path)
    base = load_profile(profile)
    fixed = dict(parse_set(text) for text in settings)
    targets = load_baseline(baseline, condition=condition)
    free_specs = free or targets.free
    problem = CalibrationProblem(
        targets=targets,
        profile=base,
        free=parse_free_list(free_specs),
        settings=fixed,
        runs=runs,
        seed=targets.seed if seed is None else seed,
    )
    if evaluations is None:
        evaluations_used = targets.evaluations or DEFAULT_EVALUATIONS
    else:
        evaluations_used = evaluations
    budget = check_evaluations(evaluations_used)
    cache = EvaluationCache(cache_file)
    console = make_console()
    setups = ", ".join(
        f"{setup.name} ({problem.simulated_runs(setup)} runs)" for setup in targets.setups
    )
    console.print(
        f"calibrating {', '.join(p.key for p in problem.free)} of profile {base.name} on "
        f"{targets.source} ({targets.condition}; {setups}), {budget} evaluations, seed "
        f"{problem.seed}; cache {cache_file} ({len(cache)} points)"
    )
    show = sys.stderr.isatty() if progress is None else progress
    bar, task = _progress_bar(show, budget + 1)

    def tell(_: Evaluation, done: int, best: float) -> None:
        bar.update(task, completed=done, best=format_number(best))

    command = command_line(
        baseline=baseline,
        free=free,
        profile=profile,
        out=out,
        name=name,
        runs=runs,
        seed=seed,
        evaluations=evaluations,
        settings=settings,
        condition=condition,
    )
    with plan.writing() as stage:
        try:
            with bar:
                result = calibrate(
                    problem,
                    evaluations=budget,
                    cache=cache,
                    name=name or targets.name or out.stem,
                    description=targets.description,
                    base=profile,
                    command=command,
                    workers=workers or os.cpu_count() or 1,
                    progress=tell,
                )
        except KeyboardInterrupt:
            note = (
                f"{len(cache)} evaluated points are kept in {cache_file}; "
                "run the same command to resume"
            )
            raise KeyboardInterrupt(note) from None
        write_profile_file(stage.path(out), result.profile)
        written = [f"profile {result.profile.name}: {out}"]
        if report is not None:
            atomic_write_bytes(stage.path(report), markdown_report(result).encode())
            written.append(f"fit report: {report}")
    table = Table(title=f"Fit of {result.profile.name} to {targets.source}")
    for column in FIT_COLUMNS:
        table.add_column(column, justify="left" if column in ("set-up", "KPI") else "right")
    for row in fit_table(result):
        table.add_row(*row)
    console.print(table)
    fitted = ", ".join(f"{key} = {value:g}" for key, value in result.fitted.items())
    console.print(f"fitted: {fitted}")
    console.print(summary_line(result))
    for note in targets.notes:
        console.print(f"note: {note}")
    if cache.skipped:
        console.print(f"note: {cache.skipped_note()}")
    for line in written:
        console.print(f"wrote {line}")
