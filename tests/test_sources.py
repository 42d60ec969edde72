"""``swarmtag._sources`` finds a module's project imports wherever statements can hold them."""

from __future__ import annotations

import ast
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
