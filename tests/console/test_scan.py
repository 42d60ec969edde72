"""The ``--scan`` source with bleak's own objects: BLEDevice and AdvertisementData fed to the
real bleak scanner's callback, writes through the real GATT writer to software tags over the
loopback client. No radio is touched unless ``SWARMTAG_REAL_BLE=1`` (the last test).
"""

import inspect
import json
import os
import time

import pytest

pytest.importorskip("bleak", reason="the ble extra")

from bleak.backends.device import BLEDevice
from bleak.backends.scanner import AdvertisementData
from bleak.exc import BleakError

from swarmtag.console.scan_source import NO_KEY, ScanSource, bench_radio
from swarmtag.console.server import scan_core
from swarmtag.errors import RadioError
from swarmtag.tag import (
    MemoryStore,
    Role,
    TagState,
    TagStatus,
    derive_role_key,
    encode_manufacturer_data,
    generate_site_key,
)
from swarmtag.tag.backends.bleak import BleakTagScanner
from swarmtag.tag.backends.bleak_writer import BleakTagWriter
from swarmtag.tag.backends.loopback import LoopbackClient
from swarmtag.tag.counter import CounterFile
from swarmtag.tag.emulator import SoftwareTag

SITE = generate_site_key()
TAGS = {
    "AA:BB:CC:DD:EE:01": TagState(urgency=4, status=TagStatus.AWAITING_PICKUP, destination=2,
                                  marker=12),
    "AA:BB:CC:DD:EE:02": TagState(urgency=1, status=TagStatus.IDLE, destination=0, marker=7),
}  # fmt: skip


class Clock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def device(address):
    if "rssi" in inspect.signature(BLEDevice).parameters:  # bleak < 0.23
        return BLEDevice(address, "tag", None, -60)
    return BLEDevice(address, "tag", None)


def advert(state, rssi=-55):
    return AdvertisementData(
        local_name=None,
        manufacturer_data=encode_manufacturer_data(state),
        service_data={},
        service_uuids=[],
        tx_power=None,
        rssi=rssi,
        platform_data=(),
    )


class Floor:
    """Two software tags, a bleak scanner hearing them, a writer reaching them by loopback."""

    def __init__(self, tmp_path, *, key=None):
        self.clock = Clock()
        self.tags = {
            address: SoftwareTag.open(
                marker=s.marker, site_key=SITE, store=MemoryStore(), urgency=s.urgency,
                status=s.status, destination=s.destination,
            )
            for address, s in TAGS.items()
        }  # fmt: skip
        self.scanner = BleakTagScanner(clock=self.clock)
        self.source = ScanSource(self.scanner)
        self.writer = BleakTagWriter(
            writer=0xFFFD,
            role=Role.OPERATOR,
            key=key or derive_role_key(SITE, Role.OPERATOR),
            counters=CounterFile(tmp_path / "operator.key.counters"),
            client_factory=self.client,
        )
        self.core = scan_core(self.source, self.writer, audit_log=tmp_path / "audit.jsonl")
        self.hear_all()

    def client(self, address, **options):
        return LoopbackClient(address, tag=self.tags[address], **options)

    def hear_all(self):
        for address, tag in self.tags.items():
            self.scanner.detection_callback(device(address), advert(tag.state))

    def rows(self):
        return {t["marker"]: t for t in self.core.tags().body}


@pytest.fixture
def floor(tmp_path):
    return Floor(tmp_path)


def test_the_table_lists_the_tags_heard(floor):
    floor.clock.now += 1.5
    rows = floor.rows()
    assert sorted(rows) == [7, 12]
    assert (rows[12]["urgency"], rows[12]["status"], rows[12]["destination"]) == (
        4,
        "awaiting_pickup",
        2,
    )
    assert rows[12]["last_heard"] == 1.5
    assert rows[12]["rssi"] == -55
    assert rows[12]["address"] == "AA:BB:CC:DD:EE:01"
    assert rows[12]["waited"] is None
    assert rows[12]["overdue"] is False


def test_foreign_devices_are_counted_not_listed(floor):
    foreign = AdvertisementData(
        local_name="phone", manufacturer_data={0x004C: b"\x02\x15"}, service_data={},
        service_uuids=[], tx_power=None, rssi=-70, platform_data=(),
    )  # fmt: skip
    floor.scanner.detection_callback(device("11:22:33:44:55:66"), foreign)
    assert sorted(floor.rows()) == [7, 12]
    k = floor.source.kpis()
    assert (k["kind"], k["tags"], k["awaiting_pickup"], k["idle"], k["foreign"]) == (
        "scan", 2, 1, 1, 1,
    )  # fmt: skip
    assert (k["mean_urgency"], k["max_urgency"], k["adverts"]) == (2.5, 4, 2)


def test_there_is_no_floor(floor):
    picture = floor.core.floor().body
    assert picture["kind"] == "none"
    assert "no floor positions" in picture["why"]
    assert picture["source"] == "scan"


