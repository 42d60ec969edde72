"""The step kernel: one tick of a batch of runs, a pure function of (state, inputs, params).

``step`` runs the phases of SPEC §4.5 in order, the world's and the
controller's (``swarmtag.sim.control.interface``) in turn: sense (``sense``) ->
breakdowns (``world``) -> the controller decides -> move and resolve
collisions (``motion``) -> the controller arrives -> docking and the tags'
answers to lift writes (``world``) -> the controller carries -> deliveries
(``world``) -> end of tick (tags' urgency growth, the advertised state
history, run ends) -> the operator writes due this tick (``wms``, fed by
``inputs.writes``) -> warehouse orders that fell due are placed
(``orders``). It returns the next state and the tick's events; the state it
is given is left untouched. The whole tick happens here, so
another backend given the same state and inputs can reproduce it.

A run that has ended (every carrier delivered, or its time limit) is frozen:
its state no longer changes and it records no events.
"""

from __future__ import annotations

from dataclasses import fields, replace
from typing import Any

import numpy as np

from swarmtag.sim.builtin.controller import BUILTIN
from swarmtag.sim.control.interface import Controller
from swarmtag.sim.model.events import TickEvents
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import WorldState
from swarmtag.sim.world.handling import answer_lifts, break_down, deliver, dock
from swarmtag.sim.world.motion import move, resolve
from swarmtag.sim.world.orders import place_orders
from swarmtag.sim.world.sensing import sense, sensed_state
from swarmtag.sim.world.urgency import growing_urgency
from swarmtag.sim.world.wms import operator_writes

__all__ = ["step"]


def _end_of_tick(s: WorldState, params: Params, t: int) -> None:
    """Grow urgencies, record what the tags advertise, and mark runs that end now."""
    growing = ~np.isnan(s.w0) & (s.arrival_time >= 0)
    if growing.any():
        grown = growing_urgency(np.where(growing, s.w0, 0.0), t, params.horizon)
        np.copyto(s.urgency, grown, where=growing)
    slot = t % (params.status_delay + 1)
    s.adv_status[:, slot] = s.status
    s.adv_urgency[:, slot] = s.urgency
    done = (~s.present & (s.arrival_time >= 0)).all(axis=1)  # all placed orders gone
    ends = (s.ended_at < 0) & (done | (t >= params.run_ticks))
    s.ended_at[ends] = t


def _freeze(before: WorldState, after: WorldState, frozen: np.ndarray) -> WorldState:
    """``after`` with the runs in ``frozen`` (R,) put back to ``before``."""
    changes: dict[str, Any] = {}
    for f in fields(after):
        new = getattr(after, f.name)
        if isinstance(new, np.ndarray) and f.name != "run_ids":
            old = getattr(before, f.name)
            mask = frozen.reshape((-1,) + (1,) * (new.ndim - 1))
            changes[f.name] = np.where(mask, old, new)
    return replace(after, **changes)


def step(
    state: WorldState,
    inputs: TickInputs,
    params: Params,
    controller: Controller = BUILTIN,
) -> tuple[WorldState, TickEvents]:
    """The state after one more tick, and what happened in it (``controller`` decides)."""
    t = state.tick + 1
    senses = sense(state, inputs, params)
    s = sensed_state(state, senses)
    events = TickEvents()
    break_down(s, inputs, events)
    controller.decide(state, s, senses=senses, inputs=inputs, params=params, t=t, events=events)
    resolve(s, move(s, params), params)
    arrivals = controller.arrive(state, s, params=params, t=t)
    dock(s, arrivals)
    answers = answer_lifts(s, arrivals.lift, params=params, t=t, events=events)
    carrying = controller.carry(s, answers, params=params, t=t)
    deliver(s, carrying, answers=answers, params=params, t=t, events=events)
    _end_of_tick(s, params, t)
    operator_writes(s, inputs.writes, t=t, events=events)
    place_orders(s, params, t=t, events=events)
    ended = state.ended_at >= 0
    if ended.any():
        return _freeze(state, s, ended), events.masked(~ended)
    return s, events
