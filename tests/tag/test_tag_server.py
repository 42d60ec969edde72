"""The tag-side transport interface and the replay server (writes from a list, no radio)."""

from __future__ import annotations

import pytest

from swarmtag.errors import FieldRangeError, StateRecordError
from swarmtag.tag import Change, MemoryStore, Role, TagStatus, WriteSigner, derive_role_key
from swarmtag.tag.backends.server import ReplayTagServer
from swarmtag.tag.emulator import SoftwareTag

SITE_KEY = b"k" * 32
OPERATOR = WriteSigner(writer=1, role=Role.OPERATOR, key=derive_role_key(SITE_KEY, Role.OPERATOR))


def tag(store: MemoryStore | None = None) -> SoftwareTag:
    return SoftwareTag.open(marker=4, site_key=SITE_KEY, store=store or MemoryStore())


def test_writes_are_served_in_order_and_handed_over_once():
    first = OPERATOR.sign(4, Change(status=TagStatus.AWAITING_PICKUP, urgency=6))
    writes = [first, first, b"\x01"]
    with ReplayTagServer(tag(), writes) as server:
        assert not server.finished
        assert server.outcomes() == []  # nothing served before the first poll
        server.poll()
        assert server.finished
        outcomes = server.outcomes()
    assert [o.att_error for o in outcomes] == [None, 0x81, 0x0D]
    assert outcomes[0].state.urgency == 6
    assert server.outcomes() == []
    assert server.failure is None
    assert server.tag.counts == {"accepted": 1, "ReplayedWrite": 1, "MalformedWrite": 1}


def test_a_stopped_server_serves_nothing():
    server = ReplayTagServer(tag(), [OPERATOR.sign(4, Change(urgency=1))])
    server.poll()  # not started
    server.start()
    server.stop()
    server.poll()
    assert server.outcomes() == []
    assert not server.finished


class FullDisk(MemoryStore):
    def __init__(self) -> None:
        super().__init__()
        self.full = False

    def save(self, record: bytes) -> None:
        if self.full:
            raise OSError(28, "No space left on device")
        super().save(record)


def test_a_store_that_cannot_save_stops_the_server():
    store = FullDisk()
    served = tag(store)
    store.full = True
    writes = [OPERATOR.sign(4, Change(urgency=1)), OPERATOR.sign(4, Change(urgency=2))]
    with ReplayTagServer(served, writes) as server:
        server.poll()
    assert isinstance(server.failure, StateRecordError)
    assert str(server.failure) == (
        "the tag's state could not be saved, so it stopped serving: No space left on device"
    )
    assert server.finished
    assert server.outcomes() == []  # the write was not acted on
    assert served.state.urgency == 0


@pytest.mark.parametrize("writes", [b"\x01" * 20, "0102", [b"ok", 5], None])
def test_writes_must_be_a_list_of_byte_values(writes):
    with pytest.raises(FieldRangeError):
        ReplayTagServer(tag(), writes)


def test_the_tag_must_be_a_software_tag():
    with pytest.raises(FieldRangeError, match="tag"):
        ReplayTagServer("tag", [])  # type: ignore[arg-type]
