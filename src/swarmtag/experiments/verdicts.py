"""The answer the report opens with: each published claim on this run, and a quick run's banner.

Every direction (``DIRECTIONS``) is judged per study exactly as over
several master seeds (``judge_study``), here on the report's own seed, and
gets one verdict:

- **reproduced**: every part (condition and swarm size) has the claimed
  sign and passes its test (``Part.significant``);
- **not reproduced (sign only)**: every part has the claimed sign (for a
  "close" claim: an estimate within the margin), not every part passes;
- **not reproduced**: some part has the wrong sign (or is out of the margin);
- **underpowered**: the study has fewer than ``MIN_RUNS`` runs per
  condition, too few for either verdict (a quick run).

Pure: reports in, records and HTML out.
"""

from __future__ import annotations

import html
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Final

from swarmtag.analysis import MetricsReport
from swarmtag.analysis.compare import MIN_RUNS
from swarmtag.analysis.html import Section
from swarmtag.analysis.tables import format_p_value
from swarmtag.experiments.directions import (
    CLOSE_MARGIN,
    DIRECTIONS,
    SIGNIFICANCE,
    Direction,
    Part,
    short_condition,
)
from swarmtag.experiments.robustness import NOT_REPRODUCED, Outcome, judge_study

__all__ = [
    "NOT_REPRODUCED",
    "REPRODUCED",
    "SIGN_ONLY",
    "UNDERPOWERED",
    "ClaimVerdict",
    "claim_verdict",
    "judge_reports",
    "quick_banner",
    "verdict_section",
]

REPRODUCED: Final = "reproduced"
SIGN_ONLY: Final = "not reproduced (sign only)"
UNDERPOWERED: Final = "underpowered"
_CLASSES: Final = {
    REPRODUCED: "v-reproduced",
    SIGN_ONLY: "v-sign",
    NOT_REPRODUCED: "v-not",
    UNDERPOWERED: "v-under",
}
"""The style of each verdict's cell (``swarmtag.analysis.html``)."""
_HEADER: Final = (
    "Claim",
    "Study",
    "Verdict",
    "Published",
    "Part",
    "Ours: difference [95 % CI]",
    "p (bootstrap)",
)
"""The verdict comes third, so that a narrow screen shows it before the table scrolls."""
_ARROW: Final = " \N{RIGHTWARDS ARROW} "


def claim_verdict(*, appears: bool, significant: bool, runs: int) -> str:
    """The verdict on a claim that ``appears`` (and is ``significant``) with ``runs`` per condition.

    >>> claim_verdict(appears=True, significant=True, runs=100)
    'reproduced'
    >>> claim_verdict(appears=True, significant=False, runs=10)
    'not reproduced (sign only)'
    >>> claim_verdict(appears=True, significant=True, runs=9)
    'underpowered'
    """
    if runs < MIN_RUNS:
        return UNDERPOWERED
    if significant:
        return REPRODUCED
    return SIGN_ONLY if appears else NOT_REPRODUCED


@dataclass(frozen=True, kw_only=True)
class ClaimVerdict:
    """One direction in one study on one seed: its parts, the runs behind them, the verdict."""

    outcome: Outcome
    runs: int
    """The fewest runs of any condition at any scale of the study."""
    resamples: int
    """Bootstrap resamples behind the parts (for the p-values' resolution)."""

    @property
    def direction(self) -> Direction:
        """The claim."""
        return self.outcome.direction

    @property
    def verdict(self) -> str:
        """``REPRODUCED``, ``SIGN_ONLY``, ``NOT_REPRODUCED`` or ``UNDERPOWERED``."""
        return claim_verdict(
            appears=self.outcome.appears, significant=self.outcome.significant, runs=self.runs
        )

    @property
    def label(self) -> str:
        """The verdict as shown; an underpowered claim also says whether it appears."""
        if self.verdict != UNDERPOWERED:
            return self.verdict
        shown = "appears" if self.outcome.appears else "does not appear"
        return f"{UNDERPOWERED} ({self.runs} runs; {shown})"


def judge_reports(
    study: str,
    seed: int,
    reports: Mapping[str, MetricsReport],
    directions: Sequence[Direction] = DIRECTIONS,
) -> tuple[ClaimVerdict, ...]:
    """Every direction naming ``study``, judged on its reports (scale -> report) at ``seed``."""
    if not reports:
        return ()
    runs = min(c.kpis.runs for report in reports.values() for c in report.conditions)
    resamples = min(report.n_resamples for report in reports.values())
    return tuple(
        ClaimVerdict(outcome=outcome, runs=runs, resamples=resamples)
        for outcome in judge_study(study, seed, reports, directions)
    )


def _part_label(part: Part) -> str:
    scale = "" if part.scale == "default" else part.scale.replace("->", _ARROW)
    condition = short_condition(part.condition)
    return f"{condition}, {scale}" if scale else condition


