"""The bleak writer without a radio: a client with BleakClient's interface, bleak's own errors.

``FakeClient`` answers as a tag's GATT server behind a ``TagModel`` and, on
every write, checks that the counter it carries is already in the counter
file (persisted before sending). Refusals are raised as bleak raises them:
``BleakGATTProtocolError`` (bleak >= 3.0) and the BlueZ ``BleakDBusError``
forms of older bleak.
"""

from __future__ import annotations

import asyncio
import functools
from typing import ClassVar

import pytest

pytest.importorskip("bleak")

import bleak
from bleak.exc import (
    BleakCharacteristicNotFoundError,
    BleakDBusError,
    BleakDeviceNotFoundError,
    BleakError,
)

from swarmtag.errors import (
    ClaimRefused,
    ConfigError,
    CounterFileError,
    ForgedWrite,
    IllegalTransition,
    KeyFileError,
    MalformedWrite,
    RadioError,
    ReplayedWrite,
    RoleNotAllowed,
    WriteRejected,
    WriterTableFull,
    WrongTarget,
)
from swarmtag.tag import (
    ATT_ERRORS,
    STATE_CHAR_UUID,
    WRITE_CHAR_UUID,
    Change,
    MemoryStore,
    Role,
    TagModel,
    TagState,
    TagStatus,
    WriteSigner,
    derive_robot_key,
    derive_role_key,
    write_key_file,
    write_robot_key_file,
    write_role_key_file,
)
from swarmtag.tag.backends.bleak_writer import (
    REFUSALS,
    BleakTagWriter,
    att_error_code,
    refusal,
)
from swarmtag.tag.counter import CounterFile

GATTProtocolError = getattr(bleak.exc, "BleakGATTProtocolError", None)
SITE = bytes(range(40, 72))
ROBOT_KEY = derive_robot_key(SITE, 7)  # robot 7's own key
OPERATOR_KEY = derive_role_key(SITE, Role.OPERATOR)
ADDRESS = "C4:7F:0E:12:34:56"
WAITING = TagState(urgency=6, status=TagStatus.AWAITING_PICKUP, destination=2, marker=12)


def new_tag(state: TagState = WAITING) -> TagModel:
    return TagModel.provision(state, site_key=SITE, store=MemoryStore())


def gatt_error(code: int) -> BleakError:
    """What bleak raises for an ATT error: BleakGATTProtocolError, or BlueZ's D-Bus error."""
    if GATTProtocolError is not None:
        return GATTProtocolError(code)
    return BleakDBusError(
        "org.bluez.Error.Failed", [f"Operation failed with ATT error: 0x{code:02x}"]
    )


class FakeClient:
    """bleak's BleakClient interface, serving a TagModel; records what was asked of it."""

    made: ClassVar[list[FakeClient]] = []

    def __init__(self, address, *, tag, counters, timeout=30.0, hang=None, fail=None, **options):
        self.address, self.tag, self.counters = address, tag, counters
        self.timeout, self.options = timeout, options
        self.hang, self.fail = hang or set(), fail or {}
        self.calls: list[str] = []
        self.sent: list[bytes] = []
        self.connected = False
        FakeClient.made.append(self)

    async def _maybe(self, step: str) -> None:
        self.calls.append(step)
        if step in self.hang:
            await asyncio.sleep(3600)
        if step in self.fail:
            raise self.fail[step]

    async def connect(self) -> None:
        await self._maybe("connect")
        self.connected = True

    async def disconnect(self) -> None:
        await self._maybe("disconnect")
        self.connected = False

    async def read_gatt_char(self, char_specifier):
        await self._maybe("read")
        assert self.connected
        if char_specifier != STATE_CHAR_UUID:
            raise BleakCharacteristicNotFoundError(char_specifier)
        state = self.tag.state
        return bytearray([state.urgency, int(state.status), state.destination, state.marker])

    async def write_gatt_char(self, char_specifier, data, response=None):
        await self._maybe("write")
        assert self.connected
        assert char_specifier == WRITE_CHAR_UUID
        assert response is True  # write with response: the verdict comes back
        writer, counter = int.from_bytes(data[2:4], "little"), int.from_bytes(data[4:8], "little")
        assert self.counters.last(writer) == counter, "sent before it was saved"
        self.sent.append(bytes(data))
        try:
            self.tag.apply(data)
        except WriteRejected as refused:
            raise gatt_error(refused.att_error) from None


