"""Who may change what on a tag (SPEC §2.2): the lifecycle as a pure function.

Robots make exactly two forward transitions, ``AWAITING_PICKUP → PICKED_UP``
(lift) and ``PICKED_UP → IDLE`` (release), and touch nothing else; a release
is taken only from the robot that lifted the carrier (``next_lifter``).
Operators (a person or the warehouse management system) may set any status,
urgency or destination, whoever lifted the carrier.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from enum import IntEnum
from typing import Final, NoReturn

from swarmtag.errors import FieldRangeError, IllegalTransition, RoleNotAllowed
from swarmtag.tag._arguments import CheckedEnumType, check_type, describe
from swarmtag.tag.codec import TagState
from swarmtag.tag.status import TagStatus

__all__ = ["ROBOT_TRANSITIONS", "Change", "Role", "apply_change", "check_role", "next_lifter"]

_ROLES: Final = "use Role.ROBOT (1) or Role.OPERATOR (2)"


class Role(IntEnum, metaclass=CheckedEnumType):
    """Who signs a write; the number is carried in the write's flags byte."""

    ROBOT = 1
    OPERATOR = 2

    @classmethod
    def _missing_(cls, value: object) -> NoReturn:
        """Refuse an unknown role with ``FieldRangeError`` (still a ``ValueError``)."""
        raise FieldRangeError(f"role: {describe(value)} is not a writer role; {_ROLES}")


def check_role(value: object) -> Role:
    """``value`` as a ``Role`` if it is one (or its number 1 or 2); else ``FieldRangeError``.

    >>> check_role(2)
    <Role.OPERATOR: 2>
    """
    if isinstance(value, bool) or not isinstance(value, int):
        raise FieldRangeError(f"role: {describe(value)} is not a writer role; {_ROLES}")
    return Role(value)


ROBOT_TRANSITIONS: Final = frozenset(
    {
        (TagStatus.AWAITING_PICKUP, TagStatus.PICKED_UP),
        (TagStatus.PICKED_UP, TagStatus.IDLE),
    }
)
"""The only (from, to) status changes a robot may make."""


@dataclass(frozen=True, slots=True)
class Change:
    """The fields a write sets; ``None`` leaves a field as it is.

    Types are checked here (and a status name or number becomes a ``TagStatus``);
    ranges are checked where the change is used (``Write``, ``TagState``), which
    name the field.
    """

    urgency: int | None = None
    status: TagStatus | None = None
    destination: int | None = None

    def __post_init__(self) -> None:
        for name in ("urgency", "destination"):
            value: object = getattr(self, name)
            if value is not None and (isinstance(value, bool) or not isinstance(value, int)):
                raise FieldRangeError(f"{name}: {describe(value)} is not an integer or None")
        status: object = self.status
        if status is not None and not isinstance(status, TagStatus):
            if isinstance(status, bool) or not isinstance(status, str | int):
                raise FieldRangeError(f"status: {describe(status)} is not a TagStatus or None")
            object.__setattr__(self, "status", TagStatus.parse(status))

    @property
    def empty(self) -> bool:
        """True when the change sets no field at all."""
        return self.urgency is None and self.status is None and self.destination is None


def apply_change(state: TagState, change: Change, role: Role) -> TagState:
    """The state after ``role`` applies ``change``; raise if that role may not.

    Field ranges are checked by ``TagState`` itself; arguments of the wrong type
    raise ``FieldRangeError``.

    >>> s = TagState(urgency=4, status=TagStatus.AWAITING_PICKUP, destination=0, marker=3)
    >>> apply_change(s, Change(status=TagStatus.PICKED_UP), Role.ROBOT).status.name
    'PICKED_UP'
    """
    check_type("state", state, TagState)
    check_type("change", change, Change)
    role = check_role(role)
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


def next_lifter(
    lifter: int | None, before: TagStatus, after: TagStatus, *, writer: int, role: Role
) -> int | None:
    """The writer id a tag remembers as its carrier's lifter after a write, or a refusal.

    ``lifter`` is the one remembered before the write (``None``: none) and
    ``before``/``after`` the statuses the write moves between (``apply_change``
    has allowed it). A robot's lift binds the carrier to that robot; a robot
    may move a carrier out of PICKED_UP only if it is the lifter (or none is
    known: set by an operator, or remembered by no older record); any status
    other than PICKED_UP forgets the lifter. Operators may override.
    ``IllegalTransition`` (ATT 0x84) for another robot's release.

    >>> next_lifter(None, TagStatus.AWAITING_PICKUP, TagStatus.PICKED_UP, writer=9, role=Role.ROBOT)
    9
    >>> next_lifter(9, TagStatus.PICKED_UP, TagStatus.IDLE, writer=7, role=Role.ROBOT)
    Traceback (most recent call last):
    ...
    swarmtag.errors.IllegalTransition: robot 7 may not release this carrier: robot 9 lifted it ...
    """
    role = check_role(role)
    moved = after is not before
    if (
        before is TagStatus.PICKED_UP
        and moved
        and role is Role.ROBOT
        and lifter not in (None, writer)
    ):
        raise IllegalTransition(
            f"robot {writer} may not release this carrier: robot {lifter} lifted it "
            "(only that robot, or an operator, may)"
        )
    if after is not TagStatus.PICKED_UP:
        return None
    if moved:
        return writer if role is Role.ROBOT else None
    return lifter
