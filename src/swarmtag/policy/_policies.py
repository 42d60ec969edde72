"""The carrier-selection policies of SPEC §3.3 as small frozen value objects.

Each policy knows its canonical condition name (SPEC §8.1) and scores
candidates with its formula. ``score`` works on scalars and on arrays of
any shape alike, so the simulator and the behaviour tree share one formula.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass
from numbers import Real
from typing import Any, overload

import numpy as np
import numpy.typing as npt

from swarmtag._checks import show
from swarmtag.errors import PolicyError
from swarmtag.policy._kernel import EDF_KIND, PROXIMITY_KIND, URGENCY_KIND, WEIGHTED_KIND
from swarmtag.policy._terms import as_float_array, formula, wrap_result

__all__ = ["Edf", "Policy", "Proximity", "Urgency", "Weighted"]


def _real(name: str, value: object, allowed: str) -> float:
    """Return ``value`` as a float, or raise ``PolicyError`` naming ``name`` and ``allowed``."""
    try:
        number = None if isinstance(value, bool) or not isinstance(value, Real) else float(value)
    except OverflowError:  # an integer beyond float range
        number = None
    if number is None:
        msg = f"{name}: {show(value)} must be {allowed}"
        raise PolicyError(msg)
    # ``+ 0.0`` turns -0.0 into 0.0 so that equal policies have equal names.
    return number + 0.0


@dataclass(frozen=True, slots=True)
class Policy(ABC):
    """A carrier-selection policy: a canonical name and a score (larger is better).

    Subclasses are frozen dataclasses; equal parameters give equal, hashable
    policies, and ``parse_policy(p.name) == p``. ``str(p)`` is ``p.name``.
    """

    @property
    @abstractmethod
    def name(self) -> str:
        """Canonical condition name (SPEC §8.1), e.g. ``urgency:alpha=0.7``."""

    @property
    @abstractmethod
    def kernel_form(self) -> tuple[int, float]:
        """``(kind, parameter)`` for ``swarmtag.policy.kernel_score`` (compiled kernels)."""

    @abstractmethod
    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        """Apply the policy's formula to float64 arrays that already have one shape."""

    @overload
    def score(self, urgency: float, distance: float) -> np.float64: ...
    @overload
    def score(
        self, urgency: npt.NDArray[Any], distance: npt.ArrayLike
    ) -> npt.NDArray[np.float64]: ...
    @overload
    def score(
        self, urgency: npt.ArrayLike, distance: npt.NDArray[Any]
    ) -> npt.NDArray[np.float64]: ...
    @overload
    def score(
        self, urgency: npt.ArrayLike, distance: npt.ArrayLike
    ) -> np.float64 | npt.NDArray[np.float64]: ...
    def score(
        self, urgency: npt.ArrayLike, distance: npt.ArrayLike
    ) -> np.float64 | npt.NDArray[np.float64]:
        """Score carriers of urgency ``urgency`` (0-9) at ``distance`` metres.

        The two inputs broadcast against each other. Scalars give a
        ``numpy.float64``; arrays give a float64 array of the broadcast
        shape, bit-identical element by element to the scalar results.
        """
        u = as_float_array("urgency", urgency)
        d = as_float_array("distance", distance)
        try:
            u, d = np.broadcast_arrays(u, d)
        except ValueError as exc:
            msg = (
                f"urgency and distance: shapes {u.shape} and {d.shape} do not broadcast "
                "against each other"
            )
            raise PolicyError(msg) from exc
        return wrap_result(self._formula(u, d), urgency, distance)

    @property
    def compiled(self) -> bool:
        """Whether the compiled kernel runs it (``kernel_form`` exists): every built-in rule."""
        return True

    @property
    def context_names(self) -> tuple[str, ...]:
        """The context its scores need beside urgency and distance (``scores``): none here."""
        return ()

    def scores(
        self,
        urgency: npt.NDArray[np.float64],
        distance: npt.NDArray[np.float64],
        context: Mapping[str, npt.ArrayLike],
    ) -> npt.NDArray[np.float64]:
        """Scores of float64 arrays of one shape, with the candidates' ``context`` (``select``).

        The built-in formulas use no context; a rule of one's own may
        (``swarmtag.policy.ScoreRule``).
        """
        del context
        return self._formula(urgency, distance)

    def __str__(self) -> str:
        return self.name


