"""Allocators as conditions: rules that look beyond one robot's scores (docs/allocators.md).

These are the value objects a condition name parses into; what each does
in a run lives in ``swarmtag.sim.allocators`` (a controller's choice step).
Each still has a score, the one its robots rank their own candidates with.

- ``Threshold(theta)``: response threshold (Bonabeau, Theraulaz and
  Deneubourg 1996): a walker takes each candidate with probability
  ``T(s) = s^2 / (s^2 + theta^2)``, stimulus ``s = u_c + 1``; among those
  it takes, the nearest (score ``u_d``);
- ``Oracle(alpha)``: a central assignment with global knowledge (Kuhn
  1955): idle robots to waiting carriers, maximising the summed urgency
  score ``u_c * (alpha + u_d)`` of true distances;
- ``Cbaa(comm_range, loss)``: the consensus-based bundle auction with one
  task per robot (Choi, Brunet and How 2009) over a robot-to-robot radio:
  bids ``u_c * (0.7 + u_d)``;
- ``ClaimFirst(hold, loss)``: the urgency score (alpha 0.7) with claims
  through the tags (the protocol's extension, ``swarmtag.tag.claim``): a
  robot that chooses a carrier claims it for ``hold`` seconds (a write,
  lost with probability ``loss``); robots that heard a live claim of
  another pass that carrier over;
- ``Adaptive(gain)``: the urgency score with each robot's own alpha,
  lowered by ``gain`` on each race it loses and drawn back to 0.7 by
  ``gain`` on each lift it wins.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from swarmtag.errors import PolicyError
from swarmtag.policy._policies import Policy, Urgency, _real
from swarmtag.policy._terms import formula
from swarmtag.tag.claim import MAX_HOLD

__all__ = [
    "ADAPTIVE_START",
    "CBAA_ALPHA",
    "CLAIM_ALPHA",
    "Adaptive",
    "Allocator",
    "Cbaa",
    "ClaimFirst",
    "Oracle",
    "Threshold",
]

CBAA_ALPHA = 0.7
"""The alpha of CBAA's bids: the published urgency policy's."""
CLAIM_ALPHA = 0.7
"""The alpha of the claiming robots' score: the published urgency policy's."""
ADAPTIVE_START = 0.7
"""Where an adaptive robot's alpha starts and returns to: the published policy's."""


def _positive(name: str, value: object) -> float:
    allowed = "a finite number > 0"
    number = _real(name, value, allowed)
    if not (math.isfinite(number) and number > 0):
        msg = f"{name}: {number!r} must be {allowed}"
        raise PolicyError(msg)
    return number


def _urgency_score(
    alpha: float, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """``u_c * (alpha + u_d)``: ``Urgency(alpha)``'s formula, the same operations."""
    return Urgency(alpha=alpha).score(urgency, distance)


@dataclass(frozen=True, slots=True)
class Allocator(Policy):
    """A rule run by an allocating controller, on the reference backend only."""

    @property
    def compiled(self) -> bool:
        """False: allocators run on the reference backend."""
        return False

    @property
    def kernel_form(self) -> tuple[int, float]:
        """None: raises ``PolicyError``."""
        msg = f"allocator {self.name!r} has no compiled form; it runs on the reference backend"
        raise PolicyError(msg)

    @property
    def draws(self) -> bool:
        """Whether its runs draw the allocation stream (docs/simulator.md, stream 9)."""
        return False


