"""Controllers as objects: ``simulate(controller=...)`` takes BUILTIN, a name or one's own."""

from __future__ import annotations

from dataclasses import replace

import pytest

from swarmtag.errors import ConfigError
from swarmtag.policy import Proximity, Urgency
from swarmtag.sim import BUILTIN, REFERENCE, Scenario, check_controller, simulate
from swarmtag.sim.builtin.controller import BuiltinController
from swarmtag.sim.controllers import controller_names, is_controller, named_controller
from swarmtag.sim.determinism import run_csv
from swarmtag.sim.model.state import Mode

SCENARIO = replace(Scenario.default(3, 7), ticks=400)


class CountingController(BuiltinController):
    """A user's controller: the built-in decisions, with each control step counted."""

    name = "counting"

    def __init__(self) -> None:
        self.calls = {"decide": 0, "arrive": 0, "carry": 0}

    def decide(self, before, s, **step):
        self.calls["decide"] += 1
        super().decide(before, s, **step)

    def arrive(self, before, s, **step):
        self.calls["arrive"] += 1
        return super().arrive(before, s, **step)

    def carry(self, s, answers, **step):
        self.calls["carry"] += 1
        return super().carry(s, answers, **step)


class IdleController(BuiltinController):
    """A user's controller that never lets a robot pursue a carrier: it only walks."""

    name = "idle"

    def decide(self, before, s, **step):
        super().decide(before, s, **step)
        pursuing = s.mode == Mode.PREDOCK
        s.mode[pursuing] = Mode.WALK
        s.target[pursuing] = -1


def _csv(result):
    return [run_csv(result, int(run)) for run in result.run_ids]


@pytest.mark.parametrize("backend", ["reference", "fast"])
def test_builtin_object_gives_the_same_bytes_as_its_name(backend):
    by_name = simulate(SCENARIO, Urgency(alpha=0.7), seed=3, runs=3, backend=backend)
    by_object = simulate(
        SCENARIO, Urgency(alpha=0.7), seed=3, runs=3, controller=BUILTIN, backend=backend
    )
    assert _csv(by_object) == _csv(by_name)


def test_a_user_written_controller_runs_through_simulate():
    mine = CountingController()
    result = simulate(SCENARIO, Proximity(), seed=1, runs=2, controller=mine)
    ticks = int(result.final_state.tick)
    assert mine.calls == {"decide": ticks, "arrive": ticks, "carry": ticks}
    assert _csv(result) == _csv(simulate(SCENARIO, Proximity(), seed=1, runs=2))
    check_controller(CountingController, SCENARIO, Proximity(), ticks=200)


@pytest.mark.first
def test_a_user_controller_that_decides_otherwise_changes_the_runs():
    longer = replace(SCENARIO, ticks=3000)
    result = simulate(longer, Proximity(), seed=1, runs=2, controller=IdleController())
    assert int(result.delivered.sum()) == 0
    assert int(simulate(longer, Proximity(), seed=1, runs=2).delivered.sum()) > 0


def test_a_user_controller_defaults_to_the_reference_backend_and_is_refused_by_fast():
    with pytest.raises(ConfigError, match="'fast' cannot run the 'counting' controller"):
        simulate(SCENARIO, Proximity(), seed=0, runs=1, controller=CountingController(),
                 backend="fast")  # fmt: skip


def test_objects_without_control_steps_and_unknown_names_are_refused():
    assert not is_controller(object())
    with pytest.raises(ConfigError, match="neither a controller name nor an object"):
        simulate(SCENARIO, Proximity(), seed=0, runs=1, controller=object())  # type: ignore[arg-type]
    with pytest.raises(ConfigError, match="'ros' is not one of builtin, bt"):
        simulate(SCENARIO, Proximity(), seed=0, runs=1, controller="ros")


def test_the_behaviour_tree_is_found_by_name_through_its_entry_point():
    assert controller_names()[:2] == ("builtin", "bt")
    made = named_controller("bt")()
    assert type(made).__module__ == "swarmtag.robot.sil"
    assert named_controller("builtin")() is BUILTIN


class LoggingBackend:
    """A user's backend object: the reference backend, with every batch it is asked for kept."""

    name = "logging"

    def __init__(self) -> None:
        self.batches = []

    def unavailable(self):
        return None

    def runs(self, controller):
        return REFERENCE.runs(controller)

    def memory(self, scenario, runs, *, record):
        return REFERENCE.memory(scenario, runs, record=record)

    def run(self, batch):
        self.batches.append(batch)
        return REFERENCE.run(batch)


def test_a_backend_object_of_ones_own_runs_through_simulate():
    mine = LoggingBackend()
    result = simulate(SCENARIO, Proximity(), seed=2, runs=3, run_offset=4, backend=mine)
    (batch,) = mine.batches
    assert (batch.seed, batch.runs, batch.run_offset, batch.controller) == (2, 3, 4, BUILTIN)
    assert _csv(result) == _csv(
        simulate(SCENARIO, Proximity(), seed=2, runs=3, run_offset=4, backend="fast")
    )
