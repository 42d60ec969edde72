"""The published directions of SPEC §6, declared once as data, and how one seed judges them.

A ``Direction`` is one claim of SPEC §6's last paragraph made testable: a
rule on one metric of the conditions compared with the study's baseline
(proximity), judged separately in each study it names. On one master seed a
rule gives one ``Part`` per condition and swarm size (or per condition from
the smallest to the largest size); the claim *appears* when every part has
the claimed sign and is *significant* when every part also passes its test:

- ``Shift(metric, sign)``: the difference ``condition - baseline`` has
  ``sign``; significant when its bootstrap p-value (SPEC §5.1) is below
  ``SIGNIFICANCE``.
- ``Close(metric)``: the relative difference ``diff / baseline`` lies within
  ``CLOSE_MARGIN`` either way; significant (an equivalence test) when its
  95 % bootstrap interval lies within the margin too.
- ``Trend(metric, sign)``: the relative difference at the last scale minus
  that at the first has ``sign`` (it grows, or shrinks); significant when
  the bootstrap p-value of that change is below ``SIGNIFICANCE``.

The rules read ``Effect`` records (``effects`` builds them from a
``MetricsReport``); the statistics are ``swarmtag.analysis``'s. What the
published study reports for a direction in a study (``Published``: the
direction alone, or its numbers from the physical trials' Table II) is
declared here too, once, for every table that shows it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.analysis import ConfidenceInterval, MetricsReport, bootstrap_p_value
from swarmtag.analysis.bootstrap import percentile_interval
from swarmtag.errors import PolicyError
from swarmtag.policy import Urgency, Weighted, parse_policy

__all__ = [
    "CLOSE_MARGIN",
    "DIRECTIONS",
    "SIGNIFICANCE",
    "Close",
    "Direction",
    "Effect",
    "Part",
    "Published",
    "Rule",
    "Shift",
    "Trend",
    "effects",
    "short_condition",
]

SIGNIFICANCE: Final = 0.05
"""A bootstrap p-value below this is significant (two-sided, SPEC §5.1)."""
CLOSE_MARGIN: Final = 0.10
""""Close to the baseline": within 10 % of the baseline's value, either way."""


@dataclass(frozen=True, kw_only=True, eq=False)
class Effect:
    """One condition against the baseline in one metric at one scale: what a rule reads."""

    condition: str
    diff: float | None
    """``condition - baseline``; ``None`` where either figure is undefined."""
    p_bootstrap: float | None
    baseline: float | None
    """The baseline's value of the metric."""
    diff_draws: NDArray[np.float64]
    """Bootstrap values of the difference (NaN where undefined)."""
    baseline_draws: NDArray[np.float64]
    """The baseline's bootstrap values, paired with ``diff_draws`` by resample index."""
    confidence_level: float = 0.95


def effects(report: MetricsReport, metric: str) -> tuple[Effect, ...]:
    """Every compared condition's ``Effect`` on ``metric``, in the report's order."""
    base = report.condition(report.baseline).estimate(metric)
    return tuple(
        Effect(
            condition=comparison.condition,
            diff=comparison.diff,
            p_bootstrap=comparison.p_bootstrap,
            baseline=base.value,
            diff_draws=comparison.bootstrap_distribution,
            baseline_draws=base.bootstrap_distribution,
            confidence_level=report.confidence_level,
        )
        for comparison in report.comparisons
        if comparison.metric == metric
    )


@dataclass(frozen=True, kw_only=True)
class Part:
    """A claim's verdict on one condition at one scale (``"5x10->20x40"`` for a trend)."""

    scale: str
    condition: str
    value: float | None
    """The figure judged: a difference, a relative difference, or its change with scale."""
    interval: ConfidenceInterval
    """Its bootstrap percentile interval."""
    p_bootstrap: float | None
    """Its bootstrap p-value; ``None`` for ``Close`` (judged by its interval)."""
    appears: bool
    significant: bool


def _relative(diff: float | None, baseline: float | None) -> float | None:
    return None if diff is None or baseline is None or baseline == 0 else diff / baseline


def _relative_draws(effect: Effect) -> NDArray[np.float64]:
    """Each resample's ``diff / baseline`` (NaN where the baseline is 0 or undefined)."""
    out = np.full(effect.diff_draws.shape, np.nan)
    np.divide(effect.diff_draws, effect.baseline_draws, out=out, where=effect.baseline_draws != 0)
    return out


def _significant(appears: bool, p: float | None) -> bool:
    return appears and p is not None and p < SIGNIFICANCE


def _signed(sign: int, value: float | None) -> bool:
    return value is not None and sign * value > 0


def _signed_number(value: float) -> str:
    """Three significant digits with a sign, no exponent, no trailing zeros: ``+0.23``, ``-250``."""
    if value == 0 or not math.isfinite(value):
        return f"{value:g}"
    decimals = max(0, 2 - math.floor(math.log10(abs(value))))
    text = f"{value:+.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def _percent(value: float, unit: str) -> str:
    return f"{100 * value:+.1f} {unit}"


