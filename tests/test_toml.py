"""The one TOML reader: size and nesting bounded before parsing, every failure one error."""

from __future__ import annotations

import time
import tomllib
from pathlib import Path
from typing import Any

import pytest
import tomli_w
from hypothesis import given, settings
from hypothesis import strategies as st

import swarmtag
from swarmtag import _toml
from swarmtag._toml import (
    MAX_TOML_BYTES,
    MAX_TOML_DEPTH,
    loads_toml,
    read_toml,
    toml_value,
    written_depth,
)
from swarmtag.errors import ConfigError, StudyError

N = 400
DEEP = {
    "arrays": "a = " + "[" * N + "]" * N + "\n",
    "inline tables": "a = " + "{b = " * N + "1" + "}" * N + "\n",
    "mixed": "a = " + "[{b = " * (N // 2) + "1" + "}]" * (N // 2) + "\n",
    "table header": "[" + ".".join(["a"] * N) + "]\nx = 1\n",
    "array-of-tables header": "[[" + ".".join(["a"] * N) + "]]\nx = 1\n",
    "dotted key": ".".join(["a"] * N) + " = 1\n",
    "dotted keys in inline tables": "a = " + "{b.c = " * (N // 2) + "1" + "}" * (N // 2) + "\n",
}
"""About a kilobyte each, 400 levels deep: tomllib raised RecursionError on the first three."""


def python_depth(value: object) -> int:
    """Levels of tables and arrays below ``value`` (a scalar: 0)."""
    if isinstance(value, dict):
        return 1 + max((python_depth(item) for item in value.values()), default=0)
    if isinstance(value, list):
        return 1 + max((python_depth(item) for item in value), default=0)
    return 0


@pytest.mark.parametrize("text", DEEP.values(), ids=DEEP.keys())
def test_deep_nesting_is_refused_before_parsing(tmp_path, text):
    path = tmp_path / "deep.toml"
    path.write_text(text)
    with pytest.raises(ConfigError) as refused:
        read_toml(path, what="scenario file", error=ConfigError)
    assert str(refused.value) == (
        f"{path}: nested more than {MAX_TOML_DEPTH} levels deep "
        "(tables, dotted keys, arrays and inline tables together); flatten it"
    )


def test_nesting_up_to_the_limit_is_read():
    text = "a = " + "[" * MAX_TOML_DEPTH + "]" * MAX_TOML_DEPTH
    assert python_depth(loads_toml(text, source="x", error=ConfigError)) == MAX_TOML_DEPTH + 1
    with pytest.raises(ConfigError, match="nested more than"):
        loads_toml("a = [" + text[4:] + "]", source="x", error=ConfigError)


def test_brackets_and_dots_in_strings_and_comments_do_not_count():
    deep = "[" * 100 + "." * 100
    text = (
        f"a = \"{deep}\"\nb = '{deep}'\nc = \"\"\"\n{deep}\n\"\"\"\nd = '''{deep}'''\n"
        f'# {deep}\n"{deep}" = 1\ne = ["\\"{deep}", "x"]  # {deep}\n'
    )
    assert written_depth(text) <= 2
    assert loads_toml(text, source="x", error=ConfigError)["a"] == deep


def test_escapes_and_closing_quotes_of_multiline_strings_are_followed():
    deep = "[" * 40
    text = f'f = """a\\"""{deep}"""\ng = """x""""\nh = \'\'\'{deep}\'\'\'\'\ni = [1]\n'
    data = loads_toml(text, source="x", error=ConfigError)
    assert (data["f"], data["g"], data["h"], data["i"]) == (f'a"""{deep}', 'x"', f"{deep}'", [1])
    assert written_depth(text) == 1


@pytest.mark.parametrize(
    "text",
    [
        'a = "' + '\\"' * 100_000,  # one unclosed string, escaped quotes all along
        '"""' + '\\"' * 100_000,
        "'x'" * 70_000,  # many short strings on one line
        '"' * 200_000,
        "a = [" + "," * 200_000,
    ],
    ids=["escaped quotes", "multi-line escaped quotes", "literals", "quotes", "commas"],
)
def test_the_scan_is_linear_on_hostile_text(text):
    started = time.perf_counter()
    written_depth(text)
    assert time.perf_counter() - started < 2  # a backtracking pattern took 33 s on 40 KB


def test_a_recursion_error_past_the_scan_is_still_one_error(monkeypatch):
    monkeypatch.setattr(_toml, "MAX_TOML_DEPTH", 10**6)  # let the scan pass anything
    with pytest.raises(ConfigError, match=r"^x: nested more than"):
        loads_toml("a = " + "[" * 5000 + "]" * 5000, source="x", error=ConfigError)


def test_an_oversize_file_is_refused_unread(tmp_path):
    path = tmp_path / "big.toml"
    path.write_bytes(b"# " + b"x" * (MAX_TOML_BYTES - 3) + b"\n")
    assert read_toml(path, what="study file", error=StudyError) == {}  # exactly the limit
    path.write_bytes(b"# " + b"x" * (MAX_TOML_BYTES - 2) + b"\n")
    with pytest.raises(StudyError) as refused:
        read_toml(path, what="study file", error=StudyError)
    assert str(refused.value) == f"{path}: larger than 1024 KiB; a study file may be no larger"


def test_a_huge_deep_text_is_refused_at_once():
    started = time.perf_counter()
    with pytest.raises(ConfigError, match="nested more than"):
        loads_toml("a = " + "[" * (MAX_TOML_BYTES - 10), source="x", error=ConfigError)
    assert time.perf_counter() - started < 2  # the scan stops at the limit


@pytest.mark.parametrize(
    ("data", "message"),
    [
        (b"a = \xff\n", "not valid TOML ('utf-8' codec can't decode byte 0xff"),
        (b"a = [1,\n", "not valid TOML (Invalid value (at end of document))"),
        (b"a = 1\na = 2\n", "not valid TOML (Cannot overwrite a value"),
    ],
)
def test_a_file_that_is_not_toml_is_one_error(tmp_path, data, message):
    path = tmp_path / "bad.toml"
    path.write_bytes(data)
    with pytest.raises(ConfigError) as refused:
        read_toml(path, what="scenario file", error=ConfigError)
    assert str(refused.value).startswith(f"{path}: {message}")


def test_set_values_are_toml_or_bare_words_and_deep_ones_are_refused():
    assert toml_value(" [1, {a = 2}] ", source="--set k", error=ConfigError) == [1, {"a": 2}]
    assert toml_value("carriers", source="--set k", error=ConfigError) == "carriers"
    assert toml_value("[oops", source="--set k", error=ConfigError) == "[oops"
    for text in (DEEP["arrays"][4:], DEEP["inline tables"][4:]):
        with pytest.raises(ConfigError, match=r"^--set k: nested more than 32 levels deep"):
            toml_value(text, source="--set k", error=ConfigError)
    with pytest.raises(ConfigError, match=r"^--set k: larger than 1024 KiB"):
        toml_value("1" * MAX_TOML_BYTES, source="--set k", error=ConfigError)


def test_every_shipped_toml_file_is_read_and_shallow():
    files = sorted(Path(swarmtag.__file__).parent.rglob("*.toml"))
    assert len(files) >= 10
    for path in files:
        data = read_toml(path, what="file", error=ConfigError)
        assert data == tomllib.loads(path.read_text(encoding="utf-8"))
        assert written_depth(path.read_text(encoding="utf-8")) <= 8, path


def test_no_module_but_the_reader_imports_tomllib():
    package = Path(swarmtag.__file__).parent
    users = [
        path.relative_to(package).as_posix()
        for path in package.rglob("*.py")
        if "import tomllib" in path.read_text(encoding="utf-8")
    ]
    assert users == ["_toml.py"]


# --- the scan never counts less than the parser nests --------------------------------------

KEYS = st.text(alphabet=st.sampled_from("ab.[]{}\"'#= \\"), min_size=1, max_size=4)
SCALARS = st.one_of(
    st.integers(-(2**63), 2**63 - 1),
    st.floats(allow_nan=False, allow_infinity=False),
    st.text(alphabet=st.sampled_from("ab.[]{},\"'#=\n\\ "), max_size=8),
    st.booleans(),
)
TREES = st.recursive(
    SCALARS,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(KEYS, inner, max_size=3),
    max_leaves=20,
)


@settings(max_examples=300, deadline=None)
@given(document=st.dictionaries(KEYS, TREES, max_size=4), multiline=st.booleans())
def test_the_scanned_depth_is_never_less_than_the_parsed_one(document: dict[str, Any], multiline):
    text = tomli_w.dumps(document, multiline_strings=multiline)
    assert tomllib.loads(text) == document
    assert written_depth(text) >= python_depth(document) - 1
