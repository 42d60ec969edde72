"""The console's audit log: one JSON line per write attempt, accepted or refused.

Each line holds ``time`` (UTC, ISO 8601), ``who`` (the client's address
and how it authenticated), ``tag`` (the marker as given), ``change`` (the
field and the value asked for), ``outcome`` (``accepted`` or ``refused``),
the HTTP ``status`` and, for a refusal, the ``reason``. Lines are appended
and flushed one at a time, so a crash loses at most the line being written.
"""

from __future__ import annotations

import json
import os
import threading
from datetime import UTC, datetime
from pathlib import Path
from typing import Final

from swarmtag.errors import ConfigError

__all__ = ["DEFAULT_AUDIT_LOG", "AuditLog"]

DEFAULT_AUDIT_LOG: Final = "swarmtag-console-audit.jsonl"
"""The audit log's default name, in the folder of the token file."""


class AuditLog:
    """Appends audit lines to ``path`` (created with mode 0600 if absent)."""

    def __init__(self, path: Path) -> None:
        """Check ``path`` now; create it only with the first line.

        Its folder must exist, and it must be absent or a file this process
        can append to; a console that fails to start leaves no file behind.
        """
        self.path = path
        self._lock = threading.Lock()
        if not path.parent.is_dir():
            raise ConfigError(f"--audit-log {path}: the folder {path.parent} does not exist")
        if path.exists() and not (path.is_file() and os.access(path, os.W_OK)):
            raise ConfigError(f"--audit-log {path}: not a file this process can append to")

    def record(
        self,
        *,
        who: str,
        tag: str,
        change: dict[str, object],
        outcome: str,
        status: int,
        reason: str | None = None,
    ) -> dict[str, object]:
        """Append one line and return it."""
        line: dict[str, object] = {
            "time": datetime.now(UTC).isoformat(timespec="milliseconds"),
            "who": who,
            "tag": tag,
            "change": change,
            "outcome": outcome,
            "status": status,
        }
        if reason is not None:
            line["reason"] = reason
        text = json.dumps(line, sort_keys=False) + "\n"
        with self._lock:
            fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o600)
            with os.fdopen(fd, "a", encoding="utf-8") as out:
                out.write(text)
        return line
