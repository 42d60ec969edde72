"""docs/architecture.md is true to the tree, and the package's arrows point one way."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "swarmtag"
_ENTRY = re.compile(r"^(?P<indent> *)(?P<names>[\w.*/-]+(?:, [\w.*/-]+)*)(?:  +.*)?$")


def _layout_block() -> list[str]:
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    section = text.split("## Layout as built", 1)[1]
    return section.split("```", 2)[1].splitlines()


def _named_paths() -> set[Path]:
    """Every path the layout map names, resolved against the folders above it."""
    named: set[Path] = set()
    stack: list[tuple[int, Path]] = []
    for line in _layout_block():
        match = _ENTRY.match(line)
        if match is None:
            continue
        indent = len(match["indent"])
        if indent % 2 or indent > 2 * (len(stack) + 1):
            continue  # a description's continuation line
        stack = [(level, path) for level, path in stack if level < indent]
        base = stack[-1][1] if stack else ROOT
        for name in match["names"].split(", "):
            path = base / name.rstrip("/")
            named.add(path)
            if name.endswith("/"):
                stack.append((indent, path))
    return named


def _modules(folder: Path) -> list[Path]:
    return sorted(p for p in folder.rglob("*.py") if "__pycache__" not in p.parts)


def test_every_module_the_map_names_exists():
    missing = [p for p in _named_paths() if not any(ROOT.glob(str(p.relative_to(ROOT))))]
    assert not missing, f"docs/architecture.md names what is not there: {missing}"


def test_every_sub_package_is_in_the_map():
    named = _named_paths()
    packages = [p.parent for p in PACKAGE.rglob("__init__.py") if "__pycache__" not in p.parts]
    unnamed = [p for p in packages if p not in named and p != PACKAGE]
    assert not unnamed, f"sub-packages missing from docs/architecture.md: {unnamed}"


def test_every_simulator_and_robot_module_is_in_the_map():
    named = _named_paths()
    for folder in (PACKAGE / "sim", PACKAGE / "robot"):
        unnamed = [p for p in _modules(folder) if p not in named and p.name != "__init__.py"]
        assert not unnamed, f"modules missing from docs/architecture.md: {unnamed}"


def _imports(path: Path) -> set[str]:
    found: set[str] = set()
    for node in ast.walk(ast.parse(path.read_bytes())):
        if isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            found.add(node.module)
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return found


@pytest.mark.parametrize("path", _modules(PACKAGE / "sim"), ids=lambda p: p.name)
def test_nothing_in_the_simulator_imports_the_robot_package(path):
    assert not [m for m in _imports(path) if m.startswith("swarmtag.robot")]


@pytest.mark.parametrize("path", _modules(PACKAGE / "robot"), ids=lambda p: p.name)
def test_the_robot_package_never_imports_the_built_in_controller(path):
    assert not [m for m in _imports(path) if m.startswith("swarmtag.sim.builtin")]


def test_the_simulator_shows_its_parts_in_folders():
    top = list((PACKAGE / "sim").glob("*.py"))
    assert len(top) <= 12, sorted(p.name for p in top)
