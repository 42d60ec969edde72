"""Initial scenes, compiled: ``model/scene.py``'s draws from each run's scene stream, in its order.

The same rejection sampling, the same numbers from the same generator, the
same IEEE operations, so the scenes are the reference's bit for bit; only
the test of a candidate against the bodies already placed looks at the
nearby ones alone (a uniform grid of cells at least as wide as the
clearance), which gives the same answer as testing them all and keeps large
swarms linear.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from swarmtag.sim.fast._jit import counted, jit
from swarmtag.sim.fast._pcg import standard_normal, states_of, uniform
from swarmtag.sim.model.params import Params
from swarmtag.sim.model.randomness import Stream, stream, unit_vectors
from swarmtag.sim.model.scene import PLACE_ATTEMPTS, PLACE_RESTARTS, sample_scene
from swarmtag.sim.model.state import Scene
from swarmtag.sim.world.urgency import initial_urgency
from swarmtag.tag import TagStatus

__all__ = ["TOO_CROWDED_CARRIERS", "TOO_CROWDED_ROBOTS", "sample_scenes", "seeded_scenes"]

TOO_CROWDED_CARRIERS = 1
"""``sample_scenes`` failure: the carriers could not be placed at random (the grid takes over)."""
TOO_CROWDED_ROBOTS = 2
"""``sample_scenes`` failure: the robots could not be placed at random (the grid takes over)."""


@jit
def _clear(
    px: float,
    py: float,
    placed: np.ndarray,
    heads: np.ndarray,
    chain: np.ndarray,
    cell: float,
    columns: int,
    rows: int,
    gap: float,
    chebyshev: bool,
) -> bool:
    """Whether ``(px, py)`` keeps ``gap`` from every placed point (Chebyshev or Euclidean)."""
    cx = min(max(int(px / cell), 0), columns - 1)
    cy = min(max(int(py / cell), 0), rows - 1)
    for gx in range(max(cx - 1, 0), min(cx + 2, columns)):
        for gy in range(max(cy - 1, 0), min(cy + 2, rows)):
            k = heads[gx * rows + gy]
            while k >= 0:
                dx = placed[k, 0] - px
                dy = placed[k, 1] - py
                if chebyshev:
                    if not max(abs(dx), abs(dy)) >= gap:
                        return False
                elif not math.sqrt(dx * dx + dy * dy) >= gap:
                    return False
                k = chain[k]
    return True


@jit
def _place(
    states: np.ndarray,
    r: int,
    out: np.ndarray,
    low_x: float,
    low_y: float,
    high_x: float,
    high_y: float,
    gap: float,
    chebyshev: bool,
    heads: np.ndarray,
    chain: np.ndarray,
    cell: float,
    columns: int,
    rows: int,
) -> bool:
    """``scene._place``: points one after another by rejection; False when it gives up.

    Draws from run ``r``'s generator state ``states[r]`` (``_pcg``), advanced in place.
    """
    high, low, inc_high, inc_low = states[r, 0], states[r, 1], states[r, 2], states[r, 3]
    span_x = high_x - low_x
    span_y = high_y - low_y
    count = out.shape[0]
    for _ in range(PLACE_RESTARTS):
        heads[:] = -1
        complete = True
        for k in range(count):
            accepted = False
            for _ in range(PLACE_ATTEMPTS):
                unit_x, high, low = uniform(high, low, inc_high, inc_low)
                unit_y, high, low = uniform(high, low, inc_high, inc_low)
                px = low_x + unit_x * span_x
                py = low_y + unit_y * span_y
                if _clear(px, py, out, heads, chain, cell, columns, rows, gap, chebyshev):
                    out[k, 0] = px
                    out[k, 1] = py
                    cx = min(max(int(px / cell), 0), columns - 1)
                    cy = min(max(int(py / cell), 0), rows - 1)
                    chain[k] = heads[cx * rows + cy]
                    heads[cx * rows + cy] = k
                    accepted = True
                    break
            if not accepted:
                complete = False
                break
        if complete:
            states[r, 0], states[r, 1] = high, low
            return True
    states[r, 0], states[r, 1] = high, low
    return False


@counted
def _grid(count: int, gap: float, high_x: float, high_y: float) -> tuple[np.ndarray, float, int]:
    """Cells for ``count`` points up to ``(high_x, high_y)``: at least ``gap`` wide, O(count)."""
    cell = max(gap, math.sqrt(max(high_x, 1e-9) * max(high_y, 1e-9) / (4.0 * count + 1.0)), 1e-9)
    columns = int(high_x / cell) + 1
    rows = int(high_y / cell) + 1
    return np.empty(columns * rows, dtype=np.int64), cell, rows


@counted
def sample_scenes(
    states: np.ndarray,
    layout: np.ndarray,
    carrier_pos: np.ndarray,
    urgency_draw: np.ndarray,
    robot_pos: np.ndarray,
    heading_draw: np.ndarray,
    speed_draw: np.ndarray,
    phase_draw: np.ndarray,
    failure: np.ndarray,
) -> None:
    """Every run's raw scene draws, in ``scene.sample_scene``'s order, into the arrays.

    ``layout`` is ``(carrier low x, low y, high x, high y, pitch, robot low x,
    low y, high x, high y, diameter)``; ``failure[r]`` is set to
    ``TOO_CROWDED_CARRIERS``/``TOO_CROWDED_ROBOTS`` where a placement gives up.
    ``states[r]`` is run ``r``'s scene generator (``_pcg.states_of``), advanced in
    place: numba's typed list of numpy generators compiled its methods in every
    process (0.8 s a start), and the same numbers come from the state words.
    """
    carriers = carrier_pos.shape[1]
    robots = robot_pos.shape[1]
    c_heads, c_cell, c_rows = _grid(carriers, layout[4], layout[2], layout[3])
    r_heads, r_cell, r_rows = _grid(robots, layout[9], layout[7], layout[8])
    c_chain = np.empty(carriers, dtype=np.int64)
    r_chain = np.empty(robots, dtype=np.int64)
    c_columns = c_heads.shape[0] // c_rows
    r_columns = r_heads.shape[0] // r_rows
    for r in range(carrier_pos.shape[0]):
        if not _place(
            states,
            r,
            carrier_pos[r],
            layout[0],
            layout[1],
            layout[2],
            layout[3],
            layout[4],
            True,
            c_heads,
            c_chain,
            c_cell,
            c_columns,
            c_rows,
        ):
            failure[r] = TOO_CROWDED_CARRIERS
            continue
        high, low, inc_high, inc_low = states[r, 0], states[r, 1], states[r, 2], states[r, 3]
        for c in range(carriers):
            urgency_draw[r, c], high, low = uniform(high, low, inc_high, inc_low)
        states[r, 0], states[r, 1] = high, low
        if not _place(
            states,
            r,
            robot_pos[r],
            layout[5],
            layout[6],
            layout[7],
            layout[8],
            layout[9],
            False,
            r_heads,
            r_chain,
            r_cell,
            r_columns,
            r_rows,
        ):
            failure[r] = TOO_CROWDED_ROBOTS
            continue
        high, low = states[r, 0], states[r, 1]
        for n in range(robots):
            heading_draw[r, n, 0], high, low = standard_normal(high, low, inc_high, inc_low)
            heading_draw[r, n, 1], high, low = standard_normal(high, low, inc_high, inc_low)
        for n in range(robots):
            speed_draw[r, n], high, low = standard_normal(high, low, inc_high, inc_low)
        for c in range(carriers):
            phase_draw[r, c], high, low = uniform(high, low, inc_high, inc_low)
        states[r, 0], states[r, 1] = high, low


def seeded_scenes(params: Params, *, seed: int, run_ids: Sequence[int]) -> list[Scene]:
    """The initial scenes of global runs ``run_ids`` of ``seed``, as ``scene.sample_scene``'s."""
    runs, robots, carriers = len(run_ids), params.robots, params.carriers
    half, radius, arena = params.carrier_half, params.robot_radius, params.arena
    layout = np.array(
        [
            half,
            half,
            params.pickup_right - half,
            arena - half,
            2 * half + params.carrier_spacing,
            params.dropoff_left + radius,
            radius,
            arena - radius,
            arena - radius,
            2 * radius,
        ]
    )
    carrier_pos = np.zeros((runs, carriers, 2))
    urgency_draw = np.zeros((runs, carriers))
    robot_pos = np.zeros((runs, robots, 2))
    heading_draw = np.zeros((runs, robots, 2))
    speed_draw = np.zeros((runs, robots))
    phase_draw = np.zeros((runs, carriers))
    failure = np.zeros(runs, dtype=np.int64)
    states = states_of([stream(seed, int(run), Stream.SCENE) for run in run_ids])
    sample_scenes(
        states,
        layout,
        carrier_pos,
        urgency_draw,
        robot_pos,
        heading_draw,
        speed_draw,
        phase_draw,
        failure,
    )
    scenes = []
    awaiting = np.full(carriers, TagStatus.AWAITING_PICKUP, dtype=np.int8)
    for r in range(runs):
        if failure[r]:  # too crowded for random placement: the reference's grid, same draws
            scenes.append(sample_scene(params, seed=seed, run=int(run_ids[r])))
            continue
        urgency = initial_urgency(
            urgency_draw[r],
            growing=params.growing,
            horizon=params.horizon,
            horizon_s=params.scenario.urgency.static_horizon,
        )
        scenes.append(
            Scene(
                robot_pos=robot_pos[r],
                carrier_pos=carrier_pos[r],
                urgency0=urgency.urgency0,
                order_time=urgency.order_time,
                w0=urgency.w0,
                heading=unit_vectors(heading_draw[r]),
                speed_factor=np.clip(1.0 + params.speed_variation * speed_draw[r], 0.5, 1.5),
                status=awaiting.copy(),
                advert_phase=phase_draw[r],
            )
        )
    return scenes
