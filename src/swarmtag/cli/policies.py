"""``swarmtag policies`` and ``swarmtag policy check``: the selection rules, built in and own."""

from __future__ import annotations

import inspect

import click
from rich.table import Table

from swarmtag.cli._console import make_console
from swarmtag.errors import PolicyError
from swarmtag.policy import (
    CATALOGUE,
    CONTEXT,
    check_rule,
    load_rule,
    registered_rule,
    rule_entry_points,
)

__all__ = ["policies_cmd", "policy_group"]

_OWN_BACKENDS = "reference, bt (fast: falls back to reference)"


@click.command("policies")
def policies_cmd() -> None:
    """List the selection rules: name, kind, definition, parameter, reference, backends.

    A condition name is the rule's name with its parameter, e.g.
    ``--condition urgency:alpha=0.7`` (docs/policy.md). A rule of one's own
    runs with ``--policy-file FILE.py:FUNCTION``; packages register rules
    under the entry-point group ``swarmtag.policies``.
    """
    table = Table(title="Selection rules (conditions: NAME or NAME:PARAMETER=VALUE)")
    for column in ("name", "kind", "definition", "parameter", "reference", "runs on", "talks"):
        table.add_column(column, overflow="fold")
    for info in CATALOGUE:
        parameter = "; ".join(f"{name}: {allowed}" for name, allowed in info.parameters) or "-"
        table.add_row(
            info.form,
            info.kind,
            info.definition,
            parameter,
            info.reference,
            ", ".join(info.backends),
            "yes" if info.communication else "no",
        )
    for name, target in rule_entry_points():
        table.add_row(name, "score", _summary(name), "-", f"package: {target}", _OWN_BACKENDS, "no")
    table.add_row(
        "FUNCTION",
        "score",
        f"your score(urgency, distance, **context) from --policy-file FILE.py:FUNCTION "
        f"(context: {', '.join(CONTEXT)})",
        "-",
        "docs/policy.md (rules of one's own)",
        _OWN_BACKENDS,
        "no",
    )
    make_console().print(table)


def _summary(name: str) -> str:
    """The first line of a registered rule's docstring, or why it cannot be shown."""
    try:
        rule = registered_rule(name)
    except PolicyError as exc:
        return f"cannot be loaded: {exc}"
    doc = inspect.getdoc(rule.function) if rule is not None else None
    return (doc or "a registered score rule").splitlines()[0]


@click.group("policy")
def policy_group() -> None:
    """Work with score rules of one's own (docs/policy.md)."""


@policy_group.command("check")
@click.argument("spec", metavar="FILE.py:FUNCTION")
def check_cmd(spec: str) -> None:
    """Check a score rule: it runs, scores are finite, deterministic, elementwise, no clock.

    Prints one line per check; exits 2 naming the failures if any.
    """
    rule = load_rule(spec)
    checks = check_rule(rule)
    for check in checks:
        mark = "ok  " if check.passed else "FAIL"
        click.echo(f"{mark} {check.name}" + (f": {check.detail}" if check.detail else ""))
    failed = [check.name for check in checks if not check.passed]
    if failed:
        msg = f"{spec}: the rule fails {len(failed)} check(s): {', '.join(failed)}"
        raise PolicyError(msg)
    click.echo(f"{spec}: condition {rule.name!r} can run (reference backend and bt)")
