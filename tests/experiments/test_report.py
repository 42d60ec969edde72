"""The reproduction report from the results store, and the reproduce / study report commands."""

from __future__ import annotations

import json
import re

import pytest

from swarmtag.cli import main
from swarmtag.errors import StudyError
from swarmtag.experiments import load_study, run_study
from swarmtag.experiments.report import StudyRecord, write_report, write_run_record

from .helpers import SMALL_TOML, write_study


def _cli(capsys, *argv):
    with pytest.raises(SystemExit) as exited:
        main(list(argv))
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def test_report_from_the_store_is_reproducible(tmp_path):
    study = load_study(write_study(tmp_path))
    out = tmp_path / "out"
    result = run_study(study, out_dir=out, workers=1)
    write_run_record(
        out,
        study,
        StudyRecord(
            wall_time_s=1.5, quick=False, computed_runs=result.computed_runs, reused_runs=0
        ),
    )
    path = write_report(out, [study])
    html = path.read_text(encoding="utf-8")
    folder = out / study.name / "default"
    tables = (folder / "tables.md").read_text()
    # The report's numbers are those of run_study's metrics: same store, seed and resamples.
    metrics = json.loads((folder / "metrics.json").read_text())
    pa = next(c for c in metrics["conditions"] if c["condition"] == "urgency:alpha=0.7")["pa"]
    assert f"{pa['value']:.4f}" in tables
    # Values, differences and the choice statistics of the stored event tables.
    assert html.count("<table>") == 3
    assert "| Choice statistic | proximity | urgency:alpha=0.7 |" in tables
    assert "| P95 latency, censored (ticks) |" in tables
    assert r"Choice statistic & proximity" in (folder / "tables.tex").read_text()
    assert html.count("data:image/png;base64,") == 3
    assert "1.5 s (full; 12 runs computed, 0 reused)" in html
    assert study.scales[0].code_version in html
    assert sorted(p.name for p in (folder / "figures").iterdir()) == [
        "latency_curves.png", "pa_curves.png", "urgency_latency.png",
    ]  # fmt: skip
    write_report(out, [study])  # again: the same tables
    assert (folder / "tables.md").read_text() == tables
    # The exported event log is the stored one and gives the same KPIs through the CLI path.
    from swarmtag.analysis import summarize
    from swarmtag.io import read_event_log

    log = read_event_log(folder / "carriers.csv")
    assert len(log) == 2 * 6 * 7
    again = summarize(log, baseline=study.baseline, n_resamples=study.resamples, seed=study.seed)
    assert again.to_json() == metrics
    write_report(out, [study], export_format="parquet")
    assert read_event_log(folder / "carriers.parquet") == log


def test_report_without_results_says_so(tmp_path):
    study = load_study(write_study(tmp_path))
    with pytest.raises(StudyError, match="no results store"):
        write_report(tmp_path, [study])


def test_scales_get_the_scalability_table(tmp_path):
    scaled = SMALL_TOML.replace("[scenario]\nrobots = 3\ncarriers = 7\n", "")
    scaled += '\n[scales."3x7"]\nrobots = 3\ncarriers = 7\n\n[scales."4x8"]\nrobots = 4\ncarriers = 8\nticks = 120\n'
    study = load_study(write_study(tmp_path, scaled))
    out = tmp_path / "out"
    run_study(study, out_dir=out, workers=1)
    html = write_report(out, [study]).read_text(encoding="utf-8")
    assert "relative change vs proximity per swarm size" in html
    table = (out / study.name / "scalability.md").read_text().split("\n\n")[0]
    rows = table.splitlines()
    assert rows[0].startswith("| Swarm | Metric | Baseline | Condition | Change (+ is better) |")
    assert len(rows) == 2 + 2 * 6  # two sizes, six metrics
    assert "| 3x7 | P95 latency, censored (ticks) |" in table


def test_reproduce_then_report_commands(tmp_path, capsys):
    source = write_study(tmp_path)
    out = tmp_path / "out"
    code, text, _ = _cli(
        capsys,
        "reproduce",
        "--quick",
        "--study",
        str(source),
        "--out",
        str(out),
        "--workers",
        "1",
        "--no-progress",
    )
    assert code == 0
    assert "small: 4 runs computed, 0 reused" in text
    assert f"report: {out / 'report.html'}" in text
    record = json.loads((out / "small" / "run.json").read_text())
    assert record["quick"] is True
    assert record["computed_runs"] == 4
    code, text, _ = _cli(capsys, "study", "report", str(out), "--study", str(source))
    assert code == 0
    assert text.strip() == f"report: {out / 'report.html'}"


def test_study_report_of_a_folder_without_results_is_one_line(tmp_path, capsys):
    code, out, err = _cli(capsys, "study", "report", str(tmp_path))
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1
    assert "no results of a shipped study here" in err


def test_a_report_reuses_the_summaries_run_study_computed(tmp_path, monkeypatch):
    study = load_study(write_study(tmp_path))
    out = tmp_path / "out"
    result = run_study(study, out_dir=out, workers=1)
    write_report(out, [study])
    folder = out / study.name / "default"
    tables = (folder / "tables.md").read_text()
    latex = (folder / "tables.tex").read_text()

    def no_bootstrap(*args, **kwargs):
        raise AssertionError("the summary was computed again")

    monkeypatch.setattr("swarmtag.experiments.report.summarize", no_bootstrap)
    write_report(out, [study], computed=[result])
    assert (folder / "tables.md").read_text() == tables
    assert (folder / "tables.tex").read_text() == latex
    # a result of other runs or resamples is not taken for this one
    other = run_study(study, out_dir=tmp_path / "quick", workers=1, quick=True)
    with pytest.raises(AssertionError, match="computed again"):
        write_report(out, [study], computed=[other])


