"""The urgency models of SPEC §4.3 as pure array formulas.

- growing: ``w0 ~ Uniform[0, T]``; ``u(t) = min(9, floor(9 * (w0 + t) / T))``;
  order time ``-w0`` (ticks).
- static: ``tau ~ Uniform[0, H]`` (H = 240 s); ``u = min(9, floor(10 * (1 - tau / H)))``;
  order time ``-(u / 9) * H`` converted to ticks (``H / tick``).

Both draw one uniform number per carrier, ``v = rng.random(carriers)``, and
scale it: ``w0 = v * T``, ``tau = v * H``. The operations run in the order
written, each an IEEE double operation, so backends can match them exactly.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from swarmtag.sim.model.geometry import Float

__all__ = ["InitialUrgency", "growing_urgency", "initial_urgency", "static_urgency", "waited"]

_TOP = 9


def growing_urgency(w0: Float, t: int | Float, horizon: float) -> NDArray[np.int8]:
    """``min(9, floor(9 * (w0 + t) / T))`` as int8.

    >>> growing_urgency(np.array([0.0, 1500.0, 2999.0, 3000.0]), 0, 3000.0)
    array([0, 4, 8, 9], dtype=int8)
    >>> growing_urgency(np.array([0.0]), 1000, 3000.0)
    array([3], dtype=int8)
    """
    return np.minimum(_TOP, np.floor(9.0 * (w0 + t) / horizon)).astype(np.int8)


def static_urgency(tau: Float, horizon_s: float) -> NDArray[np.int8]:
    """``min(9, floor(10 * (1 - tau / H)))`` as int8, ``tau`` and ``H`` in seconds.

    >>> static_urgency(np.array([0.0, 23.9, 24.0, 120.0, 239.9, 240.0]), 240.0)
    array([9, 9, 9, 5, 0, 0], dtype=int8)
    """
    return np.minimum(_TOP, np.floor(10.0 * (1.0 - tau / horizon_s))).astype(np.int8)


def waited(order_time: Float, t: int, tick: float) -> Float:
    """Seconds each carrier has waited at tick ``t``: ``max(t - order_time, 0) * tick``.

    What a rule of one's own gets as ``age`` (``swarmtag.policy.CONTEXT``).

    >>> waited(np.array([-10.0, 0.0, 50.0]), 20, 0.1)
    array([3., 2., 0.])
    """
    ticks = np.maximum(t - order_time, 0.0)
    seconds: Float = ticks * tick
    return seconds


@dataclass(frozen=True, eq=False)
class InitialUrgency:
    """One run's carriers at time 0: urgency, order time (ticks) and growth base ``w0``.

    ``w0`` is NaN for carriers whose urgency does not grow (static model).
    """

    urgency0: NDArray[np.int8]
    order_time: Float
    w0: Float


def initial_urgency(
    draw: Float, *, growing: bool, horizon: float, horizon_s: float
) -> InitialUrgency:
    """Urgencies at run start from one uniform ``draw`` in [0, 1) per carrier.

    ``horizon`` is T (growing) or H in ticks (static); ``horizon_s`` is H in
    seconds (static only).

    >>> u = initial_urgency(np.array([0.5]), growing=True, horizon=3000.0, horizon_s=240.0)
    >>> u.urgency0, u.order_time, u.w0
    (array([4], dtype=int8), array([-1500.]), array([1500.]))
    >>> u = initial_urgency(np.array([0.5]), growing=False, horizon=2400.0, horizon_s=240.0)
    >>> u.urgency0, u.order_time.round(3), u.w0
    (array([5], dtype=int8), array([-1333.333]), array([nan]))
    """
    if growing:
        w0 = draw * horizon
        return InitialUrgency(urgency0=growing_urgency(w0, 0, horizon), order_time=-w0 + 0.0, w0=w0)
    tau = draw * horizon_s
    urgency0 = static_urgency(tau, horizon_s)
    order_time = -(urgency0 / 9.0) * horizon + 0.0  # + 0.0: no -0.0 in logs
    return InitialUrgency(urgency0=urgency0, order_time=order_time, w0=np.full(draw.shape, np.nan))
