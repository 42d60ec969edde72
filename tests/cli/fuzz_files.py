"""The files the CLI fuzzer gives commands: what to make in a working folder, and how to damage it.

Used by ``tests/cli/fuzz_values.py`` and ``tests/cli/test_fuzz.py``.
"""

from __future__ import annotations

import os
import re
import shutil
import struct
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hypothesis import strategies as st

# --- files an invocation may need ------------------------------------------------------------


@dataclass(frozen=True)
class Made:
    """A file-system object an invocation needs, made in its working folder before the call.

    ``kind``: ``copy`` (a template), ``secret`` (a template copied with mode
    0600, as key files must be), ``edit`` (a template changed by ``op``),
    ``nest`` (a template, or nothing, with deep TOML added: ``op`` is the
    form and depth of ``nested_toml``), ``bytes`` (``data``), ``dir``, ``fifo``, ``tree`` (a template folder) or
    ``parent`` (only the folder above ``name``).
    """

    name: str
    kind: str
    template: str = ""
    op: tuple[Any, ...] = ()
    data: bytes = b""


Token = str | Made
"""One word of an invocation: literal text, or a path made first."""

TINY_STUDY = """\
ticks = 20
name = "tiny"
conditions = ["proximity", "urgency:alpha=0.7"]
runs = 2
quick_runs = 1
chunk_runs = 2
resamples = 20
profile = "base"

[scenario]
robots = 2
carriers = 3
"""
TINY_TARGETS = """\
[calibration]
name = "tiny"
description = "tiny"
condition = "proximity"
seed = 0
free = ["timing.dock=0.5:8:log"]
evaluations = 2

[[setups]]
name = "t"
runs = 1
scenario = { robots = 2, carriers = 3, ticks = 20 }

[setups.kpis]
deliveries_per_run = { value = 1, ci = [0.5, 1.5] }
pa = { value = 0.5, ci = [0.2, 0.8], weight = 0 }
"""
TINY_SCENARIO = "robots = 2\ncarriers = 3\nticks = 20\n\n[camera]\nmemory = 2.0\n"
TINY_WAREHOUSE = """\
robots = 2
ticks = 20

[warehouse]
map = "small-warehouse"
warmup = 0.5
order_interval = 1.0
initial_orders = 2
"""
"""A scenario file with a warehouse: a short warm-up, so that a 20-tick run is valid."""


NUMBER = re.compile(rb"-?\d+(?:\.\d+)?(?:e[+-]?\d+)?")


def edit(data: bytes, op: tuple[Any, ...]) -> bytes:  # noqa: PLR0911 - one return per edit
    """``data`` changed by ``op`` (see ``corruptions``)."""
    name, *args = op
    if name == "truncate":
        return data[: int(len(data) * args[0])]
    if name == "insert":
        at = int(len(data) * args[0])
        return data[:at] + args[1] + data[at:]
    if name == "flip":
        at = min(len(data) - 1, int(len(data) * args[0]))
        return data[:at] + bytes([args[1]]) + data[at + 1 :]
    if name == "random":
        return args[0]
    if name == "replace":  # the first occurrence of args[0] (or the end, if none)
        at = data.find(args[0])
        return data + args[1] if at < 0 else data[:at] + args[1] + data[at + len(args[0]) :]
    if name == "number":
        matches = list(NUMBER.finditer(data)) or [re.search(rb"$", data)]
        match = matches[args[0] % len(matches)]
        assert match is not None
        return data[: match.start()] + args[1] + data[match.end() :]
    lines = data.split(b"\n")
    at = args[0] % len(lines)
    if name == "rows":
        return b"\n".join(lines[: 1 + args[0]]) + b"\n"
    if name == "drop":
        return b"\n".join(lines[:at] + lines[at + 1 :])
    if name == "repeat":
        return b"\n".join([*lines[: at + 1], lines[at], *lines[at + 1 :]])
    assert name == "line", op
    return b"\n".join([*lines[:at], args[1], *lines[at + 1 :]])


