"""The verdict on each published claim that opens the report, the published values, the banner."""

from __future__ import annotations

import re

import pytest

from swarmtag.analysis import ConfidenceInterval
from swarmtag.analysis.compare import MIN_RUNS
from swarmtag.experiments import DIRECTIONS, load_study
from swarmtag.experiments.directions import Part, Published
from swarmtag.experiments.robustness import Outcome
from swarmtag.experiments.verdicts import (
    NOT_REPRODUCED,
    REPRODUCED,
    SIGN_ONLY,
    UNDERPOWERED,
    ClaimVerdict,
    claim_verdict,
    quick_banner,
    verdict_section,
)

BY_NAME = {direction.name: direction for direction in DIRECTIONS}


@pytest.mark.parametrize(
    ("appears", "significant", "runs", "expected"),
    [
        (True, True, 100, REPRODUCED),
        (True, True, MIN_RUNS, REPRODUCED),  # ten runs are enough
        (True, False, 100, SIGN_ONLY),  # the right sign, not significant
        (True, False, MIN_RUNS, SIGN_ONLY),
        (False, False, 100, NOT_REPRODUCED),  # the wrong sign
        (True, True, MIN_RUNS - 1, UNDERPOWERED),  # significant, but on too few runs
        (False, False, 3, UNDERPOWERED),
    ],
)
def test_the_verdict_of_a_claim(appears, significant, runs, expected):
    assert claim_verdict(appears=appears, significant=significant, runs=runs) == expected


def part(condition, value, *, significant=True, scale="default", p=0.001):
    return Part(
        scale=scale,
        condition=condition,
        value=value,
        interval=ConfidenceInterval(low=value - 0.05, high=value + 0.05),
        p_bootstrap=p if significant else 0.4,
        appears=value > 0,
        significant=value > 0 and significant,
    )


def claim(name, study, runs, *parts):
    outcome = Outcome(direction=BY_NAME[name], study=study, seed=0, parts=parts)
    return ClaimVerdict(outcome=outcome, runs=runs, resamples=10_000)


def test_a_claim_needs_every_part_and_enough_runs():
    both = claim("pa-raised", "controller-selection", 100,
                 part("urgency:alpha=0.7", 0.12), part("urgency:alpha=3.0", 0.2))  # fmt: skip
    assert (both.verdict, both.label) == (REPRODUCED, REPRODUCED)
    one_weak = claim("pa-raised", "controller-selection", 100,
                     part("urgency:alpha=0.7", 0.12),
                     part("urgency:alpha=3.0", 0.02, significant=False))  # fmt: skip
    assert one_weak.verdict == SIGN_ONLY
    one_wrong = claim("pa-raised", "controller-selection", 100,
                      part("urgency:alpha=0.7", 0.12), part("urgency:alpha=3.0", -0.02))  # fmt: skip
    assert one_wrong.verdict == NOT_REPRODUCED
    quick = claim("pa-raised", "physical-style", 4, part("urgency:alpha=0.7", 0.12))
    assert quick.verdict == UNDERPOWERED
    assert quick.label == "underpowered (4 runs; appears)"
    wrong_quick = claim("pa-raised", "physical-style", 4, part("urgency:alpha=0.7", -0.1))
    assert wrong_quick.label == "underpowered (4 runs; does not appear)"


def test_the_published_values_are_those_of_the_physical_trials():
    pa, throughput = BY_NAME["pa-raised"], BY_NAME["throughput-close"]
    table_ii = pa.published_in("physical-style")
    assert table_ii.value("urgency:alpha=0.7") == 0.23
    assert table_ii.value("urgency:alpha=3.0") == 0.11
    assert table_ii.value("urgency:alpha=9.0") == 0.13
    assert "0.41 \N{RIGHTWARDS ARROW} 0.64" in table_ii.note
    assert throughput.published_in("physical-style").value("urgency:alpha=0.7") == -0.012
    assert table_ii.describe(pa.rule).startswith("+0.23 (\N{GREEK SMALL LETTER ALPHA} 0.7), +0.11")
    assert throughput.published_in("physical-style").describe(throughput.rule) == (
        "-1.2 % (\N{GREEK SMALL LETTER ALPHA} 0.7)"
    )
    # the simulation studies publish the directions only
    for direction in DIRECTIONS:
        for study in direction.studies:
            published = direction.published_in(study)
            if study != "physical-style":
                assert published == Published()
                assert published.describe(direction.rule) == "direction only"
            # a published number belongs to a condition the study runs
            conditions = load_study(study).conditions
            assert all(condition in conditions for condition, _ in published.values)


