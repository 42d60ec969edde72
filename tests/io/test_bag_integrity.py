"""Bags that hold more than the mapping reads, or whose records disagree: never read short.

Service-event channels (``ros2 bag record --all``) are skipped, not parsed; a folder whose
``metadata.yaml`` disagrees with its storage (QoS, counts) is read whole or refused naming
the topic and both counts.
"""

from __future__ import annotations

import shutil

import pytest

from swarmtag.errors import BagError
from swarmtag.io.bags import read_bag
from tests.io.bag_builders import (
    LAB_LOG,
    LAB_TABLE,
    SERVICE_TOPIC,
    SERVICE_TYPE,
    TOPICS,
    lab_session,
    write_bag,
    write_mcap_file,
)

pytest.importorskip("rosbags")
pytest.importorskip("mcap")

SKIPPED = (f"{SERVICE_TOPIC} ({SERVICE_TYPE}: service events)",)


def folder_with(tmp_path, storage: str):
    """The lab session as a rosbag2 folder: its metadata.yaml text and its storage file."""
    bag = write_bag(tmp_path / "bag", storage, TOPICS, lab_session())
    (storage_file,) = [p for p in bag.iterdir() if p.name != "metadata.yaml"]
    return bag, storage_file


def edit_metadata(bag, old: str, new: str, count: int = 1) -> None:
    path = bag / "metadata.yaml"
    text = path.read_text(encoding="utf-8")
    assert text.count(old) >= count, old
    path.write_text(text.replace(old, new, count), encoding="utf-8")


QOS = """offered_qos_profiles:
      - history: keep_last
        depth: 10
        reliability: reliable
        durability: volatile
        deadline: {sec: 0, nsec: 0}
        lifespan: {sec: 0, nsec: 0}
        liveliness: automatic
        liveliness_lease_duration: {sec: 0, nsec: 0}
        avoid_ros_namespace_conventions: false"""
"""A QoS profile for metadata.yaml, as ros2 bag record writes one: its MCAP channels have none."""


def differ_in_qos(bag) -> None:
    """Give every topic of ``bag``'s metadata.yaml a QoS its storage does not record."""
    edit_metadata(bag, "offered_qos_profiles: []", QOS, count=3)


def test_a_bare_mcap_bag_with_a_service_channel_imports_its_topics(tmp_path):
    bag = write_mcap_file(tmp_path / "all.mcap", TOPICS, lab_session())
    logs = read_bag(bag, with_events=True)
    assert logs.carriers == LAB_LOG
    assert logs.events == LAB_TABLE
    assert logs.skipped == SKIPPED


def test_a_rosbag2_mcap_folder_with_a_service_channel_imports_its_topics(tmp_path):
    bag, storage_file = folder_with(tmp_path, "mcap")
    write_mcap_file(storage_file, TOPICS, lab_session())  # what ros2 bag record --all writes
    logs = read_bag(bag, with_events=True)
    assert (logs.carriers, logs.events, logs.skipped) == (LAB_LOG, LAB_TABLE, SKIPPED)


def test_a_folder_whose_metadata_qos_differs_from_its_mcap_file_is_read_whole(tmp_path):
    bag, _ = folder_with(tmp_path, "mcap")
    differ_in_qos(bag)
    logs = read_bag(bag, with_events=True)
    assert logs.carriers == LAB_LOG
    assert logs.events == LAB_TABLE  # rosbags matched channels by QoS and read none of these


@pytest.mark.parametrize("storage", ["mcap", "sqlite3"])
def test_a_folder_whose_metadata_counts_more_messages_is_refused_with_both_counts(
    tmp_path, storage
):
    bag, _ = folder_with(tmp_path, storage)
    events = sum(1 for topic, *_ in lab_session() if topic == "/swarmtag/robot_events")
    edit_metadata(bag, f"message_count: {events}\n", f"message_count: {events + 5}\n")
    text = (bag / "metadata.yaml").read_text(encoding="utf-8")
    assert f"message_count: {events + 5}\n" in text
    with pytest.raises(BagError) as error:
        read_bag(bag, with_events=True)
    assert str(error.value) == (
        f"{bag}: topic /swarmtag/robot_events: read {events} message(s), but metadata.yaml "
        f"counts {events + 5}; the bag is damaged or its records disagree, so nothing is imported"
    )


def test_a_sqlite3_folder_whose_metadata_qos_differs_is_refused_with_the_counts(tmp_path):
    """rosbags reads sqlite3 bags by (topic, type, QoS): the mismatch reads nothing, now refused."""
    bag, _ = folder_with(tmp_path, "sqlite3")
    differ_in_qos(bag)
    with pytest.raises(BagError) as error:
        read_bag(bag, with_events=True)
    assert str(error.value) == (
        f"{bag}: topic /swarmtag/trial: read 0 message(s), but metadata.yaml counts 3; "
        "the bag is damaged or its records disagree, so nothing is imported"
    )


def test_a_metadata_file_listing_a_missing_storage_file_is_one_line(tmp_path):
    bag, storage_file = folder_with(tmp_path, "mcap")
    shutil.move(storage_file, tmp_path / "elsewhere.mcap")
    with pytest.raises(BagError, match=r"bag/bag\.mcap: missing \(metadata\.yaml lists it\)$"):
        read_bag(bag)