@pytest.fixture
def counters(tmp_path):
    return CounterFile(tmp_path / "writer.counters")


def writer_for(tag, counters, *, role=Role.ROBOT, writer=7, timeout=2.0, adapter=None, **client):
    FakeClient.made.clear()
    factory = functools.partial(FakeClient, tag=tag, counters=counters, **client)
    key = derive_robot_key(SITE, writer) if role is Role.ROBOT else OPERATOR_KEY
    return BleakTagWriter(
        writer=writer,
        role=role,
        key=key,
        counters=counters,
        timeout=timeout,
        client_factory=factory,
        adapter=adapter,
    )


def test_an_accepted_write_reads_back_the_new_state(counters):
    tag = new_tag()
    outcome = writer_for(tag, counters).write(ADDRESS.lower(), Change(status=TagStatus.PICKED_UP))
    assert outcome.address == ADDRESS
    assert (outcome.writer, outcome.role, outcome.counter) == (7, Role.ROBOT, 0)
    assert outcome.before == WAITING
    assert outcome.after == tag.state
    assert outcome.after.status is TagStatus.PICKED_UP
    assert outcome.confirmed
    client = FakeClient.made[0]
    assert client.calls == ["connect", "read", "write", "read", "disconnect"]
    assert client.address == ADDRESS
    assert client.timeout == 2.0
    assert counters.last(7) == 0


def test_counters_go_up_across_writers_processes_and_tags(counters):
    tags = [new_tag(WAITING), new_tag(TagState(1, TagStatus.IDLE, 0, 30))]
    for urgency in range(3):
        for tag in tags:  # a fresh writer object each time, as a restarted process
            outcome = writer_for(tag, counters, role=Role.OPERATOR, writer=2).write(
                ADDRESS, Change(urgency=urgency)
            )
            assert outcome.after.urgency == urgency
    assert counters.last(2) == 5
    assert [tag.counters[2] for tag in tags] == [4, 5]


@pytest.mark.parametrize(
    ("state", "role", "change", "refused"),
    [
        (WAITING, Role.ROBOT, Change(urgency=1), RoleNotAllowed),
        (WAITING, Role.ROBOT, Change(status=TagStatus.IDLE), IllegalTransition),
    ],
)
def test_a_refusal_is_its_typed_error_with_the_att_code(counters, state, role, change, refused):
    tag = new_tag(state)
    with pytest.raises(refused) as caught:
        writer_for(tag, counters, role=role).write(ADDRESS, change)
    message = str(caught.value)
    code = ATT_ERRORS[refused]
    assert message.startswith(f"tag 12 at {ADDRESS} refused the write: ATT error 0x{code:02X}")
    assert f"({refused.__name__})" in message
    assert caught.value.att_error == code
    assert tag.state == state  # unchanged
    assert FakeClient.made[0].calls[-1] == "disconnect"
    assert counters.last(7) == 0  # the refused write spent its counter


def test_a_lost_counter_file_gets_replayed_write_and_says_what_to_do(tmp_path):
    tag = new_tag(TagState(1, TagStatus.IDLE, 0, 12))
    first = CounterFile(tmp_path / "a.counters")
    writer_for(tag, first, role=Role.OPERATOR, writer=4).write(ADDRESS, Change(urgency=3))
    again = CounterFile(tmp_path / "b.counters")  # a new machine, the same writer id
    with pytest.raises(ReplayedWrite, match=r"0x81 .*from writer 4: this counter file is behind"):
        writer_for(tag, again, role=Role.OPERATOR, writer=4).write(ADDRESS, Change(urgency=5))
    assert tag.state.urgency == 3


def test_a_write_under_another_sites_key_is_forged(counters):
    tag = new_tag()
    factory = functools.partial(FakeClient, tag=tag, counters=counters)
    other_site = derive_role_key(bytes(32), Role.OPERATOR)
    writer = BleakTagWriter(
        writer=1, role=Role.OPERATOR, key=other_site, counters=counters, client_factory=factory
    )
    with pytest.raises(ForgedWrite, match=r"0x80 \(ForgedWrite\): the MAC does not verify"):
        writer.write(ADDRESS, Change(urgency=0))
    assert tag.state == WAITING
    assert tag.counters == {}


