"""The published directions' rules on hand-built effects: signs, significance, the trend's pairing."""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.analysis import CORE_METRICS
from swarmtag.experiments import DIRECTIONS, REPRODUCED, Close, Shift, Trend
from swarmtag.experiments.directions import CLOSE_MARGIN, SIGNIFICANCE, Effect

RNG_DRAWS = 2000


def effect(
    diff,
    *,
    p=0.001,
    baseline=10.0,
    diff_draws=None,
    baseline_draws=None,
    condition="urgency:alpha=0.7",
):
    """An effect whose bootstrap values are constant unless given."""
    return Effect(
        condition=condition,
        diff=diff,
        p_bootstrap=p,
        baseline=baseline,
        diff_draws=np.asarray(
            np.full(RNG_DRAWS, np.nan if diff is None else diff)
            if diff_draws is None
            else diff_draws,
            dtype=np.float64,
        ),
        baseline_draws=np.asarray(
            np.full(RNG_DRAWS, baseline) if baseline_draws is None else baseline_draws,
            dtype=np.float64,
        ),
    )


def verdicts(parts):
    return [(part.appears, part.significant) for part in parts]


@pytest.mark.parametrize(
    ("sign", "diff", "p", "expected"),
    [
        (+1, 0.1, 0.001, (True, True)),
        (+1, 0.1, 0.2, (True, False)),  # the right sign, not significant
        (+1, 0.1, SIGNIFICANCE, (True, False)),  # the threshold is strict
        (+1, -0.1, 0.001, (False, False)),  # significant the wrong way: neither
        (+1, 0.0, 1.0, (False, False)),
        (+1, None, None, (False, False)),  # undefined: does not appear
        (-1, -250.0, 0.01, (True, True)),  # P95 lowered
        (-1, 250.0, 0.01, (False, False)),
    ],
)
def test_a_shift_needs_the_sign_and_a_bootstrap_p_below_the_threshold(sign, diff, p, expected):
    parts = Shift("pa", sign).judge({"default": [effect(diff, p=p)]})
    assert verdicts(parts) == [expected]
    assert parts[0].value == diff
    assert parts[0].p_bootstrap == p


def test_a_shift_has_one_part_per_scale_and_condition():
    scales = {
        "5x10": [effect(0.1, condition="a"), effect(0.2, p=0.3, condition="b")],
        "20x40": [effect(-0.1, condition="a"), effect(0.2, condition="b")],
    }
    parts = Shift("pa", +1).judge(scales)
    assert [(part.scale, part.condition) for part in parts] == [
        ("5x10", "a"), ("5x10", "b"), ("20x40", "a"), ("20x40", "b"),
    ]  # fmt: skip
    assert verdicts(parts) == [(True, True), (True, False), (False, False), (True, True)]


def test_close_is_the_relative_difference_and_its_interval_within_the_margin():
    margin = CLOSE_MARGIN * 10.0  # of the baseline 10
    tight = np.linspace(-0.5 * margin, 0.5 * margin, RNG_DRAWS)
    wide = np.linspace(-2 * margin, 2 * margin, RNG_DRAWS)
    rule = Close("throughput")
    cases = {
        "inside, CI inside": effect(0.5 * margin, diff_draws=tight),
        "inside, CI not": effect(0.5 * margin, diff_draws=wide),
        "outside": effect(1.5 * margin, diff_draws=tight + margin),
        "outside below": effect(-1.5 * margin, diff_draws=tight - margin),
        "no baseline": effect(0.1, baseline=0.0),
    }
    parts = rule.judge({name: [found] for name, found in cases.items()})
    assert verdicts(parts) == [(True, True), (True, False), (False, False), (False, False),
                               (False, False)]  # fmt: skip
    assert parts[0].value == pytest.approx(0.5 * CLOSE_MARGIN)
    assert parts[0].p_bootstrap is None
    # the interval is that of diff / baseline, resample by resample
    assert parts[1].interval.low == pytest.approx(np.percentile(wide / 10.0, 2.5))


