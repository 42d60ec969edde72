"""GATT identifiers and ATT error codes: valid, distinct, and as documented."""

from __future__ import annotations

import uuid
from pathlib import Path

from swarmtag.errors import MalformedWrite
from swarmtag.tag import ATT_ERRORS, SERVICE_UUID, STATE_CHAR_UUID, WRITE_CHAR_UUID

DOC = Path(__file__).parents[2] / "docs" / "tag-protocol.md"


def test_uuids_are_distinct_128_bit_uuids_in_canonical_form():
    uuids = [SERVICE_UUID, WRITE_CHAR_UUID, STATE_CHAR_UUID]
    assert [str(uuid.UUID(u)) for u in uuids] == uuids
    assert len(set(uuids)) == 3


def test_att_error_codes_are_distinct_and_application_errors():
    codes = list(ATT_ERRORS.values())
    assert len(set(codes)) == len(codes)
    for error, code in ATT_ERRORS.items():
        if error is MalformedWrite:
            assert code == 0x0D  # ATT "Invalid Attribute Value Length"
        else:
            assert 0x80 <= code <= 0x9F  # ATT application error range


def test_protocol_doc_names_the_uuids_and_codes_in_the_code():
    text = DOC.read_text(encoding="utf-8")
    for value in (SERVICE_UUID, WRITE_CHAR_UUID, STATE_CHAR_UUID):
        assert value in text
    for error, code in ATT_ERRORS.items():
        row = next(
            line for line in text.splitlines() if f"`{error.__name__}`" in line and "|" in line
        )
        assert f"0x{code:02X}" in row or f"0x{code:02x}" in row, row