@pytest.mark.parametrize("kind", sorted(ATT_ERRORS, key=ATT_ERRORS.get))
def test_every_tag_code_maps_back_to_its_refusal(kind):
    code = ATT_ERRORS[kind]
    assert REFUSALS[code] is kind
    forms = [
        BleakDBusError("org.bluez.Error.Failed", [f"Operation failed with ATT error: 0x{code:02x}"])
    ]
    if GATTProtocolError is not None:
        forms.append(GATTProtocolError(code))
    if code == 0x0D:  # BlueZ names this one itself (create_gatt_dbus_error)
        forms.append(BleakDBusError("org.bluez.Error.InvalidArguments", ["Invalid Length"]))
    for error in forms:
        assert att_error_code(error) == code
        found = refusal(error, address=ADDRESS, writer=9, before=WAITING)
        assert type(found) is kind
        assert f"ATT error 0x{code:02X} ({kind.__name__})" in str(found)


def test_the_refusal_table_is_the_inverse_of_att_errors():
    assert {kind: code for code, kind in REFUSALS.items()} == ATT_ERRORS
    assert set(REFUSALS.values()) == {
        MalformedWrite,
        ForgedWrite,
        ReplayedWrite,
        WrongTarget,
        RoleNotAllowed,
        IllegalTransition,
        WriterTableFull,
        ClaimRefused,
    }


@pytest.mark.parametrize(
    ("error", "code"),
    [
        (BleakDBusError("org.bluez.Error.NotPermitted", ["Write not permitted"]), 0x03),
        (BleakDBusError("org.bluez.Error.NotPermitted", ["Read not permitted"]), 0x02),
        (BleakDBusError("org.bluez.Error.NotSupported", []), 0x06),
        (BleakDBusError("org.bluez.Error.NotAuthorized", []), 0x08),
        (BleakDBusError("org.bluez.Error.Failed", ["Operation failed with ATT error: 0x0e"]), 0x0E),
    ],
)
def test_other_att_codes_say_the_device_is_no_swarmtag_tag(error, code):
    assert att_error_code(error) == code
    found = refusal(error, address=ADDRESS, writer=1)
    assert isinstance(found, RadioError)
    assert f"ATT error 0x{code:02X}" in str(found)
    assert "which a swarmtag tag never sends" in str(found)


@pytest.mark.parametrize(
    "error",
    [
        BleakError("Not connected"),
        BleakDBusError("org.bluez.Error.Failed", ["le-connection-abort-by-local"]),
        BleakDBusError("org.freedesktop.DBus.Error.ServiceUnknown", []),
        OSError(5, "Input/output error"),
    ],
)
def test_errors_without_an_att_code_are_radio_errors(error):
    assert att_error_code(error) is None
    found = refusal(error, address=ADDRESS, writer=1)
    assert isinstance(found, RadioError)
    assert str(found).startswith(f"writing to {ADDRESS} failed: ")


def test_a_lost_connection_during_the_write_says_the_counter_is_spent(counters):
    tag = new_tag()
    with pytest.raises(RadioError) as caught:
        writer_for(tag, counters, fail={"write": BleakError("Not connected")}).write(
            ADDRESS, Change(status=TagStatus.PICKED_UP)
        )
    assert str(caught.value) == (
        f"writing to {ADDRESS} failed (it may or may not have been applied; counter 0 is spent): "
        "Bluetooth adapter error: BleakError: Not connected"
    )
    assert counters.last(7) == 0


def test_a_device_not_found_is_one_line_and_spends_no_counter(counters):
    error = BleakDeviceNotFoundError(ADDRESS, f"Device with address {ADDRESS} was not found.")
    with pytest.raises(RadioError, match=r"no device C4:7F:0E:12:34:56 found within 2 s"):
        writer_for(new_tag(), counters, fail={"connect": error}).write(
            ADDRESS, Change(status=TagStatus.PICKED_UP)
        )
    assert counters.last(7) is None
    assert not (counters.path).exists()


def test_no_bluez_is_the_scanners_one_line(counters):
    error = BleakDBusError("org.freedesktop.DBus.Error.ServiceUnknown", [])
    with pytest.raises(RadioError, match=r"BlueZ is not reachable.*sudo apt install bluez"):
        writer_for(new_tag(), counters, fail={"connect": error}).write(
            ADDRESS, Change(status=TagStatus.PICKED_UP)
        )
    assert counters.last(7) is None


