"""The response threshold: its take-up is T(s) = s^2 / (s^2 + theta^2), measured."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from swarmtag.policy import Threshold
from swarmtag.sim.allocators.threshold import ThresholdChooser
from swarmtag.sim.builtin.decide import Selection


def test_take_up_matches_the_threshold_function_on_a_large_sample():
    runs, carriers, theta = 40_000, 10, 4.0
    rng = np.random.default_rng(7)
    urgency = np.broadcast_to(np.arange(carriers, dtype=np.int8), (runs, 1, carriers)).copy()
    s = SimpleNamespace(known_urgency=urgency, blocked_until=np.zeros((runs, 1, carriers), int))
    params = SimpleNamespace(carriers=carriers, cooldown_ticks=50, markers=np.arange(carriers))
    inputs = SimpleNamespace(allocation=rng.random((runs, 1, carriers + 1)))
    available = np.ones((runs, 1, carriers), bool)
    distance = np.broadcast_to(np.linspace(3.0, 0.3, carriers), (runs, 1, carriers))
    selection = Selection(s, None, np.ones((runs, 1), bool), available, distance, inputs, params, 9)
    choice, candidates = ThresholdChooser(Threshold(theta=theta))(selection)
    taken = s.blocked_until == 0
    assert (s.blocked_until[~taken] == 9 + 50).all()  # passed over for the cooldown
    expected = Threshold(theta=theta).take_up(np.arange(carriers))
    measured = taken.mean(axis=(0, 1))
    spread = np.sqrt(expected * (1 - expected) / runs)
    assert np.all(np.abs(measured - expected) < 4 * spread + 1e-12)
    assert expected[0] == pytest.approx(1 / 17)  # s = 1
    assert expected[3] == pytest.approx(0.5)  # s = theta
    # the nearest taken: the largest index taken (distances fall along the carriers)
    nearest = np.where(taken.any(axis=-1), carriers - 1 - np.argmax(taken[..., ::-1], axis=-1), -1)
    assert np.array_equal(choice, nearest)
    assert (candidates == carriers).all()


def test_the_stimulus_is_urgency_plus_one():
    take_up = Threshold(theta=1.0).take_up(np.array([0.0, 9.0]))
    assert take_up.tolist() == pytest.approx([0.5, 100 / 101])
