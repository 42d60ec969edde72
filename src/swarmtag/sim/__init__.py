"""The simulator (SPEC §4): a batched, deterministic numpy model of the swarm and its tags.

Start with ``simulate``::

    from swarmtag.policy import Urgency
    from swarmtag.sim import Scenario, simulate

    result = simulate(Scenario.default(robots=3, carriers=7), Urgency(alpha=0.7),
                      seed=0, runs=100)
    result.carriers      # swarmtag.io.CarrierLog, one row per carrier per run
    result.events        # swarmtag.io.EventTable: selections, lifts, deliveries, ...

The layers underneath, for other front ends and for tests:

- ``Scenario`` (frozen, validated; TOML and mappings) and its parts;
- profiles (``load_profile``, ``Profile``): named presets of the free parameters;
- ``make_params`` -> ``Params``: the scenario and policy in kernel units;
- ``sample_scene`` / ``Scene`` / ``initial_state`` -> ``WorldState``;
- ``RandomSource`` -> ``TickInputs``: the per-tick random numbers of SPEC §4.5;
- ``step(state, inputs, params, controller=BUILTIN) -> (state, TickEvents)``:
  the pure kernel; the world's phases around a ``Controller``'s three steps
  (``BUILTIN``: the vectorised built-in controller; ``SimRobotIO``: one
  robot's view for a per-robot controller such as ``swarmtag.robot``'s tree);
- ``run_batch``: the loop, event logs, trajectories, invariant checking;
- ``check_determinism`` / ``check_common_scenes``: checks anyone can run.

See docs/simulator.md for the model, the defaults and the random-stream layout.
"""

from __future__ import annotations

from swarmtag.sim.builtin import BUILTIN, BuiltinController
from swarmtag.sim.checks import check_common_scenes, check_determinism, run_csv
from swarmtag.sim.control import (
    COMMAND_FIELDS,
    MEMORY_FIELDS,
    Arrivals,
    Carrying,
    Controller,
    LiftAnswers,
)
from swarmtag.sim.events import EventKind, TickEvents
from swarmtag.sim.groups import (
    Arena,
    Bodies,
    Motion,
    Realism,
    Reprioritisation,
    Timing,
    UrgencyModel,
    Walk,
)
from swarmtag.sim.invariants import OVERLAP_TOLERANCE, check_tick
from swarmtag.sim.kernel import step
from swarmtag.sim.params import Params, make_params
from swarmtag.sim.profiles import DEFAULT_PROFILE, PROFILES, Profile, load_profile
from swarmtag.sim.randomness import RandomSource, Stream, TickInputs, due_writes, stream
from swarmtag.sim.robot_view import SimRobotIO, StepContext
from swarmtag.sim.runner import (
    CONTROLLERS,
    InputSource,
    SimResult,
    run_batch,
    seeded_state,
    simulate,
)
from swarmtag.sim.scenario import Scenario
from swarmtag.sim.scene import sample_scene
from swarmtag.sim.sensors import Camera, Radio
from swarmtag.sim.state import Mode, Scene, WorldState, initial_state
from swarmtag.sim.trajectories import Geometry, Trajectories

__all__ = [
    "BUILTIN",
    "COMMAND_FIELDS",
    "CONTROLLERS",
    "DEFAULT_PROFILE",
    "MEMORY_FIELDS",
    "OVERLAP_TOLERANCE",
    "PROFILES",
    "Arena",
    "Arrivals",
    "Bodies",
    "BuiltinController",
    "Camera",
    "Carrying",
    "Controller",
    "EventKind",
    "Geometry",
    "InputSource",
    "LiftAnswers",
    "Mode",
    "Motion",
    "Params",
    "Profile",
    "Radio",
    "RandomSource",
    "Realism",
    "Reprioritisation",
    "Scenario",
    "Scene",
    "SimResult",
    "SimRobotIO",
    "StepContext",
    "Stream",
    "TickEvents",
    "TickInputs",
    "Timing",
    "Trajectories",
    "UrgencyModel",
    "Walk",
    "WorldState",
    "check_common_scenes",
    "check_determinism",
    "check_tick",
    "due_writes",
    "initial_state",
    "load_profile",
    "make_params",
    "run_batch",
    "run_csv",
    "sample_scene",
    "seeded_state",
    "simulate",
    "step",
    "stream",
]
