"""Batched carrier selection: the one place where scores become a choice.

Every robot of every run picks, along the last (carriers) axis, the
available carrier with the largest score; exact ties go to the smaller
distance, then to the smaller marker id, so the choice is deterministic.
Everything is vectorised: a ``(runs, robots, carriers)`` batch costs a few
passes over the arrays and no Python loop.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import numpy.typing as npt

from swarmtag._checks import show
from swarmtag.errors import PolicyError
from swarmtag.policy._policies import Policy
from swarmtag.policy._terms import MAX_URGENCY, as_float_array

__all__ = ["best_of", "select"]


def _check_policy(policy: object) -> None:
    if not isinstance(policy, Policy):
        msg = (
            f"policy: {policy!r} is not a Policy; use Proximity(), Urgency(alpha=...), "
            "Weighted(w=...) or parse_policy(name)"
        )
        raise PolicyError(msg)


def _check_values(u: npt.NDArray[np.float64], d: npt.NDArray[np.float64]) -> None:
    # min/max propagate NaN, and NaN fails every comparison: one pass each, no temporaries.
    if u.size and not (u.min() >= 0 and u.max() <= MAX_URGENCY):
        bad = u[~((u >= 0) & (u <= MAX_URGENCY))][0]
        msg = f"urgency: {float(bad)!r} is outside 0-{MAX_URGENCY}; urgencies are integers 0-9"
        raise PolicyError(msg)
    if d.size and not d.min() >= 0:
        bad = d[~(d >= 0)][0]
        msg = (
            f"distance: {float(bad)!r} is not a distance; "
            "distances must be >= 0 metres (inf allowed)"
        )
        raise PolicyError(msg)


def _break_ties(
    tie: npt.NDArray[np.bool_], distance: npt.NDArray[np.float64], marker: npt.NDArray[np.integer]
) -> npt.NDArray[np.bool_]:
    """Narrow ``tie`` (rows of equal best scores) to the nearest, then the smallest marker."""
    tie &= distance == np.where(tie, distance, np.inf).min(axis=-1, keepdims=True)
    tie &= marker == np.where(tie, marker, np.iinfo(marker.dtype).max).min(axis=-1, keepdims=True)
    return tie


def _broadcast_shape(shapes: dict[str, tuple[int, ...]]) -> tuple[int, ...]:
    try:
        shape = np.broadcast_shapes(*shapes.values())
    except ValueError as exc:
        listed = ", ".join(f"{name} {shape}" for name, shape in shapes.items())
        msg = f"{', '.join(shapes)}: shapes do not broadcast to one (..., carriers) shape: {listed}"
        raise PolicyError(msg) from exc
    if not shape:
        msg = f"{', '.join(shapes)}: all scalars; the last axis must index the carriers"
        raise PolicyError(msg)
    return shape


def select(
    policy: Policy,
    *,
    urgency: npt.ArrayLike,
    distance: npt.ArrayLike,
    marker: npt.ArrayLike,
    available: npt.ArrayLike | None = None,
    context: Mapping[str, npt.ArrayLike] | None = None,
) -> npt.NDArray[np.intp]:
    """Index of the chosen carrier along the last axis, -1 where none is available.

    ``urgency`` (0-9), ``distance`` (metres, >= 0, ``inf`` allowed),
    ``marker`` (integers, unique along the carriers axis) and ``available``
    (booleans, default all ``True``) broadcast to one shape ``(...,
    carriers)``, e.g. ``(runs, robots, carriers)``. The result has the
    leading shape ``(...)`` and dtype ``numpy.intp``: a 0-d array for a
    single robot's ``(carriers,)``. Only available carriers are chosen;
    among them the largest ``policy.score`` wins, exact ties going to the
    smaller distance, then to the smaller marker id. Every entry is
    validated, available or not. ``context`` holds what a rule of one's own
    may ask for beside ``marker`` (``age``: seconds each carrier has waited;
    ``swarmtag.policy.CONTEXT``), each broadcasting to the same shape.
    Raises ``PolicyError`` on bad inputs.

    >>> from swarmtag.policy import Proximity, Urgency
    >>> scene = {"urgency": [1, 9], "distance": [0.9, 2.7], "marker": [10, 11]}
    >>> int(select(Proximity(), **scene)), int(select(Urgency(alpha=0.7), **scene))
    (0, 1)
    >>> select(Urgency(alpha=0.7), **scene, available=[[True, False], [False, False]])
    array([ 0, -1])
    """
    _check_policy(policy)
    u = as_float_array("urgency", urgency)
    d = as_float_array("distance", distance)
    m = np.asarray(marker)
    if m.dtype.kind not in "iu":
        msg = f"marker: must hold integers, got an array of dtype {m.dtype}"
        raise PolicyError(msg)
    shapes = {"urgency": u.shape, "distance": d.shape, "marker": m.shape}
    a = None
    if available is not None:
        a = np.asarray(available)
        if a.dtype.kind != "b":
            msg = f"available: must hold booleans, got an array of dtype {a.dtype}"
            raise PolicyError(msg)
        shapes["available"] = a.shape
    shape = _broadcast_shape(shapes)
    _check_values(u, d)
    if shape[-1] == 0:
        return np.full(shape[:-1], -1, dtype=np.intp)

    u, d, m = (np.broadcast_to(x, shape) for x in (u, d, m))
    scores = policy.scores(u, d, {"marker": m, **(context or {})})
    return _best(scores, d, m, a, fresh=True)


def best_of(
    scores: npt.NDArray[np.float64],
    *,
    distance: npt.NDArray[np.float64],
    marker: npt.NDArray[np.integer],
    available: npt.NDArray[np.bool_] | None,
) -> npt.NDArray[np.intp]:
    """The index of the largest score along the last axis, by ``select``'s tie rule; -1 none.

    For rules that compute their own scores (the allocators): ``scores``,
    ``distance`` and ``marker`` (and ``available``) broadcast to one
    ``(..., carriers)`` shape with at least one carrier; nothing is checked,
    and no input is changed.
    """
    for name, value in (("scores", scores), ("distance", distance), ("marker", marker)):
        if not isinstance(value, np.ndarray) or value.dtype.kind not in "iuf":
            raise PolicyError(f"{name}: {show(value)} is not a numpy array of numbers")
    if available is not None and (
        not isinstance(available, np.ndarray) or available.dtype.kind != "b"
    ):
        raise PolicyError(f"available: {show(available)} is not a numpy array of booleans")
    try:
        shape = np.broadcast_shapes(
            scores.shape, distance.shape, marker.shape, () if available is None else available.shape
        )
    except ValueError:
        raise PolicyError("scores, distance, marker and available do not broadcast") from None
    if not shape or shape[-1] == 0:
        raise PolicyError(f"best_of needs at least one carrier along the last axis (shape {shape})")
    return _best(scores, distance, marker, available, fresh=False)


def _best(
    scores: npt.NDArray[np.float64],
    distance: npt.NDArray[np.float64],
    marker: npt.NDArray[np.integer],
    available: npt.NDArray[np.bool_] | None,
    *,
    fresh: bool,
) -> npt.NDArray[np.intp]:
    """``best_of``; ``fresh``: ``scores`` is the caller's own new array, changed in place."""
    shape = np.broadcast_shapes(scores.shape, distance.shape, marker.shape)
    d, m = np.broadcast_to(distance, shape), np.broadcast_to(marker, shape)
    if scores.shape != shape:
        scores = np.broadcast_to(scores, shape)
    a = None if available is None else np.broadcast_to(available, shape)
    if a is not None:
        if not (fresh and scores.flags.owndata and scores.flags.writeable):
            scores = scores.copy()
        np.copyto(scores, -np.inf, where=~a)
    tie = scores == scores.max(axis=-1, keepdims=True)
    # Only rows with several best carriers need the tie rule; work on those rows alone.
    # A row with no carrier available (every score -inf: all tied) chooses none anyway.
    several = np.count_nonzero(tie, axis=-1) > 1
    some = None if a is None else a.any(axis=-1)
    if some is not None:
        several &= some
    if several.all():
        tie = _break_ties(tie, d, m)
    elif several.any():
        tie[several] = _break_ties(tie[several], d[several], m[several])
    index = np.asarray(np.argmax(tie, axis=-1), dtype=np.intp)  # the first (only) True
    if some is not None:
        index = np.where(some, index, np.intp(-1))
    return index
