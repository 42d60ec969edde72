"""The values the CLI fuzzer draws: files to make, option values good and bad, and outputs.

Used by ``tests/cli/test_fuzz.py`` (see its docstring); kept apart so that each file
holds one concept: what may be passed (here) and how invocations are run and judged.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from dataclasses import dataclass

import click
from hypothesis import strategies as st

from swarmtag.calibration.fit import MAX_EVALUATIONS
from swarmtag.data import example_trial_path
from swarmtag.sim import Scenario
from swarmtag.sim.config.mapping import flat_keys
from tests.cli.fuzz_files import (
    TINY_STUDY,
    TINY_TARGETS,
    Made,
    Token,
    copy,
    edited,
    nested,
    nested_value,
    not_a_file,
    png_claiming,
)

# --- values: a valid branch and a bad one for every option ------------------------------------


@dataclass(frozen=True)
class Values:
    """What one option or argument takes: ``good`` values and ``bad`` ones.

    ``rare``: a good value means slow work (pictures, HTML), so it is drawn a
    quarter as often.
    """

    good: st.SearchStrategy[Token]
    bad: st.SearchStrategy[Token]
    rare: bool = False


BOUNDARY = (
    "0", "-1", "1", str(10**30), str(-(10**30)), str(2**53), str(2**53 + 1), str(2**63),
    "1e308", "-1e308", "1e309", "-0.0", "0.0", "nan", "-nan", "inf", "-inf", "1e-320",
    "", " ", "\0", "1\0", "a\nb", "\n", "\u00fc", "\u2028", "\U0001f916", "1.5", "0x10",
    "1_000", " 7 ", "true", "--", "-", "=", "x" * 300,
)  # fmt: skip
"""Values at the edges of every type, as command-line text."""

words = st.text(st.characters(exclude_categories=["Cs"]), max_size=12)
junk = st.one_of(st.sampled_from(BOUNDARY), words)


def texts(good: Sequence[str], bad: Sequence[str] = ()) -> Values:
    """Strings: ``good`` ones; ``bad`` ones, boundaries and random words."""
    return Values(st.sampled_from(good), st.one_of(st.sampled_from([*bad, ""]), junk))


def integers(
    low: int | None, high: int | None, good: tuple[int, int], *, top: bool = True
) -> Values:
    """Small valid integers (``good``); the range's edges, boundaries and words.

    ``top=False`` leaves out the largest valid value (when it means a lot of work).
    """
    edges = {str(n) for n in (low, high if top else None) if n is not None}
    edges |= {str(low - 1)} if low is not None else set()
    edges |= {str(high + 1)} if high is not None else set()
    bad = st.one_of(st.sampled_from(sorted(edges) or ["-1"]), junk)
    return Values(st.integers(*good).map(str), bad)


def floats(low: float, high: float) -> Values:
    return Values(st.floats(low, high).map(repr), junk)


def from_type(param: click.Parameter) -> Values:
    """Values of a parameter nobody special-cased, from its click type alone."""
    kind = param.type
    if isinstance(kind, click.Choice):
        choices = [str(c) for c in kind.choices]
        return Values(
            st.sampled_from(choices), st.one_of(st.sampled_from(choices).map(str.upper), junk)
        )
    if isinstance(kind, click.IntRange):
        low, high = kind.min, kind.max
        start = 0 if low is None else int(low)
        return integers(low, high, (start, start + 3 if high is None else min(high, start + 3)))
    if isinstance(kind, click.FloatRange):
        return floats(float(kind.min or 0.0) + 0.05, float(kind.min or 0.0) + 5.0)
    if kind is click.INT:
        return integers(None, None, (0, 3))
    if kind is click.FLOAT:
        return floats(0.05, 5.0)
    if kind is click.STRING:
        return Values(words, junk)
    msg = f"{param.name}: no values for click type {kind!r}; teach the fuzzer this option"
    raise AssertionError(msg)


# Paths ------------------------------------------------------------------------------------------------

STEMS = ("out", "same", "\u00fcber", "new")
"""Stems of new output names: shared by every option, so two options often name one file."""


def file_output(*suffixes: str, rare: bool = False) -> Values:
    """A file an option writes: new and existing files; every way a path can be wrong."""
    right = st.sampled_from(suffixes)
    wrong = st.sampled_from(
        [s for s in (".txt", "", ".csv", ".toml", ".md", ".tmp") if s not in suffixes]
    )
    good = st.one_of(
        st.builds(str.__add__, st.sampled_from(STEMS), right),
        right.map(lambda s: Made(f"exists{s}", "bytes", data=b"old,contents\n")),
        right.map(lambda s: Made(f"sub/out{s}", "parent")),
        right.map(lambda s: f"upper{s.upper()}"),
        right.map(lambda s: f"a\nb{s}"),
    )
    bad = st.one_of(
        st.builds(str.__add__, st.sampled_from(STEMS), wrong),
        right.map(lambda s: f"missing/out{s}"),
        right.map(lambda s: Made(f"folder{s}", "dir")),
        st.just(Made("dir", "dir")),
        right.map(lambda s: Made(f"fifo{s}", "fifo")),
        right.map(lambda s: f"/proc/x{s}"),
        right.map(lambda s: "x" * 300 + s),
        st.sampled_from(["", ".", "/", "-", ".." + suffixes[0]]),
    )
    return Values(good, bad, rare=rare)


def folder_output() -> Values:
    """A folder an option writes into (made if missing; its parent must exist)."""
    new = st.one_of(
        st.sampled_from(["figs", "out", "same", "new", ".", "a\nb"]),
        st.just(Made("dir", "dir")),
        st.just(Made("results", "tree", template="results")),
    )
    bad = st.one_of(
        st.just(Made("exists.txt", "bytes", data=b"old\n")),
        st.just(Made("fifo", "fifo")),
        st.sampled_from(["missing/figs", "/proc/x", "", "x" * 300]),
    )
    return Values(new, bad)


def with_inputs(chosen: Values) -> Values:
    """``chosen`` with, among the bad values, the files other options read."""
    inputs = st.one_of(copy("targets.toml"), copy("profile.toml"), copy("trial.csv"))
    return Values(chosen.good, st.one_of(chosen.bad, inputs), rare=chosen.rare)


EVENT_LOG = Values(
    st.one_of(
        st.just(str(example_trial_path())),
        copy("trial.csv"),
        copy("small.csv"),
        copy("small.parquet"),
    ),
    st.one_of(
        edited("trial.csv", ".csv"),
        edited("small.csv", ".csv"),
        edited("small.parquet", ".parquet", text=False),
        copy("small-table.csv"),
        not_a_file(".csv"),
        st.sampled_from(["events.txt", "/proc/x.csv", "-"]),
    ),
)
"""A per-carrier event log to read: valid logs; corrupted copies, and no file at all."""
EVENT_TABLE = Values(
    st.one_of(copy("small-table.csv"), copy("small-table.parquet")),
    st.one_of(
        edited("small-table.csv", ".csv"),
        edited("small-table.parquet", ".parquet", text=False),
        copy("small.csv"),
        copy("trial.csv"),
        not_a_file(".csv"),
    ),
)
"""A long-format event table to read."""
BAG = Values(
    st.one_of(copy("trial.mcap"), copy("trial.db3"), st.just(Made("bag", "tree", template="bag"))),
    st.one_of(
        edited("trial.mcap", ".mcap", text=False),
        edited("trial.db3", ".db3", text=False),
        copy("trial.csv"),
        copy("mapping.toml"),
        not_a_file(".mcap"),
        st.sampled_from(["/proc/x.mcap", "-", "bag.bag"]),
    ),
)
"""A ROS 2 bag to read: bare MCAP and .db3 files, a rosbag2 folder; corrupted and no bags."""

TOML_VALUES = (
    "0", "-1", "1", "1.5", "1e308", "nan", "inf", "-0.0", str(10**30), str(2**63), str(2**53),
    '""', '"x"', '"\\u0000"', "[]", "{}", "true", '["proximity", "proximity"]',
    '["urgency:alpa=3"]', '"static"', '"paper-sim"', '"lab"', "1979-05-27", '"x\\ny"',
)  # fmt: skip
"""Wrong and boundary values for one key of a TOML input."""


def toml_edit(template: str, keys: Sequence[str]) -> st.SearchStrategy[Token]:
    """A TOML template with one line replaced by ``key = value`` (wrong, boundary, unknown)."""
    return st.builds(
        lambda n, at, key, value: Made(
            f"mut{n}.toml", "edit", template=template, op=("line", at, f"{key} = {value}".encode())
        ),
        st.integers(0, 3),
        st.integers(0, 30),
        st.sampled_from([*keys, "nope", "runs.x"]),
        st.sampled_from(TOML_VALUES),
    )


MAPPING_KEYS = (
    "format", "topic", "stamp", "entries", "event", "start", "end", "condition", "run", "seed",
    "time_unit", "tick", "markers", "urgency0", "order_time", "marker", "status", "urgency",
    "robot", "idle", "awaiting_pickup", "picked_up", "kind", "carrier", "value",
)  # fmt: skip
BAG_MAPPING = Values(
    copy("mapping.toml"),
    st.one_of(
        edited("mapping.toml", ".toml"),
        toml_edit("mapping.toml", MAPPING_KEYS),
        nested("mapping.toml"),
        not_a_file(".toml"),
    ),
)
"""A bag mapping to read: the default; damaged copies and other TOML files."""


STUDY_KEYS = (
    "name", "conditions", "runs", "quick_runs", "chunk_runs", "resamples", "profile",
    "robots", "carriers", "seed", "baseline", "urgency", "description", "scales",
)  # fmt: skip


def study_with(n: int, key: str, value: str) -> Made:
    """The tiny study with ``key = value`` (replaced where it is set, else added at the top)."""
    text, found = re.subn(rf"(?m)^{key} = .*$", lambda _: f"{key} = {value}", TINY_STUDY)
    if not found:
        text = f"{key} = {value}\n{text}"
    return Made(f"mut{n}.toml", "bytes", data=text.encode())


SHIPPED_STUDIES = (
    "preliminary-sweep", "candidate-alphas", "controller-selection", "physical-style",
    "scalability", "warehouse",
)  # fmt: skip
"""Shipped study names: real work, so an invocation naming one runs guarded."""
STUDY_SOURCE = Values(
    copy("study.toml"),
    st.one_of(
        edited("study.toml", ".toml", lines=False),
        st.builds(
            study_with,
            st.integers(0, 3),
            st.sampled_from(STUDY_KEYS),
            st.sampled_from(TOML_VALUES),
        ),
        st.sampled_from([*SHIPPED_STUDIES, "Scalability", "no-such-study", "tiny"]),
        nested("study.toml"),
        not_a_file(".toml"),
    ),
)
"""A study file or a shipped study's name."""

