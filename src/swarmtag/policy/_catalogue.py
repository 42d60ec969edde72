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
    parameters: tuple[tuple[str, str], ...]
    """Its parameters in condition-name order: ``(name, allowed values)`` each."""
    reference: str
    """Where it comes from."""
    backends: tuple[str, ...]
    """The simulator's backends and controllers that run it."""
    communication: bool
    """Whether robots exchange messages for it."""

    @property
    def form(self) -> str:
        """The condition name's form, e.g. ``urgency:alpha=A`` or ``cbaa:comm_range=C,loss=L``."""
        if not self.parameters:
            return self.name
        listed = ",".join(f"{name}={_letter(name)}" for name, _ in self.parameters)
        return f"{self.name}:{listed}"

    @property
    def parameter_names(self) -> tuple[str, ...]:
        """The parameters' names, in condition-name order."""
        return tuple(name for name, _ in self.parameters)


def _letter(parameter: str) -> str:
    """The placeholder of ``parameter`` in a form: its first letter, upper case."""
    return parameter[0].upper()


_EVERYWHERE: Final = ("reference", "fast", "bt")
_REFERENCE: Final = ("reference",)
_POSITIVE: Final = "a finite number > 0"

CATALOGUE: Final[tuple[RuleInfo, ...]] = (
    RuleInfo(
        name="proximity",
        kind="score",
        definition="u_d = 9 * (1 - min(d / 3.6, 1)): the nearest carrier; urgency ignored",
        parameters=(),
        reference="the published study's baseline (docs/policy.md)",
        backends=_EVERYWHERE,
        communication=False,
    ),
    RuleInfo(
        name="urgency",
        kind="score",
        definition="u_c * (alpha + u_d): urgency weighed with nearness; larger alpha, urgency",
        parameters=(("alpha", _POSITIVE),),
        reference="the published study's urgency-aware policy (docs/policy.md)",
        backends=_EVERYWHERE,
        communication=False,
    ),
    RuleInfo(
        name="edf",
        kind="score",
        definition="u_c: earliest deadline first, the most urgent carrier; ties to the nearer",
        parameters=(),
        reference="Liu and Layland, J. ACM 1973; here the ablation of urgency alone",
        backends=_EVERYWHERE,
        communication=False,
    ),
    RuleInfo(
        name="weighted",
        kind="score",
        definition="w * u_c + (1 - w) * u_d: 0 ranks like proximity, 1 by urgency alone",
        parameters=(("w", "0 <= W <= 1"),),
        reference="the published study's preliminary sweep (docs/policy.md)",
        backends=_EVERYWHERE,
        communication=False,
    ),
    RuleInfo(
        name="threshold",
        kind="allocator",
        definition="take each candidate w.p. T(s) = s^2 / (s^2 + theta^2), s = u_c + 1; "
        "the nearest taken; a declined one is passed over for the cooldown",
        parameters=(("theta", _POSITIVE),),
        reference="response threshold: Bonabeau, Theraulaz and Deneubourg, Proc. R. Soc. B 1996",
        backends=_REFERENCE,
        communication=False,
    ),
    RuleInfo(
        name="oracle",
        kind="allocator",
        definition="central assignment of idle robots to waiting carriers with global "
        "knowledge, maximising the summed u_c * (alpha + u_d); re-solved each tick",
        parameters=(("alpha", _POSITIVE),),
        reference="optimal assignment: Kuhn, Naval Res. Logist. Q. 1955 (scipy)",
        backends=_REFERENCE,
        communication=False,
    ),
    RuleInfo(
        name="cbaa",
        kind="allocator",
        definition="consensus-based auction: bid u_c * (0.7 + u_d) on the best candidate, "
        "share winning bids with robots in comm_range (each message lost w.p. loss)",
        parameters=(("comm_range", "metres, a finite number > 0"), ("loss", "0 <= L < 1")),
        reference="CBAA: Choi, Brunet and How, IEEE T-RO 2009",
        backends=_REFERENCE,
        communication=True,
    ),
    RuleInfo(
        name="claim",
        kind="allocator",
        definition="u_c * (0.7 + u_d), and the chosen carrier claimed through its tag for "
        "hold s (a write lost w.p. loss); carriers another robot holds are passed over",
        parameters=(("hold", "seconds, 1 <= H <= 255"), ("loss", "0 <= L < 1")),
        reference="this project: the tag protocol's claim extension (docs/tag-protocol.md)",
        backends=_REFERENCE,
        communication=True,
    ),
    RuleInfo(
        name="adaptive",
        kind="allocator",
        definition="u_c * (alpha_r + u_d), each robot's alpha_r lowered by gain on each race "
        "it loses, drawn back to 0.7 by gain on each lift",
        parameters=(("gain", "0 < G <= 1"),),
        reference="this project (docs/allocators.md)",
        backends=_REFERENCE,
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
        f"'{info.form}'" + (f" ({_described(info)})" if info.parameters else "")
        for info in CATALOGUE
    ]
    return "accepted forms: " + ", ".join(forms)


def _described(info: RuleInfo) -> str:
    """``A a finite number > 0`` or ``0 <= W <= 1``: the allowed values, named by their letters."""
    parts = []
    for name, allowed in info.parameters:
        letter = _letter(name)
        parts.append(allowed if letter in allowed.split() else f"{letter} {allowed}")
    return "; ".join(parts)
