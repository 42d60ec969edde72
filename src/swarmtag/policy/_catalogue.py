"""What each selection rule is, in one place: its definition, parameters, reference, backends.

``swarmtag policies`` prints this catalogue and ``parse_policy`` takes the
accepted condition names from it, so a rule is described once. A rule is a
*score* (each robot ranks its own candidates) or, once there are any, an
*allocator* (it looks beyond one robot's view).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

__all__ = ["CATALOGUE", "RuleInfo", "accepted_forms", "rule_info"]


@dataclass(frozen=True)
class RuleInfo:
    """One selection rule as ``swarmtag policies`` lists it."""

    name: str
    """The condition name's first word (``urgency`` in ``urgency:alpha=0.7``)."""
    kind: str
    """``score``: a robot ranks its own candidates; ``allocator``: beyond one robot's view."""
    definition: str
    """What it does, with its formula."""
    parameter: str | None
    """Its one parameter's name, or None."""
    allowed: str
    """The parameter's allowed values (empty without one)."""
    reference: str
    """Where it comes from."""
    backends: tuple[str, ...]
    """The simulator's backends and controllers that run it."""
    communication: bool
    """Whether robots exchange messages for it."""

    @property
    def form(self) -> str:
        """The condition name's form, e.g. ``urgency:alpha=A``."""
        if self.parameter is None:
            return self.name
        return f"{self.name}:{self.parameter}={self.parameter[0].upper()}"


_EVERYWHERE: Final = ("reference", "fast", "bt")

CATALOGUE: Final[tuple[RuleInfo, ...]] = (
    RuleInfo(
        name="proximity",
        kind="score",
        definition="u_d = 9 * (1 - min(d / 3.6, 1)): the nearest carrier; urgency ignored",
        parameter=None,
        allowed="",
        reference="the published study's baseline (docs/policy.md)",
        backends=_EVERYWHERE,
        communication=False,
    ),
    RuleInfo(
        name="urgency",
        kind="score",
        definition="u_c * (alpha + u_d): urgency weighed with nearness; larger alpha, urgency",
        parameter="alpha",
        allowed="a finite number > 0",
        reference="the published study's urgency-aware policy (docs/policy.md)",
        backends=_EVERYWHERE,
        communication=False,
    ),
    RuleInfo(
        name="edf",
        kind="score",
        definition="u_c: earliest deadline first, the most urgent carrier; ties to the nearer",
        parameter=None,
        allowed="",
        reference="Liu and Layland, J. ACM 1973; here the ablation of urgency alone",
        backends=_EVERYWHERE,
        communication=False,
    ),
    RuleInfo(
        name="weighted",
        kind="score",
        definition="w * u_c + (1 - w) * u_d: 0 ranks like proximity, 1 by urgency alone",
        parameter="w",
        allowed="0 <= W <= 1",
        reference="the published study's preliminary sweep (docs/policy.md)",
        backends=_EVERYWHERE,
        communication=False,
    ),
)
"""Every selection rule, in the order ``swarmtag policies`` lists them."""


def rule_info(name: str) -> RuleInfo | None:
    """The catalogue entry of condition-name word ``name`` (any case), or None."""
    for info in CATALOGUE:
        if info.name == name.lower():
            return info
    return None


def accepted_forms() -> str:
    """The condition names ``parse_policy`` accepts, for its error messages.

    >>> accepted_forms()[:59]
    "accepted forms: 'proximity', 'urgency:alpha=A' (A a finite "
    """
    forms = [
        f"'{info.form}'" + (f" ({_described(info)})" if info.parameter else "")
        for info in CATALOGUE
    ]
    return "accepted forms: " + ", ".join(forms)


def _described(info: RuleInfo) -> str:
    """``A a finite number > 0`` or ``0 <= W <= 1``: the allowed values, named by the letter."""
    letter = (info.parameter or "")[:1].upper()
    return info.allowed if letter in info.allowed else f"{letter} {info.allowed}"
