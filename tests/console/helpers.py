"""A small live console for the tests: 3 robots, 7 carriers of the default profile."""

from __future__ import annotations

from pathlib import Path

from swarmtag.cli._scenario import build_scenario
from swarmtag.console import ConsoleCore, ConsoleSettings, build_core
from swarmtag.policy import parse_policy


def settings(tmp_path: Path, **overrides: object) -> ConsoleSettings:
    values: dict[str, object] = {
        "scenario": build_scenario(profile="paper-sim", config=None, flags={}),
        "policy": parse_policy("urgency:alpha=0.7"),
        "audit_log": tmp_path / "audit.jsonl",
        "counter_file": tmp_path / "operator.counters",
        "speed": 5.0,
    }
    values.update(overrides)
    return ConsoleSettings(**values)  # type: ignore[arg-type]


def core(tmp_path: Path, **overrides: object) -> ConsoleCore:
    return build_core(settings(tmp_path, **overrides))
