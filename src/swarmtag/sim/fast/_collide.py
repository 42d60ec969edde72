"""Resolve collisions, compiled: ``sim/world/motion.py``'s Jacobi passes for one run.

``resolve_run`` runs the passes (every push from the positions at the start
of the pass, sums over touching bodies in index order from 0.0, then the
walls) and writes the outcome. A pass that moves nobody in the run is a
fixed point, so the run's remaining passes are skipped: the reference stops
when that holds for the whole batch, and extra passes at a fixed point change
nothing. A pass after the first computes only the robots near one the pass
before moved (with the robots' grid in large swarms, by a scan in small ones):
the others would compute their positions again unchanged.
"""

from __future__ import annotations

from typing import Final

import numpy as np

from swarmtag.sim.fast._floor import cell_of, keep_off_shelves
from swarmtag.sim.fast._geometry import contact, maximum, minimum
from swarmtag.sim.fast._grid import fill, near, near_within, table_bits
from swarmtag.sim.fast._index import grid_robots
from swarmtag.sim.fast._jit import inlined
from swarmtag.sim.fast._layout import Constants, World
from swarmtag.sim.fast._motion import start_body
from swarmtag.sim.fast._scratch import Scratch
from swarmtag.sim.model.state import Mode

__all__ = [
    "collide_range",
    "drop_ghosts",
    "resolve_begin",
    "resolve_finish",
    "resolve_passes",
    "resolve_run",
    "settle_positions",
]


@inlined
def _beyond_obstacles(r: int, xn: float, yn: float, reach: float, x: Scratch) -> bool:
    """Whether every obstacle is at least ``reach`` away along x or y (none can touch).

    Rounding is monotonic: ``xn - high >= reach`` gives ``xn - cx >= reach`` for
    every obstacle ``cx <= high``, so the exact test would reject every pair.
    """
    box = x.obstacle_box
    away: bool = (
        x.obstacle_count[r] == 0
        or xn - box[r, 1] >= reach
        or box[r, 0] - xn >= reach
        or yn - box[r, 3] >= reach
        or box[r, 2] - yn >= reach
    )
    return away


@inlined
def _robot_sums(
    r: int,
    n: int,
    xn: float,
    yn: float,
    extent: float,
    radius: float,
    ids: np.ndarray,
    count: int,
    listed: bool,
    x: Scratch,
) -> tuple[float, float]:
    """The summed pushes of other robots on movable robot ``n`` (at ``xn, yn``, its body).

    The robots are ``ids[r, :count]`` (ascending) when ``listed``, else ``0 .. count - 1``.
    """
    total_x = 0.0
    total_y = 0.0
    for j in range(count):
        m = ids[r, j] if listed else j
        if m == n:
            continue
        pair_extent = extent + x.extent[r, m]
        pair_radius = radius + x.radius[r, m]
        reach = pair_extent + pair_radius
        dx = xn - x.x[r, m]
        dy = yn - x.y[r, m]
        if abs(dx) < reach and abs(dy) < reach:
            share = 0.5 if x.movable[r, m] else 1.0
            push_x, push_y, _ = contact(dx, dy, pair_extent, pair_radius, -1.0 if n < m else 1.0)
            total_x += push_x * share
            total_y += push_y * share
    return total_x, total_y


@inlined
def _obstacle_sums(
    r: int,
    n: int,
    xn: float,
    yn: float,
    body_extent: float,
    radius: float,
    ids: np.ndarray,
    count: int,
    listed: bool,
    w: World,
    k: Constants,
    x: Scratch,
) -> tuple[float, float]:
    """The summed pushes of obstacle carriers on movable robot ``n`` (at ``xn, yn``, its body).

    The obstacles are ``ids[r, :count]`` (ascending) when ``listed``, else ``0 .. count - 1``.
    """
    extent = body_extent + k.carrier_half
    reach = extent + radius
    ghost = w.ghost[r, n]
    total_x = 0.0
    total_y = 0.0
    for j in range(count):
        i = ids[r, j] if listed else j
        dx = xn - x.obstacle_x[r, i]
        dy = yn - x.obstacle_y[r, i]
        if abs(dx) < reach and abs(dy) < reach and x.obstacles[r, i] != ghost:
            push_x, push_y, _ = contact(dx, dy, extent, radius, 1.0)
            total_x += push_x
            total_y += push_y
    return total_x, total_y


_PATCH_SHARE: Final = 16
"""A later collision pass grids every robot anew once more than 1 in this many moved since
the last grid (a crowded warehouse); fewer are patched in (a sparse million: 7x faster)."""


