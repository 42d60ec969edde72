"""``check_rule``: what a score rule of one's own must do for the simulator to trust it.

Each check runs the rule on a seeded sample of candidates (every urgency,
distances 0-5 m, ages up to 10 minutes) and reports one line:

- ``runs``: it returns one score per candidate without raising;
- ``finite``: no NaN or infinite score;
- ``deterministic``: the same inputs give the same scores, twice;
- ``elementwise``: a candidate's score depends on its own values only (the
  same scores one at a time as scalars, in another order, and as a batch
  of shape ``(runs, robots, carriers)``, the simulator's call);
- ``no wall clock``: it reads no clock (``time``'s functions), which would
  make runs differ between machines and backends.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np
import numpy.typing as npt

from swarmtag._checks import check_instance
from swarmtag.errors import PolicyError
from swarmtag.policy._rules import ScoreRule, load_rule

__all__ = ["RuleCheck", "check_rule", "load_checked_rule"]

_SAMPLE: Final = 240
_CLOCKS: Final = (
    "time",
    "time_ns",
    "monotonic",
    "monotonic_ns",
    "perf_counter",
    "perf_counter_ns",
    "process_time",
    "process_time_ns",
    "thread_time",
    "thread_time_ns",
)
_AGREE: Final = 1e-12
"""Relative difference allowed between a scalar call and the array call (vector maths may
round the last bit differently; selection compares array scores only)."""


@dataclass(frozen=True)
class RuleCheck:
    """One check's outcome: its name, whether it passed, and why not (one line)."""

    name: str
    passed: bool
    detail: str


class _ClockRead(Exception):
    """Raised by the patched clocks: the rule read one."""


def _sample(seed: int = 20261204) -> dict[str, npt.NDArray[Any]]:
    """A seeded sample of candidates: every urgency, distances 0-5 m, ages 0-600 s."""
    rng = np.random.default_rng(seed)
    urgency = np.resize(np.arange(10, dtype=np.float64), _SAMPLE)
    rng.shuffle(urgency)
    return {
        "urgency": urgency,
        "distance": np.round(rng.uniform(0.0, 5.0, _SAMPLE), 3),
        "marker": np.arange(_SAMPLE, dtype=np.int64),
        "age": np.round(rng.uniform(0.0, 600.0, _SAMPLE), 1),
    }


def _call(rule: ScoreRule, sample: dict[str, npt.NDArray[Any]]) -> npt.NDArray[np.float64]:
    context = {key: sample[key] for key in ("marker", "age")}
    return rule.scores(sample["urgency"], sample["distance"], context)


def check_rule(rule: ScoreRule) -> list[RuleCheck]:
    """Run every check on ``rule``; later checks are skipped (failed) once it cannot run."""
    check_instance("rule", rule, ScoreRule, error=PolicyError)
    sample = _sample()
    context = {key: sample[key] for key in ("marker", "age")}
    try:
        first = rule.raw_scores(sample["urgency"], sample["distance"], context)
    except PolicyError as exc:
        return [RuleCheck("runs", False, str(exc))]
    checks = [RuleCheck("runs", True, "")]
    problem = rule.non_finite(first)
    if problem is not None:
        return [*checks, RuleCheck("finite", False, problem)]
    checks.append(RuleCheck("finite", True, ""))
    checks.append(_deterministic(rule, sample, first))
    checks.append(_elementwise(rule, sample, first))
    checks.append(_no_clock(rule, sample))
    return checks


def load_checked_rule(spec: str, *, base: Path | None = None) -> ScoreRule:
    """``load_rule(spec)``, refused in one line unless it passes every check (``check_rule``)."""
    rule = load_rule(spec, base=base)
    for check in check_rule(rule):
        if not check.passed:
            msg = f"{spec}: the rule fails the check {check.name!r}: {check.detail}"
            raise PolicyError(msg)
    return rule


