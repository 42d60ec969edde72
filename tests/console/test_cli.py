import json
import stat
import subprocess
import time

import pytest

from tests.console.server_process import SWARMTAG, start

pytest.importorskip("uvicorn", reason="the console extra")  # installed by make test (dev)


@pytest.fixture
def console(tmp_path):
    running = start(tmp_path)
    yield running
    running.close()


def test_serves_the_api_to_holders_of_the_token(console):
    token_file = console.folder / "token"
    assert stat.S_IMODE(token_file.stat().st_mode) == 0o600
    assert token_file.read_text().strip() == console.token
    assert console.get("/api/tags")[0] == 401
    status, body = console.get("/api/tags", token=console.token)
    assert status == 200
    tags = json.loads(body)
    marker = next(t["marker"] for t in tags if t["urgency"] != 9)
    status, body = console.post(f"/api/tags/{marker}/urgency", b'{"urgency": 9}')
    assert status == 200, body
    deadline = time.monotonic() + 1.0
    while True:
        tags = {
            t["marker"]: t for t in json.loads(console.get("/api/tags", token=console.token)[1])
        }
        if tags[marker]["urgency"] == 9 or time.monotonic() > deadline:
            break
    assert tags[marker]["urgency"] == 9  # within a second
    status, body = console.post(f"/api/tags/{marker}/urgency", b'{"urgency": 10}')
    assert status == 422
    audit = [
        json.loads(line)
        for line in (console.folder / "swarmtag-console-audit.jsonl").read_text().splitlines()
    ]
    assert [(a["tag"], a["outcome"]) for a in audit] == [
        (str(marker), "accepted"),
        (str(marker), "refused"),
    ]
    assert (console.folder / "swarmtag-console-operator.counters").exists()


@pytest.mark.serial  # bounds seconds
def test_ctrl_c_ends_the_server_within_a_second(console):
    running = console
    # an open event stream must not hold the shutdown up
    import urllib.request

    request = urllib.request.Request(running.base + "/api/events")
    request.add_header("Authorization", f"Bearer {running.token}")
    stream = urllib.request.urlopen(request, timeout=5)
    assert stream.readline().startswith(b"event: ")
    took = running.interrupt()
    stream.close()
    assert took < 1.0, took
    assert running.process.returncode == 130
    _, stderr = running.process.communicate()
    assert stderr.strip().splitlines()[-1] == "swarmtag: error: aborted"
    assert "Traceback" not in stderr


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--speed", "0"], "--speed"),
        (["--port", "70000"], "--port"),
        (["--condition", "nonsense"], "nonsense"),
        (["--token-file", "missing/token"], "does not exist"),
        (["--robots", "0"], "--robots"),
        (["--set", "camera.memory=-1"], "camera.memory"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(tmp_path, args, says):
    _refused_in_one_line(tmp_path, args, says)
    assert list(tmp_path.iterdir()) == []  # nothing written


def _refused_in_one_line(folder, args, says):
    """``swarmtag console --port 0 ARGS`` in ``folder``: exit 2, one line saying ``says``."""
    done = subprocess.run(
        [str(SWARMTAG), "console", "--port", "0", *args],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith("swarmtag: error:")
    assert says in lines[0]


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--sim", "--scan"], "--sim and --scan: give one source"),
        (["--scan", "--replay", "run.csv"], "--scan and --replay: give one source"),
        (["--replay", "missing.csv"], "no such file"),
        (["--replay", "notes.txt"], "not an event log"),
        (["--replay", "broken.csv"], "lacks columns"),
        (["--replay", "broken.mcap"], "broken.mcap"),
        (["--scan", "--key-file", "missing.key", "--backend", "sim"], "missing.key"),
    ],
)
def test_bad_sources_are_one_line_and_exit_2(tmp_path, args, says):
    (tmp_path / "notes.txt").write_text("hello\n")
    (tmp_path / "broken.csv").write_text("a,b\n1,2\n")
    (tmp_path / "broken.mcap").write_bytes(b"\x89MCAP0\r\n" + b"\0" * 40)
    before = sorted(tmp_path.iterdir())
    _refused_in_one_line(tmp_path, args, says)
    assert sorted(tmp_path.iterdir()) == before  # no token, no audit log