@inlined
def _patched_neighbours(r: int, xn: float, yn: float, found: int, k: Constants, x: Scratch) -> int:
    """The robots near ``(xn, yn)`` where they are now, ascending in ``x.gathered[r]``.

    ``x.gathered[r, :found]`` came from the grid built at the first pass,
    where robots that moved since stand in their old cells: those are left
    out and the displaced robots the patch grid finds put in their places.
    """
    epoch = x.grid_epoch[r]
    kept = 0
    for j in range(found):
        m = x.gathered[r, j]
        if x.moved_epoch[r, m] != epoch:
            x.gathered[r, kept] = m
            kept += 1
    extra = near(
        r,
        xn,
        yn,
        k.grid_cell,
        k.grid_cell,
        x.patch_bits[r],
        x.patch_start,
        x.patch_items,
        x.near_robots,
        False,
    )
    for j in range(extra):
        m = x.displaced[r, x.near_robots[r, j]]
        position = kept
        while position > 0 and x.gathered[r, position - 1] > m:  # insertion: lists are short
            x.gathered[r, position] = x.gathered[r, position - 1]
            position -= 1
        x.gathered[r, position] = m
        kept += 1
    return kept


@inlined
def collide_range(
    r: int, lo: int, hi: int, first: bool, w: World, k: Constants, x: Scratch
) -> None:
    """A Jacobi pass's new positions of ``x.active[r, lo:hi]`` (``x.new_x[r, lo:hi]``, ``new_y``).

    Reads the positions at the pass's start (``x.x``, ``x.y``) only, so
    ranges of robots may be computed at once on several threads (each with
    its own ``x.gathered``). In the ``first`` pass of a tick with the robots'
    grid, ``active`` lists the robots bucket by bucket, and each reads its
    position from the grid's copy in that order instead of by robot id.
    """
    half = k.carrier_half
    cell = k.grid_cell
    body = max(half, k.robot_radius) * _SCREEN_MARGIN  # the widest body's extent + radius
    for j in range(lo, hi):
        n = x.active[r, j]
        in_slots = first and k.robot_grid  # the same numbers, read in memory order
        xn = x.robot_item_body[r, j, 0] if in_slots else x.x[r, n]
        yn = x.robot_item_body[r, j, 1] if in_slots else x.y[r, n]
        extent = x.robot_item_body[r, j, 2] if in_slots else x.extent[r, n]
        radius = x.robot_item_body[r, j, 3] if in_slots else x.radius[r, n]
        movable = x.robot_item_movable[r, j] if in_slots else x.movable[r, n]
        robot_x = 0.0
        robot_y = 0.0
        carrier_x = 0.0
        carrier_y = 0.0
        if movable:
            if k.robot_grid:
                found = near_within(
                    r,
                    xn,
                    yn,
                    cell,
                    k.robot_bits,
                    x.robot_start,
                    x.robot_items,
                    x.robot_item_body,
                    x.gathered,
                )
                if x.displaced_count[r] > 0:  # a later pass: robots moved since the build
                    found = _patched_neighbours(r, xn, yn, found, k, x)
                robot_x, robot_y = _robot_sums(
                    r, n, xn, yn, extent, radius, x.gathered, found, True, x
                )
            elif _others_near(r, xn, yn, (extent + radius) + body, k.robots, x.x, x.y):
                robot_x, robot_y = _robot_sums(
                    r, n, xn, yn, extent, radius, x.gathered, k.robots, False, x
                )
            reach = (extent + half) + radius
            if _beyond_obstacles(r, xn, yn, reach, x):
                pass
            elif k.obstacle_grid:
                found = near(
                    r,
                    xn,
                    yn,
                    reach,
                    cell,
                    k.carrier_bits,
                    x.obstacle_start,
                    x.obstacle_items,
                    x.gathered,
                    True,
                )
                carrier_x, carrier_y = _obstacle_sums(
                    r, n, xn, yn, extent, radius, x.gathered, found, True, w, k, x
                )
            else:
                count = x.obstacle_count[r]
                if _near_count(r, xn, yn, reach, count, x.obstacle_x, x.obstacle_y) > 0:
                    carrier_x, carrier_y = _obstacle_sums(
                        r, n, xn, yn, extent, radius, x.gathered, count, False, w, k, x
                    )
        margin = extent + radius
        new_x = minimum(maximum((xn + robot_x) + carrier_x, margin), k.arena - margin)
        new_y = minimum(maximum((yn + robot_y) + carrier_y, margin), k.arena_height - margin)
        if k.has_floor:
            row, col = cell_of(x.before_pos[r, n, 0], x.before_pos[r, n, 1], k)
            new_x, new_y = keep_off_shelves(new_x, new_y, extent, radius, row, col, k)
        x.new_x[r, j] = new_x  # by place in the list: threads write apart
        x.new_y[r, j] = new_y


