"""The software tag's core: writes in, outcomes, advertisement, notify value and E-ink out."""

from __future__ import annotations

import pytest

from swarmtag.errors import FieldRangeError, StateRecordError, SwarmtagError, WriteRejected
from swarmtag.tag import (
    Change,
    FileStore,
    MemoryStore,
    Role,
    TagState,
    TagStatus,
    Write,
    WriteSigner,
    derive_robot_key,
    derive_role_key,
    sign,
)
from swarmtag.tag.emulator import ACCEPTED, SoftwareTag, WriteOutcome, describe_outcome

SITE_KEY = bytes.fromhex("00112233445566778899aabbccddeeff00112233445566778899aabbccddeeff")
ROBOT_KEY = derive_robot_key(SITE_KEY, 7)  # robot 7's own key
OPERATOR_KEY = derive_role_key(SITE_KEY, Role.OPERATOR)
MARKER = 12
START = TagState(urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3, marker=MARKER)


def robot(writer: int = 7) -> WriteSigner:
    return WriteSigner(writer=writer, role=Role.ROBOT, key=derive_robot_key(SITE_KEY, writer))


def operator(writer: int = 1) -> WriteSigner:
    return WriteSigner(writer=writer, role=Role.OPERATOR, key=OPERATOR_KEY)


@pytest.fixture
def store() -> MemoryStore:
    return MemoryStore()


@pytest.fixture
def tag(store: MemoryStore) -> SoftwareTag:
    return SoftwareTag.provision(START, site_key=SITE_KEY, store=store)


def test_what_the_tag_shows_before_any_write(tag):
    assert tag.manufacturer_data() == {0xFFFF: b"\x07\x01\x03\x0c"}
    assert tag.payload() == bytes.fromhex("ffff0701030c")
    assert tag.state_value() == b"\x07\x01\x03\x0c"
    assert (tag.accepted, tag.refused, tag.counts) == (0, 0, {})


def test_an_accepted_write_shows_in_the_advert_the_notify_value_and_the_eink(tag, store):
    pytest.importorskip("PIL")
    from swarmtag.tag.eink import render

    before = tag.eink().tobytes()
    message = operator().sign(MARKER, Change(urgency=9, destination=4))
    outcome = tag.write(message)
    new = TagState(urgency=9, status=TagStatus.AWAITING_PICKUP, destination=4, marker=MARKER)
    assert outcome == WriteOutcome(new, Write(1, Role.OPERATOR, 0, MARKER, Change(9, None, 4)))
    assert outcome.accepted
    assert tag.state == new
    assert tag.manufacturer_data() == {0xFFFF: bytes.fromhex("0901040c")}
    assert tag.payload() == bytes.fromhex("ffff0901040c")
    assert tag.state_value() == bytes.fromhex("0901040c")
    picture = tag.eink()
    assert (picture.size, picture.mode) == ((250, 122), "1")
    assert picture.tobytes() == render(new).tobytes() != before
    assert SoftwareTag.boot(site_key=SITE_KEY, store=store).state == new  # persisted
    assert tag.counts == {ACCEPTED: 1}


def _refused(tag: SoftwareTag, store: MemoryStore, message: bytes) -> WriteOutcome:
    """Write ``message``; check that the tag and its store are exactly as before."""
    state, record, value, advert = tag.state, store.load(), tag.state_value(), tag.payload()
    outcome = tag.write(message)
    assert not outcome.accepted
    assert outcome.state == state == tag.state
    assert (store.load(), tag.state_value(), tag.payload()) == (record, value, advert)
    return outcome


def test_a_forged_write_is_refused_with_0x80(tag, store):
    # a robot's key putting operator role bits on its write: the MAC fails under the operator key
    impostor = WriteSigner(writer=7, role=Role.OPERATOR, key=ROBOT_KEY)
    outcome = _refused(tag, store, impostor.sign(MARKER, Change(urgency=0)))
    assert (outcome.att_error, outcome.refusal, outcome.write) == (0x80, "ForgedWrite", None)
    flipped = bytearray(robot().sign(MARKER, Change(status=TagStatus.PICKED_UP)))
    flipped[-1] ^= 1
    assert _refused(tag, store, bytes(flipped)).att_error == 0x80