def make(token: Made, work: Path, templates: dict[str, Path]) -> None:
    """Create ``token`` in ``work`` (once: a second token of the same name finds it made)."""
    target = work / token.name
    if token.kind == "parent":
        target.parent.mkdir(parents=True, exist_ok=True)
        return
    if target.exists() or target.is_symlink():
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    if token.kind == "dir":
        target.mkdir()
    elif token.kind == "fifo":
        os.mkfifo(target)
    elif token.kind == "tree":
        shutil.copytree(templates[token.template], target)
    elif token.kind == "copy":
        shutil.copyfile(templates[token.template], target)
    elif token.kind == "secret":
        shutil.copyfile(templates[token.template], target)
        target.chmod(0o600)
    elif token.kind == "edit":
        target.write_bytes(edit(templates[token.template].read_bytes(), token.op))
    elif token.kind == "nest":
        base = templates[token.template].read_text("utf-8") if token.template else ""
        target.write_bytes(nested_toml(*token.op, base=base))
    else:
        target.write_bytes(token.data)


def make_tag_files(folder: Path) -> None:
    """A site key, both role keys (mode 0600) and a software tag's state file (marker 12)."""
    from swarmtag.tag import (
        FileStore,
        Role,
        TagModel,
        TagState,
        TagStatus,
        derive_robot_key,
        derive_role_key,
        write_key_file,
        write_robot_key_file,
        write_role_key_file,
    )

    site = bytes(range(32))
    write_key_file(folder / "site.key", site)
    write_role_key_file(
        folder / "operator.key", Role.OPERATOR, derive_role_key(site, Role.OPERATOR)
    )
    write_robot_key_file(folder / "robot.key", 7, derive_robot_key(site, 7))  # robot 7's own key
    waiting = TagState(urgency=5, status=TagStatus.AWAITING_PICKUP, destination=2, marker=12)
    TagModel.provision(waiting, site_key=site, store=FileStore(folder / "tag.state"))


