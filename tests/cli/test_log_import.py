"""``swarmtag log import`` and ``simulate --mcap`` through the real entry point."""

from __future__ import annotations

import json
import sys
import tomllib

import pytest

from swarmtag.cli import main
from swarmtag.io import format_csv, read_event_log, read_event_table
from swarmtag.io.bag_mapping import BagMapping
from tests.io.bag_builders import LAB_LOG, LAB_TABLE, TOPICS, lab_session, write_bag

pytest.importorskip("rosbags")

EXTRA = "swarmtag: error: ROS 2 bags and MCAP files need the 'bags' extra: pip install 'swarmtag[bags]'\n"
SMALL = ["--profile", "base", "--ticks", "400", "--resamples", "20", "--no-progress"]


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(list(argv))
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


@pytest.fixture(scope="module", params=["sqlite3", "mcap"])
def bag(request, tmp_path_factory):
    folder = tmp_path_factory.mktemp("bags")
    return write_bag(folder / f"session-{request.param}", request.param, TOPICS, lab_session())


def test_import_writes_the_event_log_and_table_and_metrics_run_on_it(bag, tmp_path, capsys):
    events, table = tmp_path / "events.csv", tmp_path / "table.parquet"
    code, out, err = run(
        capsys, "log", "import", str(bag), "--events", str(events), "--event-table", str(table)
    )
    assert (code, err) == (0, "")
    assert out.splitlines() == [
        (
            f"{bag}: 2 trial(s), 5 carrier rows (3 delivered), times in seconds, "
            "conditions proximity, urgency:alpha=0.7"
        ),
        f"wrote event log: {events}",
        f"wrote event table (5 rows): {table}",
    ]
    assert events.read_text(encoding="utf-8") == format_csv(LAB_LOG)
    assert read_event_table(table) == LAB_TABLE
    code, out, err = run(capsys, "metrics", str(events), "--json", "--resamples", "50")
    assert (code, err) == (0, "")
    document = json.loads(out)
    assert [c["condition"] for c in document["conditions"]] == ["proximity", "urgency:alpha=0.7"]
    assert [c["total_deliveries"] for c in document["conditions"]] == [2, 1]


def test_a_mapping_file_is_read(bag, tmp_path, capsys):
    code, text, _ = run(capsys, "log", "mapping")
    assert code == 0
    printed = BagMapping.from_mapping(tomllib.loads(text), source="bag_mapping.toml")
    assert printed == BagMapping.default()
    mapping = tmp_path / "mine.toml"
    mapping.write_text(text.replace('"/swarmtag/trial"', '"/lab/trial"'), encoding="utf-8")
    code, _, err = run(
        capsys,
        "log",
        "import",
        str(bag),
        "--events",
        str(tmp_path / "e.csv"),
        "--mapping",
        str(mapping),
    )
    assert code == 2
    assert err.startswith(
        f"swarmtag: error: {bag}: lacks what the mapping {mapping} names: topic /lab/trial"
    )
    assert err.count("\n") == 1
    assert not (tmp_path / "e.csv").exists()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["nope.mcap", "--events", "e.csv"], "nope.mcap: no such bag"),
        (["BAG", "--events", "e.txt"], "--events: 'e.txt' must end in .csv or .parquet"),
        (
            ["BAG", "--events", "missing/e.csv"],
            "--events: 'missing/e.csv' cannot be written: folder 'missing' does not exist",
        ),
        (["BAG", "--events", "e.csv", "--mapping", "m.toml"], "m.toml: no such bag mapping"),
        (
            ["BAG", "--events", "e.csv", "--event-table", "e.csv"],
            "--event-table: 'e.csv' is also an output (--events); give each its own file",
        ),
    ],
)
def test_bad_input_is_one_line_and_writes_nothing(  # noqa: PLR0917 - fixtures and cases
    bag, tmp_path, monkeypatch, capsys, argv, message
):
    monkeypatch.chdir(tmp_path)
    argv = [str(bag) if word == "BAG" else word for word in argv]
    code, out, err = run(capsys, "log", "import", *argv)
    assert (code, out) == (2, "")
    assert err == f"swarmtag: error: {message}\n"
    assert list(tmp_path.iterdir()) == []


def test_without_rosbags_log_import_names_the_extra(bag, tmp_path, monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)
    code, out, err = run(capsys, "log", "import", str(bag), "--events", str(tmp_path / "e.csv"))
    assert (code, out, err) == (2, "", EXTRA)
    assert list(tmp_path.iterdir()) == []


