"""What the console shows and writes through: the ``ConsoleSource`` and ``Desk`` protocols.

``ConsoleCore`` (``swarmtag.console.api``) serves any source that has this
shape; three do:

- ``sim_source.SimSource`` (``--sim``): a live simulation;
- ``scan_source.ScanSource`` (``--scan``): real tags heard by a BLE scanner;
- ``replay_source.ReplaySource`` (``--replay FILE``): a recorded run, played back.

A source's ``snapshot`` is the moving picture (``run, tick, time, robots,
tags``; a tag has at least ``marker, urgency, status, destination,
last_heard, carried_by``), ``floor`` the still one (``{"kind": "none"}``
where there is no floor to draw), ``kpis`` what can be measured so far.
Writes go through a ``Desk``: it signs the change, has the tag verify it
and tells the source to carry it out, or refuses with ``SourceRefusal``
(HTTP 409) when the source cannot take writes at all (a replay).
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass
from typing import Any, Protocol

from swarmtag.errors import ConfigError
from swarmtag.tag import Change, TagState

__all__ = ["Accepted", "ConsoleSource", "Desk", "SourceRefusal"]


class SourceRefusal(ConfigError):
    """A change the source cannot carry out (HTTP 409): the tag was not written."""


@dataclass(frozen=True)
class Accepted:
    """An accepted write: the tag's states before and after, and the counter it carried."""

    before: TagState
    after: TagState
    counter: int


class ConsoleSource(Protocol):
    """What ``ConsoleCore`` reads: the tags, the floor, the KPIs, and time passing."""

    kind: str
    """``sim``, ``scan`` or ``replay``: the page shows what fits."""
    speed: float
    """How fast the source's time runs against wall time (1: real time)."""

    @property
    def markers(self) -> Collection[int]:
        """The marker ids a write may name now."""
        ...

    def advance(self, seconds: float) -> int:
        """Let ``seconds`` of wall time pass (step, play, look at the radio); the steps taken."""
        ...

    def snapshot(self) -> dict[str, Any]:
        """The moving parts now: ``run, tick, time, robots, tags``, JSON-ready."""
        ...

    def floor(self) -> dict[str, Any]:
        """The still picture: ``kind`` (``arena``, ``map`` or ``none``) and its geometry."""
        ...

    def kpis(self) -> dict[str, Any]:
        """The KPIs so far, JSON-ready, with ``kind`` naming which set they are."""
        ...

    def tag_state(self, marker: int) -> TagState:
        """What the tag of ``marker`` holds now (``KeyError``: not there)."""
        ...

    def start(self) -> None:
        """Begin (a scanner switches its radio on); called once, before serving."""
        ...

    def stop(self) -> None:
        """End and release what ``start`` took; called once, after serving."""
        ...


class Desk(Protocol):
    """The write path of a source: ``write`` signs, delivers and applies one change."""

    def write(self, marker: int, change: Change) -> Accepted:
        """The tag's answer to ``change``: ``Accepted``, or raise why not.

        ``KeyError``: no such tag now; ``SourceRefusal``: the source cannot
        carry it out (nothing signed); ``WriteRejected``: the tag refused;
        another ``SwarmtagError``: nothing was written (counter file, radio).
        """
        ...
