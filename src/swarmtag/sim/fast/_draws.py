"""A tick's random numbers, in ``RandomSource``'s order, drawn whole or piece by piece.

The numbers a tick draws (``randomness.RandomSource``: the walk's and the
sidestep's directions of every robot, then its break-down draw, then its
radio draws, its camera noise and its sight draws per carrier) are cut into
*units*, one per robot and stream: units ``0 .. robots - 1`` are the robots'
motion numbers, the next ``robots`` their break-down draws, then the
radio's, the camera's and the sight's (a stream that is off has units that
draw nothing). Drawing units
``0 .. u``, then ``u .. draw_units(k)``, gives the same numbers as drawing them
all at once: a split run's threads take the next tick's units in turn while
they wait for each other (``_split``).
"""

from __future__ import annotations

import numpy as np

from swarmtag.sim.fast._jit import inlined, jit
from swarmtag.sim.fast._layout import Constants
from swarmtag.sim.fast._pcg import standard_normal, uniform
from swarmtag.sim.fast._scratch import Scratch
from swarmtag.sim.model.randomness import Stream

__all__ = ["DRAW_CHUNK", "STREAMS", "chunk_end", "draw", "draw_range", "draw_units"]

STREAMS = (Stream.MOTION, Stream.BREAKDOWN, Stream.RADIO, Stream.CAMERA, Stream.SIGHT)
"""The tick's streams, in the order they draw: the rows of a run's generator states."""
DRAW_CHUNK = 512
"""Numbers a thread draws at a time for a split run (about 5 µs: a waiting thread is back soon)."""


@inlined
def draw_units(k: Constants) -> int:
    """Units of a tick's numbers: one per robot and stream (five streams)."""
    return 5 * k.robots


@inlined
def _numbers_per_unit(stream: int, k: Constants) -> int:
    """Numbers one unit of ``stream`` draws (0: the stream is off)."""
    if stream == 0:
        return 4
    if stream == 1:
        return 1 if k.breakdown > 0 else 0
    if stream == 2:  # the streams' order: see the module docs
        return k.carriers if k.advertisement_loss > 0 else 0
    if stream == 3:
        return 2 * k.carriers if k.detection_noise > 0 else 0
    return k.carriers if k.camera_fade > 0 else 0


