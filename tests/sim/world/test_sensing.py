"""Split perception (SPEC §4.2a) on hand-built scenes: radio, camera, occlusion, memory.

Scenes use the base defaults (tick 0.1 s, step 0.05 m, carrier half side
0.1775 m, robot radius 0.125 m); robots walk along the scripted direction.
"""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.policy import Proximity, Urgency
from swarmtag.sim import Scene, TickInputs, initial_state, make_params, run_batch
from swarmtag.sim.config.profiles import load_profile
from swarmtag.sim.world.sensing import advertising
from swarmtag.tag import TagStatus
from tests.sim.helpers import event_rows, run_script

IDLE = int(TagStatus.IDLE)


def split_params(policy=None, *, robots=1, carriers=1, **values):
    """Base-profile parameters with split perception and ``values`` (dotted keys) on top."""
    layers = {"perception": "split", "robots": robots, "carriers": carriers, **values}
    return make_params(load_profile("base").scenario(layers), policy or Proximity())


def test_tags_advertise_once_per_interval_at_their_own_phase():
    params = split_params(
        carriers=3, **{"radio.interval": 0.25}
    )  # 0.1 s ticks: 2.5 ticks per advert
    phase = np.array([0, 50_000, 249_999])  # microseconds into the interval
    sent = np.array([advertising(phase, t, params) for t in range(1, 11)])
    # adverts at phase + k * 0.25 s fall in tick t when in ((t - 1) * 0.1, t * 0.1];
    # row i is tick i + 1
    assert np.flatnonzero(sent[:, 0]).tolist() == [2, 4, 7, 9]  # 0.25, 0.5, 0.75, 1.0 s
    assert np.flatnonzero(sent[:, 1]).tolist() == [0, 2, 5, 7]  # 0.05, 0.3, 0.55, 0.8 s
    assert np.flatnonzero(sent[:, 2]).tolist() == [2, 4, 7, 9]  # 0.249999 s, ...


@pytest.mark.parametrize(
    ("robot_x", "selected"),
    [(1.5, True), (np.nextafter(1.5, 2.0), False)],
    ids=["exactly-camera-range", "just-beyond"],
)
def test_camera_range_is_inclusive_and_the_radio_alone_is_not_enough(robot_x, selected):
    # radio range 10 m hears the tag every tick (interval = one tick); the camera sees 1 m
    params = split_params(**{"camera.range": 1.0, "radio.interval": 0.1})
    scene = Scene.build(robots=[(robot_x, 2.0)], carriers=[(0.5, 2.0)], urgency=[5])
    result = run_script(params, scene, 5, walk=(1.0, 0.0))
    assert event_rows(result) == ([(1, "select", 0, 0)] if selected else [])
    assert result.final_state.known_status[0, 0, 0] == TagStatus.AWAITING_PICKUP


def test_a_carrier_seen_but_not_yet_heard_is_no_candidate():
    # one advert per second, the tag's first in tick 4 (0.35 s into the interval)
    params = split_params(**{"camera.range": 1.0, "radio.interval": 1.0})
    scene = Scene.build(robots=[(1.0, 2.0)], carriers=[(0.5, 2.0)], advert_phase=[0.35])
    result = run_script(params, scene, 6, walk=(0.0, 1.0))
    assert event_rows(result) == [(4, "select", 0, 0)]


def test_radio_range_bounds_what_is_heard():
    params = split_params(**{"camera.range": 1.0, "radio.range": 0.4, "radio.interval": 0.1})
    scene = Scene.build(robots=[(1.0, 2.0)], carriers=[(0.5, 2.0)])
    result = run_script(params, scene, 3, walk=(0.0, 1.0))
    assert event_rows(result) == []  # seen at 0.5 m but not heard beyond 0.4 m
    assert result.final_state.known_status[0, 0, 0] == -1


def _shadow_scene():
    # carrier 1 sits between the robot and carrier 0 on the line y = 2
    return Scene.build(
        robots=[(1.4, 2.0)],
        carriers=[(0.3, 2.0), (0.9, 2.0)],
        status=[int(TagStatus.AWAITING_PICKUP), IDLE],
        urgency=[5, 5],
    )


@pytest.mark.parametrize(("occlusion", "seen"), [("none", True), ("carriers", False)])
def test_other_carriers_block_the_line_of_sight(occlusion, seen):
    # a little memory, so that every sighting is recorded (without memory only those a
    # walking robot can act on are looked at: carriers it heard AWAITING_PICKUP)
    params = split_params(
        carriers=2,
        **{
            "camera.range": 1.5,
            "camera.occlusion": occlusion,
            "camera.memory": 0.1,
            "radio.interval": 0.1,
        },
    )
    result = run_script(params, _shadow_scene(), 1, walk=(1.0, 0.0))
    assert result.final_state.seen_tick[0, 0].tolist() == [1 if seen else -1, 1]
    assert event_rows(result) == ([(1, "select", 0, 0)] if seen else [])


