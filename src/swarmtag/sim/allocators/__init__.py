"""Allocators: rules that look beyond one robot's view, as controllers (docs/allocators.md).

A condition such as ``threshold:theta=5`` parses into a
``swarmtag.policy.Allocator``; ``simulate`` runs it with
``allocating_controller(policy)``, the built-in controller whose choice
step is the allocator's (``swarmtag.sim.builtin.decide.Chooser``). Each
batch gets a fresh controller, so an allocator may keep state across a
run's ticks. They run on the reference backend.
"""

from __future__ import annotations

from swarmtag.sim.allocators.controller import AllocatingController, allocating_controller
from swarmtag.sim.allocators.oracle import assign

__all__ = ["AllocatingController", "allocating_controller", "assign"]
