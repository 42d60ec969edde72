"""``swarmtag study``: run a study file (or a shipped study) into a resumable results folder."""

from __future__ import annotations

import sys
import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

import click

from swarmtag._checks import MAX_RESAMPLES, MAX_WORKERS
from swarmtag._inputs import check_path
from swarmtag.cli._scenario import backend_option, note_compilation
from swarmtag.cli._testing import tests_beside
from swarmtag.errors import ConfigError, StudyError
from swarmtag.sim.backends import resolve_backend

__all__ = ["reproduce", "study"]

workers_option = click.option(
    "--workers",
    type=click.IntRange(1, MAX_WORKERS),
    help="Worker processes, or with the fast backend threads [default: the number of CPU cores].",
)
scheduler_option = click.option(
    "--scheduler",
    metavar="ADDRESS",
    help="Run on the Dask distributed cluster with this scheduler (tcp://host:8786).",
)
progress_option = click.option(
    "--progress/--no-progress",
    default=None,
    help="Show a progress bar [default: only on a terminal].",
)


@click.group("study")
def study() -> None:
    """Run the published studies, or your own study files (see docs/experiments.md)."""


@study.command("run")
@click.argument("source", metavar="FILE|NAME")
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=Path("out"),
    show_default=True,
    help="Results folder: the store (results.duckdb) and per-study metrics.",
)
@click.option("--quick", is_flag=True, help="Run the study's quick_runs per condition only.")
@backend_option
@workers_option
@scheduler_option
@progress_option
def run_cmd(
    *,
    source: str,
    out_dir: Path,
    quick: bool,
    backend: str | None,
    workers: int | None,
    scheduler: str | None,
    progress: bool | None,
) -> None:
    """Run study FILE (a TOML path) or NAME (a shipped study), computing only missing runs.

    Interrupted runs resume where they stopped: completed runs are kept in
    the results store and never computed twice.
    """
    # The experiments extra (DuckDB) loads only when a study is run.
    from swarmtag.experiments import load_study, run_study  # noqa: PLC0415

    spec = load_study(source)
    show = sys.stderr.isatty() if progress is None else progress
    _note([backend if backend is not None else spec.backend], scheduler)
    with tests_beside(comparing=True):  # scipy.stats imported beside the first simulations
        result = run_study(
            spec,
            out_dir=out_dir,
            quick=quick,
            workers=workers,
            scheduler=scheduler,
            progress=show,
            backend=backend,
        )
    click.echo(
        f"{result.study}: {result.computed_runs} runs computed, "
        f"{result.reused_runs} reused from the store"
    )
    click.echo(f"results store: {result.store}")
    for scale, path in result.metrics_paths.items():
        click.echo(f"metrics ({scale}): {path}")


def _note(backends: Iterable[str | None], scheduler: str | None) -> None:
    """Say so before the fast kernel is compiled in this process (not on a cluster).

    ``backends``: those the studies will run on (the option's, else each study's).
    """
    if scheduler is None:
        try:
            resolved = {resolve_backend(backend).name for backend in backends}
        except ConfigError as error:
            raise StudyError(str(error)) from None
        for name in sorted(resolved):
            note_compilation(name)


def _studies(sources: Sequence[str], out_dir: Path | None) -> list[Any]:
    """The studies named (shipped names or files); by default the published ones (``REPRODUCED``).

    With ``out_dir`` (``study report``) the default is every shipped study with results there.
    """
    from swarmtag.experiments import REPRODUCED, STUDIES, load_study  # noqa: PLC0415 - DuckDB

    if sources:
        return [load_study(source) for source in sources]
    if out_dir is not None:
        check_path(out_dir, what="DIR", error=StudyError)
    shipped = REPRODUCED if out_dir is None else tuple(STUDIES)
    names = [name for name in shipped if out_dir is None or (out_dir / name).is_dir()]
    if not names:
        msg = f"{out_dir}: no results of a shipped study here; name the study with --study"
        raise StudyError(msg)
    return [load_study(name) for name in names]