def test_a_connect_that_hangs_times_out(counters):
    with pytest.raises(RadioError, match=r"could not connect to .* within 0.2 s"):
        writer_for(new_tag(), counters, timeout=0.2, hang={"connect"}).write(
            ADDRESS, Change(status=TagStatus.PICKED_UP)
        )
    assert counters.last(7) is None


def test_a_write_that_hangs_times_out_and_says_the_counter_is_spent(counters):
    tag = new_tag()
    with pytest.raises(
        RadioError, match=r"may or may not have been applied \(counter 0 is spent\)"
    ):
        writer_for(tag, counters, timeout=0.2, hang={"write"}).write(
            ADDRESS, Change(status=TagStatus.PICKED_UP)
        )
    assert counters.last(7) == 0
    assert FakeClient.made[0].calls[-1] == "disconnect"


def test_a_device_without_our_service_is_no_tag(counters):
    error = BleakCharacteristicNotFoundError(STATE_CHAR_UUID)
    with pytest.raises(RadioError, match=r"has no swarmtag GATT service.*not a swarmtag tag"):
        writer_for(new_tag(), counters, fail={"read": error}).write(
            ADDRESS, Change(status=TagStatus.PICKED_UP)
        )
    assert counters.last(7) is None


def test_state_bytes_that_are_no_tag_state_are_refused(counters):
    class Odd(FakeClient):
        async def read_gatt_char(self, char_specifier):
            return bytearray(b"\x0a\x01\x02")

    factory = functools.partial(Odd, tag=new_tag(), counters=counters)
    writer = BleakTagWriter(writer=7, role=Role.ROBOT, key=ROBOT_KEY, counters=counters,
                            client_factory=factory)  # fmt: skip
    with pytest.raises(RadioError, match="3 state bytes that are not a swarmtag tag state"):
        writer.write(ADDRESS, Change(status=TagStatus.PICKED_UP))
    assert counters.last(7) is None


def test_a_disconnect_failure_does_not_undo_the_result(counters, caplog):
    outcome = writer_for(new_tag(), counters, fail={"disconnect": BleakError("gone")}).write(
        ADDRESS, Change(status=TagStatus.PICKED_UP)
    )
    assert outcome.after.status is TagStatus.PICKED_UP
    assert "disconnecting from C4:7F:0E:12:34:56 failed" in caplog.text


def test_the_marker_is_checked_before_anything_is_signed(counters):
    tag = new_tag()
    with pytest.raises(ConfigError, match="is marker 12, not 13: nothing was sent"):
        writer_for(tag, counters).write(ADDRESS, Change(status=TagStatus.PICKED_UP), marker=13)
    assert FakeClient.made[0].sent == []
    assert counters.last(7) is None
    outcome = writer_for(tag, counters).write(
        ADDRESS, Change(status=TagStatus.PICKED_UP), marker=12
    )
    assert outcome.after.status is TagStatus.PICKED_UP


def test_a_state_changed_by_someone_else_is_not_confirmed(counters):
    tag = new_tag(TagState(1, TagStatus.IDLE, 0, 12))

    class Busy(FakeClient):
        async def write_gatt_char(self, char_specifier, data, response=None):
            await super().write_gatt_char(char_specifier, data, response)
            other = WriteSigner(writer=99, role=Role.OPERATOR, key=OPERATOR_KEY)
            self.tag.apply(other.sign(12, Change(urgency=0)))

    factory = functools.partial(Busy, tag=tag, counters=counters)
    writer = BleakTagWriter(writer=2, role=Role.OPERATOR, key=OPERATOR_KEY, counters=counters,
                            client_factory=factory)  # fmt: skip
    outcome = writer.write(ADDRESS, Change(urgency=8))
    assert outcome.after.urgency == 0
    assert not outcome.confirmed


def test_the_adapter_reaches_bleak_the_way_it_takes_it(counters):
    writer_for(new_tag(), counters, adapter="hci1").write(
        ADDRESS, Change(status=TagStatus.PICKED_UP)
    )
    options = FakeClient.made[0].options
    assert options in ({"bluez": {"adapter": "hci1"}}, {"adapter": "hci1"})
    # and bleak's own client takes exactly those options (no deprecation warning: -W error)
    client = bleak.BleakClient(ADDRESS, timeout=1.0, **options)
    assert client.address == ADDRESS