TARGET_EDITS = (
    "runs = 1", "evaluations = 2", '"timing.dock=0.5:8:log"', "value = 1", "ci = [0.5, 1.5]",
    'condition = "proximity"', "seed = 0", "robots = 2", "deliveries_per_run", "[[setups]]",
    'name = "t"', "weight = 0",
)  # fmt: skip
BASELINE = Values(
    copy("targets.toml"),
    st.one_of(
        edited("targets.toml", ".toml", lines=False),
        st.builds(
            lambda n, old, value: Made(
                f"tmut{n}.toml", "bytes", data=TINY_TARGETS.replace(old, value, 1).encode()
            ),
            st.integers(0, 3),
            st.sampled_from(TARGET_EDITS),
            st.sampled_from(TOML_VALUES),
        ),
        st.sampled_from(["lab", "paper-sim", "Lab", "nope"]),
        nested("targets.toml"),
        EVENT_LOG.bad,
        not_a_file(".toml"),
    ),
)
"""What ``calibrate --baseline`` reads; only the tiny target files run unguarded."""
UNGUARDED_BASELINES = ("targets.toml",)
"""Templates of the only calibration baselines that run unguarded (tiny and fast)."""

PROFILE = Values(
    st.one_of(st.sampled_from(["paper-sim", "lab", "base", "base"]), copy("profile.toml")),
    st.one_of(
        st.sampled_from(["BASE", "nope", "nope.toml"]),
        edited("profile.toml", ".toml"),
        toml_edit("profile.toml", ["tick", "perception", "detection_radius", "time_unit"]),
        nested("profile.toml"),
        not_a_file(".toml"),
    ),
)
WAREHOUSE_KEYS = (
    "warehouse.map", "warehouse.cell", "warehouse.order_interval", "warehouse.initial_orders",
    "warehouse.urgency_window", "warehouse.warmup", "warehouse", "warehouse.nope",
    "map", "cell", "order_interval", "initial_orders", "urgency_window", "warmup", "[warehouse]",
)  # fmt: skip
"""Keys of a scenario's ``[warehouse]`` table, dotted and bare (for a line inside the table)."""
CONFIG = Values(
    st.one_of(copy("scenario.toml"), copy("scenario.toml"), copy("warehouse.toml")),
    st.one_of(
        edited("scenario.toml", ".toml"),
        toml_edit("scenario.toml", ["robots", "carriers", "ticks", "tick", "arena", "camera"]),
        toml_edit("warehouse.toml", WAREHOUSE_KEYS),
        nested("scenario.toml"),
        not_a_file(".toml"),
    ),
)

