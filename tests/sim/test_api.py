"""The public API of swarmtag.sim: exports, results, trajectories, the event table."""

from __future__ import annotations

import importlib

import numpy as np

import swarmtag.sim
from swarmtag.io import EVENT_SCHEMA, format_csv, parse_carrier_csv
from swarmtag.policy import Urgency
from swarmtag.sim import (
    EventKind,
    Mode,
    Realism,
    Reprioritisation,
    Scenario,
    WorldState,
    make_params,
    simulate,
    step,
)
from swarmtag.sim.model.randomness import RandomSource
from swarmtag.sim.runner import seeded_state

PUBLIC = {
    # running and results
    "simulate",
    "SimResult",
    # the scenario and its parts
    "Scenario",
    "Arena",
    "Bodies",
    "Motion",
    "Walk",
    "Radio",
    "Camera",
    "Timing",
    "UrgencyModel",
    "Realism",
    "Reprioritisation",
    "Warehouse",
    # profiles
    "load_profile",
    "Profile",
    "PROFILES",
    "DEFAULT_PROFILE",
    # controllers: the protocol, the records its steps see, the built-in one
    "Controller",
    "Arrivals",
    "LiftAnswers",
    "Carrying",
    "BUILTIN",
    "BuiltinController",
    # backends
    "Backend",
    "Batch",
    "REFERENCE",
    "FAST",
    # checks users run
    "check_determinism",
    "check_common_scenes",
    "check_controller",
    "Divergence",
    # the layers underneath, for advanced use
    "step",
    "run_batch",
    "Params",
    "make_params",
    "WorldState",
    "Scene",
    "Mode",
    "initial_state",
    "sample_scene",
    "RandomSource",
    "TickInputs",
    "TickEvents",
    "EventKind",
    "Trajectories",
    "Geometry",
}
"""The user-facing API; kernel internals are imported from their modules."""


def test_all_is_the_intended_public_api():
    assert set(swarmtag.sim.__all__) == PUBLIC
    assert len(swarmtag.sim.__all__) == len(PUBLIC)  # no name twice


def test_all_is_the_public_namespace():
    public = {
        name
        for name, value in vars(swarmtag.sim).items()
        if not name.startswith("_")
        and not isinstance(value, type(importlib))
        and name != "annotations"
    }
    assert set(swarmtag.sim.__all__) == public
    for name in swarmtag.sim.__all__:
        assert getattr(swarmtag.sim, name) is not None, name


def test_star_import_exposes_the_api_and_no_submodule():
    namespace: dict[str, object] = {}
    exec("from swarmtag.sim import *", namespace)
    namespace.pop("__builtins__")
    assert set(namespace) == PUBLIC
    modules = [name for name, value in namespace.items() if isinstance(value, type(importlib))]
    assert modules == []


def test_result_tables_and_counts():
    scenario = Scenario(
        ticks=800,
        realism=Realism(breakdown=0.001),
        reprioritisations=(Reprioritisation(tick=10, carrier=0, urgency=9),),
    )
    result = simulate(scenario, Urgency(alpha=0.7), seed=3, runs=3, run_offset=10)
    log = result.carriers
    assert len(log) == 3 * 7
    assert log.run.tolist() == [r for r in (10, 11, 12) for _ in range(7)]
    assert set(log.seed.tolist()) == {3}
    assert log.time_unit == "tick"
    assert parse_carrier_csv(format_csv(log)) == log
    delivered = (~np.isnan(log.delivery_time)).reshape(3, 7).sum(axis=1)
    assert result.delivered.tolist() == delivered.tolist()
    assert (result.delivered + result.undelivered == 7).all()
    assert (result.stuck <= result.breakdowns).all()
    events = result.events
    assert [spec.name for spec in EVENT_SCHEMA] == list(events.columns())
    assert set(events.kind.tolist()) <= {kind.label for kind in EventKind}
    assert (events.kind == "reprioritise").sum() == 3
    assert (events.kind == "breakdown").sum() == result.breakdowns.sum()


def test_trajectories_record_every_tick():
    result = simulate(Scenario(ticks=120), Urgency(alpha=0.7), seed=0, runs=2, record=True)
    traj = result.trajectories
    assert traj is not None
    assert traj.ticks == 120
    assert traj.time.tolist() == list(range(121))
    assert traj.robot_pos.shape == (2, 121, 3, 2)
    assert traj.carrier_pos.shape == (2, 121, 7, 2)
    assert traj.carrier_status.shape == traj.carrier_urgency.shape == (2, 121, 7)
    assert traj.geometry.arena == 3.75
    assert traj.geometry.detection_radius == 1.0
    assert traj.condition == "urgency:alpha=0.7"
    start = seeded_state(make_params(Scenario(ticks=120), Urgency(alpha=0.7)), seed=0, runs=2)
    assert np.array_equal(traj.robot_pos[:, 0], start.robot_pos)
    assert np.array_equal(traj.robot_pos[:, -1], result.final_state.robot_pos)
    assert set(np.unique(traj.robot_mode).tolist()) <= {int(m) for m in Mode}
    held = traj.carried_by >= 0
    runs, ticks, carriers = np.nonzero(held)
    holders = traj.carried_by[runs, ticks, carriers]
    assert np.array_equal(
        traj.carrier_pos[runs, ticks, carriers], traj.robot_pos[runs, ticks, holders]
    )


def test_step_is_pure():
    params = make_params(Scenario(), Urgency(alpha=0.7))
    state = seeded_state(params, seed=1, runs=2)
    source = RandomSource(params, seed=1, run_ids=state.run_ids)
    inputs = source.inputs(1)
    snapshot = state.copy()
    first, _ = step(state, inputs, params)
    second, _ = step(state, inputs, params)
    for name in ("robot_pos", "heading", "mode", "known_status", "carrier_pos", "status"):
        assert np.array_equal(getattr(state, name), getattr(snapshot, name))
        assert np.array_equal(getattr(first, name), getattr(second, name))
    assert isinstance(first, WorldState)
    assert first.tick == 1
    assert state.tick == 0
