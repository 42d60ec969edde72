"""The ``--replay`` source: files read through the io readers, the time line, play and pause."""

import json

import pytest

from swarmtag.console import replay_file
from swarmtag.console.replay_file import read_recording
from swarmtag.console.replay_source import REPLAY_REFUSAL, ReplaySource
from swarmtag.console.server import replay_core
from swarmtag.errors import ConfigError, EventLogError
from tests.console.recordings import MCAP_TICKS, TICK, simulate_mcap, write_log


@pytest.fixture
def source(tmp_path):
    return ReplaySource(read_recording(write_log(tmp_path), tick_seconds=TICK))


def _rows(source):
    return {t["marker"]: t for t in source.snapshot()["tags"]}


def test_the_runs_lie_end_to_end_in_seconds(source):
    assert source.duration == pytest.approx(50.0 + 30.0)  # 100 and 60 ticks of 0.5 s
    assert source.floor()["kind"] == "none"
    assert "no robot poses" in source.floor()["why"]
    assert source.snapshot()["robots"] == []


@pytest.mark.parametrize(
    ("time", "run", "statuses"),
    [
        (0.0, 0, {0: "awaiting_pickup"}),  # 1 and 2 are not ordered yet
        (6.0, 0, {0: "picked_up"}),
        (12.0, 0, {0: "picked_up", 1: "awaiting_pickup"}),
        (16.0, 0, {0: "idle", 1: "awaiting_pickup"}),
        (40.0, 0, {0: "idle", 1: "picked_up", 2: "awaiting_pickup"}),
        (50.0 + 25.0, 1, {0: "idle", 1: "awaiting_pickup", 2: "awaiting_pickup"}),
    ],
)
def test_the_table_shows_the_moment_at_the_play_head(source, time, run, statuses):
    source.control({"time": time})
    snap = source.snapshot()
    assert snap["run"] == run
    assert {m: t["status"] for m, t in _rows(source).items()} == statuses


def test_urgency_and_robot_follow_the_log(source):
    source.control({"time": 6.0})
    assert _rows(source)[0]["carried_by"] == 1
    assert _rows(source)[0]["urgency"] == 5
    source.control({"time": 16.0})
    assert _rows(source)[0]["urgency"] == 9  # delivered with urgency 9
    assert _rows(source)[0]["delivered_at"] == 15.0
    assert _rows(source)[0]["carried_by"] is None


def test_play_pause_and_speed(source):
    assert source.advance(2.0) == 1
    assert source.snapshot()["time"] == 2.0
    source.control({"playing": False})
    assert source.advance(5.0) == 0
    assert source.snapshot()["time"] == 2.0
    source.control({"playing": True, "speed": 10})
    source.advance(1.0)
    assert source.snapshot()["time"] == 12.0


def test_the_play_head_stops_at_the_end(source):
    source.control({"speed": 100})
    source.advance(10.0)
    status = source.snapshot()["replay"]
    assert status["position"] == status["duration"]
    assert status["playing"] is False


@pytest.mark.parametrize(
    ("change", "says"),
    [
        ({"time": -1}, "time"),
        ({"time": 1e9}, "time"),
        ({"speed": 0}, "speed"),
        ({"speed": float("nan")}, "speed"),
        ({"playing": "yes"}, "playing"),
        ({"rewind": True}, "unknown key"),
        ({}, "send an object"),
        ([1], "send an object"),
    ],
)
def test_bad_controls_are_refused_and_change_nothing(source, change, says):
    before = source.snapshot()["replay"]
    with pytest.raises(ConfigError, match=says):
        source.control(change)
    assert source.snapshot()["replay"] == before


def test_kpis_grow_with_the_play_head(source):
    source.control({"time": 0.0})
    assert source.kpis()["deliveries"] == 0
    source.control({"time": 16.0})
    first = source.kpis()
    assert (first["runs"], first["deliveries"]) == (1, 1)
    assert first["mean_latency"] == pytest.approx((30 + 10) * TICK)  # ordered at -10 ticks
    source.control({"time": source.duration})
    assert source.kpis()["deliveries"] == 2
    assert source.kpis()["runs"] == 2