@inlined
def _pass_update(r: int, count: int, first: bool, k: Constants, x: Scratch) -> int:
    """Move the robots ``x.active[r, :count]`` to their new positions; list the movers.

    (``first``: as in ``collide_range``.)

    Lists those that moved (and where they stood) in ``x.movers``; returns how many did.
    """
    movers = 0
    epoch = x.grid_epoch[r]
    for j in range(count):  # Jacobi: every new position from the pass's start
        n = x.active[r, j]
        in_slots = first and k.robot_grid
        old_x = x.robot_item_body[r, j, 0] if in_slots else x.x[r, n]
        old_y = x.robot_item_body[r, j, 1] if in_slots else x.y[r, n]
        if x.new_x[r, j] != old_x or x.new_y[r, j] != old_y:
            x.movers[r, movers] = n
            x.mover_x[r, movers] = old_x
            x.mover_y[r, movers] = old_y
            movers += 1
            x.x[r, n] = x.new_x[r, j]
            x.y[r, n] = x.new_y[r, j]
            if k.robot_grid and x.moved_epoch[r, n] != epoch:  # now away from its grid cell
                x.moved_epoch[r, n] = epoch
                x.displaced[r, x.displaced_count[r]] = n
                x.displaced_count[r] += 1
    return movers


@inlined
def _next_active(r: int, movers: int, k: Constants, x: Scratch) -> int:
    """The robots the next pass must compute: within a cell of where a mover was or is.

    A robot none of whose neighbours (within the longest reach of a pair)
    moved, and which did not move itself, would compute exactly its current
    position again: leaving it out changes nothing. Returns how many.
    """
    cell = k.grid_cell
    if x.displaced_count[r] * _PATCH_SHARE > k.robots:  # many moved: a new grid is cheaper
        grid_robots(r, k, x, True)
        x.grid_epoch[r] += 1
        x.displaced_count[r] = 0
    _patch_grid(r, k, x)
    x.stamp[r] += 1
    stamp = x.stamp[r]
    epoch = x.grid_epoch[r]
    count = 0
    for i in range(movers):
        for side in range(4):  # where it was, where it is; each in both grids
            mover = x.movers[r, i]
            px = x.mover_x[r, i] if side % 2 == 0 else x.x[r, mover]
            py = x.mover_y[r, i] if side % 2 == 0 else x.y[r, mover]
            patch = side >= 2
            found = near(
                r,
                px,
                py,
                cell,
                cell,
                x.patch_bits[r] if patch else k.robot_bits,
                x.patch_start if patch else x.robot_start,
                x.patch_items if patch else x.robot_items,
                x.near_robots,
                False,
            )
            for j in range(found):
                m = x.displaced[r, x.near_robots[r, j]] if patch else x.near_robots[r, j]
                if not patch and x.moved_epoch[r, m] == epoch:
                    continue  # in the grid where it stood: the patch has it where it is
                if x.collision_mark[r, m] != stamp:
                    x.collision_mark[r, m] = stamp
                    x.active[r, count] = m
                    count += 1
    return count


_SCREEN_MARGIN: Final = 1.000001
"""Widens a screen's reach past the rounding of the exact tests' sums of two or three terms."""


@inlined
def _near_count(
    r: int, xn: float, yn: float, reach: float, count: int, xs: np.ndarray, ys: np.ndarray
) -> int:
    """How many points ``xs[r, :count]``, ``ys`` are within ``reach`` of ``(xn, yn)`` on both axes.

    A screen without branches (SIMD) before an exact loop that has them.
    """
    hits = 0
    for i in range(count):
        hits += (abs(xn - xs[r, i]) < reach) & (abs(yn - ys[r, i]) < reach)
    return hits


@inlined
def _others_near(
    r: int, xn: float, yn: float, reach: float, count: int, xs: np.ndarray, ys: np.ndarray
) -> bool:
    """Whether a robot other than the one at ``(xn, yn)`` (itself among ``xs``) is that near."""
    return _near_count(r, xn, yn, reach, count, xs, ys) > 1


@inlined
def _near_movers(r: int, movers: int, k: Constants, x: Scratch) -> int:
    """``_next_active`` without a grid (small swarms): robots near where a mover was or is.

    Lists them ascending in ``x.active[r]``; returns how many.
    """
    reach = k.grid_cell * _SCREEN_MARGIN  # the longest reach of a pair
    count = 0
    for m in range(k.robots):
        xm = x.x[r, m]
        ym = x.y[r, m]
        for i in range(movers):
            mover = x.movers[r, i]
            if (abs(xm - x.mover_x[r, i]) < reach and abs(ym - x.mover_y[r, i]) < reach) or (
                abs(xm - x.x[r, mover]) < reach and abs(ym - x.y[r, mover]) < reach
            ):
                x.active[r, count] = m
                count += 1
                break
    return count


