"""Who may change what on a tag (SPEC §2.2): the lifecycle as a pure function.

Robots make exactly two forward transitions, ``AWAITING_PICKUP → PICKED_UP``
(lift) and ``PICKED_UP → IDLE`` (release), and touch nothing else. Operators
(a person or the warehouse management system) may set any status, urgency or
destination.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import IntEnum
from typing import Final

from swarmtag.errors import IllegalTransition, RoleNotAllowed
from swarmtag.tag.codec import TagState
from swarmtag.tag.status import TagStatus

__all__ = ["ROBOT_TRANSITIONS", "Change", "Role", "apply_change"]


class Role(IntEnum):
    """Who signs a write; the number is carried in the write's flags byte."""

    ROBOT = 1
    OPERATOR = 2


ROBOT_TRANSITIONS: Final = frozenset(
    {
        (TagStatus.AWAITING_PICKUP, TagStatus.PICKED_UP),
        (TagStatus.PICKED_UP, TagStatus.IDLE),
    }
)
"""The only (from, to) status changes a robot may make."""


@dataclass(frozen=True, slots=True)
class Change:
    """The fields a write sets; ``None`` leaves a field as it is."""

    urgency: int | None = None
    status: TagStatus | None = None
    destination: int | None = None

    @property
    def empty(self) -> bool:
        """True when the change sets no field at all."""
        return self.urgency is None and self.status is None and self.destination is None


def apply_change(state: TagState, change: Change, role: Role) -> TagState:
    """The state after ``role`` applies ``change``; raise if that role may not.

    Field ranges are checked by ``TagState`` itself.

    >>> s = TagState(urgency=4, status=TagStatus.AWAITING_PICKUP, destination=0, marker=3)
    >>> apply_change(s, Change(status=TagStatus.PICKED_UP), Role.ROBOT).status.name
    'PICKED_UP'
    """
    if role is Role.ROBOT:
        if change.urgency is not None or change.destination is not None:
            fields = [
                name for name in ("urgency", "destination") if getattr(change, name) is not None
            ]
            raise RoleNotAllowed(
                f"a robot may not change {' or '.join(fields)}; only an operator may"
            )
        if change.status is None:
            raise RoleNotAllowed("a robot write must change the status")
        if (state.status, change.status) not in ROBOT_TRANSITIONS:
            raise IllegalTransition(
                f"a robot may not move a tag from {state.status.name} to {change.status.name}; "
                "robots only lift (AWAITING_PICKUP -> PICKED_UP) and release (PICKED_UP -> IDLE)"
            )
    elif role is not Role.OPERATOR:  # pragma: no cover - Role has two members
        raise RoleNotAllowed(f"unknown role {role!r}")
    return replace(
        state,
        urgency=state.urgency if change.urgency is None else change.urgency,
        status=state.status if change.status is None else change.status,
        destination=state.destination if change.destination is None else change.destination,
    )
