"""How far the camera sees in each direction around the robot (``camera.bearing``).

A real robot's four perimeter cameras do not see alike all round: the DOTS
robot's 88° cameras at ±17° and ±129° leave blind wedges around ±73° and
behind. A *bearing profile* scales the camera's reach by a factor per
bearing (the angle between the robot's heading and the carrier, either
side): robot ``n`` sees carrier ``c`` within ``reach * factor(bearing)``,
where ``reach`` is the hard disc's ``camera.range`` or this tick's draw of
the fade's ramp. The factor is 1 straight ahead, so ``camera.range`` keeps
its meaning: the 50 % detection distance straight ahead.

Each factor is measured: the range study (``benchmarks/camera_range.py``,
docs/perception.md) gives the detection rate ``p(d)`` at each distance and
bearing; a bearing's *equivalent range* is the area under its curve,
``∫ p(d) dd`` (trapezoids, ``p`` taken as flat from the robot to the first
distance) — for a linear ramp centred on ``R`` that area is exactly ``R``,
so the profile replaces each bearing's curve by the ramp with the same
area. The factor is that range over the range straight ahead. Between the
measured bearings the factor is linear in ``cos(bearing)``, so the kernels
need no angle: ``cos(bearing) = (offset · heading) / distance``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import ConfigError

__all__ = ["BEARING_PROFILES", "BearingProfile", "bearing_profile", "profile_from_study"]

BearingProfile = tuple[tuple[float, float], ...]
"""``(bearing in degrees, factor)`` pairs, bearings rising from 0 to 180."""

BEARING_PROFILES: Final[dict[str, BearingProfile]] = {
    "uniform": (),
    "dots": (
        (0.0, 1.0),
        (17.0, 1.072),
        (30.0, 0.96),
        (45.0, 0.824),
        (60.0, 0.494),
        (73.0, 0.03),
        (90.0, 0.616),
        (129.0, 0.888),
        (180.0, 0.272),
    ),
}
"""The shipped profiles: ``uniform`` sees alike all round; ``dots`` is the DOTS robot's rig
measured by ``benchmarks/camera_range.py --rig dots`` (docs/perception/dots/range.json,
``profile_from_study``, factors to three decimals)."""


def profile_from_study(
    distances: Sequence[float], bearings: Sequence[float], rates: Sequence[Sequence[float]]
) -> BearingProfile:
    """The bearing profile of a range study: equivalent ranges over the one straight ahead.

    ``rates[i][j]`` is the detection rate at ``distances[i]`` and
    ``bearings[j]``; the first bearing must be 0 and the last 180.
    """
    d = np.asarray(distances, dtype=np.float64)
    b = np.asarray(bearings, dtype=np.float64)
    p = np.asarray(rates, dtype=np.float64)
    if b.size < 2 or b[0] != 0.0 or b[-1] != 180.0 or np.any(np.diff(b) <= 0):
        msg = f"bearings: {b.tolist()} do not rise from 0 to 180 degrees"
        raise ConfigError(msg)
    if p.shape != (d.size, b.size):
        msg = f"detection rates: shape {p.shape} is not distances x bearings {(d.size, b.size)}"
        raise ConfigError(msg)
    area = d[0] * p[0] + np.trapezoid(p, d, axis=0)
    if area[0] <= 0:
        msg = "detection rates: nothing is detected straight ahead"
        raise ConfigError(msg)
    return tuple((float(angle), float(a / area[0])) for angle, a in zip(b, area, strict=True))


def bearing_profile(name: str) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The kernels' form of profile ``name``: cosines (falling, 1 to -1) and factors.

    Empty arrays for ``uniform`` (no factor at all, so no arithmetic changes).
    """
    profile = BEARING_PROFILES[name]
    cosines = np.array([math.cos(math.radians(b)) for b, _ in profile], dtype=np.float64)
    if cosines.size:
        cosines[0], cosines[-1] = 1.0, -1.0  # exact ends: every cosine falls in a segment
    factors = np.array([f for _, f in profile], dtype=np.float64)
    cosines.flags.writeable = False
    factors.flags.writeable = False
    return cosines, factors
