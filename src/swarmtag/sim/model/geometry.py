"""Pure batched 2-D geometry for the kernel: lengths, steps, turns, contacts, walls.

Vectors are arrays whose last axis has length 2 (x, y); every function works
elementwise over any leading axes (runs, robots, carriers ...). The floating
point is written down so that other backends can match it bit for bit: a
length is ``sqrt(x*x + y*y)`` (never ``hypot``), no sin/cos/atan2 appear
(turns use a precomputed cosine and sine of the largest turn per tick), and
sums over bodies run in index order (``ordered_sum``), never pairwise.

Bodies are *rounded boxes*: an axis-aligned square of half-side ``extent``
grown by a disc of ``radius``. A robot is ``(0, r)``, a carrier or a loaded
robot ``(h, 0)``. Two rounded boxes touch like one point against the box of
half-side ``extent_a + extent_b`` grown by ``radius_a + radius_b``, so one
formula (``contact_push``) covers disc-disc, disc-square and square-square.
"""

from __future__ import annotations

from typing import Final

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "FACE_NORMALS",
    "Float",
    "bearing_factor",
    "clamp_to_box",
    "contact_depth",
    "contact_push",
    "contact_xy",
    "length",
    "length_xy",
    "ordered_sum",
    "segment_crosses_box",
    "segment_near_point",
    "step_towards",
    "turn_towards",
]

Float = NDArray[np.float64]

FACE_NORMALS: Final = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
"""Outward normals of a carrier's faces, in face order: east, north, west, south."""
FACE_NORMALS.flags.writeable = False


def length(v: Float) -> Float:
    """``sqrt(x*x + y*y)`` over the last axis.

    >>> length(np.array([[3.0, 4.0], [0.0, 0.0]]))
    array([5., 0.])
    """
    return length_xy(v[..., 0], v[..., 1])


def length_xy(x: Float, y: Float) -> Float:
    """``length`` of vectors given as separate x and y arrays (no (..., 2) array made).

    Where the leading axes are many and the last is 2, numpy's loops over
    pairs cost more than the arithmetic: (R, N, C) arrays of x and y are
    several times faster, with the same bits.

    >>> length_xy(np.array([3.0, 0.0]), np.array([4.0, 0.0]))
    array([5., 0.])
    """
    return np.sqrt(x * x + y * y)


def ordered_sum(values: Float, axis: int) -> Float:
    """Sum along ``axis`` strictly left to right (``cumsum``'s order), whatever the layout.

    >>> ordered_sum(np.array([[1e16, 1.0, -1e16]]), axis=1)
    array([0.])
    """
    if values.shape[axis] == 0:
        return np.zeros(np.delete(values.shape, axis), dtype=np.float64)
    total: Float = np.take(np.cumsum(values, axis=axis), -1, axis=axis)
    return total


def step_towards(position: Float, goal: Float, step: Float) -> Float:
    """Move up to ``step`` along the straight line to ``goal``; land exactly on it if closer.

    ``step`` has the leading shape (one length per body).

    >>> step_towards(np.array([[0.0, 0.0]]), np.array([[3.0, 4.0]]), np.array([1.0]))
    array([[0.6, 0.8]])
    >>> step_towards(np.array([[0.0, 0.0]]), np.array([[0.3, 0.4]]), np.array([1.0]))
    array([[0.3, 0.4]])
    """
    offset = goal - position
    distance = length(offset)
    scale = np.divide(step, distance, out=np.zeros_like(distance), where=distance > 0)
    moved = position + offset * scale[..., None]
    return np.where((distance <= step)[..., None], goal, moved)


def turn_towards(heading: Float, target: Float, cos_step: float, sin_step: float) -> Float:
    """Turn unit ``heading`` towards unit ``target`` by at most the angle of (cos, sin).

    Within one step the heading becomes ``target`` exactly; otherwise it
    rotates by the full step (counter-clockwise when ``target`` is straight
    behind) and is renormalised.

    >>> turn_towards(np.array([1.0, 0.0]), np.array([0.0, 1.0]), 0.0, 1.0)
    array([0., 1.])
    >>> turn_towards(np.array([1.0, 0.0]), np.array([-1.0, 0.0]), 0.0, 1.0)
    array([0., 1.])
    """
    hx, hy = heading[..., 0], heading[..., 1]
    tx, ty = target[..., 0], target[..., 1]
    dot = hx * tx + hy * ty
    cross = hx * ty - hy * tx
    sin = np.where(cross < 0, -sin_step, sin_step)
    rx = hx * cos_step - hy * sin
    ry = hx * sin + hy * cos_step
    norm = np.sqrt(rx * rx + ry * ry)
    turned = np.stack((rx / norm, ry / norm), axis=-1)
    return np.where((dot >= cos_step)[..., None], target, turned)


