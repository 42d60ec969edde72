"""Herding without livelock: robots that see a predock point taken go to another free face.

The case of docs/simulator.md: run 53 of seed 0 with far sight (disc R = 3.6 m)
and urgency alpha = 9. Without the remedy all three robots crowd one east
predock point, none reaches it, all time out in the same tick every 300
ticks and come back after the cool-down: a periodic livelock that leaves 3
carriers undelivered. With ``motion.avoid_taken_faces`` the crowd spreads
over the free faces, one robot docks and the others hear the lift and leave.
"""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.policy import Proximity, Urgency
from swarmtag.sim import Scene, make_params, simulate
from swarmtag.sim.config.profiles import load_profile
from tests.sim.helpers import event_rows, run_script


def _run_53(avoid: bool):
    scenario = load_profile("base").scenario(
        {"detection_radius": 3.6, "motion.avoid_taken_faces": avoid}
    )
    return simulate(scenario, Urgency(alpha=9.0), seed=0, runs=1, run_offset=53)


def lockstep_timeouts(events) -> int:
    """Ticks in which two or more robots timed out together (the livelock's signature)."""
    times = events.time[events.kind == "timeout"]
    _, counts = np.unique(times, return_counts=True)
    return int((counts >= 2).sum())


def test_the_old_face_rule_livelocks_in_run_53():
    result = _run_53(avoid=False)
    assert result.undelivered.tolist() == [3]
    assert lockstep_timeouts(result.events) >= 5  # every 300 ticks, all three at once


def test_avoiding_taken_faces_ends_the_livelock_of_run_53():
    result = _run_53(avoid=True)
    assert result.undelivered.tolist() == [0]
    assert lockstep_timeouts(result.events) == 0
    assert int(result.end_tick[0]) < 1000


@pytest.mark.parametrize(("avoid", "face"), [(False, 0), (True, 1)])
def test_a_robot_does_not_choose_a_face_it_sees_taken(avoid, face):
    # robot 1 stands on the east predock point of the carrier; robot 0 comes from the
    # east-north-east, so the east face is nearest to it, the north face next
    params = make_params(
        load_profile("base").scenario(
            {"robots": 2, "carriers": 1, "motion.avoid_taken_faces": avoid}
        ),
        Proximity(),
    )
    scene = Scene.build(
        robots=[(1.5, 2.3), (0.6 + 0.3525, 2.0)],
        heading=[(-1.0, 0.0), (0.0, 1.0)],
        carriers=[(0.6, 2.0)],
        urgency=[4],
    )
    result = run_script(params, scene, 1, walk=[[0.0, 1.0], [0.0, 1.0]])
    assert event_rows(result)[:1] == [(1, "select", 0, 0)]
    assert int(result.final_state.face[0, 0]) == face