@inlined
def _patch_grid(r: int, k: Constants, x: Scratch) -> None:
    """Grid the robots displaced since the first pass's grid, where they are now.

    O(displaced) instead of a new grid of every robot for each later pass.
    """
    displaced = x.displaced_count[r]
    for i in range(displaced):
        n = x.displaced[r, i]
        x.displaced_x[r, i] = x.x[r, n]
        x.displaced_y[r, i] = x.y[r, n]
    bits = table_bits(displaced)
    x.patch_bits[r] = bits
    fill(
        r,
        x.displaced_x,
        x.displaced_y,
        displaced,
        k.grid_cell,
        bits,
        x.patch_start,
        x.patch_items,
        x.robot_keys,
    )


@inlined
def _collision_pass(r: int, count: int, w: World, k: Constants, x: Scratch) -> int:
    """One Jacobi pass for the robots ``x.active[r, :count]``; returns how many moved."""
    collide_range(r, 0, count, False, w, k, x)
    return _pass_update(r, count, False, k, x)


@inlined
def resolve_run(r: int, w: World, k: Constants, x: Scratch) -> None:
    """Resolve collisions of the proposed positions of run ``r`` (``motion.resolve``).

    A pass that moves nobody is a fixed point: the run's remaining passes
    would change nothing. With a grid (large swarms) a pass after the first
    computes only the robots near a robot the pass before moved.
    """
    count = resolve_begin(r, False, w, k, x)
    collide_range(r, 0, count, True, w, k, x)
    resolve_finish(r, count, w, k, x)


@inlined
def resolve_begin(r: int, split: bool, w: World, k: Constants, x: Scratch) -> int:
    """Bodies, the proposed positions as the first pass's start, its robots (all of them).

    ``split``: each robot's body and start were set as it moved (``start_body``
    in ``_tick.tick_robots``), and the caller copies the robots to their grid
    slots (``_index.copy_to_slots``) before the first pass.
    """
    if not split:
        for n in range(k.robots):
            start_body(r, n, w, k, x)
    if k.robot_grid:
        grid_robots(r, k, x, not split)
        x.grid_epoch[r] += 1  # nobody displaced from this grid yet
        x.displaced_count[r] = 0
        for j in range(k.robots):  # bucket by bucket: neighbours' buckets stay in cache
            x.active[r, j] = x.robot_items[r, j]
    else:
        for n in range(k.robots):
            x.active[r, n] = n
    return k.robots


@inlined
def resolve_finish(r: int, count: int, w: World, k: Constants, x: Scratch) -> None:
    """After the first pass's ``collide_range``: its update, the other passes, the outcome."""
    resolve_passes(r, count, w, k, x)
    settle_positions(r, 0, k.robots, w, k, x)
    drop_ghosts(r, 0, k.robots, w, k, x)


@inlined
def resolve_passes(r: int, count: int, w: World, k: Constants, x: Scratch) -> None:
    """The first pass's update and the other passes (one thread: their lists are ordered)."""
    movers = _pass_update(r, count, True, k, x)
    for _ in range(1, k.collision_iterations):
        if movers == 0:
            break
        count = _next_active(r, movers, k, x) if k.robot_grid else _near_movers(r, movers, k, x)
        movers = _collision_pass(r, count, w, k, x)


@inlined
def settle_positions(r: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """Robots ``lo .. hi - 1`` where the passes left them, their contacts, their loads with them.

    Each writes its own entries and its own load's (a carrier has one
    carrier), so ranges may run at once on several threads.
    """
    for n in range(lo, hi):
        w.contact[r, n, 0] = x.x[r, n] - x.proposed[r, n, 0]
        w.contact[r, n, 1] = x.y[r, n] - x.proposed[r, n, 1]
        w.robot_pos[r, n, 0] = x.x[r, n]
        w.robot_pos[r, n, 1] = x.y[r, n]
    for n in range(lo, hi):
        if x.extent[r, n] > 0:  # loaded: its carrier goes with it
            target = w.target[r, n]
            w.carrier_pos[r, target, 0] = x.x[r, n]
            w.carrier_pos[r, target, 1] = x.y[r, n]


@inlined
def drop_ghosts(r: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """Robots ``lo .. hi - 1`` clear of the carrier they drove into overlap it no longer.

    Reads every carrier where ``settle_positions`` left it: after all its ranges.
    """
    for n in range(lo, hi):
        ghost = w.ghost[r, n]
        if ghost < 0:
            continue
        dx = w.robot_pos[r, n, 0] - w.carrier_pos[r, ghost, 0]
        dy = w.robot_pos[r, n, 1] - w.carrier_pos[r, ghost, 1]
        _, _, depth = contact(dx, dy, x.extent[r, n] + k.carrier_half, x.radius[r, n], 1.0)
        mode = w.mode[r, n]
        if depth <= 0 and mode not in (Mode.DOCK, Mode.CENTRE):
            w.ghost[r, n] = -1