def test_without_rosbags_simulate_mcap_names_the_extra_before_any_work(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.setitem(sys.modules, "rosbags.rosbag2", None)
    code, out, err = run(
        capsys, "simulate", *SMALL, "--runs", "1", "--mcap", str(tmp_path / "run.mcap")
    )
    assert (code, out, err) == (2, "", EXTRA)
    assert list(tmp_path.iterdir()) == []


def test_simulate_mcap_checks_the_recorded_run_s_memory_before_any_work(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "200MiB")
    long_run = ["--profile", "base", "--ticks", "2000000", "--runs", "1", "--no-progress"]
    code, out, err = run(capsys, "simulate", *long_run, "--mcap", str(tmp_path / "run.mcap"))
    assert (code, out) == (2, "")
    assert err.startswith(
        "swarmtag: error: --runs 1 of 2 condition(s) with 7 carriers needs about "
    )
    assert "200.0 MiB is available" in err
    assert list(tmp_path.iterdir()) == []
    # the same runs without a recorded one fit: the recording is what was refused
    from swarmtag.cli.simulate import _check_work
    from swarmtag.sim import Scenario

    _check_work(Scenario.from_mapping({"ticks": 2_000_000}), 2, 1, 0, record=False)


def test_simulate_mcap_refuses_more_carriers_than_one_byte_markers_before_any_work(
    tmp_path, capsys
):
    # a warehouse allocates its orders as carriers: 300 s at an order a second is over 256
    warehouse = ["--set", "warehouse.map=small-warehouse", "--set", "warehouse.order_interval=1"]
    code, out, err = run(
        capsys,
        "simulate",
        "--profile",
        "lab",
        "--ticks",
        "3000",
        "--runs",
        "1",
        "--no-progress",
        *warehouse,
        "--mcap",
        str(tmp_path / "run.mcap"),
    )
    assert (code, out) == (2, "")
    assert err.startswith(
        "swarmtag: error: an MCAP run names its carriers by one-byte marker ids (0-255), "
    )
    assert err.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_simulate_mcap_then_log_import_gives_the_identical_event_log(tmp_path, capsys):
    events, mcap = tmp_path / "sim.csv", tmp_path / "run.mcap"
    table = tmp_path / "sim-table.csv"
    code, _, err = run(
        capsys, "simulate", *SMALL, "--runs", "1", "--run-offset", "3", "--condition", "proximity",
        "--events", str(events), "--event-table", str(table), "--mcap", str(mcap),
    )  # fmt: skip
    assert (code, err) == (0, "")
    back, back_table = tmp_path / "back.csv", tmp_path / "back-table.csv"
    code, _, err = run(
        capsys, "log", "import", str(mcap), "--events", str(back), "--event-table", str(back_table)
    )
    assert (code, err) == (0, "")
    assert back.read_bytes() == events.read_bytes()
    assert back_table.read_bytes() == table.read_bytes()


def test_simulate_mcap_writes_one_file_per_condition_for_the_drawn_run(tmp_path, capsys):
    events, mcap = tmp_path / "sim.parquet", tmp_path / "run.mcap"
    code, out, err = run(
        capsys, "simulate", *SMALL, "--runs", "2", "--draw-run", "1", "--events", str(events),
        "--mcap", str(mcap), "--condition", "proximity", "--condition", "urgency:alpha=0.7",
    )  # fmt: skip
    assert (code, err) == (0, "")
    log = read_event_log(events)
    for condition, slug in (("proximity", "proximity"), ("urgency:alpha=0.7", "urgency-alpha-0.7")):
        path = tmp_path / f"run-{slug}.mcap"
        assert f"MCAP of {condition} run 1 (" in out
        run(capsys, "log", "import", str(path), "--events", str(tmp_path / f"{slug}.csv"))
        back = read_event_log(tmp_path / f"{slug}.csv")
        assert back == log.take((log.condition == condition) & (log.run == 1))
    assert not mcap.exists()


def test_log_import_of_the_name_given_to_simulate_reads_every_condition_s_file(tmp_path, capsys):
    """``simulate --mcap run.mcap`` of two conditions, then ``log import run.mcap`` (README)."""
    events, table, mcap = tmp_path / "sim.csv", tmp_path / "sim-table.csv", tmp_path / "run.mcap"
    code, _, err = run(
        capsys, "simulate", *SMALL, "--runs", "1", "--run-offset", "2", "--events", str(events),
        "--event-table", str(table), "--mcap", str(mcap),
    )  # fmt: skip  # the default conditions: proximity and urgency:alpha=0.7
    assert (code, err) == (0, "")
    files = [tmp_path / "run-proximity.mcap", tmp_path / "run-urgency-alpha-0.7.mcap"]
    assert sorted(tmp_path.glob("*.mcap")) == files
    back, back_table = tmp_path / "back.csv", tmp_path / "back-table.csv"
    code, out, err = run(
        capsys, "log", "import", str(mcap), "--events", str(back), "--event-table", str(back_table)
    )
    assert (code, err) == (0, "")
    lines = out.splitlines()
    assert lines[0] == (
        f"{mcap}: no such file; read the 2 files run-*.mcap beside it "
        "(one per condition, as simulate --mcap writes them) into one event log:"
    )
    assert lines[1].startswith(f"{files[0]}: 1 trial(s), 7 carrier rows (")
    assert lines[1].endswith("times in ticks, conditions proximity")
    assert lines[2].endswith("conditions urgency:alpha=0.7")
    assert lines[3:] == [
        f"wrote event log: {back}",
        f"wrote event table ({len(read_event_table(table))} rows): {back_table}",
    ]
    assert back.read_bytes() == events.read_bytes()
    assert back_table.read_bytes() == table.read_bytes()
    # a name with glob characters is matched as written, and an existing file wins
    for source in files:
        (tmp_path / source.name.replace("run-", "a[1]-")).write_bytes(source.read_bytes())
    only = tmp_path / "only.csv"
    code, out, _ = run(capsys, "log", "import", str(tmp_path / "a[1].mcap"), "--events", str(only))
    assert code == 0
    assert "read the 2 files a[1]-*.mcap" in out
    assert read_event_log(only) == read_event_log(events)
    code, out, _ = run(capsys, "log", "import", str(files[0]), "--events", str(only))
    assert code == 0
    assert "no such file" not in out
    assert read_event_log(only).conditions == ("proximity",)


def test_log_import_of_clashing_condition_files_is_one_line_naming_them(tmp_path, capsys):
    code, _, err = run(
        capsys, "simulate", *SMALL, "--runs", "1", "--condition", "proximity",
        "--mcap", str(tmp_path / "run-a.mcap"),
    )  # fmt: skip
    assert (code, err) == (0, "")
    (tmp_path / "run-b.mcap").write_bytes((tmp_path / "run-a.mcap").read_bytes())
    events = tmp_path / "e.csv"
    code, out, err = run(
        capsys, "log", "import", str(tmp_path / "run.mcap"), "--events", str(events)
    )
    assert (code, out) == (2, "")
    assert err.startswith(
        f"swarmtag: error: {tmp_path / 'run-a.mcap'}, {tmp_path / 'run-b.mcap'}: cannot be "
        "imported as one event log (run 0 of proximity has two rows for carrier "
    )
    assert err.endswith("; import each on its own\n")
    assert err.count("\n") == 1
    assert not events.exists()


def test_a_bag_with_service_events_imports_and_names_the_skipped_topic(tmp_path, capsys):
    from tests.io.bag_builders import SERVICE_TOPIC, SERVICE_TYPE, write_mcap_file

    bag = write_mcap_file(tmp_path / "all.mcap", TOPICS, lab_session())
    events = tmp_path / "e.csv"
    code, out, err = run(capsys, "log", "import", str(bag), "--events", str(events))
    assert (code, err) == (0, "")
    assert out.splitlines()[1] == (
        f"{bag}: skipped 1 topic(s) that hold no plain messages (not read): "
        f"{SERVICE_TOPIC} ({SERVICE_TYPE}: service events)"
    )
    assert events.read_text(encoding="utf-8") == format_csv(LAB_LOG)


def test_a_bag_read_short_of_its_metadata_count_exits_2_and_writes_nothing(tmp_path, capsys):
    bag = write_bag(tmp_path / "bag", "mcap", TOPICS, lab_session())
    metadata = bag / "metadata.yaml"
    text = metadata.read_text(encoding="utf-8")
    metadata.write_text(text.replace("message_count: 5\n", "message_count: 31\n"), "utf-8")
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    table = out_dir / "t.csv"
    code, out, err = run(
        capsys, "log", "import", str(bag), "--events", str(out_dir / "e.csv"),
        "--event-table", str(table),
    )  # fmt: skip
    assert (code, out) == (2, "")
    assert err == (
        f"swarmtag: error: {bag}: topic /swarmtag/robot_events: read 5 message(s), but "
        "metadata.yaml counts 31; the bag is damaged or its records disagree, so nothing is "
        "imported\n"
    )
    assert list(out_dir.iterdir()) == []
