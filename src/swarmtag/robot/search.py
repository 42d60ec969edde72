"""BLE-led search in the behaviour tree: seeking a chosen tag by its signal (docs/simulator.md).

With ``radio_search`` a robot chooses among every tag it heard awaiting
pick-up, ranging those its cameras do not know by their RSSI
(``TagStates.distance``). A chosen tag the cameras do not see is *sought*:
the robot walks on, keeping its heading while the tag's estimated distance
stays within ``seek_margin`` of the least on this heading and taking a new
random one when it grows beyond (run and tumble); it approaches the carrier
once a camera sees it. The pursuit's abandon and timeout rules apply from
the choice on. The same rules as ``swarmtag.sim.builtin.decide``, for one
robot.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarmtag.robot.config import ControllerConfig
from swarmtag.robot.io import Detections, Float, Report, RobotIO, TagStates
from swarmtag.tag import TagStatus

__all__ = ["candidate_distances", "give_up_seeking", "seek_tumbles", "start_seeking"]

_AWAITING = int(TagStatus.AWAITING_PICKUP)


def candidate_distances(tags: TagStates, seen: Detections) -> Float:
    """(C,): ``d`` of the score: the camera's distance where it knows the carrier, else RSSI's."""
    if tags.distance is None:
        msg = "BLE-led search needs TagStates.distance (the tags' RSSI ranging)"
        raise RuntimeError(msg)
    ranged = np.where(np.isnan(tags.distance), np.inf, tags.distance)  # never heard: no candidate
    distance: Float = np.where(seen.known, seen.distance, ranged)
    return distance


def give_up_seeking(io: RobotIO, memory: Any, config: ControllerConfig) -> bool:  # noqa: ANN401
    """A seeker's pursuit checks: abandon or time out (then back to a fresh walk).

    Returns whether the robot gave its tag up (it may choose again this tick).
    """
    sought = int(memory.seek)
    heard = int(io.tag_states().status[sought])
    if heard != _AWAITING:
        io.report(Report.ABANDON, sought, float(heard))
    elif io.tick - memory.pursuit_start >= config.timeout_ticks:
        io.report(Report.TIMEOUT, sought, float("nan"))
        memory.blocked_until[sought] = io.tick + config.cooldown_ticks
    else:
        return False
    io.walk()
    memory.target = memory.face = memory.seek = -1
    memory.timer = 0
    memory.redirect = True
    return True


def start_seeking(memory: Any, carrier: int, tags: TagStates) -> None:  # noqa: ANN401
    """Seek ``carrier`` from now on, its current estimate the first leg's reference."""
    assert tags.distance is not None
    memory.seek = carrier
    memory.seek_ref = float(tags.distance[carrier])


def seek_tumbles(io: RobotIO, memory: Any, config: ControllerConfig, fresh: bool) -> bool:  # noqa: ANN401
    """``fresh``, or a seeker whose tag's signal weakened: take a new heading (run and tumble)."""
    tags = io.tag_states()
    assert tags.distance is not None
    sought = int(memory.seek)
    now = float(tags.distance[sought])
    if tags.age[sought] == 0:  # heard this tick
        if now > memory.seek_ref * config.seek_margin:
            fresh = True
        memory.seek_ref = min(memory.seek_ref, now)
    if fresh:
        memory.seek_ref = now
    return fresh