SCENARIO = flat_keys(Scenario().to_mapping())
CHEAP = {
    "ticks": st.integers(1, 30),
    "robots": st.integers(1, 4),
    "urgency.static_time_limit": st.integers(1, 30),
}
"""Scenario keys whose own (default) value would make a simulation slow: small values instead."""


def toml_literal(value: object) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    return str(value)


def set_items() -> Values:
    """``KEY=VALUE`` with real scenario keys: their own values; boundaries and garbage."""
    keys = [*SCENARIO, "arena", "camera..memory", "camera.memory.x", "nope", "", " ticks"]
    own = st.sampled_from(sorted(k for k in SCENARIO if k not in CHEAP)).map(
        lambda k: f"{k}={toml_literal(SCENARIO[k])}"
    )
    cheap = st.sampled_from(sorted(CHEAP)).flatmap(lambda k: CHEAP[k].map(lambda v: f"{k}={v}"))
    garbage = st.builds(
        "{}={}".format,
        st.sampled_from([*keys, *WAREHOUSE_KEYS[:8]]),
        st.one_of(st.sampled_from(TOML_VALUES), junk),
    )
    deep = st.builds(
        "{}={}".format,
        st.sampled_from(["robots", "camera.memory", "warehouse.map", "nope"]),
        st.builds(
            nested_value,
            st.sampled_from(["array", "inline", "mixed"]),
            st.sampled_from([40, 400, 3000]),
        ),
    )
    malformed = st.sampled_from(["", "=", "=5", "ticks", "ticks==5", "[x]=1", "a=b=c"])
    malformed |= st.sampled_from([".".join(["warehouse"] * 400) + "=1", "warehouse..map=x"])
    return Values(
        st.one_of(own, cheap, own, warehouse_items()), st.one_of(garbage, deep, malformed)
    )


