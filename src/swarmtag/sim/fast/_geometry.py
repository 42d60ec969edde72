"""Scalar geometry of the compiled kernel: ``sim/model/geometry.py`` one operation at a time.

Every function here performs the same IEEE operations, in the same order, as
its batched numpy twin in ``swarmtag.sim.model.geometry`` (named in each docstring),
so that the compiled kernel's positions are the reference kernel's bit for
bit. ``maximum``/``minimum`` are numpy's ``np.maximum``/``np.minimum`` for
numbers that are not NaN (the kernel never makes a NaN position).
"""

from __future__ import annotations

import math
from typing import Final

import numpy as np

from swarmtag.sim.fast._jit import jit

__all__ = [
    "FACE_X",
    "FACE_Y",
    "away_from",
    "bearing_factor",
    "contact",
    "maximum",
    "minimum",
    "norm",
    "segment_crosses_box",
    "segment_near_point",
    "step_towards",
    "turn_towards",
    "unit_vector",
]

FACE_X: Final = np.array([1.0, 0.0, -1.0, 0.0])
"""x of the outward face normals, east, north, west, south (``geometry.FACE_NORMALS``)."""
FACE_Y: Final = np.array([0.0, 1.0, 0.0, -1.0])
"""y of the outward face normals."""


@jit
def maximum(a: float, b: float) -> float:
    """``np.maximum(a, b)`` for numbers that are not NaN."""
    return a if a >= b else b  # noqa: FURB136 - numpy's rule written out, not Python's max


@jit
def minimum(a: float, b: float) -> float:
    """``np.minimum(a, b)`` for numbers that are not NaN."""
    return a if a <= b else b  # noqa: FURB136 - numpy's rule written out, not Python's min


@jit
def norm(x: float, y: float) -> float:
    """``geometry.length``: ``sqrt(x*x + y*y)``."""
    return math.sqrt(x * x + y * y)


@jit
def bearing_factor(
    ox: float,
    oy: float,
    distance: float,
    hx: float,
    hy: float,
    cosines: np.ndarray,
    factors: np.ndarray,
) -> float:
    """``geometry.bearing_factor`` for one offset: linear in the bearing's cosine."""
    cos = 1.0
    if distance > 0:
        cos = (ox * hx + oy * hy) / distance
    cos = minimum(maximum(cos, -1.0), 1.0)
    i = 0
    for j in range(1, cosines.size - 1):
        if cosines[j] > cos:
            i += 1
    p0 = cosines[i]
    p1 = cosines[i + 1]
    f0 = factors[i]
    f1 = factors[i + 1]
    factor: float = f0 + (f1 - f0) * ((p0 - cos) / (p0 - p1))
    return factor


@jit
def step_towards(px: float, py: float, gx: float, gy: float, step: float) -> tuple[float, float]:
    """``geometry.step_towards`` for one body."""
    ox = gx - px
    oy = gy - py
    distance = math.sqrt(ox * ox + oy * oy)
    scale = step / distance if distance > 0 else 0.0
    if distance <= step:
        return gx, gy
    return px + ox * scale, py + oy * scale


@jit
def turn_towards(
    hx: float, hy: float, tx: float, ty: float, cos_step: float, sin_step: float
) -> tuple[float, float]:
    """``geometry.turn_towards`` for one heading."""
    dot = hx * tx + hy * ty
    cross = hx * ty - hy * tx
    sin = -sin_step if cross < 0 else sin_step
    rx = hx * cos_step - hy * sin
    ry = hx * sin + hy * cos_step
    length = math.sqrt(rx * rx + ry * ry)
    if dot >= cos_step:
        return tx, ty
    return rx / length, ry / length


@jit
def contact(
    dx: float, dy: float, extent: float, radius: float, tie: float
) -> tuple[float, float, float]:
    """``geometry.contact_xy`` for one pair: push x, push y and depth."""
    nearest_x = minimum(maximum(dx, -extent), extent)
    nearest_y = minimum(maximum(dy, -extent), extent)
    out_x = dx - nearest_x
    out_y = dy - nearest_y
    distance = math.sqrt(out_x * out_x + out_y * out_y)
    if distance > 0:
        depth = radius - distance
        scale = depth / distance
        push_x = out_x * scale
        push_y = out_y * scale
    else:
        overlap_x = extent + radius - abs(dx)
        overlap_y = extent + radius - abs(dy)
        if overlap_x <= overlap_y:
            depth = overlap_x
            sign = 1.0 if dx > 0 else (-1.0 if dx < 0 else tie)
            push_x = sign * overlap_x
            push_y = 0.0
        else:
            depth = overlap_y
            sign = 1.0 if dy > 0 else (-1.0 if dy < 0 else tie)
            push_x = 0.0
            push_y = sign * overlap_y
    if depth > 0:
        return push_x, push_y, depth
    return 0.0, 0.0, depth


@jit
def unit_vector(g0: float, g1: float) -> tuple[float, float]:
    """``randomness.unit_vectors`` for one pair of Gaussian numbers (``(1, 0)`` for zeros)."""
    length = math.sqrt(g0 * g0 + g1 * g1)
    if length == 0:
        return 1.0, 0.0
    return g0 / length, g1 / length


@jit
def away_from(dx: float, dy: float, push_x: float, push_y: float) -> tuple[float, float]:
    """``decide.away_from``: the direction reversed where it points against the push."""
    if dx * push_x + dy * push_y < 0:
        return -dx, -dy
    return dx, dy


@jit
def segment_crosses_box(
    sx: float, sy: float, ex_: float, ey_: float, cx: float, cy: float, half: float
) -> bool:
    """``geometry.segment_crosses_box`` for one segment and one square."""
    ex = (ex_ - sx) * 0.5
    ey = (ey_ - sy) * 0.5
    mx = (sx + ex) - cx
    my = (sy + ey) - cy
    ax = abs(ex)
    ay = abs(ey)
    return (
        abs(mx) < half + ax
        and abs(my) < half + ay
        and abs(ex * my - ey * mx) < half * ay + half * ax
    )


@jit
def segment_near_point(
    sx: float, sy: float, ex: float, ey: float, px: float, py: float, radius: float
) -> bool:
    """``geometry.segment_near_point`` for one segment and one point."""
    dx = ex - sx
    dy = ey - sy
    qx = px - sx
    qy = py - sy
    squared = dx * dx + dy * dy
    dot = qx * dx + qy * dy
    along = dot / squared if squared > 0 else 0.0
    along = minimum(maximum(along, 0.0), 1.0)
    ox = qx - along * dx
    oy = qy - along * dy
    return ox * ox + oy * oy < radius * radius
