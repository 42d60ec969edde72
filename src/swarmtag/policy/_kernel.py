"""The policies' formulas as one plain scalar function, for compiled kernels.

``kernel_score(kind, parameter, urgency, distance)`` performs exactly the
IEEE operations of ``Policy.score`` (``_terms.formula`` and each policy's
``_formula``), in the same order, on Python floats, so a compiler such as
numba can take it as it is and give bit-identical scores; a policy names its
``(kind, parameter)`` with ``Policy.kernel_form``. Tests check the two forms
against each other.
"""

from __future__ import annotations

from numbers import Real
from typing import Final

from swarmtag._checks import check_int, check_number, show
from swarmtag.errors import PolicyError
from swarmtag.policy._terms import MAX_URGENCY, PROXIMITY_RANGE, URGENCY_SCALE

__all__ = [
    "EDF_KIND",
    "PROXIMITY_KIND",
    "URGENCY_KIND",
    "WEIGHTED_KIND",
    "checked_kernel_score",
    "kernel_score",
]

PROXIMITY_KIND: Final = 0
"""``kernel_form`` kind of ``Proximity`` (parameter unused)."""
URGENCY_KIND: Final = 1
"""``kernel_form`` kind of ``Urgency`` (parameter: alpha)."""
WEIGHTED_KIND: Final = 2
"""``kernel_form`` kind of ``Weighted`` (parameter: w)."""
EDF_KIND: Final = 3
"""``kernel_form`` kind of ``Edf`` (parameter unused)."""


def kernel_score(kind: int, parameter: float, urgency: float, distance: float) -> float:
    """The score of one carrier under the policy ``(kind, parameter)``.

    >>> kernel_score(URGENCY_KIND, 0.5, 4.0, 1.8)
    20.0
    """
    if kind == EDF_KIND:
        return urgency
    term = distance / PROXIMITY_RANGE
    term = min(term, 1.0)  # np.minimum(term, 1.0): term unless 1.0 is smaller
    term = URGENCY_SCALE * (1.0 - term)
    if kind == URGENCY_KIND:
        return urgency * (parameter + term)
    if kind == WEIGHTED_KIND:
        return parameter * urgency + (1.0 - parameter) * term
    return term


def checked_kernel_score(kind: int, parameter: float, urgency: float, distance: float) -> float:
    """``kernel_score`` with its arguments checked: what ``swarmtag.policy`` exports.

    The compiled kernels take the plain ``kernel_score`` (checks would not
    compile, and the simulator checks a policy once when it is built).

    >>> checked_kernel_score(7, 0.5, 4.0, 1.8)
    Traceback (most recent call last):
    ...
    swarmtag.errors.PolicyError: kind: 7 is not an integer in 0-3
    """
    kind = check_int("kind", kind, low=PROXIMITY_KIND, high=EDF_KIND, error=PolicyError)
    parameter = check_number("parameter", parameter, error=PolicyError)
    urgency = check_number("urgency", urgency, low=0.0, high=MAX_URGENCY, error=PolicyError)
    given: object = distance  # checked as what it is, not as annotated
    if isinstance(given, bool) or not isinstance(given, Real) or not float(given) >= 0:
        raise PolicyError(f"distance: {show(given)} is not a number >= 0 (inf allowed)")
    return kernel_score(kind, parameter, urgency, float(given))