def warehouse_items() -> st.SearchStrategy[str]:
    """``--set warehouse.KEY=VALUE`` that a warehouse run takes (a short warm-up, small maps)."""
    return st.sampled_from([
        "warehouse.map=small-warehouse", 'warehouse.map="small-warehouse"', "warehouse.warmup=0",
        "warehouse.warmup=0.5", "warehouse.order_interval=1", "warehouse.initial_orders=2",
        "warehouse.cell=0.75", "warehouse.urgency_window=600",
    ])  # fmt: skip


CONDITIONS = texts(
    ["proximity", "urgency:alpha=0.7", "urgency:alpha=9", "weighted:w=0.5"],
    ["Proximity", "urgency", "urgency:alpha=-1", "urgency:alpha=nan", "urgency:alpha=1e309",
     "weighted:w=2", "urgency:alpa=3", "urgency:alpha=0.7,w=1", "x:y=z"],
)  # fmt: skip
FREE = texts(
    ["timing.dock=0.5:8:log", "timing.dock=0.5:8", "motion.speed=0.1:0.5", "tick=0.05:0.2"],
    ["timing.dock=8:0.5", "timing.dock=0:8:log", "timing.dock=1:1e309", "timing.dock=a:b",
     "timing.dock", "timing.dock=1:2:ln", "nope=1:2", "robots=1:5", "ticks=1:10",
     "perception=1:2", "timing.dock=-1e308:1e308", "timing.dock=nan:1"],
)  # fmt: skip
HEX = texts(
    ["ffff0701030c", "0xffff0701030c", "ff:ff:07:01:03:0c", "FF-FF-07-01-03-0C",
     "ff ff 07 01 03 0c"],
    ["ffff0a01030c", "ffff0703030c", "feff0701030c", "ffff070103", "ffff0701030c00",
     "ffff0701030", "zz", "0x"],
)  # fmt: skip

