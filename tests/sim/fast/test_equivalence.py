"""The compiled backend gives the reference's event logs and final states, byte for byte.

Every mechanic is switched on somewhere below: both perception models, every
occlusion setting, sighting memory, both urgency models, every realism
option, re-prioritisations (also several in one tick), the correlated walk,
with and without taken-face avoidance, small and larger swarms, all three
policies. Each case runs a few runs of one seed; the property test draws
scenarios at random.

The cases run only as long as it takes every event they are there for to
happen (``EVENTS``, asserted: a case made too short fails), one comparison
of 200 runs stays at the published length (``test_hundreds_of_runs_agree``),
and ``SWARMTAG_LONG_TESTS=1`` (``tests/long_mode.py``) runs every case at its
full length, as before the suite was sized for two cores.
"""

from __future__ import annotations

from dataclasses import replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmtag.policy import Edf, Proximity, Urgency, Weighted
from swarmtag.sim import (
    Camera,
    Motion,
    Radio,
    Realism,
    Reprioritisation,
    Scenario,
    Timing,
    UrgencyModel,
    Walk,
)
from tests.long_mode import length
from tests.sim.fast.helpers import compare

POLICIES = [Proximity(), Urgency(alpha=0.7), Urgency(alpha=9.0), Weighted(w=0.3)]

PAPER = replace(Scenario.default(3, 7), ticks=length(700, 1500))
"""The paper's set-up: the first deliveries come from tick 550 on (the last policy's by 700)."""
PAPER_LATE = replace(PAPER, ticks=length(800, 1500))
"""``PAPER`` for cameras and searches that find their first carrier later (100 ticks more)."""
LAB = Scenario.default(3, 7, profile="lab")
BASE = replace(Scenario.default(3, 7, profile="base"), ticks=length(800, 1200))
"""The base profile (0.1 s ticks): every run delivers all seven carriers and ends by tick 750."""


def warehouse(robots: int, ticks: int, **part: object) -> Scenario:
    """A warehouse on the lab profile (seconds, the calibrated handling times)."""
    lab = LAB.to_mapping()
    return Scenario.from_mapping({**lab, "robots": robots, "ticks": ticks, "warehouse": part})