def test_scan_without_an_adapter_is_one_line(tmp_path, monkeypatch, capsys):
    """bleak's scanner fails as on a machine with no adapter: exit 2, nothing written."""
    pytest.importorskip("bleak", reason="the ble extra")
    from swarmtag.tag.backends import bleak as bleak_backend

    class NoAdapter:
        def __init__(self, **_options):
            pass

        async def start(self):
            raise bleak_backend.BleakError("No Bluetooth adapters found.")

        async def stop(self):
            pass

    monkeypatch.setattr(bleak_backend.bleak, "BleakScanner", NoAdapter)
    assert _scan_refused(tmp_path, monkeypatch, capsys) == (
        "swarmtag: error: --scan: no Bluetooth adapter found: plug in a BLE adapter and "
        "check 'bluetoothctl list'"
    )


def _scan_refused(folder, monkeypatch, capsys):
    """``console --scan`` run in ``folder``: exit 2, nothing written there; its one stderr line."""
    from swarmtag.cli import main

    monkeypatch.chdir(folder)
    with pytest.raises(SystemExit) as ended:
        main(["console", "--scan", "--port", "0"])
    assert ended.value.code == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert list(folder.iterdir()) == []
    return line


def test_scan_bounds_the_wait_for_the_scanner_thread_at_ctrl_c(tmp_path, monkeypatch, capsys):
    """bleak's scanner thread is waited for at most half a second: Ctrl-C ends within one."""
    from swarmtag.cli import main
    from swarmtag.errors import ConfigError
    from swarmtag.tag import backends

    asked = {}

    def scanner(backend, **options):
        asked.update(options, backend=backend)
        raise ConfigError("stop here")

    monkeypatch.setattr(backends, "open_scanner", scanner)
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit):
        main(["console", "--scan", "--port", "0"])
    assert asked["backend"] == "bleak"
    assert 0 < asked["join_timeout"] <= 0.5


def test_scan_without_bleak_is_one_line(tmp_path, monkeypatch, capsys):
    import sys

    monkeypatch.setitem(sys.modules, "bleak", None)
    monkeypatch.delitem(sys.modules, "swarmtag.tag.backends.bleak_writer", raising=False)
    monkeypatch.delitem(sys.modules, "swarmtag.tag.backends.bleak", raising=False)
    assert _scan_refused(tmp_path, monkeypatch, capsys) == (
        "swarmtag: error: console --scan needs the bleak package, which is not installed: "
        "pip install 'swarmtag[ble]'"
    )


def test_replay_serves_the_file_and_refuses_writes(tmp_path):
    from tests.console.recordings import write_log

    write_log(tmp_path)
    running = start(tmp_path, "--tick", "0.1", source=("--replay", "run.csv"))
    try:
        status, body = running.get("/api/floor", token=running.token)
        assert status == 200
        floor = json.loads(body)
        assert (floor["source"], floor["kind"]) == ("replay", "none")
        status, body = running.post("/api/replay", b'{"playing": false, "time": 8}')
        assert status == 200, body
        tags = json.loads(running.get("/api/tags", token=running.token)[1])
        assert {t["marker"]: t["status"] for t in tags} == {
            0: "idle",
            1: "picked_up",
            2: "awaiting_pickup",
        }
        status, body = running.post("/api/tags/1/urgency", b'{"urgency": 9}')
        assert status == 409
        assert "a replay cannot be re-prioritised" in json.loads(body)["error"]
        (line,) = (tmp_path / "swarmtag-console-audit.jsonl").read_text().splitlines()
        assert json.loads(line)["status"] == 409
        assert running.interrupt() < 1.0
    finally:
        running.close()


def test_scan_on_the_bench_radio_serves_and_writes(tmp_path):
    pytest.importorskip("bleak", reason="the ble extra")
    running = start(tmp_path, "--backend", "sim", source=("--scan",))
    try:
        deadline = time.monotonic() + 5
        tags: list[dict[str, object]] = []
        while len(tags) < 3 and time.monotonic() < deadline:
            tags = json.loads(running.get("/api/tags", token=running.token)[1])
            time.sleep(0.1)
        assert sorted(t["marker"] for t in tags) == [7, 12, 21]
        status, body = running.post("/api/tags/21/urgency", b'{"urgency": 0}')
        assert status == 200, body
        tags = json.loads(running.get("/api/tags", token=running.token)[1])
        assert {t["marker"]: t["urgency"] for t in tags}[21] == 0
        assert running.interrupt() < 1.0
    finally:
        running.close()
