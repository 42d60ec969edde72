"""The console's ``--sim`` source: one live simulated run, stepped in real time, rolled over.

``SimSource`` owns a one-run ``WorldState`` and steps the pure kernel
(``swarmtag.sim.step``) as wall time passes, ``speed`` times real time.
When the run ends (every carrier delivered, or its time limit) the next run
of the same seed starts, so the floor keeps moving; the carrier logs of the
runs so far feed the KPIs. Operator writes arrive here only after the tag
(``swarmtag.console.writes``) accepted them: an urgency becomes the
simulator's own WMS write at the next tick (``TickInputs.writes``, applied
by ``swarmtag.sim.world.wms`` exactly like a scheduled re-prioritisation); a
status or destination is set on the carrier between ticks, where the
simulated floor can carry it out (``check_change`` says where it cannot).
Every public method takes the source's lock, so the stepping thread and the
API never see half a tick.
"""

from __future__ import annotations

import threading
from dataclasses import replace
from typing import Any, Final

import numpy as np

from swarmtag.console.kpis import log_kpis
from swarmtag.console.source import SourceRefusal
from swarmtag.io import CarrierLog
from swarmtag.policy import Policy
from swarmtag.sim import RandomSource, Scenario, make_params, step
from swarmtag.sim.builtin.controller import BUILTIN
from swarmtag.sim.config.parts import Reprioritisation
from swarmtag.sim.model.state import Mode, WorldState
from swarmtag.sim.outputs.trajectories import Geometry
from swarmtag.sim.runner import carrier_log, seeded_state
from swarmtag.sim.world.wms import SIM_SITE_KEY
from swarmtag.tag import Change, TagState, TagStatus

__all__ = ["MAX_TICKS_PER_ADVANCE", "SimSource", "SourceRefusal"]

MAX_TICKS_PER_ADVANCE: Final = 2000
"""Ticks one ``advance`` runs at most: a slow machine falls behind instead of freezing."""
_HELD: Final = frozenset({TagStatus.IDLE, TagStatus.AWAITING_PICKUP})