def test_a_replayed_write_is_refused_with_0x81(tag, store):
    lift = robot().sign(MARKER, Change(status=TagStatus.PICKED_UP))
    assert tag.write(lift).accepted
    outcome = _refused(tag, store, lift)
    assert (outcome.att_error, outcome.refusal) == (0x81, "ReplayedWrite")
    assert outcome.write == Write(7, Role.ROBOT, 0, MARKER, Change(status=TagStatus.PICKED_UP))
    assert "not above the highest seen" in outcome.reason


def test_wrong_role_writes_are_refused_with_their_codes(tag, store):
    urgency = _refused(tag, store, robot().sign(MARKER, Change(urgency=9)))
    assert (urgency.att_error, urgency.refusal) == (0x83, "RoleNotAllowed")
    backwards = _refused(tag, store, robot().sign(MARKER, Change(status=TagStatus.IDLE)))
    assert (backwards.att_error, backwards.refusal) == (0x84, "IllegalTransition")


def test_wrong_target_and_malformed_writes(tag, store):
    elsewhere = _refused(tag, store, operator().sign(MARKER + 1, Change(urgency=1)))
    assert (elsewhere.att_error, elsewhere.refusal) == (0x82, "WrongTarget")
    short = _refused(tag, store, b"\x01\x22\x07")
    assert (short.att_error, short.refusal, short.write) == (0x0D, "MalformedWrite", None)
    assert _refused(tag, store, "not bytes").att_error == 0x0D  # type: ignore[arg-type]


def test_refusals_are_counted_by_reason(tag):
    lift = robot().sign(MARKER, Change(status=TagStatus.PICKED_UP))
    for message in (lift, lift, lift, b"", robot(8).sign(MARKER, Change(urgency=1))):
        tag.write(message)
    assert tag.counts == {
        ACCEPTED: 1,
        "ReplayedWrite": 2,
        "MalformedWrite": 1,
        "RoleNotAllowed": 1,
    }
    assert (tag.accepted, tag.refused) == (1, 4)
    counts = tag.counts
    counts[ACCEPTED] = 99  # a copy
    assert tag.accepted == 1


def test_the_state_survives_a_reboot_from_a_file_store(tmp_path):
    path = tmp_path / "tag.bin"
    tag = SoftwareTag.open(marker=MARKER, site_key=SITE_KEY, store=FileStore(path), urgency=2)
    assert tag.provisioned
    lift_signer = robot()
    ready = operator().sign(MARKER, Change(status=TagStatus.AWAITING_PICKUP))
    lift = lift_signer.sign(MARKER, Change(status=TagStatus.PICKED_UP))
    assert tag.write(ready).accepted
    assert tag.write(lift).accepted
    rebooted = SoftwareTag.open(marker=MARKER, site_key=SITE_KEY, store=FileStore(path))
    assert not rebooted.provisioned
    assert rebooted.state == TagState(2, TagStatus.PICKED_UP, 0, MARKER)
    assert rebooted.state_value() == bytes.fromhex("0202000c")
    store = FileStore(path)
    assert rebooted.write(lift).att_error == 0x81  # its counter survived the power cycle
    assert FileStore(path).load() == store.load()
    release = lift_signer.sign(MARKER, Change(status=TagStatus.IDLE))
    assert rebooted.write(release).state.status is TagStatus.IDLE


def test_open_provisions_an_empty_store_with_defaults(store):
    tag = SoftwareTag.open(marker=40, site_key=SITE_KEY, store=store)
    assert tag.state == TagState(0, TagStatus.IDLE, 0, 40)
    assert store.load() is not None
    named = SoftwareTag.open(
        marker=5, site_key=SITE_KEY, store=MemoryStore(), status="picked_up", destination=9
    )
    assert named.state == TagState(0, TagStatus.PICKED_UP, 9, 5)