@study.command("report")
@click.argument("out_dir", metavar="DIR", type=click.Path(file_okay=False, path_type=Path))
@click.option(
    "--study",
    "sources",
    multiple=True,
    metavar="NAME|FILE",
    help="Study to report, repeatable [default: every shipped study with results in DIR].",
)
@click.option(
    "--resamples",
    type=click.IntRange(1, MAX_RESAMPLES),
    metavar="N",
    help="Bootstrap resamples [default: the study's own; capped after a quick run].",
)
@click.option(
    "--format",
    "export_format",
    type=click.Choice(["csv", "parquet"]),
    default="csv",
    show_default=True,
    help="Format of the exported event logs (carriers.*, events.* per study and scale).",
)
def report_cmd(
    *, out_dir: Path, sources: tuple[str, ...], resamples: int | None, export_format: str
) -> None:
    """Event logs, tables, figures and DIR/report.html from the results stored in DIR."""
    from swarmtag.experiments.report import write_report  # noqa: PLC0415 - DuckDB is an extra

    studies = _studies(sources, out_dir)
    path = write_report(out_dir, studies, resamples=resamples, export_format=export_format)
    click.echo(f"report: {path}")


@click.command("reproduce")
@click.option(
    "--quick", is_flag=True, help="Every study with its quick run count (about a minute)."
)
@click.option(
    "--study",
    "sources",
    multiple=True,
    metavar="NAME|FILE",
    help="Study to run, repeatable [default: the five published studies, docs/experiments.md].",
)
@click.option(
    "--out",
    "out_dir",
    type=click.Path(file_okay=False, path_type=Path),
    default=Path("out/reproduction"),
    show_default=True,
    help="Results folder: store, metrics, tables, figures and report.html.",
)
@click.option(
    "--seeds",
    type=click.IntRange(min=1),  # the upper bound is the library's (MAX_SEEDS), checked there
    default=1,
    show_default=True,
    metavar="K",
    help="Run every study at its master seed + 0 .. K-1 and judge the published directions "
    "over the K seeds (DIR/seeds.md; docs/experiments.md).",
)
@backend_option
@workers_option
@scheduler_option
@progress_option
def reproduce(
    *,
    quick: bool,
    sources: tuple[str, ...],
    out_dir: Path,
    seeds: int,
    backend: str | None,
    workers: int | None,
    scheduler: str | None,
    progress: bool | None,
) -> None:
    """Run the published studies (resuming what is stored) and write the report."""
    # The experiments extra (DuckDB) loads only when a study is run.
    from swarmtag.experiments.reproduce import StudyRun  # noqa: PLC0415
    from swarmtag.experiments.reproduce import reproduce as run_all  # noqa: PLC0415
    from swarmtag.experiments.seed_tables import console_lines  # noqa: PLC0415

    studies = _studies(sources, None)
    show = sys.stderr.isatty() if progress is None else progress
    _note([backend if backend is not None else spec.backend for spec in studies], scheduler)

    def echo(run: StudyRun) -> None:
        seed = f" (seed {run.seed})" if seeds > 1 else ""
        click.echo(
            f"{run.study}{seed}: {run.computed_runs} runs computed, {run.reused_runs} reused, "
            f"{run.wall_time_s:.1f} s"
        )

    started = time.perf_counter()
    with tests_beside(comparing=True):  # scipy.stats imported beside the first simulations
        done = run_all(
            studies,
            out_dir=out_dir,
            seeds=seeds,
            quick=quick,
            workers=workers,
            scheduler=scheduler,
            progress=show,
            backend=backend,
            on_study=echo,
        )
    for line in console_lines(done.robustness):
        click.echo(line)
    for path in done.summary_files:
        click.echo(f"seeds summary: {path}")
    click.echo(f"report: {done.report} ({time.perf_counter() - started:.1f} s in all)")
