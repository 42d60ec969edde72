"""Canonical condition names (SPEC §8.1) back into policies.

Names travel through event logs, the command line and study specs, so the
parser accepts the canonical form and a few forgiving spellings, and refuses
everything else with a message that lists what it accepts.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from typing import Final

from swarmtag._checks import show
from swarmtag.errors import PolicyError
from swarmtag.policy._allocators import Adaptive, Cbaa, ClaimFirst, Oracle, Threshold
from swarmtag.policy._catalogue import accepted_forms, rule_info
from swarmtag.policy._policies import Edf, Policy, Proximity, Urgency, Weighted
from swarmtag.policy._rules import registered_rule

__all__ = ["parse_policy"]

_ACCEPTED: Final = accepted_forms()
_NAME: Final = re.compile(
    r"""\s*(?P<kind>[A-Za-z][A-Za-z0-9_]*)\s*
        (?: :(?P<params>.*) )?""",
    re.VERBOSE | re.DOTALL,
)
_PARAMETER: Final = re.compile(r"\s*(?P<param>[A-Za-z_]+)\s*=\s*(?P<value>\S+?)\s*")
# Decimal numbers as ``repr(float)`` writes them, plus integers: 0.7, 3, 1e-05, 1.5E+16.
_NUMBER: Final = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_MAKERS: Final[dict[str, Callable[..., Policy]]] = {
    "proximity": Proximity,
    "urgency": Urgency,
    "edf": Edf,
    "weighted": Weighted,
    "threshold": Threshold,
    "oracle": Oracle,
    "cbaa": Cbaa,
    "claim": ClaimFirst,
    "adaptive": Adaptive,
}
"""Each catalogued rule's class, by name (called with its parameters as keywords)."""


def parse_policy(name: str) -> Policy:
    """Parse a condition name such as ``urgency:alpha=0.7`` into its policy.

    Accepts the canonical names and forgiving spellings of them: surrounding
    whitespace, any letter case in the words, integers for floats; and the
    names of score rules of one's own loaded in this process (``load_rule``)
    or offered by an installed package (``swarmtag.policies``). Raises
    ``PolicyError`` naming the text otherwise. ``parse_policy(p.name) == p``.

    >>> parse_policy("urgency:alpha=3")
    Urgency(alpha=3.0)
    >>> parse_policy(" Weighted : w = 0.3 ").name
    'weighted:w=0.3'
    """
    checked: object = name  # names also come from files and scripts, outside the type checker
    if not isinstance(checked, str):
        msg = f"condition name: {show(checked)} is not a string; {_ACCEPTED}"
        raise PolicyError(msg)
    match = _NAME.fullmatch(checked)
    if match is None:
        msg = f"condition name: cannot read {name!r}; {_ACCEPTED}"
        raise PolicyError(msg)
    kind = match["kind"].lower()
    info = rule_info(kind)
    if info is None:
        rule = registered_rule(match["kind"]) if match["params"] is None else None
        if rule is not None:
            return rule
        msg = f"condition name: unknown policy {match['kind']!r} in {name!r}; {_ACCEPTED}"
        raise PolicyError(msg)
    expected = info.parameter_names
    if match["params"] is None:
        given: dict[str, str] = {}
    else:
        given = _parameters(match["params"], name, kind, several=len(expected) > 1)
    if not expected and given:
        msg = f"condition name: {kind} takes no parameter, got {name!r}; {_ACCEPTED}"
        raise PolicyError(msg)
    if [key.lower() for key in given] != list(expected):
        wanted = (
            f"one parameter {expected[0]}"
            if len(expected) == 1
            else f"the parameters {', '.join(expected)}"
        )
        msg = f"condition name: {kind} takes {wanted} in {name!r}; {_ACCEPTED}"
        raise PolicyError(msg)
    values = {}
    for key, text in zip(expected, given.values(), strict=True):
        if _NUMBER.fullmatch(text) is None:
            msg = f"{key}: {text!r} in {name!r} is not a decimal number; {_ACCEPTED}"
            raise PolicyError(msg)
        values[key] = float(text)
    try:
        return _MAKERS[kind](**values)
    except PolicyError as exc:
        msg = f"{exc} (in condition name {name!r})"
        raise PolicyError(msg) from exc


def _parameters(text: str, name: str, kind: str, *, several: bool) -> dict[str, str]:
    """``{parameter: value text}`` of ``p=v`` (``several``: ``p=v,q=w``); else ``PolicyError``."""
    given: dict[str, str] = {}
    for part in text.split(",") if several else [text]:
        found = _PARAMETER.fullmatch(part)
        if found is None or found["param"].lower() in (key.lower() for key in given):
            msg = f"condition name: cannot read the parameters of {kind} in {name!r}; {_ACCEPTED}"
            raise PolicyError(msg)
        given[found["param"]] = found["value"]
    return given
