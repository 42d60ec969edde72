"""A scanner's sightings as the robot-I/O ``tag_states`` sensor (issue 11: scanner -> robot I/O)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from swarmtag.errors import ConfigError
from swarmtag.robot import Ranging, TagCache, TagStates, tag_states
from swarmtag.tag import TagState, TagStatus
from swarmtag.tag.backends import Sighting
from swarmtag.tag.backends.fake import FakeScanner
from tests.robot.fake_io import FakeIO


class Clock:
    def __init__(self, now: float = 100.0) -> None:
        self.now = now

    def __call__(self) -> float:
        return self.now


def heard(marker: int, seen_at: float, *, urgency: int = 4, status=TagStatus.AWAITING_PICKUP):
    state = TagState(urgency=urgency, status=status, destination=1, marker=marker)
    return Sighting(marker, state, -60, seen_at, f"AA:{marker:02X}")


def advert(urgency: int, status: int, marker: int) -> dict[int, bytes]:
    return {0xFFFF: bytes([urgency, status, 3, marker])}


def test_sightings_become_arrays_by_marker_with_ages_in_ticks():
    sightings = {0: heard(0, 99.95, urgency=9), 2: heard(2, 99.0, status=TagStatus.PICKED_UP)}
    states = tag_states(sightings, carriers=4, now=100.0, tick=0.1)
    assert isinstance(states, TagStates)
    assert states.status.tolist() == [1, -1, 2, -1]
    assert states.urgency.tolist() == [9, 0, 4, 0]
    assert states.age.tolist() == [0, -1, 10, -1]  # 0.05 s: this tick; 1.0 s: 10 ticks
    assert (states.status.dtype, states.urgency.dtype, states.age.dtype) == (
        np.int8,
        np.int8,
        np.int64,
    )  # the dtypes of the simulated robot's cache (sim.state known_status / known_urgency)
    assert tag_states(list(sightings.values()), carriers=4, now=100.0, tick=0.1).age.tolist() == [
        0,
        -1,
        10,
        -1,
    ]


def test_a_sighting_from_the_future_is_age_0():
    assert tag_states([heard(1, 100.5)], carriers=2, now=100.0, tick=0.1).age.tolist() == [-1, 0]


def test_the_cache_remembers_what_the_scanner_aged_out():
    clock = Clock()
    scanner = FakeScanner(clock=clock, max_age=5.0)
    cache = TagCache(carriers=3, tick=0.5)
    scanner.feed("AA:01", advert(7, 1, 1))
    assert cache.read(scanner).status.tolist() == [-1, 1, -1]
    clock.now = 110.0  # 10 s later: the scanner dropped it, the robot still knows it
    assert scanner.states() == {}
    states = cache.read(scanner)
    assert (states.status.tolist(), states.urgency.tolist(), states.age.tolist()) == (
        [-1, 1, -1],
        [0, 7, 0],
        [-1, 20, -1],
    )
    scanner.feed("AA:01", advert(7, 2, 1))  # heard again, picked up now
    assert cache.read(scanner).status.tolist() == [-1, 2, -1]
    assert cache.read(scanner).age.tolist() == [-1, 0, -1]


def test_an_older_sighting_never_replaces_a_newer_one():
    cache = TagCache(carriers=2, tick=0.1)
    assert cache.update([heard(0, 50.0, urgency=8)]) == 1
    assert cache.update([heard(0, 40.0, urgency=1)]) == 0
    assert cache.update([heard(0, 50.0, urgency=1)]) == 0  # the same moment again: kept as is
    assert cache.states(60.0).urgency.tolist() == [8, 0]


def test_markers_beyond_the_sites_carriers_are_left_out_and_noted():
    cache = TagCache(carriers=2, tick=0.1)
    assert cache.update([heard(1, 1.0), heard(7, 1.0), heard(200, 1.0)]) == 1
    assert cache.ignored == {7, 200}
    assert cache.states(1.0).status.tolist() == [-1, 1]


@pytest.mark.parametrize(
    ("call", "words"),
    [
        (lambda: TagCache(carriers=0, tick=0.1), "carriers"),
        (lambda: TagCache(carriers=257, tick=0.1), "carriers"),
        (lambda: TagCache(carriers=3, tick=0.0), "tick"),
        (lambda: TagCache(carriers=3, tick=float("nan")), "tick"),
        (lambda: tag_states({}, carriers=3, now=float("inf"), tick=0.1), "now"),
        (lambda: tag_states([object()], carriers=3, now=0.0, tick=0.1), "Sighting"),
        (lambda: tag_states(5, carriers=3, now=0.0, tick=0.1), "sightings"),
        (lambda: TagCache(carriers=3, tick=0.1).read(object()), "Scanner"),
    ],
)
def test_bad_arguments_are_one_config_error(call, words):
    with pytest.raises(ConfigError, match=words):
        call()


def test_the_behaviour_tree_selects_from_what_the_scanner_heard():
    """A robot whose ``tag_states`` is the cache over a scanner: the urgent carrier wins."""
    pytest.importorskip("py_trees")
    from swarmtag.policy import Urgency
    from swarmtag.robot import ControllerConfig, Report
    from swarmtag.sim import Scenario, make_params
    from tests.robot.test_behaviours import Robot

    class RadioRobot(FakeIO):
        def tag_states(self) -> TagStates:
            return cache.read(scanner)

    clock = Clock()
    scanner = FakeScanner(clock=clock)
    cache = TagCache(carriers=2, tick=0.1)
    io = RadioRobot(carriers=2)
    io.carrier_pos[:] = [(2.5, 2.0), (0.5, 2.0)]  # 0 near, 1 far
    io.known[:] = True
    scanner.feed("AA:00", advert(1, 1, 0))
    scanner.feed("AA:01", advert(9, 1, 1))
    scanner.feed("PHONE", {0x004C: b"\x02\x15"})
    params = make_params(Scenario(ticks=1000), Urgency(alpha=0.7))
    config = replace(
        ControllerConfig.from_params(params),
        avoid_taken_faces=False,
        markers=np.arange(2, dtype=np.int64),
    )
    bot = Robot(config, io)
    try:
        bot.tick()
    finally:
        bot.close()
    assert io.target == 1
    assert io.reports[0] == (Report.SELECT, 1, 9.0)


def test_a_ranging_cache_turns_each_new_sightings_rssi_into_a_running_distance():
    awaiting = TagState(5, TagStatus.AWAITING_PICKUP, 1, 1)
    ranging = Ranging(rssi_at_1m=-60.0, path_loss_exponent=2.0, smoothing=0.5)
    cache = TagCache(carriers=3, tick=0.1, ranging=ranging)
    cache.update([Sighting(1, awaiting, -80, 1.0, "AA")])  # 10 m
    first = cache.states(1.0)
    assert first.distance is not None
    assert np.isnan(first.distance[[0, 2]]).all()  # never heard
    assert first.distance[1] == pytest.approx(10.0)
    cache.update([Sighting(1, awaiting, -66, 2.0, "AA")])  # 2 m: halfway from 10
    assert cache.states(2.0).distance[1] == pytest.approx(6.0, rel=1e-3)
    cache.update([Sighting(1, awaiting, -40, 1.5, "AA")])  # older than held: ignored
    assert cache.states(2.0).distance[1] == pytest.approx(6.0, rel=1e-3)
    assert TagCache(carriers=3, tick=0.1).states(2.0).distance is None  # not ranging


def test_ranging_refuses_impossible_settings():
    with pytest.raises(ConfigError, match="path_loss_exponent"):
        Ranging(path_loss_exponent=0.5)
    with pytest.raises(ConfigError, match="smoothing"):
        Ranging(smoothing=0.0)
    with pytest.raises(ConfigError, match="ranging"):
        TagCache(carriers=3, tick=0.1, ranging="-60 dBm")
