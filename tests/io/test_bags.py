"""Reading event logs out of ROS 2 bags built here with rosbags' writer (sqlite3 and MCAP)."""

from __future__ import annotations

import sys
import textwrap

import numpy as np
import pytest

from swarmtag.analysis import summarize
from swarmtag.errors import BagError
from swarmtag.io import CarrierLog, format_csv, read_event_log, write_event_log
from swarmtag.io.bag_mapping import BagMapping, default_mapping
from swarmtag.io.bags import bag_path, read_bag
from tests.io.bag_builders import (
    AWAITING,
    IDLE,
    LAB_LOG,
    LAB_TABLE,
    PICKED_UP,
    SEC,
    T0,
    TOPICS,
    Messages,
    lab_session,
    write_bag,
)

pytest.importorskip("rosbags")

STORAGES = ("sqlite3", "mcap", "db3", "bare-mcap")


def bag_name(storage: str) -> str:
    return {"db3": "session.db3", "bare-mcap": "session.mcap"}.get(storage, "session")


@pytest.fixture(scope="module", params=STORAGES)
def lab_bag(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp(request.param)
    return write_bag(folder / bag_name(request.param), request.param, TOPICS, lab_session())


def test_bag_gives_the_exact_event_log_it_encodes(lab_bag):
    logs = read_bag(lab_bag, with_events=True)
    assert logs.trials == 2
    assert logs.carriers == LAB_LOG
    assert format_csv(logs.carriers) == format_csv(LAB_LOG)
    assert logs.events == LAB_TABLE


def test_the_imported_log_passes_the_file_checks_and_metrics_run_on_it(lab_bag, tmp_path):
    log = read_bag(lab_bag).carriers
    for suffix in (".csv", ".parquet"):
        write_event_log(log, tmp_path / f"events{suffix}")
        assert read_event_log(tmp_path / f"events{suffix}") == LAB_LOG
    report = summarize(log, n_resamples=50, seed=0)
    assert [c.condition for c in report.conditions] == ["proximity", "urgency:alpha=0.7"]
    assert report.condition("proximity").kpis.total_deliveries == 2
    assert report.condition("urgency:alpha=0.7").kpis.undelivered == 1


def test_the_event_table_is_read_only_when_asked_for(lab_bag):
    assert read_bag(lab_bag).events is None


def test_a_bag_without_message_definitions_is_read_with_the_shipped_types(tmp_path):
    import sqlite3

    bag = write_bag(tmp_path / "humble.db3", "db3", TOPICS, lab_session())
    with sqlite3.connect(bag) as database:  # as ROS 2 Humble's sqlite3 storage writes bags
        database.execute("DELETE FROM message_definitions")
    assert read_bag(bag).carriers == LAB_LOG


def test_a_type_neither_the_bag_nor_the_reader_knows_is_named(tmp_path):
    import sqlite3

    from rosbags.typesys import get_types_from_msg

    store = Messages().store
    store.register(get_types_from_msg(LAB_MSG, "lab_msgs/msg/CarrierState"))
    bag = write_bag(
        tmp_path / "lab.db3", "db3", {"/lab/carrier_state": "lab_msgs/msg/CarrierState"}, [], store
    )
    with sqlite3.connect(bag) as database:
        database.execute("DELETE FROM message_definitions")
    mapping = BagMapping.load(written(tmp_path / "lab.toml", LAB_MAPPING))
    with pytest.raises(
        BagError,
        match=r"the definition of lab_msgs/msg/CarrierState, the type of /lab/carrier_state \(the bag carries none",
    ):
        read_bag(bag, mapping)


def test_a_bag_without_the_mapped_topics_and_fields_is_refused_naming_all_of_them(tmp_path):
    m = Messages()
    only_tags = {"/swarmtag/tag_status": TOPICS["/swarmtag/tag_status"]}
    bag = write_bag(tmp_path / "b.mcap", "bare-mcap", only_tags, [m.tags(T0, (1, AWAITING, 3, -1))])
    mapping = BagMapping.load(
        written(
            tmp_path / "map.toml",
            DEFAULT.replace('robot = "robot"', 'robot = "writer_id"').replace(
                'urgency = "urgency"', 'urgency = "prio.level"'
            ),
        )
    )
    with pytest.raises(BagError) as error:
        read_bag(bag, mapping, with_events=True)
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith(f"{bag}: lacks what the mapping {tmp_path / 'map.toml'} names: ")
    assert "topic /swarmtag/trial ([trial] topic)" in message
    assert "field prio.level of /swarmtag/tag_status" in message
    assert "([tag_status] urgency)" in message
    assert "field writer_id of /swarmtag/tag_status" in message
    assert "topic /swarmtag/robot_events ([robot_events] topic)" in message
    assert "The bag's topics: /swarmtag/tag_status (swarmtag_msgs/msg/TagStatusArray)" in message


def test_a_field_of_the_wrong_type_is_named(tmp_path):
    m = Messages()
    bag = write_bag(tmp_path / "b.mcap", "bare-mcap", TOPICS, [m.trial(T0, condition="p")])
    mapping = BagMapping.from_mapping(
        parsed(DEFAULT.replace('run = "run"', 'run = "condition"')), source="m.toml"
    )
    with pytest.raises(
        BagError,
        match=r"field condition of /swarmtag/trial .* is string, not what \[trial\] run needs",
    ):
        read_bag(bag, mapping)


# --- another layout, described by its own mapping ---------------------------------------------

LAB_MSG = """\
std_msgs/Header header
uint16 carrier_id
int8 state
uint8 priority
int16 agent
"""
LAB_MAPPING = """\
format = 1

[trial]
condition = { value = "weighted:w=0.3" }
run = { value = 4 }
seed = { value = 11 }

[tag_status]
topic = "/lab/carrier_state"
stamp = "@log"
marker = "carrier_id"
status = "state"
urgency = "priority"
robot = "agent"
idle = 10
awaiting_pickup = 11
picked_up = 12
"""


def test_a_custom_layout_is_read_through_its_mapping(tmp_path):
    from rosbags.typesys import get_types_from_msg

    store = Messages().store
    store.register(get_types_from_msg(LAB_MSG, "lab_msgs/msg/CarrierState"))
    state = store.types["lab_msgs/msg/CarrierState"]
    header = Messages(store).header

    def change(at: int, carrier: int, code: int, priority: int, agent: int):
        message = state(
            header=header(0), carrier_id=carrier, state=code, priority=priority, agent=agent
        )
        return ("/lab/carrier_state", at, message)

    start = 5 * SEC  # the bag's first message: the one trial's start
    messages = [
        change(start, 1, 11, 8, -1),
        change(start + 2 * SEC, 2, 11, 1, -1),
        change(start + 4 * SEC, 1, 12, 8, 3),
        change(start + 9 * SEC, 1, 10, 8, 3),
    ]
    bag = write_bag(
        tmp_path / "lab",
        "sqlite3",
        {"/lab/carrier_state": "lab_msgs/msg/CarrierState"},
        messages,
        store,
    )
    mapping = BagMapping.load(written(tmp_path / "lab.toml", LAB_MAPPING))
    log = read_bag(bag, mapping).carriers
    assert log == CarrierLog(
        condition=["weighted:w=0.3"] * 2,
        run=[4, 4],
        seed=[11, 11],
        carrier=[1, 2],
        urgency0=[8, 1],
        order_time=[0.0, 2.0],
        pickup_time=[4.0, np.nan],
        delivery_time=[9.0, np.nan],
        robot=[3, -1],
        run_end=[np.nan, np.nan],
        urgency_end=[8, 1],
        time_unit="s",
    )


def test_a_status_value_the_mapping_does_not_know_is_refused(tmp_path):
    m = Messages()
    messages = [m.trial(T0, condition="proximity"), m.tags(T0 + SEC, (1, 7, 3, -1))]
    bag = write_bag(tmp_path / "b.mcap", "bare-mcap", TOPICS, messages)
    with pytest.raises(BagError) as error:
        read_bag(bag)
    assert str(error.value) == (
        f"{bag}: /swarmtag/tag_status message 1 (0.997 s into the bag): status 7 is none of "
        "idle 0, awaiting_pickup 1, picked_up 2 ([tag_status] values)"
    )


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        ((1, AWAITING, 10, -1), r"\[tag_status\] urgency: 10 is not an integer in 0-9"),
        ((1, PICKED_UP, 3, 0), r"carrier 1 is lifted without an order"),
        ((1, IDLE, 3, 0), r"no carrier was ordered in any of its 1 trial\(s\)"),
    ],
)
def test_values_and_stories_no_event_log_can_hold_are_refused(tmp_path, change, expected):
    m = Messages()
    bag = write_bag(
        tmp_path / "b.mcap",
        "bare-mcap",
        TOPICS,
        [m.trial(T0, condition="p"), m.tags(T0 + SEC, change)],
    )
    with pytest.raises(BagError, match=expected):
        read_bag(bag)