CASES = {
    "paper-sim": PAPER,
    "paper-sim-5x10": replace(Scenario.default(5, 10), ticks=length(750, 800)),
    "lab-static": replace(
        LAB, urgency=UrgencyModel(model="static", static_time_limit=length(900, 2500))
    ),
    "base-disc": BASE,
    "realism": replace(
        PAPER,
        ticks=length(700, 900),
        realism=Realism(
            advertisement_loss=0.2,
            status_delay=3,
            detection_noise=0.03,
            speed_variation=0.2,
            breakdown=0.0005,
        ),
    ),
    "disc-realism": replace(
        BASE, realism=Realism(advertisement_loss=0.3, detection_noise=0.05, breakdown=0.001)
    ),
    "memory-robots-occlude": replace(  # full length: a sighting's expiry decides seldom
        PAPER, ticks=1500, camera=Camera(range=2.0, occlusion="carriers+robots", memory=4.0)
    ),
    "robots-occlude": replace(PAPER, camera=Camera(range=3.6, occlusion="carriers+robots")),
    "no-occlusion-short-camera": replace(PAPER_LATE, camera=Camera(range=1.2, occlusion="none")),
    "camera-fade": replace(PAPER_LATE, camera=Camera(range=1.5, fade=1.0, occlusion="carriers")),
    "camera-fade-memory": replace(PAPER_LATE, camera=Camera(range=1.2, fade=0.8, memory=3.0)),
    "camera-bearing": replace(
        PAPER_LATE, camera=Camera(range=1.5, fade=1.0, occlusion="carriers", bearing="dots")
    ),
    "camera-bearing-memory-disc": replace(
        PAPER_LATE, camera=Camera(range=1.2, memory=3.0, bearing="dots")
    ),
    "look-around": replace(
        PAPER_LATE,
        camera=Camera(range=1.5, fade=1.0, occlusion="carriers", bearing="dots", look_around=1.0),
    ),
    "memory-drift": replace(PAPER_LATE, camera=Camera(range=1.5, memory=20.0, drift=0.3)),
    "look-around-memory-noise": replace(
        PAPER,
        ticks=900,  # the first deliveries by tick 825
        camera=Camera(range=1.2, memory=0.3, bearing="dots", look_around=0.8, drift=0.1),
        realism=Realism(detection_noise=0.03, advertisement_loss=0.2),
        walk=Walk(curve=90.0),
    ),
    "slow-radio": replace(PAPER, radio=Radio(range=3.0, interval=0.7)),
    "ble-search": replace(
        PAPER_LATE, camera=Camera(range=1.0, occlusion="carriers"), radio=Radio(search=True)
    ),
    "ble-search-exact-memory-turns": replace(
        PAPER_LATE,
        camera=Camera(range=0.8, memory=2.0),
        radio=Radio(search=True, shadowing=0.0, smoothing=1.0, range=2.5),
        walk=Walk(turn_interval=0.4, turn_angle=75.0),
    ),
    "ble-search-realism": replace(
        PAPER,
        ticks=length(800, 900),
        camera=Camera(range=1.2, fade=0.6),
        radio=Radio(search=True, shadowing=8.0, path_loss_exponent=2.7),
        realism=Realism(advertisement_loss=0.3, status_delay=2, detection_noise=0.03),
    ),
    "turning-walk": replace(PAPER, walk=Walk(turn_interval=0.4, turn_angle=75.0)),
    "curved-walk": replace(LAB, ticks=length(900, 3000), walk=Walk(curve=90.0)),
    "curved-walk-search": replace(
        PAPER_LATE,
        camera=Camera(range=1.0, bearing="dots"),
        radio=Radio(search=True),
        walk=Walk(curve=240.0),
    ),
    "reprioritised": replace(
        PAPER_LATE,  # past the write at tick 700
        reprioritisations=(
            Reprioritisation(tick=60, carrier=2, urgency=9),
            Reprioritisation(tick=60, carrier=3, urgency=0),
            Reprioritisation(tick=60, carrier=3, urgency=4),
            Reprioritisation(tick=700, carrier=1, urgency=5),
        ),
    ),
    "herding-no-avoidance": replace(
        BASE,
        detection_radius=3.6,
        motion=replace(BASE.motion, avoid_taken_faces=False),
    ),
    "quick-handling": replace(
        PAPER, timing=Timing(dock=0.0, lift=0.0, release=0.0, pursuit_timeout=2.0, cooldown=1.0)
    ),
    "crowded-20x40": replace(Scenario.default(20, 40), ticks=400),
    "grid-placed-20x40": replace(
        Scenario.default(20, 40), ticks=400, arena=None, arena_scaling=0.3
    ),
    "warehouse": warehouse(8, length(900, 1500), order_interval=12.0, initial_orders=6),
}
HALL = replace(
    warehouse(30, 1800, map="warehouse-hall", order_interval=3.0, initial_orders=20),
    realism=Realism(status_delay=3, advertisement_loss=0.1, speed_variation=0.2),
)
"""The large map, with realism: one policy, in a test of its own (30 robots, 1,800 ticks)."""