def _deterministic(
    rule: ScoreRule, sample: dict[str, npt.NDArray[Any]], first: npt.NDArray[np.float64]
) -> RuleCheck:
    again = _attempt(lambda: _call(rule, sample))
    if isinstance(again, str):
        return RuleCheck("deterministic", False, f"a second call failed: {again}")
    differ = np.flatnonzero(again != first)
    if differ.size:
        i = int(differ[0])
        return RuleCheck(
            "deterministic",
            False,
            f"the same candidate scored {first[i]!r} and then {again[i]!r} "
            "(random numbers or state kept between calls?)",
        )
    return RuleCheck("deterministic", True, "")


def _elementwise(  # noqa: PLR0911 - one return per way a rule is not elementwise
    rule: ScoreRule, sample: dict[str, npt.NDArray[Any]], first: npt.NDArray[np.float64]
) -> RuleCheck:
    name = "elementwise"
    for i in range(0, _SAMPLE, 7):
        one = {key: value[i : i + 1].reshape(()) for key, value in sample.items()}
        scalar = _attempt(lambda one=one: _call(rule, one))  # type: ignore[misc]
        if isinstance(scalar, str):
            return RuleCheck(name, False, f"one candidate alone (0-d arrays) failed: {scalar}")
        if not _close(float(scalar), float(first[i])):
            return RuleCheck(
                name,
                False,
                f"candidate {i} scored {float(scalar)!r} alone but {float(first[i])!r} among "
                "others; score each candidate from its own values",
            )
    order = np.random.default_rng(1).permutation(_SAMPLE)
    shuffled = _attempt(lambda: _call(rule, {k: v[order] for k, v in sample.items()}))
    if isinstance(shuffled, str):
        return RuleCheck(name, False, f"the candidates in another order failed: {shuffled}")
    if not np.array_equal(shuffled, first[order]):
        return RuleCheck(name, False, "the candidates in another order scored differently")
    batch = {k: v.reshape(4, 6, _SAMPLE // 24) for k, v in sample.items()}
    batched = _attempt(lambda: _call(rule, batch))
    if isinstance(batched, str):
        return RuleCheck(name, False, f"a (runs, robots, carriers) batch failed: {batched}")
    if not np.array_equal(batched.reshape(-1), first):
        return RuleCheck(
            name, False, "a (runs, robots, carriers) batch scored differently from a flat list"
        )
    return RuleCheck(name, True, "")


def _no_clock(rule: ScoreRule, sample: dict[str, npt.NDArray[Any]]) -> RuleCheck:
    name = "no wall clock"
    held = getattr(rule.function, "__globals__", {})
    for key, value in held.items():
        for clock in _CLOCKS:
            if value is getattr(time, clock, None):
                return RuleCheck(name, False, f"its module holds time.{clock} as {key!r}")
    with _clocks_patched():
        outcome = _attempt(lambda: _call(rule, sample))
    if isinstance(outcome, str) and _ClockRead.__name__ in outcome:
        clock = outcome.rsplit(": ", 1)[-1]
        return RuleCheck(name, False, f"it reads the clock ({clock}); scores must not")
    return RuleCheck(name, True, "")


@contextmanager
def _clocks_patched() -> Iterator[None]:
    from unittest import mock  # noqa: PLC0415 - with asyncio, 20 ms of every command's start

    with ExitStack() as stack:
        for clock in _CLOCKS:
            if hasattr(time, clock):
                stack.enter_context(mock.patch.object(time, clock, _raiser(f"time.{clock}")))
        yield


def _raiser(label: str) -> Callable[..., Any]:
    def read(*_: object) -> object:
        raise _ClockRead(label)

    return read


def _attempt(call: Callable[[], npt.NDArray[np.float64]]) -> npt.NDArray[np.float64] | str:
    """The call's scores, or its ``PolicyError``'s message."""
    try:
        return call()
    except PolicyError as exc:
        return str(exc)


def _close(a: float, b: float) -> bool:
    return a == b or abs(a - b) <= _AGREE * max(abs(a), abs(b))
