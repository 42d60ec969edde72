"""Reading TOML, the one way: bounded in size and nesting, every failure one clear error.

Every TOML input goes through here: profile, scenario, study, target,
camera and bag-mapping files (``read_toml``), the shipped bag mapping
(``loads_toml``) and ``--set KEY=VALUE`` values (``toml_value``). Each is

- at most ``MAX_TOML_BYTES`` (1 MiB; the largest shipped file is about
  2 KiB), checked before the text is parsed (a file is read no further);
- nested at most ``MAX_TOML_DEPTH`` (32) levels deep, checked by a scan of
  the text *before* parsing: ``tomllib`` parses nested arrays and inline
  tables recursively, so a kilobyte of ``[[[[...`` or ``{a = {a = ...``
  raised ``RecursionError`` (a traceback) instead of a refusal, and deep
  tables built from dotted keys (``[a.a.a...]``) would reach whatever later
  walks them. The depth counted is the one written: the segments of the
  current table header (twice, once an array of tables was declared), the
  dotted segments of a key, and every open ``[``
  or ``{`` of a value, outside strings and comments (a dot in a float counts
  too, erring on the safe side). A ``RecursionError`` that got past the
  scan would be refused the same way;
- refused, when it is not valid UTF-8 TOML, with the parser's message.

Each refusal is the caller's ``SwarmtagError`` subclass naming the file
(or ``--set``), so the command line prints one line and exits 2.
"""

from __future__ import annotations

import os
import re
import tomllib
from dataclasses import dataclass, field
from typing import Any, Final

from swarmtag._inputs import regular_file
from swarmtag.errors import SwarmtagError

__all__ = [
    "MAX_TOML_BYTES",
    "MAX_TOML_DEPTH",
    "check_toml_depth",
    "loads_toml",
    "read_toml",
    "toml_value",
    "written_depth",
]

MAX_TOML_BYTES: Final = 1 << 20
"""Largest TOML input read (1 MiB): hundreds of times any real profile, study or rig file."""
MAX_TOML_DEPTH: Final = 32
"""Deepest nesting a TOML input may write (headers, dotted keys and brackets; see the module)."""

_MARKS: Final = re.compile(r"[\[\]{}.,=\n\"'#]")
"""What nests, separates or ends a statement, and what starts a string or a comment."""
_BASIC_BODY: Final = re.compile(r'(?:[^"\\\n]|\\.)*')
_MULTILINE_BODY: Final = re.compile(r'(?:[^"\\]|\\.|"{1,2}(?!"))*', re.DOTALL)


def _past_string(text: str, start: int) -> int:
    """Where the string opening at ``start`` ends (an unclosed one: its line, or the text).

    Each character is looked at once, by a pattern that never backtracks
    more than two quotes, so the scan stays linear on any text.
    """
    if text.startswith('"""', start):
        end = _MULTILINE_BODY.match(text, start + 3)
        return _past_quotes(text, end.end() if end else len(text), '"')
    if text.startswith("'''", start):
        end_at = text.find("'''", start + 3)
        return len(text) if end_at < 0 else _past_quotes(text, end_at, "'")
    if text[start] == '"':
        end = _BASIC_BODY.match(text, start + 1)
        close = end.end() if end else start + 1
        if text.startswith('"', close):
            return close + 1
    else:
        close = text.find("'", start + 1)
        if close >= 0 and text.find("\n", start + 1, close) < 0:  # never past the string
            return close + 1
    newline = text.find("\n", start + 1)  # unclosed: invalid TOML, the parser says so
    return len(text) if newline < 0 else newline


def _past_quotes(text: str, at: int, quote: str) -> int:
    """Past the run of ``quote`` at ``at`` (a multi-line string may end in 3-5 of them)."""
    end = at
    while end < len(text) and text[end] == quote:
        end += 1
    return end


def _too_deep(source: str) -> str:
    return (
        f"{source}: nested more than {MAX_TOML_DEPTH} levels deep "
        "(tables, dotted keys, arrays and inline tables together); flatten it"
    )


@dataclass
class _Scan:
    """Where ``written_depth`` is in the text: the levels so far, and what is open."""

    header: int = 0  # levels of the current table header
    level: int = 0  # levels of the current statement so far
    opened: list[int] = field(default_factory=list)  # the level before each open bracket
    in_header: bool = False
    in_value: bool = False  # past the statement's '=' (at the top level)
    parts: int = 0  # the segments of the header being read
    array_header: bool = False  # the header being read is '[[...]]'
    arrays_seen: bool = False  # some '[[...]]' header came before

    def step(self, mark: str) -> None:
        """Take one structural character: a bracket, brace, dot, comma, '=' or newline."""
        if mark == "\n":
            if not self.opened and not self.in_header:
                self.level, self.in_value = self.header, False
        elif self.in_header:
            self._header(mark)
        elif mark == "[" and not self.opened and not self.in_value:
            self.in_header, self.level, self.parts, self.array_header = True, 1, 1, False
        else:
            self._statement(mark)

    def _header(self, mark: str) -> None:
        """A header's levels: its segments, each counted twice once any ``[[`` came before.

        Any segment may name an array of tables, which nests one level more
        than it is written (``[[a]]`` then ``[a.b]`` is a, its list, its
        last table, b): the scan does not read names, so it assumes so.
        """
        if mark == ".":
            self.level += 1
            self.parts += 1
        elif mark == "]":
            self.arrays_seen = self.arrays_seen or self.array_header
            self.in_header = False
            self.header = self.level = 2 * self.parts if self.arrays_seen else self.parts
        elif mark == "[":
            self.level += 1  # '[[': an array of tables, one level more
            self.array_header = True

    def _statement(self, mark: str) -> None:
        if mark in "[{":
            self.opened.append(self.level)
            self.level += 1
        elif mark in "]}":
            self.level = self.opened.pop() if self.opened else self.level
        elif mark == ",":
            self.level = self.opened[-1] + 1 if self.opened else self.level
        elif mark == ".":
            self.level += 1
        elif mark == "=" and not self.opened:
            self.in_value = True