def test_a_parquet_log_replays_alike(tmp_path):
    pytest.importorskip("pyarrow")
    csv = ReplaySource(read_recording(write_log(tmp_path), tick_seconds=TICK))
    parquet = ReplaySource(read_recording(write_log(tmp_path, "run.parquet"), tick_seconds=TICK))
    for time in (0.0, 12.0, 70.0):
        csv.control({"time": time})
        parquet.control({"time": time})
        assert csv.snapshot()["tags"] == parquet.snapshot()["tags"]


def test_writes_are_refused_with_409_and_audited(tmp_path):
    core = replay_core(
        read_recording(write_log(tmp_path), tick_seconds=TICK), audit_log=tmp_path / "a.jsonl"
    )
    reply = core.write(who="me", client="me", marker="0", field="urgency", body=b'{"urgency": 9}')
    assert reply.status == 409
    assert "a replay cannot be re-prioritised" in reply.body["error"]
    assert reply.body["error"] == f"refused: {REPLAY_REFUSAL}"
    (line,) = [json.loads(x) for x in (tmp_path / "a.jsonl").read_text().splitlines()]
    assert (line["outcome"], line["status"], line["tag"]) == ("refused", 409, "0")
    assert core.control(b'{"time": 12}').status == 200
    assert core.control(b'{"time": "x"}').status == 422
    assert core.control(b"not json").status == 400
    assert core.floor().body["source"] == "replay"


@pytest.mark.parametrize(
    ("name", "text", "error", "says"),
    [
        ("missing.csv", None, ConfigError, "no such file"),
        ("notes.txt", "hello\n", ConfigError, "not an event log"),
        ("broken.csv", "a,b\n1,2\n", EventLogError, "lacks columns"),
        ("empty.csv", None, EventLogError, "no rows"),
    ],
)
def test_bad_files_are_one_line(tmp_path, name, text, error, says):
    path = tmp_path / name
    if text is not None:
        path.write_text(text)
    if name == "empty.csv":
        path.write_text(write_log(tmp_path).read_text().splitlines()[0] + "\n")
    with pytest.raises(error, match=says) as raised:
        read_recording(path, tick_seconds=TICK)
    assert "\n" not in str(raised.value)
    assert str(raised.value).startswith("--replay ")


def test_a_file_over_the_limit_is_refused_before_it_is_read(tmp_path, monkeypatch):
    path = write_log(tmp_path)
    monkeypatch.setattr(replay_file, "MAX_REPLAY_BYTES", path.stat().st_size - 1)
    with pytest.raises(ConfigError, match="over the replay limit"):
        read_recording(path, tick_seconds=TICK)


@pytest.fixture(scope="module")
def mcap(tmp_path_factory):
    pytest.importorskip("mcap", reason="the bags extra")
    return simulate_mcap(tmp_path_factory.mktemp("mcap"))


def test_an_mcap_run_brings_robots_carriers_and_the_floor(mcap):
    recording = read_recording(mcap, tick_seconds=99.0)  # the file states its own tick
    source = ReplaySource(recording)
    floor = source.floor()
    assert floor["kind"] == "arena"
    assert floor["arena"] > 0
    assert 0 < floor["pickup_right"] < floor["dropoff_left"] < floor["arena"]
    snap = source.snapshot()
    assert len(snap["robots"]) == 3
    assert all(t["x"] is not None for t in snap["tags"])
    start = [(r["x"], r["y"]) for r in snap["robots"]]
    source.control({"time": source.duration / 2})
    assert [(r["x"], r["y"]) for r in source.snapshot()["robots"]] != start
    assert source.duration == pytest.approx(MCAP_TICKS * recording.tick_seconds, rel=0.01)


def test_an_mcap_gives_the_event_log_that_log_import_gives(mcap):
    from swarmtag.io.bags import read_bag

    assert read_recording(mcap, tick_seconds=1.0).log == read_bag(mcap).carriers


def test_an_mcap_run_shows_its_own_tag_changes(mcap):
    """Urgencies grow and lifts show their robot as the file's /swarmtag/tag_status says."""
    source = ReplaySource(read_recording(mcap, tick_seconds=1.0))
    log = source.recording.log
    ordered = dict(zip(log.carrier.tolist(), log.urgency0.tolist(), strict=True))
    grown = lifted = False
    for step in range(21):
        source.control({"time": source.duration * step / 20})
        for tag in source.snapshot()["tags"]:
            grown |= tag["urgency"] != ordered[tag["marker"]]
            if tag["status"] == "picked_up":
                lifted = True
                assert tag["carried_by"] is not None
    assert grown
    assert lifted