@dataclass(frozen=True, slots=True)
class Threshold(Allocator):
    """Response threshold: take a candidate with probability ``T(u_c + 1)``; the nearest taken.

    >>> Threshold(theta=5).name
    'threshold:theta=5.0'
    >>> round(float(Threshold(theta=5).take_up(np.array(4.0))), 3)  # s = 5: one half
    0.5
    """

    theta: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "theta", _positive("theta", self.theta))

    @property
    def name(self) -> str:
        """``threshold:theta=THETA``."""
        return f"threshold:theta={self.theta!r}"

    @property
    def draws(self) -> bool:
        """True: one uniform number per robot and carrier a tick."""
        return True

    def take_up(self, urgency: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """``T(s) = s^2 / (s^2 + theta^2)`` with stimulus ``s = urgency + 1``."""
        stimulus = np.asarray(urgency, dtype=np.float64) + 1.0
        squared = stimulus * stimulus
        result: npt.NDArray[np.float64] = squared / (squared + self.theta * self.theta)
        return result

    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        del urgency  # urgency decides what is taken; among those, the nearest
        return formula(distance)


@dataclass(frozen=True, slots=True)
class Oracle(Allocator):
    """Central assignment with global knowledge, maximising the summed urgency score.

    >>> Oracle(alpha=0.7).name
    'oracle:alpha=0.7'
    """

    alpha: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "alpha", _positive("alpha", self.alpha))

    @property
    def name(self) -> str:
        """``oracle:alpha=ALPHA``."""
        return f"oracle:alpha={self.alpha!r}"

    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        return _urgency_score(self.alpha, urgency, distance)


@dataclass(frozen=True, slots=True)
class Cbaa(Allocator):
    """Consensus-based auction over a radio of ``comm_range`` m losing each message w.p. ``loss``.

    >>> Cbaa(comm_range=5, loss=0.1).name
    'cbaa:comm_range=5.0,loss=0.1'
    """

    comm_range: float
    loss: float

    def __post_init__(self) -> None:
        object.__setattr__(self, "comm_range", _positive("comm_range", self.comm_range))
        object.__setattr__(self, "loss", _loss(self.loss))

    @property
    def name(self) -> str:
        """``cbaa:comm_range=R,loss=P``."""
        return f"cbaa:comm_range={self.comm_range!r},loss={self.loss!r}"

    @property
    def draws(self) -> bool:
        """True: one uniform number per robot pair a tick (message loss)."""
        return True

    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        return _urgency_score(CBAA_ALPHA, urgency, distance)


def _loss(value: object) -> float:
    allowed = "a number with 0 <= loss < 1"
    loss = _real("loss", value, allowed)
    if not 0.0 <= loss < 1.0:
        msg = f"loss: {loss!r} must be {allowed}"
        raise PolicyError(msg)
    return loss


@dataclass(frozen=True, slots=True)
class ClaimFirst(Allocator):
    """Claims through the tag: choose by the urgency score, claim for ``hold`` s, skip claims.

    >>> ClaimFirst(hold=30, loss=0.1).name
    'claim:hold=30.0,loss=0.1'
    """

    hold: float
    loss: float

    def __post_init__(self) -> None:
        allowed = "a number of seconds, 1 <= hold <= 255"
        hold = _real("hold", self.hold, allowed)
        if not 1.0 <= hold <= MAX_HOLD:
            msg = f"hold: {hold!r} must be {allowed}"
            raise PolicyError(msg)
        object.__setattr__(self, "hold", hold)
        object.__setattr__(self, "loss", _loss(self.loss))

    @property
    def name(self) -> str:
        """``claim:hold=H,loss=P``."""
        return f"claim:hold={self.hold!r},loss={self.loss!r}"

    @property
    def draws(self) -> bool:
        """True: one uniform number per robot and carrier a tick (a claim write's loss)."""
        return True

    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        return _urgency_score(CLAIM_ALPHA, urgency, distance)


@dataclass(frozen=True, slots=True)
class Adaptive(Allocator):
    """The urgency score with each robot's own alpha, adapted to the races it loses and wins.

    >>> Adaptive(gain=0.5).name
    'adaptive:gain=0.5'
    """

    gain: float

    def __post_init__(self) -> None:
        allowed = "a number with 0 < gain <= 1"
        gain = _real("gain", self.gain, allowed)
        if not 0.0 < gain <= 1.0:
            msg = f"gain: {gain!r} must be {allowed}"
            raise PolicyError(msg)
        object.__setattr__(self, "gain", gain)

    @property
    def name(self) -> str:
        """``adaptive:gain=G``."""
        return f"adaptive:gain={self.gain!r}"

    def _formula(
        self, urgency: npt.NDArray[np.float64], distance: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        return _urgency_score(ADAPTIVE_START, urgency, distance)
