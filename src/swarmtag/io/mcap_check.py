"""Verifying an MCAP file's checksums before it is read (the ``bags`` extra: Foxglove's ``mcap``).

An MCAP file may carry three CRC-32s (``zlib.crc32``; 0 means "not written"): one per chunk
over its uncompressed records, one over the whole data section (in the DataEnd record) and
one over the summary section and footer. ``verify_mcap`` reads the file once, front to back,
with ``mcap``'s ``StreamReader`` (which checks the data-section CRC), decompresses every chunk
and checks its CRC and size, and checks the summary CRC, which ``mcap`` does not. A mismatch is
one ``BagError`` line naming the byte offset of the damaged record, so a file damaged on disk
or in transfer is refused instead of read short.
"""

from __future__ import annotations

import os
import zlib
from pathlib import Path
from typing import BinaryIO, Final

from mcap.records import Chunk, Footer
from mcap.stream_reader import CRCValidationError, StreamReader, get_chunk_data_stream

from swarmtag._interrupt import checkpoint
from swarmtag.errors import BagError, SwarmtagError

__all__ = ["one_line", "verify_mcap"]

_MAGIC_BYTES: Final = 8
_CRC_BYTES: Final = 4 + _MAGIC_BYTES
"""What the summary CRC leaves out at the end of the file: the CRC itself and the magic."""
_DETAIL_LIMIT: Final = 2000


def one_line(error: BaseException) -> str:
    """The whole text of a library's error on one line (its lines joined), or its kind."""
    text = " ".join(str(error).split())
    if len(text) > _DETAIL_LIMIT:
        text = text[:_DETAIL_LIMIT] + " ..."
    return text or type(error).__name__


def _check_chunk(chunk: Chunk, at: int, name: str) -> None:
    """Decompress one chunk and check its size and CRC; ``at`` is its byte offset."""
    try:
        _, length = get_chunk_data_stream(chunk, validate_crc=True)
    except CRCValidationError as error:
        msg = (
            f"{name}: damaged: the chunk at byte {at} fails its CRC "
            f"(stored {error.expected:#010x}, computed {error.actual:#010x})"
        )
        raise BagError(msg) from None
    except MemoryError:
        msg = f"{name}: damaged: the chunk at byte {at} is too large to decompress"
        raise BagError(msg) from None
    except Exception as error:  # noqa: BLE001 - zstandard and lz4 raise their own kinds
        msg = f"{name}: damaged: the chunk at byte {at} cannot be decompressed ({one_line(error)})"
        raise BagError(msg) from None
    if length != chunk.uncompressed_size:
        msg = (
            f"{name}: damaged: the chunk at byte {at} decompresses to {length} bytes, "
            f"not the {chunk.uncompressed_size} it states"
        )
        raise BagError(msg)


def _check_summary(handle: BinaryIO, footer: Footer, footer_at: int, size: int, name: str) -> None:
    """Check the footer's summary CRC: every byte from the summary start up to the CRC field."""
    if footer.summary_crc == 0:
        return
    start = footer.summary_start or footer_at
    if not _MAGIC_BYTES <= start <= footer_at:
        msg = f"{name}: damaged: the footer at byte {footer_at} points outside the file"
        raise BagError(msg)
    handle.seek(start)
    computed, remaining = 0, size - _CRC_BYTES - start
    while remaining > 0:
        block = handle.read(min(remaining, 1 << 20))
        if not block:
            break
        computed = zlib.crc32(block, computed)
        remaining -= len(block)
    if computed != footer.summary_crc:
        msg = (
            f"{name}: damaged: the summary section at byte {start} fails its CRC "
            f"(stored {footer.summary_crc:#010x}, computed {computed:#010x})"
        )
        raise BagError(msg)


def verify_mcap(path: str | os.PathLike[str], name: str) -> None:
    """Refuse ``path`` in one line (naming ``name`` and a byte offset) if a CRC it carries fails.

    Chunks are also refused when they cannot be decompressed or decompress to another size
    than they state, whether or not they carry a CRC.
    """
    size = Path(path).stat().st_size
    with Path(path).open("rb") as handle:
        records = iter(StreamReader(handle, validate_crcs=True, emit_chunks=True).records)
        at = 0  # where the record being read starts (the first read takes the magic too)
        footer: tuple[Footer, int] | None = None
        while True:
            checkpoint()
            try:
                record = next(records)
            except StopIteration:
                break
            except CRCValidationError as error:  # raised at the DataEnd record only
                msg = (
                    f"{name}: damaged: the data section before byte {at} fails its CRC "
                    f"(stored {error.expected:#010x}, computed {error.actual:#010x})"
                )
                raise BagError(msg) from None
            except SwarmtagError:
                raise
            except Exception as error:  # noqa: BLE001 - mcap raises many kinds on damaged files
                msg = (
                    f"{name}: not a readable ROS 2 bag (no MCAP record at byte {at}: "
                    f"{one_line(error)})"
                )
                raise BagError(msg) from None
            if isinstance(record, Chunk):
                _check_chunk(record, at, name)
            elif isinstance(record, Footer):
                footer = (record, at)
            at = handle.tell()
        if footer is not None:
            _check_summary(handle, *footer, size, name)