@inlined
def chunk_end(unit: int, numbers: int, k: Constants) -> int:
    """End of the units from ``unit`` that draw about ``numbers`` numbers (within one stream)."""
    stream = unit // k.robots
    end = (stream + 1) * k.robots
    per_unit = _numbers_per_unit(stream, k)
    if per_unit == 0:
        return end
    return min(end, unit + max(1, numbers // per_unit))


_Settings = tuple[int, int, float, float, float, float, float]
_Buffers = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


@inlined
def _settings(k: Constants) -> _Settings:
    """What the draws need of the constants: robots, carriers, the realism rates, the fade."""
    return (
        k.robots,
        k.carriers,
        k.breakdown,
        k.advertisement_loss,
        k.detection_noise,
        k.camera_far,
        k.camera_fade,
    )


@inlined
def _buffers(r: int, x: Scratch) -> _Buffers:
    """Run ``r``'s buffers of a tick's numbers: walk, sidestep, break-down, radio, camera, sight."""
    return (
        x.walk_gaussians[r],
        x.sidestep_gaussians[r],
        x.breakdown_draw[r],
        x.radio_draw[r],
        x.noise[r],
        x.sight[r],
    )


@inlined
def _draw_numbers(
    first: int,
    stop: int,
    state: np.ndarray,
    settings: _Settings,
    buffers: _Buffers,
) -> None:
    """Units ``first .. stop - 1`` of a run's tick from its generators ``state`` into ``buffers``.

    ``state``: one row per stream in ``STREAMS``' order, advanced in place;
    each stream's state stays in registers while its units draw.
    """
    robots, carriers, breakdown, advertisement_loss, detection_noise, far, fade = settings
    walk, sidestep, breakdowns, radio, noise, sight = buffers
    high, low, inc_high, inc_low = state[0, 0], state[0, 1], state[0, 2], state[0, 3]
    for n in range(max(first, 0), min(stop, robots)):
        g0, high, low = standard_normal(high, low, inc_high, inc_low)
        g1, high, low = standard_normal(high, low, inc_high, inc_low)
        g2, high, low = standard_normal(high, low, inc_high, inc_low)
        g3, high, low = standard_normal(high, low, inc_high, inc_low)
        walk[n, 0], walk[n, 1] = g0, g1  # normalised where used: most robots keep their heading
        sidestep[n, 0], sidestep[n, 1] = g2, g3
    state[0, 0], state[0, 1] = high, low
    if breakdown > 0:
        high, low, inc_high, inc_low = state[1, 0], state[1, 1], state[1, 2], state[1, 3]
        for n in range(max(first, robots) - robots, min(stop, 2 * robots) - robots):
            breakdowns[n], high, low = uniform(high, low, inc_high, inc_low)
        state[1, 0], state[1, 1] = high, low
    if advertisement_loss > 0:
        high, low, inc_high, inc_low = state[2, 0], state[2, 1], state[2, 2], state[2, 3]
        for n in range(max(first, 2 * robots) - 2 * robots, min(stop, 3 * robots) - 2 * robots):
            for c in range(carriers):
                radio[n, c], high, low = uniform(high, low, inc_high, inc_low)
        state[2, 0], state[2, 1] = high, low
    if detection_noise > 0:
        high, low, inc_high, inc_low = state[3, 0], state[3, 1], state[3, 2], state[3, 3]
        for n in range(max(first, 3 * robots) - 3 * robots, min(stop, 4 * robots) - 3 * robots):
            for c in range(carriers):
                g0, high, low = standard_normal(high, low, inc_high, inc_low)
                g1, high, low = standard_normal(high, low, inc_high, inc_low)
                noise[n, c, 0] = g0 * detection_noise
                noise[n, c, 1] = g1 * detection_noise
        state[3, 0], state[3, 1] = high, low
    if fade > 0:  # as RandomSource: how far each robot sees each carrier this tick
        high, low, inc_high, inc_low = state[4, 0], state[4, 1], state[4, 2], state[4, 3]
        for n in range(max(first, 4 * robots) - 4 * robots, min(stop, 5 * robots) - 4 * robots):
            for c in range(carriers):
                u, high, low = uniform(high, low, inc_high, inc_low)
                sight[n, c] = far - u * fade
        state[4, 0], state[4, 1] = high, low


@jit
def _draw_numbers_called(
    first: int,
    stop: int,
    state: np.ndarray,
    settings: _Settings,
    buffers: _Buffers,
) -> None:
    """``_draw_numbers`` compiled once, as a call: see ``draw_range``."""
    _draw_numbers(first, stop, state, settings, buffers)


@inlined
def draw_range(
    r: int, first: int, stop: int, streams: np.ndarray, k: Constants, x: Scratch
) -> None:
    """Units ``first .. stop - 1`` of run ``r``'s tick: read only by the robots' phases.

    ``streams[r]``: the run's generators (``_pcg``), one row per stream in
    ``STREAMS``' order, advanced in place. A call (its arrays, not the
    state's tuples): a split run draws from several places in its
    kernel, and one compiled copy keeps that kernel's compilation short;
    a chunk's numbers take far longer than the call.
    """
    _draw_numbers_called(first, stop, streams[r], _settings(k), _buffers(r, x))


@inlined
def draw(r: int, streams: np.ndarray, k: Constants, x: Scratch) -> None:
    """Every number of run ``r``'s tick, in the order ``RandomSource`` draws them.

    Inlined: a batch draws once a tick for each of its (often small) runs.
    """
    _draw_numbers(0, draw_units(k), streams[r], _settings(k), _buffers(r, x))