@dataclass(frozen=True, slots=True)
class Proximity(Policy):
    """The baseline: score ``u_d``, so the nearest carrier wins and urgency is ignored.

    >>> Proximity().name
    'proximity'
    >>> float(Proximity().score(9, 1.8))
    4.5
    """

    @property
    def name(self) -> str:
        """Canonical condition name: ``proximity``."""
        return "proximity"

    @property
    def kernel_form(self) -> tuple[int, float]:
        """``(PROXIMITY_KIND, 0.0)``."""
        return PROXIMITY_KIND, 0.0

    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        del urgency  # the baseline ignores urgency by definition
        return formula(distance)


@dataclass(frozen=True, slots=True)
class Urgency(Policy):
    """The proposed policy: score ``u_c * (alpha + u_d)``; larger ``alpha`` favours urgency.

    ``alpha`` must be a finite number > 0; it is stored as a ``float``.

    >>> Urgency(alpha=3).name
    'urgency:alpha=3.0'
    >>> float(Urgency(alpha=0.5).score(4, 1.8))  # 4 * (0.5 + 4.5)
    20.0
    """

    alpha: float

    def __post_init__(self) -> None:
        allowed = "a finite number > 0"
        alpha = _real("alpha", self.alpha, allowed)
        if not (math.isfinite(alpha) and alpha > 0):
            msg = f"alpha: {alpha!r} must be {allowed}"
            raise PolicyError(msg)
        object.__setattr__(self, "alpha", alpha)

    @property
    def name(self) -> str:
        """Canonical condition name, e.g. ``urgency:alpha=0.7`` (alpha as ``repr(float)``)."""
        return f"urgency:alpha={self.alpha!r}"

    @property
    def kernel_form(self) -> tuple[int, float]:
        """``(URGENCY_KIND, alpha)``."""
        return URGENCY_KIND, self.alpha

    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        # urgency * (alpha + u_d), computed in place on the fresh u_d buffer.
        result = formula(distance)
        np.add(self.alpha, result, out=result)
        np.multiply(urgency, result, out=result)
        return result


@dataclass(frozen=True, slots=True)
class Weighted(Policy):
    """The preliminary sweep's policy: score ``w * u_c + (1 - w) * u_d``, ``0 <= w <= 1``.

    ``w = 0`` ranks like proximity, ``w = 1`` by urgency alone.

    >>> Weighted(w=0.3).name
    'weighted:w=0.3'
    >>> float(Weighted(w=0.5).score(4, 1.8))  # 0.5 * 4 + 0.5 * 4.5
    4.25
    """

    w: float

    def __post_init__(self) -> None:
        allowed = "a number with 0 <= w <= 1"
        w = _real("w", self.w, allowed)
        if not 0.0 <= w <= 1.0:  # also false for NaN
            msg = f"w: {w!r} must be {allowed}"
            raise PolicyError(msg)
        object.__setattr__(self, "w", w)

    @property
    def name(self) -> str:
        """Canonical condition name, e.g. ``weighted:w=0.3`` (w as ``repr(float)``)."""
        return f"weighted:w={self.w!r}"

    @property
    def kernel_form(self) -> tuple[int, float]:
        """``(WEIGHTED_KIND, w)``."""
        return WEIGHTED_KIND, self.w

    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        # w * urgency + (1 - w) * u_d, computed in place on the fresh u_d buffer.
        result = formula(distance)
        np.multiply(1.0 - self.w, result, out=result)
        np.add(self.w * urgency, result, out=result)
        return result


@dataclass(frozen=True, slots=True)
class Edf(Policy):
    """Earliest deadline first: score ``u_c``, the most urgent carrier; distance breaks ties.

    Urgency alone, the ablation of the distance term (Liu and Layland, J. ACM
    1973, for the rule): a carrier's urgency stands for how soon it is due.

    >>> Edf().name
    'edf'
    >>> float(Edf().score(4, 1.8))
    4.0
    """

    @property
    def name(self) -> str:
        """Canonical condition name: ``edf``."""
        return "edf"

    @property
    def kernel_form(self) -> tuple[int, float]:
        """``(EDF_KIND, 0.0)``."""
        return EDF_KIND, 0.0

    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        del distance  # ties only (select's rule), never the score
        return np.array(urgency, dtype=np.float64)
