"""``simulate``: seeded runs of a scenario under a policy, by any controller, on any backend."""

from __future__ import annotations

import warnings

from swarmtag._checks import MAX_RUN_INDEX, check_int
from swarmtag._resources import check_memory
from swarmtag.errors import BackendFallback, ConfigError
from swarmtag.policy import Allocator, Policy
from swarmtag.sim.backends import FAST, MAX_THREADS, REFERENCE, Backend, Batch, resolve_backend
from swarmtag.sim.builtin.controller import BUILTIN
from swarmtag.sim.config.scenario import Scenario
from swarmtag.sim.control.interface import Controller
from swarmtag.sim.controllers import is_controller, named_controller
from swarmtag.sim.model.params import make_params
from swarmtag.sim.runner import SimResult

__all__ = ["backend_for", "simulate"]


def _controller(controller: Controller | str) -> tuple[Controller, bool]:
    """The controller to run and whether ``simulate`` made it (and so closes it)."""
    if isinstance(controller, str):
        if controller == "builtin":
            return BUILTIN, False
        return named_controller(controller)(), True
    if not is_controller(controller):
        msg = (
            f"controller: {controller!r} is neither a controller name nor an object with "
            "decide, arrive and carry steps (swarmtag.sim.Controller)"
        )
        raise ConfigError(msg)
    return controller, False


def _close(controller: Controller, owned: bool) -> None:
    """Close a controller ``simulate`` made from a name (if it can be closed)."""
    close = getattr(controller, "close", None)
    if owned and callable(close):
        close()


def backend_for(controller: Controller | str, backend: Backend | str | None) -> Backend:
    """The backend ``simulate`` runs ``controller`` on (a name and its extra checked first)."""
    running, owned = _controller(controller)
    try:
        return resolve_backend(backend, controller=running)
    finally:
        _close(running, owned)


def _allocating(running: Controller, policy: Allocator) -> Controller:
    """The batch's allocating controller (``swarmtag.sim.allocators``); the built-in one only."""
    if running is not BUILTIN:
        name = getattr(running, "name", type(running).__name__)
        msg = (
            f"controller: allocator {policy.name!r} runs with the built-in controller, not {name!r}"
        )
        raise ConfigError(msg)
    from swarmtag.sim.allocators import allocating_controller  # noqa: PLC0415 - on use

    return allocating_controller(policy)


def _runs_rule(chosen: Backend, policy: Policy) -> Backend:
    """``chosen``, or the reference backend where ``chosen`` is compiled and the rule is Python.

    Says so with a ``BackendFallback`` warning (the command line's stderr note).
    """
    checked: object = policy
    if chosen is not FAST or not isinstance(checked, Policy) or checked.compiled:
        return chosen
    what = (
        "is an allocator, which the compiled backend does not run"
        if isinstance(checked, Allocator)
        else "is Python code, which the compiled backend cannot call"
    )
    msg = (
        f"condition {policy.name!r} {what}; its runs go to the reference backend "
        "(the same results, slower: docs/performance.md)"
    )
    warnings.warn(msg, BackendFallback, stacklevel=3)
    return REFERENCE


def simulate(
    scenario: Scenario,
    policy: Policy,
    *,
    seed: int,
    runs: int,
    run_offset: int = 0,
    record: bool = False,
    check: bool = False,
    controller: Controller | str = "builtin",
    backend: Backend | str | None = None,
    threads: int | None = None,
) -> SimResult:
    """Simulate runs ``run_offset ..`` of master ``seed`` under ``policy`` (SPEC §4).

    Run ``i`` is a pure function of (scenario, policy, seed, i): the same rows
    alone or in any batch. ``record=True`` keeps per-tick trajectories;
    ``check=True`` verifies the world invariants every tick (slower).
    ``controller``: any ``swarmtag.sim.Controller`` object, or a name:
    ``"builtin"`` (``BUILTIN``, vectorised, the default), ``"bt"`` (each robot
    under its own behaviour tree, ``swarmtag.robot``; same event logs) or one
    a package registers (``swarmtag.sim.controllers``). An object passed in
    is used as it is (a stateful one serves one call); one made from a name
    is closed after the batch.
    ``backend``: a ``swarmtag.sim.Backend`` or its name, ``"reference"``
    (numpy) or ``"fast"`` (compiled with numba; the same bytes); ``None``
    picks ``fast`` where numba is installed and the controller is built in.
    A rule of one's own (``swarmtag.policy.ScoreRule``, Python code) runs on
    the reference backend where ``fast`` was asked for or is the default,
    with a ``BackendFallback`` warning.
    ``threads``: threads the fast backend runs runs on (default: every core,
    or ``SWARMTAG_THREADS``).

    >>> from swarmtag.policy import Urgency
    >>> result = simulate(Scenario(ticks=600), Urgency(alpha=0.7), seed=1, runs=2)
    >>> len(result.carriers), result.carriers.conditions, result.carriers.time_unit
    (14, ('urgency:alpha=0.7',), 'tick')
    """
    checked: object = scenario
    if not isinstance(checked, Scenario):
        msg = f"scenario: {checked!r} is not a Scenario"
        raise ConfigError(msg)
    runs = check_int("runs", runs, low=1, high=MAX_RUN_INDEX)
    if threads is not None:
        threads = check_int("threads", threads, low=1, high=MAX_THREADS)
    running, owned = _controller(controller)
    try:
        chosen = _runs_rule(resolve_backend(backend, controller=running), policy)
        if isinstance(policy, Allocator):
            running = _allocating(running, policy)
        check_memory(
            f"{runs} runs of {scenario.robots} robots and {scenario.carriers} carriers",
            chosen.memory(scenario, runs, record=record),
            error=ConfigError,
        )
        params = make_params(scenario, policy)
        batch = Batch(
            params, running, seed, runs, run_offset, record=record, check=check, threads=threads
        )
        return chosen.run(batch)
    finally:
        _close(running, owned)
