"""The MCAP recorder: a file Foxglove's own MCAP reader opens and decodes, written all or nothing."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmtag.errors import BagError
from swarmtag.io.bags import read_bag
from swarmtag.io.mcap_out import CHANNELS, FRAME, Arena, McapRecorder, TrialInfo

pytest.importorskip("rosbags")

ARENA = Arena(size=3.0, pickup_right=1.0, dropoff_left=2.5, robot_radius=0.125, carrier_size=0.35)
INFO = TrialInfo(condition="proximity", run=2, seed=5, time_unit="tick", tick=0.1)
STEP = 100_000_000


def record(path) -> None:
    """Two robots, two carriers, three ticks: carrier 4 is lifted at tick 1, delivered at 2."""
    with McapRecorder(path) as out:
        out.trial(0, INFO, starts=True, markers=[4, 6], urgency0=[3, 9], order_time=[-12.5, 0.0])
        out.arena(0, ARENA)
        out.tag_changes(0, [(4, 1, 3, -1), (6, 1, 9, -1)])
        statuses = ([1, 1], [2, 1], [0, 1])
        for tick, status in enumerate(statuses):
            at = tick * STEP
            if tick == 1:
                out.tag_changes(at, [(4, 2, 3, 0)])
                out.robot_events(at, [("lift", 0, 4, 3.0), ("select", 1, 6, 9.0)])
            if tick == 2:
                out.tag_changes(at, [(4, 0, 3, 0)])
                out.robot_events(at, [("deliver", 0, 4, 3.0), ("breakdown", 1, -1, math.nan)])
            out.frame(
                at,
                ARENA,
                robot_xy=np.array([[0.5 + tick, 1.0], [2.0, 2.0]]),
                robot_heading=np.array([[1.0, 0.0], [0.0, 1.0]]),
                robot_labels=["r0 walk", "r1 walk"],
                markers=[4, 6],
                carrier_xy=np.array([[0.5 + tick, 1.0], [0.4, 2.0]]),
                carrier_status=status,
                carrier_urgency=[3, 9],
                carrier_present=[tick < 2, True],
            )
        out.trial(2 * STEP, INFO, starts=False)


def test_foxglove_s_mcap_reader_opens_the_file_and_decodes_every_message(tmp_path):
    pytest.importorskip("mcap_ros2")
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    record(tmp_path / "run.mcap")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.mcap"]
    with (tmp_path / "run.mcap").open("rb") as handle:
        reader = make_reader(handle, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == "ros2"
        summary = reader.get_summary()
        assert summary is not None
        channels = {
            c.topic: (
                summary.schemas[c.schema_id].name,
                summary.schemas[c.schema_id].encoding,
                c.message_encoding,
            )
            for c in summary.channels.values()
        }
        assert channels == {
            topic: (msgtype, "ros2msg", "cdr") for topic, msgtype in CHANNELS.items()
        }
        decoded = {}
        for _, channel, message, value in reader.iter_decoded_messages():
            decoded.setdefault(channel.topic, []).append((message.log_time, value))
    counts = {topic: len(found) for topic, found in decoded.items()}
    assert counts == {
        "/swarmtag/trial": 2,
        "/swarmtag/arena": 1,
        "/swarmtag/tag_status": 3,
        "/swarmtag/robot_events": 2,
        "/swarmtag/robots": 3,
        "/swarmtag/carriers": 3,
        "/swarmtag/scene": 3,
    }
    at, scene = decoded["/swarmtag/scene"][2]
    assert at == 2 * STEP
    assert scene.markers[0].action == 3  # DELETEALL, then this step's markers
    names = [(m.ns, m.id) for m in scene.markers[1:]]
    assert names == [
        ("robots", 0),
        ("headings", 0),
        ("robot_labels", 0),
        ("robots", 1),
        ("headings", 1),
        ("robot_labels", 1),
        ("carriers", 6),
        ("carrier_labels", 6),
    ]  # fmt: skip; carrier 4 was delivered
    assert {m.header.frame_id for m in scene.markers} == {FRAME}
    assert scene.markers[-1].text == "6 u9"
    _, robots = decoded["/swarmtag/robots"][1]
    pose = robots.poses[1]
    assert (pose.position.x, pose.position.y) == (2.0, 2.0)
    assert pose.orientation.z == pytest.approx(math.sin(math.pi / 4))  # heading +y: yaw 90 degrees
    _, carriers = decoded["/swarmtag/carriers"][1]
    assert carriers.poses[0].position.z > 0  # lifted
    _, start = decoded["/swarmtag/trial"][0]
    assert (start.condition, start.run, start.seed, start.time_unit, start.tick) == (
        "proximity",
        2,
        5,
        "tick",
        0.1,
    )
    assert list(start.order_time) == [-12.5, 0.0]


def test_the_recorded_trial_imports_as_its_event_log(tmp_path):
    record(tmp_path / "run.mcap")
    logs = read_bag(tmp_path / "run.mcap", with_events=True)
    log = logs.carriers
    assert log.carrier.tolist() == [4, 6]
    assert log.pickup_time.tolist()[0] == 1.0
    assert log.delivery_time.tolist()[0] == 2.0
    assert log.robot.tolist() == [0, -1]
    assert log.run_end.tolist() == [2.0, 2.0]
    assert log.time_unit == "tick"
    assert logs.events is not None
    assert logs.events.kind.tolist() == ["lift", "select", "deliver", "breakdown"]
    assert logs.events.carrier.tolist() == [4, 6, 4, -1]


def test_the_same_recording_gives_the_same_bytes(tmp_path):
    record(tmp_path / "a.mcap")
    record(tmp_path / "b.mcap")
    assert (tmp_path / "a.mcap").read_bytes() == (tmp_path / "b.mcap").read_bytes()


def test_a_failure_while_recording_leaves_no_file(tmp_path):
    class Stop(Exception):
        pass

    def fail() -> None:
        with McapRecorder(tmp_path / "run.mcap") as out:
            out.trial(0, INFO, starts=True)
            raise Stop

    with pytest.raises(Stop):
        fail()
    assert list(tmp_path.iterdir()) == []


def test_an_unwritable_place_is_one_line(tmp_path):
    (tmp_path / "file").write_text("x")
    with (
        pytest.raises(BagError, match=r"run.mcap: cannot write"),
        McapRecorder(tmp_path / "file" / "run.mcap"),
    ):
        pass


# --- checksums: written, checked by an independent reader, and refused when they fail ----------


def summary_of(path):
    from mcap.reader import make_reader

    with path.open("rb") as handle:
        reader = make_reader(handle)
        summary = reader.get_summary()
        assert summary is not None
        return summary


def footer_of(data: bytes):
    """(summary start, summary CRC) from the footer (the last 37 bytes)."""
    import struct

    summary_start, _, crc = struct.unpack_from("<QQI", data, len(data) - 8 - 20)
    return summary_start, crc


def test_every_crc_is_written_and_foxglove_s_reader_validates_them(tmp_path):
    import zlib

    from mcap.reader import NonSeekingReader
    from mcap.records import Chunk, DataEnd
    from mcap.stream_reader import StreamReader

    path = tmp_path / "run.mcap"
    record(path)
    data = path.read_bytes()
    with path.open("rb") as handle:
        records = list(StreamReader(handle, emit_chunks=True).records)
    chunks = [r for r in records if isinstance(r, Chunk)]
    (data_end,) = [r for r in records if isinstance(r, DataEnd)]
    assert chunks
    assert all(chunk.uncompressed_crc != 0 for chunk in chunks)
    assert data_end.data_section_crc != 0
    summary_start, summary_crc = footer_of(data)
    assert summary_crc == zlib.crc32(data[summary_start : len(data) - 12])
    with path.open("rb") as handle:  # chunk and data-section CRCs checked by mcap itself
        messages = list(NonSeekingReader(handle, validate_crcs=True).iter_messages())
    assert len(messages) == 17


def flipped(path, offset: int):
    data = bytearray(path.read_bytes())
    data[offset] ^= 0xFF
    path.write_bytes(bytes(data))


@pytest.mark.parametrize("where", [0.25, 0.5, 0.9])
def test_a_byte_flipped_inside_a_chunk_is_refused_naming_the_chunk(tmp_path, where):
    path = tmp_path / "run.mcap"
    record(path)
    (chunk,) = summary_of(path).chunk_indexes
    header = 1 + 8 + 8 + 8 + 8 + 4 + 4 + len(chunk.compression) + 8
    inside = chunk.chunk_start_offset + header + int(chunk.compressed_size * where)
    flipped(path, inside)
    with pytest.raises(BagError) as error:
        read_bag(path, with_events=True)
    message = str(error.value)
    assert message.startswith(f"{path}: damaged: the chunk at byte {chunk.chunk_start_offset} ")
    assert "\n" not in message


def test_a_byte_flipped_in_the_summary_is_refused_naming_it(tmp_path):
    path = tmp_path / "run.mcap"
    record(path)
    data = path.read_bytes()
    summary_start, _ = footer_of(data)
    inside = data.index(b"uint8 urgency", summary_start) + 6  # a schema's text: still parses
    flipped(path, inside)
    with pytest.raises(BagError) as error:
        read_bag(path)
    assert str(error.value).startswith(
        f"{path}: damaged: the summary section at byte {summary_start} fails its CRC (stored "
    )


def test_a_byte_flipped_in_the_data_section_outside_chunks_is_refused(tmp_path):
    path = tmp_path / "run.mcap"
    record(path)
    data = path.read_bytes()
    (chunk,) = summary_of(path).chunk_indexes
    index_at = chunk.chunk_start_offset + chunk.chunk_length  # the message indexes that follow
    flipped(path, index_at + 1 + 8 + 2 + 4 + 3)  # inside the first index's first timestamp
    summary_start, _ = footer_of(data)
    with pytest.raises(BagError, match=r"damaged: the data section before byte \d+ fails its CRC"):
        read_bag(path)
    assert index_at < summary_start
