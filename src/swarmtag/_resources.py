"""Bounding work before it starts: the memory this machine can give, and one refusal rule.

Commands estimate the memory a request needs (runs, resamples, scenario
sizes, study sizes) and call ``check_memory`` before allocating anything;
what cannot fit is refused with the estimate and the limit in one line.
The limit is the memory available now (``MemAvailable``), or
``SWARMTAG_MEMORY_LIMIT`` (bytes, or with a KiB/MiB/GiB suffix) when set.
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Final

from swarmtag.errors import ResourceError, SwarmtagError

__all__ = ["MEMORY_LIMIT_VARIABLE", "check_memory", "format_bytes", "memory_limit"]

MEMORY_LIMIT_VARIABLE: Final = "SWARMTAG_MEMORY_LIMIT"
"""Environment variable that sets the memory limit explicitly (tests, shared machines)."""
_UNITS: Final = {"": 1, "b": 1, "kib": 2**10, "mib": 2**20, "gib": 2**30, "tib": 2**40}
_FALLBACK: Final = 4 * 2**30
"""Limit when the platform says nothing about its memory."""


def format_bytes(count: float) -> str:
    """``count`` bytes in the largest binary unit that keeps it above 1.

    >>> format_bytes(37 * 2**30), format_bytes(512)
    ('37.0 GiB', '512 B')
    """
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if count >= size:
            return f"{count / size:.1f} {unit}"
    return f"{count:.0f} B"


def _parse_limit(text: str) -> int:
    match = re.fullmatch(r"\s*(\d+(?:\.\d+)?)\s*([A-Za-z]*)\s*", text)
    if match is None or match.group(2).lower() not in _UNITS:
        msg = f"{MEMORY_LIMIT_VARIABLE}: {text!r} is not a size such as 2GiB or 500000000"
        raise ResourceError(msg)
    return int(float(match.group(1)) * _UNITS[match.group(2).lower()])


def memory_limit() -> int:
    """Bytes a command may plan to use: ``SWARMTAG_MEMORY_LIMIT`` or the memory available now."""
    explicit = os.environ.get(MEMORY_LIMIT_VARIABLE)
    if explicit:
        return _parse_limit(explicit)
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, AttributeError):  # pragma: no cover - non-POSIX platforms
        return _FALLBACK


def check_memory(what: str, estimate: float, *, error: type[SwarmtagError] = ResourceError) -> None:
    """Refuse ``what`` (e.g. ``"--runs 10000000000"``) if ``estimate`` bytes exceed the limit."""
    limit = memory_limit()
    if estimate > limit:
        msg = (
            f"{what} needs about {format_bytes(estimate)} of memory; "
            f"{format_bytes(limit)} is available (set {MEMORY_LIMIT_VARIABLE} to change the limit)"
        )
        raise error(msg)
