"""Sampling a run's initial scene from its scene stream (SPEC §4.1, §4.5).

The scene stream of run ``i`` (``SeedSequence(S, spawn_key=(i, 0))``) is
used in this order, whatever the policy, so run ``i`` starts from the same
scene in every condition:

1. carriers, in marker order, by rejection: each candidate is
   ``lo + rng.random(2) * (hi - lo)`` within the pick-up area (the carrier
   wholly inside it); it is kept when its Chebyshev distance to every carrier
   already placed is at least ``carrier_size + carrier_spacing``. After
   1000 rejected candidates for one carrier the placement starts over;
   after 100 restarts (a pick-up area too crowded for random placement,
   which jams at about half of the densest packing) the carriers stand on
   the densest grid instead: ``rng.permutation`` of its cells (row by row,
   spacing ``carrier_size + carrier_spacing`` from the area's corner), the
   first ``C`` of them in marker order (``Scenario`` has refused scenarios
   whose grid holds fewer);
2. one ``rng.random(C)`` for the urgencies (``swarmtag.sim.world.urgency``);
3. robots, in id order, by rejection within the drop-off area: kept when
   ``sqrt(dx*dx + dy*dy)`` to every robot already placed is at least one
   diameter (same limits, the same grid after them, spacing one diameter);
4. ``rng.standard_normal((N, 2))``, normalised: initial headings (and
   random-walk directions);
5. ``rng.standard_normal(N)``: speed factors ``clip(1 + v * z, 0.5, 1.5)``
   for speed variation v (exactly 1 when v = 0);
6. ``rng.random(C)``: each tag's advertising phase, as a fraction of the
   advertising interval (drawn last, so the draws above are those of the
   simulator before it had phases).

A warehouse scene (orders, robots on the floor) is sampled by
``swarmtag.sim.world.orders.sample_warehouse_scene`` from the same stream.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Final

import numpy as np

from swarmtag.errors import ConfigError
from swarmtag.sim.model.geometry import Float
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import Stream, stream, unit_vectors
from swarmtag.sim.model.state import Scene
from swarmtag.sim.world.orders import sample_warehouse_scene
from swarmtag.sim.world.urgency import initial_urgency
from swarmtag.tag import TagStatus

__all__ = ["grid_place", "sample_scene"]

PLACE_ATTEMPTS: Final = 1000
PLACE_RESTARTS: Final = 100


def _place(
    rng: np.random.Generator,
    count: int,
    *,
    low: Float,
    high: Float,
    far_enough: Callable[[float, float, list[tuple[float, float]]], bool],
    pitch: float,
) -> Float:
    """``count`` points placed one after another by rejection, else on the grid (module docs).

    The candidates and distances are plain floats: the same IEEE operations as
    on arrays, without numpy's call overhead on two numbers (a crowded area
    tries hundreds of thousands of candidates).
    """
    low_x, low_y = low.tolist()
    span_x, span_y = (high - low).tolist()
    for _ in range(PLACE_RESTARTS):
        placed: list[tuple[float, float]] = []
        for _ in range(count):
            for _ in range(PLACE_ATTEMPTS):
                unit_x, unit_y = rng.random(2).tolist()
                x, y = low_x + unit_x * span_x, low_y + unit_y * span_y
                if far_enough(x, y, placed):
                    placed.append((x, y))
                    break
            else:
                break
        else:
            return np.array(placed, dtype=np.float64).reshape(count, 2)
    return grid_place(rng, count, low=low, high=high, pitch=pitch)


def grid_place(
    rng: np.random.Generator, count: int, *, low: Float, high: Float, pitch: float
) -> Float:
    """``count`` cells of the grid of ``pitch`` from ``low`` within ``high``, chosen at random.

    The cells are numbered row by row (x fastest); ``rng.permutation`` of
    their numbers picks them, the first ``count`` in order. ``ConfigError``
    when the grid has fewer cells (``Scenario`` refuses such scenarios first).

    >>> cells = grid_place(np.random.default_rng(0), 3, low=np.zeros(2), high=np.ones(2),
    ...                    pitch=0.5)
    >>> sorted(map(tuple, cells.tolist()))
    [(0.5, 0.5), (1.0, 0.0), (1.0, 0.5)]
    """
    columns, rows = (np.floor((high - low) / pitch).astype(np.int64) + 1).tolist()
    if columns * rows < count:
        msg = f"{count} bodies do not fit on a {columns} x {rows} grid of pitch {pitch!r} m"
        raise ConfigError(msg)
    chosen = rng.permutation(columns * rows)[:count]
    cells: Float = low + np.stack((chosen % columns, chosen // columns), axis=-1) * pitch
    return cells


def sample_scene(params: Params, *, seed: int, run: int) -> Scene:
    """The initial scene of global run ``run`` of master seed ``seed``."""
    rng = stream(seed, run, Stream.SCENE)
    if params.floor is not None:
        return sample_warehouse_scene(params, rng)
    half, radius, arena = params.carrier_half, params.robot_radius, params.arena
    pitch = 2 * half + params.carrier_spacing

    def carriers_apart(x: float, y: float, others: list[tuple[float, float]]) -> bool:
        return all(max(abs(x - ox), abs(y - oy)) >= pitch for ox, oy in others)

    carrier_pos = _place(
        rng,
        params.carriers,
        low=np.array([half, half]),
        high=np.array([params.pickup_right - half, arena - half]),
        far_enough=carriers_apart,
        pitch=pitch,
    )
    urgency = initial_urgency(
        rng.random(params.carriers),
        growing=params.growing,
        horizon=params.horizon,
        horizon_s=params.scenario.urgency.static_horizon,
    )

    diameter = 2 * radius

    def robots_apart(x: float, y: float, others: list[tuple[float, float]]) -> bool:
        return all(
            math.sqrt((ox - x) * (ox - x) + (oy - y) * (oy - y)) >= diameter for ox, oy in others
        )

    robot_pos = _place(
        rng,
        params.robots,
        low=np.array([params.dropoff_left + radius, radius]),
        high=np.array([arena - radius, arena - radius]),
        far_enough=robots_apart,
        pitch=diameter,
    )
    heading = unit_vectors(rng.standard_normal((params.robots, 2)))
    factor = np.clip(1.0 + params.speed_variation * rng.standard_normal(params.robots), 0.5, 1.5)
    phase = rng.random(params.carriers)
    return Scene(
        robot_pos=robot_pos,
        carrier_pos=carrier_pos,
        urgency0=urgency.urgency0,
        order_time=urgency.order_time,
        w0=urgency.w0,
        heading=heading,
        speed_factor=factor,
        status=np.full(params.carriers, TagStatus.AWAITING_PICKUP, dtype=np.int8),
        advert_phase=phase,
    )
