"""Snapshots and animations drawn from recorded trajectories."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from swarmtag.errors import ConfigError
from swarmtag.policy import Urgency
from swarmtag.sim import Mode, Scenario, simulate
from swarmtag.sim.outputs.render import animate, default_snapshot_tick, snapshot


@pytest.fixture(scope="module")
def traj():
    result = simulate(
        Scenario(ticks=300), Urgency(alpha=0.7), seed=3, runs=2, run_offset=5, record=True
    )
    assert result.trajectories is not None
    return result.trajectories


def test_default_tick_shows_the_most_carriers_being_pursued_or_carried(traj):
    tick = default_snapshot_tick(traj, 6)
    modes, targets = traj.robot_mode[1], traj.robot_target[1]
    busy = (modes >= Mode.PREDOCK) & (modes <= Mode.RELEASE) & (targets >= 0)
    engaged = np.array([len(set(targets[t][busy[t]].tolist())) for t in range(len(modes))])
    assert engaged[tick] == engaged.max() >= 2
    assert tick == int(np.flatnonzero(engaged == engaged.max())[0])  # earliest on ties


def test_snapshot_writes_a_png_at_the_asked_tick(traj, tmp_path):
    path = tmp_path / "s.png"
    assert snapshot(traj, path, run=5, tick=0) == 0
    with Image.open(path) as image:
        assert image.format == "PNG"


@pytest.mark.parametrize(
    ("kwargs", "words"), [({"run": 0}, "run: 0"), ({"run": 5, "tick": 301}, "tick: 301")]
)
def test_snapshot_refuses_what_was_not_recorded(traj, tmp_path, kwargs, words):
    with pytest.raises(ConfigError, match=words):
        snapshot(traj, tmp_path / "s.png", **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_animation_frames_cover_the_run(traj, tmp_path):
    path = tmp_path / "a.gif"
    frames = animate(traj, path, run=5, every=50)
    end = traj.ended_at[0] if traj.ended_at[0] >= 0 else traj.ticks
    assert frames == len(range(0, int(end) + 1, 50)) + (int(end) % 50 != 0)
    with Image.open(path) as movie:
        assert movie.n_frames == frames


def test_animation_format_checked_first(traj, tmp_path):
    with pytest.raises(ConfigError, match=r"\.gif or \.mp4"):
        animate(traj, tmp_path / "a.avi", run=5)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(("robots", "drawn"), [(12, True), (13, False)])
def test_perception_ranges_are_drawn_around_a_dozen_robots_at_most(robots, drawn, tmp_path):
    from swarmtag.sim.config.profiles import (
        load_profile,
    )  # split perception: one range pair per robot
    from swarmtag.sim.outputs.render import _draws_ranges

    scenario = load_profile("paper-sim").scenario({"robots": robots, "carriers": 7, "ticks": 5})
    recorded = simulate(scenario, Urgency(alpha=0.7), seed=0, runs=1, record=True).trajectories
    assert recorded is not None
    assert _draws_ranges(recorded) is drawn
    snapshot(recorded, tmp_path / "crowd.png", tick=1)
    assert (tmp_path / "crowd.png").stat().st_size > 0
