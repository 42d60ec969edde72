"""The smart tag: advertisement codec, lifecycle, authenticated writes, keys, persistence.

Everything here is pure (no radio, no clock); transports that move these
bytes over real BLE live in adapters built on top.
"""

from __future__ import annotations

from swarmtag.tag.codec import (
    COMPANY_ID,
    FIELD_LENGTH,
    MAX_URGENCY,
    PAYLOAD_LENGTH,
    TagState,
    decode,
    decode_manufacturer_data,
    encode,
    encode_manufacturer_data,
)
from swarmtag.tag.filestore import FileStore
from swarmtag.tag.gatt import ATT_ERRORS, SERVICE_UUID, STATE_CHAR_UUID, WRITE_CHAR_UUID
from swarmtag.tag.keys import (
    WriterKey,
    derive_robot_key,
    derive_role_key,
    generate_site_key,
    read_key_file,
    read_role_key_file,
    read_writer_key_file,
    write_key_file,
    write_robot_key_file,
    write_role_key_file,
)
from swarmtag.tag.lifecycle import ROBOT_TRANSITIONS, Change, Role, apply_change
from swarmtag.tag.model import MemoryStore, TagModel, TagStore
from swarmtag.tag.record import MAX_WRITERS, TagRecord
from swarmtag.tag.scan import ScanFilter
from swarmtag.tag.status import TagStatus
from swarmtag.tag.write import (
    MAC_LENGTH,
    WRITE_LENGTH,
    WRITE_VERSION,
    Write,
    WriteSigner,
    sign,
    verify,
)

__all__ = [
    "ATT_ERRORS",
    "COMPANY_ID",
    "FIELD_LENGTH",
    "MAC_LENGTH",
    "MAX_URGENCY",
    "MAX_WRITERS",
    "PAYLOAD_LENGTH",
    "ROBOT_TRANSITIONS",
    "SERVICE_UUID",
    "STATE_CHAR_UUID",
    "WRITE_CHAR_UUID",
    "WRITE_LENGTH",
    "WRITE_VERSION",
    "Change",
    "FileStore",
    "MemoryStore",
    "Role",
    "ScanFilter",
    "TagModel",
    "TagRecord",
    "TagState",
    "TagStatus",
    "TagStore",
    "Write",
    "WriteSigner",
    "WriterKey",
    "apply_change",
    "decode",
    "decode_manufacturer_data",
    "derive_robot_key",
    "derive_role_key",
    "encode",
    "encode_manufacturer_data",
    "generate_site_key",
    "read_key_file",
    "read_role_key_file",
    "read_writer_key_file",
    "sign",
    "verify",
    "write_key_file",
    "write_robot_key_file",
    "write_role_key_file",
]
