"""Claims through the tag (the tag protocol's extension, ``swarmtag.tag.claim``), simulated.

Each carrier's tag holds at most one claim: its holder and the tick it
ends. A walker scores its candidates ``u_c * (0.7 + u_d)`` and passes over
those whose last advertisement it heard carried another robot's live
claim. The carrier it chooses it claims for ``hold`` seconds: one write
(counted as a ``messages`` event of value 1), lost with probability
``loss`` (the allocation stream's number for that robot and carrier). The
tag grants it as ``grant_claim`` does: while the carrier awaits a robot and
no other robot holds a live claim; then the robot pursues it. A refused
claim tells the robot who holds the carrier, and it chooses nothing this
tick; a lost one leaves the carrier unclaimed and the robot pursues it all
the same (it learnt nothing). A claim ends at its time or when the
carrier's status leaves AWAITING_PICKUP. Robots hear a claim with the
tag's advertisements (the ticks their radio hears the tag; the status
delay is not applied to claims).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import SimulationError
from swarmtag.io import MISSING_ID
from swarmtag.policy import ClaimFirst, best_of
from swarmtag.sim.allocators.base import AllocatorChooser
from swarmtag.sim.builtin.decide import Selection
from swarmtag.sim.model.events import EventKind, TickEvents
from swarmtag.sim.model.indexing import grid
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import Int, WorldState
from swarmtag.tag import TagStatus

__all__ = ["ClaimChooser"]

_AWAITING = int(TagStatus.AWAITING_PICKUP)
_NONE = -1


class ClaimChooser(AllocatorChooser):
    """The claims of one batch: each tag's (R, C) and what each robot heard (R, N, C)."""

    def __init__(self, policy: ClaimFirst) -> None:
        self.policy = policy
        self.holder: Int | None = None
        self.until: Int | None = None
        self.heard_holder: Int | None = None
        self.heard_until: Int | None = None
        self.writes: Int | None = None

    def _tables(self, s: WorldState) -> tuple[Int, Int, Int, Int, Int]:
        if self.holder is None:
            self.holder = np.full(s.status.shape, _NONE, dtype=np.int64)
            self.until = np.zeros(s.status.shape, dtype=np.int64)
            self.heard_holder = np.full(s.known_status.shape, _NONE, dtype=np.int64)
            self.heard_until = np.zeros(s.known_status.shape, dtype=np.int64)
            self.writes = np.zeros(s.mode.shape, dtype=np.int64)
        if (
            self.until is None
            or self.heard_holder is None
            or self.heard_until is None
            or self.writes is None
        ):
            msg = "claim: the tables are half made"
            raise SimulationError(msg)
        return self.holder, self.until, self.heard_holder, self.heard_until, self.writes

    def prepare(
        self,
        before: WorldState,
        s: WorldState,
        *,
        inputs: TickInputs,
        params: Params,
        t: int,
        events: TickEvents,
    ) -> None:
        """End claims whose time ran out or whose carrier was lifted; robots hear the rest."""
        del before, inputs, params, events
        holder, until, heard_holder, heard_until, _ = self._tables(s)
        ended = (holder >= 0) & ((until <= t) | (s.status != _AWAITING))
        holder[ended] = _NONE
        heard = s.heard_tick == t  # (R, N, C): an advertisement reached the robot this tick
        np.copyto(heard_holder, np.broadcast_to(holder[:, None, :], heard.shape), where=heard)
        np.copyto(heard_until, np.broadcast_to(until[:, None, :], heard.shape), where=heard)

    def __call__(self, selection: Selection) -> tuple[Int, NDArray[np.float64]]:
        """Choose among the carriers not held by another; claim the choice; count the write."""
        s, params, t = selection.s, selection.params, selection.t
        _, _, heard_holder, heard_until, _ = self._tables(s)
        drawn = selection.inputs.allocation
        if drawn is None:
            msg = "claim: the tick's inputs carry no allocation draws"
            raise SimulationError(msg)
        ids = grid(*s.mode.shape)[1][..., None]
        held = (heard_holder >= 0) & (heard_holder != ids) & (heard_until > t)
        candidates = selection.available & ~held
        choice = best_of(
            self.policy.score(s.known_urgency.astype(np.float64), selection.distance),
            distance=selection.distance,
            marker=params.markers,
            available=candidates,
        ).astype(np.int64)
        hold = max(1, math.ceil(self.policy.hold / params.scenario.tick - 1e-9))
        for run, robot in zip(*np.nonzero(choice >= 0), strict=True):  # robot id order
            carrier = int(choice[run, robot])
            self._claim(run, robot, carrier, lost=drawn[run, robot, carrier] < self.policy.loss,
                        s=s, t=t, hold=hold, choice=choice)  # fmt: skip
        return choice, candidates.sum(axis=-1).astype(np.float64)

    def _claim(
        self,
        run: int,
        robot: int,
        carrier: int,
        *,
        lost: bool,
        s: WorldState,
        t: int,
        hold: int,
        choice: Int,
    ) -> None:
        """Robot ``robot`` writes its claim on ``carrier``: lost, granted or refused."""
        holder, until, heard_holder, heard_until, writes = self._tables(s)
        writes[run, robot] += 1
        if lost:
            return
        other = holder[run, carrier] >= 0 and holder[run, carrier] != robot
        if s.status[run, carrier] != _AWAITING or (other and until[run, carrier] > t):
            heard_holder[run, robot, carrier] = holder[run, carrier]  # the refusal says who
            heard_until[run, robot, carrier] = until[run, carrier]
            choice[run, robot] = _NONE
            return
        holder[run, carrier] = robot
        until[run, carrier] = t + hold

    def settle(
        self, before: WorldState, s: WorldState, *, params: Params, t: int, events: TickEvents
    ) -> None:
        """This tick's claim writes as ``messages`` events (each robot's count)."""
        del before, params, t
        _, _, _, _, writes = self._tables(s)
        wrote = writes > 0
        if wrote.any():
            carrier = np.full(wrote.shape, MISSING_ID, dtype=np.int64)
            events.add(EventKind.MESSAGES, wrote, carrier, writes.astype(np.float64))
            writes[:] = 0
