"""Scenario configuration: SPEC defaults, the scaling rule, validation, TOML and mappings."""

from __future__ import annotations

import math

import pytest

from swarmtag.errors import ConfigError
from swarmtag.policy import Proximity
from swarmtag.sim import (
    Arena,
    Motion,
    Realism,
    Reprioritisation,
    Scenario,
    Timing,
    UrgencyModel,
    make_params,
)


def test_spec_defaults_for_three_robots_and_seven_carriers():
    s = Scenario()
    assert (s.robots, s.carriers, s.ticks, s.tick) == (3, 7, 3000, 0.1)
    assert s.area.size == 3.75
    assert (s.bodies.robot_diameter, s.bodies.carrier_size) == (0.25, 0.355)
    assert s.motion.speed == 0.5
    assert s.urgency.model == "growing"
    assert s.realism == Realism()
    assert not s.realism.enabled
    assert s.area.carrier_spacing >= s.bodies.robot_diameter


def test_kernel_units():
    p = make_params(Scenario(), Proximity())
    assert p.step == 0.05
    assert (p.dock_ticks, p.lift_ticks, p.release_ticks) == (10, 10, 10)
    assert (p.timeout_ticks, p.cooldown_ticks) == (300, 300)
    assert p.pickup_right == 1.5
    assert p.dropoff_left == 3.0
    assert p.predock_offset == pytest.approx(0.3525)
    assert p.turn_cos == pytest.approx(math.cos(math.radians(9.0)))
    assert p.markers.tolist() == list(range(7))
    static = make_params(Scenario(urgency=UrgencyModel(model="static")), Proximity())
    assert static.horizon == 2400.0
    assert static.run_ticks == 6000


@pytest.mark.parametrize(("carriers", "side"), [(7, 3.75), (28, 7.5), (3, 3.75)])
def test_arena_scales_to_keep_carrier_density(carriers, side):
    s = Scenario(robots=3, carriers=carriers)
    assert s.area.size == pytest.approx(side)
    assert s.area.pickup_width / s.area.size == pytest.approx(1.5 / 3.75)
    assert s.area.dropoff_width / s.area.size == pytest.approx(0.75 / 3.75)


def test_an_explicit_arena_is_not_scaled():
    s = Scenario(carriers=10, arena=Arena(size=5.0))
    assert s.area.size == 5.0


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: Scenario(robots=0), "robots: 0 is not an integer in 1-10000000"),
        (lambda: Scenario(robots=2.5), "robots: 2.5 is not an integer in 1-10000000"),
        (lambda: Scenario(carriers=True), "carriers: True is not an integer in 1-256"),
        (lambda: Scenario(carriers=300), "carriers: 300 is not an integer in 1-256"),
        (lambda: Scenario(tick=0), "tick: 0 is not a number in [1e-06, 3600]"),
        (lambda: Arena(size=-1.0), "arena.size: -1.0 is not a number in (0, 100000]"),
        (lambda: Timing(dock=-1), "timing.dock: -1 is not a number in [0, 1e+07]"),
        (lambda: Motion(collision_iterations=0), "motion.collision_iterations: 0"),
        (lambda: Realism(breakdown=1.5), "realism.breakdown: 1.5 is not a number in [0, 1]"),
        (
            lambda: Realism(status_delay=-1),
            "realism.status_delay: -1 is not an integer in 0-100000000",
        ),
        (lambda: UrgencyModel(model="linear"), "urgency.model: 'linear' is not one of"),
        (lambda: Reprioritisation(tick=5, carrier=1, urgency=10), "reprioritisations.urgency"),
        (lambda: Scenario(arena=Arena(carrier_spacing=0.1)), "arena.carrier_spacing: 0.1"),
        (lambda: Scenario(carriers=40, arena=Arena()), "carriers: 40 do not fit"),
        (lambda: Scenario(robots=200), "robots: 200 do not fit"),
        (
            lambda: Scenario(reprioritisations=(Reprioritisation(tick=5, carrier=7, urgency=3),)),
            "reprioritisations.carrier: 7 is not a carrier",
        ),
        (
            lambda: Scenario(
                reprioritisations=(Reprioritisation(tick=3001, carrier=0, urgency=3),)
            ),
            "reprioritisations.tick: 3001 is after the end of the run",
        ),
    ],
)
def test_bad_values_name_the_field_and_range(build, message):
    with pytest.raises(ConfigError) as caught:
        build()
    assert message in str(caught.value)


def test_from_mapping_with_overrides_and_scaling():
    s = Scenario.from_mapping(
        {"robots": 5, "carriers": 14, "timing": {"dock": 2.0}},
        {"timing.lift": 3.0, "realism": {"breakdown": 0.001}},
    )
    assert (s.robots, s.carriers) == (5, 14)
    assert s.area.size == pytest.approx(3.75 * math.sqrt(2))
    assert (s.timing.dock, s.timing.lift, s.timing.release) == (2.0, 3.0, 1.0)
    assert s.realism.breakdown == 0.001


