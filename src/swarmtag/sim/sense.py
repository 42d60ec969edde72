"""Phase 1 of a tick, sense: what each robot detects and hears (SPEC §4.2, §4.5).

Robots sense the world as it was at the end of the previous tick. A robot
detects a carrier when the centres are at most R apart (the carrier being in
the arena) and then hears its tag's advertisement, unless the radio loses it
this tick. Tags advertise their state of ``status_delay`` ticks earlier.
Each robot keeps the last status and urgency it heard per tag (its BLE
cache); the camera's distance may carry noise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.geometry import Float, length
from swarmtag.sim.params import Params
from swarmtag.sim.randomness import TickInputs
from swarmtag.sim.state import WorldState

__all__ = ["Senses", "sense"]


@dataclass(frozen=True, eq=False)
class Senses:
    """What the robots perceive this tick, shapes (R, N, C)."""

    in_range: NDArray[np.bool_]
    """Carrier detected: in the arena and within the detection radius."""
    distance: Float
    """Robot-to-carrier distance as measured (true distance plus camera noise)."""
    known_status: NDArray[np.int8]
    """Each robot's cache of tag statuses after this tick's advertisements (-1 never heard)."""
    known_urgency: NDArray[np.int8]
    """Each robot's cache of tag urgencies after this tick's advertisements."""


def advertised(state: WorldState, params: Params) -> tuple[NDArray[np.int8], NDArray[np.int8]]:
    """Status and urgency the tags advertise during tick ``state.tick + 1``, shapes (R, C)."""
    slot = (state.tick - params.status_delay) % (params.status_delay + 1)
    return state.adv_status[:, slot], state.adv_urgency[:, slot]


def sense(state: WorldState, inputs: TickInputs, params: Params) -> Senses:
    """Detections and the updated tag caches, from ``state`` (the end of the previous tick)."""
    offset = state.carrier_pos[:, None, :, :] - state.robot_pos[:, :, None, :]  # (R, N, C, 2)
    distance = length(offset)
    in_range = state.present[:, None, :] & (distance <= params.detection_radius)
    heard = in_range if inputs.heard is None else in_range & inputs.heard
    status, urgency = advertised(state, params)
    known_status = np.where(heard, status[:, None, :], state.known_status)
    known_urgency = np.where(heard, urgency[:, None, :], state.known_urgency)
    if inputs.noise is not None:
        distance = length(offset + inputs.noise)
    return Senses(
        in_range=in_range,
        distance=distance,
        known_status=known_status,
        known_urgency=known_urgency,
    )