def test_from_key_file_takes_the_role_and_writer_from_the_file(tmp_path, counters):
    path = write_robot_key_file(tmp_path / "robot.key", 7, ROBOT_KEY)
    writer = BleakTagWriter.from_key_file(path, counters=counters)
    assert (writer.role, writer.writer) == (Role.ROBOT, 7)
    assert BleakTagWriter.from_key_file(path, writer=7, counters=counters, role=Role.ROBOT)
    with pytest.raises(ConfigError, match=r"operator does not match the key file .* robot key"):
        BleakTagWriter.from_key_file(path, counters=counters, role=Role.OPERATOR)
    with pytest.raises(ConfigError, match=r"writer 3 does not match the key file .* robot 7's"):
        BleakTagWriter.from_key_file(path, writer=3, counters=counters)
    operator = write_role_key_file(tmp_path / "operator.key", Role.OPERATOR, OPERATOR_KEY)
    assert BleakTagWriter.from_key_file(operator, writer=3, counters=counters).writer == 3
    with pytest.raises(ConfigError, match=r"operator key, shared by its writers: give .*--writer"):
        BleakTagWriter.from_key_file(operator, counters=counters)
    site = write_key_file(tmp_path / "site.key", SITE)
    with pytest.raises(KeyFileError, match="is the site key file, not a writer's key file"):
        BleakTagWriter.from_key_file(site, writer=3, counters=counters)


def test_a_robot_key_file_cannot_make_an_operator_write(tmp_path, counters):
    """The issue's line, through the whole writer: a robot's machine holds only its own key."""
    path = write_robot_key_file(tmp_path / "robot.key", 7, ROBOT_KEY)
    tag = new_tag()
    writer = BleakTagWriter.from_key_file(
        path,
        counters=counters,
        client_factory=functools.partial(FakeClient, tag=tag, counters=counters),
    )
    with pytest.raises(RoleNotAllowed):
        writer.write(ADDRESS, Change(urgency=0, destination=9))
    assert tag.state == WAITING


@pytest.mark.parametrize(
    ("options", "words"),
    [
        ({"writer": 70000}, "writer"),
        ({"role": 3}, "role"),
        ({"key": SITE[:16]}, "key is 32 bytes"),
        ({"timeout": 0.0}, "timeout"),
        ({"timeout": float("nan")}, "timeout"),
        ({"adapter": "usb0"}, "not a BlueZ adapter name"),
        ({"client_factory": 3}, "client_factory"),
    ],
)
def test_bad_settings_are_refused_at_set_up(counters, options, words):
    settings = {"writer": 1, "role": Role.ROBOT, "key": ROBOT_KEY, "counters": counters}
    with pytest.raises((ConfigError, ValueError), match=words):
        BleakTagWriter(**{**settings, **options})


@pytest.mark.parametrize(
    ("address", "change", "marker", "words"),
    [
        ("nope", Change(status=TagStatus.PICKED_UP), None, "not a Bluetooth address"),
        (ADDRESS, Change(), None, "at least one field"),
        (ADDRESS, Change(status=TagStatus.PICKED_UP), 256, "marker"),
    ],
)
def test_bad_writes_are_refused_before_the_radio(counters, address, change, marker, words):
    writer = writer_for(new_tag(), counters)
    with pytest.raises(ConfigError, match=words):
        writer.write(address, change, marker=marker)
    assert FakeClient.made == [] or FakeClient.made[0].calls == []


def test_an_unusable_counter_file_is_refused_before_the_radio(tmp_path):
    path = tmp_path / "w.counters"
    path.write_bytes(b"precious notes\n")
    writer = writer_for(new_tag(), CounterFile(path))
    with pytest.raises(CounterFileError, match="is not a swarmtag counter file"):
        writer.write(ADDRESS, Change(status=TagStatus.PICKED_UP))
    assert FakeClient.made == []
    assert path.read_bytes() == b"precious notes\n"


def test_write_inside_an_event_loop_points_to_write_async(counters):
    writer = writer_for(new_tag(), counters)

    async def inside():
        with pytest.raises(ConfigError, match="await write_async"):
            writer.write(ADDRESS, Change(status=TagStatus.PICKED_UP))
        return await writer.write_async(ADDRESS, Change(status=TagStatus.PICKED_UP))

    assert asyncio.run(inside()).after.status is TagStatus.PICKED_UP