def test_close_divides_each_resample_by_its_own_baseline():
    # diff and baseline move together: diff / baseline is 5 % in every resample
    baseline_draws = np.linspace(5.0, 15.0, RNG_DRAWS)
    parts = Close("throughput").judge(
        {"s": [effect(0.5, diff_draws=0.05 * baseline_draws, baseline_draws=baseline_draws)]}
    )
    assert verdicts(parts) == [(True, True)]
    assert parts[0].interval.low == pytest.approx(0.05)
    assert parts[0].interval.high == pytest.approx(0.05)


def scale_pair(first_gain, last_gain, *, spread=0.0, seed=0):
    """Two scales whose relative gains are ``first_gain`` and ``last_gain`` (baseline 10)."""
    rng = np.random.default_rng(seed)
    noise = rng.normal(0.0, spread, RNG_DRAWS) if spread else np.zeros(RNG_DRAWS)
    return {
        "5x10": [effect(10 * first_gain, diff_draws=10 * (first_gain + noise))],
        "20x40": [effect(10 * last_gain, diff_draws=10 * (last_gain + noise))],
    }


@pytest.mark.parametrize(
    ("sign", "gains", "expected"),
    [
        (+1, (0.1, 0.3), (True, True)),  # the PA gain grows
        (+1, (0.3, 0.1), (False, False)),
        (-1, (-0.05, -0.15), (True, True)),  # the P95 change falls: the gain grows
        (-1, (-0.15, -0.05), (False, False)),
    ],
)
def test_a_trend_compares_the_last_scale_with_the_first(sign, gains, expected):
    scales = scale_pair(*gains, spread=0.01)
    middle = {"10x20": [effect(-100.0)]}  # in between: not read
    parts = Trend("pa", sign).judge({"5x10": scales["5x10"], **middle, "20x40": scales["20x40"]})
    assert verdicts(parts) == [expected]
    assert parts[0].scale == "5x10->20x40"
    assert parts[0].value == pytest.approx(gains[1] - gains[0])


def test_a_trend_within_the_noise_appears_without_significance():
    parts = Trend("pa", +1).judge(scale_pair(0.10, 0.12, spread=0.1))
    assert verdicts(parts) == [(True, False)]
    assert parts[0].p_bootstrap > SIGNIFICANCE


def test_a_trend_pairs_the_two_scales_as_independent_resamples():
    # Both scales drew the same rows (same condition, seed, run count): paired by
    # index their noise cancels and a small trend would look certain. Independent
    # resampling keeps the noise of both.
    parts = Trend("pa", +1).judge(scale_pair(0.10, 0.12, spread=0.1, seed=3))
    assert parts[0].p_bootstrap > 0.5
    assert parts[0].interval.high - parts[0].interval.low > 0.3


def test_a_trend_needs_two_scales():
    assert Trend("pa", +1).judge({"default": [effect(0.1)]}) == ()


def test_a_rule_refuses_a_sign_other_than_plus_or_minus_one():
    with pytest.raises(ValueError, match="sign"):
        Shift("pa", 2)
    with pytest.raises(ValueError, match="sign"):
        Trend("pa", 0)


def test_the_directions_cover_spec_6():
    names = [direction.name for direction in DIRECTIONS]
    assert len(set(names)) == len(names)
    assert set(names) == {
        "pa-raised", "p95-lowered", "mean-raised", "throughput-close", "deliveries-close",
        "pa-gain-grows", "p95-gain-grows", "throughput-cost-shrinks",
    }  # fmt: skip
    for direction in DIRECTIONS:
        assert set(direction.studies) <= set(REPRODUCED)
        assert direction.rule.metric in CORE_METRICS
    # the scalability study's claims: PA gain, P95 gain, deliveries, throughput
    scalability = {d.rule.metric for d in DIRECTIONS if "scalability" in d.studies}
    assert scalability == {"pa", "p95_latency", "deliveries_per_run", "throughput"}
    # the candidate alphas have no proximity baseline: no direction names them
    assert not [d for d in DIRECTIONS if "candidate-alphas" in d.studies]
