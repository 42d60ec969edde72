"""``swarmtag metrics --warmup T``: KPIs of the orders placed after a warm-up; bad T in one line."""

from __future__ import annotations

import json

import pytest

from swarmtag.analysis import summarize, trim_warmup
from swarmtag.cli import main
from swarmtag.io import write_event_log
from tests.analysis.test_window import window_log


def run(argv: list[str], capsys) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    out, err = capsys.readouterr()
    return exit_info.value.code, out, err


@pytest.fixture
def events(tmp_path) -> str:
    path = tmp_path / "events.csv"
    write_event_log(window_log(), path)
    return str(path)


def test_warmup_trims_before_every_figure(events, capsys):
    argv = ["metrics", events, "--json", "--resamples", "30"]
    code, whole, err = run(argv, capsys)
    assert (code, err) == (0, "")
    code, window, err = run([*argv, "--warmup", "20"], capsys)
    assert (code, err) == (0, "")
    log = window_log()
    assert json.loads(whole) == summarize(log, n_resamples=30).to_json()
    assert json.loads(window) == summarize(trim_warmup(log, 20.0), n_resamples=30).to_json()
    (condition,) = json.loads(window)["conditions"]
    assert (condition["total_deliveries"], condition["undelivered"]) == (3, 2)
    assert json.loads(whole)["conditions"][0]["total_deliveries"] == 6
    code, zero, _ = run([*argv, "--warmup", "0"], capsys)
    assert zero == whole


def test_the_table_says_what_the_window_covers(events, capsys):
    code, out, _ = run(["metrics", events, "--resamples", "30", "--warmup", "20"], capsys)
    assert code == 0
    assert "KPIs cover the orders placed at or after 20 s" in " ".join(out.split())
    code, out, _ = run(["metrics", events, "--resamples", "30"], capsys)
    assert "KPIs cover" not in out


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("-1", "--warmup: -1.0 is not a number >= 0"),
        ("nan", "--warmup: nan is not a number >= 0"),
        ("inf", "--warmup: inf is not a number >= 0"),
        ("soon", "'soon' is not a valid float"),
        ("55", "warm-up 55: run 1 of c has no order placed at or after it"),
    ],
)
def test_a_bad_warmup_is_one_line(events, capsys, value, message):
    code, out, err = run(["metrics", events, "--resamples", "30", f"--warmup={value}"], capsys)
    assert (code, out) == (2, "")
    assert err.startswith("swarmtag: error: ")
    assert err.count("\n") == 1
    assert message in err
