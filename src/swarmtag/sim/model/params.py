"""Kernel parameters: the scenario and the policy in the kernel's units, frozen.

The kernel never sees seconds or degrees: durations are whole ticks, speeds
metres per tick, and the largest turn per tick is given as its cosine and
sine, computed here once (``math.cos``/``math.sin``, outside any kernel).
Other backends and the behaviour tree must take these numbers from
``Params`` rather than recompute them, so that they match bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import ConfigError
from swarmtag.policy import Policy
from swarmtag.sim.config.bearing import bearing_profile
from swarmtag.sim.config.floor_map import FloorMap
from swarmtag.sim.config.scenario import Scenario
from swarmtag.sim.config.warehouse import floor_of
from swarmtag.sim.model._fields import ParamFields
from swarmtag.sim.model.geometry import Float
from swarmtag.sim.model.kernel_parameters import derive_all

__all__ = ["FIRST_CACHE_CAPACITY", "Params", "make_params", "sparse_tag_cache"]


@dataclass(frozen=True, eq=False)
class Params(ParamFields):
    """Everything the step kernel needs besides the state and the tick's random inputs.

    Lengths are metres, times ticks. The lab arena is ``[0, arena]^2``; the
    pick-up area is ``x <= pickup_right``, the drop-off area (destination 0)
    ``x >= dropoff_left``. A warehouse (``floor`` set) is
    ``[0, arena] x [0, arena_height]`` with its map's shelves and areas.
    The kernel parameters are ``ParamFields``' (generated from the schema,
    ``swarmtag.sim.model.kernel_parameters``); these are the rest.
    """

    scenario: Scenario
    policy: Policy
    markers: NDArray[np.int64]
    """Marker id of each carrier (its index; in a warehouse, the order number)."""
    floor: FloorMap | None
    """The warehouse floor (shelves, pick-up and drop-off cells); None in the lab arena."""
    sparse_tag_cache: bool
    """The compiled kernel keeps each robot's tag cache as a short list (``sparse_tag_cache``)."""
    bearing_cos: Float
    """The camera's bearing profile (``camera.bearing``): its points' cosines, falling 1 to -1."""
    bearing_factor: Float
    """The reach's factor at each point (both empty: alike all round)."""

    @property
    def condition(self) -> str:
        """The policy's canonical condition name (SPEC §8.1)."""
        return self.policy.name


FIRST_CACHE_CAPACITY: Final = 64
"""Entries of each robot's sparse tag cache the compiled kernel tries first."""
SPARSE_FROM_PAIRS: Final = 65_536
"""Robot-carrier pairs of a run from which its tag caches are lists (below, the dense arrays
are small and their lookups faster: 20 robots and 40 carriers ran 25 % slower as lists,
the warehouse hall 30 %; docs/performance.md)."""


def sparse_tag_cache(scenario: Scenario) -> bool:
    """Whether the compiled kernel keeps ``scenario``'s robots' tag caches as short lists.

    Where the lists are exact (split perception with neither sighting memory,
    a look round, BLE-led search nor the per-pair draws of advertisement loss and camera noise,
    ``sim/fast/_tag_cache.py``) and pay: from ``SPARSE_FROM_PAIRS``
    robot-carrier pairs a run (a warehouse's carriers are its orders, so its
    dense caches grow with the run). The compiled backend's states then
    carry no dense caches.
    """
    realism = scenario.realism
    exact = (
        scenario.perception == "split"
        and scenario.camera.memory == 0
        and realism.advertisement_loss == 0
        and realism.detection_noise == 0
        and scenario.camera.fade == 0
        and scenario.camera.look_around == 0
        and not scenario.radio.search
    )
    return exact and scenario.robots * scenario.carriers >= SPARSE_FROM_PAIRS


def make_params(scenario: Scenario, policy: Policy) -> Params:
    """Kernel parameters for ``scenario`` under ``policy``.

    >>> from swarmtag.policy import Proximity
    >>> p = make_params(Scenario(), Proximity())
    >>> p.step, p.dock_ticks, p.timeout_ticks, round(p.turn_cos, 6)
    (0.05, 10, 300, 0.987688)
    """
    checked: object = policy
    if not isinstance(checked, Policy):
        msg = f"policy: {checked!r} is not a Policy; use swarmtag.policy.parse_policy(name)"
        raise ConfigError(msg)
    markers = np.arange(scenario.carriers, dtype=np.int64)
    markers.flags.writeable = False
    bearing_cos, bearing_factor = bearing_profile(scenario.camera.bearing)
    return Params(
        scenario=scenario,
        policy=policy,
        markers=markers,
        floor=None if scenario.warehouse is None else floor_of(scenario.warehouse),
        sparse_tag_cache=sparse_tag_cache(scenario),
        bearing_cos=bearing_cos,
        bearing_factor=bearing_factor,
        **derive_all(scenario),
    )
