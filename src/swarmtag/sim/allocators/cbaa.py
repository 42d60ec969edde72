"""CBAA, the consensus-based auction (Choi, Brunet and How, IEEE T-RO 2009), one task per robot.

Each robot keeps a table of what it believes about every carrier: the
winning bid, its bidder, and the tick its bidder last renewed it.

1. **Bidding** (the choice step): a walker bids ``u_c * (0.7 + u_d)`` on
   each of its candidates and takes the best one it would win by its own
   table (a larger bid than the winning one, or an equal one from a smaller
   robot id, or none yet); its table then names it the winner, stamped now.
2. **Consensus** (every ``CBAA_ROUND_S`` seconds): every robot that holds
   a live entry sends its table to every robot within ``comm_range`` metres
   (true positions; broken robots neither send nor hear); each message is
   lost with probability ``loss`` (the allocation stream's number for that
   sender and receiver). A receiver keeps, per carrier, the larger bid,
   ties to the smaller bidder id, and for the same bidder the newer stamp.
   The messages sent are counted (``messages`` events).
3. **Release**: a robot renews its own entry while it pursues the carrier;
   an entry not renewed for ``CBAA_LEASE_S`` seconds lapses (a task given
   up is freed), and a robot clears the entry of a carrier it heard is no
   longer awaiting a robot.
4. **Outbid**: a robot approaching a carrier (PREDOCK or DOCK) whose table
   names another winner drops it (an ``abandon`` event whose value is the
   status it heard, AWAITING_PICKUP) and walks on.

``messages`` events carry the messages a robot sent since its last such
event: written when its table runs empty (it stops sending), every
``CBAA_REPORT_S`` seconds, and at the run's time limit.
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import SimulationError
from swarmtag.io import MISSING_ID
from swarmtag.policy import Cbaa, best_of
from swarmtag.sim.allocators.base import AllocatorChooser
from swarmtag.sim.builtin.decide import Selection
from swarmtag.sim.model.events import EventKind, TickEvents
from swarmtag.sim.model.geometry import Float
from swarmtag.sim.model.indexing import PURSUIT_MODES, grid, in_modes, own, to_walk
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import TickInputs
from swarmtag.sim.model.state import Int, Mode, WorldState
from swarmtag.tag import TagStatus

__all__ = [
    "CBAA_LEASE_S",
    "CBAA_REPORT_S",
    "CBAA_ROUND_S",
    "CbaaChooser",
    "bid_phase",
    "merge_tables",
]

CBAA_ROUND_S: Final = 0.1
"""Seconds between consensus rounds (10 Hz, a common rate for robot-to-robot state sharing)."""
CBAA_LEASE_S: Final = 1.0
"""Seconds an entry lives without its bidder renewing it (ten rounds)."""
CBAA_REPORT_S: Final = 10.0
"""Longest wait before a robot's message count goes into the event table."""
_AWAITING = int(TagStatus.AWAITING_PICKUP)
_NONE = -1


def merge_tables(
    bid: Float, winner: Int, stamp: Int, link: NDArray[np.bool_]
) -> tuple[Float, Int, Int]:
    """One consensus round: every robot's table merged with the tables it received.

    ``bid``, ``winner`` and ``stamp`` are (R, N, C) (no entry: bid ``-inf``,
    winner -1); ``link`` (R, N, N) says whether robot ``i``'s message reached
    robot ``j`` (``link[r, i, j]``). Per carrier the kept entry has the
    largest bid, then the smallest winner id, then the newest stamp; every
    robot sends the table it had before the round.

    >>> bid = np.array([[[5.0], [7.0]]]); winner = np.array([[[0], [1]]])
    >>> stamp = np.zeros((1, 2, 1), dtype=np.int64); link = np.array([[[0, 1], [1, 0]]], bool)
    >>> merged = merge_tables(bid, winner, stamp, link)
    >>> merged[0][0, :, 0].tolist(), merged[1][0, :, 0].tolist()
    ([7.0, 7.0], [1, 1])
    """
    runs, robots, _ = bid.shape
    heard = link | np.eye(robots, dtype=bool)[None]  # (R, sender, receiver): itself too
    # (R, receiver, sender, C): the offers each receiver weighs
    offered = np.where(heard.transpose(0, 2, 1)[..., None], bid[:, None], -np.inf)
    best = offered.max(axis=2, keepdims=True)
    keep = (offered == best) & (best > -np.inf)
    who = np.where(keep, winner[:, None], np.iinfo(np.int64).max)
    keep &= who == who.min(axis=2, keepdims=True)
    when = np.where(keep, stamp[:, None], np.iinfo(np.int64).min)
    keep &= when == when.max(axis=2, keepdims=True)
    sender = np.argmax(keep, axis=2)  # (R, receiver, C): the first sender of the kept entry
    found = keep.any(axis=2)
    rows = np.arange(runs)[:, None, None]
    carriers = np.arange(bid.shape[2])[None, None, :]
    merged_bid = np.where(found, bid[rows, sender, carriers], -np.inf)
    merged_winner = np.where(found, winner[rows, sender, carriers], _NONE)
    merged_stamp = np.where(found, stamp[rows, sender, carriers], 0)
    return merged_bid, merged_winner, merged_stamp


