"""The warehouse part of a scenario: a floor map, a stream of orders, a KPI window.

A scenario with a ``[warehouse]`` table models continuous operation on a
floor read from an ASCII map (``swarmtag.sim.config.floor_map``) instead of the lab
arena: shelves are static obstacles, orders arrive on carriers as a Poisson
stream (mean gap ``order_interval`` seconds) into the pick-up cells, each for
one drop-off area, and the KPIs are computed over the orders placed after
``warmup`` seconds. ``initial_orders`` carriers wait in the pick-up area at
the start. An order's urgency grows under the growing model with
``urgency_window`` seconds as its ``T``: an order of initial waiting time
``w0`` placed at tick ``a`` has urgency ``min(9, floor(9 * (w0 + t - a) / T))``.

A run pre-allocates ``order_capacity`` carriers (the initial orders plus the
expected stream and six standard deviations), so the kernels keep fixed
array shapes; orders due after the run's end are not part of the run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

from swarmtag._checks import check_int, check_number
from swarmtag.errors import ConfigError
from swarmtag.sim.config.floor_map import SHIPPED_MAPS, FloorMap, load_floor_map
from swarmtag.sim.config.parts import MAX_DURATION, MAX_LENGTH

__all__ = ["MAX_ORDERS", "Warehouse", "floor_of"]

MAX_ORDERS: Final = 100_000
"""Most orders one warehouse run may pre-allocate (state is dense robot x order arrays)."""
_TAIL: Final = 6.0
"""Standard deviations of the order count pre-allocated beyond its mean."""


def floor_of(warehouse: Warehouse) -> FloorMap:
    """The floor map of ``warehouse``: parsed once per process and map (``load_floor_map``)."""
    return load_floor_map(warehouse.map, cell=warehouse.cell)


@dataclass(frozen=True, slots=True)
class Warehouse:
    """A warehouse floor and its order stream (see the module docs); times in seconds.

    ``map`` is a shipped map's name (``SHIPPED_MAPS``) or a map file; ``cell``
    the side of one map character in metres.

    >>> w = Warehouse()
    >>> w.map, w.cell, w.order_capacity(300.0)
    ('small-warehouse', 0.75, 49)
    """

    map: str = "small-warehouse"
    cell: float = 0.75
    order_interval: float = 20.0
    initial_orders: int = 4
    urgency_window: float = 600.0
    warmup: float = 60.0

    def __post_init__(self) -> None:
        given: object = self.map
        if not isinstance(given, str) or not given:
            msg = f"warehouse.map: {given!r} is not a map name ({', '.join(SHIPPED_MAPS)}) or file"
            raise ConfigError(msg)
        cell = check_number("warehouse.cell", self.cell, low=0.0, low_open=True, high=MAX_LENGTH)
        object.__setattr__(self, "cell", cell)
        for name in ("order_interval", "urgency_window"):
            value = check_number(
                f"warehouse.{name}", getattr(self, name), low=0.0, low_open=True, high=MAX_DURATION
            )
            object.__setattr__(self, name, value)
        warmup = check_number("warehouse.warmup", self.warmup, low=0.0, high=MAX_DURATION)
        object.__setattr__(self, "warmup", warmup)
        initial = check_int("warehouse.initial_orders", self.initial_orders, low=0, high=MAX_ORDERS)
        object.__setattr__(self, "initial_orders", initial)

    def summary(self) -> str:
        """One line on the floor and the order stream, for headers and reports.

        >>> Warehouse(order_interval=60.0).summary()
        'warehouse small-warehouse (12 x 7.5 m), an order every 60 s on average'
        """
        floor = floor_of(self)
        return (
            f"warehouse {self.map} ({floor.width:g} x {floor.height:g} m), "
            f"an order every {self.order_interval:g} s on average"
        )

    def order_capacity(self, run_seconds: float) -> int:
        """Carriers a run of ``run_seconds`` pre-allocates: initial orders plus the stream's tail.

        The stream's count is Poisson with mean ``m = run_seconds / order_interval``;
        ``m + 6 sqrt(m) + 6`` exceeds it with a probability below 1e-8.
        """
        mean = run_seconds / self.order_interval
        capacity = self.initial_orders + math.ceil(mean + _TAIL * math.sqrt(mean) + _TAIL)
        if capacity > MAX_ORDERS:
            msg = (
                f"warehouse.order_interval: {self.order_interval:g} s over a run of "
                f"{run_seconds:g} s needs {capacity} orders; at most {MAX_ORDERS} per run "
                "(a longer order_interval or shorter runs)"
            )
            raise ConfigError(msg)
        return max(1, capacity)

    def check_floor(
        self,
        floor: FloorMap,
        *,
        robots: int,
        carrier_size: float,
        spacing: float,
        largest_margin: float,
        step: float,
    ) -> None:
        """Refuse scenarios whose bodies do not fit this floor (names the field to change)."""
        if floor.cell < carrier_size + spacing:
            msg = (
                f"warehouse.cell: {floor.cell!r} m is less than a carrier plus the carrier "
                f"spacing ({carrier_size + spacing!r} m); carriers on neighbouring pick-up "
                "cells must leave room for a robot"
            )
            raise ConfigError(msg)
        if 2.0 * largest_margin + 2.0 * step >= floor.cell:
            msg = (
                f"warehouse.cell: {floor.cell!r} m is too small for a loaded robot "
                f"({2.0 * largest_margin!r} m across) moving {step!r} m a tick; a body must "
                "fit in one cell with room to move"
            )
            raise ConfigError(msg)
        if self.initial_orders > floor.pickup_slots.shape[0]:
            msg = (
                f"warehouse.initial_orders: {self.initial_orders} is more than the map's "
                f"{floor.pickup_slots.shape[0]} pick-up cells"
            )
            raise ConfigError(msg)
        starts = floor.start_cells.size
        if robots > starts:
            msg = (
                f"robots: {robots} do not fit on the floor of warehouse.map {self.map!r} "
                f"(one robot per free cell: at most {starts})"
            )
            raise ConfigError(msg)
