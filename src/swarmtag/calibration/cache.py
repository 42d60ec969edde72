"""A resumable cache of evaluated points: JSON lines, appended and flushed after each evaluation.

Each line holds a point's key (``CalibrationProblem.point_key``: targets,
base values, free values, runs, seed, model digest), its free values, the
KPIs the simulation achieved per set-up, and ``check``: the SHA-256 of the
rest of the line in canonical JSON. The objective is recomputed from the
KPIs when a line is reused, so it always follows the current targets. A
rerun of the same command finds every point it visits here: an interrupted
calibration resumes, a repeated one simulates nothing.

The file is input like any other, so every line is checked before it is
used (``parse_line``): at most ``MAX_LINE_BYTES``, nested at most
``MAX_JSON_DEPTH`` deep, plain JSON (no ``NaN`` or ``Infinity``, no integer
of more than ``MAX_DIGITS`` digits), exactly the keys above, names of at
most ``MAX_NAME`` characters, at most ``MAX_ENTRIES`` values or KPIs per
table, every number finite and within ``MAX_MAGNITUDE``, and its check
matching. The check is what catches a value that is well formed but not the
one written (a ``null`` where a number was, a renamed set-up or KPI, an
edited number): the schema alone cannot know which KPI may be undefined.

A line that fails (a line cut off by a kill, or edited, or damaged) is never
used: it is skipped, its point is simulated again when the search visits it,
and ``skipped_note`` names the lines in one line. Lines are never rewritten:
the file is appended to only. A file that is not UTF-8 text is refused as a
whole, since appending to it would damage what it is.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import os
import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Final, NoReturn

from swarmtag._atomic import write_failure
from swarmtag._checks import check_path_value, show
from swarmtag.calibration.objective import Achieved
from swarmtag.errors import CalibrationError

__all__ = [
    "MAX_DIGITS",
    "MAX_ENTRIES",
    "MAX_JSON_DEPTH",
    "MAX_LINE_BYTES",
    "MAX_MAGNITUDE",
    "MAX_NAME",
    "CacheEntry",
    "EvaluationCache",
    "default_cache_path",
    "parse_line",
]

MAX_LINE_BYTES: Final = 1 << 20
"""Longest line read (1 MiB): a point of a hundred set-ups of every KPI takes about 30 KiB."""
MAX_JSON_DEPTH: Final = 4
"""Deepest nesting of a line: the line, ``achieved``, a set-up, its KPIs (3), and one to spare."""
MAX_DIGITS: Final = 20
"""Most digits of an integer in a line (an int64 has 19); longer ones are refused unparsed."""
MAX_NAME: Final = 256
"""Longest free-parameter, set-up or KPI name in a line."""
MAX_ENTRIES: Final = 10_000
"""Most free values, set-ups, or KPIs of one set-up in a line."""
MAX_MAGNITUDE: Final = 1e15
"""Largest magnitude of a value in a line: KPIs are times up to 1e12 s and counts well below."""
_KEYS: Final = frozenset({"key", "values", "objective", "achieved", "check"})
_HEX: Final = re.compile(r"[0-9a-f]{64}")
_NESTING: Final = re.compile(r'["\[\]{}]')
_STRING_BODY: Final = re.compile(r'(?:[^"\\]|\\.)*', re.DOTALL)
_SHOWN_LINES: Final = 5


def default_cache_path(out: Path) -> Path:
    """``PROFILE.cache.jsonl`` next to ``PROFILE.toml``.

    >>> default_cache_path(Path("out/lab.toml")).as_posix()
    'out/lab.cache.jsonl'
    """
    path = Path(check_path_value("out", out, error=CalibrationError))
    if not path.stem or path.name in (".", ".."):
        raise CalibrationError(f"out: {show(str(out))} names no file to put a cache next to")
    return path.with_name(f"{path.stem}.cache.jsonl")


@dataclass(frozen=True)
class CacheEntry:
    """What the cache keeps of one evaluation: the free values and the achieved KPIs."""

    values: Mapping[str, float]
    achieved: Achieved


def _check(record: Mapping[str, Any]) -> str:
    """The SHA-256 of ``record`` (a line but its check) in the canonical JSON it is written in."""
    text = json.dumps(record, sort_keys=True, allow_nan=False)
    return hashlib.sha256(text.encode()).hexdigest()


def _constant(name: str) -> NoReturn:
    msg = f"{name} is not a number JSON allows"
    raise CalibrationError(msg)


def _integer(text: str) -> int:
    if len(text.lstrip("-")) > MAX_DIGITS:
        msg = f"an integer of {len(text.lstrip('-'))} digits"
        raise CalibrationError(msg)
    return int(text)


def _real(text: str) -> float:
    if len(text) > 2 * MAX_DIGITS:
        msg = f"a number written in {len(text)} characters"
        raise CalibrationError(msg)
    return float(text)  # 1e400 gives inf: refused with the range check


def _unique(pairs: list[tuple[str, Any]]) -> dict[str, Any]:
    table = dict(pairs)
    if len(table) != len(pairs):
        raise CalibrationError("a key given twice")
    return table


def _depth(text: str) -> int:
    """The ``[``/``{`` nesting of JSON ``text`` outside strings, up to ``MAX_JSON_DEPTH`` + 1."""
    level = deepest = at = 0
    while (found := _NESTING.search(text, at)) is not None:
        mark, at = found.group(), found.end()
        if mark == '"':  # skip the string; an unclosed one runs to the end
            body = _STRING_BODY.match(text, at)
            at = (body.end() if body else at) + 1
        elif mark in "[{":
            level += 1
            deepest = max(deepest, level)
            if deepest > MAX_JSON_DEPTH:
                break  # deep enough to refuse: no need to read on
        else:
            level -= 1
    return deepest


def _name(value: object, where: str) -> str:
    if not isinstance(value, str) or not value or len(value) > MAX_NAME:
        msg = f"{where}: not a name of 1-{MAX_NAME} characters"
        raise CalibrationError(msg)
    return value


def _number(value: object, where: str) -> float:
    """A finite number within ``MAX_MAGNITUDE``, as a float."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        msg = f"{where}: {type(value).__name__} is not a number"
        raise CalibrationError(msg)
    number = float(value)
    if not math.isfinite(number) or abs(number) > MAX_MAGNITUDE:
        msg = f"{where}: {number!r} is not a finite number within {MAX_MAGNITUDE:g}"
        raise CalibrationError(msg)
    return number


def _kpi(value: object, where: str) -> float | None:
    """An achieved KPI: a number as ``_number`` checks it, or ``None`` (left undefined)."""
    return None if value is None else _number(value, where)


def _table(value: object, where: str) -> dict[str, Any]:
    if not isinstance(value, dict):
        msg = f"{where}: not an object"
        raise CalibrationError(msg)
    if len(value) > MAX_ENTRIES:
        msg = f"{where}: more than {MAX_ENTRIES} entries"
        raise CalibrationError(msg)
    return value


def parse_line(text: str) -> tuple[str, CacheEntry]:
    """The key and entry of one cache line; ``CalibrationError`` saying why it cannot be used.

    >>> parse_line('{"key": "k"}')
    Traceback (most recent call last):
    swarmtag.errors.CalibrationError: keys achieved, check, objective, values missing
    >>> parse_line('{"a": NaN}')
    Traceback (most recent call last):
    swarmtag.errors.CalibrationError: NaN is not a number JSON allows
    """
    if len(text) > MAX_LINE_BYTES:
        msg = f"longer than {MAX_LINE_BYTES} bytes"
        raise CalibrationError(msg)
    if _depth(text) > MAX_JSON_DEPTH:
        msg = f"nested more than {MAX_JSON_DEPTH} levels deep"
        raise CalibrationError(msg)
    try:
        data = json.loads(
            text,
            parse_constant=_constant,
            parse_int=_integer,
            parse_float=_real,
            object_pairs_hook=_unique,
        )
    except RecursionError:  # the scan above should have refused it first
        msg = f"nested more than {MAX_JSON_DEPTH} levels deep"
        raise CalibrationError(msg) from None
    except CalibrationError:
        raise  # from the hooks: NaN, a huge integer, a key given twice
    except ValueError as error:  # json.JSONDecodeError among them
        msg = f"not JSON ({error})"
        raise CalibrationError(msg) from None
    record = _table(data, "the line")
    if set(record) != _KEYS:
        missing, unknown = _KEYS - set(record), set(record) - _KEYS
        parts = [f"keys {', '.join(sorted(missing))} missing"] if missing else []
        parts += [f"unknown keys {', '.join(sorted(map(str, unknown)))}"] if unknown else []
        raise CalibrationError("; ".join(parts)[: 4 * MAX_NAME])
    check = record.pop("check")
    if not isinstance(check, str) or not _HEX.fullmatch(check) or check != _check(record):
        raise CalibrationError("its check does not match its content (the line was changed)")
    key = _name(record["key"], "key")
    _kpi(record["objective"], "objective")
    values = {
        name: _number(value, f"values.{_name(name, 'values')}")
        for name, value in _table(record["values"], "values").items()
    }
    achieved: dict[str, dict[str, float | None]] = {}
    for setup, kpis in _table(record["achieved"], "achieved").items():
        where = f"achieved.{_name(setup, 'achieved')}"
        achieved[setup] = {
            kpi: _kpi(value, f"{where}.{_name(kpi, where)}")
            for kpi, value in _table(kpis, where).items()
        }
    return key, CacheEntry(values=values, achieved=achieved)


def _lines(handle: IO[bytes]) -> Iterator[tuple[int, bytes | None]]:
    """Each line's number and bytes (``None`` for one over ``MAX_LINE_BYTES``, never held whole)."""
    number = 0
    while True:
        line = handle.readline(MAX_LINE_BYTES + 1)
        if not line:
            return
        number += 1
        if len(line) > MAX_LINE_BYTES and not line.endswith(b"\n"):
            while line and not line.endswith(b"\n"):  # skip the rest of the long line
                line = handle.readline(MAX_LINE_BYTES)
            yield number, None
            continue
        yield number, line


def _spans(numbers: list[int]) -> str:
    """``"3, 7-9"`` for lines 3, 7, 8, 9."""
    spans: list[list[int]] = []
    for number in numbers:
        if spans and number == spans[-1][1] + 1:
            spans[-1][1] = number
        else:
            spans.append([number, number])
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in spans)


class EvaluationCache:
    """Evaluations by key, read from and appended to a JSON-lines file (``None``: memory only)."""

    def __init__(self, path: Path | None) -> None:
        self.path = path
        self.skipped_lines: list[tuple[int, str]] = []
        """The lines that could not be used, by number (from 1), each with why."""
        self._entries: dict[str, CacheEntry] = {}
        if path is not None and path.exists():
            self._load(path)

    @property
    def skipped(self) -> int:
        """How many lines of the file could not be used (e.g. one cut off by a kill)."""
        return len(self.skipped_lines)

    def skipped_note(self) -> str:
        """One line naming the skipped lines and why the first was, or ``""`` if none was.

        >>> cache = EvaluationCache(None)
        >>> cache.skipped_lines = [(3, "not JSON"), (4, "x"), (5, "y"), (9, "z")]
        >>> cache.path = Path("c")
        >>> print(cache.skipped_note())
        4 lines of c could not be used (lines 3-5, 9; line 3: not JSON); a point found in no
        other line is simulated again
        """
        if not self.skipped_lines:
            return ""
        numbers = [number for number, _ in self.skipped_lines]
        shown = _spans(numbers[:_SHOWN_LINES])
        more = f" and {len(numbers) - _SHOWN_LINES} more" if len(numbers) > _SHOWN_LINES else ""
        first, why = self.skipped_lines[0]
        count = "1 line" if len(numbers) == 1 else f"{len(numbers)} lines"
        word = "line" if len(numbers) == 1 else "lines"
        return (
            f"{count} of {self.path} could not be used ({word} {shown}{more}; line {first}: "
            f"{why}); a point found in no other line is simulated again"
        )

    def _load(self, path: Path) -> None:
        try:
            with path.open("rb") as handle:
                for number, line in _lines(handle):
                    self._read(number, line)
        except OSError as error:
            raise CalibrationError(f"--cache {path}: cannot read it ({error})") from None

    def _read(self, number: int, line: bytes | None) -> None:
        if line is None:
            self.skipped_lines.append((number, f"longer than {MAX_LINE_BYTES} bytes"))
            return
        try:
            text = line.decode("utf-8")
        except UnicodeDecodeError as error:
            msg = f"--cache {self.path}: cannot read it (line {number} is not UTF-8 text: {error})"
            raise CalibrationError(msg) from None
        if not text.strip():
            return
        try:
            key, entry = parse_line(text)
        except CalibrationError as error:  # never used: its point is simulated again
            self.skipped_lines.append((number, str(error)))
            return
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
        record["check"] = _check(record)
        line = json.dumps(record, sort_keys=True, allow_nan=False) + "\n"
        existed = self.path.exists()
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
            if not existed:  # created just now and never written: leave nothing behind
                with contextlib.suppress(OSError):
                    self.path.unlink()
            failure = write_failure(error, self.path)  # a full disk: said as every output says it
            if failure is not None:
                raise failure from None
            raise CalibrationError(f"--cache {self.path}: cannot append to it ({error})") from None