def test_a_trial_whose_log_breaks_the_event_log_checks_is_named(tmp_path):
    m = Messages()
    messages = [
        m.trial(T0, condition="p", markers=[1], urgency0=[3], order_time=[50.0]),
        m.tags(T0 + SEC, (1, PICKED_UP, 3, 0)),
    ]
    bag = write_bag(tmp_path / "b.mcap", "bare-mcap", TOPICS, messages)
    with pytest.raises(BagError) as error:
        read_bag(bag)
    assert str(error.value) == (
        f"{bag}: the trial starting 0.000 s into the bag (run 0 of p): row 1, column "
        "pickup_time: 1.0 is before order_time 50.0; a carrier is picked up after it is ordered"
    )


# --- paths that are no bag ---------------------------------------------------------------------


def test_paths_that_are_no_bag_are_refused_in_one_line(tmp_path):
    (tmp_path / "folder").mkdir()
    (tmp_path / "notes.txt").write_text("x")
    (tmp_path / "broken.mcap").write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 40)
    for name, expected in (
        ("missing.mcap", "no such bag"),
        ("folder", "a folder without metadata.yaml is no rosbag2 bag"),
        ("notes.txt", "not a ROS 2 bag; give a rosbag2 folder, an .mcap or a .db3 file"),
        ("broken.mcap", "not a readable ROS 2 bag ("),
    ):
        with pytest.raises(BagError) as error:
            read_bag(tmp_path / name)
        assert str(error.value).startswith(f"{tmp_path / name}: {expected}")
        assert "\n" not in str(error.value)
    assert bag_path(write_bag(tmp_path / "ok", "sqlite3", TOPICS, [])) == tmp_path / "ok"