HANDLING = frozenset({"select", "lift", "deliver", "abandon"})
EVENTS = dict.fromkeys(CASES, HANDLING) | {
    "realism": HANDLING | {"breakdown"},
    "disc-realism": HANDLING | {"breakdown"},
    "look-around-memory-noise": HANDLING - {"abandon"},  # none in 900 ticks
    "reprioritised": HANDLING | {"reprioritise"},
    "herding-no-avoidance": HANDLING | {"timeout"},
    "quick-handling": HANDLING | {"timeout"},
    "crowded-20x40": frozenset({"select"}),  # the crowd: collisions and choices, no lift yet
    "grid-placed-20x40": frozenset({"select", "lift"}),
    "warehouse": HANDLING | {"arrive"},
}
"""The events each case's runs show in every policy: what the comparison is there to compare."""
ENDING = frozenset({"base-disc", "disc-realism", "herding-no-avoidance"})
"""Cases some of whose runs deliver every carrier and end early (the end of a run compared)."""

ONE_RUN_EACH = {"grid-placed-20x40": length(1, 2)}
"""Runs per policy where not 4, each policy on runs of its own: a run of the grid placement of
20 x 40 takes about half a second in the reference backend, and the scene does not depend on
the policy, so four policies test four scenes."""


SEED, RUNS, OFFSET = 11, 4, 3
"""The runs each case compares (``RUNS`` from run ``OFFSET`` of seed ``SEED``), but
``ONE_RUN_EACH``; ``test_tag_cache`` compares its sparse caches on the same runs."""


@pytest.mark.parametrize("policy", POLICIES, ids=lambda p: p.name)
@pytest.mark.parametrize("case", list(CASES))
def test_backends_agree(case, policy):
    runs, offset = RUNS, OFFSET
    if case in ONE_RUN_EACH:
        runs = ONE_RUN_EACH[case]
        offset += POLICIES.index(policy) * runs
    fast = compare(CASES[case], policy, seed=SEED, runs=runs, run_offset=offset)
    missing = EVENTS[case] - set(fast.events.kind.tolist())
    assert not missing, f"{case}: no {sorted(missing)} in the compared runs: too short?"
    if case in ENDING:
        assert (fast.end_tick < CASES[case].run_ticks).any(), f"{case}: no run ended early"


@pytest.mark.first
def test_the_warehouse_hall_places_orders_and_delivers():
    # the hall only tests the warehouse if orders arrive and robots deliver them (the small
    # warehouse case asserts the same in test_backends_agree)
    result = compare(HALL, Urgency(alpha=0.7), seed=11, runs=2, run_offset=3)
    assert (result.events.kind == "arrive").sum() > 0
    assert result.delivered.sum() > 0


@pytest.mark.first
def test_hundreds_of_runs_agree():
    # the published set-up: 200 runs at full length, the urgency policy most sensitive to order
    result = compare(
        replace(Scenario.default(3, 7), ticks=3000), Urgency(alpha=9.0), seed=5, runs=200
    )
    assert result.delivered.sum() > 0


@pytest.mark.parametrize(
    "scenario",
    [PAPER, CASES["warehouse"], CASES["reprioritised"]],
    ids=["lab", "warehouse", "reprioritised"],
)
def test_recorded_and_checked_runs_agree(scenario):
    reference = compare(scenario, Urgency(alpha=3.0), seed=2, runs=2, record=True, check=True)
    assert reference.trajectories is not None


motions = st.builds(
    Motion,
    speed=st.sampled_from([0.2, 0.5, 1.0]),
    turn_rate=st.sampled_from([45.0, 90.0, 400.0]),
    arrival_tolerance=st.sampled_from([0.005, 0.01, 0.03]),
    collision_iterations=st.integers(1, 8),
    avoid_taken_faces=st.booleans(),
)
cameras = st.builds(
    Camera,
    range=st.sampled_from([0.8, 1.5, 3.6]),
    occlusion=st.sampled_from(["none", "carriers", "carriers+robots"]),
    memory=st.sampled_from([0.0, 0.0, 1.0, 6.0]),
    fade=st.sampled_from([0.0, 0.0, 0.5, 1.5]),
    bearing=st.sampled_from(["uniform", "uniform", "dots"]),
    look_around=st.sampled_from([0.0, 0.0, 0.5]),
    drift=st.sampled_from([0.0, 0.0, 0.2]),
)
realisms = st.builds(
    Realism,
    advertisement_loss=st.sampled_from([0.0, 0.25]),
    status_delay=st.integers(0, 4),
    detection_noise=st.sampled_from([0.0, 0.02]),
    speed_variation=st.sampled_from([0.0, 0.3]),
    breakdown=st.sampled_from([0.0, 0.002]),
)


