"""Each mechanic of SPEC §4.2 on a small hand-built scene, with outcomes worked out by hand.

Defaults used below: step 0.05 m per tick, robot radius 0.125 m, carrier
half side 0.1775 m, predock offset 0.1775 + 0.175 = 0.3525 m, arrival
tolerance 0.01 m, dock = lift = release = 10 ticks, drop-off area x >= 3.0.
"""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.policy import Proximity, Urgency
from swarmtag.sim import Mode, Reprioritisation, Scene, Timing
from swarmtag.tag import TagStatus
from tests.sim.helpers import event_rows, params_for, run_script

IDLE = int(TagStatus.IDLE)
CARRIER = (0.6, 2.0)
EAST_PREDOCK = (0.6 + 0.3525, 2.0)
FAR_CORNER = (0.3, 0.3)


def test_head_on_collision_stops_both_then_they_turn_back():
    params = params_for(robots=2, carriers=1)
    scene = Scene.build(
        robots=[(1.5, 2.0), (1.93, 2.0)],
        heading=[(1.0, 0.0), (-1.0, 0.0)],
        carriers=[FAR_CORNER],
        status=[IDLE],
    )
    walk = [[1.0, 0.0], [-1.0, 0.0]]  # each tick's random direction points at the other robot
    after2 = run_script(params, scene, 2, walk=walk).final_state
    # tick 1: 1.55 and 1.88; tick 2 would leave them 0.23 apart (overlap 0.02):
    # the push is shared, each goes back 0.01, and they end exactly touching
    assert after2.robot_pos[0, :, 0] == pytest.approx([1.59, 1.84], abs=1e-12)
    assert after2.robot_pos[0, :, 1].tolist() == [2.0, 2.0]
    assert after2.contact[0, :, 0] == pytest.approx([-0.01, 0.01], abs=1e-12)

    after3 = run_script(params, scene, 3, walk=walk).final_state
    # the new random direction points into the contact, so it is reversed: they part
    assert after3.walk[0].tolist() == [[-1.0, 0.0], [1.0, 0.0]]
    assert after3.robot_pos[0, :, 0] == pytest.approx([1.54, 1.89], abs=1e-12)
    assert (after3.contact == 0).all()


@pytest.mark.parametrize(
    ("walk", "expected_walk", "expected_pos"),
    [
        ((1.0, 0.0), (-1.0, 0.0), (3.575, 2.0)),  # points into the wall: reversed
        ((0.0, 1.0), (0.0, 1.0), (3.625, 2.05)),  # parallel to the wall: kept, slides along
    ],
)
def test_robot_at_a_wall_is_stopped_and_picks_a_direction_away(walk, expected_walk, expected_pos):
    params = params_for(robots=1, carriers=1)
    scene = Scene.build(robots=[(3.6, 2.0)], carriers=[FAR_CORNER], status=[IDLE])
    one = run_script(params, scene, 1, walk=walk).final_state
    assert one.robot_pos[0, 0].tolist() == [3.625, 2.0]  # clamped at 3.75 - 0.125
    assert one.contact[0, 0, 0] == pytest.approx(-0.025, abs=1e-12)
    two = run_script(params, scene, 2, walk=walk).final_state
    assert two.walk[0, 0].tolist() == list(expected_walk)
    assert two.robot_pos[0, 0] == pytest.approx(expected_pos, abs=1e-12)


def test_robot_in_a_corner_is_held_inside_and_turns_out():
    params = params_for(robots=1, carriers=1)
    diagonal = (np.sqrt(0.5), np.sqrt(0.5))
    scene = Scene.build(
        robots=[(3.6, 3.6)], heading=[diagonal], carriers=[FAR_CORNER], status=[IDLE]
    )
    result = run_script(params, scene, 6, walk=(0.6, 0.8))
    state = result.final_state
    # tick 1 pins it in the corner; tick 2 reverses (0.6, 0.8), which points into both walls
    assert state.walk[0, 0].tolist() == [-0.6, -0.8]
    expected = 3.625 - 5 * 0.05 * np.array([0.6, 0.8])
    assert state.robot_pos[0, 0] == pytest.approx(expected, abs=1e-12)