def _ours(claim: ClaimVerdict, part: Part) -> str:
    show = claim.direction.rule.show
    if part.value is None:
        return "n/a"
    low, high = part.interval.low, part.interval.high
    interval = "" if low is None or high is None else f" [{show(low)}, {show(high)}]"
    return show(part.value) + interval


def _p(claim: ClaimVerdict, part: Part) -> str:
    if part.p_bootstrap is None:
        return "- (CI test)"  # a "close" claim: judged by its interval
    return format_p_value(part.p_bootstrap, claim.resamples)


def _cell(text: str, *, rows: int = 1, css: str = "") -> str:
    span = f' rowspan="{rows}"' if rows > 1 else ""
    kind = f' class="{css}"' if css else ""
    return f"<td{span}{kind}>{html.escape(text)}</td>"


def _rows(claim: ClaimVerdict) -> list[str]:
    """The claim's rows: one per part; claim, study, published and verdict span them all."""
    parts = claim.outcome.parts
    direction, study = claim.direction, claim.outcome.study
    rows = []
    for index, part in enumerate(parts):
        cells = []
        if index == 0:
            cells += [
                _cell(direction.text, rows=len(parts), css="claim"),
                _cell(study, rows=len(parts)),
                _cell(claim.label, rows=len(parts), css=_CLASSES[claim.verdict]),
                _cell(direction.published_in(study).describe(direction.rule), rows=len(parts)),
            ]
        cells += [
            _cell(_part_label(part), css="part"),
            _cell(_ours(claim, part), css="num"),
            _cell(_p(claim, part), css="num"),
        ]
        rows.append("<tr>" + "".join(cells) + "</tr>")
    return rows


def _table(claims: Sequence[ClaimVerdict]) -> str:
    head = "".join(f"<th>{html.escape(h)}</th>" for h in _HEADER)
    body = "".join(row for claim in claims for row in _rows(claim))
    return f'<table class="verdicts"><thead><tr>{head}</tr></thead><tbody>{body}</tbody></table>'


def _tally(claims: Sequence[ClaimVerdict]) -> str:
    counts = dict.fromkeys(_CLASSES, 0)
    for claim in claims:
        counts[claim.verdict] += 1
    found = ", ".join(f"{n} {verdict}" for verdict, n in counts.items() if n)
    seeds = sorted({claim.outcome.seed for claim in claims})
    on = f"master seed {seeds[0]}" if len(seeds) == 1 else "each study's own master seed"
    return f"{len(claims)} published claims judged on {on}: {found}."


_RULES: Final = (
    "Each row is a published direction (docs/reproduction.md) in one study, against the "
    "study's baseline; its parts are the conditions (and swarm sizes) it covers, each "
    "shown as its difference (condition - baseline; % and pp: relative to the baseline, "
    "pp its change from the smallest to the largest swarm) with the 95 % bootstrap CI. "
    "Reproduced: every part has "
    f"the claimed sign and a bootstrap p below {SIGNIFICANCE:g} (for 'close to the baseline': "
    f"the 95 % CI within \N{PLUS-MINUS SIGN}{CLOSE_MARGIN * 100:g} %). Not reproduced (sign "
    "only): every part has the claimed sign (or lies within the margin), not every part is "
    "significant. Not reproduced: some part has the wrong sign. Underpowered: fewer than "
    f"{MIN_RUNS} runs per condition, no verdict either way. Published: the physical trials' "
    "Table II (15-17 runs per condition); the simulation studies publish the directions only."
)


def verdict_section(claims: Sequence[ClaimVerdict]) -> Section:
    """The report's first section: the tally, then one row group per claim, then the rules."""
    title = "Do the published findings reproduce?"
    if not claims:
        note = "No published direction names these studies (they are judged in the shipped five)."
        return Section(title=title, paragraphs=[note])
    rules = f'<p class="note">{html.escape(_RULES)}</p>'
    return Section(title=title, paragraphs=[_tally(claims)], tables_html=[_table(claims), rules])


def quick_banner(runs: Mapping[str, int], full: Mapping[str, int]) -> str:
    """The warning atop a quick run's report: its runs per study, and how to get the full ones.

    ``runs``: each study's runs per condition in this report; ``full``: those
    of its full run. Backticked text is shown as code.
    """
    return (
        f"Quick run: {_counts(runs)}. Verdicts are underpowered where a study has fewer than "
        f"{MIN_RUNS} and rest on few runs elsewhere. For the full reproduction, "
        f"{_counts(full)}, run `swarmtag reproduce`."
    )


def _counts(runs: Mapping[str, int]) -> str:
    """``N-M runs per condition (each study's)``; one count for all: ``100 runs per condition``.

    >>> _counts({"a": 100, "b": 100, "c": 16}).replace("\N{EN DASH}", "-")
    '16-100 runs per condition (a 100, b 100, c 16)'
    """
    fewest, most = min(runs.values()), max(runs.values())
    if fewest == most:
        return f"{most} runs per condition"
    each = ", ".join(f"{study} {n}" for study, n in runs.items())
    return f"{fewest}\N{EN DASH}{most} runs per condition ({each})"
