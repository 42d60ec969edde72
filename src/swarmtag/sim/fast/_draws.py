"""A tick's random numbers, in ``RandomSource``'s order, drawn whole or piece by piece.

The numbers a tick draws (``randomness.RandomSource``: the walk's and the
sidestep's directions of every robot, then its break-down draw, then its
radio draws and its camera noise per carrier) are cut into *units*, one per
robot and stream: units ``0 .. robots - 1`` are the robots' motion numbers,
the next ``robots`` their break-down draws, then the radio's, then the
camera's (a stream that is off has units that draw nothing). Drawing units
``0 .. u``, then ``u .. draw_units(k)``, gives the same numbers as drawing them
all at once: a split run's threads take the next tick's units in turn while
they wait for each other (``_split``).
"""

from __future__ import annotations

import math

import numpy as np

from swarmtag.sim.fast._jit import inlined, jit
from swarmtag.sim.fast._layout import Constants, Scratch
from swarmtag.sim.fast._pcg import standard_normal, uniform
from swarmtag.sim.randomness import Stream

__all__ = ["DRAW_CHUNK", "STREAMS", "chunk_end", "draw", "draw_range", "draw_units"]

STREAMS = (Stream.MOTION, Stream.BREAKDOWN, Stream.RADIO, Stream.CAMERA)
"""The tick's streams, in the order they draw: the rows of a run's generator states."""
DRAW_CHUNK = 512
"""Numbers a thread draws at a time for a split run (about 5 µs: a waiting thread is back soon)."""


@jit
def _unit(g0: float, g1: float) -> tuple[float, float]:
    """``randomness.unit_vectors`` for one pair of Gaussian numbers."""
    length = math.sqrt(g0 * g0 + g1 * g1)
    if length == 0:
        return 1.0, 0.0
    return g0 / length, g1 / length


@inlined
def draw_units(k: Constants) -> int:
    """Units of a tick's numbers: one per robot and stream (four streams)."""
    return 4 * k.robots


@inlined
def _numbers_per_unit(stream: int, k: Constants) -> int:
    """Numbers one unit of ``stream`` draws (0: the stream is off)."""
    if stream == 0:
        return 4
    if stream == 1:
        return 1 if k.breakdown > 0 else 0
    if stream == 2:  # the streams' order: see the module docs
        return k.carriers if k.advertisement_loss > 0 else 0
    return 2 * k.carriers if k.detection_noise > 0 else 0


@inlined
def chunk_end(unit: int, numbers: int, k: Constants) -> int:
    """End of the units from ``unit`` that draw about ``numbers`` numbers (within one stream)."""
    stream = unit // k.robots
    end = (stream + 1) * k.robots
    per_unit = _numbers_per_unit(stream, k)
    if per_unit == 0:
        return end
    return min(end, unit + max(1, numbers // per_unit))


@inlined
def draw_range(
    r: int, first: int, stop: int, streams: np.ndarray, k: Constants, x: Scratch
) -> None:
    """Units ``first .. stop - 1`` of run ``r``'s tick: read only by the robots' phases.

    ``streams[r]``: the run's generators (``_pcg``), one row per stream in
    ``STREAMS``' order, advanced in place; each stream's state stays in
    registers while its units draw.
    """
    robots = k.robots
    state = streams[r]
    high, low, inc_high, inc_low = state[0, 0], state[0, 1], state[0, 2], state[0, 3]
    for n in range(max(first, 0), min(stop, robots)):
        g0, high, low = standard_normal(high, low, inc_high, inc_low)
        g1, high, low = standard_normal(high, low, inc_high, inc_low)
        g2, high, low = standard_normal(high, low, inc_high, inc_low)
        g3, high, low = standard_normal(high, low, inc_high, inc_low)
        x.walk_in[r, n, 0], x.walk_in[r, n, 1] = _unit(g0, g1)
        x.sidestep_in[r, n, 0], x.sidestep_in[r, n, 1] = _unit(g2, g3)
    state[0, 0], state[0, 1] = high, low
    if k.breakdown > 0:
        high, low, inc_high, inc_low = state[1, 0], state[1, 1], state[1, 2], state[1, 3]
        for n in range(max(first, robots) - robots, min(stop, 2 * robots) - robots):
            x.breakdown_draw[r, n], high, low = uniform(high, low, inc_high, inc_low)
        state[1, 0], state[1, 1] = high, low
    if k.advertisement_loss > 0:
        high, low, inc_high, inc_low = state[2, 0], state[2, 1], state[2, 2], state[2, 3]
        for n in range(max(first, 2 * robots) - 2 * robots, min(stop, 3 * robots) - 2 * robots):
            for c in range(k.carriers):
                x.radio_draw[r, n, c], high, low = uniform(high, low, inc_high, inc_low)
        state[2, 0], state[2, 1] = high, low
    if k.detection_noise > 0:
        high, low, inc_high, inc_low = state[3, 0], state[3, 1], state[3, 2], state[3, 3]
        for n in range(max(first, 3 * robots) - 3 * robots, min(stop, 4 * robots) - 3 * robots):
            for c in range(k.carriers):
                g0, high, low = standard_normal(high, low, inc_high, inc_low)
                g1, high, low = standard_normal(high, low, inc_high, inc_low)
                x.noise[r, n, c, 0] = g0 * k.detection_noise
                x.noise[r, n, c, 1] = g1 * k.detection_noise
        state[3, 0], state[3, 1] = high, low


@inlined
def draw(r: int, streams: np.ndarray, k: Constants, x: Scratch) -> None:
    """Every number of run ``r``'s tick, in the order ``RandomSource`` draws them."""
    draw_range(r, 0, draw_units(k), streams, k, x)