@pytest.mark.parametrize(
    ("robot_x", "selected"),
    [(1.5, True), (np.nextafter(1.5, 2.0), False)],
    ids=["exactly-R", "just-beyond-R"],
)
def test_detection_range_is_inclusive_at_the_radius(robot_x, selected):
    params = params_for(robots=1, carriers=1, detection_radius=1.0)
    scene = Scene.build(robots=[(robot_x, 2.0)], carriers=[(0.5, 2.0)], urgency=[5])
    # the robot walks away (+x), so only the first tick's sensing can see the carrier
    result = run_script(params, scene, 5, walk=(1.0, 0.0))
    expected = [(1, "select", 0, 0)] if selected else []
    assert event_rows(result) == expected


def test_race_loser_abandons_on_the_status_it_hears_next_tick():
    params = params_for(robots=2, carriers=1)
    scene = Scene.build(
        robots=[EAST_PREDOCK, (0.6, 2.9)],
        heading=[(-1.0, 0.0), (0.0, -1.0)],
        carriers=[CARRIER],
        urgency=[4],
    )
    result = run_script(params, scene, 25)
    # robot 0 stands on the east predock point facing the carrier: docks at tick 1,
    # drives 0.3525 m in, arriving within 0.01 m after 7 ticks (tick 8), centres 10
    # ticks and lifts at tick 18. Robot 1 reaches the north predock point while robot 0
    # is under the carrier, so it waits there; it hears PICKED_UP at tick 19 and abandons.
    assert event_rows(result) == [
        (1, "select", 0, 0),
        (1, "select", 1, 0),
        (18, "lift", 0, 0),
        (19, "abandon", 1, 0),
    ]
    abandon = result.events.take(result.events.kind == "abandon")
    assert abandon.value.tolist() == [float(TagStatus.PICKED_UP)]
    assert result.final_state.mode[0, 1] == Mode.WALK


WEST_PREDOCK = (0.6 - 0.3525, 2.0)


@pytest.mark.parametrize("ticks", [1, 17])
def test_one_robot_under_a_carrier_the_other_waits_at_its_predock_point(ticks):
    # Both robots stand on opposite predock points facing the carrier and select it at
    # tick 1; both arrive in that tick, so the smaller id (robot 0) drives in and robot 1
    # waits in PREDOCK where it is, for as long as robot 0 is docking and centring.
    params = params_for(robots=2, carriers=1)
    scene = Scene.build(
        robots=[EAST_PREDOCK, WEST_PREDOCK],
        heading=[(-1.0, 0.0), (1.0, 0.0)],
        carriers=[CARRIER],
        urgency=[4],
    )
    result = run_script(params, scene, ticks)
    mode = result.final_state.mode[0]
    assert mode[0] in (Mode.DOCK, Mode.CENTRE)
    assert mode[1] == Mode.PREDOCK
    assert result.final_state.robot_pos[0, 1].tolist() == pytest.approx(list(WEST_PREDOCK))


def test_the_waiting_robot_abandons_when_it_hears_the_lift():
    params = params_for(robots=2, carriers=1)
    scene = Scene.build(
        robots=[EAST_PREDOCK, WEST_PREDOCK],
        heading=[(-1.0, 0.0), (1.0, 0.0)],
        carriers=[CARRIER],
        urgency=[4],
    )
    result = run_script(params, scene, 25)
    # robot 0: docks at tick 1, centre after 7 ticks (tick 8), lifts at tick 18.
    assert event_rows(result) == [
        (1, "select", 0, 0),
        (1, "select", 1, 0),
        (18, "lift", 0, 0),
        (19, "abandon", 1, 0),
    ]
    assert "timeout" not in result.events.kind.tolist()