def test_open_refuses_another_marker_or_new_fields_for_a_stored_tag(tag, store):
    with pytest.raises(FieldRangeError, match=r"marker: 13 is not the stored tag's marker \(12\)"):
        SoftwareTag.open(marker=13, site_key=SITE_KEY, store=store)
    with pytest.raises(FieldRangeError, match="urgency, status: only set up a new tag"):
        SoftwareTag.open(marker=MARKER, site_key=SITE_KEY, store=store, urgency=1, status=0)
    assert SoftwareTag.open(marker=MARKER, site_key=SITE_KEY, store=store).state == START


@pytest.mark.parametrize(
    ("options", "match"),
    [
        ({"marker": 256}, "marker"),
        ({"marker": 1, "urgency": 10}, "urgency"),
        ({"marker": 1, "status": "lost"}, "status"),
        ({"marker": 1, "destination": -1}, "destination"),
    ],
)
def test_open_refuses_bad_fields_before_saving(options, match):
    store = MemoryStore()
    with pytest.raises(FieldRangeError, match=match):
        SoftwareTag.open(site_key=SITE_KEY, store=store, **options)
    assert store.load() is None


def test_a_store_that_cannot_save_stops_the_write(tag, store, monkeypatch):
    def broken(_record: bytes) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(store, "save", broken)
    with pytest.raises(OSError, match="No space"):
        tag.write(operator().sign(MARKER, Change(urgency=0)))
    assert tag.state == START
    assert tag.counts == {}


def test_a_corrupt_store_is_refused_at_boot():
    store = MemoryStore()
    store.save(b"\x01junk")
    with pytest.raises(StateRecordError):
        SoftwareTag.open(marker=MARKER, site_key=SITE_KEY, store=store)


def test_a_refusal_is_an_outcome_never_an_exception(tag):
    forged = sign(Write(9, Role.OPERATOR, 1, MARKER, Change(urgency=0)), ROBOT_KEY)
    try:
        outcome = tag.write(forged)
    except WriteRejected as error:  # pragma: no cover - the failure this test is for
        pytest.fail(f"raised {error!r}")
    assert outcome.att_error == 0x80


def test_describe_outcome_lines(tag):
    lift = robot().sign(MARKER, Change(status=TagStatus.PICKED_UP))
    assert describe_outcome(tag.write(lift)) == (
        "accepted from writer 7 (robot, counter 0): now urgency 7, PICKED_UP, destination 3"
    )
    assert describe_outcome(tag.write(lift)) == (
        "refused from writer 7 (robot, counter 0): ReplayedWrite (ATT 0x81): counter 0 from "
        "writer 7 is not above the highest seen (0): replay refused"
    )
    assert describe_outcome(tag.write(bytes(20))).startswith(
        "refused from an unverified writer: ForgedWrite (ATT 0x80): "
    )


HOSTILE = (None, True, "12", 1.5, -1, 2**40, b"", [], object())


@pytest.mark.parametrize(
    ("argument", "value"),
    [
        (argument, value)
        for argument in ("marker", "site_key", "store", "urgency", "status", "destination")
        for value in HOSTILE
        if not (value is None and argument in ("urgency", "status", "destination"))  # defaults
    ],
)
def test_open_refuses_any_bad_argument_with_a_swarmtag_error(argument, value):
    store = MemoryStore()
    options = {"marker": MARKER, "site_key": SITE_KEY, "store": store, argument: value}
    with pytest.raises(SwarmtagError):
        SoftwareTag.open(**options)
    assert store.load() is None


@pytest.mark.parametrize("value", HOSTILE)
def test_every_written_value_is_an_outcome(tag, value):
    assert tag.write(value).att_error == 0x0D


@pytest.mark.parametrize("value", HOSTILE)
def test_bad_constructor_arguments_are_refused(tag, value):
    with pytest.raises(SwarmtagError):
        SoftwareTag(value, site_key=SITE_KEY)
    with pytest.raises(SwarmtagError):
        describe_outcome(value)
