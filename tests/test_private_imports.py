"""No module of the package imports a dependency's private module (``a._b``) or private name.

A dependency's underscored modules and names are not its API: they move or
go between releases without notice. What the project needs from one it
copies (``swarmtag.sim.fast``'s ziggurat tables) or does itself. The
standard library's own underscored modules (``_thread``) are documented
and stable, and ``swarmtag``'s are the project's.
"""

from __future__ import annotations

import ast
import sys
from pathlib import Path

import swarmtag

PACKAGE = Path(swarmtag.__file__).parent
MODULES = sorted(PACKAGE.rglob("*.py"))
ALLOWED_TOP = {"swarmtag", "__future__", "_typeshed", *sys.stdlib_module_names}
"""The project, the standard library, and ``_typeshed``: the type checkers' standard-library
stubs (annotations under ``TYPE_CHECKING`` only; no module at run time)."""


def private_imports(source: str) -> list[str]:
    """The private imports of other packages in ``source``: ``module`` or ``module:name``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            imported = [(alias.name, []) for alias in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            imported = [(node.module, [alias.name for alias in node.names])]
        else:
            continue  # relative imports are the package's own
        for module, names in imported:
            parts = module.split(".")
            if parts[0] in ALLOWED_TOP:
                continue
            if any(part.startswith("_") for part in parts):
                found.append(f"{module} (line {node.lineno})")
                continue
            found += [
                f"{module}:{name} (line {node.lineno})"
                for name in names
                if name.startswith("_") and not name.startswith("__")
            ]
    return found


def test_the_check_finds_private_imports():
    source = (
        "from numba.np.random._constants import ki_double\n"
        "import dbus_next._private.address\n"
        "from numpy import _core\n"
        "from __future__ import annotations\n"
        "import _thread\n"
        "from _typeshed import DataclassInstance\n"
        "from swarmtag._checks import check_int\n"
        "from numpy.random import Generator\n"
        "from . import _sibling\n"
    )
    assert private_imports(source) == [
        "numba.np.random._constants (line 1)",
        "dbus_next._private.address (line 2)",
        "numpy:_core (line 3)",
    ]


def test_modules_are_found():
    assert PACKAGE / "sim" / "fast" / "_pcg.py" in MODULES


def test_no_private_import_of_a_dependency():
    offenders = {
        path.relative_to(PACKAGE).as_posix(): found
        for path in MODULES
        if (found := private_imports(path.read_text(encoding="utf-8")))
    }
    assert offenders == {}
