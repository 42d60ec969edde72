"""Study files that name score rules of one's own: loaded, run, and keyed by their code."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from swarmtag.errors import BackendFallback, StudyError
from swarmtag.experiments import load_study, run_study, study_key
from swarmtag.policy import _rules

from .helpers import SMALL_TOML, write_study


@pytest.fixture(autouse=True)
def _fresh_rules(monkeypatch):
    """Each test's rule files are new: their names are not taken by another test's."""
    monkeypatch.setattr(_rules, "_REGISTERED", {})


RULE = "def most_urgent(urgency, distance):\n    return urgency\n"


def rule_study(
    folder: Path, rule: str = RULE, files: str = '["rules/mine.py:most_urgent"]'
) -> Path:
    (folder / "rules").mkdir(exist_ok=True)
    (folder / "rules" / "mine.py").write_text(rule)
    text = SMALL_TOML.replace('profile = "base"\n', f'profile = "base"\npolicy_files = {files}\n')
    return write_study(folder, text)


def test_a_rule_file_adds_its_condition_relative_to_the_study_file(tmp_path, monkeypatch):
    path = rule_study(tmp_path)
    monkeypatch.chdir("/")
    study = load_study(path)
    assert study.conditions == ("proximity", "urgency:alpha=0.7", "most_urgent")
    assert study.policy_files == (f"{(tmp_path / 'rules' / 'mine.py').resolve()}:most_urgent",)
    assert [p.name for p in study.policies()][-1] == "most_urgent"


@pytest.mark.parametrize(
    ("rule", "files", "words"),
    [
        (RULE, '["rules/none.py:f"]', "policy_files[0]: rules/none.py: no such file"),
        (RULE, '"rules/mine.py:most_urgent"', "policy_files: 'rules/mine.py:most_urgent' is not"),
        (RULE, "[3]", "policy_files[0]: 3 is not a 'FILE.py:FUNCTION' string"),
        ("def most_urgent(u, d):\n    return u / 0.0\n", '["rules/mine.py:most_urgent"]',
         "fails the check 'finite'"),
    ],
)  # fmt: skip
def test_bad_rule_files_name_the_study_file_and_key(tmp_path, rule, files, words):
    path = rule_study(tmp_path, rule, files)
    with pytest.raises(StudyError, match=r"^study\.toml: ") as caught:
        load_study(path)
    assert words in str(caught.value)
    assert "\n" not in str(caught.value)


def test_a_rule_study_runs_and_an_edited_rule_is_computed_afresh(tmp_path):
    path = rule_study(tmp_path)
    study = load_study(path)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BackendFallback)
        first = run_study(study, out_dir=tmp_path / "out", quick=True, workers=1)
    assert first.computed_runs == 3 * 2
    assert "most_urgent" in {c["condition"] for c in first.metrics["default"]["conditions"]}
    key = study_key(study, "default")
    assert key.code_version.endswith(f".rules-{study.rules_digest}")
    rule_study(tmp_path, "def most_urgent(urgency, distance):\n    return -urgency\n")
    edited = load_study(path)
    assert edited.rules_digest != study.rules_digest
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BackendFallback)
        again = run_study(edited, out_dir=tmp_path / "out", quick=True, workers=1)
    assert again.computed_runs == 3 * 2
    assert again.reused_runs == 0


def test_spawned_workers_load_the_rule_and_agree_with_one_process(tmp_path):
    study = load_study(rule_study(tmp_path))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BackendFallback)
        alone = run_study(study, out_dir=tmp_path / "one", quick=True, workers=1)
    spawned = run_study(study, out_dir=tmp_path / "two", quick=True, workers=2, backend="reference")
    assert spawned.metrics == alone.metrics


def test_python_conditions_run_in_worker_processes_with_one_note(tmp_path, capsys):
    from swarmtag.cli import main
    from swarmtag.sim.backends import fast_available

    if not fast_available():
        pytest.skip("the routing is from the compiled backend's threads")
    path = rule_study(tmp_path)
    with pytest.raises(SystemExit) as ended:
        main(["study", "run", str(path), "--quick", "--out", str(tmp_path / "out")])
    assert ended.value.code == 0
    err = capsys.readouterr().err
    assert err.count("swarmtag: note:") == 1
    assert "most_urgent: not compiled; their runs go to the reference backend" in err
