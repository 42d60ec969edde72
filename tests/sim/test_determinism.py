"""SPEC §4.5: a run gives the same bytes alone, in any batch, in another process, any policy."""

from __future__ import annotations

import hashlib
import subprocess
import sys

import pytest

from swarmtag.errors import DeterminismError
from swarmtag.policy import Proximity, Urgency
from swarmtag.sim import (
    Camera,
    Motion,
    Realism,
    Reprioritisation,
    Scenario,
    Walk,
    check_common_scenes,
    check_determinism,
    simulate,
)
from swarmtag.sim.determinism import run_csv

SCENARIO = Scenario(
    ticks=500,
    detection_radius=2.0,
    realism=Realism(advertisement_loss=0.1, detection_noise=0.02, breakdown=0.0002),
    reprioritisations=(Reprioritisation(tick=40, carrier=1, urgency=9),),
)


def test_check_determinism_alone_versus_batch():
    result = check_determinism(SCENARIO, Urgency(alpha=0.7), seed=12, runs=4, run_offset=3)
    assert result.run_ids.tolist() == [3, 4, 5, 6]


def test_any_batch_gives_the_same_rows_for_a_run():
    whole = simulate(SCENARIO, Proximity(), seed=2, runs=6)
    part = simulate(SCENARIO, Proximity(), seed=2, runs=3, run_offset=2)
    for run in (2, 3, 4):
        assert run_csv(whole, run) == run_csv(part, run)
    assert run_csv(whole, 0) != run_csv(whole, 1)


_CHILD = """
import hashlib, sys
from swarmtag.policy import Proximity
from swarmtag.sim import Realism, Reprioritisation, Scenario, simulate
from swarmtag.sim.determinism import run_csv
scenario = Scenario(
    ticks=500,
    detection_radius=2.0,
    realism=Realism(advertisement_loss=0.1, detection_noise=0.02, breakdown=0.0002),
    reprioritisations=(Reprioritisation(tick=40, carrier=1, urgency=9),),
)
result = simulate(scenario, Proximity(), seed=2, runs=1, run_offset=4)
carriers, events = run_csv(result, 4)
print(hashlib.sha256(carriers + events).hexdigest())
"""


def test_another_process_gives_the_same_bytes():
    here = simulate(SCENARIO, Proximity(), seed=2, runs=2, run_offset=3)
    carriers, events = run_csv(here, 4)
    child = subprocess.run(
        [sys.executable, "-c", _CHILD], capture_output=True, text=True, check=True
    )
    assert child.stdout.strip() == hashlib.sha256(carriers + events).hexdigest()


def test_same_initial_scene_under_every_policy():
    check_common_scenes(
        SCENARIO, [Proximity(), Urgency(alpha=0.7), Urgency(alpha=9.0)], seed=8, runs=5
    )
    proximity = simulate(SCENARIO, Proximity(), seed=8, runs=5).carriers
    urgency = simulate(SCENARIO, Urgency(alpha=9.0), seed=8, runs=5).carriers
    assert proximity.urgency0.tolist() == urgency.urgency0.tolist()
    assert proximity.order_time.tolist() == urgency.order_time.tolist()


def test_the_check_reports_a_run_that_differs(monkeypatch):
    from swarmtag.sim import determinism as checks

    real = checks.simulate
    calls = []

    def flaky(*args, **kwargs):
        calls.append(kwargs)
        result = real(*args, **kwargs)
        if len(calls) == 2:  # the first run computed alone
            return real(args[0], args[1], **{**kwargs, "seed": kwargs["seed"] + 1})
        return result

    monkeypatch.setattr(checks, "simulate", flaky)
    with pytest.raises(DeterminismError, match="run 0 of seed 1 under proximity"):
        check_determinism(Scenario(ticks=200), Proximity(), seed=1, runs=2)


SPLIT = Scenario(
    ticks=400,
    perception="split",
    camera=Camera(range=1.5, occlusion="carriers+robots", memory=5.0),
    walk=Walk(turn_interval=0.5, turn_angle=60.0),
    motion=Motion(avoid_taken_faces=True),
    realism=Realism(advertisement_loss=0.1, detection_noise=0.02),
)


def test_split_perception_and_a_turning_walk_are_deterministic_in_any_batch():
    result = check_determinism(SPLIT, Urgency(alpha=3.0), seed=5, runs=4, run_offset=1)
    assert result.events.kind.tolist().count("candidates") > 0
    assert check_common_scenes(SPLIT, [Proximity(), Urgency(alpha=9.0)], seed=5, runs=3) is None
