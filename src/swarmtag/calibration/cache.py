"""A resumable cache of evaluated points: JSON lines, appended and flushed after each evaluation.

Each line holds a point's key (``CalibrationProblem.point_key``: targets,
base values, free values, runs, seed, model digest), its free values and the
KPIs the simulation achieved per set-up. The objective is recomputed from
the KPIs when a line is reused, so it always follows the current targets.
A rerun of the same command finds every point it visits here: an
interrupted calibration resumes, a repeated one simulates nothing. Lines
that do not parse (a line cut off by a kill) are skipped and counted.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from swarmtag.calibration.objective import Achieved
from swarmtag.errors import CalibrationError

__all__ = ["CacheEntry", "EvaluationCache", "default_cache_path"]


def default_cache_path(out: Path) -> Path:
    """``PROFILE.cache.jsonl`` next to ``PROFILE.toml``.

    >>> default_cache_path(Path("out/lab.toml")).as_posix()
    'out/lab.cache.jsonl'
    """
    return out.with_name(f"{out.stem}.cache.jsonl")


@dataclass(frozen=True)
class CacheEntry:
    """What the cache keeps of one evaluation: the free values and the achieved KPIs."""

    values: Mapping[str, float]
    achieved: Achieved


def _float_or_none(value: object) -> float | None:
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise TypeError(value)
    return float(value)


def _entry(data: object) -> tuple[str, CacheEntry]:
    """Parse one line's object; ``TypeError``/``KeyError`` for anything malformed."""
    if not isinstance(data, dict):
        raise TypeError(data)
    key = data["key"]
    if not isinstance(key, str):
        raise TypeError(key)
    values = {str(name): float(value) for name, value in data["values"].items()}
    achieved = {
        str(setup): {str(kpi): _float_or_none(value) for kpi, value in kpis.items()}
        for setup, kpis in data["achieved"].items()
    }
    return key, CacheEntry(values=values, achieved=achieved)


class EvaluationCache:
    """Evaluations by key, read from and appended to a JSON-lines file (``None``: memory only)."""

    def __init__(self, path: Path | None) -> None:
        self.path = path
        self.skipped = 0
        """Lines of the file that could not be read (e.g. one cut off by a kill)."""
        self._entries: dict[str, CacheEntry] = {}
        if path is not None and path.exists():
            self._load(path)

    def _load(self, path: Path) -> None:
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as error:
            raise CalibrationError(f"--cache {path}: cannot read it ({error})") from None
        for line in text.splitlines():
            if not line.strip():
                continue
            try:
                key, entry = _entry(json.loads(line))
            except (ValueError, TypeError, KeyError, AttributeError):
                self.skipped += 1
                continue
            self._entries[key] = entry

    def __len__(self) -> int:
        return len(self._entries)

    def __contains__(self, key: object) -> bool:
        return key in self._entries

    def get(self, key: str) -> CacheEntry | None:
        """The entry under ``key``, if any."""
        return self._entries.get(key)

    def put(self, key: str, entry: CacheEntry, *, objective: float) -> None:
        """Keep ``entry`` and append it to the file at once (flushed to disk).

        ``objective`` is written for people reading the file; it is not read back.
        """
        self._entries[key] = entry
        if self.path is None:
            return
        record: dict[str, Any] = {
            "key": key,
            "values": dict(entry.values),
            "objective": objective if math.isfinite(objective) else None,
            "achieved": {setup: dict(kpis) for setup, kpis in entry.achieved.items()},
        }
        line = json.dumps(record, sort_keys=True, allow_nan=False) + "\n"
        try:
            with self.path.open("a+b") as handle:
                handle.seek(0, os.SEEK_END)
                if handle.tell() > 0:
                    handle.seek(-1, os.SEEK_END)
                    if handle.read(1) != b"\n":  # a line cut off by a kill: end it first
                        handle.write(b"\n")
                handle.write(line.encode())
                handle.flush()
                os.fsync(handle.fileno())
        except OSError as error:
            raise CalibrationError(f"--cache {self.path}: cannot append to it ({error})") from None
