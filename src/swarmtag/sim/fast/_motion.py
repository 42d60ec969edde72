"""Move, compiled: ``sim/world/motion.py``'s proposals for one run (the collisions: ``_collide``).

``move_robots`` proposes each robot's position and turns its heading;
``start_body`` sets its body for the collision passes.
"""

from __future__ import annotations

import math

from swarmtag.sim.fast._decide import is_loaded
from swarmtag.sim.fast._floor import waypoint_of
from swarmtag.sim.fast._geometry import FACE_X, FACE_Y, step_towards, turn_towards
from swarmtag.sim.fast._jit import inlined
from swarmtag.sim.fast._layout import Constants, World
from swarmtag.sim.fast._scratch import Scratch
from swarmtag.sim.model.state import Mode

__all__ = ["move_robots", "start_body"]


@inlined
def move_robots(r: int, lo: int, hi: int, w: World, k: Constants, x: Scratch) -> None:
    """Proposed positions, turned headings, sidesteps counted down (``motion.move``)."""
    for n in range(lo, hi):
        mode = w.mode[r, n]
        px = w.robot_pos[r, n, 0]
        py = w.robot_pos[r, n, 1]
        speed = w.speed[r, n]
        face = max(w.face[r, n], 0)
        target = max(w.target[r, n], 0)
        nx = FACE_X[face]
        ny = FACE_Y[face]
        if k.has_floor and mode == Mode.TRANSPORT:  # the next waypoint of the path to its area
            goal_x, goal_y = waypoint_of(px, py, w.destination[r, target], k)
            w.goal[r, n, 0] = goal_x
            w.goal[r, n, 1] = goal_y
        looking = k.look_ticks > 0 and mode == Mode.WALK and w.look[r, n] >= 0
        if looking:  # stands and turns counter-clockwise
            qx = px
            qy = py
        elif mode == Mode.WALK:
            qx = px + w.walk[r, n, 0] * speed
            qy = py + w.walk[r, n, 1] * speed
        elif mode == Mode.TRANSPORT and w.sidestep[r, n] > 0:
            qx = px + w.sidestep_dir[r, n, 0] * speed
            qy = py + w.sidestep_dir[r, n, 1] * speed
            w.sidestep[r, n] -= 1
        elif mode == Mode.PREDOCK:
            cx = w.carrier_pos[r, target, 0]
            cy = w.carrier_pos[r, target, 1]
            qx, qy = step_towards(
                px, py, cx + nx * k.predock_offset, cy + ny * k.predock_offset, speed
            )
        elif mode == Mode.DOCK:
            qx, qy = step_towards(
                px, py, w.carrier_pos[r, target, 0], w.carrier_pos[r, target, 1], speed
            )
        elif mode == Mode.TRANSPORT:
            qx, qy = step_towards(px, py, w.goal[r, n, 0], w.goal[r, n, 1], speed)
        else:
            qx = px
            qy = py
        x.proposed[r, n, 0] = qx
        x.proposed[r, n, 1] = qy

        _turn_heading(r, n, mode, looking, qx - px, qy - py, face, w, k)


@inlined
def _turn_heading(
    r: int,
    n: int,
    mode: int,
    looking: bool,
    tx: float,
    ty: float,
    face: int,
    w: World,
    k: Constants,
) -> None:
    """Turn robot ``n``'s heading by a turn step towards where it faces (``motion.move``).

    ``tx, ty``: its proposed move; ``face``: the face it approaches (PREDOCK).
    """
    distance = math.sqrt(tx * tx + ty * ty)
    if mode == Mode.PREDOCK:
        fx = -FACE_X[face]
        fy = -FACE_Y[face]
    elif looking:
        fx = -w.heading[r, n, 1]
        fy = w.heading[r, n, 0]
    elif mode == Mode.WALK:
        fx = w.walk[r, n, 0]
        fy = w.walk[r, n, 1]
    else:
        safe = distance if distance > 0 else 1.0
        fx = tx / safe
        fy = ty / safe
    if mode in (Mode.PREDOCK, Mode.WALK) or (mode == Mode.TRANSPORT and distance > 0):
        hx, hy = turn_towards(
            w.heading[r, n, 0], w.heading[r, n, 1], fx, fy, k.turn_cos, k.turn_sin
        )
        w.heading[r, n, 0] = hx
        w.heading[r, n, 1] = hy


@inlined
def start_body(r: int, n: int, w: World, k: Constants, x: Scratch) -> None:
    """Robot ``n``'s rounded box, whether it can be pushed (``motion._bodies``) and its start.

    The collisions' start is the proposed position; robot ``n``'s mode,
    target and proposal are final once it has moved.
    """
    mode = w.mode[r, n]
    loaded = is_loaded(mode, w.target[r, n])
    x.extent[r, n] = k.carrier_half if loaded else 0.0
    x.radius[r, n] = 0.0 if loaded else k.robot_radius
    x.movable[r, n] = not (mode in (Mode.CENTRE, Mode.LIFT) or mode >= Mode.RELEASE)
    x.x[r, n] = x.proposed[r, n, 0]
    x.y[r, n] = x.proposed[r, n, 1]
