"""The bag mapping file: the shipped default, and one clear line for every wrong key or value."""

from __future__ import annotations

import tomllib

import pytest

from swarmtag.errors import BagError
from swarmtag.io.bag_mapping import LOG_TIME, BagMapping, FieldKind, default_mapping

DEFAULT = default_mapping().read_text(encoding="utf-8")


def mapping(text: str) -> BagMapping:
    return BagMapping.from_mapping(tomllib.loads(text), source="m.toml")


def test_the_default_mapping_describes_the_swarmtag_msgs_layout():
    found = BagMapping.default()
    assert found.source == "bag_mapping.toml"
    trial = found.trial
    assert (trial.topic, trial.stamp, trial.start, trial.end) == (
        "/swarmtag/trial",
        ("header", "stamp"),
        0,
        1,
    )
    assert [
        s.path for s in (trial.condition, trial.run, trial.seed, trial.time_unit, trial.tick)
    ] == [
        ("condition",),
        ("run",),
        ("seed",),
        ("time_unit",),
        ("tick",),
    ]
    assert trial.markers is not None
    assert trial.markers.kind is FieldKind.INTS
    tags = found.tag_status
    assert (tags.topic, tags.entries, tags.idle, tags.awaiting_pickup, tags.picked_up) == (
        "/swarmtag/tag_status",
        ("tags",),
        0,
        1,
        2,
    )
    assert found.robot_events is not None
    assert found.robot_events.topic == "/swarmtag/robot_events"


def test_the_status_values_are_the_wire_values_of_the_tag():
    from swarmtag.tag import TagStatus

    tags = BagMapping.default().tag_status
    assert (tags.idle, tags.awaiting_pickup, tags.picked_up) == (
        TagStatus.IDLE,
        TagStatus.AWAITING_PICKUP,
        TagStatus.PICKED_UP,
    )


def test_fixed_values_defaults_and_the_log_time():
    found = mapping(
        """
        format = 1
        [trial]
        condition = { value = "proximity" }
        run = { value = 3 }
        seed = { value = 0 }
        [tag_status]
        topic = "/t"
        stamp = "@log"
        marker = "m"
        status = "s"
        urgency = "u"
        robot = { value = -1 }
        """
    )
    trial = found.trial
    assert trial.topic is None
    assert (trial.condition.fixed, trial.run.fixed, trial.time_unit.fixed, trial.tick.fixed) == (
        "proximity",
        3,
        "s",
        0.0,
    )
    assert trial.markers is None
    assert trial.event is None
    assert found.tag_status.stamp is None
    assert LOG_TIME == "@log"
    assert found.tag_status.robot.fixed == -1
    assert found.tag_status.robot.path == ()
    assert found.robot_events is None


def replaced(old: str, new: str) -> str:
    assert old in DEFAULT
    return DEFAULT.replace(old, new, 1)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (replaced("format = 1", "format = 2"), "m.toml: format 2 is not 1; write format = 1"),
        (replaced("format = 1", ""), "m.toml: format None is not 1; write format = 1"),
        (
            DEFAULT + "\n[extra]\n",
            "m.toml: unknown key or table 'extra'; expected format, [trial], [tag_status], [robot_events]",
        ),
        (replaced("[tag_status]", "[tag_statuses]"), "m.toml: unknown key or table 'tag_statuses'"),
        (
            replaced('condition = "condition"', 'condtion = "condition"'),
            "m.toml: [trial] has no key 'condtion'; its keys are topic, stamp, event,",
        ),
        (replaced('seed = "seed"', ""), "m.toml: [trial] lacks seed"),
        (
            replaced('marker = "marker"', 'marker = "tags..marker"'),
            "m.toml: [tag_status] marker: 'tags..marker' is not a field path (names joined by dots, e.g. header.stamp)",
        ),
        (
            replaced('marker = "marker"', "marker = 3"),
            "m.toml: [tag_status] marker: 3 is not a field path",
        ),
        (
            replaced('run = "run"', 'run = { value = "3" }'),
            "m.toml: [trial] run: '3' is not an integer",
        ),
        (
            replaced('tick = "tick"', "tick = { value = nan }"),
            "m.toml: [trial] tick: nan is not a number",
        ),
        (
            replaced('run = "run"', "run = { value = true }"),
            "m.toml: [trial] run: True is not an integer",
        ),
        (
            replaced('run = "run"', "run = { val = 3 }"),
            "m.toml: [trial] run: a fixed value is written { value = ... }",
        ),
        (
            replaced('markers = "markers"', ""),
            "m.toml: [trial] markers, urgency0 and order_time go together",
        ),
        (
            replaced('topic = "/swarmtag/trial"', ""),
            "m.toml: [trial] markers: 'markers' names a field, but [trial] has no topic; give a fixed value",
        ),
        (
            replaced('topic = "/swarmtag/tag_status"', 'topic = "swarmtag/tag_status"'),
            "m.toml: [tag_status] topic: 'swarmtag/tag_status' is not a topic name",
        ),
        (
            replaced("picked_up = 2", "picked_up = 1"),
            "m.toml: [tag_status] idle, awaiting_pickup, picked_up must be different values",
        ),
        (replaced("end = 1", "end = 0"), "m.toml: [trial] start, end must be different values"),
        (replaced("idle = 0", 'idle = "0"'), "m.toml: [tag_status] idle: '0' is not an integer"),
        (replaced('kind = "kind"', ""), "m.toml: [robot_events] lacks kind"),
        (replaced("[trial]", "trial = 3\n[trial_]"), "m.toml: unknown key or table 'trial_'"),
    ],
)
def test_a_wrong_mapping_is_refused_naming_the_key(text, message):
    with pytest.raises(BagError) as error:
        mapping(text)
    assert str(error.value).startswith(message)
    assert "\n" not in str(error.value)


def test_mapping_files_are_read_with_one_line_per_failure(tmp_path):
    with pytest.raises(BagError, match=r"missing.toml: no such bag mapping"):
        BagMapping.load(tmp_path / "missing.toml")
    (tmp_path / "bad.toml").write_text("format = ")
    with pytest.raises(BagError, match=r"bad.toml: not valid TOML"):
        BagMapping.load(tmp_path / "bad.toml")
    (tmp_path / "good.toml").write_text(DEFAULT)
    assert BagMapping.load(tmp_path / "good.toml").trial == BagMapping.default().trial
