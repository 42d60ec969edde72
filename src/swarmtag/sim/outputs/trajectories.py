"""Per-tick trajectories for replay, snapshots and animations (SPEC §4.4).

Everything a renderer needs, with a leading run axis and then a time axis
(tick 0 = the start, then one entry per tick, after the tick's last phase):
robots' positions, headings, modes and targets; carriers' positions,
statuses, urgencies, holders and presence; plus the static ``Geometry``
(arena, zones, detection radius, body sizes). Runs that ended before the
batch stopped repeat their final state.
"""

from __future__ import annotations

import os
import zipfile
from dataclasses import MISSING, asdict, dataclass, fields
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._atomic import atomic_path
from swarmtag.errors import ConfigError
from swarmtag.sim.model.geometry import Float
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.state import Int, WorldState

__all__ = ["Geometry", "Trajectories", "TrajectoryRecorder"]


@dataclass(frozen=True)
class Geometry:
    """The static picture: arena ``[0, arena]^2`` (m), zones, perception ranges, body sizes.

    ``detection_radius`` is the disc model's radius, or the camera range of
    split perception; ``radio_range`` is the BLE range of split perception
    (0 for the disc model, where the two are one).
    """

    arena: float
    pickup_right: float
    """The pick-up area is ``0 <= x <= pickup_right``."""
    dropoff_left: float
    """The drop-off area (destination 0) is ``dropoff_left <= x <= arena``."""
    detection_radius: float
    robot_radius: float
    carrier_size: float
    tick_seconds: float
    radio_range: float = 0.0
    height: float = 0.0
    """The arena's extent in y; 0: square (``arena``)."""
    floor_text: str = ""
    """A warehouse's map (``FloorMap.text``: lines, top first); empty in the lab arena."""
    floor_cell: float = 0.0
    """Side of one map cell, metres (warehouse only)."""

    @property
    def extent_y(self) -> float:
        """The arena's extent in y."""
        return self.height or self.arena

    @classmethod
    def from_params(cls, params: Params) -> Geometry:
        """The geometry of a parameter set."""
        return cls(
            arena=params.arena,
            pickup_right=params.pickup_right,
            dropoff_left=params.dropoff_left,
            detection_radius=params.detection_radius,
            robot_radius=params.robot_radius,
            carrier_size=2 * params.carrier_half,
            tick_seconds=params.scenario.tick,
            radio_range=params.radio_range if params.split else 0.0,
            height=params.arena_height,
            floor_text="" if params.floor is None else params.floor.text,
            floor_cell=0.0 if params.floor is None else params.floor.cell,
        )


@dataclass(frozen=True, eq=False)
class Trajectories:
    """Recorded states, shapes (R, T + 1, ...) for R runs and T recorded ticks.

    ``robot_mode`` holds ``swarmtag.sim.Mode`` values; ``robot_target`` and
    ``carried_by`` are -1 for none; ``carrier_status`` holds ``TagStatus``
    values; carriers with ``carrier_present`` false have been delivered.
    """

    geometry: Geometry
    condition: str
    seed: int
    run_ids: Int
    time: Int
    """(T + 1,) tick numbers 0..T."""
    robot_pos: Float
    robot_heading: Float
    robot_mode: NDArray[np.int8]
    robot_target: NDArray[np.int16]
    carrier_pos: Float
    carrier_status: NDArray[np.int8]
    carrier_urgency: NDArray[np.int8]
    carried_by: NDArray[np.int16]
    carrier_present: NDArray[np.bool_]
    ended_at: Int
    """(R,) tick each run ended, -1 if it was still running when recording stopped."""

    @property
    def ticks(self) -> int:
        """Number of recorded ticks T."""
        return int(self.time.shape[0]) - 1

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write a compressed ``.npz`` file that ``load`` reads back, for replay and drawing."""
        payload: dict[str, Any] = {
            f.name: getattr(self, f.name) for f in fields(self) if f.name not in _SCALARS
        }
        payload.update(format=_FORMAT, condition=self.condition, seed=self.seed)
        payload.update({f"geometry.{k}": v for k, v in asdict(self.geometry).items()})
        with atomic_path(path) as temp, temp.open("wb") as handle:
            arrays = {k: np.asarray(v) for k, v in payload.items()}
            # numpy's stubs let ** reach the bool allow_pickle (numpy >= 2.1 only): not ours.
            np.savez_compressed(handle, **arrays)  # type: ignore[arg-type]

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Trajectories:
        """Read trajectories written by ``save``; ``ConfigError`` if the file is not one."""
        where = os.fspath(path)
        try:
            with np.load(path, allow_pickle=False) as data:
                if "format" not in data or str(data["format"]) != _FORMAT:
                    msg = f"{where}: not a swarmtag trajectories file ({_FORMAT})"
                    raise ConfigError(msg)
                given = {
                    f.name: data[f"geometry.{f.name}"]
                    for f in fields(Geometry)
                    if f"geometry.{f.name}" in data or f.default is MISSING
                }
                text = str(given.pop("floor_text", ""))
                geometry = Geometry(**{k: float(v) for k, v in given.items()}, floor_text=text)
                arrays = {f.name: data[f.name] for f in fields(cls) if f.name not in _SCALARS}
                return cls(
                    geometry=geometry,
                    condition=str(data["condition"]),
                    seed=int(data["seed"]),
                    **arrays,
                )
        except (OSError, ValueError, KeyError, zipfile.BadZipFile) as error:
            msg = f"{where}: cannot read trajectories ({error})"
            raise ConfigError(msg) from None


_FORMAT: Final = "swarmtag-trajectories-1"
"""Version tag stored in every trajectories file."""
_SCALARS: Final = frozenset({"geometry", "condition", "seed"})

_FIELDS = {
    "robot_pos": ("robot_pos", np.float64),
    "robot_heading": ("heading", np.float64),
    "robot_mode": ("mode", np.int8),
    "robot_target": ("target", np.int16),
    "carrier_pos": ("carrier_pos", np.float64),
    "carrier_status": ("status", np.int8),
    "carrier_urgency": ("urgency", np.int8),
    "carried_by": ("carried_by", np.int16),
    "carrier_present": ("present", np.bool_),
}


class TrajectoryRecorder:
    """Collects states tick by tick into preallocated arrays."""

    def __init__(self, first: WorldState, max_ticks: int) -> None:
        self._arrays: dict[str, NDArray[Any]] = {}
        for name, (source, dtype) in _FIELDS.items():
            value = getattr(first, source)
            shape = (value.shape[0], max_ticks + 1, *value.shape[1:])
            self._arrays[name] = np.empty(shape, dtype=dtype)
        self._count = 0
        self.add(first)

    def add(self, state: WorldState) -> None:
        """Record ``state`` as the next time step."""
        for name, (source, _dtype) in _FIELDS.items():
            self._arrays[name][:, self._count] = getattr(state, source)
        self._count += 1

    def finish(self, params: Params, *, seed: int, last: WorldState) -> Trajectories:
        """The trajectories recorded so far."""
        arrays = {name: array[:, : self._count].copy() for name, array in self._arrays.items()}
        return Trajectories(
            geometry=Geometry.from_params(params),
            condition=params.condition,
            seed=seed,
            run_ids=last.run_ids.copy(),
            time=np.arange(self._count, dtype=np.int64),
            ended_at=last.ended_at.copy(),
            **arrays,
        )