def test_a_bag_whose_tag_changes_outgrow_the_memory_limit_is_refused(tmp_path, monkeypatch):
    m = Messages()
    crowd = [(n % 256, AWAITING, 3, -1) for n in range(70_000)]
    bag = write_bag(
        tmp_path / "b.mcap", "bare-mcap", TOPICS, [m.trial(T0, condition="p"), m.tags(T0, *crowd)]
    )
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "1MiB")
    with pytest.raises(
        BagError,
        match=r"b.mcap \(70001 trial marks, tag changes and events\) needs about 20.0 MiB of memory",
    ):
        read_bag(bag)


def test_an_event_table_needs_a_robot_events_table_in_the_mapping(lab_bag, tmp_path):
    without = DEFAULT[: DEFAULT.index("[robot_events]")]
    mapping = BagMapping.load(written(tmp_path / "no-events.toml", without))
    assert read_bag(lab_bag, mapping).carriers == LAB_LOG
    with pytest.raises(BagError) as error:
        read_bag(lab_bag, mapping, with_events=True)
    assert str(error.value) == (
        f"{tmp_path / 'no-events.toml'}: has no [robot_events] table; an event table needs one"
    )


def test_an_empty_bag_has_no_trial(tmp_path):
    bag = write_bag(tmp_path / "empty.mcap", "bare-mcap", TOPICS, [])
    with pytest.raises(BagError, match="no trial starts in the bag; nothing to import"):
        read_bag(bag)


def test_without_rosbags_the_extra_is_named(lab_bag, monkeypatch):
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)  # as if it were not installed
    with pytest.raises(BagError) as error:
        read_bag(lab_bag)
    assert str(error.value) == (
        "ROS 2 bags and MCAP files need the 'bags' extra: pip install 'swarmtag[bags]'"
    )


# --- helpers -----------------------------------------------------------------------------------

DEFAULT = default_mapping().read_text(encoding="utf-8")


def parsed(text: str) -> dict:
    import tomllib

    return tomllib.loads(text)


def written(path, text: str):
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path
