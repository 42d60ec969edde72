"""The loopback GATT client: a tag's GATT answers, refusals as bleak raises them (no radio)."""

from __future__ import annotations

import asyncio

import pytest

pytest.importorskip("bleak")

import bleak
from bleak.exc import BleakCharacteristicNotFoundError, BleakDBusError, BleakError

from swarmtag.errors import WriteRejected
from swarmtag.tag import (
    ATT_ERRORS,
    STATE_CHAR_UUID,
    WRITE_CHAR_UUID,
    Change,
    MemoryStore,
    Role,
    TagState,
    TagStatus,
    WriteSigner,
    derive_robot_key,
)
from swarmtag.tag.backends import loopback
from swarmtag.tag.backends.bleak_writer import att_error_code
from swarmtag.tag.backends.loopback import LoopbackClient, att_exception
from swarmtag.tag.emulator import SoftwareTag

SITE = bytes(range(32))
STATE = TagState(urgency=4, status=TagStatus.AWAITING_PICKUP, destination=1, marker=9)


def client() -> LoopbackClient:
    tag = SoftwareTag.provision(STATE, site_key=SITE, store=MemoryStore())
    return LoopbackClient("AA:BB:CC:DD:EE:FF", tag=tag, timeout=5.0, bluez={"adapter": "hci0"})


def robot() -> WriteSigner:
    return WriteSigner(writer=3, role=Role.ROBOT, key=derive_robot_key(SITE, 3))


def test_state_reads_as_the_four_field_bytes_and_writes_apply():
    async def go(c):
        await c.connect()
        before = await c.read_gatt_char(STATE_CHAR_UUID)
        await c.write_gatt_char(
            WRITE_CHAR_UUID, robot().sign(9, Change(status=TagStatus.PICKED_UP)), True
        )
        after = await c.read_gatt_char(STATE_CHAR_UUID)
        await c.disconnect()
        return before, after

    c = client()
    before, after = asyncio.run(go(c))
    assert before == bytearray([4, 1, 1, 9])
    assert after == bytearray([4, 2, 1, 9])
    assert (c.writes, c.is_connected) == (1, False)


@pytest.mark.parametrize(
    ("change", "target", "kind"),
    [
        (Change(urgency=1), 9, "RoleNotAllowed"),
        (Change(status=TagStatus.PICKED_UP), 8, "WrongTarget"),
    ],
)
def test_a_refusal_is_raised_as_bleak_raises_the_tags_att_error(change, target, kind):
    async def go(c):
        await c.connect()
        await c.write_gatt_char(WRITE_CHAR_UUID, robot().sign(target, change), response=True)

    c = client()
    with pytest.raises(BleakError) as caught:
        asyncio.run(go(c))
    code = next(code for error, code in ATT_ERRORS.items() if error.__name__ == kind)
    assert att_error_code(caught.value) == code
    assert c.tag.state == STATE


def test_old_bleak_gets_the_bluez_dbus_form(monkeypatch):
    monkeypatch.setattr(loopback, "_PROTOCOL_ERROR", None)
    error = att_exception(0x84)
    assert isinstance(error, BleakDBusError)
    assert error.dbus_error == "org.bluez.Error.Failed"
    assert "Operation failed with ATT error: 0x84" in str(error)
    assert att_error_code(error) == 0x84
    if hasattr(bleak.exc, "BleakGATTProtocolError"):
        monkeypatch.undo()
        assert isinstance(att_exception(0x84), bleak.exc.BleakGATTProtocolError)


def test_only_our_characteristics_and_write_with_response_are_served():
    async def go(c, step):
        await c.connect()
        return await step(c)

    cases = [
        (lambda c: c.read_gatt_char("0000180f-0000-1000-8000-00805f9b34fb"), None),
        (lambda c: c.read_gatt_char(WRITE_CHAR_UUID), 0x02),
        (lambda c: c.write_gatt_char(STATE_CHAR_UUID, b"x" * 20, True), 0x03),
        (lambda c: c.write_gatt_char(WRITE_CHAR_UUID, b"x" * 20, False), 0x03),
    ]
    for step, code in cases:
        c = client()
        with pytest.raises(BleakError) as caught:
            asyncio.run(go(c, step))
        if code is None:
            assert isinstance(caught.value, BleakCharacteristicNotFoundError)
        else:
            assert att_error_code(caught.value) == code
        assert c.writes == 0


def test_nothing_works_before_connecting():
    with pytest.raises(BleakError, match="Not connected"):
        asyncio.run(client().read_gatt_char(STATE_CHAR_UUID))


def test_a_malformed_write_is_att_0x0d():
    async def go(c):
        await c.connect()
        await c.write_gatt_char(WRITE_CHAR_UUID, b"\x01" * 7, response=True)

    with pytest.raises(BleakError) as caught:
        asyncio.run(go(client()))
    assert att_error_code(caught.value) == 0x0D
    assert issubclass(next(e for e, c in ATT_ERRORS.items() if c == 0x0D), WriteRejected)