SCAN_TIMEOUT = Values(
    st.floats(0.0, 0.3).map(repr),
    st.one_of(st.sampled_from(["-1", "-0.01", "nan", "inf", "1e9", "86401"]), junk),
)
"""``tag scan --timeout``: short scans only (the sim radio), else refused values."""
SCAN_BACKEND = Values(
    st.just("sim"),
    st.one_of(st.sampled_from(["BLEAK", "Sim", "fake", "nope"]), junk).filter(
        lambda word: word != "bleak"  # the real radio: never opened by the fuzzer
    ),
)
"""``tag scan --backend`` (hidden): the simulated radio, or refused names."""
ADAPTER = texts(["hci0", "hci1"], ["eth0", "hci", "HCI0", "hci0 ", "hci1234"])
"""``--adapter`` of tag scan and tag write: BlueZ adapter names (the sim and loopback ignore it)."""


def secret(template: str) -> st.SearchStrategy[Token]:
    """A key file template copied with mode 0600, as key files must be."""
    return st.just(Made(template, "secret", template=template))


SITE_KEY = Values(
    secret("site.key"),
    st.one_of(
        secret("robot.key"), copy("site.key"), edited("site.key", ".key"), not_a_file(".key")
    ),
)
"""A site key file to read: the private template; a role key, a shared copy, damage, no file."""
ROLE_KEY = Values(
    st.one_of(secret("robot.key"), secret("operator.key")),
    st.one_of(
        secret("site.key"), copy("robot.key"), edited("operator.key", ".key"), not_a_file(".key")
    ),
)
"""``tag write --key-file``: role key files; the site key, a shared copy, damage, no file."""
TAG_STATE = Values(
    copy("tag.state"),
    st.one_of(edited("tag.state", ".state", text=False), copy("site.key"), not_a_file(".state")),
)
"""``tag write --loopback-state`` (hidden): the software tag's FileStore record (marker 12)."""
WRITE_OPTIONS: dict[str, Values] = {
    "address": texts(
        ["AA:BB:CC:DD:EE:01", "aa:bb:cc:dd:ee:01", "12345678-1234-1234-1234-123456789abc"],
        ["AA:BB:CC:DD:EE", "AA-BB-CC-DD-EE-01", "AA:BB:CC:DD:EE:0G", "hci0", "12"],
    ),
    "key_file": ROLE_KEY,
    "writer": integers(0, 0xFFFF, (0, 3)),
    "marker": Values(st.just("12"), integers(0, 255, (0, 11)).good),  # the software tag is 12
    "counter_file": Values(
        file_output(".counters").good,
        st.one_of(file_output(".counters").bad, secret("robot.key"), copy("tag.state")),
    ),
    "timeout": Values(
        st.floats(0.1, 5.0).map(repr),
        st.one_of(st.sampled_from(["0", "0.05", "-1", "nan", "inf", "601"]), junk),
    ),
    "adapter": ADAPTER,
    "backend": Values(
        st.just("loopback"),
        st.one_of(st.sampled_from(["LOOPBACK", "sim", "nope"]), junk).filter(
            lambda word: word != "bleak"  # the real radio: never opened by the fuzzer
        ),
    ),
    "loopback_state": TAG_STATE,
    "loopback_key": SITE_KEY,
}
"""``tag write``: a software tag through the hidden loopback backend, never a radio."""


def _bench_writes() -> bytes:
    """A replay file for ``tag emulate``: writes to tag 12 under the template site key."""
    from swarmtag.tag import Change, Role, TagStatus, WriteSigner, derive_robot_key, derive_role_key

    site = bytes(range(32))  # the key of the site.key template (fuzz_files.make_tag_files)
    operator = WriteSigner(1, Role.OPERATOR, derive_role_key(site, Role.OPERATOR))
    robot = WriteSigner(7, Role.ROBOT, derive_robot_key(site, 7))
    lift = robot.sign(12, Change(status=TagStatus.PICKED_UP))
    writes = [
        operator.sign(12, Change(urgency=9, status=TagStatus.AWAITING_PICKUP)),
        lift,
        lift,  # replayed
        robot.sign(12, Change(urgency=1)),  # wrong role
        robot.sign(3, Change(status=TagStatus.IDLE)),  # another tag
        bytes(20),  # forged
        b"\x01\x02",  # malformed
    ]
    return ("# bench writes\n" + "\n".join(w.hex() for w in writes) + "\n").encode()


