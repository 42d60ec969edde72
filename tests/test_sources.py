"""``swarmtag._sources`` finds a module's project imports wherever statements can hold them."""

from __future__ import annotations

import ast
import hashlib
import json
import textwrap

import pytest

from swarmtag._sources import PACKAGE_ROOT, _import_statements, _imports

NESTED = textwrap.dedent(
    """
    import swarmtag.errors
    '''from swarmtag._toml import nothing: a docstring, not an import'''


    class Outer:
        from swarmtag import _checks

        def method(self):
            with open(self) as handle:
                for _ in handle:
                    while True:
                        import swarmtag._atomic
            async def inner():
                async with self:
                    async for _ in self:
                        import swarmtag._inputs


    try:
        import swarmtag._outputs
    except ImportError:
        import swarmtag._interrupt
    else:
        import swarmtag._resources
    finally:
        import swarmtag._pools

    match swarmtag:
        case 1:
            import swarmtag._sources
        case _:
            if True:
                pass
            elif False:
                pass
            else:
                import swarmtag.data
    """
)


def _walked(tree: ast.AST) -> list[str]:
    return sorted(
        ast.dump(node) for node in ast.walk(tree) if isinstance(node, ast.Import | ast.ImportFrom)
    )


def test_imports_in_every_kind_of_body_are_found_and_strings_are_not(tmp_path):
    tree = ast.parse(NESTED)
    assert sorted(ast.dump(node) for node in _import_statements(tree)) == _walked(tree)
    module = tmp_path / "nested.py"
    module.write_text(NESTED, encoding="utf-8")
    names = {path.relative_to(PACKAGE_ROOT).as_posix() for path in _imports(module)}
    assert names == {
        "errors.py",
        "__init__.py",
        "_checks.py",
        "_atomic.py",
        "_inputs.py",
        "_outputs.py",
        "_interrupt.py",
        "_resources.py",
        "_pools.py",
        "_sources.py",
        "data/__init__.py",
    }


@pytest.mark.parametrize("package", ["sim", "analysis", "cli", "experiments"])
def test_the_statement_walk_finds_what_a_full_walk_finds_in_the_project(package):
    for path in sorted((PACKAGE_ROOT / package).rglob("*.py")):
        tree = ast.parse(path.read_bytes())
        assert sorted(ast.dump(node) for node in _import_statements(tree)) == _walked(tree), path


def test_names_come_from_the_cache_until_a_file_changes(tmp_path, monkeypatch):
    from swarmtag import _sources

    cache = tmp_path / "cache" / "imports.json"
    monkeypatch.setattr(_sources, "CACHE_FILE", cache)
    roots = [PACKAGE_ROOT / "sim" / "simulation.py"]
    fresh = _sources.imported_sources(roots, transitive=True)
    assert cache.is_file()

    def no_parsing(*args, **kwargs):
        raise AssertionError("parsed again")

    monkeypatch.setattr(ast, "parse", no_parsing)
    assert _sources.imported_sources(roots, transitive=True) == fresh
    monkeypatch.undo()
    monkeypatch.setattr(_sources, "CACHE_FILE", cache)
    # an edited file is read again: its new import counts, and the cache learns it
    module = tmp_path / "module.py"
    module.write_text("import swarmtag.errors\n", encoding="utf-8")
    assert set(_sources.imported_sources([module], transitive=False)) == {
        PACKAGE_ROOT / "errors.py",
        module,
    }
    module.write_text("import swarmtag.errors\nimport swarmtag._toml\n", encoding="utf-8")
    assert PACKAGE_ROOT / "_toml.py" in _sources.imported_sources([module], transitive=False)


@pytest.mark.parametrize("content", [b"{not json", b"[1, 2]", b'{"a": 3, "b": [4]}'])
def test_a_cache_that_cannot_be_read_or_written_changes_no_answer(tmp_path, monkeypatch, content):
    from swarmtag import _sources

    roots = list((PACKAGE_ROOT / "sim" / "fast").glob("*.py"))
    monkeypatch.setattr(_sources, "CACHE_FILE", tmp_path / "none.json")
    expected = _sources.imported_sources(roots, transitive=False)
    broken = tmp_path / "broken.json"
    broken.write_bytes(content)
    monkeypatch.setattr(_sources, "CACHE_FILE", broken)
    assert _sources.imported_sources(roots, transitive=False) == expected
    blocked = tmp_path / "file" / "imports.json"  # its folder is a file: nothing is written
    (tmp_path / "file").write_bytes(b"")
    monkeypatch.setattr(_sources, "CACHE_FILE", blocked)
    assert _sources.imported_sources(roots, transitive=False) == expected
    assert sorted(p.name for p in tmp_path.iterdir()) == ["broken.json", "file", "none.json"]


def test_the_cache_keeps_the_files_last_used(tmp_path, monkeypatch):
    from swarmtag import _sources

    cache = tmp_path / "imports.json"
    monkeypatch.setattr(_sources, "CACHE_FILE", cache)
    monkeypatch.setattr(_sources, "CACHE_ENTRIES", 3)
    modules = []
    for index in range(5):
        module = tmp_path / f"m{index}.py"
        module.write_text(f"import swarmtag.errors  # {index}\n", encoding="utf-8")
        modules.append(module)
        _sources.imported_sources([module], transitive=False)
    kept = json.loads(cache.read_text(encoding="utf-8"))
    assert len(kept) == 3
    assert set(kept) == {hashlib.sha256(m.read_bytes()).hexdigest() for m in modules[2:]}
