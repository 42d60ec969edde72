"""A tick's random numbers drawn chunk by chunk are the numbers drawn at once, stream by stream."""

from __future__ import annotations

from dataclasses import replace

import numba
import numpy as np
import pytest

from swarmtag.policy import Urgency
from swarmtag.sim import Camera, Realism, Scenario
from swarmtag.sim.fast._draws import STREAMS, chunk_end, draw, draw_range, draw_units
from swarmtag.sim.fast._geometry import unit_vector
from swarmtag.sim.fast._layout import Constants, constants_of
from swarmtag.sim.fast._pcg import states_of
from swarmtag.sim.fast._scratch import Scratch, scratch_for
from swarmtag.sim.model.params import make_params
from swarmtag.sim.model.randomness import stream, unit_vectors


@numba.njit(cache=False)  # not cached: machine code cached here would keep old _draws code
def _draw_whole(streams: np.ndarray, k: Constants, x: Scratch) -> None:
    """Run 0's tick drawn at once."""
    draw(0, streams, k, x)


@numba.njit(cache=False)
def _draw_in_chunks(streams: np.ndarray, numbers: int, k: Constants, x: Scratch) -> int:
    """Run 0's tick drawn about ``numbers`` numbers at a time; returns how many chunks."""
    unit = 0
    chunks = 0
    while unit < draw_units(k):
        stop = chunk_end(unit, numbers, k)
        draw_range(0, unit, stop, streams, k, x)
        unit = stop
        chunks += 1
    return chunks


def _states(seed: int) -> np.ndarray:
    """Run 0's generator states of the tick's five streams, in ``draw``'s order."""
    return states_of([stream(seed, 0, purpose) for purpose in STREAMS])[None]


DRAWN = ("walk_gaussians", "sidestep_gaussians", "breakdown_draw", "radio_draw", "noise", "sight")


@pytest.mark.parametrize("numbers", [1, 7, 512, 10_000])
@pytest.mark.parametrize("realism", [False, True], ids=["motion-only", "every-stream"])
def test_chunks_draw_the_numbers_of_one_draw(numbers, realism):
    scenario = Scenario.default(9, 5)
    if realism:
        imperfect = Realism(breakdown=0.001, advertisement_loss=0.2, detection_noise=0.03)
        scenario = replace(scenario, realism=imperfect, camera=Camera(range=1.5, fade=1.0))
    params = make_params(scenario, Urgency(alpha=0.7))
    k = constants_of(params)
    whole, chunked = scratch_for(1, k, 256), scratch_for(1, k, 256)
    states = _states(3), _states(3)
    _draw_whole(states[0], k, whole)
    chunks = _draw_in_chunks(states[1], numbers, k, chunked)
    for name in DRAWN:
        np.testing.assert_array_equal(getattr(whole, name), getattr(chunked, name), err_msg=name)
    assert np.abs(whole.walk_gaussians).sum() > 0  # the buffers were written
    if realism:
        assert np.abs(whole.noise).sum() > 0
        assert whole.radio_draw.sum() > 0
        assert whole.breakdown_draw.sum() > 0
        assert whole.sight.sum() > 0
    np.testing.assert_array_equal(states[0], states[1])  # every stream left at the same place
    assert not np.array_equal(states[0], _states(3))  # and moved on
    assert chunks >= len(STREAMS)  # a chunk never spans two streams
    if numbers < 4 * 9:  # fewer numbers than the motion stream's: it was cut
        assert chunks > len(STREAMS)


def test_a_tick_draws_the_reference_streams_numbers():
    imperfect = Realism(breakdown=0.001, advertisement_loss=0.2, detection_noise=0.03)
    fading = Camera(range=1.5, fade=1.0)
    scenario = replace(Scenario.default(9, 5), realism=imperfect, camera=fading)
    params = make_params(scenario, Urgency(alpha=0.7))
    k = constants_of(params)
    x = scratch_for(1, k, 256)
    states = _states(5)
    for _ in range(3):  # the third tick: each stream carries on where the last tick left it
        _draw_whole(states, k, x)
    n, c = params.robots, params.carriers
    motion, breakdown, radio, camera, sight = (stream(5, 0, purpose) for purpose in STREAMS)
    gaussians = motion.standard_normal((3, n, 4))[2]
    np.testing.assert_array_equal(x.walk_gaussians[0], gaussians[:, :2])
    np.testing.assert_array_equal(x.sidestep_gaussians[0], gaussians[:, 2:])
    np.testing.assert_array_equal(x.breakdown_draw[0], breakdown.random((3, n))[2])
    np.testing.assert_array_equal(x.radio_draw[0], radio.random((3, n, c))[2])
    noise = camera.standard_normal((3, n, c, 2))[2] * params.detection_noise
    np.testing.assert_array_equal(x.noise[0], noise)
    reach = params.camera_far - sight.random((3, n, c))[2] * params.camera_fade
    np.testing.assert_array_equal(x.sight[0], reach)


@numba.njit(cache=False)  # not cached: machine code cached here would keep old geometry code
def _unit_vectors(pairs: np.ndarray) -> np.ndarray:
    out = np.empty_like(pairs)
    for i in range(pairs.shape[0]):
        out[i, 0], out[i, 1] = unit_vector(pairs[i, 0], pairs[i, 1])
    return out


def test_a_pair_of_gaussian_numbers_becomes_the_reference_s_unit_vector():
    pairs = np.random.default_rng(3).standard_normal((500, 2))
    pairs[:3] = [[0.0, 0.0], [-0.0, 2.5], [1e-300, -1e-300]]  # no direction; an axis; underflow
    compiled = _unit_vectors(pairs)
    np.testing.assert_array_equal(compiled, unit_vectors(pairs))
    assert compiled[0].tolist() == [1.0, 0.0]
