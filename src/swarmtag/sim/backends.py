"""Simulation backends as objects: the numpy reference kernel and the compiled one (numba).

Both give byte-identical event logs for the same (scenario, policy, seed,
run). ``simulate(..., backend=)`` takes a ``Backend`` object or its name;
``None`` picks ``FAST`` where numba is installed and the controller is the
built-in one, else ``REFERENCE``. A backend of one's own implements the
``Backend`` protocol (a name, whether it runs here, which controllers it
runs, its memory estimate and ``run``, which computes a ``Batch``).
"""

from __future__ import annotations

import importlib.util
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Final, Protocol, runtime_checkable

from swarmtag._checks import check_choice
from swarmtag._resources import check_memory
from swarmtag.errors import ConfigError
from swarmtag.sim.builtin.controller import BUILTIN
from swarmtag.sim.config.scenario import Scenario
from swarmtag.sim.control.interface import Controller
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import RandomSource
from swarmtag.sim.runner import SimResult, batch_memory, batch_result, run_batch, seeded_state

__all__ = [
    "BACKENDS",
    "FAST",
    "MAX_THREADS",
    "REFERENCE",
    "Backend",
    "Batch",
    "FastBackend",
    "ReferenceBackend",
    "fast_available",
    "resolve_backend",
]

MAX_THREADS: Final = 1024
"""Most threads the compiled backend is asked to use."""


@dataclass(frozen=True, eq=False)
class Batch:
    """What ``simulate`` asks a backend for: runs ``run_offset ..`` of master ``seed``."""

    params: Params
    controller: Controller
    seed: int
    runs: int
    run_offset: int = 0
    record: bool = False
    """Keep per-tick trajectories."""
    check: bool = False
    """Verify the world invariants every tick."""
    threads: int | None = None
    """Threads over runs (the compiled backend's; None: its default)."""


@runtime_checkable
class Backend(Protocol):
    """What ``simulate`` needs of a backend."""

    name: str
    """The shorthand ``simulate``, the CLI and study files accept for it."""

    def unavailable(self) -> str | None:
        """Why the backend cannot run here (a missing extra), or None when it can."""
        ...

    def runs(self, controller: Controller) -> bool:
        """Whether the backend can run ``controller``."""
        ...

    def memory(self, scenario: Scenario, runs: int, *, record: bool) -> float:
        """Estimated peak bytes of one batch of ``runs`` runs of ``scenario``."""
        ...

    def run(self, batch: Batch) -> SimResult:
        """The batch's runs: the seeded start, every tick, the logs."""
        ...


class _Shipped:
    """What the two shipped backends share: their memory estimates (``runner.batch_memory``)."""

    name: str

    def memory(self, scenario: Scenario, runs: int, *, record: bool) -> float:
        """``runner.batch_memory`` for this backend."""
        return batch_memory(scenario, runs, record=record, backend=self.name)


class ReferenceBackend(_Shipped):
    """The numpy reference kernel: any controller, ticks in a Python loop, vectorised over runs."""

    name = "reference"

    def unavailable(self) -> str | None:
        """Always available (numpy only)."""
        return None

    def runs(self, controller: Controller) -> bool:
        """Every controller."""
        return True

    def run(self, batch: Batch) -> SimResult:
        """Seeded start, ``run_batch`` (``threads`` is the compiled backend's; unused here)."""
        params, seed = batch.params, batch.seed
        state = seeded_state(
            params, seed=seed, runs=batch.runs, run_offset=batch.run_offset, backend=self.name
        )
        source = RandomSource(params, seed=seed, run_ids=state.run_ids)
        return run_batch(
            state, params, source, seed=seed, record=batch.record, check=batch.check,
            controller=batch.controller,
        )  # fmt: skip


class FastBackend(_Shipped):
    """The compiled kernel (numba, the ``fast`` extra): the built-in controller, runs on threads."""

    name = "fast"

    def unavailable(self) -> str | None:
        """Says numba is missing, if it is."""
        if fast_available():
            return None
        return "backend: 'fast' needs numba (install the fast extra: pip install 'swarmtag[fast]')"

    def runs(self, controller: Controller) -> bool:
        """The built-in controller only (compiled with the world)."""
        return controller is BUILTIN

    def run(self, batch: Batch) -> SimResult:
        """The batch on the compiled kernel, ``threads`` threads over runs.

        A batch whose sparse tag caches overflow (``sim/fast/_tag_cache.py``)
        starts again from its seeded start with twice the room (if it fits in
        memory): the same bytes.
        """
        from swarmtag.sim.fast import TagCacheFull, simulate_fast  # noqa: PLC0415 - numba extra

        params, seed, runs, record = batch.params, batch.seed, batch.runs, batch.record
        capacity = None
        while True:
            state = seeded_state(
                params, seed=seed, runs=runs, run_offset=batch.run_offset, backend=self.name
            )
            try:
                final, events, breakdowns, recorder = simulate_fast(
                    state, params, seed=seed, record=record, check=batch.check,
                    threads=batch.threads,
                    adopt=True, cache_capacity=capacity,
                )  # fmt: skip
            except TagCacheFull as full:
                capacity = full.capacity
                need = batch_memory(
                    params.scenario, runs, record=record, backend=self.name, cache_capacity=capacity
                )
                what = f"{runs} runs of {params.robots} robots with {capacity} tag cache entries"
                check_memory(what, need, error=ConfigError)
                continue
            return batch_result(
                final, params, seed=seed, events=events, breakdowns=breakdowns, recorder=recorder
            )


REFERENCE: Final = ReferenceBackend()
FAST: Final = FastBackend()
BACKENDS: Final[Mapping[str, Backend]] = MappingProxyType(
    {backend.name: backend for backend in (REFERENCE, FAST)}
)
"""The shipped backends by name (the shorthands ``simulate`` and the CLI accept)."""


def fast_available() -> bool:
    """Whether the compiled backend can run here (numba is installed)."""
    return importlib.util.find_spec("numba") is not None


def resolve_backend(backend: Backend | str | None, *, controller: Controller = BUILTIN) -> Backend:
    """The backend to run ``controller`` on: ``backend`` checked, or the default for ``None``.

    The default is ``FAST`` where numba is installed and the controller is
    the built-in one, else ``REFERENCE`` (the two give the same bytes).

    >>> resolve_backend("reference").name
    'reference'
    """
    if backend is None:
        return FAST if FAST.runs(controller) and FAST.unavailable() is None else REFERENCE
    if isinstance(backend, str):
        backend = BACKENDS[check_choice("backend", backend, tuple(BACKENDS))]
    checked: object = backend
    if not isinstance(checked, Backend):
        msg = f"backend: {checked!r} is neither a backend name nor a swarmtag.sim.Backend"
        raise ConfigError(msg)
    reason = backend.unavailable()
    if reason is not None:
        raise ConfigError(reason)
    if not backend.runs(controller):
        name = getattr(controller, "name", type(controller).__name__)
        msg = (
            f"backend: {backend.name!r} cannot run the {name!r} controller; "
            "the reference backend runs every controller"
        )
        raise ConfigError(msg)
    return backend
