"""Canonical condition names (SPEC §8.1) back into policies.

Names travel through event logs, the command line and study specs, so the
parser accepts the canonical form and a few forgiving spellings, and refuses
everything else with a message that lists what it accepts.
"""

from __future__ import annotations

import re
from typing import Final

from swarmtag.errors import PolicyError
from swarmtag.policy._catalogue import CATALOGUE, accepted_forms
from swarmtag.policy._policies import Edf, Policy, Proximity, Urgency, Weighted
from swarmtag.policy._rules import registered_rule

__all__ = ["parse_policy"]

_ACCEPTED: Final = accepted_forms()
_NAME: Final = re.compile(
    r"""\s*(?P<kind>[A-Za-z][A-Za-z0-9_]*)\s*
        (?: :\s*(?P<param>[A-Za-z]+)\s*=\s*(?P<value>\S+?)\s* )?""",
    re.VERBOSE,
)
# Decimal numbers as ``repr(float)`` writes them, plus integers: 0.7, 3, 1e-05, 1.5E+16.
_NUMBER: Final = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
_PARAMETER: Final = {info.name: info.parameter for info in CATALOGUE if info.parameter}
_PLAIN: Final[dict[str, type[Policy]]] = {"proximity": Proximity, "edf": Edf}
"""The rules without a parameter, by name."""


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
        msg = f"condition name: {checked!r} is not a string; {_ACCEPTED}"
        raise PolicyError(msg)
    match = _NAME.fullmatch(checked)
    if match is None:
        msg = f"condition name: cannot read {name!r}; {_ACCEPTED}"
        raise PolicyError(msg)
    kind = match["kind"].lower()
    param = match["param"]
    plain = _PLAIN.get(kind)
    if plain is not None:
        if param is None:
            return plain()
        msg = f"condition name: {kind} takes no parameter, got {name!r}; {_ACCEPTED}"
        raise PolicyError(msg)
    expected = _PARAMETER.get(kind)
    if expected is None:
        rule = registered_rule(match["kind"]) if param is None else None
        if rule is not None:
            return rule
        msg = f"condition name: unknown policy {match['kind']!r} in {name!r}; {_ACCEPTED}"
        raise PolicyError(msg)
    if param is None or param.lower() != expected:
        msg = f"condition name: {kind} takes one parameter {expected} in {name!r}; {_ACCEPTED}"
        raise PolicyError(msg)
    text = match["value"]
    if _NUMBER.fullmatch(text) is None:
        msg = f"{expected}: {text!r} in {name!r} is not a decimal number; {_ACCEPTED}"
        raise PolicyError(msg)
    value = float(text)
    try:
        return Urgency(alpha=value) if kind == "urgency" else Weighted(w=value)
    except PolicyError as exc:
        msg = f"{exc} (in condition name {name!r})"
        raise PolicyError(msg) from exc