def test_partial_arena_table_keeps_the_scaled_defaults():
    s = Scenario.from_mapping({"carriers": 28, "arena": {"dropoff_width": 2.0}})
    assert s.area.size == pytest.approx(7.5)
    assert s.area.pickup_width == pytest.approx(3.0)
    assert s.area.dropoff_width == 2.0


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"robotz": 3}, "robotz: unknown key; a scenario has keys"),
        ({"arena": {"sise": 3}}, "arena.sise: unknown key; [arena] has keys"),
        ({"arena": 3}, "arena: 3 is not a table of keys"),
        ({"reprioritisations": [{"tick": 1, "carrier": 0}]}, "lacks urgency"),
        ({"reprioritisations": [{"tick": 1, "carrier": 0, "urgency": 1, "x": 2}]}, ".x: unknown"),
        ({"reprioritisations": 5}, "reprioritisations: 5 is not a list of tables"),
    ],
)
def test_unknown_or_malformed_keys_are_errors(data, message):
    with pytest.raises(ConfigError) as caught:
        Scenario.from_mapping(data)
    assert message in str(caught.value)


def test_toml_file_round_trip(tmp_path):
    path = tmp_path / "lab.toml"
    path.write_text(
        """
robots = 4
carriers = 7
ticks = 1200
detection_radius = 1.5

[timing]
pursuit_timeout = 20.0

[urgency]
model = "static"
static_time_limit = 4000

[[reprioritisations]]
tick = 100
carrier = 2
urgency = 9
""",
        encoding="utf-8",
    )
    s = Scenario.from_toml(path, {"realism.advertisement_loss": 0.1})
    assert (s.robots, s.ticks, s.detection_radius) == (4, 1200, 1.5)
    assert s.timing.pursuit_timeout == 20.0
    assert s.urgency == UrgencyModel(model="static", static_time_limit=4000)
    assert s.run_ticks == 4000
    assert s.reprioritisations == (Reprioritisation(tick=100, carrier=2, urgency=9),)
    assert s.realism.advertisement_loss == 0.1
    assert Scenario.from_mapping(s.to_mapping()) == s


def test_toml_errors_name_the_file(tmp_path):
    missing = tmp_path / "missing.toml"
    with pytest.raises(ConfigError, match=r"missing\.toml: no such scenario file"):
        Scenario.from_toml(missing)
    broken = tmp_path / "broken.toml"
    broken.write_text("robots = = 3\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"broken\.toml: not valid TOML"):
        Scenario.from_toml(broken)
    bad = tmp_path / "bad.toml"
    bad.write_text("robots = 0\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"bad.toml: robots: 0 is not an integer in 1-10000000"):
        Scenario.from_toml(bad)


def test_scenarios_are_frozen_and_hashable():
    s = Scenario()
    with pytest.raises(AttributeError):
        s.robots = 4  # type: ignore[misc]
    assert hash(s) == hash(Scenario())


def test_a_camera_fade_is_at_most_twice_the_range():
    from swarmtag.sim import Camera

    assert Camera(range=1.5, fade=1.0).fade == 1.0
    assert Camera(range=0.5, fade=1.0).fade == 1.0  # the ramp starts at the robot's centre
    with pytest.raises(ConfigError, match=r"camera\.fade: 1\.2 is more than twice camera\.range"):
        Camera(range=0.5, fade=1.2)
    with pytest.raises(ConfigError, match=r"camera\.fade: -0\.1 is not a number"):
        Camera(fade=-0.1)


def test_perception_can_grow_with_the_arena_and_is_fixed_by_default():
    from swarmtag.policy import Proximity
    from swarmtag.sim.model.params import make_params

    fixed = Scenario.default(20, 40)
    grown = Scenario.default(20, 40).to_mapping() | {"perception_scaling": "arena"}
    scaled = Scenario.from_mapping(grown)
    factor = (40 / 7) ** 0.5
    assert fixed.perception_factor == 1.0
    assert scaled.perception_factor == pytest.approx(factor)
    assert scaled.camera.range == fixed.camera.range  # the declared camera stays
    a, b = make_params(fixed, Proximity()), make_params(scaled, Proximity())
    assert a.camera_range == fixed.camera.range
    assert b.camera_range == pytest.approx(3.6 * factor)  # 8.6 m at 20 / 40
    assert b.detection_radius == b.camera_range == b.camera_far
    assert Scenario.from_mapping(scaled.to_mapping()) == scaled  # no double scaling
    with pytest.raises(ConfigError, match="perception_scaling"):
        Scenario(perception_scaling="camera")


def test_perception_scaling_is_refused_on_a_warehouse_floor():
    from swarmtag.sim import load_profile

    part = {"map": "small-warehouse", "order_interval": 60.0}
    with pytest.raises(ConfigError, match="perception_scaling: 'arena'"):
        load_profile("lab").scenario({"warehouse": part, "perception_scaling": "arena"})


@pytest.mark.parametrize(
    "values",
    [{"perception": "disc"}, {"radio": {"search": True}}],
    ids=["disc", "search"],
)
def test_a_look_round_needs_split_perception_without_search(values):
    mapping = Scenario.default(3, 7, profile="paper-sim").to_mapping()
    mapping["camera"] |= {"look_around": 1.0}
    for key, value in values.items():
        mapping[key] = mapping.get(key, {}) | value if isinstance(value, dict) else value
    with pytest.raises(ConfigError, match=r"camera.look_around: a look round before choosing"):
        Scenario.from_mapping(mapping)
