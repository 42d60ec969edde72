"""The robustness over master seeds as text: JSON, Markdown, a report section and console lines.

Every form takes its rows from the same ``ClaimSummary`` records
(``swarmtag.experiments.robustness``), so they cannot disagree. Pure:
records in, strings and JSON objects out.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Final

from swarmtag.analysis.html import Section
from swarmtag.analysis.summary import JsonValue
from swarmtag.analysis.tables import html_table, markdown_table
from swarmtag.experiments.directions import CLOSE_MARGIN, SIGNIFICANCE, Part
from swarmtag.experiments.robustness import ClaimSummary

__all__ = ["console_lines", "robustness_json", "robustness_markdown", "robustness_section"]

_CLAIM_HEADER: Final = (
    "Direction",
    "Study",
    "Published",
    "Rule",
    "Appears",
    "Significant",
    "Verdict",
)
_PART_HEADER: Final = ("Direction", "Study", "Scale", "Condition", "Appears", "Significant")


def _seeds_note(seeds: Mapping[str, Sequence[int]]) -> str:
    count = _seed_count(seeds)
    listed = "; ".join(
        f"{study}: {values[0]}" + (f"-{values[-1]}" if len(values) > 1 else "")
        for study, values in seeds.items()
    )
    return f"Master seeds: each study at its own seed + 0 .. {count - 1} ({listed})."


def _seed_count(seeds: Mapping[str, Sequence[int]]) -> int:
    return max((len(values) for values in seeds.values()), default=0)


def _rules_note() -> str:
    return (
        "A claim appears in a seed when every part (condition and swarm size) has the claimed "
        f"sign; it is significant when every part also has a bootstrap p below {SIGNIFICANCE:g} "
        f"(for 'close to the baseline': the 95 % interval of diff / baseline within "
        f"{CLOSE_MARGIN * 100:g} % either way). Reproduced robustly: significant in more than "
        "half of the seeds; on some seeds: appears in at least one; else not reproduced. "
        "Published: the physical trials' numbers (Table II, in the rule's terms: a "
        "difference, or % of the baseline); the simulation studies publish the direction only."
    )


def _published(summary: ClaimSummary) -> str:
    direction = summary.direction
    return direction.published_in(summary.study).describe(direction.rule)


def _count(value: int, seeds: int) -> str:
    return f"{value} / {seeds}"


def _claim_rows(summaries: Sequence[ClaimSummary]) -> list[list[str]]:
    return [
        [
            s.direction.text,
            s.study,
            _published(s),
            s.direction.rule.describe(),
            _count(s.appeared, len(s.outcomes)),
            _count(s.significant, len(s.outcomes)),
            s.verdict,
        ]
        for s in summaries
    ]


def _part_rows(summaries: Sequence[ClaimSummary]) -> list[list[str]]:
    return [
        [
            s.direction.name,
            s.study,
            part.scale,
            part.condition,
            _count(part.appeared, len(s.outcomes)),
            _count(part.significant, len(s.outcomes)),
        ]
        for s in summaries
        for part in s.parts()
    ]


def _title(count: int) -> str:
    return f"Robustness of the published directions over {count} master seeds"


def robustness_markdown(
    summaries: Sequence[ClaimSummary], *, seeds: Mapping[str, Sequence[int]]
) -> str:
    """``seeds.md``: the rules, one row per direction and study, then one row per part.

    ``seeds`` maps each study to the master seeds it ran on.
    """
    return (
        "\n\n".join(
            [
                f"# {_title(_seed_count(seeds))}",
                _seeds_note(seeds),
                _rules_note(),
                markdown_table(_CLAIM_HEADER, _claim_rows(summaries)),
                "## Each part",
                markdown_table(_PART_HEADER, _part_rows(summaries)),
            ]
        )
        + "\n"
    )


def robustness_section(
    summaries: Sequence[ClaimSummary], *, seeds: Mapping[str, Sequence[int]]
) -> Section:
    """The report's section after the verdicts: the tables of ``robustness_markdown``.

    The per-part table is folded: it is long, and the claims' table answers first.
    """
    parts = _part_rows(summaries)
    each = Section(
        title="Each part",
        summary=f"{len(parts)} rows: every condition and swarm size of each direction",
        paragraphs=["Every condition and swarm size of each direction, counted alike."],
        tables_html=[html_table(_PART_HEADER, parts)],
    )
    return Section(
        title=_title(_seed_count(seeds)),
        paragraphs=[_seeds_note(seeds), _rules_note()],
        tables_html=[html_table(_CLAIM_HEADER, _claim_rows(summaries))],
        parts=[each],
    )


def _part_json(part: Part) -> JsonValue:
    return {
        "scale": part.scale,
        "condition": part.condition,
        "value": part.value,
        "ci": [part.interval.low, part.interval.high],
        "p_bootstrap": part.p_bootstrap,
        "appears": part.appears,
        "significant": part.significant,
    }


def _published_json(summary: ClaimSummary) -> JsonValue:
    published = summary.direction.published_in(summary.study)
    values: dict[str, JsonValue] = dict(published.values)
    return {"text": _published(summary), "values": values, "note": published.note}


def robustness_json(
    summaries: Sequence[ClaimSummary], *, seeds: Mapping[str, Sequence[int]]
) -> dict[str, JsonValue]:
    """``seeds.json``: the rules' constants, the seeds per study, every claim at every seed."""
    claims: list[JsonValue] = [
        {
            "direction": s.direction.name,
            "text": s.direction.text,
            "study": s.study,
            "published": _published_json(s),
            "rule": s.direction.rule.describe(),
            "seeds": list(s.seeds),
            "appeared": s.appeared,
            "significant": s.significant,
            "verdict": s.verdict,
            "parts": [
                {
                    "scale": part.scale,
                    "condition": part.condition,
                    "appeared": part.appeared,
                    "significant": part.significant,
                }
                for part in s.parts()
            ],
            "per_seed": [
                {
                    "seed": outcome.seed,
                    "appears": outcome.appears,
                    "significant": outcome.significant,
                    "parts": [_part_json(part) for part in outcome.parts],
                }
                for outcome in s.outcomes
            ],
        }
        for s in summaries
    ]
    return {
        "significance": SIGNIFICANCE,
        "close_margin": CLOSE_MARGIN,
        "seeds": {study: list(values) for study, values in seeds.items()},
        "claims": claims,
    }


def console_lines(summaries: Sequence[ClaimSummary]) -> list[str]:
    """One line per direction and study: appearances, significance and the verdict."""
    return [
        f"{s.direction.text} [{s.study}]: appears in {_count(s.appeared, len(s.outcomes))} seeds, "
        f"significant in {_count(s.significant, len(s.outcomes))}: {s.verdict}"
        for s in summaries
    ]