@st.composite
def scenarios(draw: st.DrawFn) -> Scenario:
    """A short scenario with every setting drawn at random."""
    tick = draw(st.sampled_from([0.02, 0.1, 0.25]))
    motion = draw(motions.filter(lambda m: m.speed * tick <= 0.125))  # at most a radius a tick
    base = Scenario.default(draw(st.integers(1, 8)), draw(st.integers(1, 12)), profile="base")
    model = draw(st.sampled_from(["growing", "static"]))
    perception = draw(st.sampled_from(["disc", "split"]))
    camera = draw(cameras)
    if perception == "disc":  # a look round needs split perception
        camera = replace(camera, look_around=0.0)
    return replace(
        base,
        ticks=300,
        tick=tick,
        perception=perception,
        detection_radius=1.5,
        motion=motion,
        camera=camera,
        realism=draw(realisms),
        walk=draw(
            st.sampled_from([Walk(), Walk(turn_interval=0.3, turn_angle=90.0), Walk(curve=90.0)])
        ),
        urgency=UrgencyModel(model=model, static_time_limit=300),
    )


@pytest.mark.first
@settings(max_examples=length(40, 200))
@given(scenario=scenarios(), policy=st.sampled_from(POLICIES), seed=st.integers(0, 2**32))
def test_random_scenarios_agree(scenario, policy, seed):
    compare(scenario, policy, seed=seed, runs=2)


LARGE = replace(Scenario.default(120, 128), ticks=200)
"""Beyond ``_layout.GRID_FROM`` robots and carriers: every grid path of the compiled kernel."""


@pytest.mark.parametrize(
    "scenario",
    [
        LARGE,
        replace(LARGE, camera=Camera(range=3.6, occlusion="carriers+robots")),
        replace(LARGE, camera=Camera(range=0.3, occlusion="carriers+robots", memory=2.0)),
        replace(LARGE, camera=Camera(range=1.0, fade=1.2, occlusion="carriers")),
        replace(LARGE, camera=Camera(range=1.2, fade=0.6, occlusion="carriers", bearing="dots")),
        replace(LARGE, camera=Camera(range=1.2, occlusion="carriers", look_around=1.0)),
        replace(LARGE, camera=Camera(range=0.8, memory=3.0, drift=0.2), ticks=150),
        replace(LARGE, perception="disc", detection_radius=2.0),
        replace(LARGE, realism=Realism(advertisement_loss=0.2, detection_noise=0.02)),
        replace(LARGE, radio=Radio(range=0.8, interval=0.3)),  # the radio grid leaves tags out
        warehouse(120, 200, map="warehouse-hall", order_interval=0.5, initial_orders=40),
        replace(
            warehouse(120, 200, map="warehouse-hall", order_interval=0.5, initial_orders=40),
            radio=Radio(range=3.0, interval=0.3),  # the radio grid across shelves
        ),
    ],
    ids=[
        "grids",
        "robots-occlude",
        "memory",
        "fade",
        "bearing",
        "look-around",
        "drift",
        "disc",
        "realism",
        "short-radio",
        "warehouse",
        "warehouse-short-radio",
    ],
)
def test_large_swarms_agree(scenario):
    compare(scenario, Urgency(alpha=3.0), seed=21, runs=2)


@pytest.mark.parametrize("case", ["paper-sim", "camera-bearing", "look-around"])
def test_earliest_deadline_first_agrees(case):
    result = compare(CASES[case], Edf(), seed=7, runs=3)
    assert result.delivered.sum() > 0
