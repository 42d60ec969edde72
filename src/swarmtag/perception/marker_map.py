"""A marker map on a carrier's underside: a grid of small ArUco markers the upward camera reads.

The DOTS carriers carry no single underside marker but a *marker map*: 7 x 7
``ARUCO_MIP_36h12`` markers, ids 200-248, 23.4 mm each (the lab's public robot
code; docs/perception.md, "The dots rig's underside"). Every carrier carries the
same map, so a map marker names no carrier: it says where the carrier's centre
is and how the carrier is turned, from whichever part of the map is in view.

``UndersideMap`` is that grid: its size, its markers' size, their pitch
(centre-to-centre spacing) and its first id. Ids run along a row (the map's
``x``), rows follow each other along its ``y``, and the grid is centred on the
underside: the layout of the lab's map file (``dots_vision/params/mm49_out.yml``,
id 200 at the corner of smallest ``x`` and ``y``). The map's frame is the
underside marker frame of ``markers.marker_frames`` (``x`` towards the carrier's
east face, ``z`` down, so ``y`` towards its south face), and ``offset`` gives
each marker's centre in it. A rig without a map keeps the single underside
marker with the carrier's own id (``CarrierMarkers.underside_map`` is None).

>>> grid = UndersideMap()
>>> grid.ids
range(200, 249)
>>> grid.offset(200).round(4).tolist(), grid.offset(224).tolist()
([-0.1053, -0.1053], [0.0, 0.0])
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import check_int, check_number
from swarmtag.errors import PerceptionError

__all__ = ["MAX_GRID", "MIN_GAP_MODULES", "UndersideMap"]

Float = NDArray[np.float64]

MAX_GRID: Final = 50
"""Most markers along either side of a map (the dictionary holds 250 ids in all)."""
MIN_GAP_MODULES: Final = 1.0
"""Least white gap between two map markers, in modules (1/8 of a marker's side): with less,
neighbouring black borders merge and ArUco finds no square."""
_LAST_ID: Final = 249
"""The dictionary's last id (``markers.MARKER_IDS`` - 1; this module sits below ``markers``)."""
_MAX_LENGTH: Final = 10.0
"""Largest marker side or pitch accepted (m): far beyond any carrier."""


@dataclass(frozen=True, slots=True)
class UndersideMap:
    """A ``columns`` x ``rows`` grid of markers on the underside, centred on the carrier.

    ``marker_size`` (m): each marker's black square; ``pitch`` (m): from one marker's
    centre to the next (the same along both axes; at least one module of white
    between markers); ``first_id``: the id of the marker at the corner of smallest
    ``x`` and ``y``, the others numbered along rows. The defaults are the DOTS map
    (docs/perception.md gives where each number comes from).
    """

    columns: int = 7
    rows: int = 7
    marker_size: float = 0.0234
    pitch: float = 0.0351
    first_id: int = 200

    def __post_init__(self) -> None:
        for name in ("columns", "rows"):
            count = check_int(
                f"underside_map.{name}",
                getattr(self, name),
                low=1,
                high=MAX_GRID,
                error=PerceptionError,
            )
            object.__setattr__(self, name, count)
        size = check_number(
            "underside_map.marker_size",
            self.marker_size,
            low=0.0,
            low_open=True,
            high=_MAX_LENGTH,
            error=PerceptionError,
        )
        least = size * (1.0 + MIN_GAP_MODULES / 8.0)
        pitch = check_number(
            "underside_map.pitch",
            self.pitch,
            low=least,
            high=_MAX_LENGTH,
            error=PerceptionError,
        )
        last = _LAST_ID - self.columns * self.rows + 1
        first = check_int(
            "underside_map.first_id", self.first_id, low=0, high=last, error=PerceptionError
        )
        object.__setattr__(self, "marker_size", size)
        object.__setattr__(self, "pitch", pitch)
        object.__setattr__(self, "first_id", first)

    @property
    def ids(self) -> range:
        """The map's marker ids, in order."""
        return range(self.first_id, self.first_id + self.columns * self.rows)

    @property
    def extent(self) -> float:
        """The map's longer side, from the outer edge of one corner marker to the other's (m)."""
        return (max(self.columns, self.rows) - 1) * self.pitch + self.marker_size

    def holds(self, marker: int) -> bool:
        """Whether ``marker`` is one of the map's ids."""
        return marker in self.ids

    def offset(self, marker: int) -> Float:
        """Map marker ``marker``'s centre (2,) in the map's frame (m, from the map's centre)."""
        if not self.holds(marker):
            msg = f"marker {marker} is not on the underside map (ids {self.describe()})"
            raise PerceptionError(msg)
        row, column = divmod(marker - self.first_id, self.columns)
        return np.array(
            [
                (column - (self.columns - 1) / 2) * self.pitch,
                (row - (self.rows - 1) / 2) * self.pitch,
            ]
        )

    def describe(self) -> str:
        """The map's ids as a range, ``200-248``."""
        return f"{self.ids.start}-{self.ids.stop - 1}"
