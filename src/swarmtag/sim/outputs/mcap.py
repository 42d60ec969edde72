"""A recorded run as an MCAP file for Foxglove and ``swarmtag log import`` (the ``bags`` extra).

``write_mcap`` walks one recorded run tick by tick and writes it through
``swarmtag.io.mcap_out.McapRecorder``: the trial start (condition, run, seed, time unit, tick,
and every carrier's urgency and order time) at tick 0, each tick's tag changes (lifts and
deliveries with their robot, then urgency changes from growth and operator writes, in the
order they took effect), its events (the event-table rows of that tick, in their order),
robot and carrier poses and the 3-D scene, and the trial end at the tick the run ended.
Tick ``n`` is stamped ``n`` ticks after time 0, so importing the file gives back the run's
event log and event table exactly (``swarmtag.io.bag_trials.trial_time``).
"""

from __future__ import annotations

import os
from typing import Final

import numpy as np

from swarmtag._interrupt import checkpoint
from swarmtag.errors import ConfigError
from swarmtag.io import CarrierLog, EventTable
from swarmtag.io.bag_trials import tick_nanoseconds
from swarmtag.io.mcap_out import Arena, McapRecorder, TrialInfo
from swarmtag.sim.model.state import Mode
from swarmtag.sim.outputs.trajectories import Geometry, Trajectories
from swarmtag.tag import TagStatus

__all__ = ["MCAP_MARKERS", "check_mcap_carriers", "write_mcap"]

_STATUS_EVENTS: Final = {"lift": int(TagStatus.PICKED_UP), "deliver": int(TagStatus.IDLE)}


def _run_rows(traj: Trajectories, run: int) -> int:
    matches = np.flatnonzero(traj.run_ids == run)
    if matches.size == 0:
        msg = f"run: {run} was not recorded"
        raise ConfigError(msg)
    return int(matches[0])


def _floor_cells(geometry: Geometry) -> tuple[tuple[str, float, float, float], ...]:
    """A warehouse map's shelf, pick-up and drop-off cells for the 3-D scene (lab: none)."""
    lines = geometry.floor_text.splitlines()
    kinds = {"#": "shelf", "P": "pickup", **dict.fromkeys("0123456789", "dropoff")}
    side = geometry.floor_cell
    return tuple(
        (kinds[char], column * side, (len(lines) - 1 - line) * side, side)
        for line, text in enumerate(lines)
        for column, char in enumerate(text)
        if char in kinds
    )


MCAP_MARKERS: Final = 256
"""Carriers an MCAP trial can name: its markers are one byte (``swarmtag_msgs/Trial``,
as the tag's advertisement byte 5), and a carrier's marker is its index in the run."""


def check_mcap_carriers(carriers: int) -> None:
    """Refuse (``ConfigError``) runs of more carriers than an MCAP trial's markers can name."""
    if carriers > MCAP_MARKERS:
        msg = (
            f"an MCAP run names its carriers by one-byte marker ids (0-{MCAP_MARKERS - 1}), "
            f"but this scenario has {carriers} carriers (a warehouse's orders over the run): "
            "shorten the run, lengthen warehouse.order_interval, or write no MCAP"
        )
        raise ConfigError(msg)


def write_mcap(
    path: str | os.PathLike[str],
    traj: Trajectories,
    carriers: CarrierLog,
    events: EventTable,
    *,
    run: int,
) -> int:
    """Write run ``run`` of ``traj``, with its rows of ``carriers`` and ``events``; the ticks."""
    check_mcap_carriers(traj.carrier_status.shape[-1])
    row = _run_rows(traj, run)
    log = carriers.take((carriers.run == run) & (carriers.condition == traj.condition))
    table = events.take((events.run == run) & (events.condition == traj.condition))
    geometry = traj.geometry
    scale = 1.0 if log.time_unit == "tick" else geometry.tick_seconds
    step = tick_nanoseconds(geometry.tick_seconds)
    end_tick = round(float(log.run_end[0]) / scale) if len(log) else traj.ticks
    event_ticks = np.rint(table.time / scale).astype(np.int64)
    arena = Arena(
        size=geometry.arena,
        pickup_right=geometry.pickup_right,
        dropoff_left=geometry.dropoff_left,
        robot_radius=geometry.robot_radius,
        carrier_size=geometry.carrier_size,
        height=geometry.extent_y,
        cells=_floor_cells(geometry),
    )
    markers = log.carrier.tolist()
    columns = np.asarray(markers, dtype=np.int64)  # a carrier's marker is its index in the run
    status = traj.carrier_status[row][:, columns].astype(np.int64)
    urgency = traj.carrier_urgency[row][:, columns].astype(np.int64)
    last = dict.fromkeys(markers, (-1, -1))
    trial = TrialInfo(
        condition=traj.condition,
        run=run,
        seed=traj.seed,
        time_unit=log.time_unit or "tick",
        tick=geometry.tick_seconds,
    )
    with McapRecorder(path) as out:
        for tick in range(min(end_tick, traj.ticks) + 1):
            checkpoint()
            at = tick * step
            rows = np.flatnonzero(event_ticks == tick)
            changes = []
            if tick == 0:
                out.trial(
                    at,
                    trial,
                    starts=True,
                    markers=markers,
                    urgency0=log.urgency0.tolist(),
                    order_time=log.order_time.tolist(),
                )
                out.arena(at, arena)
            for index in rows.tolist():
                kind = str(table.kind[index])
                if kind in _STATUS_EVENTS:
                    marker = int(table.carrier[index])
                    change = (_STATUS_EVENTS[kind], int(table.value[index]))
                    changes.append((marker, *change, int(table.robot[index])))
                    last[marker] = change
            for position, marker in enumerate(markers):
                now = (int(status[tick, position]), int(urgency[tick, position]))
                if now != last[marker]:
                    changes.append((marker, *now, -1))
                    last[marker] = now
            if changes:
                out.tag_changes(at, changes)
            if rows.size:
                out.robot_events(
                    at,
                    [
                        (
                            str(table.kind[i]),
                            int(table.robot[i]),
                            int(table.carrier[i]),
                            float(table.value[i]),
                        )
                        for i in rows.tolist()
                    ],
                )
            out.frame(
                at,
                arena,
                robot_xy=traj.robot_pos[row, tick],
                robot_heading=traj.robot_heading[row, tick],
                robot_labels=[
                    f"r{r} {Mode(int(m)).name.lower()}"
                    for r, m in enumerate(traj.robot_mode[row, tick].tolist())
                ],
                markers=markers,
                carrier_xy=traj.carrier_pos[row, tick][columns],
                carrier_status=status[tick].tolist(),
                carrier_urgency=urgency[tick].tolist(),
                carrier_present=traj.carrier_present[row, tick][columns].tolist(),
            )
            if tick == end_tick:
                out.trial(at, trial, starts=False)
    return min(end_tick, traj.ticks) + 1
