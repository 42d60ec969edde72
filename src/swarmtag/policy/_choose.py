"""One robot's choice from a list of candidates, for the behaviour-tree controller.

A thin wrapper over ``select``: the formulas and the tie rule exist once.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from numbers import Integral, Real

import numpy as np

from swarmtag._checks import check_instance, check_sequence
from swarmtag.errors import PolicyError
from swarmtag.policy._policies import Policy
from swarmtag.policy._select import select

__all__ = ["Candidate", "choose"]


@dataclass(frozen=True, slots=True)
class Candidate:
    """A carrier one robot can pick: detected and advertising ``AWAITING_PICKUP``.

    ``marker`` is the carrier's marker id, ``urgency`` its advertised urgency
    (0-9), ``distance`` the robot-to-carrier distance in metres. Types are
    checked here (``PolicyError``); ranges are checked by ``choose``.
    """

    marker: int
    urgency: int
    distance: float

    def __post_init__(self) -> None:
        for name, kind, allowed in (
            ("marker", Integral, "an integer"),
            ("urgency", Integral, "an integer 0-9"),
            ("distance", Real, "a number of metres >= 0"),
        ):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, kind):
                msg = f"{name}: {value!r} must be {allowed}"
                raise PolicyError(msg)


def choose(policy: Policy, candidates: Sequence[Candidate]) -> Candidate | None:
    """The candidate ``policy`` picks, or ``None`` for an empty list.

    Same scores and tie rule as ``select`` (which it calls); raises
    ``PolicyError`` on bad values.

    >>> from swarmtag.policy import Urgency
    >>> near, far = Candidate(marker=4, urgency=1, distance=0.9), Candidate(7, 9, 2.7)
    >>> choose(Urgency(alpha=0.7), [near, far])
    Candidate(marker=7, urgency=9, distance=2.7)
    >>> choose(Urgency(alpha=0.7), []) is None
    True
    """
    for candidate in check_sequence("candidates", candidates, error=PolicyError):
        check_instance("candidates", candidate, Candidate, error=PolicyError)
    try:
        marker = np.array([c.marker for c in candidates], dtype=np.int64)
    except OverflowError as exc:
        msg = f"marker: a marker id does not fit in 64 bits ({exc})"
        raise PolicyError(msg) from exc
    index = select(
        policy,
        urgency=np.array([c.urgency for c in candidates], dtype=np.float64),
        distance=np.array([c.distance for c in candidates], dtype=np.float64),
        marker=marker,
    )
    chosen = int(index)
    return None if chosen < 0 else candidates[chosen]
