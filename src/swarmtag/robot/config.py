"""What a robot's controller is configured with: its mission rules in ticks and metres.

The same values the built-in controller reads from the simulator's
``Params``; on a real robot they come from the site's configuration
(``from_params`` builds them from a simulated scenario).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from swarmtag.policy import Policy

if TYPE_CHECKING:
    from swarmtag.sim.params import Params

__all__ = ["ControllerConfig"]


@dataclass(frozen=True, eq=False)
class ControllerConfig:
    """The rules of SPEC §3.2 and the site geometry a controller needs.

    Times are ticks, lengths metres. The drop-off area is ``x >=
    dropoff_left``; transport goals lie at ``x = transport_x``.
    """

    policy: Policy
    markers: NDArray[np.int64]
    """Marker id of each carrier."""
    dock_ticks: int
    lift_ticks: int
    release_ticks: int
    timeout_ticks: int
    """A pursuit (predock, dock, centre) gives up after this long."""
    cooldown_ticks: int
    """A carrier given up on by timeout is not chosen again for this long."""
    stuck_ticks: int
    sidestep_ticks: int
    walk_turn_ticks: int
    """A walking robot turns every so many ticks (0: straight until contact)."""
    predock_offset: float
    arrival_tolerance: float
    robot_radius: float
    sight: float
    """How far the robot sees other robots (face-taken checks)."""
    avoid_taken_faces: bool
    carrier_half: float
    arena: float
    transport_x: float
    dropoff_left: float

    @classmethod
    def from_params(cls, params: Params) -> ControllerConfig:
        """The configuration of the robots of a simulated scenario."""
        return cls(
            policy=params.policy,
            markers=params.markers,
            dock_ticks=params.dock_ticks,
            lift_ticks=params.lift_ticks,
            release_ticks=params.release_ticks,
            timeout_ticks=params.timeout_ticks,
            cooldown_ticks=params.cooldown_ticks,
            stuck_ticks=params.stuck_ticks,
            sidestep_ticks=params.sidestep_ticks,
            walk_turn_ticks=params.walk_turn_ticks,
            predock_offset=params.predock_offset,
            arrival_tolerance=params.arrival_tolerance,
            robot_radius=params.robot_radius,
            sight=params.detection_radius,
            avoid_taken_faces=params.avoid_taken_faces,
            carrier_half=params.carrier_half,
            arena=params.arena,
            transport_x=params.transport_x,
            dropoff_left=params.dropoff_left,
        )
