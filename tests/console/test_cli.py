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
    done = subprocess.run(
        [str(SWARMTAG), "console", "--port", "0", *args],
        cwd=tmp_path,
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
    assert list(tmp_path.iterdir()) == []  # nothing written