def make_camera_files(folder: Path) -> None:
    """Camera images of carrier 7 (front, upward, one of another size) and the shipped rig."""
    import cv2
    import numpy as np

    from swarmtag.perception import Placement, load_rig, render, rig_path

    rig = load_rig()
    rng = np.random.default_rng(0)
    front = render(rig.camera("front"), rig.carrier, [Placement.at(7, 1.0, 0.0, 10.0)], rng=rng)
    cv2.imwrite(str(folder / "camera.png"), front)
    cv2.imwrite(str(folder / "small.png"), front[:480, :640])
    under = render(rig.camera("upward"), rig.carrier, [Placement(7, 0.02, 0.0)], rng=rng)
    cv2.imwrite(str(folder / "under.png"), under)
    shutil.copyfile(rig_path("dots-like"), folder / "rig.toml")
    cv2.imwrite(str(folder / "one.png"), front[:1, :1])  # a 1 x 1 image
    data = (folder / "camera.png").read_bytes()
    (folder / "cut.png").write_bytes(data[: len(data) * 3 // 5])  # a truncated PNG


def png_claiming(width: int, height: int) -> bytes:
    """A small PNG whose header claims ``width`` x ``height`` pixels (a decompression bomb).

    >>> len(png_claiming(100_000, 100_000)) < 100
    True
    """

    def chunk(kind: bytes, body: bytes) -> bytes:
        crc = zlib.crc32(kind + body)
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", crc)

    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)  # 8-bit grey
    pixels = zlib.compress(b"\0" * 64)
    return (
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", pixels) + chunk(b"IEND", b"")
    )


def make_cache_file(folder: Path) -> None:
    """A valid calibration cache (two lines) for the fuzzer to damage."""
    from swarmtag.calibration import EvaluationCache
    from swarmtag.calibration.cache import CacheEntry

    cache = EvaluationCache(folder / "cache.jsonl")
    for number, dock in enumerate((0.5, 4.0)):
        achieved = {"t": {"deliveries_per_run": 1.0 + number, "pa": None}}
        cache.put(f"k{number}", CacheEntry({"timing.dock": dock}, achieved), objective=1.0)


# --- damaged and missing inputs -----------------------------------------------------------

DEPTHS = (20, 40, 400, 3000)
"""How deep the nested TOML goes: below, at and far above every surface's limit."""


def nested_value(form: str, depth: int) -> str:
    """A TOML value nested ``depth`` deep: arrays, inline tables, or both in turn."""
    if form == "array":
        return "[" * depth + "1" + "]" * depth
    if form == "inline":
        return "{a = " * depth + "1" + "}" * depth
    return "[{a = " * (depth // 2) + "1" + "}]" * (depth // 2)


def nested_toml(form: str, depth: int, base: str = "") -> bytes:
    """A TOML document with something ``depth`` deep, after ``base`` (a file it extends).

    ``tables``: ``[a.a.a...]`` headers; ``arrays``: ``[[a.a...]]`` arrays of
    tables; ``array``, ``inline``, ``mixed``: one key's value (``nested_value``).
    """
    if form == "tables":
        extra = "[" + ".".join(["a"] * depth) + "]\nx = 1\n"
    elif form == "arrays":
        extra = "[[" + ".".join(["a"] * depth) + "]]\nx = 1\n"
    else:
        extra = f"deep = {nested_value(form, depth)}\n"
    return (
        (extra + base).encode()
        if form in ("array", "inline", "mixed")
        else (base + "\n" + extra).encode()
    )


NESTED_FORMS = ("tables", "arrays", "array", "inline", "mixed")


def nested(template: str, suffix: str = ".toml") -> st.SearchStrategy[Token]:
    """``template`` (a template name, or "" for nothing) with deep TOML added to it."""

    def build(form: str, depth: int) -> Token:
        return Made(f"deep-{form}-{depth}{suffix}", "nest", template=template, op=(form, depth))

    return st.builds(build, st.sampled_from(NESTED_FORMS), st.sampled_from(DEPTHS))


HUGE = (
    b"1e308", b"1e309", b"-1e309", b"nan", b"inf", b"-inf", b"-0.0", b"1" + b"0" * 30,
    b"9" * 400, b"1e-400", b"0x10", b"", b"\xff", b"-1", b"true", b'"x"', b"[]",
)  # fmt: skip
"""Replacements for one number of an input file."""
LINES = (b"", b",,,,,,,,,,,", b"\xc3\xa9", b"\0\0", b"x = ", b"[", b"proximity,0", b"\r")
"""Replacements for one line of an input file."""


def corruptions(*, text: bool = True, lines: bool = True) -> st.SearchStrategy[tuple[Any, ...]]:
    """Ways to break a file: truncate, insert NUL, flip a byte, random bytes; for text also
    a huge number for one number, and (``lines``) only the first rows, a line dropped,
    repeated or replaced. Study and target files get no line edits: without its ``ticks``
    line a study or set-up would simulate the default 3,000 ticks.
    """
    fraction = st.floats(0.0, 1.0)
    ops = [
        st.tuples(st.just("truncate"), fraction),
        st.tuples(st.just("insert"), fraction, st.sampled_from([b"\0", b"\xff\xfe", b"\n"])),
        st.tuples(st.just("flip"), fraction, st.integers(0, 255)),
        st.tuples(st.just("random"), st.binary(max_size=200)),
    ]
    index = st.integers(0, 400)
    if text:
        ops.append(st.tuples(st.just("number"), index, st.sampled_from(HUGE)))
    if text and lines:
        ops += [
            st.tuples(st.just("rows"), st.integers(0, 6)),
            st.tuples(st.just("drop"), index),
            st.tuples(st.just("repeat"), index),
            st.tuples(st.just("line"), index, st.sampled_from(LINES)),
        ]
    return st.one_of(*ops)


def edited(
    template: str, suffix: str, *, text: bool = True, lines: bool = True
) -> st.SearchStrategy[Token]:
    return st.builds(
        lambda n, op: Made(f"bad{n}{suffix}", "edit", template=template, op=op),
        st.integers(0, 3),
        corruptions(text=text, lines=lines),
    )


def copy(template: str) -> st.SearchStrategy[Token]:
    return st.just(Made(template, "copy", template=template))


def not_a_file(suffix: str) -> st.SearchStrategy[Token]:
    """Inputs that are no file: missing, a folder, a FIFO, a name too long for a path."""
    return st.one_of(
        st.sampled_from([f"missing{suffix}", f"missing/x{suffix}", "", "x" * 300]),
        st.just(Made(f"folder{suffix}", "dir")),
        st.just(Made(f"fifo{suffix}", "fifo")),
        st.just(Made("exists.txt", "bytes", data=b"old\n")),
    )
