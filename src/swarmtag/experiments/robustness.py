"""The published directions over several master seeds: counts and verdicts (SPEC §4.6).

``judge_study`` judges every direction that names a study on one seed's
reports of it (one ``Outcome`` each); ``robustness`` gathers the outcomes of
all seeds into one ``ClaimSummary`` per direction and study: in how many
seeds the claim appears, in how many it is significant, and its ``verdict``.
A direction is *reproduced robustly* when it appears and is significant in
more than half of the seeds, *on some seeds* when it appears in at least
one, else *not reproduced*. Pure: reports in, records out.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from typing import Final

from swarmtag.analysis import MetricsReport
from swarmtag.experiments.directions import DIRECTIONS, Direction, Part

__all__ = [
    "NOT_REPRODUCED",
    "ROBUST",
    "SOME_SEEDS",
    "ClaimSummary",
    "Outcome",
    "PartCount",
    "judge_study",
    "robustness",
    "verdict",
]

ROBUST: Final = "reproduced robustly"
SOME_SEEDS: Final = "on some seeds"
NOT_REPRODUCED: Final = "not reproduced"


def verdict(appeared: int, significant: int, seeds: int) -> str:
    """``ROBUST`` if significant in most (more than half) of ``seeds``; else by appearance.

    A significant claim has also appeared (``Part.significant`` implies ``appears``).

    >>> verdict(10, 6, 10), verdict(10, 5, 10), verdict(0, 0, 10)
    ('reproduced robustly', 'on some seeds', 'not reproduced')
    """
    if 2 * significant > seeds:
        return ROBUST
    return SOME_SEEDS if appeared else NOT_REPRODUCED


@dataclass(frozen=True, kw_only=True)
class Outcome:
    """One direction in one study on one master seed: its parts and what they add up to."""

    direction: Direction
    study: str
    seed: int
    parts: tuple[Part, ...]

    @property
    def appears(self) -> bool:
        """Every part has the claimed sign."""
        return bool(self.parts) and all(part.appears for part in self.parts)

    @property
    def significant(self) -> bool:
        """Every part has the claimed sign and passes its test."""
        return bool(self.parts) and all(part.significant for part in self.parts)


def judge_study(
    study: str,
    seed: int,
    reports: Mapping[str, MetricsReport],
    directions: Sequence[Direction] = DIRECTIONS,
) -> tuple[Outcome, ...]:
    """Every direction naming ``study``, judged on its reports (scale -> report) at ``seed``.

    A direction its results cannot judge (a trend on a single scale) is left out.
    """
    outcomes = []
    for direction in directions:
        if study in direction.studies:
            parts = direction.judge(reports)
            if parts:
                outcomes.append(Outcome(direction=direction, study=study, seed=seed, parts=parts))
    return tuple(outcomes)


@dataclass(frozen=True, kw_only=True)
class PartCount:
    """One part of a claim (a condition at a scale) over the seeds: appeared and significant."""

    scale: str
    condition: str
    appeared: int
    significant: int


@dataclass(frozen=True, kw_only=True)
class ClaimSummary:
    """One direction in one study over the seeds: counts, verdict and every seed's outcome."""

    direction: Direction
    study: str
    outcomes: tuple[Outcome, ...]

    @property
    def seeds(self) -> tuple[int, ...]:
        """The master seeds judged, in run order."""
        return tuple(outcome.seed for outcome in self.outcomes)

    @property
    def appeared(self) -> int:
        """Seeds in which the claim appears."""
        return sum(outcome.appears for outcome in self.outcomes)

    @property
    def significant(self) -> int:
        """Seeds in which the claim appears and is significant."""
        return sum(outcome.significant for outcome in self.outcomes)

    @property
    def verdict(self) -> str:
        """``ROBUST``, ``SOME_SEEDS`` or ``NOT_REPRODUCED``."""
        return verdict(self.appeared, self.significant, len(self.outcomes))

    def parts(self) -> tuple[PartCount, ...]:
        """Each part's counts over the seeds, in the order the parts were judged."""
        counts: dict[tuple[str, str], list[int]] = {}
        for outcome in self.outcomes:
            for part in outcome.parts:
                count = counts.setdefault((part.scale, part.condition), [0, 0])
                count[0] += part.appears
                count[1] += part.significant
        return tuple(
            PartCount(scale=scale, condition=condition, appeared=a, significant=s)
            for (scale, condition), (a, s) in counts.items()
        )


def robustness(
    outcomes: Iterable[Outcome], directions: Sequence[Direction] = DIRECTIONS
) -> tuple[ClaimSummary, ...]:
    """The outcomes of every seed, one summary per direction and study (in ``directions`` order)."""
    grouped: dict[tuple[str, str], list[Outcome]] = {}
    for outcome in outcomes:
        grouped.setdefault((outcome.direction.name, outcome.study), []).append(outcome)
    order = {direction.name: index for index, direction in enumerate(directions)}

    def position(key: tuple[str, str]) -> tuple[int, int]:
        direction = grouped[key][0].direction
        studies = direction.studies
        return order.get(key[0], len(order)), studies.index(key[1])

    return tuple(
        ClaimSummary(direction=group[0].direction, study=group[0].study, outcomes=tuple(group))
        for key in sorted(grouped, key=position)
        for group in (grouped[key],)
    )
