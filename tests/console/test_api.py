import json

import pytest

from swarmtag.console.api import MAX_BODY
from swarmtag.errors import ForgedWrite, ReplayedWrite
from swarmtag.tag import Change, Role, derive_robot_key
from swarmtag.tag.keys import derive_role_key
from swarmtag.tag.write import Write, sign
from tests.console.helpers import core


def _audit(tmp_path):
    return [json.loads(line) for line in (tmp_path / "audit.jsonl").read_text().splitlines()]


def _urgencies(c):
    return {t["marker"]: t["urgency"] for t in c.tags().body}


def test_tags_list_has_the_contract_fields(tmp_path):
    c = core(tmp_path)
    c.source.advance(1.0)
    tags = c.tags().body
    assert [t["marker"] for t in tags] == list(range(7))
    for t in tags:
        assert {"marker", "urgency", "status", "destination", "last_heard", "carried_by"} <= set(t)
        assert 0 <= t["urgency"] <= 9


def test_urgency_write_is_signed_verified_and_reaches_the_simulation(tmp_path):
    c = core(tmp_path)
    marker = next(m for m, u in _urgencies(c).items() if u != 9)
    reply = c.write(
        who="me", client="me", marker=str(marker), field="urgency", body=b'{"urgency": 9}'
    )
    assert reply.status == 200, reply.body
    assert reply.body["urgency"] == 9
    c.source.step_once()  # the simulator's WMS write lands at the next tick
    assert _urgencies(c)[marker] == 9
    assert (tmp_path / "operator.counters").read_text().split()[-1] == "0"  # counter reserved
    (line,) = _audit(tmp_path)
    assert line["outcome"] == "accepted"
    assert line["tag"] == str(marker)
    assert line["change"] == {"field": "urgency", "value": 9, "counter": 0}
    assert {"time", "who"} <= set(line)


@pytest.mark.parametrize(
    ("marker", "field", "body", "status", "says"),
    [
        ("3", "urgency", b'{"urgency": 10}', 422, "not in 0-9"),
        ("3", "urgency", b'{"urgency": -1}', 422, "not in 0-9"),
        ("3", "urgency", b'{"urgency": true}', 400, "integer"),
        ("3", "urgency", b'{"urgency": "9"}', 400, "integer"),
        ("3", "urgency", b"{urgency: 9", 400, "not JSON"),
        ("3", "urgency", b'{"urgency": 9, "status": 1}', 400, "exactly one key"),
        ("3", "urgency", b"[9]", 400, "exactly one key"),
        ("3", "urgency", b'{"urgency": 9' + b" " * MAX_BODY + b"}", 413, "bytes"),
        ("99", "urgency", b'{"urgency": 9}', 404, "no tag"),
        ("abc", "urgency", b'{"urgency": 9}', 404, "no tag"),
        ("3", "colour", b'{"colour": 9}', 404, "no field"),
        ("3", "status", b'{"status": "lost"}', 422, "status"),
        ("3", "status", b'{"status": "picked_up"}', 409, "only a robot lifts"),
        ("3", "destination", b'{"destination": 7}', 409, "no drop-off area"),
        ("3", "destination", b'{"destination": 256}', 422, "not in 0-255"),
    ],
)
def test_bad_writes_are_refused_change_nothing_and_are_audited(  # noqa: PLR0917
    tmp_path, marker, field, body, status, says
):
    c = core(tmp_path)
    before = c.tags().body
    reply = c.write(who="me", client="me", marker=marker, field=field, body=body)
    assert reply.status == status
    assert says in reply.body["error"]
    c.source.step_once()
    after = c.tags().body
    assert [(t["urgency"], t["status"], t["destination"]) for t in after] == [
        (t["urgency"], t["status"], t["destination"]) for t in before
    ]
    (line,) = _audit(tmp_path)
    assert line["outcome"] == "refused"
    assert line["status"] == status


def test_hold_and_release_a_waiting_carrier(tmp_path):
    c = core(tmp_path)
    waiting = next(t["marker"] for t in c.tags().body if t["carried_by"] is None)
    held = c.write(
        who="me", client="me", marker=str(waiting), field="status", body=b'{"status": "idle"}'
    )
    assert held.status == 200
    assert c.source.tag_state(waiting).status.name == "IDLE"
    back = c.write(
        who="me", client="me", marker=str(waiting), field="status", body=b'{"status": 1}'
    )
    assert back.status == 200
    assert c.source.tag_state(waiting).status.name == "AWAITING_PICKUP"


def test_write_rate_is_bounded_per_client(tmp_path):
    c = core(tmp_path, writes_per_second=0.001)
    answers = [
        c.write(who="a", client="a", marker="3", field="urgency", body=b'{"urgency": 5}').status
        for _ in range(c.limiter.burst + 2)
    ]
    assert answers[: c.limiter.burst] == [200] * c.limiter.burst
    assert answers[c.limiter.burst :] == [429, 429]
    other = c.write(who="b", client="b", marker="3", field="urgency", body=b'{"urgency": 5}')
    assert other.status == 200


def test_the_tag_refuses_a_forged_or_replayed_write(tmp_path):
    c = core(tmp_path)
    state = c.source.tag_state(3)
    robot_key = derive_robot_key(c.source.site_key, 0xFFFD)  # not the operator key
    forged = sign(
        Write(writer=0xFFFD, role=Role.OPERATOR, counter=50, target=3, change=Change(urgency=9)),
        robot_key,
    )
    with pytest.raises(ForgedWrite):
        c.desk.deliver(3, state, forged)
    good = sign(
        Write(writer=0xFFFD, role=Role.OPERATOR, counter=50, target=3, change=Change(urgency=9)),
        derive_role_key(c.source.site_key, Role.OPERATOR),
    )
    assert c.desk.deliver(3, state, good).urgency == 9
    with pytest.raises(ReplayedWrite):
        c.desk.deliver(3, state, good)


def test_a_console_with_another_sites_operator_key_writes_nothing(tmp_path):
    c = core(tmp_path, operator_key=derive_role_key(b"another-site-key", Role.OPERATOR))
    before = c.source.tag_state(3)
    reply = c.write(who="me", client="me", marker="3", field="urgency", body=b'{"urgency": 9}')
    assert reply.status == 409
    assert "MAC" in reply.body["error"]
    c.source.step_once()
    assert c.source.tag_state(3).urgency == before.urgency


def test_kpis_count_deliveries_so_far(tmp_path):
    c = core(tmp_path)
    first = c.kpis().body
    assert first["deliveries"] == 0
    for _ in range(2000):  # the first delivery comes within a few hundred ticks
        c.source.step_once()
        if c.source.log().delivery_time.size and (c.source.log().delivery_time >= 0).any():
            break
    c._kpis = None  # past the half-second cache
    k = c.kpis().body
    assert k["deliveries"] > 0
    assert k["p95_latency"] >= k["mean_latency"] > 0
    assert 0 <= k["pa"] <= 1


def test_eink_picture_is_a_png(tmp_path):
    c = core(tmp_path)
    png = c.eink("3")
    assert isinstance(png, bytes)
    assert png.startswith(b"\x89PNG")
    assert c.eink("300").status == 404
