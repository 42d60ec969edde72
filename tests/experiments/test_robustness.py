"""The directions over master seeds: counts, verdicts, and the tables that show them."""

from __future__ import annotations

import json

import pytest

from swarmtag.analysis import ConfidenceInterval
from swarmtag.experiments import DIRECTIONS
from swarmtag.experiments.directions import Part
from swarmtag.experiments.robustness import (
    NOT_REPRODUCED,
    ROBUST,
    SOME_SEEDS,
    Outcome,
    robustness,
    verdict,
)
from swarmtag.experiments.seed_tables import (
    console_lines,
    robustness_json,
    robustness_markdown,
    robustness_section,
)

BY_NAME = {direction.name: direction for direction in DIRECTIONS}


@pytest.mark.parametrize(
    ("appeared", "significant", "seeds", "expected"),
    [
        (10, 6, 10, ROBUST),  # most seeds: more than half
        (10, 5, 10, SOME_SEEDS),  # half is not most
        (10, 0, 10, SOME_SEEDS),  # appears everywhere, never significant
        (1, 0, 10, SOME_SEEDS),
        (0, 0, 10, NOT_REPRODUCED),
        (1, 1, 1, ROBUST),
        (2, 1, 2, SOME_SEEDS),
    ],
)
def test_verdict(appeared, significant, seeds, expected):
    assert verdict(appeared, significant, seeds) == expected


def part(scale, appears, significant, condition="urgency:alpha=0.7"):
    return Part(
        scale=scale,
        condition=condition,
        value=0.1 if appears else -0.1,
        interval=ConfidenceInterval(low=0.0, high=0.2),
        p_bootstrap=0.01 if significant else 0.3,
        appears=appears,
        significant=significant,
    )


def outcome(name, study, seed, *parts):
    return Outcome(direction=BY_NAME[name], study=study, seed=seed, parts=parts)


def seeded_outcomes():
    """Three seeds of two claims; the PA claim misses significance at 5x10 in seed 2."""
    outcomes = []
    for seed in range(3):
        small = part("5x10", appears=True, significant=seed != 2)
        outcomes += [
            outcome("pa-raised", "scalability", seed, small, part("20x40", True, True)),
            outcome("pa-gain-grows", "scalability", seed, part("5x10->20x40", seed == 0, False)),
            outcome("pa-raised", "controller-selection", seed, part("default", True, True)),
        ]
    return outcomes


def test_an_outcome_needs_every_part():
    both = outcome("pa-raised", "scalability", 0, part("a", True, True), part("b", True, True))
    assert both.appears
    assert both.significant
    mixed = outcome("pa-raised", "scalability", 0, part("a", True, True), part("b", True, False))
    assert mixed.appears
    assert not mixed.significant
    wrong = outcome("pa-raised", "scalability", 0, part("a", False, False), part("b", True, True))
    assert not wrong.appears
    assert not outcome("pa-raised", "scalability", 0).appears  # no parts: nothing shown


def test_robustness_counts_seeds_per_direction_and_study():
    summaries = robustness(seeded_outcomes())
    # in DIRECTIONS order, then the direction's own order of studies
    assert [(s.direction.name, s.study) for s in summaries] == [
        ("pa-raised", "controller-selection"),
        ("pa-raised", "scalability"),
        ("pa-gain-grows", "scalability"),
    ]
    cs, scalability, grows = summaries
    assert (cs.appeared, cs.significant, cs.verdict) == (3, 3, ROBUST)
    assert cs.seeds == (0, 1, 2)
    assert (scalability.appeared, scalability.significant, scalability.verdict) == (3, 2, ROBUST)
    assert [(p.scale, p.appeared, p.significant) for p in scalability.parts()] == [
        ("5x10", 3, 2),
        ("20x40", 3, 3),
    ]
    assert (grows.appeared, grows.significant, grows.verdict) == (1, 0, SOME_SEEDS)


def test_the_tables_agree_with_the_counts():
    summaries = robustness(seeded_outcomes())
    seeds = {"controller-selection": [0, 1, 2], "scalability": [0, 1, 2]}
    markdown = robustness_markdown(summaries, seeds=seeds)
    assert markdown.startswith("# Robustness of the published directions over 3 master seeds\n")
    assert "scalability: 0-2" in markdown
    rows = [line for line in markdown.splitlines() if line.startswith("|")]
    claims = rows[: rows.index("| Direction | Study | Scale | Condition | Appears | Significant |")]
    assert claims[0] == (
        "| Direction | Study | Published | Rule | Appears | Significant | Verdict |"
    )
    assert all(row.count("|") == 8 for row in claims)  # seven cells each: no stray pipes
    assert (
        "| urgency-aware selection raises PA at every alpha and every scale | scalability | "
        "direction only | diff pa > 0, p < 0.05 | 3 / 3 | 2 / 3 | reproduced robustly |"
    ) in rows
    assert "| pa-raised | scalability | 5x10 | urgency:alpha=0.7 | 3 / 3 | 2 / 3 |" in rows
    data = json.loads(json.dumps(robustness_json(summaries, seeds=seeds), allow_nan=False))
    claim = data["claims"][1]
    assert (claim["direction"], claim["study"], claim["seeds"]) == ("pa-raised", "scalability",
                                                                   [0, 1, 2])  # fmt: skip
    assert (claim["appeared"], claim["significant"]) == (3, 2)
    assert [entry["significant"] for entry in claim["per_seed"]] == [True, True, False]
    assert data["seeds"] == seeds
    assert claim["published"] == {"text": "direction only", "values": {}, "note": ""}
    section = robustness_section(summaries, seeds=seeds)
    assert section.tables_html[0].count("<tr>") == 1 + 3
    assert "<th>Published</th>" in section.tables_html[0]
    (each,) = section.parts  # the long per-part table, folded
    assert each.summary.startswith("4 rows")  # 5x10, 20x40, the trend, controller selection
    assert each.tables_html[0].count("<tr>") == 1 + 4
    assert console_lines(summaries)[2] == (
        "the PA gain grows with swarm size [scalability]: appears in 1 / 3 seeds, "
        "significant in 0 / 3: on some seeds"
    )


def test_seeds_md_takes_the_published_numbers_from_the_directions():
    physical = [
        outcome("pa-raised", "physical-style", seed, part("default", True, seed == 0))
        for seed in range(2)
    ] + [outcome("throughput-close", "physical-style", 0, part("default", True, False))]
    summaries = robustness(physical)
    markdown = robustness_markdown(summaries, seeds={"physical-style": [0, 1]})
    pa = BY_NAME["pa-raised"].published_in("physical-style")
    assert (
        "| urgency-aware selection raises PA at every alpha and every scale | physical-style | "
        "+0.23 (\N{GREEK SMALL LETTER ALPHA} 0.7), +0.11 (\N{GREEK SMALL LETTER ALPHA} 3), "
        f"+0.13 (\N{GREEK SMALL LETTER ALPHA} 9); {pa.note} | diff pa > 0, p < 0.05 | 2 / 2 | "
        "1 / 2 | on some seeds |"
    ) in markdown
    assert "| physical-style | -1.2 % (\N{GREEK SMALL LETTER ALPHA} 0.7) | diff throughput" in (
        markdown
    )
    data = robustness_json(summaries, seeds={"physical-style": [0, 1]})
    assert data["claims"][0]["published"]["values"] == {
        "urgency:alpha=0.7": 0.23, "urgency:alpha=3.0": 0.11, "urgency:alpha=9.0": 0.13,
    }  # fmt: skip
