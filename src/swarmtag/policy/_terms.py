"""The proximity term of SPEC §3.3 and the constants it is built from.

Distance is turned into a score on the tags' 0-9 urgency scale, so that the
urgency and weighted policies can add or multiply the two on equal footing.
"""

from __future__ import annotations

from typing import Any, Final, overload

import numpy as np
import numpy.typing as npt

from swarmtag.errors import PolicyError

__all__ = ["MAX_URGENCY", "PROXIMITY_RANGE", "URGENCY_SCALE", "as_float_array", "proximity_term"]

PROXIMITY_RANGE: Final = 3.6
"""Metres at which the proximity term reaches 0; farther carriers all score 0."""
MAX_URGENCY: Final = 9
"""Largest urgency a tag advertises (SPEC §2.1); urgencies are integers 0-9."""
URGENCY_SCALE: Final = 9.0
"""The proximity term's value at distance 0: the top of the tags' 0-9 scale."""


def as_float_array(name: str, value: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Convert ``value`` to a float64 array, or raise ``PolicyError`` naming ``name``."""
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as exc:  # e.g. ragged nested lists
        msg = f"{name}: cannot be read as an array of numbers ({exc})"
        raise PolicyError(msg) from exc
    if array.dtype.kind not in "biuf":
        msg = f"{name}: must hold real numbers, got an array of dtype {array.dtype}"
        raise PolicyError(msg)
    return array.astype(np.float64, copy=False)


def formula(d: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Evaluate ``u_d`` on a float64 array into a new array; the one place it is written.

    The steps are exactly ``9.0 * (1.0 - np.minimum(d / 3.6, 1.0))`` in that
    order, done in place on one buffer to spare large batches three
    temporaries. Each step is one correctly rounded IEEE operation, so the
    values are the same bits as the scalar expression's.
    """
    result = np.divide(d, PROXIMITY_RANGE, out=np.empty(d.shape, dtype=np.float64))
    np.minimum(result, 1.0, out=result)
    np.subtract(1.0, result, out=result)
    np.multiply(URGENCY_SCALE, result, out=result)
    return result


@overload
def proximity_term(distance: float) -> np.float64: ...
@overload
def proximity_term(distance: npt.NDArray[Any]) -> npt.NDArray[np.float64]: ...
@overload
def proximity_term(distance: npt.ArrayLike) -> np.float64 | npt.NDArray[np.float64]: ...
def proximity_term(distance: npt.ArrayLike) -> np.float64 | npt.NDArray[np.float64]:
    """Proximity term ``u_d = 9 * (1 - min(d / 3.6, 1))`` for a distance ``d`` in metres.

    9 at the carrier, falling linearly to 0 at 3.6 m and staying 0 beyond.
    A scalar (Python or numpy) gives a ``numpy.float64`` (a ``float``
    subclass); an array (or list) gives a float64 array of the same shape.
    Scalar and array forms give bit-identical values. A negative or NaN
    distance is refused (``PolicyError``); ``inf`` gives 0.

    >>> float(proximity_term(1.8))
    4.5
    >>> proximity_term(np.array([0.0, 0.9, 3.6, 5.0]))
    array([9.  , 6.75, 0.  , 0.  ])
    """
    d = as_float_array("distance", distance)
    if not (d >= 0).all():
        msg = "distance: a value is negative or NaN (distances are metres, >= 0)"
        raise PolicyError(msg)
    return wrap_result(formula(d), distance)


def wrap_result(
    result: npt.NDArray[np.float64], *inputs: npt.ArrayLike
) -> np.float64 | npt.NDArray[np.float64]:
    """Give arrays back for array inputs and a ``numpy.float64`` for scalar inputs."""
    if any(isinstance(x, np.ndarray) for x in inputs) or np.ndim(result) > 0:
        return np.asarray(result, dtype=np.float64)
    return np.float64(result)