@pytest.mark.parametrize(("occlusion", "seen"), [("carriers", True), ("carriers+robots", False)])
def test_robots_block_the_line_of_sight_only_when_asked(occlusion, seen):
    params = split_params(
        robots=2,
        **{
            "camera.range": 1.5,
            "camera.occlusion": occlusion,
            "camera.memory": 0.1,
            "radio.interval": 0.1,
        },
    )
    scene = Scene.build(
        robots=[(1.4, 2.0), (0.9, 2.0)], carriers=[(0.3, 2.0)], urgency=[5], status=[IDLE]
    )
    result = run_script(params, scene, 1, walk=(0.0, 1.0))
    assert bool(result.final_state.seen_tick[0, 0, 0] == 1) is seen
    assert result.final_state.seen_tick[0, 1, 0] == 1  # the robot in front sees it


@pytest.mark.parametrize(("memory", "selected"), [(0.0, False), (0.5, True)])
def test_sighting_memory_keeps_a_carrier_a_candidate_after_it_left_the_view(memory, selected):
    # The robot sees the carrier at tick 1 (0.45 m) and walks away at 0.05 m per tick,
    # leaving the 0.5 m camera range after tick 2; the tag's first advert comes in
    # tick 5. With 0.5 s (5 ticks) of memory the sighting of tick 2 still counts.
    params = split_params(**{"camera.range": 0.5, "camera.memory": memory, "radio.interval": 1.0})
    scene = Scene.build(robots=[(0.95, 2.0)], carriers=[(0.5, 2.0)], advert_phase=[0.45])
    result = run_script(params, scene, 6, walk=(1.0, 0.0))
    # without memory nothing unheard is looked at; with it the last sighting is tick 2
    assert result.final_state.seen_tick[0, 0, 0] == (2 if memory else -1)
    assert event_rows(result) == ([(5, "select", 0, 0)] if selected else [])


def test_a_remembered_carrier_is_forgotten_after_the_horizon():
    params = split_params(**{"camera.range": 0.5, "camera.memory": 0.2, "radio.interval": 1.0})
    scene = Scene.build(robots=[(0.95, 2.0)], carriers=[(0.5, 2.0)], advert_phase=[0.45])
    result = run_script(params, scene, 6, walk=(1.0, 0.0))
    assert event_rows(result) == []  # last seen at tick 2, 3 ticks before the advert


def test_candidates_events_count_what_the_robot_chose_among():
    params = split_params(
        Urgency(alpha=0.7), carriers=3, **{"camera.range": 1.2, "radio.interval": 0.1}
    )
    scene = Scene.build(
        robots=[(1.4, 2.0)],
        carriers=[(0.5, 1.4), (0.5, 2.6), (0.4, 0.3)],
        urgency=[2, 8, 9],
    )
    result = run_script(params, scene, 1, walk=(0.0, 1.0))
    assert event_rows(result, candidates=True) == [(1, "select", 0, 1), (1, "candidates", 0, 1)]
    assert result.events.value.tolist() == [8.0, 2.0]  # the urgent one of the two it sees


def test_a_correlated_walk_turns_every_interval_by_the_drawn_angle():
    params = split_params(**{"walk.turn_interval": 0.3})  # every 3 ticks
    scene = Scene.build(robots=[(2.0, 2.0)], carriers=[(0.3, 0.3)], status=[IDLE])
    quarter = np.array([[[0.0, 1.0]]])  # (cos, sin) of +90 degrees

    class Turning:
        def inputs(self, tick):
            inputs = TickInputs.fixed(1, 1, walk=(1.0, 0.0))
            return TickInputs(
                walk=inputs.walk, sidestep=inputs.sidestep, breakdown=inputs.breakdown,
                turn=quarter,
            )  # fmt: skip

    state = initial_state(params, [scene], [0])
    result = run_batch(state, params, Turning(), ticks=7, check=True)
    # heading +x for ticks 1-2, turned at tick 3 (+y), 6 (-x): positions follow
    walk = result.final_state.walk[0, 0]
    assert walk == pytest.approx([-1.0, 0.0], abs=1e-12)
    expected = np.array([2.0, 2.0]) + 0.05 * np.array([2, 0]) + 0.05 * np.array([0, 3])
    expected += 0.05 * np.array([-2, 0])
    assert result.final_state.robot_pos[0, 0] == pytest.approx(expected, abs=1e-12)


