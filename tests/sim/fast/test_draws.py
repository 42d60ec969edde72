"""A tick's random numbers drawn chunk by chunk are the numbers drawn at once, stream by stream."""

from __future__ import annotations

from dataclasses import replace

import numba
import numpy as np
import pytest

from swarmtag.policy import Urgency
from swarmtag.sim import Realism, Scenario
from swarmtag.sim.fast._draws import chunk_end, draw, draw_range, draw_units
from swarmtag.sim.fast._layout import Constants, Scratch, constants_of, scratch_for
from swarmtag.sim.params import make_params
from swarmtag.sim.randomness import Stream, stream


@numba.njit(cache=False)  # not cached: machine code cached here would keep old _draws code
def _draw_whole(generators: tuple, k: Constants, x: Scratch) -> None:
    """Run 0's tick drawn at once."""
    motion, breakdown, radio, camera = generators
    draw(0, motion, breakdown, radio, camera, k, x)


@numba.njit(cache=False)
def _draw_in_chunks(generators: tuple, numbers: int, k: Constants, x: Scratch) -> int:
    """Run 0's tick drawn about ``numbers`` numbers at a time; returns how many chunks."""
    motion, breakdown, radio, camera = generators
    unit = 0
    chunks = 0
    while unit < draw_units(k):
        stop = chunk_end(unit, numbers, k)
        draw_range(0, unit, stop, motion, breakdown, radio, camera, k, x)
        unit = stop
        chunks += 1
    return chunks


STREAMS = (Stream.MOTION, Stream.BREAKDOWN, Stream.RADIO, Stream.CAMERA)


def _generators(seed: int) -> tuple[np.random.Generator, ...]:
    """Run 0's generators of the tick's four streams, in ``draw``'s order."""
    return tuple(stream(seed, 0, purpose) for purpose in STREAMS)


DRAWN = ("walk_in", "sidestep_in", "breakdown_draw", "radio_draw", "noise")


@pytest.mark.parametrize("numbers", [1, 7, 512, 10_000])
@pytest.mark.parametrize("realism", [False, True], ids=["motion-only", "every-stream"])
def test_chunks_draw_the_numbers_of_one_draw(numbers, realism):
    scenario = Scenario.default(9, 5)
    if realism:
        imperfect = Realism(breakdown=0.001, advertisement_loss=0.2, detection_noise=0.03)
        scenario = replace(scenario, realism=imperfect)
    params = make_params(scenario, Urgency(alpha=0.7))
    k = constants_of(params)
    whole, chunked = scratch_for(1, k, 256), scratch_for(1, k, 256)
    generators = _generators(3), _generators(3)
    _draw_whole(generators[0], k, whole)
    chunks = _draw_in_chunks(generators[1], numbers, k, chunked)
    for name in DRAWN:
        np.testing.assert_array_equal(getattr(whole, name), getattr(chunked, name), err_msg=name)
    assert np.abs(whole.walk_in).sum() > 0  # the buffers were written
    if realism:
        assert np.abs(whole.noise).sum() > 0
        assert whole.radio_draw.sum() > 0
        assert whole.breakdown_draw.sum() > 0
    for first, second in zip(*generators, strict=True):  # every stream left at the same place
        assert first.random() == second.random()
    assert chunks >= len(STREAMS)  # a chunk never spans two streams
    if numbers < 4 * 9:  # fewer numbers than the motion stream's: it was cut
        assert chunks > len(STREAMS)