def _gap(dx: Float, dy: Float, extent: Float) -> tuple[Float, Float, Float]:
    """The offset from the nearest point of the summed box (x, y) and its length."""
    nearest_x = np.minimum(np.maximum(dx, -extent), extent)
    nearest_y = np.minimum(np.maximum(dy, -extent), extent)
    out_x = dx - nearest_x
    out_y = dy - nearest_y
    return out_x, out_y, np.sqrt(out_x * out_x + out_y * out_y)


def _overlaps(
    dx: Float, dy: Float, extent: Float, radius: Float
) -> tuple[Float, Float, NDArray[np.bool_]]:
    """A centre inside the summed box: the overlap along x and along y, and which is least."""
    overlap_x = extent + radius - np.abs(dx)
    overlap_y = extent + radius - np.abs(dy)
    return overlap_x, overlap_y, overlap_x <= overlap_y


def _depth(
    outside: NDArray[np.bool_],
    depth_outside: Float,
    overlaps: tuple[Float, Float, NDArray[np.bool_]],
) -> Float:
    """The depth: ``radius - distance`` outside the summed box, else the least overlap."""
    overlap_x, overlap_y, along_x = overlaps
    depth: Float = np.where(outside, depth_outside, np.where(along_x, overlap_x, overlap_y))
    return depth


def contact_depth(dx: Float, dy: Float, extent: Float, radius: Float) -> Float:
    """``contact_xy``'s depth alone (positive where the bodies overlap), without the push.

    >>> contact_depth(np.array([0.2, 0.6]), np.array([0.0, 0.0]), np.array(0.0), np.array(0.25))
    array([ 0.05, -0.35])
    """
    _, _, distance = _gap(dx, dy, extent)
    depth_outside = radius - distance
    outside = distance > 0
    if outside.all():  # no centre inside the summed box (nearly every contact)
        return depth_outside
    return _depth(outside, depth_outside, _overlaps(dx, dy, extent, radius))


def contact_xy(
    dx: Float, dy: Float, extent: Float, radius: Float, tie: Float | float
) -> tuple[Float, Float, Float]:
    """``contact_push`` on separate x and y arrays: returns push x, push y and depth."""
    out_x, out_y, distance = _gap(dx, dy, extent)
    outside = distance > 0
    depth_outside = radius - distance
    if outside.all():  # no centre inside the summed box (nearly every contact): the same values
        hit_outside = depth_outside > 0
        ratio = depth_outside / distance
        return (
            np.where(hit_outside, out_x * ratio, 0.0),
            np.where(hit_outside, out_y * ratio, 0.0),
            depth_outside,
        )
    scale = np.divide(depth_outside, distance, out=np.zeros_like(distance), where=outside)

    overlaps = _overlaps(dx, dy, extent, radius)
    overlap_x, overlap_y, along_x = overlaps
    sign_x = np.where(dx > 0, 1.0, np.where(dx < 0, -1.0, tie))
    sign_y = np.where(dy > 0, 1.0, np.where(dy < 0, -1.0, tie))

    depth = _depth(outside, depth_outside, overlaps)
    hit = depth > 0
    push_x = np.where(outside, out_x * scale, np.where(along_x, sign_x * overlap_x, 0.0))
    push_y = np.where(outside, out_y * scale, np.where(along_x, 0.0, sign_y * overlap_y))
    return np.where(hit, push_x, 0.0), np.where(hit, push_y, 0.0), depth


def contact_push(
    offset: Float, extent: Float, radius: Float, tie: Float | float
) -> tuple[Float, Float]:
    """How far body A must move to stop overlapping body B, and the overlap depth.

    ``offset`` is A's centre minus B's (last axis x, y); ``extent`` and
    ``radius`` are the summed half-sides and radii of the two rounded boxes.
    Outside the summed box the push is along the line from its nearest point,
    ``outward * ((radius - d) / d)``; inside (centres closer than the box) it
    is along the axis of least overlap (x on a tie), in the direction of the
    offset (``tie``, +1 or -1, where that component is 0). The push is zero
    where the depth is not positive.

    >>> push, depth = contact_push(np.array([0.2, 0.0]), np.array(0.0), np.array(0.25), 1.0)
    >>> push.round(12), depth.round(12)
    (array([0.05, 0.  ]), np.float64(0.05))
    >>> push, depth = contact_push(np.array([0.0, 0.3]), np.array(0.355), np.array(0.0), 1.0)
    >>> push.round(12), depth.round(12)
    (array([0.   , 0.055]), np.float64(0.055))
    """
    push_x, push_y, depth = contact_xy(offset[..., 0], offset[..., 1], extent, radius, tie)
    return np.stack((push_x, push_y), axis=-1), depth