def test_pursuit_timeout_then_cooldown_bars_the_carrier():
    params = params_for(
        robots=2,
        carriers=1,
        detection_radius=3.0,
        timing=Timing(pursuit_timeout=2.0, cooldown=3.0),
    )
    scene = Scene.build(
        robots=[(1.6, 2.0), EAST_PREDOCK],
        heading=[(-1.0, 0.0), (-1.0, 0.0)],
        carriers=[CARRIER],
        urgency=[4],
    )
    # robot 1 breaks down on the only free-to-reach predock point before it selects;
    # robot 0 cannot get there: timeout after 20 ticks, then barred for 30 ticks.
    result = run_script(params, scene, 60, walk=(-1.0, 0.0), breakdowns={1: [1]})
    assert event_rows(result) == [
        (1, "breakdown", 1, -1),
        (1, "select", 0, 0),
        (21, "timeout", 0, 0),
        (51, "select", 0, 0),
    ]
    assert result.breakdowns.tolist() == [1]
    assert result.stuck.tolist() == [0]


def _two_carrier_scene():
    # Carriers 0 (urgency 2) and 1 (urgency 8) at equal distance from a robot walking
    # towards them; both come into range (R = 1) together at tick 5.
    return Scene.build(
        robots=[(1.55, 2.0)],
        heading=[(-1.0, 0.0)],
        carriers=[(0.5, 1.5), (0.5, 2.5)],
        urgency=[2, 8],
    )


def test_urgency_policy_prefers_the_urgent_of_two_equidistant_carriers():
    params = params_for(Urgency(alpha=0.7), robots=1, carriers=2)
    result = run_script(params, _two_carrier_scene(), 6, walk=(-1.0, 0.0))
    assert event_rows(result) == [(5, "select", 0, 1)]
    proximity = run_script(params_for(Proximity(), robots=1, carriers=2), _two_carrier_scene(), 6)
    assert event_rows(proximity)[0] == (5, "select", 0, 0)  # a distance tie: smaller marker


def test_timed_reprioritisation_changes_the_selection():
    params = params_for(
        Urgency(alpha=0.7),
        robots=1,
        carriers=2,
        reprioritisations=(Reprioritisation(tick=2, carrier=0, urgency=9),),
    )
    result = run_script(params, _two_carrier_scene(), 6, walk=(-1.0, 0.0))
    assert event_rows(result) == [(2, "reprioritise", -1, 0), (5, "select", 0, 0)]
    events = result.events
    # the new urgency, the urgency heard, then the number of candidates chosen among
    assert events.value.tolist() == [9.0, 9.0, 2.0]
    log = result.carriers
    assert log.urgency0.tolist() == [2, 8]  # the log keeps the urgency at run start


def test_reprioritisation_goes_through_the_authenticated_operator_write(monkeypatch):
    from swarmtag.sim.world import wms
    from swarmtag.tag import Role, TagModel, verify

    applied = []
    real_apply = TagModel.apply

    def spy(self, message):
        applied.append(bytes(message))
        return real_apply(self, message)

    monkeypatch.setattr(wms.TagModel, "apply", spy)
    params = params_for(
        Urgency(alpha=0.7),
        robots=1,
        carriers=2,
        reprioritisations=(
            Reprioritisation(tick=2, carrier=0, urgency=9),
            Reprioritisation(tick=3, carrier=1, urgency=0),
        ),
    )
    result = run_script(params, _two_carrier_scene(), 4)
    writes = [verify(message, wms.SIM_SITE_KEY) for message in applied]
    assert [(w.role, w.writer, w.counter, w.target, w.change.urgency) for w in writes] == [
        (Role.OPERATOR, wms.OPERATOR_ID, 0, 0, 9),
        (Role.OPERATOR, wms.OPERATOR_ID, 1, 1, 0),
    ]
    assert result.final_state.urgency[0].tolist() == [9, 0]


