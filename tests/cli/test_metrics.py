"""``swarmtag metrics`` through the real entry point: tables, JSON, and refusals in one line."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from swarmtag.analysis import METRICS, summarize
from swarmtag.cli import main
from swarmtag.data import example_trial_path
from swarmtag.io import read_event_log, write_event_log
from tests.io.test_csv import GOOD


def run(argv: list[str], capsys) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    out, err = capsys.readouterr()
    return exit_info.value.code, out, err


@pytest.fixture(scope="module")
def example() -> str:
    return str(example_trial_path())


def test_table_output(example, capsys):
    code, out, err = run(["metrics", example, "--resamples", "300"], capsys)
    assert (code, err) == (0, "")
    assert "Metrics by condition (12 runs each): value [95 % CI]" in out
    assert "proximity" in out
    assert "urgency:alpha=3.0" in out
    for label in ("P95 latency (s)", "Mean latency (s)", "Throughput (per 100 s)", "PA (5-50 %)"):
        assert label in out
    assert "Differences from the baseline proximity" in out
    assert "p (bootstrap)" in out
    assert "p (Mann-Whitney)" in out
    assert "Latency covers delivered carriers only" in out
    assert "undelivered: proximity 2, urgency:alpha=3.0 1." in out
    assert "Times are in seconds (time_unit s)." in out
    # The PA cell of the baseline shows the value and its interval, from the same computation.
    figures = summarize(read_event_log(example), n_resamples=300).conditions[0].pa
    interval = figures.confidence_interval
    assert f"{figures.value:.4f} [{interval.low:.4f}, {interval.high:.4f}]" in out


def test_json_output_is_the_contract(example, capsys):
    code, out, err = run(
        ["metrics", example, "--json", "--resamples", "200", "--seed", "3"], capsys
    )
    assert (code, err) == (0, "")
    document = json.loads(out)
    expected = summarize(read_event_log(example), n_resamples=200, seed=3).to_json()
    assert document == expected
    assert [c["condition"] for c in document["conditions"]] == ["proximity", "urgency:alpha=3.0"]
    assert [c["metric"] for c in document["comparisons"]] == list(METRICS)
    assert document["conditions"][0]["runs"] == 12
    assert document["conditions"][0]["undelivered"] == 2


def test_baseline_option(example, capsys):
    argv = ["metrics", example, "--json", "--resamples", "50", "--baseline", "urgency:alpha=3.0"]
    code, out, _ = run(argv, capsys)
    assert code == 0
    document = json.loads(out)
    assert document["conditions"][0]["condition"] == "urgency:alpha=3.0"
    assert {c["baseline"] for c in document["comparisons"]} == {"urgency:alpha=3.0"}
    assert {c["condition"] for c in document["comparisons"]} == {"proximity"}


def test_unknown_baseline_is_one_line(example, capsys):
    code, out, err = run(["metrics", example, "--baseline", "random"], capsys)
    assert (code, out) == (2, "")
    assert err == (
        "swarmtag: error: unknown baseline 'random'; "
        "the log has conditions proximity, urgency:alpha=3.0\n"
    )


def test_bad_file_is_one_line_naming_line_and_column(tmp_path, capsys):
    path = tmp_path / "events.csv"
    path.write_text(GOOD.replace("37.1,52.7", "37.1,abc"))
    code, out, err = run(["metrics", str(path)], capsys)
    assert (code, out) == (2, "")
    assert err == (
        f"swarmtag: error: {path}: line 2, column delivery_time: 'abc' is not a number\n"
    )


def test_missing_file_and_wrong_format(tmp_path, capsys):
    code, _, err = run(["metrics", str(tmp_path / "nope.csv")], capsys)
    assert (code, err) == (2, f"swarmtag: error: {tmp_path / 'nope.csv'}: no such file\n")
    code, _, err = run(["metrics", str(tmp_path / "nope.xlsx")], capsys)
    assert code == 2
    assert "unknown event-log format .xlsx; expected a .csv or .parquet file" in err


def test_usage_errors_are_one_line(example, capsys):
    code, _, err = run(["metrics", example, "--resamples", "0"], capsys)
    assert code == 2
    assert err.count("\n") == 1
    assert "--resamples" in err
    code, _, err = run(["metrics"], capsys)
    assert code == 2
    assert err.count("\n") == 1
    assert "EVENTS" in err


def test_parquet_and_a_log_without_time_unit(tmp_path, capsys):
    path = tmp_path / "events.parquet"
    write_event_log(read_event_log(Path(example_trial_path())), path)
    code, out, _ = run(["metrics", str(path), "--resamples", "50", "--json"], capsys)
    assert code == 0
    assert len(json.loads(out)["comparisons"]) == len(METRICS)
    plain = tmp_path / "plain.csv"
    plain.write_text(GOOD)
    code, out, _ = run(["metrics", str(plain), "--resamples", "50"], capsys)
    assert code == 0
    assert "does not state its time unit" in out
    assert "Only one condition (proximity): nothing to compare." in out
    assert "Throughput (per 100 time units)" in out
    # Run 1 of GOOD has one delivery and run 0 one: throughput is undefined -> n/a.
    assert "n/a" in out


def test_help_describes_the_command_and_every_option(capsys):
    code, out, _ = run(["metrics", "--help"], capsys)
    assert code == 0
    for text in (
        "EVENTS",
        ".csv or .parquet",
        "--baseline NAME",
        "--resamples N",
        "--seed S",
        "--json",
    ):
        assert text in out
    assert "proximity" in out  # the default baseline is explained


def test_installed_entry_point(tmp_path):
    script = Path(sys.executable).with_name("swarmtag")
    result = subprocess.run(
        [str(script), "metrics", str(tmp_path / "missing.csv")],
        capture_output=True,
        text=True,
        check=False,
    )
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr == f"swarmtag: error: {tmp_path / 'missing.csv'}: no such file\n"


def test_partly_undefined_resamples_are_noted(tmp_path, capsys):
    # Run 1 has no delivery: resamples without run 0 have no latency; throughput is never defined.
    path = tmp_path / "gappy.csv"
    path.write_text(
        "condition,run,seed,carrier,urgency0,order_time,pickup_time,delivery_time,robot\n"
        "proximity,0,7,3,8,-10,1,2,1\n"
        "proximity,1,7,3,8,-10,,,\n"
    )
    code, out, _ = run(["metrics", str(path), "--resamples", "400"], capsys)
    assert code == 0
    assert "Mean latency (time units) of proximity was undefined in" in out
    assert "of 400 resamples (left out of its CI)." in out
    assert "Throughput (per 100 time units) of proximity was undefined" not in out


def test_markdown_latex_and_figures_written(tmp_path, capsys):
    from swarmtag.cli import main
    from swarmtag.data import example_trial_path

    argv = [
        "metrics", str(example_trial_path()), "--resamples", "300",
        "--markdown", str(tmp_path / "t.md"), "--latex", str(tmp_path / "t.tex"),
        "--figures", str(tmp_path / "fig"),
    ]  # fmt: skip
    with pytest.raises(SystemExit) as exited:
        main(argv)
    out = capsys.readouterr().out
    assert exited.value.code == 0
    assert (tmp_path / "t.md").read_text().startswith("| Metric | proximity |")
    assert r"\begin{tabular}" in (tmp_path / "t.tex").read_text()
    assert sorted(p.name for p in (tmp_path / "fig").iterdir()) == [
        "latency_curves.png", "pa_curves.png", "urgency_latency.png",
    ]  # fmt: skip
    assert f"wrote Markdown tables: {tmp_path / 't.md'}" in out


def test_markdown_into_missing_folder_is_refused_before_work(tmp_path, capsys):
    from swarmtag.cli import main
    from swarmtag.data import example_trial_path

    with pytest.raises(SystemExit) as exited:
        main(["metrics", str(example_trial_path()), "--markdown", str(tmp_path / "no" / "t.md")])
    err = capsys.readouterr().err
    assert exited.value.code == 2
    assert err.startswith("swarmtag: error: --markdown: ")
    assert "does not exist" in err
    assert list(tmp_path.iterdir()) == []


def test_html_report_embeds_tables_and_figures(tmp_path, capsys):
    from swarmtag.cli import main
    from swarmtag.data import example_trial_path

    path = tmp_path / "report.html"
    with pytest.raises(SystemExit) as exited:
        main(["metrics", str(example_trial_path()), "--resamples", "300", "--html", str(path)])
    assert exited.value.code == 0
    text = path.read_text(encoding="utf-8")
    assert text.count("<table>") == 2
    assert text.count("data:image/png;base64,") == 3
    assert "example_trial.csv" in text
    assert list(tmp_path.iterdir()) == [path]  # figures went to a temporary folder


def test_censored_rows_and_the_undelivered_flag_in_the_text(example, capsys):
    code, out, _ = run(["metrics", example, "--resamples", "300"], capsys)
    assert code == 0
    lines = [line.strip() for line in out.splitlines()]
    for label in ("P95 latency, censored (s)", "Mean latency, censored (s)", "KM P95 latency (s)"):
        # a row of the value table and one of the difference table (undelivered carriers exist)
        assert sum(line.startswith(f"{label}   ") for line in lines) == 2
    assert "P95 latency (s) \N{DAGGER}" in out  # 1 vs 2 undelivered: delivered-only is biased
    assert (
        "\N{DAGGER} urgency:alpha=3.0: undelivered differs from proximity (1 vs 2): "
        "delivered-only latency is biased; compare the censored rows." in out
    )
    assert "end at their latest pickup or delivery: a weaker lower bound" in out  # no run_end


EVENTS_HEADER = "condition,seed,run,time,kind,carrier,robot,value"


def _choice_files(folder: Path) -> tuple[Path, Path]:
    log = folder / "carriers.csv"
    log.write_text(
        "condition,run,seed,carrier,urgency0,order_time,pickup_time,delivery_time,robot\n"
        "proximity,0,0,1,5,0,2,4,0\nproximity,1,0,1,5,0,,,\n"
        "urgency:alpha=0.7,0,0,1,5,0,2,4,1\n"
    )
    events = folder / "events.csv"
    events.write_text(
        f"{EVENTS_HEADER}\n"
        "proximity,0,0,1,select,1,0,5\nproximity,0,0,1,candidates,1,0,2\n"
        "proximity,0,0,1,select,1,1,5\nproximity,0,0,1,candidates,1,1,1\n"
        "proximity,0,0,3,abandon,1,1,1\n"
        "urgency:alpha=0.7,0,0,1,select,1,1,5\n"
    )
    return log, events


def test_event_table_adds_the_choice_statistics(tmp_path, capsys):
    from swarmtag.analysis import choice_statistics
    from swarmtag.io import read_event_table

    log, events = _choice_files(tmp_path)
    argv = ["metrics", str(log), "--event-table", str(events), "--resamples", "100"]
    code, out, _ = run([*argv, "--json", "--seed", "2"], capsys)
    assert code == 0
    document = json.loads(out)
    assert list(document) == ["conditions", "comparisons", "choices"]
    expected = choice_statistics(
        read_event_table(events), log=read_event_log(log), n_resamples=100, seed=2
    )
    assert document["choices"] == [c.to_json() for c in expected]
    proximity, urgency = document["choices"]
    assert (proximity["runs"], proximity["selections"], proximity["double_pursuits"]) == (2, 2, 1)
    assert proximity["share_1_candidate"] == 0.5
    assert urgency["share_1_candidate"] is None  # no candidates events: unknown
    code, out, _ = run([*argv, "--markdown", str(tmp_path / "t.md")], capsys)
    assert code == 0
    assert "Choice statistics by condition (event table)" in out
    assert "Double pursuits per run [95 % CI]" in out
    assert "unknown" in out
    assert "| Share among 1 candidate | 0.5000 | unknown |" in (tmp_path / "t.md").read_text()
    code, out, _ = run(["metrics", str(log), "--resamples", "100"], capsys)
    assert "Choice statistics" not in out  # only with --event-table


def test_event_table_of_other_runs_is_one_line(tmp_path, capsys):
    log, events = _choice_files(tmp_path)
    events.write_text(f"{EVENTS_HEADER}\nproximity,0,5,1,select,1,0,5\n")
    code, out, err = run(["metrics", str(log), "--event-table", str(events)], capsys)
    assert (code, out) == (2, "")
    assert err == (
        "swarmtag: error: event table row 1: run 5 of proximity is not in the event log; "
        "are the two files from the same simulation?\n"
    )
