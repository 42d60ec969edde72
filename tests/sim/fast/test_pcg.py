"""The compiled PCG64 gives numpy's numbers bit for bit: 64-bit words, uniforms, Gaussians."""

from __future__ import annotations

import numba
import numpy as np
import pytest

from swarmtag.sim.fast._pcg import (
    STATE_WORDS,
    next_uint64,
    standard_normal,
    states_of,
    uniform,
)
from swarmtag.sim.model.randomness import Stream, stream

WORDS, UNIFORMS, GAUSSIANS = 0, 1, 2


@numba.njit(cache=False)  # not cached: machine code cached here would keep old _pcg code
def _fill(state: np.ndarray, kind: int, out: np.ndarray) -> None:
    """``out`` drawn from ``state`` (advanced in place), as ``kind`` says."""
    high, low, inc_high, inc_low = state[0], state[1], state[2], state[3]
    for i in range(out.shape[0]):
        if kind == WORDS:
            word, high, low = next_uint64(high, low, inc_high, inc_low)
            out[i] = word
        elif kind == UNIFORMS:
            value, high, low = uniform(high, low, inc_high, inc_low)
            out[i] = value
        else:
            value, high, low = standard_normal(high, low, inc_high, inc_low)
            out[i] = value
    state[0] = high
    state[1] = low


def _expected(generator: np.random.Generator, kind: int, size: int) -> np.ndarray:
    if kind == WORDS:
        return generator.bit_generator.random_raw(size)  # type: ignore[no-any-return]
    if kind == UNIFORMS:
        return generator.random(size)
    return generator.standard_normal(size)


@pytest.mark.parametrize("kind", [WORDS, UNIFORMS, GAUSSIANS], ids=["words", "uniform", "normal"])
@pytest.mark.parametrize("seed", [0, 7, 2**63 + 5])
def test_numbers_are_numpys_bit_for_bit(kind, seed):
    generator = stream(seed, 3, Stream.MOTION)
    state = states_of([generator])[0]
    size = 1_000_000  # about 7,000 rejections, tens of them in the ziggurat's tail
    out = np.empty(size, dtype=np.uint64 if kind == WORDS else np.float64)
    _fill(state, kind, out)
    expected = _expected(generator, kind, size)
    np.testing.assert_array_equal(out.view(np.uint64), expected.view(np.uint64))  # -0.0 too
    np.testing.assert_array_equal(state, states_of([generator])[0])  # the same place after
    if kind == GAUSSIANS:  # the ziggurat's tail and its rejections were taken
        assert np.abs(out).max() > 3.6541528853610088  # beyond the base layer's edge r
        assert 0.99 < out.std() < 1.01


def test_draws_continue_from_the_generators_place():
    generator = np.random.default_rng(11)
    generator.standard_normal(5)
    state = states_of([generator])[0]
    out = np.empty(1000)
    _fill(state, GAUSSIANS, out)
    np.testing.assert_array_equal(out, generator.standard_normal(1000))


def test_states_of_lays_out_each_generators_words():
    generators = [np.random.default_rng(seed) for seed in (1, 2)]
    states = states_of(generators)
    assert states.shape == (2, STATE_WORDS)
    assert states.dtype == np.uint64
    for row, generator in zip(states, generators, strict=True):
        words = generator.bit_generator.state["state"]
        assert (int(row[0]) << 64) | int(row[1]) == words["state"]
        assert (int(row[2]) << 64) | int(row[3]) == words["inc"]


def test_other_bit_generators_are_refused():
    with pytest.raises(ValueError, match="PCG64 generators, not MT19937"):
        states_of([np.random.Generator(np.random.MT19937(1))])
