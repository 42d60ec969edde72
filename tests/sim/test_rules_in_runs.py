"""A score rule of one's own in whole runs: as written, on the reference backend, said so."""

from __future__ import annotations

import warnings
from pathlib import Path

import pytest

from swarmtag.analysis import summarize
from swarmtag.errors import BackendFallback, PolicyError
from swarmtag.io import CarrierLog
from swarmtag.policy import Edf, Proximity, load_rule
from swarmtag.sim import Scenario, simulate
from swarmtag.sim.backends import fast_available
from swarmtag.sim.determinism import run_csv

EXAMPLES = Path(__file__).parents[1] / "policy" / "rule_examples.py"


def test_a_rule_ranking_urgency_first_runs_exactly_as_edf():
    # urgency * 100 - distance ranks like edf (urgency, then the nearer): the same bytes
    rule = load_rule(f"{EXAMPLES}:urgency_first")
    world = Scenario(robots=3, carriers=7)
    own = simulate(world, rule, seed=5, runs=6, backend="reference")
    builtin = simulate(world, Edf(), seed=5, runs=6)
    for run in range(6):
        mine = [part.replace(b"urgency_first", b"edf") for part in run_csv(own, run)]
        assert mine == list(run_csv(builtin, run))


def test_urgency_first_raises_priority_adherence_at_40_runs():
    # the rule's runs are edf's (the test above); edf runs on the fast backend here
    world = Scenario.default(3, 7, profile="paper-sim")  # the command line's default
    logs = [simulate(world, p, seed=1, runs=40).carriers for p in (Proximity(), Edf())]
    report = summarize(CarrierLog.concat(logs), n_resamples=2000, seed=1)
    pa = next(c for c in report.comparisons if c.metric == "pa")
    assert pa.diff > 0.1
    assert pa.p_bootstrap is not None
    assert pa.p_bootstrap < 0.01


def test_runs_go_to_the_reference_backend_with_a_note():
    rule = load_rule(f"{EXAMPLES}:oldest_first")
    world = Scenario(robots=2, carriers=3, ticks=200)
    asked = ["fast", None] if fast_available() else [None]
    reference = simulate(world, rule, seed=2, runs=2, backend="reference")
    for backend in asked:
        with pytest.warns(BackendFallback, match="'oldest_first' is Python code"):
            result = simulate(world, rule, seed=2, runs=2, backend=backend)
        assert run_csv(result, 0) == run_csv(reference, 0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        simulate(world, Edf(), seed=2, runs=1)


def test_a_rule_that_fails_mid_run_stops_the_run_with_its_message():
    rule = load_rule(f"{EXAMPLES}:raises")
    with pytest.raises(PolicyError, match="raised ValueError: no score today"):
        simulate(Scenario(robots=2, carriers=3, ticks=200), rule, seed=0, runs=1,
                 backend="reference")  # fmt: skip
