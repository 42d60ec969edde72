"""The compiled backend's own constants beside the kernel parameters: name, type, doc.

``Constants`` (generated into ``_constants.py`` by
``swarmtag.sim.model.kernel_parameters``) holds every scalar of ``Params``
and then these; ``_layout.constants_of`` computes them.
"""

from __future__ import annotations

from typing import Final

__all__ = ["EXTRAS"]

EXTRAS: Final[tuple[tuple[str, str, str], ...]] = (
    ("policy_kind", "int", "The policy as the kernel's kind (``swarmtag.policy.kernel_form``)."),
    ("policy_parameter", "float", "The policy's parameter (alpha, w; 0 for proximity)."),
    ("grid_cell", "float", "Side of a grid cell: the longest reach of a collision."),
    ("robot_bits", "int", "The robots' grid tables have ``2**bits`` by ``2**bits`` buckets."),
    ("carrier_bits", "int", "The same for the carriers' grid tables."),
    ("obstacle_grid", "bool", "Find each robot's obstacle carriers with the grid, not a scan."),
    ("robot_grid", "bool", "Find each robot's neighbours with the grid (many robots), not a scan."),
    (
        "sight_reach",
        "float",
        "The camera's farthest reach: its far end times the top bearing factor.",
    ),
    (
        "sight_cell",
        "float",
        "Side of a coarse grid cell: the camera's farthest reach (at least one).",
    ),
    ("radio_grid", "bool", "Find the advertising tags each robot may hear with a grid."),
    ("radio_cell", "float", "Side of a radio grid cell: the radio range, padded against rounding."),
    ("sparse_cache", "bool", "Robots keep their tag caches as short lists (``Params``)."),
    ("cache_capacity", "int", "Entries of a sparse tag cache (``World.cache_*``); 0 when dense."),
    ("has_floor", "bool", "A warehouse floor (the ``floor_*`` arrays); else the lab arena."),
    ("floor_cell", "float", "Side of a floor cell, metres."),
    ("floor_rows", "int", "Rows of the floor map."),
    ("floor_cols", "int", "Columns of the floor map."),
    ("floor_blocked", "NDArray[np.bool_]", "(rows + 2, cols + 2) shelves and the wall around."),
    ("floor_area", "NDArray[np.int64]", "(rows, cols) drop-off area id of each cell, -1 none."),
    ("floor_waypoint", "NDArray[np.float64]", "(D, rows, cols, 2) the next waypoint to each area."),
    ("floor_destinations", "NDArray[np.int64]", "(D,) the destination (area) ids."),
    ("pickup_slots", "NDArray[np.float64]", "(K, 2) the pick-up slots' centres (lab: a dummy)."),
    ("slot_at", "NDArray[np.int64]", "(rows, cols) the pick-up slot of each cell, -1 none."),
    ("bearing", "bool", "The camera's reach varies with bearing (``Params.bearing_factor``)."),
    (
        "bearing_cosines",
        "NDArray[np.float64]",
        "The bearing profile's cosines, falling (``Params``).",
    ),
    ("bearing_factors", "NDArray[np.float64]", "The reach's factor at each of them (``Params``)."),
)
"""The backend's own fields of ``Constants``, after the parameters, in this order."""
