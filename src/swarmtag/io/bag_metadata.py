"""A rosbag2 folder's ``metadata.yaml``: its storage, files and per-topic message counts.

``swarmtag.io.bags`` reads a folder's MCAP files itself (``swarmtag.io.mcap_in``) and holds
what it read against the counts the recorder wrote here (``topics_with_message_count``), so a
topic whose messages cannot be read is refused instead of imported short. The file is read
with ``ruamel.yaml``'s safe loader (what ``rosbags`` reads it with); a file that is too large,
not YAML or not rosbag2 metadata is one ``BagError`` line.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path, PurePath
from typing import Any, Final

from swarmtag.errors import BagError, SwarmtagError
from swarmtag.io.mcap_check import one_line

__all__ = ["MAX_METADATA_BYTES", "BagMetadata", "read_metadata"]

MAX_METADATA_BYTES: Final = 16 * 2**20
"""The largest ``metadata.yaml`` read: thousands of topics and files take well under 1 MiB."""


@dataclass(frozen=True, slots=True)
class BagMetadata:
    """What ``metadata.yaml`` states: storage plugin, compression mode, files, counts by topic."""

    storage: str
    compression: str
    files: tuple[Path, ...]
    counts: dict[str, int]


def _load(path: Path, name: str) -> Any:  # noqa: ANN401 - YAML gives any shape
    from ruamel.yaml import YAML  # noqa: PLC0415 - the bags extra

    try:
        size = path.stat().st_size
        if size > MAX_METADATA_BYTES:
            msg = f"{name}: {size} bytes, more than {MAX_METADATA_BYTES} (no rosbag2 metadata is)"
            raise BagError(msg)
        text = path.read_text(encoding="utf-8")
        return YAML(typ="safe", pure=True).load(text)
    except SwarmtagError:
        raise
    except OSError as error:
        msg = f"{name}: cannot be read ({error.strerror or error})"
        raise BagError(msg) from None
    except RecursionError:
        msg = f"{name}: nested too deeply to be rosbag2 metadata"
        raise BagError(msg) from None
    except Exception as error:  # noqa: BLE001 - ruamel raises many kinds on broken YAML
        msg = f"{name}: not readable YAML ({one_line(error)})"
        raise BagError(msg) from None


def read_metadata(folder: Path, name: str) -> BagMetadata:
    """The metadata of the rosbag2 folder ``folder`` (``name``: the folder as the user wrote it)."""
    where = str(PurePath(name, "metadata.yaml"))
    document = _load(folder / "metadata.yaml", where)
    try:
        info = document["rosbag2_bagfile_information"]
        storage = str(info["storage_identifier"])
        compression = str(info.get("compression_mode") or "").lower()
        files = tuple(folder / PurePath(str(p)).name for p in info["relative_file_paths"])
        counts: dict[str, int] = {}
        for entry in info.get("topics_with_message_count") or ():
            topic = str(entry["topic_metadata"]["name"])
            count = entry["message_count"]
            if isinstance(count, bool) or not isinstance(count, int) or count < 0:
                msg = f"{where}: message_count {count!r} of {topic} is not a count"
                raise BagError(msg)
            counts[topic] = counts.get(topic, 0) + count
    except SwarmtagError:
        raise
    except (KeyError, TypeError, AttributeError) as error:
        msg = f"{where}: not rosbag2 metadata (missing or malformed: {one_line(error)})"
        raise BagError(msg) from None
    return BagMetadata(
        storage=storage,
        compression="" if compression == "none" else compression,
        files=files,
        counts=counts,
    )
