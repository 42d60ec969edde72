"""The console's access rules: the token, how a request proves it holds it, the write rate.

The token is 32 random bytes (URL-safe base64), written to the token file
with mode 0600 (created if absent; an existing file is reused if it holds a
token, so bookmarks survive a restart). A request holds it if it carries
``Authorization: Bearer TOKEN`` or the ``swarmtag_console`` cookie that the
page's token URL sets (``HttpOnly; SameSite=Strict``). Writes made with the
cookie must also carry the ``X-Swarmtag-Console`` header, which no other
site's form or link can add: a cross-site request forgery gets 403.
"""

from __future__ import annotations

import hmac
import os
import re
import secrets
import threading
import time
from pathlib import Path
from typing import Final

from swarmtag._atomic import WriteFailure, atomic_path
from swarmtag.errors import ConfigError

__all__ = [
    "COOKIE",
    "WRITE_HEADER",
    "RateLimiter",
    "load_or_create_token",
    "token_matches",
]

COOKIE: Final = "swarmtag_console"
"""The cookie the token URL sets."""
WRITE_HEADER: Final = "x-swarmtag-console"
"""The header a cookie-authenticated write must carry (the page's script adds it)."""
_TOKEN: Final = re.compile(r"[A-Za-z0-9_-]{32,128}")
_MAX_TOKEN_FILE: Final = 1024


def load_or_create_token(path: Path) -> str:
    """The token in ``path``, or a new random one written there with mode 0600."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_NOFOLLOW)
    except FileNotFoundError:
        return _new_token(path)
    except OSError as error:
        raise ConfigError(f"--token-file {path}: cannot open it ({error.strerror})") from None
    with os.fdopen(fd, "r+", encoding="ascii", errors="replace") as handle:
        if os.fstat(handle.fileno()).st_mode & 0o077:
            os.fchmod(handle.fileno(), 0o600)
        text = handle.read(_MAX_TOKEN_FILE).strip()
    if _TOKEN.fullmatch(text):
        return text
    if text:
        raise ConfigError(
            f"--token-file {path}: holds something that is not a console token; "
            "remove it or name another file"
        )
    return _new_token(path)


def _new_token(path: Path) -> str:
    """A new random token, written to ``path`` (mode 0600) whole or not at all.

    Written aside and renamed into place, so that a full disk leaves no empty
    token file behind (one line naming the file, as every output).
    """
    token = secrets.token_urlsafe(32)
    try:
        with atomic_path(path) as temporary:
            temporary.chmod(0o600)
            temporary.write_text(token + "\n", encoding="ascii")
    except WriteFailure:
        raise
    except OSError as error:
        raise ConfigError(f"--token-file {path}: cannot write it ({error.strerror})") from None
    return token


def token_matches(given: str | None, token: str) -> bool:
    """Whether ``given`` is the token (in constant time)."""
    return given is not None and hmac.compare_digest(given.encode(), token.encode())


class RateLimiter:
    """A token bucket per client: ``burst`` writes at once, then ``per_second`` on average."""

    def __init__(self, *, per_second: float = 5.0, burst: int = 10) -> None:
        self.per_second = per_second
        self.burst = burst
        self._buckets: dict[str, tuple[float, float]] = {}
        self._lock = threading.Lock()

    def allow(self, client: str, now: float | None = None) -> bool:
        """Take one write from ``client``'s bucket; False if it is empty."""
        now = time.monotonic() if now is None else now
        with self._lock:
            level, then = self._buckets.get(client, (float(self.burst), now))
            level = min(float(self.burst), level + (now - then) * self.per_second)
            if level < 1.0:
                self._buckets[client] = (level, now)
                return False
            self._buckets[client] = (level - 1.0, now)
            if len(self._buckets) > 10_000:  # forget idle clients
                self._buckets = {client: self._buckets[client]}
            return True