class SimSource:
    """A live simulated floor: state, stepping, tag list, floor picture, operator changes."""

    kind = "sim"
    site_key: bytes = SIM_SITE_KEY
    """The site key the simulated tags hold (the operator key derives from it)."""

    def __init__(
        self, scenario: Scenario, policy: Policy, *, seed: int = 0, speed: float = 1.0
    ) -> None:
        self.params = make_params(scenario, policy)
        self.seed = seed
        self.speed = speed
        self.geometry = Geometry.from_params(self.params)
        self._lock = threading.RLock()
        self._run = 0
        self._finished: list[CarrierLog] = []
        self._pending: list[Reprioritisation] = []
        self._owed = 0.0
        self._start(0)

    @property
    def tick_seconds(self) -> float:
        """Seconds of robot time per tick."""
        return float(self.params.scenario.tick)

    @property
    def markers(self) -> list[int]:
        """The marker id of every carrier (the index of a carrier's column)."""
        return [int(m) for m in self.params.markers]

    def _start(self, run: int) -> None:
        self._run = run
        self._state: WorldState = seeded_state(self.params, seed=self.seed, runs=1, run_offset=run)
        self._inputs = RandomSource(self.params, seed=self.seed, run_ids=self._state.run_ids)

    def advance(self, seconds: float) -> int:
        """Step the ticks that ``seconds`` of wall time hold at ``speed``; the number stepped."""
        with self._lock:
            self._owed += seconds * self.speed / self.tick_seconds
            ticks = min(int(self._owed), MAX_TICKS_PER_ADVANCE)
            self._owed = min(self._owed - ticks, 1.0)
            for _ in range(ticks):
                self.step_once()
            return ticks

    def step_once(self) -> None:
        """One tick (and the next run, if this one has ended), with the writes now due."""
        with self._lock:
            s = self._state
            if s.ended_at[0] >= 0 or s.tick >= self.params.run_ticks:
                self._finished.append(self.log())
                self._start(self._run + 1)
                s = self._state
            inputs = self._inputs.inputs(s.tick + 1)
            if self._pending:
                inputs = replace(inputs, writes=(*inputs.writes, *self._pending))
                self._pending = []
            self._state, _ = step(s, inputs, self.params, BUILTIN)

    def log(self) -> CarrierLog:
        """The event log (SPEC §8.1) of the run under way, as far as it got."""
        with self._lock:
            return carrier_log(self._state, self.params, seed=self.seed)

    def logs(self) -> list[CarrierLog]:
        """The event logs of the finished runs and of the run under way."""
        with self._lock:
            return [*self._finished, self.log()]

    def start(self) -> None:
        """Nothing to switch on: the simulation is stepped by ``advance``."""

    def stop(self) -> None:
        """Nothing to release."""

    def kpis(self) -> dict[str, Any]:
        """The KPIs of the runs so far (``swarmtag.console.kpis``)."""
        log = CarrierLog.concat(self.logs())
        return log_kpis(log, self.params.condition, self.tick_seconds)

    def floor(self) -> dict[str, Any]:
        """The still picture: the arena and its areas, or the warehouse map."""
        g = self.geometry
        return {
            "kind": "map" if g.floor_text else "arena",
            "arena": g.arena,
            "height": g.extent_y,
            "pickup_right": g.pickup_right,
            "dropoff_left": g.dropoff_left,
            "robot_radius": g.robot_radius,
            "carrier_size": g.carrier_size,
            "floor_text": g.floor_text,
            "floor_cell": g.floor_cell,
            "destinations": list(self.destinations()),
            "tick_seconds": g.tick_seconds,
        }

    def _column(self, marker: int) -> int:
        where = np.flatnonzero(self.params.markers == marker)
        if where.size == 0 or not self._placed(int(where[0])):
            raise KeyError(marker)
        return int(where[0])

    def _placed(self, c: int) -> bool:
        return bool(self._state.due[0, c] <= self._state.tick)

    def tag_state(self, marker: int) -> TagState:
        """What the tag of ``marker`` holds now (with a written urgency the next tick applies).

        ``KeyError`` if no such carrier is on the floor.
        """
        with self._lock:
            c = self._column(marker)
            s = self._state
            due = [w.urgency for w in self._pending if w.carrier == c]
            return TagState(
                urgency=due[-1] if due else int(s.urgency[0, c]),
                status=TagStatus(int(s.status[0, c])),
                destination=self._destination_of(int(s.destination[0, c])),
                marker=marker,
            )

    def _destination_of(self, index: int) -> int:
        floor = self.params.floor
        return 0 if floor is None else int(floor.destinations[index])

    def destinations(self) -> tuple[int, ...]:
        """The drop-off areas a carrier may be sent to (the lab has one, 0)."""
        floor = self.params.floor
        return (0,) if floor is None else tuple(int(d) for d in floor.destinations)

    def check_change(self, marker: int, change: Change) -> None:
        """Refuse (``SourceRefusal``) a change the simulated floor cannot carry out."""
        with self._lock:
            c = self._column(marker)
            s = self._state
            if change.destination is not None and change.destination not in self.destinations():
                shown = ", ".join(map(str, self.destinations()))
                raise SourceRefusal(
                    f"destination {change.destination} is no drop-off area of this floor "
                    f"(it has: {shown})"
                )
            if change.status is not None:
                if change.status not in _HELD:
                    raise SourceRefusal(
                        "in the simulation only a robot lifts a carrier; an operator may set "
                        "idle (hold) or awaiting_pickup (release the hold)"
                    )
                if s.carried_by[0, c] >= 0 or s.delivery_time[0, c] >= 0:
                    raise SourceRefusal(
                        f"carrier {marker} is on a robot or delivered; only a carrier waiting "
                        "on the floor can be held or released"
                    )

    def apply(self, marker: int, before: TagState, after: TagState) -> None:
        """Carry out a change the tag accepted: ``before`` and ``after`` are its states."""
        with self._lock:
            c = self._column(marker)
            s = self._state
            if after.urgency != before.urgency:
                self._pending.append(
                    Reprioritisation(tick=s.tick + 1, carrier=c, urgency=after.urgency)
                )
            if after.status != before.status:
                s.status[0, c] = int(after.status)
                s.adv_status[0, :, c] = int(after.status)
            if after.destination != before.destination:
                s.destination[0, c] = self.destinations().index(after.destination)

    def snapshot(self) -> dict[str, Any]:
        """The moving parts now: time, robots and tags, as plain JSON-ready values."""
        with self._lock:
            s = self._state
            scale = self.tick_seconds
            robots = [
                {
                    "id": n,
                    "x": round(float(s.robot_pos[0, n, 0]), 3),
                    "y": round(float(s.robot_pos[0, n, 1]), 3),
                    "hx": round(float(s.heading[0, n, 0]), 3),
                    "hy": round(float(s.heading[0, n, 1]), 3),
                    "mode": Mode(int(s.mode[0, n])).name.lower(),
                    "target": self._marker_or_none(int(s.target[0, n])),
                }
                for n in range(s.robot_pos.shape[1])
            ]
            return {
                "run": self._run,
                "tick": int(s.tick),
                "time": round(s.tick * scale, 3),
                "robots": robots,
                "tags": self._tags(s, scale),
            }

    def _marker_or_none(self, c: int) -> int | None:
        return None if c < 0 else int(self.params.markers[c])

    def _tags(self, s: WorldState, scale: float) -> list[dict[str, Any]]:
        heard = s.heard_tick[0].max(axis=0) if s.heard_tick.shape[-1] else None
        rows = []
        for c, marker in enumerate(self.markers):
            if not self._placed(c):
                continue
            last = None if heard is None or heard[c] < 0 else round(float(heard[c]) * scale, 3)
            delivered = int(s.delivery_time[0, c])
            rows.append(
                {
                    "marker": marker,
                    "urgency": int(s.urgency[0, c]),
                    "status": TagStatus(int(s.status[0, c])).name.lower(),
                    "destination": self._destination_of(int(s.destination[0, c])),
                    "last_heard": last,
                    "carried_by": None if s.carried_by[0, c] < 0 else int(s.carried_by[0, c]),
                    "x": round(float(s.carrier_pos[0, c, 0]), 3),
                    "y": round(float(s.carrier_pos[0, c, 1]), 3),
                    "present": bool(s.present[0, c]),
                    "order_time": round(float(s.order_time[0, c]) * scale, 3),
                    "delivered_at": None if delivered < 0 else round(delivered * scale, 3),
                }
            )
        return rows