def test_without_memory_only_actionable_sightings_are_looked_at_and_choices_are_the_same():
    # Restricting the camera to walking robots and carriers they heard AWAITING_PICKUP
    # changes no candidate: the full line-of-sight computation gives the same ones.
    from swarmtag.sim import RandomSource, step
    from swarmtag.sim.runner import seeded_state
    from swarmtag.sim.world.sensing import actionable, line_of_sight, sense

    params = make_params(
        load_profile("base").scenario(
            {"perception": "split", "camera.range": 3.6, "camera.occlusion": "carriers+robots"}
        ),
        Urgency(alpha=3.0),
    )
    state = seeded_state(params, seed=3, runs=12)
    source = RandomSource(params, seed=3, run_ids=state.run_ids)
    compared = 0
    for tick in range(1, 400):
        inputs = source.inputs(tick)
        senses = sense(state, inputs, params)
        offset = state.carrier_pos[:, None, :, :] - state.robot_pos[:, :, None, :]
        in_view = (
            state.present[:, None, :]
            & (state.carried_by < 0)[:, None, :]
            & (np.sqrt((offset**2).sum(axis=-1)) <= params.camera_range)
        )
        full = line_of_sight(state, in_view, params)
        relevant = actionable(state, senses.known_status)
        assert np.array_equal(senses.known, full & relevant)
        compared += int(relevant.sum())
        state, _ = step(state, inputs, params)
    assert compared > 300


@pytest.mark.parametrize(
    ("fade", "expected"),
    [(1.0, (1.0, 0.5, 0.0)), (0.0, (1.0, 1.0, 0.0))],
    ids=["ramp", "hard-disc"],
)
def test_a_camera_fade_makes_camera_range_the_50_percent_detection_distance(fade, expected):
    from swarmtag.sim import RandomSource
    from swarmtag.sim.world.sensing import sense

    # carriers 0.45 m (inside the ramp 0.5-1.5 m), 1.0 m (its middle), 1.55 m (beyond) away
    params = split_params(
        carriers=3, **{"camera.range": 1.0, "camera.fade": fade, "radio.interval": 0.1}
    )
    scene = Scene.build(robots=[(2.0, 2.0)], carriers=[(2.45, 2.0), (2.0, 3.0), (0.45, 2.0)])
    state = initial_state(params, [scene], np.array([0]))
    source = RandomSource(params, seed=3, run_ids=[0])
    ticks = 400
    seen = np.zeros(3)
    for t in range(1, ticks + 1):
        seen += sense(state, source.inputs(t), params).known[0, 0]
    near, middle, far = seen / ticks
    assert (near, far) == (expected[0], expected[2])
    assert middle == pytest.approx(expected[1], abs=0.08)


def test_ble_ranging_draws_log_normal_distances_and_smooths_them():
    from swarmtag.sim import RandomSource
    from swarmtag.sim.world.sensing import sense, sensed_state

    # one tag 2 m away, advertising every tick: the samples' log10 error has sd shadowing / (10 n)
    values = {"radio.search": True, "radio.interval": 0.1, "radio.shadowing": 6.0}
    values |= {"radio.path_loss_exponent": 2.5, "radio.smoothing": 1.0}
    params = split_params(**values)
    assert params.rssi_sigma == pytest.approx(6.0 / 25.0)
    scene = Scene.build(robots=[(1.0, 2.0)], carriers=[(3.0, 2.0)])
    state = initial_state(params, [scene], np.array([0]))
    source = RandomSource(params, seed=5, run_ids=[0])
    samples = []
    for t in range(1, 2001):
        senses = sense(state, source.inputs(t), params)
        samples.append(senses.rssi[0, 0, 0])
        state = sensed_state(state, senses)
    error = np.log10(np.array(samples) / 2.0)
    assert abs(error.mean()) < 0.02
    assert error.std() == pytest.approx(0.24, rel=0.05)

    # smoothing: the estimate moves a quarter of the way to each new sample
    smooth = split_params(**(values | {"radio.smoothing": 0.25}))
    state = initial_state(smooth, [scene], np.array([0]))
    source = RandomSource(smooth, seed=5, run_ids=[0])
    estimates = []
    for t in range(1, 2001):
        senses = sense(state, source.inputs(t), smooth)
        estimates.append(senses.rssi[0, 0, 0])
        state = sensed_state(state, senses)
    assert estimates[0] == samples[0]  # the first hearing starts the estimate
    assert estimates[1] == pytest.approx(samples[0] + 0.25 * (samples[1] - samples[0]))
    assert np.log10(np.array(estimates[100:]) / 2.0).std() < 0.5 * error.std()


def test_without_ble_search_nothing_is_ranged_or_drawn():
    from swarmtag.sim import RandomSource

    params = split_params(**{"radio.shadowing": 6.0})
    assert not params.radio_search
    assert RandomSource(params, seed=0, run_ids=[0]).inputs(1).rssi is None


