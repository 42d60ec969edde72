"""Which of the package's source files a module depends on: its project imports, read statically.

Two digests need it: the compiled kernel's (stale machine code is discarded
when a module it reads constants from changes) and the model's (a stored
run is recomputed when the code that decides its rows changes, but not when
a picture's code does). Imports are read with ``ast``, so imports inside
functions (lazy extras) count, and nothing is imported to find them.

Parsing is most of a digest's time, and what a file names depends on its
bytes alone: the names found are kept by the SHA-256 of the file's bytes in
``CACHE_FILE`` (beside the package's bytecode), so a file is parsed again
only once it changed. Which files the names are is looked up each time.
"""

from __future__ import annotations

import ast
import contextlib
import hashlib
import json
import os
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Final

__all__ = ["CACHE_FILE", "PACKAGE_ROOT", "imported_sources"]

PACKAGE_ROOT: Final = Path(__file__).resolve().parent
"""The ``swarmtag`` package's folder."""
CACHE_FILE: Final = PACKAGE_ROOT / "__pycache__" / "swarmtag-imports.json"
"""The module names each source file imports, by the SHA-256 of its bytes (``_Names``)."""
CACHE_ENTRIES: Final = 2000
"""File versions the cache keeps, the most recently used: a few edits of every source."""


def _module_file(module: str) -> Path | None:
    """The source file of project module ``module`` (``swarmtag.x.y``), or None if not ours."""
    parts = module.split(".")
    if parts[0] != "swarmtag":
        return None
    base = PACKAGE_ROOT.joinpath(*parts[1:])
    if base.with_suffix(".py").is_file():
        return base.with_suffix(".py")
    package = base / "__init__.py"
    return package if package.is_file() else None


def _import_statements(tree: ast.Module) -> Iterator[ast.Import | ast.ImportFrom]:
    """Every import statement in ``tree``, at any depth (functions, classes, ``if``, ``try``).

    Imports are statements, so only statement bodies are searched, never
    expressions: a tenth of the nodes ``ast.walk`` visits.
    """
    bodies: list[ast.AST] = [tree]
    while bodies:
        node = bodies.pop()
        for field in _BODIES:
            for child in getattr(node, field, ()):
                if isinstance(child, ast.Import | ast.ImportFrom):
                    yield child
                elif isinstance(child, ast.stmt | ast.excepthandler | ast.match_case):
                    bodies.append(child)


_BODIES: Final = ("body", "orelse", "finalbody", "handlers", "cases")
"""The fields of a node that hold statements (or the handlers and cases that hold them)."""


class _Names:
    """The project module names each source imports, by its bytes' SHA-256: ``CACHE_FILE``.

    A cache that cannot be read starts empty; one that cannot be written is left
    as it was (the names are then found again next time).
    """

    def __init__(self, file: Path) -> None:
        self.file = file
        self.entries: dict[str, list[str]] = {}
        self.changed = False
        with contextlib.suppress(OSError, ValueError):
            data = json.loads(file.read_bytes())
            if isinstance(data, dict):
                self.entries = {
                    key: names
                    for key, names in data.items()
                    if isinstance(names, list) and all(isinstance(n, str) for n in names)
                }

    def of(self, source: bytes) -> list[str]:
        """The module names ``source`` imports (absolute imports, submodules included)."""
        key = hashlib.sha256(source).hexdigest()
        names = self.entries.pop(key, None)
        if names is None:
            names = _names(ast.parse(source))
            self.changed = True
        self.entries[key] = names  # last: the most recently used
        return names

    def save(self) -> None:
        """Write the cache if it gained names, the ``CACHE_ENTRIES`` last used (atomically)."""
        if not self.changed:
            return
        kept = dict(list(self.entries.items())[-CACHE_ENTRIES:])
        temp = self.file.with_name(f"{self.file.name}.{os.getpid()}.tmp")
        try:
            self.file.parent.mkdir(exist_ok=True)
            temp.write_text(json.dumps(kept, separators=(",", ":")), encoding="utf-8")
            temp.replace(self.file)
        except OSError:  # a read-only installation: found again next time
            with contextlib.suppress(OSError):
                temp.unlink(missing_ok=True)


def _names(tree: ast.Module) -> list[str]:
    """The project module names ``tree`` imports (absolute imports, submodules included)."""
    names: set[str] = set()
    for node in _import_statements(tree):
        if isinstance(node, ast.ImportFrom):
            if node.module and node.level == 0:
                names.add(node.module)
                names.update(f"{node.module}.{alias.name}" for alias in node.names)
        else:
            names.update(alias.name for alias in node.names)
    return sorted(name for name in names if name.split(".")[0] == "swarmtag")


def _imports(path: Path, names: _Names | None = None) -> set[Path]:
    """The project source files ``path`` imports (absolute imports, submodules included)."""
    source = path.read_bytes()
    found = _names(ast.parse(source)) if names is None else names.of(source)
    return {file for name in found if (file := _module_file(name)) is not None}


def imported_sources(roots: Iterable[Path], *, transitive: bool) -> list[Path]:
    """``roots`` and the project sources they import: directly, or (``transitive``) all the way.

    >>> here = PACKAGE_ROOT / "_sources.py"
    >>> imported_sources([here], transitive=True) == [here]
    True
    """
    names = _Names(CACHE_FILE)
    found = set(roots)
    queue = list(found)
    while queue:
        for imported in _imports(queue.pop(), names):
            if imported not in found:
                found.add(imported)
                if transitive:
                    queue.append(imported)
    names.save()
    return sorted(found)
