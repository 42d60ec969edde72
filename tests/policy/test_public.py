"""The public surface of swarmtag.policy, its doctests, and docs/policy.md's examples."""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

import swarmtag.policy

DOCS = Path(__file__).resolve().parents[2] / "docs" / "policy.md"
PUBLIC = {
    "ADAPTIVE_START",
    "CATALOGUE",
    "CBAA_ALPHA",
    "CLAIM_ALPHA",
    "Adaptive",
    "Allocator",
    "Cbaa",
    "ClaimFirst",
    "Oracle",
    "Threshold",
    "best_of",
    "CONTEXT",
    "EDF_KIND",
    "PROXIMITY_KIND",
    "PROXIMITY_RANGE",
    "RULE_GROUP",
    "URGENCY_KIND",
    "URGENCY_SCALE",
    "WEIGHTED_KIND",
    "Candidate",
    "Edf",
    "Policy",
    "Proximity",
    "RuleCheck",
    "RuleInfo",
    "ScoreRule",
    "Urgency",
    "Weighted",
    "check_rule",
    "choose",
    "kernel_score",
    "load_checked_rule",
    "load_rule",
    "parse_policy",
    "proximity_term",
    "register_rule",
    "registered_rule",
    "rule_entry_points",
    "select",
}


def test_all_is_exactly_the_public_api():
    assert set(swarmtag.policy.__all__) == PUBLIC
    assert len(swarmtag.policy.__all__) == len(PUBLIC)
    public_names = {name for name in vars(swarmtag.policy) if not name.startswith("_")}
    modules = {"annotations"}  # from __future__
    assert public_names - modules == PUBLIC


@pytest.mark.parametrize("name", sorted(PUBLIC))
def test_public_objects_have_docstrings(name):
    obj = getattr(swarmtag.policy, name)
    if callable(obj):
        assert obj.__doc__
        assert obj.__doc__.strip()


@pytest.mark.parametrize(
    "module",
    [
        "swarmtag.policy",
        "swarmtag.policy._terms",
        "swarmtag.policy._policies",
        "swarmtag.policy._names",
        "swarmtag.policy._select",
        "swarmtag.policy._choose",
        "swarmtag.policy._catalogue",
    ],
)
def test_module_doctests(module):
    result = doctest.testmod(importlib.import_module(module))
    assert result.failed == 0


def test_docs_examples():
    result = doctest.testfile(str(DOCS), module_relative=False)
    assert result.attempted > 0
    assert result.failed == 0
