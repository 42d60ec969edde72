"""The random-stream layout of SPEC §4.5, as documented in swarmtag.sim.model.randomness."""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.errors import ConfigError
from swarmtag.policy import Proximity
from swarmtag.sim import RandomSource, Realism, Scenario, make_params
from swarmtag.sim.model.randomness import Stream, stream, unit_vectors

REALISM = Realism(advertisement_loss=0.2, detection_noise=0.03, breakdown=0.01)


def test_streams_are_keyed_by_seed_run_and_purpose():
    a = stream(7, 3, Stream.MOTION).random(4)
    direct = np.random.default_rng(np.random.SeedSequence(7, spawn_key=(3, 1))).random(4)
    assert a.tolist() == direct.tolist()
    assert stream(7, 3, Stream.SCENE).random() != stream(7, 4, Stream.SCENE).random()


def test_tick_inputs_follow_the_documented_layout():
    params = make_params(Scenario(robots=3, carriers=7, realism=REALISM), Proximity())
    source = RandomSource(params, seed=5, run_ids=[2, 9])
    motion = [stream(5, run, Stream.MOTION) for run in (2, 9)]
    radio = [stream(5, run, Stream.RADIO) for run in (2, 9)]
    camera = [stream(5, run, Stream.CAMERA) for run in (2, 9)]
    breakdown = [stream(5, run, Stream.BREAKDOWN) for run in (2, 9)]
    for tick in range(1, 4):
        inputs = source.inputs(tick)
        for row in range(2):
            g = motion[row].standard_normal((3, 4))
            assert inputs.walk[row].tolist() == unit_vectors(g[:, 0:2]).tolist()
            assert inputs.sidestep[row].tolist() == unit_vectors(g[:, 2:4]).tolist()
            assert inputs.breakdown[row].tolist() == (breakdown[row].random(3) < 0.01).tolist()
            assert inputs.heard is not None
            assert inputs.heard[row].tolist() == (radio[row].random((3, 7)) >= 0.2).tolist()
            assert inputs.noise is not None
            noise = camera[row].standard_normal((3, 7, 2)) * 0.03
            assert inputs.noise[row].tolist() == noise.tolist()


@pytest.mark.parametrize("chunk", [1, 3, 64])
def test_pre_drawing_in_chunks_gives_the_same_numbers(chunk):
    params = make_params(Scenario(realism=REALISM), Proximity())
    reference = RandomSource(params, seed=1, run_ids=[0, 1], chunk=1)
    chunked = RandomSource(params, seed=1, run_ids=[0, 1], chunk=chunk)
    for tick in range(1, 10):
        a, b = reference.inputs(tick), chunked.inputs(tick)
        assert np.array_equal(a.walk, b.walk)
        assert np.array_equal(a.breakdown, b.breakdown)
        assert np.array_equal(a.heard, b.heard)
        assert np.array_equal(a.noise, b.noise)


def test_a_run_numbers_do_not_depend_on_the_batch():
    params = make_params(Scenario(), Proximity())
    batch = RandomSource(params, seed=0, run_ids=[4, 5, 6])
    alone = RandomSource(params, seed=0, run_ids=[5])
    for tick in range(1, 6):
        assert np.array_equal(batch.inputs(tick).walk[1], alone.inputs(tick).walk[0])


def test_disabled_options_draw_nothing_and_leave_motion_unchanged():
    quiet = RandomSource(make_params(Scenario(), Proximity()), seed=3, run_ids=[0])
    noisy = RandomSource(make_params(Scenario(realism=REALISM), Proximity()), seed=3, run_ids=[0])
    a, b = quiet.inputs(1), noisy.inputs(1)
    assert a.heard is None
    assert a.noise is None
    assert not a.breakdown.any()
    assert np.array_equal(a.walk, b.walk)


def test_ticks_must_be_asked_in_order():
    source = RandomSource(make_params(Scenario(), Proximity()), seed=0, run_ids=[0])
    source.inputs(1)
    with pytest.raises(ConfigError, match="tick: asked for 3"):
        source.inputs(3)


def test_unit_vectors():
    v = unit_vectors(np.random.default_rng(0).standard_normal((100, 2)))
    assert np.allclose(np.sqrt((v * v).sum(axis=1)), 1.0)
    assert unit_vectors(np.zeros((1, 2))).tolist() == [[1.0, 0.0]]


def test_bad_seed_is_refused():
    with pytest.raises(ConfigError, match="seed: -1 is not an integer in 0-9223372036854775807"):
        RandomSource(make_params(Scenario(), Proximity()), seed=-1, run_ids=[0])
