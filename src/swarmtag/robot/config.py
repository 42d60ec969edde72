"""What a robot's controller is configured with: its mission rules in ticks and metres.

The same values the built-in controller reads from the simulator's
``Params``; on a real robot they come from the site's configuration
(``from_params`` builds them from a simulated scenario).
"""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from swarmtag.policy import Policy
from swarmtag.sim.model._fields import ControllerFields

if TYPE_CHECKING:
    from swarmtag.sim.model.params import Params

__all__ = ["ControllerConfig"]


@dataclass(frozen=True, eq=False)
class ControllerConfig(ControllerFields):
    """The rules of SPEC §3.2 and the site geometry a controller needs.

    Times are ticks, lengths metres. The drop-off area is ``x >=
    dropoff_left``; transport goals lie at ``x = transport_x``. The
    parameters are ``ControllerFields``' (the kernel parameters marked for
    controllers in the schema); these are the rest.
    """

    policy: Policy
    markers: NDArray[np.int64]
    """Marker id of each carrier."""

    @classmethod
    def from_params(cls, params: Params) -> ControllerConfig:
        """The configuration of the robots of a simulated scenario."""
        shared = {item.name: getattr(params, item.name) for item in fields(ControllerFields)}
        return cls(policy=params.policy, markers=params.markers, **shared)