BENCH_WRITES = Made("writes.txt", "bytes", data=_bench_writes())
"""``tag emulate --replay``: what the fuzzer serves instead of the radio when none is drawn."""
EMULATE_OPTIONS: dict[str, Values] = {
    "key_file": SITE_KEY,
    "marker": Values(st.just("12"), integers(0, 255, (0, 11)).good),
    "state_file": Values(
        st.one_of(file_output(".bin").good, copy("tag.state")),
        st.one_of(file_output(".bin").bad, edited("tag.state", ".state", text=False)),
    ),
    "eink": file_output(".png"),
    "timeout": SCAN_TIMEOUT,
    "adapter": ADAPTER,
    "replay": Values(
        st.just(BENCH_WRITES),
        st.one_of(
            st.just(Made("bad.txt", "bytes", data=b"0102\nzz\n")),
            st.just(Made("big.txt", "bytes", data=b"00" * (1 << 20))),
            not_a_file(".txt"),
        ),
    ),
}
"""``tag emulate``: the software tag on replayed writes (hidden --replay), never a radio."""

FIELDS_OF_VIEW = ("1", "1.5", "2", "3", "5", "0.1", "179.9")
"""Horizontal fields of view (degrees) of valid but narrow (or all but flat) cameras."""


def narrow_cameras() -> st.SearchStrategy[Token]:
    """The shipped rig with a 1-5 degree field of view (and the extremes around it)."""
    return st.sampled_from(FIELDS_OF_VIEW).map(
        lambda fov: Made(
            f"fov-{fov}.toml",
            "edit",
            template="rig.toml",
            op=("replace", b"horizontal_fov = 102.0", f"horizontal_fov = {fov}".encode()),
        )
    )


CACHE_NUMBERS = (
    b"NaN", b"Infinity", b"-Infinity", b"null", b"9" * 400, b"-1e308", b"1e309", b'"1.0"',
    b"[" * 400 + b"1" + b"]" * 400, b'{"a": ' * 300 + b"1" + b"}" * 300, b"true", b"1e-400",
)  # fmt: skip
"""Replacements for one value of a calibration cache line."""
CACHE_RENAMES = (
    (b'"achieved"', b'"achieveD"'), (b'"values"', b'"value"'), (b'"check"', b'"chek"'),
    (b'"timing.dock"', b'"timing.undock"'), (b'"pa"', b'"PA"'), (b'"key"', b'"key", "key"'),
    (b"{", b"["), (b"\n", b"\n\n{}\n"),
)  # fmt: skip
"""Key renames and shape changes of a cache line."""


CACHE_SPOTS = (b"1.0", b"0.5", b"2.0", b"4.0", b"null", b'"k0"')
"""Values of the template cache's lines (KPIs, free values, a key) that draws replace."""


def damaged_caches() -> st.SearchStrategy[Token]:
    """The template cache with a value replaced, a key renamed, or bytes damaged."""
    number = st.builds(
        lambda n, spot, value: Made(
            f"cache{n}.jsonl", "edit", template="cache.jsonl", op=("replace", spot, value)
        ),
        st.integers(0, 3),
        st.sampled_from(CACHE_SPOTS),
        st.sampled_from(CACHE_NUMBERS),
    )
    renamed = st.builds(
        lambda n, pair: Made(
            f"cache{n}.jsonl", "edit", template="cache.jsonl", op=("replace", *pair)
        ),
        st.integers(0, 3),
        st.sampled_from(CACHE_RENAMES),
    )
    return st.one_of(number, renamed, edited("cache.jsonl", ".jsonl", text=False))


