"""Controllers by object or by name: the built-in one, and those packages register by name.

``simulate(..., controller=)`` takes any object with the three control
steps of ``swarmtag.sim.Controller`` (``decide``, ``arrive``, ``carry``), or
a name: ``"builtin"`` (``BUILTIN``) or one registered under the entry-point
group ``swarmtag.controllers`` (this package registers ``"bt"``, the
behaviour tree of ``swarmtag.robot``, there; so the simulator never imports
the robot package). A named entry point is a factory called once per batch;
what it makes is closed after the batch if it has ``close()``.
"""

from __future__ import annotations

from collections.abc import Callable
from importlib.metadata import EntryPoint, entry_points
from typing import Final

from swarmtag.errors import ConfigError
from swarmtag.sim.builtin.controller import BUILTIN
from swarmtag.sim.control.interface import Controller

__all__ = ["CONTROLLER_GROUP", "controller_names", "is_controller", "named_controller"]

CONTROLLER_GROUP: Final = "swarmtag.controllers"
"""The entry-point group of named controllers (``name = "module:factory [extra]"``)."""
_STEPS: Final = ("decide", "arrive", "carry")


def is_controller(candidate: object) -> bool:
    """Whether ``candidate`` has the three control steps of ``Controller`` (callables)."""
    return all(callable(getattr(candidate, step, None)) for step in _STEPS)


def _registered() -> dict[str, EntryPoint]:
    """The named controllers the installed packages register."""
    return {entry.name: entry for entry in entry_points(group=CONTROLLER_GROUP)}


def controller_names() -> tuple[str, ...]:
    """Every name ``simulate`` accepts: ``builtin`` first, then the registered ones, sorted."""
    return ("builtin", *sorted(set(_registered()) - {"builtin"}))


def named_controller(name: str) -> Callable[[], Controller]:
    """The factory of the controller called ``name`` (``ConfigError`` naming what is missing).

    >>> named_controller("builtin")() is BUILTIN
    True
    """
    if name == "builtin":
        return lambda: BUILTIN
    entry = _registered().get(name)
    if entry is None:
        msg = f"controller: {name!r} is not one of {', '.join(controller_names())}"
        raise ConfigError(msg)
    try:
        factory = entry.load()
    except ModuleNotFoundError as missing:
        extras = ",".join(entry.extras)
        hint = f" (install the {extras} extra: pip install 'swarmtag[{extras}]')" if extras else ""
        msg = f"controller: {name!r} needs {missing.name}{hint}"
        raise ConfigError(msg) from None
    if not callable(factory):
        msg = f"controller: the entry point {entry.value!r} of {name!r} is not callable"
        raise ConfigError(msg)

    def make() -> Controller:
        made = factory()
        if not is_controller(made):
            msg = f"controller: {name!r} made {made!r}, which has no decide, arrive and carry steps"
            raise ConfigError(msg)
        controller: Controller = made
        return controller

    return make