def test_the_verdict_table_has_one_row_group_per_claim():
    claims = [
        claim("pa-raised", "controller-selection", 100,
              part("urgency:alpha=0.7", 0.12), part("urgency:alpha=3.0", 0.2, p=0.0)),
        claim("pa-raised", "physical-style", 4,
              part("urgency:alpha=0.7", 0.0875), part("urgency:alpha=3.0", 0.0875),
              part("urgency:alpha=9.0", 0.0875)),
        claim("mean-raised", "controller-selection", 100,
              part("urgency:alpha=0.7", 25.5, significant=False)),
    ]  # fmt: skip
    section = verdict_section(claims)
    assert list(section.paragraphs) == [
        (
            "3 published claims judged on master seed 0: 1 reproduced, "
            "1 not reproduced (sign only), 1 underpowered."
        )
    ]
    table = section.tables_html[0]
    assert table.startswith('<table class="verdicts">')
    assert table.count("<tr>") == 1 + 2 + 3 + 1  # the header, then one row per part
    header = re.findall(r"<th>([^<]*)</th>", table)
    assert header[:3] == ["Claim", "Study", "Verdict"]  # the answer before the details
    assert '<td rowspan="3" class="v-under">underpowered (4 runs; appears)</td>' in table
    assert '<td rowspan="2" class="v-reproduced">reproduced</td>' in table
    assert '<td class="v-sign">not reproduced (sign only)</td>' in table
    # each part: its condition, the difference with its CI, p (0 shown below the resolution)
    assert '<td class="part">\N{GREEK SMALL LETTER ALPHA} 3</td>' in table
    assert '<td class="num">+0.2 [+0.15, +0.25]</td><td class="num">&lt; 0.0002</td>' in table
    assert "+0.23 (\N{GREEK SMALL LETTER ALPHA} 0.7), +0.11" in table  # published, Table II
    assert table.count("direction only") == 2


def test_a_close_claim_and_a_trend_show_their_own_terms():
    close = claim("throughput-close", "scalability", 21, part("urgency:alpha=0.7", 0.038,
                  scale="5x10", p=None))  # fmt: skip
    trend = claim("pa-gain-grows", "scalability", 21,
                  part("urgency:alpha=0.7", 0.174, scale="5x10->20x40", p=0.49))  # fmt: skip
    table = verdict_section([close, trend]).tables_html[0]
    assert '<td class="part">\N{GREEK SMALL LETTER ALPHA} 0.7, 5x10</td>' in table
    assert "+3.8 % [-1.2 %, +8.8 %]" in table
    assert "- (CI test)" in table  # judged by its interval, no p
    assert "\N{GREEK SMALL LETTER ALPHA} 0.7, 5x10 \N{RIGHTWARDS ARROW} 20x40" in table
    assert "+17.4 pp [+12.4 pp, +22.4 pp]" in table


def test_studies_no_direction_names_get_a_line_not_a_table():
    section = verdict_section([])
    assert section.tables_html == ()
    assert "No published direction names these studies" in section.paragraphs[0]


def test_the_quick_banner_names_the_runs_and_the_full_command():
    banner = quick_banner(
        {"preliminary-sweep": 6, "physical-style": 4, "controller-selection": 10},
        {"preliminary-sweep": 100, "physical-style": 16, "controller-selection": 100},
    )
    assert banner.startswith(
        "Quick run: 4\N{EN DASH}10 runs per condition "
        "(preliminary-sweep 6, physical-style 4, controller-selection 10). "
        "Verdicts are underpowered where a study has fewer than 10"
    )
    assert "16\N{EN DASH}100 runs per condition (preliminary-sweep 100, physical-style 16" in banner
    assert banner.endswith("run `swarmtag reproduce`.")
    same = quick_banner({"a": 3, "b": 3}, {"a": 21, "b": 21})
    assert same.startswith("Quick run: 3 runs per condition.")
    assert "For the full reproduction, 21 runs per condition, run" in same
