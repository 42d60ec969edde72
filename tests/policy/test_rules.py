"""Score rules of one's own: loading, the call contract, condition names, entry points."""

from __future__ import annotations

from importlib.metadata import EntryPoint
from pathlib import Path

import numpy as np
import pytest

from swarmtag.errors import PolicyError
from swarmtag.policy import (
    CONTEXT,
    RULE_GROUP,
    Edf,
    ScoreRule,
    _rules,
    load_rule,
    parse_policy,
    registered_rule,
    select,
)

EXAMPLES = Path(__file__).with_name("rule_examples.py")


def rule(name: str) -> ScoreRule:
    return load_rule(f"{EXAMPLES}:{name}")


def test_a_file_rule_is_a_condition_named_after_its_function():
    loaded = rule("urgency_first")
    assert loaded.name == "urgency_first"
    assert not loaded.compiled
    assert parse_policy("urgency_first") is loaded
    assert parse_policy(" urgency_first ") is loaded
    with pytest.raises(PolicyError, match="no compiled form"):
        _ = loaded.kernel_form


def test_loading_twice_and_by_another_path_gives_the_same_rule(tmp_path, monkeypatch):
    monkeypatch.chdir(EXAMPLES.parent)
    assert load_rule("rule_examples.py:most_urgent") is rule("most_urgent")
    assert load_rule(f"{EXAMPLES.name}:most_urgent", base=EXAMPLES.parent) is rule("most_urgent")


def test_another_function_under_a_registered_name_is_refused(tmp_path):
    other = tmp_path / "other.py"
    other.write_text("def urgency_first(urgency, distance):\n    return -urgency\n")
    rule("urgency_first")
    with pytest.raises(PolicyError, match="already the rule from"):
        load_rule(f"{other}:urgency_first")


def test_scores_are_the_functions_and_select_uses_them():
    chosen = select(
        rule("urgency_first"),
        urgency=[3, 9, 9],
        distance=[0.1, 2.0, 1.0],
        marker=[5, 6, 7],
    )
    assert int(chosen) == 2  # urgency 9, the nearer of the two
    edf = select(Edf(), urgency=[3, 9, 9], distance=[0.1, 2.0, 1.0], marker=[5, 6, 7])
    assert int(select(rule("most_urgent"), urgency=[3, 9, 9], distance=[0.1, 2.0, 1.0],
                      marker=[5, 6, 7])) == int(edf)  # fmt: skip


def test_context_reaches_the_rule_by_name():
    assert rule("oldest_first").context_names == ("age",)
    assert rule("by_marker").context_names == ("marker",)
    assert rule("everything").context_names == CONTEXT
    scene = {"urgency": [9, 0, 4], "distance": [1.0, 1.0, 1.0], "marker": [8, 3, 5]}
    assert int(select(rule("oldest_first"), **scene, context={"age": [10.0, 300.0, 20.0]})) == 1
    assert int(select(rule("by_marker"), **scene)) == 1
    with pytest.raises(PolicyError, match="asks for 'age', not given here"):
        select(rule("oldest_first"), **scene)


def test_a_batch_of_runs_and_robots_is_scored_in_one_call():
    urgency = np.arange(24, dtype=float).reshape(2, 3, 4) % 10
    chosen = select(rule("urgency_first"), urgency=urgency, distance=1.0, marker=np.arange(4))
    assert chosen.shape == (2, 3)
    assert np.array_equal(chosen, np.argmax(urgency, axis=-1))


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("nan_scores", "returned a score of nan; scores are finite"),
        ("raises", "raised ValueError: no score today"),
    ],
)
def test_bad_scores_are_one_line_naming_the_rule(name, message):
    with pytest.raises(PolicyError, match=message) as caught:
        select(rule(name), urgency=[1, 2], distance=[1.0, 2.0], marker=[0, 1])
    assert "\n" not in str(caught.value)
    assert f"rule {name!r} ({EXAMPLES}:{name})" in str(caught.value)


def test_a_wrong_shape_is_refused():
    shaped = ScoreRule.make("shaped", lambda u, d: np.zeros(3), "test")
    with pytest.raises(PolicyError, match=r"returned shape \(3,\) for \(2,\) candidates"):
        select(shaped, urgency=[1, 2], distance=[1.0, 2.0], marker=[0, 1])


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("missing.py:f", "missing.py: no such file"),
        ("rules.txt:f", "a rule file is a Python file ending in .py"),
        ("rules.py", "is not FILE.py:FUNCTION"),
        ("syntax.py:f", r"syntax.py: line 2: "),
        ("importing.py:f", "importing it raised ZeroDivisionError"),
        ("good.py:nothere", r"no function 'nothere' \(it defines: good\)"),
        ("good.py:CONSTANT", "is not a function"),
    ],
)
def test_bad_rule_files_are_one_line_naming_the_file(tmp_path, monkeypatch, text, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rules.txt").write_text("")
    (tmp_path / "syntax.py").write_text("def f(u, d):\n    return u +\n")
    (tmp_path / "importing.py").write_text("X = 1 / 0\n")
    (tmp_path / "good.py").write_text("CONSTANT = 3\n\ndef good(u, d):\n    return u\n")
    with pytest.raises(PolicyError, match=message) as caught:
        load_rule(text)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize(
    ("name", "message"),
    [
        ("one_argument", r"a rule takes \(urgency, distance, \*\*context\)"),
        ("wants_more", "missing a required argument: 'battery'"),
        ("edf", "'edf' is a built-in rule's name"),
    ],
)
def test_signatures_a_rule_cannot_have_are_refused(name, message):
    with pytest.raises(PolicyError, match=message):
        rule(name)


def test_entry_points_register_rules_by_name(monkeypatch):
    point = EntryPoint(
        name="registered_fifo",
        value="tests.policy.rule_examples:oldest_first",
        group=RULE_GROUP,
    )
    broken = EntryPoint(name="broken_rule", value="tests.policy.no_such_module:f", group=RULE_GROUP)

    def found(*, group: str) -> list[EntryPoint]:
        return [point, broken] if group == RULE_GROUP else []

    monkeypatch.setattr(_rules, "entry_points", found)
    monkeypatch.setattr(_rules, "_REGISTERED", {})
    loaded = parse_policy("registered_fifo")
    assert isinstance(loaded, ScoreRule)
    assert loaded.source == "entry point tests.policy.rule_examples:oldest_first"
    assert loaded.context_names == ("age",)
    assert registered_rule("registered_fifo") is loaded
    assert _rules.rule_entry_points() == (
        ("broken_rule", "tests.policy.no_such_module:f"),
        ("registered_fifo", "tests.policy.rule_examples:oldest_first"),
    )
    with pytest.raises(PolicyError, match=r"'broken_rule': its entry point .* failed to load"):
        parse_policy("broken_rule")
    with pytest.raises(PolicyError, match="unknown policy 'nobody'"):
        parse_policy("nobody")