def test_reprioritisation_stops_growth_and_keeps_order_time():
    params = params_for(
        robots=1,
        carriers=1,
        ticks=90,
        reprioritisations=(Reprioritisation(tick=25, carrier=0, urgency=1),),
    )
    scene = Scene.build(
        robots=[(3.4, 3.4)], carriers=[(0.3, 0.3)], urgency=[0], w0=[0.0], order_time=[-0.0]
    )
    # u(t) = min(9, floor(9 * (0 + t) / 90)) = t // 10 until the write at tick 25 sets 1
    for ticks, expected in ((24, 2), (25, 1), (60, 1)):
        state = run_script(params, scene, ticks, walk=(0.0, 1.0)).final_state
        assert int(state.urgency[0, 0]) == expected
    result = run_script(params, scene, 60, walk=(0.0, 1.0))
    assert result.carriers.urgency0.tolist() == [0]
    assert result.carriers.order_time.tolist() == [0.0]


def test_breakdown_while_loaded_leaves_the_carrier_stuck():
    params = params_for(robots=1, carriers=1)
    scene = Scene.build(
        robots=[EAST_PREDOCK], heading=[(-1.0, 0.0)], carriers=[CARRIER], urgency=[4]
    )
    result = run_script(params, scene, 60, breakdowns={30: [0]})
    assert event_rows(result) == [(1, "select", 0, 0), (18, "lift", 0, 0), (30, "breakdown", 0, 0)]
    state = result.final_state
    assert state.mode[0, 0] == Mode.BROKEN
    assert state.status[0, 0] == TagStatus.PICKED_UP
    assert state.carried_by[0, 0] == 0
    assert state.carrier_pos[0, 0].tolist() == state.robot_pos[0, 0].tolist()
    assert result.stuck.tolist() == [1]
    assert result.undelivered.tolist() == [1]
    log = result.carriers
    assert log.pickup_time.tolist() == [18.0]
    assert np.isnan(log.delivery_time).all()
    assert log.robot.tolist() == [-1]


def test_full_cycle_pickup_transport_release_with_event_times():
    params = params_for(robots=1, carriers=1)
    scene = Scene.build(
        robots=[EAST_PREDOCK], heading=[(-1.0, 0.0)], carriers=[CARRIER], urgency=[6]
    )
    result = run_script(params, scene, 200)
    # lift at 18 (see the race), lifting until tick 28, then 52 steps of 0.05 m east
    # until the carrier lies in the drop-off area (x >= 3.0 + 0.1775): tick 80;
    # release for 10 ticks: delivered at tick 90, and the run ends there.
    assert event_rows(result) == [(1, "select", 0, 0), (18, "lift", 0, 0), (90, "deliver", 0, 0)]
    log = result.carriers
    assert log.pickup_time.tolist() == [18.0]
    assert log.delivery_time.tolist() == [90.0]
    assert log.robot.tolist() == [0]
    assert result.end_tick.tolist() == [90]
    state = result.final_state
    assert state.status[0, 0] == TagStatus.IDLE
    assert not state.present[0, 0]
    assert state.mode[0, 0] == Mode.WALK
    assert state.robot_pos[0, 0, 0] == pytest.approx(0.6 + 52 * 0.05, abs=1e-9)


def test_lift_write_is_refused_unless_the_tag_awaits_pickup():
    params = params_for(robots=1, carriers=1, detection_radius=1.0)
    scene = Scene.build(
        robots=[EAST_PREDOCK],
        heading=[(-1.0, 0.0)],
        carriers=[CARRIER],
        urgency=[4],
        status=[IDLE],
    )
    result = run_script(params, scene, 30)
    assert event_rows(result) == []  # an IDLE carrier is never selected
    assert result.final_state.status[0, 0] == IDLE
