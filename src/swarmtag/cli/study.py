"""``swarmtag study``: run a study file (or a shipped study) into a resumable results folder."""

from __future__ import annotations

import sys
from pathlib import Path

import click

__all__ = ["study"]


@click.group("study")
def study() -> None:
    """Run the studies of SPEC §6, or your own study files (see docs/experiments.md)."""


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
@click.option(
    "--workers",
    type=click.IntRange(min=1),
    help="Worker processes [default: the number of CPU cores].",
)
@click.option(
    "--scheduler",
    metavar="ADDRESS",
    help="Run on the Dask distributed cluster with this scheduler (tcp://host:8786).",
)
@click.option(
    "--progress/--no-progress",
    default=None,
    help="Show a progress bar [default: only on a terminal].",
)
def run_cmd(
    *,
    source: str,
    out_dir: Path,
    quick: bool,
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
    result = run_study(
        spec, out_dir=out_dir, quick=quick, workers=workers, scheduler=scheduler, progress=show
    )
    click.echo(
        f"{result.study}: {result.computed_runs} runs computed, "
        f"{result.reused_runs} reused from the store"
    )
    click.echo(f"results store: {result.store}")
    for scale, path in result.metrics_paths.items():
        click.echo(f"metrics ({scale}): {path}")
