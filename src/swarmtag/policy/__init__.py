"""Carrier-selection policies (SPEC §3.3): the one place the formulas live.

A robot scores every available carrier it detects and fetches the best one:

- ``Proximity()`` scores ``u_d = 9 * (1 - min(d / 3.6, 1))`` (nearest wins);
- ``Urgency(alpha)`` scores ``u_c * (alpha + u_d)``;
- ``Weighted(w)`` scores ``w * u_c + (1 - w) * u_d``;
- ``Edf()`` scores ``u_c`` (earliest deadline first: urgency alone).

A rule of one's own is a Python function ``score(urgency, distance,
**context)`` (``ScoreRule``; ``load_rule("rules.py:FUNCTION")``, or a
package's entry point in the group ``swarmtag.policies``); ``check_rule``
says whether the simulator can trust it.

Exact ties go to the smaller distance, then the smaller marker id. The
simulator calls ``select`` on ``(runs, robots, carriers)`` arrays; the
behaviour tree calls ``choose`` on one robot's ``Candidate`` list. Policies
round-trip through their canonical condition names with ``parse_policy``.

>>> parse_policy("urgency:alpha=0.7")
Urgency(alpha=0.7)
>>> int(select(Proximity(), urgency=[9, 0], distance=[2.0, 1.0], marker=[3, 4]))
1
"""

from __future__ import annotations

from swarmtag.policy._allocators import (
    ADAPTIVE_START,
    CBAA_ALPHA,
    CLAIM_ALPHA,
    Adaptive,
    Allocator,
    Cbaa,
    ClaimFirst,
    Oracle,
    Threshold,
)
from swarmtag.policy._catalogue import CATALOGUE, RuleInfo
from swarmtag.policy._check import RuleCheck, check_rule, load_checked_rule
from swarmtag.policy._choose import Candidate, choose
from swarmtag.policy._kernel import (
    EDF_KIND,
    PROXIMITY_KIND,
    URGENCY_KIND,
    WEIGHTED_KIND,
)
from swarmtag.policy._kernel import checked_kernel_score as kernel_score
from swarmtag.policy._names import parse_policy
from swarmtag.policy._policies import Edf, Policy, Proximity, Urgency, Weighted
from swarmtag.policy._rules import (
    CONTEXT,
    RULE_GROUP,
    ScoreRule,
    load_rule,
    register_rule,
    registered_rule,
    rule_entry_points,
)
from swarmtag.policy._select import best_of, select
from swarmtag.policy._terms import PROXIMITY_RANGE, URGENCY_SCALE, proximity_term

__all__ = [
    "ADAPTIVE_START",
    "CATALOGUE",
    "CBAA_ALPHA",
    "CLAIM_ALPHA",
    "CONTEXT",
    "EDF_KIND",
    "PROXIMITY_KIND",
    "PROXIMITY_RANGE",
    "RULE_GROUP",
    "URGENCY_KIND",
    "URGENCY_SCALE",
    "WEIGHTED_KIND",
    "Adaptive",
    "Allocator",
    "Candidate",
    "Cbaa",
    "ClaimFirst",
    "Edf",
    "Oracle",
    "Policy",
    "Proximity",
    "RuleCheck",
    "RuleInfo",
    "ScoreRule",
    "Threshold",
    "Urgency",
    "Weighted",
    "best_of",
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
]