def short_condition(name: str) -> str:
    """A condition's short label for tables: alpha (the Greek letter) 0.7, ``w 0.5``, else the name.

    >>> short_condition("weighted:w=0.50"), short_condition("proximity")
    ('w 0.5', 'proximity')
    """
    try:
        policy = parse_policy(name)
    except PolicyError:
        return name
    if isinstance(policy, Urgency):
        return f"\N{GREEK SMALL LETTER ALPHA} {policy.alpha:g}"
    if isinstance(policy, Weighted):
        return f"w {policy.w:g}"
    return name


def _check_sign(sign: int) -> None:
    if sign not in (-1, 1):
        msg = f"sign: {sign!r} is not +1 (raises, grows) or -1 (lowers, shrinks)"
        raise ValueError(msg)


@dataclass(frozen=True)
class Shift:
    """Every condition moves ``metric`` the way of ``sign`` (+1 up, -1 down) at every scale."""

    metric: str
    sign: int

    def __post_init__(self) -> None:
        _check_sign(self.sign)

    def describe(self) -> str:
        """The rule in one line, for tables."""
        return f"diff {self.metric} {'>' if self.sign > 0 else '<'} 0, p < {SIGNIFICANCE:g}"

    def show(self, value: float) -> str:
        """A figure this rule judges, as text: the difference itself (``+0.23``)."""
        return _signed_number(value)

    def judge(self, scales: Mapping[str, Sequence[Effect]]) -> tuple[Part, ...]:
        """One part per scale and condition."""
        parts = []
        for scale, found in scales.items():
            for effect in found:
                appears = _signed(self.sign, effect.diff)
                interval = percentile_interval(
                    effect.diff_draws, confidence_level=effect.confidence_level
                )
                parts.append(
                    Part(
                        scale=scale,
                        condition=effect.condition,
                        value=effect.diff,
                        interval=interval,
                        p_bootstrap=effect.p_bootstrap,
                        appears=appears,
                        significant=_significant(appears, effect.p_bootstrap),
                    )
                )
        return tuple(parts)


@dataclass(frozen=True)
class Close:
    """Every condition keeps ``metric`` within ``margin`` of the baseline's value at every scale."""

    metric: str
    margin: float = CLOSE_MARGIN

    def describe(self) -> str:
        """The rule in one line, for tables."""
        margin = f"{self.margin * 100:g} %"
        return f"diff {self.metric} / baseline and its 95 % CI within -{margin} .. +{margin}"

    def show(self, value: float) -> str:
        """A figure this rule judges, as text: the relative difference in percent (``-1.2 %``)."""
        return _percent(value, "%")

    def judge(self, scales: Mapping[str, Sequence[Effect]]) -> tuple[Part, ...]:
        """One part per scale and condition: the relative difference and its interval."""
        parts = []
        for scale, found in scales.items():
            for effect in found:
                value = _relative(effect.diff, effect.baseline)
                interval = percentile_interval(
                    _relative_draws(effect), confidence_level=effect.confidence_level
                )
                appears = value is not None and abs(value) <= self.margin
                inside = (
                    interval.low is not None
                    and interval.high is not None
                    and -self.margin <= interval.low
                    and interval.high <= self.margin
                )
                parts.append(
                    Part(
                        scale=scale,
                        condition=effect.condition,
                        value=value,
                        interval=interval,
                        p_bootstrap=None,
                        appears=appears,
                        significant=appears and inside,
                    )
                )
        return tuple(parts)


@dataclass(frozen=True)
class Trend:
    """The relative difference in ``metric`` moves the way of ``sign`` from first to last scale.

    The two scales' bootstrap values are independent resamples: a scale
    draws the same rows as another when condition, seed and run count agree
    (``swarmtag.analysis.resampling``), so the last scale's values are
    shifted by one resample before they are paired with the first's.
    """

    metric: str
    sign: int

    def __post_init__(self) -> None:
        _check_sign(self.sign)

    def describe(self) -> str:
        """The rule in one line, for tables."""
        way = "rises" if self.sign > 0 else "falls"
        return f"diff {self.metric} / baseline {way} from first to last scale, p < {SIGNIFICANCE:g}"

    def show(self, value: float) -> str:
        """A figure this rule judges, as text: the relative difference's change (``+3.1 pp``)."""
        return _percent(value, "pp")

    def judge(self, scales: Mapping[str, Sequence[Effect]]) -> tuple[Part, ...]:
        """One part per condition present at both ends; none with fewer than two scales."""
        if len(scales) < 2:
            return ()
        (first, small), *_, (last, large) = scales.items()
        at_large = {effect.condition: effect for effect in large}
        parts = []
        for before in small:
            after = at_large.get(before.condition)
            if after is None:
                continue
            start = _relative(before.diff, before.baseline)
            end = _relative(after.diff, after.baseline)
            value = None if start is None or end is None else end - start
            draws = np.roll(_relative_draws(after), 1) - _relative_draws(before)
            p = bootstrap_p_value(draws)
            appears = _signed(self.sign, value)
            parts.append(
                Part(
                    scale=f"{first}->{last}",
                    condition=before.condition,
                    value=value,
                    interval=percentile_interval(draws, confidence_level=before.confidence_level),
                    p_bootstrap=p,
                    appears=appears,
                    significant=_significant(appears, p),
                )
            )
        return tuple(parts)


