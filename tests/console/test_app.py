import json

import pytest

pytest.importorskip("starlette", reason="the console extra")  # installed by make test (dev)

from starlette.testclient import TestClient

from swarmtag.console.app import make_app
from swarmtag.console.auth import COOKIE
from tests.console.helpers import core

TOKEN = "t" * 43


@pytest.fixture
def client(tmp_path):
    with TestClient(make_app(core(tmp_path), TOKEN), base_url="http://127.0.0.1") as client:
        yield client


def bearer(token=TOKEN):
    return {"Authorization": f"Bearer {token}"}


@pytest.mark.parametrize(
    "path",
    ["/api/tags", "/api/kpis", "/api/floor", "/api/state", "/api/events", "/api/tags/3/eink"],
)
def test_every_api_call_needs_the_token(client, path):
    assert client.get(path).status_code == 401
    assert client.get(path, headers=bearer("x" * 43)).status_code == 401


def test_writes_need_the_token(client):
    answer = client.post("/api/tags/3/urgency", json={"urgency": 9})
    assert answer.status_code == 401
    assert (
        client.post(
            "/api/tags/3/urgency", json={"urgency": 9}, headers=bearer("x" * 43)
        ).status_code
        == 401
    )


def test_tags_with_the_token(client):
    answer = client.get("/api/tags", headers=bearer())
    assert answer.status_code == 200
    tags = answer.json()
    assert {"marker", "urgency", "status", "destination", "last_heard"} <= set(tags[0])


def test_post_urgency_then_the_list_shows_it(client):
    marker = next(
        t["marker"] for t in client.get("/api/tags", headers=bearer()).json() if t["urgency"] != 9
    )
    answer = client.post(f"/api/tags/{marker}/urgency", json={"urgency": 9}, headers=bearer())
    assert answer.status_code == 200, answer.text
    assert answer.json()["urgency"] == 9
    for _ in range(100):  # the stepping task applies it at the next tick (20 ms at speed 5)
        tags = {t["marker"]: t for t in client.get("/api/tags", headers=bearer()).json()}
        if tags[marker]["urgency"] == 9:
            break
        import time

        time.sleep(0.01)
    assert tags[marker]["urgency"] == 9


def test_bad_write_is_4xx_with_a_message(client):
    answer = client.post("/api/tags/3/urgency", json={"urgency": 10}, headers=bearer())
    assert answer.status_code == 422
    assert "0-9" in answer.json()["error"]
    huge = client.post(
        "/api/tags/3/urgency", content=b"{" + b" " * 100_000 + b"}", headers=bearer()
    )
    assert huge.status_code == 413


def test_token_url_sets_a_strict_cookie_and_drops_the_token_from_the_address(client):
    page = client.get("/")
    assert page.status_code == 401
    answer = client.get(f"/?token={TOKEN}", follow_redirects=False)
    assert answer.status_code == 303
    assert answer.headers["location"] == "/"
    cookie = answer.headers["set-cookie"]
    assert "HttpOnly" in cookie
    assert "SameSite=strict" in cookie or "SameSite=Strict" in cookie
    assert client.cookies.get(COOKIE) == TOKEN
    assert client.get("/").status_code == 200
    assert client.get("/api/tags").status_code == 200


def test_cookie_writes_need_the_console_header(client):
    client.get(f"/?token={TOKEN}")
    forged = client.post("/api/tags/3/urgency", json={"urgency": 9})  # what another site could send
    assert forged.status_code == 403
    good = client.post(
        "/api/tags/3/urgency", json={"urgency": 9}, headers={"X-Swarmtag-Console": "1"}
    )
    assert good.status_code == 200


def test_a_wrong_token_url_is_refused(client):
    assert client.get("/?token=nope", follow_redirects=False).status_code == 401
    assert COOKIE not in client.cookies


def test_static_assets_and_nothing_else(client):
    assert client.get("/static/console.js").status_code == 200
    assert client.get("/static/console.css").headers["content-type"].startswith("text/css")
    assert client.get("/static/..%2Fapi.py").status_code == 404
    assert client.get("/static/index.html").status_code == 404


def test_eink_png(client):
    answer = client.get("/api/tags/3/eink", headers=bearer())
    assert answer.status_code == 200
    assert answer.headers["content-type"] == "image/png"
    assert answer.content.startswith(b"\x89PNG")


def test_event_stream_sends_state_and_kpis(client):
    with client.stream("GET", "/api/events", headers=bearer()) as stream:
        assert stream.headers["content-type"].startswith("text/event-stream")
        kinds = {}
        lines = stream.iter_lines()
        while len(kinds) < 2:
            line = next(lines)
            if line.startswith("event: "):
                kind = line.removeprefix("event: ")
                kinds[kind] = json.loads(next(lines).removeprefix("data: "))
    assert {"robots", "tags", "tick"} <= set(kinds["state"])
    assert "deliveries" in kinds["kpis"]


def test_replay_controls_need_the_token_and_a_replay(client):
    assert client.post("/api/replay", json={"playing": False}).status_code == 401
    answer = client.post("/api/replay", json={"playing": False}, headers=bearer())
    assert answer.status_code == 409
    assert "no replay controls" in answer.json()["error"]


@pytest.fixture
def replay_client(tmp_path):
    from swarmtag.console.replay_file import read_recording
    from swarmtag.console.server import replay_core
    from tests.console.recordings import TICK, write_log

    recording = read_recording(write_log(tmp_path), tick_seconds=TICK)
    core = replay_core(recording, audit_log=tmp_path / "audit.jsonl")
    with TestClient(make_app(core, TOKEN), base_url="http://127.0.0.1") as client:
        yield client


def test_replay_controls_seek_and_the_tags_follow(replay_client):
    client = replay_client
    answer = client.post("/api/replay", json={"playing": False, "time": 40}, headers=bearer())
    assert answer.status_code == 200, answer.text
    assert answer.json()["playing"] is False
    tags = client.get("/api/tags", headers=bearer()).json()
    assert [t["status"] for t in tags] == ["idle", "picked_up", "awaiting_pickup"]
    bad = client.post("/api/replay", json={"time": -5}, headers=bearer())
    assert bad.status_code == 422
    client.get(f"/?token={TOKEN}")
    forged = client.post("/api/replay", json={"time": 0})  # the cookie alone: another site
    assert forged.status_code == 403
    write = client.post("/api/tags/1/urgency", json={"urgency": 9}, headers=bearer())
    assert write.status_code == 409
    assert "a replay cannot be re-prioritised" in write.json()["error"]
