"""``swarmtag policies``: the catalogue of selection rules on the command line."""

from __future__ import annotations

import json
from importlib.metadata import EntryPoint
from pathlib import Path

import pytest
from click.testing import CliRunner

from swarmtag.cli import main
from swarmtag.cli._main import app
from swarmtag.policy import CATALOGUE, RULE_GROUP, _rules, parse_policy
from swarmtag.sim.backends import fast_available


def test_every_rule_is_listed_with_its_form_reference_and_backends():
    result = CliRunner().invoke(app, ["policies"], env={"COLUMNS": "200"})
    assert result.exit_code == 0, result.output
    for info in CATALOGUE:
        line = next(row for row in result.output.splitlines() if f"│ {info.form} " in row)
        assert info.kind in line
        assert ", ".join(info.backends)[:12] in line
        assert info.reference[:12] in result.output  # the column may fold the rest
    assert [info.form for info in CATALOGUE] == [
        "proximity",
        "urgency:alpha=A",
        "edf",
        "weighted:w=W",
        "threshold:theta=T",
        "oracle:alpha=A",
        "cbaa:comm_range=C,loss=L",
        "claim:hold=H,loss=L",
        "adaptive:gain=G",
    ]


def test_the_catalogue_is_what_condition_names_accept():
    for info in CATALOGUE:
        values = ",".join(f"{name}={1 if name == 'hold' else 0.5}" for name in info.parameter_names)
        name = f"{info.name}:{values}" if values else info.name
        assert parse_policy(name).name.split(":")[0] == info.name


RULES = Path(__file__).parents[1] / "policy" / "rule_examples.py"
SMALL = ["--profile", "base", "--ticks", "300", "--resamples", "200", "--no-progress"]


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(list(argv))
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def test_a_good_rule_passes_policy_check(capsys):
    code, out, err = run(capsys, "policy", "check", f"{RULES}:oldest_first")
    assert code == 0, err
    assert out.splitlines()[:5] == [
        "ok   runs",
        "ok   finite",
        "ok   deterministic",
        "ok   elementwise",
        "ok   no wall clock",
    ]
    assert "condition 'oldest_first' can run" in out


@pytest.mark.parametrize(
    ("name", "failure"),
    [
        ("nan_scores", "FAIL finite: "),
        ("ranked", "FAIL elementwise: "),
        ("clocked", "FAIL no wall clock: it reads the clock (time.monotonic)"),
        ("raises", "FAIL runs: "),
    ],
)
def test_a_bad_rule_fails_policy_check_in_one_line_each(capsys, name, failure):
    code, out, err = run(capsys, "policy", "check", f"{RULES}:{name}")
    assert code == 2
    assert failure in out
    assert err.count("\n") == 1
    assert err.startswith("swarmtag: error: ")
    assert "fails 1 check(s)" in err


@pytest.mark.parametrize(
    ("spec", "words"),
    [
        ("syntax.py:f", "syntax.py: line 2"),
        (f"{RULES}:one_argument", "a rule takes (urgency, distance, **context)"),
        (f"{RULES}:nan_scores", "fails the check 'finite'"),
        (f"{RULES}:raises", "raised ValueError: no score today"),
        ("missing.py:f", "missing.py: no such file"),
    ],
)
def test_bad_rule_files_stop_simulate_in_one_line(capsys, tmp_path, monkeypatch, spec, words):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "syntax.py").write_text("def f(u, d):\n    return u +\n")
    code, out, err = run(capsys, "simulate", *SMALL, "--runs", "1", "--policy-file", spec)
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1
    assert words in err


def test_policy_file_adds_a_condition_named_after_the_function(capsys):
    code, out, err = run(
        capsys, "simulate", *SMALL, "--runs", "2", "--condition", "proximity",
        "--policy-file", f"{RULES}:urgency_first", "--policy-file", f"{RULES}:oldest_first",
        "--json",
    )  # fmt: skip
    assert code == 0, err
    names = [c["condition"] for c in json.loads(out)["conditions"]]
    assert names == ["proximity", "oldest_first", "urgency_first"]
    if fast_available():
        assert err.count("swarmtag: note: condition ") == 2
        assert "'urgency_first' is Python code" in err


def test_policies_lists_the_rules_packages_register(monkeypatch):
    point = EntryPoint(
        name="fifo_by_age", value="tests.policy.rule_examples:oldest_first", group=RULE_GROUP
    )
    monkeypatch.setattr(
        _rules, "entry_points", lambda *, group: [point] if group == RULE_GROUP else []
    )
    result = CliRunner().invoke(app, ["policies"], env={"COLUMNS": "250"})
    assert result.exit_code == 0, result.output
    line = next(row for row in result.output.splitlines() if "│ fifo_by_age " in row)
    assert "FIFO: the carrier" in line
    assert "falls back" in line
    assert "--policy-file" in result.output


ROOT = Path(__file__).parents[2]


@pytest.mark.parametrize("name", ["urgency_first", "oldest_first"])
def test_the_shipped_example_rules_pass_and_run_as_the_readme_says(capsys, monkeypatch, name):
    monkeypatch.setattr(_rules, "_REGISTERED", {})  # the test rules use the same names
    monkeypatch.chdir(ROOT)
    code, out, err = run(capsys, "policy", "check", f"examples/rules.py:{name}")
    assert code == 0, err
    assert f"condition {name!r} can run" in out
    code, out, err = run(
        capsys, "simulate", *SMALL, "--runs", "2", "--condition", "proximity",
        "--policy-file", f"examples/rules.py:{name}", "--json",
    )  # fmt: skip
    assert code == 0, err
    assert [c["condition"] for c in json.loads(out)["conditions"]] == ["proximity", name]