def test_a_ranking_study_gets_the_ranking_table_and_the_pareto_figure(tmp_path):
    import warnings

    from swarmtag.errors import BackendFallback

    from .helpers import small_study

    study = small_study(
        conditions=["proximity", "edf", "oracle:alpha=0.7"], ranking=True, runs=2, quick_runs=2
    )
    out = tmp_path / "out"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BackendFallback)
        run_study(study, out_dir=out, workers=1)
    html = write_report(out, [study]).read_text(encoding="utf-8")
    ranking = (out / "small" / "ranking.md").read_text(encoding="utf-8")
    rows = [line for line in ranking.splitlines() if line.startswith("| ") and "rank" not in line]
    assert len(rows) == 3
    assert {row.split(" | ")[1] for row in rows} == {"proximity", "edf", "oracle:alpha=0.7"}
    assert (out / "small" / "pareto.png").stat().st_size > 10_000
    assert "small: the conditions ranked" in html


# The small study under a name the published directions judge (proximity vs alpha = 0.7).
AS_CONTROLLER_SELECTION = SMALL_TOML.replace('name = "small"', 'name = "controller-selection"')


def test_the_report_opens_with_the_verdicts_and_warns_of_a_quick_run(tmp_path):
    from swarmtag.experiments import reproduce
    from swarmtag.experiments.robustness import judge_study
    from swarmtag.experiments.verdicts import claim_verdict

    study = load_study(
        write_study(tmp_path, AS_CONTROLLER_SELECTION.replace("runs = 6", "runs = 10"))
    )
    quick = reproduce([study], out_dir=tmp_path / "quick", quick=True, workers=1)
    html = quick.report.read_text(encoding="utf-8")
    banner, verdicts = html.index('<p class="banner">'), html.index('<table class="verdicts">')
    first_study = html.index("<details>")
    assert banner < verdicts < first_study
    assert html.index("<h2>Do the published findings reproduce?</h2>") < first_study
    assert "Quick run: 2 runs per condition. Verdicts are underpowered" in html
    assert (
        "For the full reproduction, 10 runs per condition, run <code>swarmtag reproduce</code>"
        in html
    )
    # one claim per direction naming the study; each underpowered at two runs
    assert html.count("underpowered (2 runs;") == 4
    assert "<summary><h2>controller-selection</h2>" in html
    assert "2 runs per condition (quick), 2 conditions</span></summary>" in html
    assert "SPEC" not in html  # the report names docs pages, never a SPEC section (none ships)

    full = reproduce([study], out_dir=tmp_path / "full", workers=1)
    html = full.report.read_text(encoding="utf-8")
    assert 'class="banner"' not in html
    assert "Quick run" not in html
    assert html.index('<table class="verdicts">') < html.index("<details>")
    assert "10 runs per condition, 2 conditions</span></summary>" in html
    # the verdicts are those of the directions on the study's own summary, at ten runs
    result = run_study(study, out_dir=tmp_path / "full", workers=1)  # from the store
    assert result.computed_runs == 0
    outcomes = judge_study(study.name, study.seed, result.reports)
    assert len(outcomes) == 4
    for outcome in outcomes:
        expected = claim_verdict(appears=outcome.appears, significant=outcome.significant, runs=10)
        assert expected != "underpowered"
        row = re.search(
            rf"<td rowspan=\"\d+\" class=\"claim\">{re.escape(outcome.direction.text)}</td>"
            r"<td[^>]*>controller-selection</td><td[^>]*>([^<]*)</td>"
            if len(outcome.parts) > 1
            else rf"<td class=\"claim\">{re.escape(outcome.direction.text)}</td>"
            r"<td>controller-selection</td><td[^>]*>([^<]*)</td>",
            html,
        )
        assert row is not None, outcome.direction.name
        assert row.group(1) == expected


def test_the_report_reads_each_table_from_the_store_once(tmp_path, monkeypatch):
    from swarmtag.experiments.store import ResultsStore

    study = load_study(write_study(tmp_path))
    out = tmp_path / "out"
    run_study(study, out_dir=out, workers=1)
    reads = []
    for method in ("load_log", "load_events"):
        original = getattr(ResultsStore, method)

        def counted(self, *args, _original=original, _method=method, **kwargs):
            reads.append(_method)
            return _original(self, *args, **kwargs)

        monkeypatch.setattr(ResultsStore, method, counted)
    write_report(out, [study])
    assert sorted(reads) == ["load_events", "load_log"]  # the export writes the same tables
    assert (out / study.name / "default" / "carriers.csv").is_file()


def test_figures_drawn_in_worker_processes_are_the_same_files(tmp_path, monkeypatch):
    from swarmtag.experiments import report

    scaled = SMALL_TOML.replace("[scenario]\nrobots = 3\ncarriers = 7\n", "")
    scaled += (
        '\n[scales."3x7"]\nrobots = 3\ncarriers = 7\n\n[scales."4x8"]\nrobots = 4\ncarriers = 8\n'
    )
    study = load_study(write_study(tmp_path, scaled))
    out = tmp_path / "out"
    run_study(study, out_dir=out, workers=1)

    def files():
        found = sorted((out / study.name).rglob("*.png"))
        return {path.relative_to(out): path.read_bytes() for path in found}

    here = write_report(out, [study]).read_text(encoding="utf-8")
    drawn_here = files()
    assert len(drawn_here) == 6
    monkeypatch.setattr(report, "FIGURE_WORKERS_FROM", 1)
    monkeypatch.setattr(report.os, "cpu_count", lambda: 2)
    assert report._figure_workers(2) == 1  # one worker beside this process
    elsewhere = write_report(out, [study]).read_text(encoding="utf-8")
    assert files() == drawn_here
    assert elsewhere == here