Rule = Shift | Close | Trend
"""How a direction is judged on one seed."""


@dataclass(frozen=True, kw_only=True)
class Published:
    """What the published study reports for one direction in one study.

    Every direction is published (SPEC §6); ``values`` hold its numbers
    where the study gives them, in the rule's own terms (a difference for
    ``Shift``, a relative difference for ``Close``), keyed by condition.
    """

    values: tuple[tuple[str, float], ...] = ()
    note: str = ""
    """Context in a few words (the published means behind a difference)."""

    def value(self, condition: str) -> float | None:
        """The published figure of ``condition``, if the study gives one."""
        return dict(self.values).get(condition)

    def describe(self, rule: Rule) -> str:
        """One line for tables: each value and condition, then the note; or ``direction only``."""
        if not self.values:
            return "direction only"
        shown = ", ".join(f"{rule.show(v)} ({short_condition(c)})" for c, v in self.values)
        return f"{shown}; {self.note}" if self.note else shown


DIRECTION_ONLY: Final = Published()
"""A direction the published study states without a number (the simulation studies)."""


@dataclass(frozen=True, kw_only=True)
class Direction:
    """One published direction: a sentence of SPEC §6, its rule, and the studies that test it."""

    name: str
    text: str
    rule: Rule
    studies: tuple[str, ...]
    published: Mapping[str, Published] = field(default_factory=dict, hash=False)
    """The published numbers by study; a study not named here has the direction only."""

    def published_in(self, study: str) -> Published:
        """What the published study reports for this direction in ``study``."""
        return self.published.get(study, DIRECTION_ONLY)

    def judge(self, reports: Mapping[str, MetricsReport]) -> tuple[Part, ...]:
        """The parts of this direction on one study's reports (scale -> report) of one seed."""
        return self.rule.judge(
            {scale: effects(report, self.rule.metric) for scale, report in reports.items()}
        )


_EVERY_SIZE: Final = ("controller-selection", "physical-style", "scalability")
"""The studies that compare urgency-aware selection with proximity (3/7 sim, lab, larger swarms)."""
_AT_3_7: Final = ("controller-selection", "physical-style")
"""The studies at 3 robots / 7 carriers with proximity as the baseline."""
_TABLE_II: Final = "physical-style"
"""The study of the published physical trials (their Table II gives numbers; 15-17 runs)."""

DIRECTIONS: Final = (
    Direction(
        name="pa-raised",
        text="urgency-aware selection raises PA at every alpha and every scale",
        rule=Shift("pa", +1),
        studies=_EVERY_SIZE,
        published={
            _TABLE_II: Published(
                values=(
                    ("urgency:alpha=0.7", 0.23),
                    ("urgency:alpha=3.0", 0.11),
                    ("urgency:alpha=9.0", 0.13),
                ),
                note="PA 0.41 \N{RIGHTWARDS ARROW} 0.64 at \N{GREEK SMALL LETTER ALPHA} 0.7",
            )
        },
    ),
    Direction(
        name="p95-lowered",
        text="stronger weighting lowers P95 latency",
        rule=Shift("p95_latency", -1),
        studies=_EVERY_SIZE,
    ),
    Direction(
        name="mean-raised",
        text="stronger weighting raises mean latency",
        rule=Shift("mean_latency", +1),
        studies=_AT_3_7,
    ),
    Direction(
        name="throughput-close",
        text="throughput stays close to the baseline",
        rule=Close("throughput"),
        studies=_EVERY_SIZE,
        published={_TABLE_II: Published(values=(("urgency:alpha=0.7", -0.012),))},
    ),
    Direction(
        name="deliveries-close",
        text="deliveries stay close to the baseline at every scale",
        rule=Close("deliveries_per_run"),
        studies=("scalability",),
    ),
    Direction(
        name="pa-gain-grows",
        text="the PA gain grows with swarm size",
        rule=Trend("pa", +1),
        studies=("scalability",),
    ),
    Direction(
        name="p95-gain-grows",
        text="the P95 gain grows with swarm size",
        rule=Trend("p95_latency", -1),
        studies=("scalability",),
    ),
    Direction(
        name="throughput-cost-shrinks",
        text="the throughput cost shrinks with swarm size",
        rule=Trend("throughput", +1),
        studies=("scalability",),
    ),
)
"""SPEC §6's directions, each judged in the studies it names (against their proximity baseline).

The published numbers are the physical trials' (Table II): PA 0.41 -> 0.64
at alpha 0.7 (+0.23; +0.11 at 3, +0.13 at 9), throughput -1.2 % at 0.7;
the simulation studies publish the directions only.

The scalability study's claims are its PA gain and P95 gain (at every
size, and growing with size), its deliveries and its throughput (close to
the baseline at every size, and the throughput cost shrinking with size).
"""
