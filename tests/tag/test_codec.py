"""The 6-byte advertisement payload of SPEC §2.1: golden vectors, properties, errors."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from swarmtag.errors import (
    FieldRangeError,
    ForeignCompanyError,
    PayloadError,
    PayloadLengthError,
    UnknownStatusError,
    UrgencyRangeError,
)
from swarmtag.tag import (
    TagState,
    TagStatus,
    decode,
    decode_manufacturer_data,
    encode,
    encode_manufacturer_data,
)
from tests.strategies import tag_states

# Wire constants written out as literals: if the codec drifts, these break.
GOLDEN = [
    (b"\xff\xff\x07\x01\x03\x0c", (7, TagStatus.AWAITING_PICKUP, 3, 12)),
    (b"\xff\xff\x00\x00\x00\x00", (0, TagStatus.IDLE, 0, 0)),
    (b"\xff\xff\x09\x02\xff\xff", (9, TagStatus.PICKED_UP, 255, 255)),
    (b"\xff\xff\x05\x01\x00\x2a", (5, TagStatus.AWAITING_PICKUP, 0, 42)),
]


def _state(fields: tuple[int, TagStatus, int, int]) -> TagState:
    urgency, status, destination, marker = fields
    return TagState(urgency=urgency, status=status, destination=destination, marker=marker)


def test_status_numbers_are_the_wire_values():
    assert (TagStatus.IDLE, TagStatus.AWAITING_PICKUP, TagStatus.PICKED_UP) == (0x00, 0x01, 0x02)
    assert len(TagStatus) == 3


@pytest.mark.parametrize(("payload", "fields"), GOLDEN)
def test_golden_vectors_encode(payload, fields):
    assert encode(_state(fields)) == payload


@pytest.mark.parametrize(("payload", "fields"), GOLDEN)
def test_golden_vectors_decode(payload, fields):
    assert decode(payload) == _state(fields)
    assert decode(bytearray(payload)) == _state(fields)
    assert decode(memoryview(payload)) == _state(fields)


@pytest.mark.parametrize(("payload", "fields"), GOLDEN)
def test_golden_vectors_mapping_form(payload, fields):
    mapping = {0xFFFF: payload[2:]}
    assert encode_manufacturer_data(_state(fields)) == mapping
    assert decode_manufacturer_data(mapping) == _state(fields)


def test_spec_example_hex():
    state = TagState(urgency=7, status=TagStatus.AWAITING_PICKUP, destination=3, marker=12)
    assert encode(state).hex() == "ffff0701030c"


def test_mapping_form_ignores_other_companies():
    mapping = {0x004C: b"\x02\x15\x00", 0x0006: b"", 0xFFFF: b"\x09\x02\x01\x07"}
    assert decode_manufacturer_data(mapping) == _state((9, TagStatus.PICKED_UP, 1, 7))


@pytest.mark.parametrize(
    ("payload", "error", "words"),
    [
        (b"", PayloadLengthError, "0 bytes"),
        (b"\xff\xff\x07\x01\x03", PayloadLengthError, "5 bytes"),
        (b"\xff\xff\x07\x01\x03\x0c\x00", PayloadLengthError, "7 bytes"),
        (b"\x4c\x00\x07\x01\x03\x0c", ForeignCompanyError, "0x004c"),
        (b"\xfe\xff\x07\x01\x03\x0c", ForeignCompanyError, "0xfffe"),
        (b"\xff\xfe\x07\x01\x03\x0c", ForeignCompanyError, "0xfeff"),
        (b"\xff\xff\x0a\x01\x03\x0c", UrgencyRangeError, "10"),
        (b"\xff\xff\xff\x01\x03\x0c", UrgencyRangeError, "255"),
        (b"\xff\xff\x07\x03\x03\x0c", UnknownStatusError, "0x03"),
        (b"\xff\xff\x07\xff\x03\x0c", UnknownStatusError, "0xff"),
    ],
)
def test_malformed_payloads_raise_typed_errors(payload, error, words):
    with pytest.raises(error, match=words) as caught:
        decode(payload)
    assert isinstance(caught.value, PayloadError)
    assert isinstance(caught.value, ValueError)


@pytest.mark.parametrize(
    ("mapping", "error"),
    [
        ({}, ForeignCompanyError),
        ({0x004C: b"\x07\x01\x03\x0c"}, ForeignCompanyError),
        ({0xFFFF: b"\x07\x01\x03"}, PayloadLengthError),
        ({0xFFFF: b"\xff\xff\x07\x01\x03\x0c"}, PayloadLengthError),  # company id repeated
        ({0xFFFF: b"\x0a\x01\x03\x0c"}, UrgencyRangeError),
        ({0xFFFF: b"\x07\x09\x03\x0c"}, UnknownStatusError),
    ],
)
def test_malformed_mappings_raise_typed_errors(mapping, error):
    with pytest.raises(error):
        decode_manufacturer_data(mapping)


@pytest.mark.parametrize(
    ("field", "value"),
    [("urgency", 10), ("urgency", -1), ("destination", 256), ("marker", -1), ("marker", 1.0)],
)
def test_state_refuses_out_of_range_fields(field, value):
    fields = {"urgency": 1, "status": TagStatus.IDLE, "destination": 0, "marker": 0}
    fields[field] = value
    with pytest.raises(FieldRangeError, match=field):
        TagState(**fields)


def test_state_accepts_status_number_or_name_at_runtime():
    assert TagState(urgency=1, status=2, destination=0, marker=0).status is TagStatus.PICKED_UP  # type: ignore[arg-type]
    with pytest.raises(FieldRangeError, match="status"):
        TagState(urgency=1, status=7, destination=0, marker=0)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("text", "status"),
    [
        ("awaiting_pickup", TagStatus.AWAITING_PICKUP),
        ("AWAITING_PICKUP", TagStatus.AWAITING_PICKUP),
        ("Picked_Up", TagStatus.PICKED_UP),
        (" idle ", TagStatus.IDLE),
        ("0", TagStatus.IDLE),
        ("2", TagStatus.PICKED_UP),
        (1, TagStatus.AWAITING_PICKUP),
    ],
)
def test_status_parse(text, status):
    assert TagStatus.parse(text) is status


@pytest.mark.parametrize("text", ["3", "-1", "awaiting", "", "picked up", True])
def test_status_parse_rejects(text):
    with pytest.raises(FieldRangeError, match="not a tag status"):
        TagStatus.parse(text)


@given(tag_states)
def test_round_trip_raw(state):
    payload = encode(state)
    assert len(payload) == 6
    assert payload[:2] == b"\xff\xff"
    assert decode(payload) == state


@given(tag_states)
def test_round_trip_mapping(state):
    mapping = encode_manufacturer_data(state)
    assert list(mapping) == [0xFFFF]
    assert len(mapping[0xFFFF]) == 4
    assert decode_manufacturer_data(mapping) == state
    assert encode(state)[2:] == mapping[0xFFFF]


@given(st.binary(min_size=6, max_size=6))
def test_decode_then_encode_is_identity_on_accepted_bytes(payload):
    try:
        state = decode(payload)
    except PayloadError:
        return
    assert encode(state) == payload
