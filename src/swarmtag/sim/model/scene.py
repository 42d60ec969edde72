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

from collections.abc import Callable
from typing import Final

import numpy as np
from numpy.typing import NDArray

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


FarEnough = Callable[[Float, Float, Float], NDArray[np.bool_]]
"""Which candidates ``(xs[j], ys[j])`` keep their distance to every point of ``placed`` (rows)."""

_FIRST_BLOCK: Final = 16
"""Candidates drawn and tested at once for a point at first; the blocks double after each miss."""
_BLOCK: Final = 128
"""Most candidates drawn and tested at once (a grid-placed 20 x 40 scene: 0.53 s one at a time,
0.08 s so; an uncrowded 3 x 7 scene: 0.1 ms one at a time, 0.2 ms so)."""


def _place(
    rng: np.random.Generator,
    count: int,
    *,
    low: Float,
    high: Float,
    far_enough: FarEnough,
    pitch: float,
) -> Float:
    """``count`` points placed one after another by rejection, else on the grid (module docs)."""
    span = high - low
    for _ in range(PLACE_RESTARTS):
        placed = np.empty((count, 2))
        for n in range(count):
            point = _first_kept(rng, low, span, far_enough, placed[:n])
            if point is None:
                break
            placed[n] = point
        else:
            return placed
    return grid_place(rng, count, low=low, high=high, pitch=pitch)


def _first_kept(
    rng: np.random.Generator, low: Float, span: Float, far_enough: FarEnough, placed: Float
) -> Float | None:
    """The first of ``PLACE_ATTEMPTS`` candidates that ``far_enough`` keeps, or None.

    The candidates are drawn and tested in blocks (a crowded area tries
    hundreds of thousands of them; one at a time, each cost two numpy calls
    and a Python loop over the points placed). The stream is left exactly
    where drawing them one pair at a time leaves it: after a block that
    holds the kept one, its generator goes back to before the block and
    draws again only as far as the kept one. The same IEEE operations on
    the same numbers: the same points as one at a time.
    """
    bits = rng.bit_generator
    tried, block = 0, _FIRST_BLOCK
    while tried < PLACE_ATTEMPTS:
        size = min(block, PLACE_ATTEMPTS - tried)
        before = bits.state
        candidates = low + rng.random((size, 2)) * span
        kept = far_enough(candidates[:, 0], candidates[:, 1], placed)
        if kept.any():
            first = int(kept.argmax())
            if first < size - 1:
                bits.state = before
                rng.random((first + 1, 2))
            kept_point: Float = candidates[first]
            return kept_point
        tried += size
        block = min(2 * block, _BLOCK)
    return None


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

    def carriers_apart(xs: Float, ys: Float, others: Float) -> NDArray[np.bool_]:
        gap = np.maximum(np.abs(xs[:, None] - others[:, 0]), np.abs(ys[:, None] - others[:, 1]))
        return np.asarray((gap >= pitch).all(axis=1), dtype=np.bool_)

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

    def robots_apart(xs: Float, ys: Float, others: Float) -> NDArray[np.bool_]:
        dx, dy = others[:, 0] - xs[:, None], others[:, 1] - ys[:, None]
        return np.asarray((np.sqrt(dx * dx + dy * dy) >= diameter).all(axis=1), dtype=np.bool_)

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
