"""The simulator (SPEC §4): a batched, deterministic numpy model of the swarm and its tags.

Start with ``simulate``::

    from swarmtag.policy import Urgency
    from swarmtag.sim import Scenario, simulate

    result = simulate(Scenario.default(robots=3, carriers=7), Urgency(alpha=0.7),
                      seed=0, runs=100)
    result.carriers      # swarmtag.io.CarrierLog, one row per carrier per run
    result.events        # swarmtag.io.EventTable: selections, lifts, deliveries, ...

What this package exports:

- ``simulate`` -> ``SimResult``; ``Scenario`` (frozen, validated; TOML and
  mappings) and its parts (``Arena``, ``Bodies``, ``Motion``, ``Walk``,
  ``Radio``, ``Camera``, ``Timing``, ``UrgencyModel``, ``Realism``,
  ``Reprioritisation``, ``Warehouse``);
- profiles (``load_profile``, ``Profile``, ``PROFILES``, ``DEFAULT_PROFILE``):
  named presets of the free parameters;
- controllers: the ``Controller`` protocol with the step records one
  implementing it sees (``Arrivals``, ``LiftAnswers``, ``Carrying``), and the
  vectorised built-in one (``BUILTIN``, a ``BuiltinController``); per-robot
  controllers such as ``swarmtag.robot``'s tree see one robot through
  ``swarmtag.robot.SimRobotIO``;
- backends: ``Backend``, the protocol ``simulate(..., backend=)`` takes (its
  ``run`` computes a ``Batch``), and
  the shipped ``REFERENCE`` (numpy) and ``FAST`` (numba) ones;
- checks anyone can run on their own scenarios and controllers:
  ``check_determinism``, ``check_common_scenes``, ``check_controller`` (its
  finding: a ``Divergence``).

For other front ends and for tests, the layers underneath:

- ``make_params`` -> ``Params``: the scenario and policy in kernel units;
- ``sample_scene`` / ``Scene`` / ``initial_state`` -> ``WorldState`` (robots in a ``Mode``);
- ``RandomSource`` -> ``TickInputs``: the per-tick random numbers of SPEC §4.5;
- ``step(state, inputs, params, controller=BUILTIN) -> (state, TickEvents)``:
  the pure kernel (events by ``EventKind``);
- ``run_batch``: the loop, event logs, ``Trajectories`` (with their
  ``Geometry``), invariant checking.

Everything else (random-stream layout, invariants, controller memory fields,
the world's phases, the compiled kernel) is imported from its module:
``swarmtag.sim.model``, ``swarmtag.sim.world``, ``swarmtag.sim.control``,
``swarmtag.sim.runner``, ``swarmtag.sim.determinism``, ``swarmtag.sim.fast``.
See docs/simulator.md for the model, the defaults and the random-stream layout.
"""

from __future__ import annotations

from swarmtag.sim.backends import FAST, REFERENCE, Backend, Batch
from swarmtag.sim.builtin.controller import BUILTIN, BuiltinController
from swarmtag.sim.config.parts import (
    Arena,
    Bodies,
    Motion,
    Realism,
    Reprioritisation,
    Timing,
    UrgencyModel,
    Walk,
)
from swarmtag.sim.config.profiles import DEFAULT_PROFILE, PROFILES, Profile, load_profile
from swarmtag.sim.config.scenario import Scenario
from swarmtag.sim.config.sensors import Camera, Radio
from swarmtag.sim.config.warehouse import Warehouse
from swarmtag.sim.conformance import Divergence, check_controller
from swarmtag.sim.control.interface import Arrivals, Carrying, Controller, LiftAnswers
from swarmtag.sim.determinism import check_common_scenes, check_determinism
from swarmtag.sim.model.events import EventKind, TickEvents
from swarmtag.sim.model.params import Params, make_params
from swarmtag.sim.model.randomness import RandomSource, TickInputs
from swarmtag.sim.model.scene import sample_scene
from swarmtag.sim.model.state import Mode, Scene, WorldState, initial_state
from swarmtag.sim.model.step import step
from swarmtag.sim.outputs.trajectories import Geometry, Trajectories
from swarmtag.sim.runner import SimResult, run_batch
from swarmtag.sim.simulation import simulate

__all__ = [
    "BUILTIN",
    "DEFAULT_PROFILE",
    "FAST",
    "PROFILES",
    "REFERENCE",
    "Arena",
    "Arrivals",
    "Backend",
    "Batch",
    "Bodies",
    "BuiltinController",
    "Camera",
    "Carrying",
    "Controller",
    "Divergence",
    "EventKind",
    "Geometry",
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
    "TickEvents",
    "TickInputs",
    "Timing",
    "Trajectories",
    "UrgencyModel",
    "Walk",
    "Warehouse",
    "WorldState",
    "check_common_scenes",
    "check_controller",
    "check_determinism",
    "initial_state",
    "load_profile",
    "make_params",
    "run_batch",
    "sample_scene",
    "simulate",
    "step",
]