def clamp_to_box(position: Float, margin: Float, size: float) -> Float:
    """Keep a body whose half-size is ``margin`` inside the square ``[0, size]^2``.

    >>> clamp_to_box(np.array([[0.05, 3.9]]), np.array([0.125]), 3.75)
    array([[0.125, 3.625]])
    """
    low = margin[..., None]
    return np.minimum(np.maximum(position, low), size - low)


def segment_crosses_box(start: Float, end: Float, centre: Float, half: float) -> NDArray[np.bool_]:
    """Whether the segment ``start``-``end`` passes through the open square ``centre`` +- ``half``.

    Separating-axis test (x, y and the segment's normal), without divisions;
    a segment that only grazes an edge or a corner does not count.

    >>> segment_crosses_box(np.array([0.0, 0.0]), np.array([2.0, 0.0]), np.array([1.0, 0.1]), 0.2)
    np.True_
    >>> segment_crosses_box(np.array([0.0, 0.0]), np.array([2.0, 0.0]), np.array([1.0, 0.2]), 0.2)
    np.False_
    """
    ex = (end[..., 0] - start[..., 0]) * 0.5
    ey = (end[..., 1] - start[..., 1]) * 0.5
    mx = (start[..., 0] + ex) - centre[..., 0]
    my = (start[..., 1] + ey) - centre[..., 1]
    ax, ay = np.abs(ex), np.abs(ey)
    crosses: NDArray[np.bool_] = (
        (np.abs(mx) < half + ax)
        & (np.abs(my) < half + ay)
        & (np.abs(ex * my - ey * mx) < half * ay + half * ax)
    )
    return crosses


def segment_near_point(start: Float, end: Float, point: Float, radius: float) -> NDArray[np.bool_]:
    """Whether the segment ``start``-``end`` passes closer than ``radius`` to ``point``.

    >>> segment_near_point(np.array([0.0, 0.0]), np.array([2.0, 0.0]), np.array([1.0, 0.1]), 0.125)
    np.True_
    >>> segment_near_point(np.array([0.0, 0.0]), np.array([2.0, 0.0]), np.array([3.0, 0.0]), 0.5)
    np.False_
    """
    dx = end[..., 0] - start[..., 0]
    dy = end[..., 1] - start[..., 1]
    qx = point[..., 0] - start[..., 0]
    qy = point[..., 1] - start[..., 1]
    squared = dx * dx + dy * dy
    dot = qx * dx + qy * dy
    squared = np.broadcast_to(squared, dot.shape)
    along = np.divide(dot, squared, out=np.zeros(dot.shape), where=squared > 0)
    along = np.minimum(np.maximum(along, 0.0), 1.0)
    ox = qx - along * dx
    oy = qy - along * dy
    near: NDArray[np.bool_] = ox * ox + oy * oy < radius * radius
    return near


def bearing_factor(
    dx: Float, dy: Float, distance: Float, heading: Float, *, cosines: Float, factors: Float
) -> Float:
    """A bearing profile's factor for each offset ``(dx, dy)`` seen from a robot facing ``heading``.

    ``cos(bearing) = (offset . heading) / distance`` (1 at distance 0),
    clipped to [-1, 1]; between the profile's points (``cosines`` falling
    from 1 to -1) the factor is linear in it (``swarmtag.sim.config.bearing``).

    >>> cosines, factors = np.array([1.0, 0.0, -1.0]), np.array([1.0, 0.5, 0.25])
    >>> dx, dy = np.array([2.0, 0.0, -2.0]), np.array([0.0, -3.0, 0.0])
    >>> heading = np.array([1.0, 0.0])
    >>> bearing_factor(dx, dy, length_xy(dx, dy), heading, cosines=cosines, factors=factors)
    array([1.  , 0.5 , 0.25])
    """
    dot = dx * heading[..., 0] + dy * heading[..., 1]
    ahead = distance > 0
    cos = np.divide(dot, distance, out=np.ones(dot.shape), where=ahead)
    cos = np.minimum(np.maximum(cos, -1.0), 1.0)
    i = (cosines[1:-1] > cos[..., None]).sum(axis=-1)
    p0, p1 = cosines[i], cosines[i + 1]
    f0, f1 = factors[i], factors[i + 1]
    factor: Float = f0 + (f1 - f0) * ((p0 - cos) / (p0 - p1))
    return factor
