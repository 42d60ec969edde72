"""Adaptive alpha: lowered by the races a robot loses, drawn back by its lifts."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from swarmtag.policy import ADAPTIVE_START, Adaptive
from swarmtag.sim.allocators.adaptive import ADAPTIVE_FLOOR, AdaptiveChooser
from swarmtag.sim.model.state import Mode
from swarmtag.tag import TagStatus


def state(mode, target, heard):
    known = np.full((1, len(mode), 2), int(TagStatus.AWAITING_PICKUP), dtype=np.int8)
    known[0, :, 0] = heard
    return SimpleNamespace(
        mode=np.array([mode], dtype=np.int8), target=np.array([target]), known_status=known
    )


def test_a_lost_race_lowers_alpha_and_a_lift_draws_it_back():
    chooser = AdaptiveChooser(Adaptive(gain=0.5))
    picked = int(TagStatus.PICKED_UP)
    # robot 0 pursued carrier 0 and gave up on hearing it picked up; robot 1 timed out
    before = state([Mode.PREDOCK, Mode.PREDOCK, Mode.WALK], [0, 1, -1], picked)
    after = state([Mode.WALK, Mode.WALK, Mode.WALK], [-1, -1, -1], picked)
    chooser.settle(before, after, params=None, t=5, events=None)
    assert chooser.alpha.tolist() == [[ADAPTIVE_START * 0.5, ADAPTIVE_START, ADAPTIVE_START]]
    for _ in range(20):
        chooser.settle(before, after, params=None, t=6, events=None)
    assert chooser.alpha[0, 0] == ADAPTIVE_FLOOR
    lifting = state([Mode.LIFT, Mode.WALK, Mode.WALK], [0, -1, -1], picked)
    chooser.settle(lifting, lifting, params=None, t=7, events=None)
    assert chooser.alpha[0, 0] == pytest.approx(ADAPTIVE_FLOOR + 0.5 * (0.7 - ADAPTIVE_FLOOR))
    chooser.settle(lifting, lifting, params=None, t=8, events=None)  # still lifting: once per lift
    assert chooser.alpha[0, 0] == pytest.approx(ADAPTIVE_FLOOR + 0.5 * (0.7 - ADAPTIVE_FLOOR))