def written_depth(text: str, *, stop_above: int | None = None) -> int:
    r"""How deep ``text`` nests as written (see the module); a linear scan, never a parse.

    At least the depth of the parsed tables and arrays below the top table
    (an array of tables counts one more). Linear in the text's length on any
    input (strings are skipped by patterns that do not backtrack); stops as
    soon as the depth passes ``stop_above``.

    >>> written_depth('[a.b]\nc = [1, {d = "[[["}]  # ]]]'), written_depth("x.y = [[1]]")
    (4, 3)
    """
    scan = _Scan()
    deepest = 0
    at = 0
    while (found := _MARKS.search(text, at)) is not None:
        mark, at = found.group(), found.start()
        if mark in "\"'":
            at = _past_string(text, at)
            continue
        if mark == "#":
            newline = text.find("\n", at)
            at = len(text) if newline < 0 else newline
            continue
        scan.step(mark)
        at += 1
        deepest = max(deepest, scan.level)
        if stop_above is not None and deepest > stop_above:
            break
    return deepest


def check_toml_depth(text: str, *, source: str, error: type[SwarmtagError]) -> None:
    """Refuse ``text`` if it nests deeper than ``MAX_TOML_DEPTH`` (``written_depth``).

    >>> check_toml_depth("a = " + "[" * 40 + "]" * 40, source="x", error=SwarmtagError)
    Traceback (most recent call last):
    swarmtag.errors.SwarmtagError: x: nested more than 32 levels deep ...
    """
    if sum(map(text.count, "[{.")) <= MAX_TOML_DEPTH:
        return  # each level is written with one of these: no need to scan
    if written_depth(text, stop_above=MAX_TOML_DEPTH) > MAX_TOML_DEPTH:
        raise error(_too_deep(source))


def _check_size_and_depth(text: str, *, source: str, error: type[SwarmtagError]) -> None:
    """Refuse ``text`` above ``MAX_TOML_BYTES`` (in UTF-8) or ``MAX_TOML_DEPTH`` levels deep."""
    if len(text) > MAX_TOML_BYTES or len(text.encode("utf-8", "surrogatepass")) > MAX_TOML_BYTES:
        msg = f"{source}: larger than {MAX_TOML_BYTES // 1024} KiB; a TOML input may be no larger"
        raise error(msg)
    check_toml_depth(text, source=source, error=error)


def _parse(text: str, *, source: str, error: type[SwarmtagError]) -> dict[str, Any]:
    """``tomllib.loads`` of checked text; ``TOMLDecodeError`` is the caller's to handle."""
    try:
        return tomllib.loads(text)
    except RecursionError:  # the scan should have refused it first; never a traceback
        raise error(_too_deep(source)) from None


def loads_toml(text: str, *, source: str, error: type[SwarmtagError]) -> dict[str, Any]:
    """The top table of the TOML ``text``; ``error`` naming ``source`` if it is refused.

    >>> loads_toml('a = [1, {b = 2}]', source="x.toml", error=SwarmtagError)
    {'a': [1, {'b': 2}]}
    """
    _check_size_and_depth(text, source=source, error=error)
    try:
        return _parse(text, source=source, error=error)
    except tomllib.TOMLDecodeError as problem:
        msg = f"{source}: not valid TOML ({problem})"
        raise error(msg) from None


def read_toml(
    path: str | os.PathLike[str], *, what: str, error: type[SwarmtagError]
) -> dict[str, Any]:
    """The top table of the TOML file at ``path``; failures raise ``error`` naming the file.

    ``what`` names the kind of file in the "no such ..." message (``"study file"``).
    Only a regular file is opened, and no more than ``MAX_TOML_BYTES`` + 1 bytes are read.
    """
    name = os.fspath(path)
    try:
        with regular_file(path, what=what, error=error).open("rb") as handle:
            data = handle.read(MAX_TOML_BYTES + 1)
    except FileNotFoundError:
        msg = f"{name}: no such {what}"
        raise error(msg) from None
    except OSError as problem:
        msg = f"{name}: cannot read ({problem.strerror})"
        raise error(msg) from None
    if len(data) > MAX_TOML_BYTES:
        msg = f"{name}: larger than {MAX_TOML_BYTES // 1024} KiB; a {what} may be no larger"
        raise error(msg)
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as problem:
        msg = f"{name}: not valid TOML ({problem})"
        raise error(msg) from None
    return loads_toml(text, source=name, error=error)


def toml_value(text: str, *, source: str, error: type[SwarmtagError]) -> object:
    """``text`` read as a TOML value (``20``, ``[1, 2]``, ``"a"``), or itself if it is none.

    For ``--set KEY=VALUE``: a bare word (``carriers``) is not TOML and stays
    a string (stripped). Too long or too deeply nested text is refused, never parsed.

    >>> toml_value("20", source="--set", error=SwarmtagError)
    20
    >>> toml_value(" carriers ", source="--set", error=SwarmtagError)
    'carriers'
    """
    raw = text.strip()
    document = f"v = {raw}"
    _check_size_and_depth(document, source=source, error=error)
    try:
        return _parse(document, source=source, error=error)["v"]
    except tomllib.TOMLDecodeError:
        return raw
