"""Which of the package's source files a module depends on: its project imports, read statically.

Two digests need it: the compiled kernel's (stale machine code is discarded
when a module it reads constants from changes) and the model's (a stored
run is recomputed when the code that decides its rows changes, but not when
a picture's code does). Imports are read with ``ast``, so imports inside
functions (lazy extras) count, and nothing is imported to find them.
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Final

__all__ = ["PACKAGE_ROOT", "imported_sources"]

PACKAGE_ROOT: Final = Path(__file__).resolve().parent
"""The ``swarmtag`` package's folder."""


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


def _imports(path: Path) -> set[Path]:
    """The project source files ``path`` imports (absolute imports, submodules included)."""
    found: set[Path] = set()
    for node in _import_statements(ast.parse(path.read_bytes())):
        names: list[str] = []
        if isinstance(node, ast.ImportFrom):
            if node.module and node.level == 0:
                names = [node.module] + [f"{node.module}.{alias.name}" for alias in node.names]
        else:
            names = [alias.name for alias in node.names]
        found.update(file for name in names if (file := _module_file(name)) is not None)
    return found


def imported_sources(roots: Iterable[Path], *, transitive: bool) -> list[Path]:
    """``roots`` and the project sources they import: directly, or (``transitive``) all the way.

    >>> here = PACKAGE_ROOT / "_sources.py"
    >>> imported_sources([here], transitive=True) == [here]
    True
    """
    found = set(roots)
    queue = list(found)
    while queue:
        for imported in _imports(queue.pop()):
            if imported not in found:
                found.add(imported)
                if transitive:
                    queue.append(imported)
    return sorted(found)