def test_a_write_is_signed_sent_over_gatt_and_shown(floor, tmp_path):
    reply = floor.core.write(
        who="me", client="me", marker="12", field="urgency", body=b'{"urgency": 9}'
    )
    assert reply.status == 200, reply.body
    assert reply.body["urgency"] == 9
    assert floor.tags["AA:BB:CC:DD:EE:01"].state.urgency == 9  # the tag itself changed
    assert floor.rows()[12]["urgency"] == 9  # shown before the tag advertises it
    assert CounterFile(tmp_path / "operator.key.counters").last(0xFFFD) == 0
    floor.clock.now += 0.5
    floor.hear_all()  # the tag advertises the new state
    assert floor.rows()[12]["urgency"] == 9
    assert floor.source.kpis()["writes"] == 1
    (line,) = [json.loads(x) for x in (tmp_path / "audit.jsonl").read_text().splitlines()]
    assert line["change"] == {"field": "urgency", "value": 9, "counter": 0}


def test_the_tag_refuses_a_write_under_another_key(tmp_path):
    floor = Floor(tmp_path, key=derive_role_key(generate_site_key(), Role.OPERATOR))
    reply = floor.core.write(
        who="me", client="me", marker="12", field="urgency", body=b'{"urgency": 9}'
    )
    assert reply.status == 409
    assert "ForgedWrite" in reply.body["error"]
    assert floor.tags["AA:BB:CC:DD:EE:01"].state.urgency == 4
    assert floor.rows()[12]["urgency"] == 4


def test_a_tag_out_of_range_is_404(floor):
    floor.clock.now += 60  # past the scanner's max age
    reply = floor.core.write(
        who="me", client="me", marker="12", field="urgency", body=b'{"urgency": 9}'
    )
    assert reply.status == 404
    assert "in range" in reply.body["error"]


def test_without_an_operator_key_writes_are_refused(tmp_path, floor):
    core = scan_core(floor.source, None, audit_log=tmp_path / "b.jsonl")
    reply = core.write(who="me", client="me", marker="12", field="urgency", body=b'{"urgency": 9}')
    assert reply.status == 409
    assert NO_KEY in reply.body["error"]
    assert floor.tags["AA:BB:CC:DD:EE:01"].state.urgency == 4


class NoAdapter:
    """bleak's scanner on a machine without an adapter."""

    def __init__(self, **_options):
        pass

    async def start(self):
        raise BleakError("No Bluetooth adapters found.")

    async def stop(self):
        pass


def test_no_adapter_is_one_line_at_start():
    source = ScanSource(BleakTagScanner(scanner_factory=NoAdapter), ready_s=5.0)
    started = time.monotonic()
    with pytest.raises(RadioError, match="no Bluetooth adapter found") as raised:
        source.start()
    assert time.monotonic() - started < 5.0
    assert str(raised.value).startswith("--scan: ")
    assert "\n" not in str(raised.value)


def test_the_bench_radio_hears_three_tags_and_takes_writes(tmp_path):
    from swarmtag.sim.world.wms import SIM_SITE_KEY

    scanner, factory, heard = bench_radio(SIM_SITE_KEY)
    source = ScanSource(scanner, on_written=heard)
    writer = BleakTagWriter(
        writer=0xFFFD,
        role=Role.OPERATOR,
        key=derive_role_key(SIM_SITE_KEY, Role.OPERATOR),
        counters=CounterFile(tmp_path / "c.counters"),
        client_factory=factory,
    )
    core = scan_core(source, writer, audit_log=tmp_path / "audit.jsonl")
    source.start()
    try:
        deadline = time.monotonic() + 3
        while len(source.markers) < 3 and time.monotonic() < deadline:
            source.advance(0.05)
            time.sleep(0.05)
        assert sorted(source.markers) == [7, 12, 21]
        reply = core.write(
            who="me", client="me", marker="7", field="urgency", body=b'{"urgency": 8}'
        )
        assert reply.status == 200, reply.body
        time.sleep(0.6)
        source.advance(0.6)  # the simulated radio now hears the new state
        assert {t["marker"]: t["urgency"] for t in core.tags().body}[7] == 8
    finally:
        source.stop()


@pytest.mark.skipif(
    os.environ.get("SWARMTAG_REAL_BLE") != "1",
    reason="opt-in: SWARMTAG_REAL_BLE=1 scans with this machine's real Bluetooth adapter",
)
def test_a_real_adapter_scans(tmp_path):  # pragma: no cover - needs a radio
    """With a real adapter (opt-in): the console's scan source starts, lists what it hears."""
    source = ScanSource(BleakTagScanner())
    source.start()
    try:
        time.sleep(3.0)
        core = scan_core(source, None, audit_log=tmp_path / "audit.jsonl")
        tags = core.tags().body
        assert isinstance(tags, list)
        assert all({"marker", "urgency", "rssi", "address"} <= set(t) for t in tags)
        assert source.scanner.failure is None
    finally:
        source.stop()