IMAGE = Values(
    st.one_of(copy("camera.png"), copy("under.png")),
    st.one_of(
        edited("camera.png", ".png", text=False),
        copy("one.png"),  # 1 x 1
        copy("cut.png"),  # truncated
        st.sampled_from([(100_000, 100_000), (1, 100_000), (65_535, 65_535)]).map(
            lambda size: Made(f"claims-{size[0]}x{size[1]}.png", "bytes", data=png_claiming(*size))
        ),  # a few bytes whose header claims a huge image
        copy("trial.csv"),
        copy("rig.toml"),
        not_a_file(".png"),
        st.sampled_from(["/proc/x.png", "-"]),
    ),
)
"""``aruco detect IMAGE``: camera images of carrier 7; damaged ones, another size, no image."""
RIG_KEYS = (
    "name", "width", "height", "fx", "cx", "horizontal_fov", "distortion", "position", "yaw",
    "pitch", "kind", "side", "marker_size", "marker_height", "underside_height",
)  # fmt: skip
CAMERA_FILE = Values(
    st.one_of(st.just("dots-like"), copy("rig.toml")),
    st.one_of(
        edited("rig.toml", ".toml"),
        toml_edit("rig.toml", RIG_KEYS),
        nested("rig.toml"),
        narrow_cameras(),
        not_a_file(".toml"),
        st.sampled_from(["Dots-like", "nope", "nope.toml"]),
        junk,
    ),
)
"""``aruco --camera``: the shipped rig by name or file; damaged rig files, other TOML files."""
ARUCO_VIEW = texts(["front", "left", "back", "right", "upward"], ["Front", "top"])
ARUCO_RENDER: dict[str, Values] = {
    "out": file_output(".png"),
    "camera": CAMERA_FILE,
    "view": ARUCO_VIEW,
    "distance": Values(st.floats(0.0, 4.0).map(repr), junk),
    "bearing": Values(st.floats(-180.0, 180.0).map(repr), junk),
    "turn": Values(st.floats(-180.0, 180.0).map(repr), junk),
    "blur": floats(0.0, 3.0),
    "noise": floats(0.0, 20.0),
    "exposure": floats(0.0, 3.0),
    "occlusion": floats(0.0, 1.0),
}
"""``aruco render``: a carrier anywhere around the robot, any camera, any degradation."""

