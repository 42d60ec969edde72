"""The broad phase (``swarmtag.sim.world.broad_phase``): grids find every pair the exact tests accept.

Every pairwise test of the reference kernel has a dense path (all pairs at
once) and a grid path; ``GRID_FROM`` picks one by size. These tests force
each path on random states (many robots and carriers, robots at and beyond
the walls, touching, coinciding and overlapping bodies, loaded robots,
ghosts, delivered and carried carriers) and require the very same numbers
(``np.array_equal``, not closeness). The collision pass is also compared
with the dense code as it was before the broad phase (``_pass_before``).
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import replace

import numpy as np
import pytest

from swarmtag.policy import Proximity, Urgency
from swarmtag.sim import (
    Arena,
    Camera,
    Mode,
    Motion,
    Scenario,
    Scene,
    WorldState,
    initial_state,
    make_params,
    simulate,
)
from swarmtag.sim.builtin.docking import _dock_free
from swarmtag.sim.model.geometry import contact_xy, segment_crosses_box, segment_near_point
from swarmtag.sim.world import broad_phase, motion
from swarmtag.sim.world.predock import free_faces, taken_faces
from swarmtag.sim.world.sensing import line_of_sight
from tests.sim.fast.helpers import assert_same

SEEDS = range(12)


@contextmanager
def _path(name: str) -> Iterator[None]:
    """Force every pairwise test onto the ``dense`` or the ``grid`` path."""
    saved = dict(broad_phase.GRID_FROM)
    force = (0, 0) if name == "grid" else (10**9, 10**18)
    for key in saved:
        broad_phase.GRID_FROM[key] = force
    try:
        yield
    finally:
        broad_phase.GRID_FROM.update(saved)


def _both(compute):
    """``compute()`` on the dense path and on the grid path."""
    with _path("dense"):
        dense = compute()
    with _path("grid"):
        grid = compute()
    return dense, grid


def _params(robots: int = 60, carriers: int = 32, size: float = 6.0):
    scenario = Scenario(
        robots=robots,
        carriers=carriers,
        perception="split",
        arena=Arena(size=size, pickup_width=2.5, dropoff_width=2.5),
        camera=Camera(range=3.6, occlusion="carriers+robots"),
        motion=Motion(avoid_taken_faces=True),
    )
    return make_params(scenario, Proximity())


def _random_state(seed: int, params, runs: int = 3) -> WorldState:
    """A crowded, awkward state: every body kind, at walls, touching, coinciding, overlapping."""
    rng = np.random.default_rng(seed)
    n, c, size = params.robots, params.carriers, params.arena
    h, r = params.carrier_half, params.robot_radius
    carriers = rng.uniform(0.0, size, (runs, c, 2))
    carriers[:, 0] = (h, h)  # in a corner
    carriers[:, 1] = carriers[:, 2] + (params.predock_offset + h + r, 0.0)  # a point just clear
    robots = rng.uniform(-0.1, size + 0.1, (runs, n, 2))  # some beyond the walls
    near = rng.integers(0, c, (runs, n // 3))
    robots[:, : n // 3] = carriers[np.arange(runs)[:, None], near] + rng.uniform(
        -0.4, 0.4, (runs, n // 3, 2)
    )
    crowd = slice(n // 3, n // 2)
    robots[:, crowd] = robots[:, : n // 2 - n // 3] + rng.uniform(-0.3, 0.3, robots[:, crowd].shape)
    robots[:, n // 2] = robots[:, 0]  # coinciding
    robots[:, n // 2 + 1] = robots[:, 1] + (2 * r, 0.0)  # exactly one diameter apart
    robots[:, n // 2 + 2] = robots[:, 2] + (np.nextafter(2 * r, 0.0), 0.0)  # just touching
    robots[:, n // 2 + 3] = (r, size - r)  # on the walls' margin
    robots[:, n // 2 + 4] = carriers[:, 3]  # on a carrier's centre
    mode = rng.integers(0, len(Mode), (runs, n)).astype(np.int8)
    target = np.where(rng.random((runs, n)) < 0.7, rng.integers(0, c, (runs, n)), -1)
    carried_by = np.full((runs, c), -1, dtype=np.int64)
    holding = np.isin(mode, (Mode.LIFT, Mode.TRANSPORT, Mode.RELEASE, Mode.BROKEN))
    for run in range(runs):
        free = list(rng.permutation(c))
        for robot in np.flatnonzero(holding[run]):
            if free and (mode[run, robot] != Mode.BROKEN or rng.random() < 0.5):
                carrier = free.pop()
                target[run, robot] = carrier
                carried_by[run, carrier] = robot
                carriers[run, carrier] = robots[run, robot]
            elif mode[run, robot] != Mode.BROKEN:
                mode[run, robot] = Mode.WALK
                target[run, robot] = -1
            else:
                target[run, robot] = -1
    present = (rng.random((runs, c)) < 0.85) | (carried_by >= 0)
    ghost = np.where(rng.random((runs, n)) < 0.3, rng.integers(0, c, (runs, n)), -1)
    scenes = [Scene.build(robots=robots[k], carriers=carriers[k]) for k in range(runs)]
    state = initial_state(params, scenes, range(runs))
    return replace(
        state,
        robot_pos=robots,
        carrier_pos=carriers,
        mode=mode,
        target=target,
        face=np.where(target >= 0, rng.integers(0, 4, (runs, n)), -1),
        ghost=ghost,
        present=present,
        carried_by=carried_by,
    )


def _pass_before(x, y, s: WorldState, params):
    """One collision pass as the dense code computed it before the broad phase."""
    robots = s.mode.shape[1]
    extent, radius = motion.body_shape(s.mode, s.target, params)
    movable = ~np.isin(s.mode, (Mode.CENTRE, Mode.LIFT, Mode.RELEASE, Mode.BROKEN))
    share = np.where(
        movable[:, :, None] & movable[:, None, :], 0.5, np.where(movable[:, :, None], 1.0, 0.0)
    )
    share[:, np.arange(robots), np.arange(robots)] = 0.0
    index = np.arange(robots)
    tie = np.where(index[:, None] < index[None, :], -1.0, 1.0)
    pair_extent = extent[:, :, None] + extent[:, None, :]
    pair_radius = radius[:, :, None] + radius[:, None, :]
    carriers = np.arange(s.carrier_pos.shape[1])
    obstacle = (s.present & (s.carried_by < 0))[:, None, :] & (carriers != s.ghost[..., None])
    obstacle &= movable[..., None]
    carrier_extent = np.broadcast_to(extent[..., None] + params.carrier_half, obstacle.shape)
    carrier_radius = np.broadcast_to(radius[..., None], obstacle.shape)

    dx = x[:, :, None] - x[:, None, :]
    dy = y[:, :, None] - y[:, None, :]
    reach = pair_extent + pair_radius
    runs, ids, others = np.nonzero((np.abs(dx) < reach) & (np.abs(dy) < reach) & (share > 0))
    push_x, push_y, _ = contact_xy(
        dx[runs, ids, others],
        dy[runs, ids, others],
        pair_extent[runs, ids, others],
        pair_radius[runs, ids, others],
        tie[ids, others],
    )
    weight = share[runs, ids, others]
    robot_x, robot_y = motion._summed(runs, ids, x.shape, push_x * weight, push_y * weight)
    cx = x[:, :, None] - s.carrier_pos[:, None, :, 0]
    cy = y[:, :, None] - s.carrier_pos[:, None, :, 1]
    reach = carrier_extent + carrier_radius
    rows, ids, near = np.nonzero((np.abs(cx) < reach) & (np.abs(cy) < reach) & obstacle)
    push_x, push_y, _ = contact_xy(
        cx[rows, ids, near],
        cy[rows, ids, near],
        carrier_extent[rows, ids, near],
        carrier_radius[rows, ids, near],
        1.0,
    )
    carrier_x, carrier_y = motion._summed(rows, ids, x.shape, push_x, push_y)
    margin = extent + radius
    new_x = np.minimum(np.maximum((x + robot_x) + carrier_x, margin), params.arena - margin)
    new_y = np.minimum(np.maximum((y + robot_y) + carrier_y, margin), params.arena - margin)
    return new_x, new_y, bool(runs.size or rows.size)


# --- the collision pass and resolve ---------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_a_collision_pass_is_the_same_on_both_paths_and_as_before(seed):
    params = _params()
    s = _random_state(seed, params)
    x, y = s.robot_pos[..., 0], s.robot_pos[..., 1]
    dense, grid = _both(lambda: motion._collision_pass(x, y, motion._bodies(s, params)))
    before = _pass_before(x, y, s, params)
    assert before[2]  # something touches
    for ours in (dense, grid):
        assert np.array_equal(ours[0], before[0])
        assert np.array_equal(ours[1], before[1])


@pytest.mark.parametrize("seed", SEEDS)
def test_resolving_collisions_gives_the_same_positions_on_both_paths(seed):
    params = _params()
    s = _random_state(seed, params)
    proposed = s.robot_pos + np.random.default_rng(seed).uniform(-0.06, 0.06, s.robot_pos.shape)

    def resolved() -> WorldState:
        out = s.copy()
        motion.resolve(out, proposed, params)
        return out

    dense, grid = _both(resolved)
    for name in ("robot_pos", "contact", "carrier_pos", "ghost"):
        assert np.array_equal(getattr(dense, name), getattr(grid, name)), name
    assert not np.array_equal(dense.contact, np.zeros_like(dense.contact))


# --- predock faces, line of sight, smallest ids ---------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_free_faces_are_the_same_on_both_paths(seed):
    params = _params()
    s = _random_state(seed, params)
    obstacle = s.present & (s.carried_by < 0)
    dense, grid = _both(lambda: free_faces(s.carrier_pos, obstacle, params))
    assert np.array_equal(dense, grid)
    assert dense.any()
    assert not dense.all()


@pytest.mark.parametrize("seed", SEEDS)
def test_taken_faces_are_the_same_on_both_paths_for_the_robots_asking(seed):
    params = _params()
    s = _random_state(seed, params)
    rng = np.random.default_rng(seed)
    centre = s.carrier_pos[np.arange(s.runs)[:, None], np.maximum(s.target, 0)]
    asking = rng.random(s.mode.shape) < 0.5

    def taken(who):
        return taken_faces(
            s.robot_pos, centre, params.predock_offset, body=0.25, sight=3.6, asking=who
        )

    everyone_dense, everyone_grid = _both(lambda: taken(None))
    asked_dense, asked_grid = _both(lambda: taken(asking))
    assert np.array_equal(everyone_dense, everyone_grid)
    assert everyone_dense.any()
    assert np.array_equal(asked_dense, asked_grid)
    assert np.array_equal(asked_dense, everyone_dense & asking[..., None])


@pytest.mark.parametrize("seed", SEEDS)
@pytest.mark.parametrize("occlusion", [1, 2])
def test_lines_of_sight_are_the_same_on_both_paths(seed, occlusion):
    params = replace(_params(), occlusion=occlusion)
    s = _random_state(seed, params)
    visible = np.random.default_rng(seed).random((s.runs, params.robots, params.carriers)) < 0.4
    dense, grid = _both(lambda: line_of_sight(s, visible, params))
    assert np.array_equal(dense, grid)
    assert (dense != visible).any()


@pytest.mark.parametrize("seed", SEEDS)
def test_the_smallest_id_wins_as_by_comparing_every_pair(seed):
    rng = np.random.default_rng(seed)
    claim = rng.random((5, 40)) < 0.5
    key = np.where(claim, rng.integers(0, 6, (5, 40)), -1)
    index = np.arange(40)
    rival = (
        claim[:, None, :] & (key[:, None, :] == key[:, :, None]) & (index[None, :] < index[:, None])
    ).any(axis=-1)
    assert np.array_equal(broad_phase.first_claims(claim, key, 6), claim & ~rival)


def test_only_the_smallest_id_arriving_drives_in_under_a_free_carrier():
    params = _params(robots=5, carriers=3)
    scene = Scene.build(robots=[(4.0, y) for y in range(1, 6)], carriers=[(1, 1), (1, 3), (1, 5)])
    s = initial_state(params, [scene], [0])
    s = replace(
        s,
        mode=np.array([[Mode.DOCK, 0, 0, 0, 0]], dtype=np.int8),
        target=np.array([[0, 1, 0, 1, 2]]),
    )
    arriving = np.array([[False, True, True, True, True]])
    # robot 2: carrier 0 has a robot under it; robot 3: robot 1 goes first
    assert _dock_free(s, arriving).tolist() == [[False, True, False, False, True]]


# --- the candidates themselves ----------------------------------------------------------------


@pytest.mark.parametrize("offset", [0.0, 1e6])
def test_near_points_include_every_pair_within_reach_even_at_its_edge(offset):
    rng = np.random.default_rng(1)
    reach = 0.355
    items = rng.uniform(0, 5, (2, 300, 2)) + offset
    edge = np.nextafter(reach, 0.0)
    sides = np.array([(edge, 0.0), (-edge, 0.0), (0.0, edge), (0.0, -edge), (reach, 0.0)])
    queries = np.concatenate(
        [items + side for side in sides] + [items + rng.uniform(-0.4, 0.4, items.shape)], axis=1
    )
    queries[:, 0] = (np.nan, 1.0)  # never near anything
    queries[:, 1] = items[:, 3] + (1e3, 0.0)  # far beyond the grid
    valid = rng.random((2, 300)) < 0.9
    grid = broad_phase.build_grid(items[..., 0], items[..., 1], valid, reach)
    asking = rng.random(queries.shape[:2]) < 0.9
    runs, asked, found = broad_phase.near_points(
        grid, queries[..., 0], queries[..., 1], asking, reach
    )
    got = set(zip(runs.tolist(), asked.tolist(), found.tolist(), strict=True))
    assert len(got) == runs.size  # no pair twice
    dx = queries[:, :, None, 0] - items[:, None, :, 0]
    dy = queries[:, :, None, 1] - items[:, None, :, 1]
    near = (np.abs(dx) < reach) & (np.abs(dy) < reach) & valid[:, None, :] & asking[..., None]
    wanted = set(zip(*(index.tolist() for index in np.nonzero(near)), strict=True))
    assert len(wanted) > 2000
    assert wanted <= got
    assert {pair for pair in got if not (valid[pair[0], pair[2]] and asking[pair[:2]])} == set()


def test_near_segments_include_every_box_crossed_and_every_point_passed_near():
    rng = np.random.default_rng(2)
    points = rng.uniform(0, 8, (2, 150, 2))
    runs = rng.integers(0, 2, 400)
    start = rng.uniform(0, 8, (400, 2))
    end = start + rng.uniform(-3, 3, (400, 2))
    end[:20] = start[:20]  # points, not segments
    everyone = np.ones((2, 150), dtype=bool)
    for reach, test in ((0.1775, segment_crosses_box), (0.125, segment_near_point)):
        grid = broad_phase.build_grid(points[..., 0], points[..., 1], everyone, 0.75)
        line, found = broad_phase.near_segments(grid, runs, start, end, reach)
        got = set(zip(line.tolist(), found.tolist(), strict=True))
        assert len(got) == line.size
        hit = test(start[:, None, :], end[:, None, :], points[runs], reach)
        wanted = set(zip(*(index.tolist() for index in np.nonzero(hit)), strict=True))
        assert wanted
        assert wanted <= got
        assert len(got) < 0.2 * 400 * 150  # a broad phase, not all pairs


def test_candidate_pairs_sort_into_the_dense_mask_order():
    rng = np.random.default_rng(3)
    mask = rng.random((3, 7, 5)) < 0.3
    runs, rows, cols = np.nonzero(mask)
    shuffled = rng.permutation(runs.size)
    again = broad_phase.sorted_pairs(runs[shuffled], rows[shuffled], cols[shuffled], mask.shape)
    for ours, theirs in zip(again, (runs, rows, cols), strict=True):
        assert np.array_equal(ours, theirs)


def test_small_swarms_stay_dense_and_large_ones_take_the_grid():
    assert not broad_phase.grid_pays("robots", 1000 * 3, 3)  # 3/7, 1000 runs
    assert not broad_phase.grid_pays("robots", 100 * 20, 20)  # 20/40, 100 runs
    assert broad_phase.grid_pays("obstacles", 100 * 20, 40)
    assert broad_phase.grid_pays("robots", 4 * 200, 200)  # 200/256, 4 runs
    assert broad_phase.grid_pays("robots", 2000, 2000)


# --- whole runs ----------------------------------------------------------------------------


def test_crowded_runs_give_the_same_event_logs_and_states_on_both_paths():
    scenario = Scenario(
        robots=30,
        carriers=20,
        ticks=400,
        perception="split",
        arena=Arena(size=5.0, pickup_width=2.5, dropoff_width=1.5),
        camera=Camera(range=3.6, occlusion="carriers+robots", memory=1.0),
        motion=Motion(avoid_taken_faces=True),
    )
    dense, grid = _both(
        lambda: simulate(scenario, Urgency(alpha=0.7), seed=4, runs=2, backend="reference")
    )
    assert dense.delivered.sum() > 0
    assert_same(dense, grid)
