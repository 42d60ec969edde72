"""``check_rule``: each way a rule of one's own can be untrustworthy is caught, in one line."""

from __future__ import annotations

from pathlib import Path

import pytest

from swarmtag.policy import check_rule, load_rule

EXAMPLES = Path(__file__).with_name("rule_examples.py")
CHECKS = ["runs", "finite", "deterministic", "elementwise", "no wall clock"]


def failures(name: str) -> dict[str, str]:
    checks = check_rule(load_rule(f"{EXAMPLES}:{name}"))
    return {check.name: check.detail for check in checks if not check.passed}


@pytest.mark.parametrize("name", ["most_urgent", "urgency_first", "oldest_first", "everything"])
def test_good_rules_pass_every_check(name):
    checks = check_rule(load_rule(f"{EXAMPLES}:{name}"))
    assert [check.name for check in checks] == CHECKS
    assert all(check.passed for check in checks)


@pytest.mark.parametrize(
    ("name", "check", "detail"),
    [
        ("raises", "runs", "raised ValueError: no score today"),
        ("nan_scores", "finite", "returned a score of nan"),
        ("drifting", "deterministic", "scored"),
        ("ranked", "elementwise", "one candidate alone"),
        ("normalised", "elementwise", "alone but"),
        ("clocked", "no wall clock", "it reads the clock (time.monotonic)"),
    ],
)
def test_each_failure_is_named_in_one_line(name, check, detail):
    failed = failures(name)
    # state kept between calls also breaks the one-at-a-time comparison
    assert list(failed) == ([check, "elementwise"] if name == "drifting" else [check])
    assert detail in failed[check]
    assert "\n" not in failed[check]


def test_a_module_holding_a_clock_function_fails(tmp_path):
    source = tmp_path / "sneaky.py"
    source.write_text("from time import perf_counter as now\n\ndef sneaky(u, d):\n    return u\n")
    checks = check_rule(load_rule(f"{source}:sneaky"))
    failed = {check.name: check.detail for check in checks if not check.passed}
    assert failed == {"no wall clock": "its module holds time.perf_counter as 'now'"}