class CbaaChooser(AllocatorChooser):
    """The auction of one batch: each robot's table, its unreported messages."""

    def __init__(self, policy: Cbaa) -> None:
        self.policy = policy
        self.bid: Float | None = None
        self.winner: Int | None = None
        self.stamp: Int | None = None
        self.unreported: Int | None = None
        self.reported_at: Int | None = None

    def _start(self, s: WorldState) -> None:
        if self.bid is None:
            shape = s.known_status.shape
            self.bid = np.full(shape, -np.inf)
            self.winner = np.full(shape, _NONE, dtype=np.int64)
            self.stamp = np.zeros(shape, dtype=np.int64)
            self.unreported = np.zeros(s.mode.shape, dtype=np.int64)
            self.reported_at = np.zeros(s.mode.shape, dtype=np.int64)

    def _tables(self) -> tuple[Float, Int, Int, Int, Int]:
        if (
            self.bid is None
            or self.winner is None
            or self.stamp is None
            or self.unreported is None
            or self.reported_at is None
        ):
            msg = "cbaa: the tables are used before the first tick"
            raise SimulationError(msg)
        return self.bid, self.winner, self.stamp, self.unreported, self.reported_at

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
        """Release and renew entries, run a consensus round when one is due, drop outbid tasks."""
        del before
        self._start(s)
        bid, winner, stamp, unreported, reported_at = self._tables()
        runs, robots = s.mode.shape
        rows, me = grid(runs, robots)
        lease = max(1, math.ceil(CBAA_LEASE_S / params.scenario.tick - 1e-9))
        gone = (s.known_status >= 0) & (s.known_status != _AWAITING)
        lapsed = (winner >= 0) & (t - stamp > lease)
        clear = gone | lapsed
        bid[clear], winner[clear], stamp[clear] = -np.inf, _NONE, 0
        pursuing = in_modes(s.mode, PURSUIT_MODES)
        mine = pursuing & (own(winner, s.target) == me)
        stamp[rows, me, np.maximum(s.target, 0)] = np.where(
            mine, t, stamp[rows, me, np.maximum(s.target, 0)]
        )
        every = max(1, round(CBAA_ROUND_S / params.scenario.tick))
        if t % every == 0:
            self._round(s, inputs, params)
            bid, winner, stamp, unreported, reported_at = self._tables()
        approaching = in_modes(s.mode, (Mode.PREDOCK, Mode.DOCK))
        outbid = approaching & (own(winner, s.target) != me)
        if outbid.any():
            heard = own(s.known_status, s.target).astype(np.float64)
            events.add(EventKind.ABANDON, outbid, s.target.copy(), heard)
            to_walk(s, outbid)
        live = (winner >= 0).any(axis=-1)
        due = (unreported > 0) & (
            ~live
            | (t - reported_at >= round(CBAA_REPORT_S / params.scenario.tick))
            | (t >= params.run_ticks)
        )
        if due.any():
            events.add(
                EventKind.MESSAGES,
                due,
                np.full(due.shape, MISSING_ID, dtype=np.int64),
                unreported.astype(np.float64),
            )
            unreported[due] = 0
            reported_at[due] = t

    def _round(self, s: WorldState, inputs: TickInputs, params: Params) -> None:
        """One consensus round: send, lose, merge, count."""
        bid, winner, stamp, unreported, _ = self._tables()
        drawn = inputs.allocation
        if drawn is None:
            msg = "cbaa: the tick's inputs carry no allocation draws"
            raise SimulationError(msg)
        robots = s.mode.shape[1]
        working = s.mode != int(Mode.BROKEN)
        sending = working & (winner >= 0).any(axis=-1)
        offset = s.robot_pos[:, :, None, :] - s.robot_pos[:, None, :, :]
        near = offset[..., 0] ** 2 + offset[..., 1] ** 2 <= self.policy.comm_range**2
        near &= ~np.eye(robots, dtype=bool)[None]
        sent = near & sending[:, :, None] & working[:, None, :]  # (R, sender, receiver)
        unreported += sent.sum(axis=2)
        arrived = sent & (drawn[..., params.carriers :] >= self.policy.loss)
        if arrived.any():
            self.bid, self.winner, self.stamp = merge_tables(bid, winner, stamp, arrived)

    def __call__(self, selection: Selection) -> tuple[Int, NDArray[np.float64]]:
        """Bid on the best candidate the robot would win by its own table."""
        s, params = selection.s, selection.params
        self._start(s)
        bid, winner, stamp, _, _ = self._tables()
        offers = self.policy.score(s.known_urgency.astype(np.float64), selection.distance)
        choice = bid_phase(
            offers,
            bid,
            winner,
            stamp,
            available=selection.available,
            distance=selection.distance,
            markers=params.markers,
            t=selection.t,
        )
        return choice, selection.available.sum(axis=-1).astype(np.float64)


def bid_phase(
    offers: Float,
    bid: Float,
    winner: Int,
    stamp: Int,
    *,
    available: NDArray[np.bool_],
    distance: Float,
    markers: Int,
    t: int,
) -> Int:
    """Each robot's bid (R, N), -1 none: its best offer it would win by its own table.

    ``offers`` (R, N, C) are the robots' bids on their ``available``
    candidates. A robot would win carrier ``c`` where its table has no
    winner, a smaller winning bid, an equal one from a larger robot id, or
    itself. The best such offer (``best_of``'s tie rule) goes into the
    robot's table (in place), stamped ``t``.
    """
    runs, robots = winner.shape[:2]
    rows, me = grid(runs, robots)
    ids = me[..., None]
    wins = (winner < 0) | (offers > bid) | ((offers == bid) & (ids < winner)) | (winner == ids)
    choice = best_of(offers, distance=distance, marker=markers, available=available & wins)
    choice = choice.astype(np.int64)
    chosen = choice >= 0
    at = np.maximum(choice, 0)
    bid[rows, me, at] = np.where(chosen, offers[rows, me, at], bid[rows, me, at])
    winner[rows, me, at] = np.where(chosen, me, winner[rows, me, at])
    stamp[rows, me, at] = np.where(chosen, t, stamp[rows, me, at])
    return choice