@pytest.mark.parametrize(
    ("bearing", "expected"),
    [("dots", [True, False, True, False, True]), ("uniform", [True] * 5)],
)
def test_a_bearing_profile_blinds_the_wedges_between_the_cameras(bearing, expected):
    from swarmtag.sim import RandomSource
    from swarmtag.sim.world.sensing import sense

    # the robot faces +x; carriers 0.8 m ahead, at 73 degrees (blind), at 129 degrees
    # (the rear cameras), 0.8 m behind (too far for the rear) and 0.15 m behind (near enough)
    params = split_params(
        carriers=5, **{"camera.range": 1.0, "camera.bearing": bearing, "radio.interval": 0.1}
    )
    angles = np.radians([0.0, 73.0, 129.0, 180.0, 180.0])
    reach = np.array([0.8, 0.8, 0.8, 0.8, 0.15])
    carriers = [
        (2.0 + d * np.cos(a), 2.0 + d * np.sin(a)) for a, d in zip(angles, reach, strict=True)
    ]
    scene = Scene.build(robots=[(2.0, 2.0)], carriers=carriers)
    state = initial_state(params, [scene], np.array([0]))
    source = RandomSource(params, seed=3, run_ids=[0])
    inputs = source.inputs(1)
    assert sense(state, inputs, params).known[0, 0].tolist() == expected
    turned = state.copy()
    turned.heading[0, 0] = (0.0, 1.0)  # facing the 73-degree carrier: now 17 degrees off
    assert sense(turned, inputs, params).known[0, 0, 1]


@pytest.mark.parametrize(
    ("look", "expected"), [(2.0, [(21, "select", 0, 1)]), (0.0, [(1, "select", 0, 0)])]
)
def test_a_look_round_finds_the_carrier_in_the_blind_wedge(look, expected):
    # facing +x: carrier 0 (urgency 1) 0.8 m ahead is seen at once; carrier 1 (urgency 9)
    # 0.7 m away at 73 degrees is in the dots cameras' blind wedge until the robot turns
    values = {"camera.range": 1.0, "camera.bearing": "dots", "radio.interval": 0.1}
    params = split_params(Urgency(alpha=9.0), carriers=2, **values, **{"camera.look_around": look})
    assert params.look_ticks == round(look / 0.1)
    angle = np.radians(73.0)
    scene = Scene.build(
        robots=[(1.5, 2.0)],
        carriers=[(2.3, 2.0), (1.5 + 0.7 * np.cos(angle), 2.0 + 0.7 * np.sin(angle))],
        urgency=[1, 9],
    )
    result = run_script(params, scene, 22, walk=(1.0, 0.0))
    assert event_rows(result) == expected
    if look:  # it stands while it looks round, turning counter-clockwise a step a tick
        looking = run_script(params, scene, 20, walk=(1.0, 0.0)).final_state
        assert looking.robot_pos[0, 0].tolist() == [1.5, 2.0]
        assert looking.look[0, 0] == 1
        assert looking.heading[0, 0] == pytest.approx([-1.0, 0.0], abs=1e-9)  # 20 x 9 degrees


@pytest.mark.parametrize("drift", [0.0, 0.2])
def test_odometry_drift_blurs_a_remembered_position_as_the_robot_drives_on(drift):
    from swarmtag.sim import RandomSource
    from swarmtag.sim.world.sensing import sense, sensed_state

    values = {"camera.range": 1.0, "camera.memory": 10.0, "camera.drift": drift}
    params = split_params(**values, **{"radio.interval": 0.1})
    scene = Scene.build(robots=[(1.0, 2.0)], carriers=[(1.8, 2.0)])
    state = initial_state(params, [scene], np.array([0]))
    source = RandomSource(params, seed=4, run_ids=[0])
    first = sense(state, source.inputs(1), params)
    assert first.known[0, 0, 0]
    assert first.distance[0, 0, 0] == pytest.approx(0.8)  # seen now: no error yet
    state = sensed_state(state, first)
    state.robot_pos[0, 0] = (1.0, 3.5)  # drove 1.5 m on: out of sight, still remembered
    later = sense(state, source.inputs(2), params)
    assert later.known[0, 0, 0]
    error = later.distance[0, 0, 0] - np.hypot(0.8, 1.5)
    if drift:
        moved = np.sqrt(1.5) * drift  # the error's standard deviation per axis
        assert later.odometry[0, 0] == pytest.approx(source_numbers(8, 4, 2) * moved)
        assert abs(error) > 1e-3
    else:
        assert later.odometry is None
        assert error == pytest.approx(0.0, abs=1e-12)


def source_numbers(stream, seed, tick):
    """The odometry stream's numbers of run 0, robot 0 at ``tick`` (1-based)."""
    from swarmtag.sim.model.randomness import stream as generator

    return generator(seed, 0, stream).standard_normal((tick, 1, 2))[tick - 1, 0]