COMMON: dict[str, Values] = {
    "conditions": CONDITIONS,
    "settings": set_items(),
    "profile": PROFILE,
    "config": CONFIG,
    "events": file_output(".csv", ".parquet"),
    "event_table": file_output(".csv", ".parquet"),
    "snapshot": file_output(".png", rare=True),
    "animation": file_output(".gif", ".mp4", rare=True),
    "trajectories_out": file_output(".npz"),
    "mcap": file_output(".mcap"),
    "baseline": texts(["proximity", "urgency:alpha=0.7", "urgency:alpha=3.0"], ["nope"]),
    "resamples": integers(1, 10**9, (1, 50)),
    "runs": integers(1, 2**53, (1, 3)),
    "ticks": integers(1, None, (1, 30)),
    "robots": integers(1, None, (1, 4)),
    "carriers": integers(1, None, (1, 8)),
    "w": floats(0.0, 1.0),
    "workers": texts(["1"]),
    "scheduler": texts(["tcp://127.0.0.1:9"]),
    "sources": STUDY_SOURCE,
    "source": STUDY_SOURCE,
    "out_dir": folder_output(),
    "status": texts(["idle", "awaiting_pickup", "PICKED_UP", "0", "1", "2"], ["3", "-1"]),
    "hex_payload": HEX,
    "name": PROFILE,
}
"""Values of the options and arguments a click type alone does not describe, by name."""
BY_COMMAND: dict[tuple[str, ...], dict[str, Values]] = {
    ("metrics",): {
        "events": EVENT_LOG,
        "event_table": EVENT_TABLE,
        "markdown": file_output(".md", ".markdown"),
        "latex": file_output(".tex"),
        "html_out": file_output(".html", ".htm", rare=True),
        "figures": Values(folder_output().good, folder_output().bad, rare=True),
    },
    ("study", "report"): {
        "out_dir": Values(
            st.just(Made("results", "tree", template="results")),
            st.one_of(folder_output().good, folder_output().bad),
            rare=True,  # a report draws figures: about a second
        ),
        "resamples": integers(1, None, (1, 50)),
    },
    ("reproduce",): {
        "sources": Values(STUDY_SOURCE.good, STUDY_SOURCE.bad, rare=True),  # runs and reports
    },
    ("robot", "tree"): {"folder": folder_output()},
    ("tag", "render"): {"out": file_output(".png")},
    ("tag", "keygen"): {"out": file_output(".key"), "site_file": SITE_KEY},
    ("tag", "scan"): {"timeout": SCAN_TIMEOUT, "backend": SCAN_BACKEND, "adapter": ADAPTER},
    ("tag", "write"): WRITE_OPTIONS,
    ("tag", "emulate"): EMULATE_OPTIONS,
    ("log", "import"): {"bag": BAG, "mapping": BAG_MAPPING},
    ("aruco", "render"): ARUCO_RENDER,
    ("aruco", "detect"): {"image": IMAGE, "camera": CAMERA_FILE, "view": ARUCO_VIEW},
    ("console",): {
        "token_file": file_output(".token"),
        "audit_log": file_output(".jsonl"),
        "counter_file": file_output(".counters"),
        "host": texts(["127.0.0.1", "::1", "localhost"], ["256.0.0.1", "no such host"]),
        "port": integers(0, 65535, (0, 0)),  # any free port: parallel workers never collide
        "replay": Values(
            st.one_of(EVENT_LOG.good, copy("trial.mcap")),
            st.one_of(EVENT_LOG.bad, BAG.bad),
        ),
        "key_file": ROLE_KEY,  # --scan: the operator key signs; a robot key is refused
        "writer": integers(0, 0xFFFF, (0, 3)),
        "adapter": ADAPTER,
        "backend": SCAN_BACKEND,  # --scan hears the bench radio, never a real one
    },
    ("calibrate",): {
        "baseline": BASELINE,
        "out": with_inputs(file_output(".toml")),
        "report": file_output(".md"),
        "cache_path": Values(
            st.one_of(file_output(".jsonl", ".cache").good, copy("cache.jsonl")),
            st.one_of(with_inputs(file_output(".jsonl", ".cache")).bad, damaged_caches()),
        ),
        "free": FREE,
        "name": texts(["mine", "tiny", "a b"]),
        "condition": texts(["proximity"], ["urgency:alpha=0.7", "nope"]),
        "runs": integers(None, None, (1, 2)),
        "seed": integers(None, None, (0, 5)),
        "evaluations": integers(1, MAX_EVALUATIONS, (1, 3), top=False),
    },
}
"""Values that differ by command (``--baseline`` of metrics and of calibrate, ...)."""
INPUTS = {
    ("metrics",): ("events", "event_table"),
    ("simulate",): ("config", "profile"),
    ("calibrate",): ("baseline", "profile"),
    ("study", "run"): ("source",),
    ("study", "report"): ("sources",),
    ("reproduce",): ("sources",),
    ("profiles",): ("name",),
    ("tag", "keygen"): ("site_file",),
    ("tag", "write"): ("key_file", "loopback_key"),
    ("tag", "emulate"): ("key_file", "replay"),
    ("log", "import"): ("bag", "mapping"),
    ("console",): ("replay", "key_file"),
    ("aruco", "render"): ("camera",),
    ("aruco", "detect"): ("image", "camera"),
}
"""Parameters that name files a command reads (which no success may change), by command."""


def values(path: tuple[str, ...], param: click.Parameter) -> Values:
    name = param.name or ""
    chosen = BY_COMMAND.get(path, {}).get(name) or COMMON.get(name)
    return from_type(param) if chosen is None else chosen


# --- invocations ------------------------------------------------------------------------------

OUTPUTS: dict[tuple[str, ...], dict[str, str]] = {
    ("simulate",): {
        "events": "file",
        "event_table": "file",
        "snapshot": "per-condition",
        "animation": "per-condition",
        "trajectories_out": "per-condition",
        "mcap": "per-condition",
    },
    ("metrics",): {"markdown": "file", "latex": "file", "html_out": "file", "figures": "folder"},
    ("calibrate",): {"out": "file", "report": "file", "cache_path": "optional"},
    ("study", "run"): {"out_dir": "folder"},
    ("study", "report"): {"out_dir": "folder"},
    ("reproduce",): {"out_dir": "folder"},
    ("robot", "tree"): {"folder": "folder"},
    ("tag", "render"): {"out": "file"},
    ("tag", "keygen"): {"out": "file"},
    ("tag", "write"): {"counter_file": "file", "loopback_state": "optional"},
    ("tag", "emulate"): {"state_file": "file", "eink": "file"},
    ("log", "import"): {"events": "file", "event_table": "file"},
    ("aruco", "render"): {"out": "file"},
    ("console",): {"token_file": "file", "audit_log": "optional", "counter_file": "optional"},
}
"""The outputs of each command, by parameter name: what a success must have written."""
