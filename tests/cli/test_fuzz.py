"""A Hypothesis fuzzer of every ``swarmtag`` command: refused input is one line, never a trace.

Each test draws random invocations of one command: a random subset of the
options that the click command object itself declares (read from
``swarmtag.cli._main.app``), each with a value that is valid, at a boundary
(0, -1, 10**30, 1e308, -0.0, nan, inf, empty, NUL, newline, unicode), of the
wrong type or a random word; paths are new names with right and wrong
suffixes, missing folders, folders, regular files, FIFOs, ``/proc`` (which
even root cannot write), or one name given to two options; inputs are the
shipped example trial, small valid logs and study/target/profile files, and
corrupted copies of them. The newer surfaces are drawn too: ``warehouse.*``
scenario keys (``--set warehouse.KEY=VALUE`` and ``[warehouse]`` tables in
``--config`` files), TOML nested 20 to 3,000 deep (tables, arrays of tables,
arrays, inline tables) on every TOML surface (``--profile``, ``--config``,
``--set`` values, study files, calibration baselines, bag mappings, camera
files), damaged calibration caches (NaN, Infinity, null, 400-digit numbers,
-1e308, deep nesting, renamed keys), PNGs whose header claims 100000 x 100000
pixels, truncated PNGs and 1 x 1 images for ``aruco detect``, and camera files
with a 1-5 degree field of view. How often a value is a bad one is drawn per
invocation, so that some invocations are wholly valid and reach deep.

Every invocation must exit 0 or 2; exit 2 prints exactly one
``swarmtag: error:`` line on stderr and no help on stdout (a command may
have said what it started); no invocation prints a traceback; a failing one
leaves its working folder exactly as it was (no staging folder, no
``*.tmp``), a succeeding one writes every output it names and nothing else.
``tag write`` may also exit 1, when the (software) tag refused the write:
then with exactly one ``swarmtag: refused:`` line, and nothing written but
its outputs (the counter it spent).

The commands that write files (``FULL_DISK_EXAMPLES``, 200 invocations in
all) are fuzzed once more on a full disk: the same invocations, with the
working folders on an 8 MiB tmpfs that is filled to its last byte after an
invocation's inputs are made and freed when it returns (root only; skipped
with the reason elsewhere). There an invocation may exit 0 only if it wrote
nothing (it printed help, or its results on stdout), never having failed to
write an output it names; otherwise it exits 2 with exactly one
``swarmtag: error:`` line, and its folder is exactly as it was.

Invocations are kept cheap: simulations get at most 30 ticks (and a static
time limit of 30) unless those are drawn, resample, run and evaluation counts
are small in the valid branch, one worker process, and
``SWARMTAG_MEMORY_LIMIT`` is 2 GiB so that huge requests are refused at once.
The few inputs that would start real work (shipped studies, shipped
calibration baselines, event-log baselines) run under a 1 KiB limit, which
refuses them before their first simulation.

The seed is 0 unless pinned, and printed with every failure (also one that
is not an invocation's, such as a template that cannot be made); pin another
one, and ask for more invocations in all (shared out over the commands as in
the normal mode; the full-disk invocations are scaled alike)::

    SWARMTAG_FUZZ_SEED=7 SWARMTAG_FUZZ_EXAMPLES=20000 \\
        pytest -q -p no:cacheprovider tests/cli/test_fuzz.py

``-rP`` shows each test's line: invocations, successes, time, slowest calls.
"""

from __future__ import annotations

import contextlib
import os
import re
import shutil
import signal
import stat
import tempfile
import time
import traceback
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import click
import pytest
from hypothesis import HealthCheck, Phase, given, seed, settings
from hypothesis import strategies as st

from swarmtag._outputs import STAGING_PREFIX
from swarmtag._resources import MEMORY_LIMIT_VARIABLE
from swarmtag.calibration import default_cache_path
from swarmtag.cli import main
from swarmtag.cli._main import app
from swarmtag.cli.console import DEFAULT_COUNTER_FILE as COUNTERS
from swarmtag.cli.console import DEFAULT_TOKEN_FILE
from swarmtag.console.audit import DEFAULT_AUDIT_LOG
from swarmtag.data import example_trial_path
from swarmtag.sim.config.profiles import profile_path
from tests.cli.fuzz_files import (
    TINY_SCENARIO,
    TINY_STUDY,
    TINY_TARGETS,
    TINY_WAREHOUSE,
    Made,
    Token,
    make,
    make_cache_file,
    make_camera_files,
    make_tag_files,
)
from tests.cli.fuzz_values import (
    BENCH_WRITES,
    CHEAP,
    INPUTS,
    OUTPUTS,
    SCAN_TIMEOUT,
    SHIPPED_STUDIES,
    UNGUARDED_BASELINES,
    Values,
    junk,
    values,
)
from tests.full_disk import fill, free, tmpfs
from tests.io.bag_builders import write_fuzz_bags

SEED = int(os.environ.get("SWARMTAG_FUZZ_SEED", "0"))
"""Hypothesis seed of every fuzz test (``SWARMTAG_FUZZ_SEED``)."""
NORMAL_EXAMPLES = {
    (): 120,
    ("tag", "encode"): 200,
    ("tag", "decode"): 180,
    ("metrics",): 330,
    ("simulate",): 400,
    ("study", "run"): 160,
    ("study", "report"): 110,
    ("reproduce",): 100,
    ("profiles",): 200,  # with and without --json
    ("policies",): 20,
    ("policy", "check"): 20,
    ("calibrate",): 250,
    ("demo",): 8,
    ("robot", "tree"): 40,
    ("tag", "render"): 60,
    ("tag", "keygen"): 60,
    ("tag", "scan"): 30,
    ("tag", "write"): 60,
    ("tag", "emulate"): 60,
    ("log", "import"): 80,  # a missing BAG may stand for its per-condition files
    ("log", "mapping"): 5,
    ("aruco", "render"): 50,
    ("aruco", "detect"): 50,
    ("console",): 70,  # the server returns at once (test_fuzz_command): its set-up is fuzzed
}
"""Invocations per command in the normal suite (2,663 in all)."""
FULL_DISK_EXAMPLES = {
    ("simulate",): 25,
    ("metrics",): 25,
    ("calibrate",): 15,
    ("study", "run"): 15,
    ("study", "report"): 10,
    ("reproduce",): 10,
    ("robot", "tree"): 10,
    ("tag", "render"): 10,
    ("tag", "keygen"): 15,
    ("tag", "write"): 15,
    ("tag", "emulate"): 15,
    ("log", "import"): 15,
    ("aruco", "render"): 10,
    ("console",): 10,
}
"""Invocations per writing command on a full disk in the normal suite (200 in all)."""
FULL_DISK_SIZE = "8m"
"""The tmpfs that holds the working folders of the full-disk invocations."""
TOTAL = int(os.environ.get("SWARMTAG_FUZZ_EXAMPLES", "0")) or sum(NORMAL_EXAMPLES.values())
"""Invocations in all (``SWARMTAG_FUZZ_EXAMPLES``), shared out as in ``NORMAL_EXAMPLES``;
the full-disk ones are scaled alike (``FULL_DISK_EXAMPLES``), on top.
"""
HANG_SECONDS = 60
"""One invocation running longer than this is reported as a hang."""
MEMORY = "2GiB"
"""The memory limit of every invocation: huge requests are refused, not attempted."""
GUARD_MEMORY = "1KiB"
"""The limit of invocations whose input would start real work: refused before it starts."""
BADNESS = (3, 20, 50, 90)
"""Percent chances that an invocation's values are bad ones, one drawn per invocation."""
REFUSING = {("tag", "write"): "swarmtag: refused: "}
"""Commands that exit 1 when the device they talk to refuses, with the line they print then."""


def examples(path: tuple[str, ...], budget: dict[tuple[str, ...], int] = NORMAL_EXAMPLES) -> int:
    share = budget[path] * TOTAL / sum(NORMAL_EXAMPLES.values())
    return max(1, round(share))


def walk(group: click.Group, prefix: tuple[str, ...] = ()) -> dict[tuple[str, ...], click.Command]:
    """Every command under ``group``, by its words (``("study", "run")``)."""
    found: dict[tuple[str, ...], click.Command] = {}
    context = click.Context(group)  # the root group loads its commands when asked
    for name in group.list_commands(context):
        command = group.get_command(context, name)
        assert command is not None, name
        if isinstance(command, click.Group):
            found.update(walk(command, (*prefix, name)))
        else:
            found[(*prefix, name)] = command
    return found


COMMANDS = walk(app)


# --- the files every working folder may copy -------------------------------------------


@pytest.fixture(scope="module")
def templates(tmp_path_factory) -> dict[str, Path]:
    """What working folders copy: logs, tables, study, targets, scenario, profile, results, keys."""
    from swarmtag.experiments import load_study, run_study
    from swarmtag.io import CarrierLog, EventTable, write_event_log, write_event_table
    from swarmtag.policy import Proximity, Urgency
    from swarmtag.sim import simulate
    from swarmtag.sim.config.profiles import load_profile

    folder = tmp_path_factory.mktemp("fuzz-templates")
    scenario = load_profile("base").scenario({"robots": 2, "carriers": 3, "ticks": 300})
    results = [simulate(scenario, p, seed=0, runs=2) for p in (Proximity(), Urgency(alpha=0.7))]
    log = CarrierLog.concat([result.carriers for result in results])
    table = EventTable.concat([result.events for result in results])
    for suffix in (".csv", ".parquet"):
        write_event_log(log, folder / f"small{suffix}")
        write_event_table(table, folder / f"small-table{suffix}")
    shutil.copy(example_trial_path(), folder / "trial.csv")
    (folder / "study.toml").write_text(TINY_STUDY, encoding="utf-8")
    (folder / "targets.toml").write_text(TINY_TARGETS, encoding="utf-8")
    (folder / "scenario.toml").write_text(TINY_SCENARIO, encoding="utf-8")
    (folder / "warehouse.toml").write_text(TINY_WAREHOUSE, encoding="utf-8")
    profile = profile_path("base").read_text(encoding="utf-8")
    (folder / "profile.toml").write_text(profile.replace('name = "base"', 'name = "mine"'))
    run_study(load_study(str(folder / "study.toml")), out_dir=folder / "results", workers=1)
    make_tag_files(folder)
    write_fuzz_bags(folder)  # trial.mcap, trial.db3, bag/ and mapping.toml
    make_camera_files(folder)  # camera.png, small.png, under.png, one.png, cut.png, rig.toml
    make_cache_file(folder)  # cache.jsonl
    return {path.name: path for path in folder.iterdir()}


JUNK = ("--no-such-option", "-z", "extra", "--", "--help", "-h")
"""Words no command takes (or help), slipped in now and then."""


@dataclass
class Invocation:
    """A drawn command line: its words, its outputs, and whether it must run guarded."""

    argv: list[Token]
    outputs: list[tuple[str, Token]] = field(default_factory=list)
    guarded: bool = False
    given: dict[str, list[Token]] = field(default_factory=dict)
    path: tuple[str, ...] = ()
    made: list[Made] = field(default_factory=list)


def draw_value(draw: st.DrawFn, chosen: Values, badness: int) -> Token:
    if (chosen.rare and draw(st.integers(0, 3))) or draw(st.integers(0, 99)) < badness:
        return draw(chosen.bad)
    return draw(chosen.good)


def draw_words(
    draw: st.DrawFn, path: tuple[str, ...], param: click.Parameter, call: Invocation, badness: int
) -> list[Token]:
    """The words of one option or argument, noting its values in ``call.given``."""
    name = param.name or ""
    if isinstance(param, click.Option) and param.is_flag:
        return [draw(st.sampled_from([*param.opts, *param.secondary_opts]))]
    found: list[Token] = []
    repeats = draw(st.integers(1, 3)) if getattr(param, "multiple", False) else 1
    for _ in range(repeats):
        value = draw_value(draw, values(path, param), badness)
        call.given.setdefault(name, []).append(value)
        found += (
            [draw(st.sampled_from(param.opts)), value]
            if isinstance(param, click.Option)
            else [value]
        )
    return found


@st.composite
def invocations(draw: st.DrawFn, path: tuple[str, ...]) -> Invocation:
    """Random options (required ones nine times in ten), arguments, now and then junk."""
    command = COMMANDS[path]
    badness = draw(st.sampled_from(BADNESS))
    options = [p for p in command.params if isinstance(p, click.Option)]
    chosen = draw(st.lists(st.sampled_from(options), unique_by=lambda p: p.name)) if options else []
    chosen += [p for p in options if p.required and p not in chosen and draw(st.integers(0, 9))]
    call = Invocation([], path=path)
    groups = [draw_words(draw, path, option, call, badness) for option in chosen]
    for argument in (p for p in command.params if isinstance(p, click.Argument)):
        if draw(st.integers(0, 19)) if argument.required else draw(st.booleans()):
            at = draw(st.integers(0, len(groups)))
            groups.insert(at, draw_words(draw, path, argument, call, badness))
    if draw(st.integers(0, 19)) == 0:
        groups.insert(draw(st.integers(0, len(groups))), [draw(st.sampled_from(JUNK))])
    call.argv = [*path, *(word for group in groups for word in group)]
    defaults = {p.name: p.default for p in command.params}
    for name, kind in OUTPUTS.get(path, {}).items():
        default = defaults[name]
        fallback = [str(default)] if isinstance(default, str | Path) else []
        call.outputs += [(kind, value) for value in (call.given.get(name) or fallback)[-1:]]
    out = call.given.get("out", [])
    keys = call.given.get("key_file", [])
    if path == ("tag", "write") and not call.given.get("counter_file") and keys:
        call.outputs.append(("file", f"{word(keys[-1])}.counters"))  # next to the key file
    if path == ("console",):  # the audit log and the counters go next to the token file
        token = Path(word((call.given.get("token_file") or [DEFAULT_TOKEN_FILE])[-1]))
        for name, default in (("audit_log", DEFAULT_AUDIT_LOG), ("counter_file", COUNTERS)):
            if not call.given.get(name):
                call.outputs.append(("optional", str(token.parent / default)))
    if path == ("calibrate",) and not call.given.get("cache_path") and out:
        with contextlib.suppress(ValueError):  # a name calibrate refuses anyway
            call.outputs.append(("optional", str(default_cache_path(Path(word(out[-1]))))))
    return cheap(draw, path, call)


def no_radio(draw: st.DrawFn, path: tuple[str, ...], call: Invocation) -> None:
    """Never a real radio: ``tag scan`` hears the sim radio (never the default 10 s), and
    ``tag write`` writes to the templates' software tag (the hidden loopback backend).
    """
    if path == ("tag", "scan"):
        if not call.given.get("backend"):
            call.argv += ["--backend", "sim"]
        if not call.given.get("timeout"):
            call.argv += ["--timeout", draw(SCAN_TIMEOUT.good)]
        return
    if not call.given.get("backend"):
        call.argv += ["--backend", "loopback"]
    for option, made in (
        ("loopback_state", Made("tag.state", "copy", "tag.state")),
        ("loopback_key", Made("site.key", "secret", "site.key")),
    ):
        if not call.given.get(option):
            call.argv += [f"--{option.replace('_', '-')}", made]
            if option == "loopback_state":
                call.outputs.append(("optional", made.name))  # an accepted write changes it


def cheap(draw: st.DrawFn, path: tuple[str, ...], call: Invocation) -> Invocation:
    """Keep the call cheap: short runs, few resamples, one worker, real work guarded."""
    settings_ = [word(v) for v in call.given.get("settings", [])]
    if path in (("simulate",), ("calibrate",)):
        # calibrate refuses --set ticks (the set-ups set their own run length)
        for key in ("ticks", "urgency.static_time_limit")[path == ("calibrate",) :]:
            flag = call.given.get(key) if key == "ticks" else None
            if not flag and not any(text.startswith(f"{key}=") for text in settings_):
                call.argv += ["--set", f"{key}={draw(CHEAP[key])}"]
    if path in (("tag", "scan"), ("tag", "write")):
        no_radio(draw, path, call)
    if path == ("tag", "emulate") and not call.given.get("replay"):
        call.argv += ["--replay", BENCH_WRITES]  # the software tag never touches a radio
    if path == ("console",) and not call.given.get("backend"):
        call.argv += ["--backend", "sim"]  # --scan hears the bench radio, never a real one
    if path == ("reproduce",) and draw(st.booleans()):
        call.made.append(Made("out", "dir"))  # so that the default --out out/reproduction works
    if path in (("simulate",), ("metrics",)) and not call.given.get("resamples"):
        call.argv += ["--resamples", str(draw(st.integers(1, 50)))]
    if path == ("simulate",) and not call.given.get("runs"):
        call.argv += ["--runs", str(draw(st.integers(1, 3)))]  # not the default 30
    if path in (("study", "run"), ("reproduce",), ("calibrate",)) and not call.given.get("workers"):
        call.argv += ["--workers", "1"]
    if path in (("study", "run"), ("reproduce",)):
        sources = [word(v) for v in call.given.get("source", []) + call.given.get("sources", [])]
        shipped = any(s.lower() in SHIPPED_STUDIES for s in sources)
        call.guarded = shipped or (path == ("reproduce",) and not sources)
    if path == ("calibrate",):
        call.guarded = not all(
            isinstance(v, Made) and v.template in UNGUARDED_BASELINES
            for v in call.given.get("baseline", [])
        )
    return call


# --- running and checking one invocation ------------------------------------------------------


class Hang(BaseException):
    """An invocation ran past ``HANG_SECONDS``."""


@contextlib.contextmanager
def watchdog(seconds: float) -> Iterator[None]:
    def alarm(_signum: int, _frame: object) -> None:
        raise Hang

    previous = signal.signal(signal.SIGALRM, alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


Snapshot = dict[str, tuple[str, int, int]]


def snapshot(root: Path) -> Snapshot:
    """Every path under ``root``: its kind, and size and mtime for regular files."""
    found = {}
    for folder, dirs, files in os.walk(root):
        for name in [*dirs, *files]:
            path = Path(folder) / name
            info = path.lstat()
            if stat.S_ISREG(info.st_mode):
                found[str(path.relative_to(root))] = ("file", info.st_size, info.st_mtime_ns)
            else:
                kind = "dir" if stat.S_ISDIR(info.st_mode) else "other"
                found[str(path.relative_to(root))] = (kind, 0, 0)
    return found


def word(token: Token) -> str:
    return token.name if isinstance(token, Made) else token


def local(token: Token) -> str | None:
    """An output's path relative to the working folder, or None if it lies elsewhere."""
    text = word(token) or "."  # click reads "" as Path(""), the current folder
    if text.startswith("/") or "\0" in text:
        return None
    return os.path.normpath(text)


def allowed(rel: str, outputs: Sequence[tuple[str, Token]]) -> bool:
    """Whether a success may have written ``rel``: an output, inside a folder output, or a
    per-condition picture (``snap-proximity.png`` for ``--snapshot snap.png``).
    """
    for kind, token in outputs:
        target = local(token)
        if target is None:
            continue
        if rel == target or (kind == "folder" and (target == "." or rel.startswith(target + "/"))):
            return True
        if kind == "per-condition":
            suffix = Path(target).suffix
            stem = target.removesuffix(suffix)
            if rel.startswith(stem + "-") and rel.endswith(suffix) and "/" not in rel[len(stem) :]:
                return True
    return False


def not_written(outputs: Sequence[tuple[str, Token]]) -> list[str]:
    """The outputs a success named but did not write."""
    missing = []
    for kind, token in outputs:
        target = local(token)
        if target is None or kind == "optional":
            continue
        path = Path(target)
        variants = path.parent.glob(re.sub(r"([*?\[])", r"[\1]", path.stem) + f"-*{path.suffix}")
        there = {
            "folder": path.is_dir,
            "file": path.is_file,
            "per-condition": lambda: path.is_file() or any(variants),  # noqa: B023
        }[kind]()
        if not there:
            missing.append(target)
    return missing


@dataclass
class Fuzzer:
    """Runs invocations in fresh working folders under ``root`` and checks each one.

    With ``full_disk``, ``root`` is a small tmpfs: it is filled once an invocation's inputs
    are made, just before the command runs, and freed as soon as it has returned.
    """

    root: Path
    templates: dict[str, Path]
    capsys: pytest.CaptureFixture[str]
    monkeypatch: pytest.MonkeyPatch
    full_disk: bool = False
    count: int = 0
    seconds: float = 0.0
    successes: int = 0
    slowest: list[tuple[float, list[str]]] = field(default_factory=list)

    def run(self, call: Invocation) -> None:
        work = Path(tempfile.mkdtemp(prefix="w", dir=self.root))
        for token in [*call.argv, *call.made]:
            if isinstance(token, Made):
                make(token, work, self.templates)
        argv = [word(token) for token in call.argv]
        self.monkeypatch.chdir(work)
        self.monkeypatch.setenv(MEMORY_LIMIT_VARIABLE, GUARD_MEMORY if call.guarded else MEMORY)
        before = snapshot(work)
        self.capsys.readouterr()
        code: object = None
        crash = ""
        if self.full_disk:
            fill(self.root)
        started = time.perf_counter()
        try:
            with watchdog(HANG_SECONDS):
                main(argv)
        except SystemExit as exited:
            code = exited.code
        except BaseException:  # noqa: BLE001 - anything else is the bug being looked for
            crash = traceback.format_exc()
        finally:
            took = time.perf_counter() - started
            if self.full_disk:
                free(self.root)
        out, err = self.capsys.readouterr()
        self.count += 1
        self.seconds += took
        self.slowest = sorted([*self.slowest, (took, argv)], reverse=True)[:5]
        result = Result(argv, code, crash, out, err)
        after = snapshot(work)
        if self.full_disk:  # a failure must not leave the small device short of room
            shutil.rmtree(work, ignore_errors=True)
        result.check(call, before, after, full_disk=self.full_disk)
        self.successes += code == 0
        shutil.rmtree(work, ignore_errors=True)
        if any(self.root.glob(f"{STAGING_PREFIX}*")):
            result.fail("left a staging folder outside its working folder")

    def summary(self, path: tuple[str, ...]) -> str:
        slowest = "; ".join(f"{t:.2f} s {a[:8]}" for t, a in self.slowest[:3])
        return (
            f"fuzz {' '.join(path) or 'swarmtag'}{' on a full disk' * self.full_disk}: "
            f"{self.count} invocations "
            f"({self.successes} succeeded) in {self.seconds:.1f} s, seed {SEED}; "
            f"slowest: {slowest}"
        )


@dataclass
class Result:
    """What one invocation did: exit status (None if it returned), traceback, output."""

    argv: list[str]
    code: object
    crash: str
    out: str
    err: str

    def fail(self, what: str) -> None:
        pytest.fail(
            f"{what}\n  argv: {self.argv!r}\n  seed: SWARMTAG_FUZZ_SEED={SEED}\n"
            f"  stdout: {self.out[-2000:]!r}\n  stderr: {(self.crash + self.err)[-5000:]!r}",
            pytrace=False,
        )

    def check(
        self, call: Invocation, before: Snapshot, after: Snapshot, *, full_disk: bool = False
    ) -> None:
        """The contract of one invocation (see the module docstring); on a full disk nothing
        can be written, so only an invocation that wrote nothing may exit 0 (or 1).
        """
        if self.crash:
            self.fail("raised instead of exiting")
        refused = self.code == 1 and call.path in REFUSING
        if self.code not in (0, 2) and not refused:
            self.fail(f"exit status {self.code!r}, not 0 or 2")
        if "Traceback" in self.out or "Traceback" in self.err:
            self.fail("printed a traceback")
        gone = sorted(set(before) - set(after))
        if gone:
            self.fail(f"removed {gone}")
        left = [
            p
            for p in after
            if (Path(p).name.startswith(STAGING_PREFIX) or p.endswith(".tmp"))
            and not (self.code == 0 and allowed(p, call.outputs))  # asked for: --out x.tmp
        ]
        if left:
            self.fail(f"left {left}")
        changed = sorted(p for p in after if before.get(p) != after[p])
        helped = self.code == 0 and self.out.startswith("Usage:")
        if self.code == 2 or helped:
            if changed:
                self.fail(f"{'printed help' if helped else 'failed'} but wrote {changed}")
            if self.code == 2:
                self.check_refusal()
            return
        if full_disk and changed:
            self.fail(f"exit {self.code!r} on a full disk, having written {changed}")
        self.check_said(call, refused=refused)
        stray = [p for p in changed if not allowed(p, call.outputs)]
        if stray:
            self.fail(f"wrote {stray}, which no option names")
        inputs = INPUTS.get(call.path, ())
        read = {local(v) for k, vs in call.given.items() if k in inputs for v in vs}
        overwritten = sorted(read.intersection(changed))
        if overwritten:
            self.fail(f"changed {overwritten}, which it reads")
        missing = [] if refused else not_written(call.outputs)
        if missing:
            self.fail(f"succeeded without writing {missing}")

    def check_said(self, call: Invocation, *, refused: bool) -> None:
        """A success prints no error; a device's refusal (exit 1) is exactly its one line."""
        if not refused:
            if "swarmtag: error:" in self.err:
                self.fail("succeeded but printed an error")
            return
        lines = self.err.split("\n")
        if len(lines) != 2 or lines[1] or not self.err.startswith(REFUSING[call.path]):
            self.fail(f"refused, but not in exactly one {REFUSING[call.path]!r} line")

    def check_refusal(self) -> None:
        lines = self.err.split("\n")
        if len(lines) != 2 or lines[1] or not self.err.startswith("swarmtag: error: "):
            self.fail("refused, but not in exactly one 'swarmtag: error:' line")
        if "Usage:" in self.out:  # a command may have said what it started before it failed
            self.fail("refused, but printed help on stdout")


# --- the tests ----------------------------------------------------------------------------------


def fuzz(
    path: tuple[str, ...],
    strategy: st.SearchStrategy[Invocation],
    fuzzer: Fuzzer,
    budget: dict[tuple[str, ...], int] = NORMAL_EXAMPLES,
) -> None:
    @seed(SEED)
    @settings(
        max_examples=examples(path, budget),
        deadline=None,
        database=None,
        suppress_health_check=list(HealthCheck),
        phases=[Phase.explicit, Phase.generate],  # shrinking CLI calls takes minutes
        print_blob=False,
    )
    @given(strategy)
    def one(call: Invocation) -> None:
        fuzzer.run(call)

    try:
        one()
    except BaseException as exc:
        exc.add_note(f"seed: SWARMTAG_FUZZ_SEED={SEED}")  # pytest shows notes with the error
        raise
    assert fuzzer.count >= 1, f"{' '.join(path) or 'swarmtag'}: no invocation was generated"
    print(fuzzer.summary(path))  # shown by -rP


@pytest.fixture
def fuzzer(tmp_path, templates, capsys, monkeypatch) -> Fuzzer:
    return Fuzzer(tmp_path, templates, capsys, monkeypatch)


def test_every_command_and_option_is_fuzzed():
    assert set(COMMANDS) == set(NORMAL_EXAMPLES) - {()}
    for path, command in COMMANDS.items():
        for param in command.params:
            if not (isinstance(param, click.Option) and param.is_flag):
                values(path, param)  # raises for an option the fuzzer has no values for
        names = {p.name for p in command.params}
        assert set(OUTPUTS.get(path, {})) | set(INPUTS.get(path, ())) <= names, path


def serve_nothing(path: tuple[str, ...], monkeypatch: pytest.MonkeyPatch) -> None:
    """``console`` runs everything up to serving: the server stops as soon as it starts."""
    if path == ("console",):
        uvicorn = pytest.importorskip("uvicorn")
        monkeypatch.setattr(uvicorn.Server, "run", lambda _server, sockets=None: None)


@pytest.mark.first
@pytest.mark.parametrize("path", sorted(COMMANDS), ids=" ".join)
def test_fuzz_command(path, fuzzer):
    serve_nothing(path, fuzzer.monkeypatch)
    fuzz(path, invocations(path), fuzzer)


def test_every_writing_command_is_fuzzed_on_a_full_disk():
    assert set(OUTPUTS) <= set(FULL_DISK_EXAMPLES) <= set(COMMANDS)


@pytest.mark.parametrize("path", sorted(FULL_DISK_EXAMPLES), ids=" ".join)
def test_fuzz_command_on_a_full_disk(path, tmp_path, templates, capsys, monkeypatch):
    """The same invocations with the working folder on a tmpfs filled before the command runs."""
    serve_nothing(path, monkeypatch)
    with tmpfs(tmp_path / "device", FULL_DISK_SIZE) as device:
        fuzzer = Fuzzer(device, templates, capsys, monkeypatch, full_disk=True)
        fuzz(path, invocations(path), fuzzer, FULL_DISK_EXAMPLES)


ROOT_WORDS = ("--help", "-h", "--version", "tag", "study", "nope", "", "-", "--", "Simulate")
LEAVES = {path[-1] for path in COMMANDS}


@st.composite
def root_invocations(draw: st.DrawFn) -> Invocation:
    """Group-level words: help, version, groups without a command, unknown commands.

    A command named here is always followed by a word it refuses (or --help):
    its own options are the other tests' business.
    """
    first = draw(st.lists(st.sampled_from([*ROOT_WORDS, *sorted(LEAVES)]), max_size=3))
    extra = st.one_of(st.sampled_from([w for w in JUNK if w != "--"]), junk)
    rest = draw(st.lists(extra.filter(lambda w: w not in ("", "--")), max_size=2))
    if LEAVES & set(first) and not rest:
        rest = ["--help"]
    return Invocation([*first, *rest])


def test_fuzz_root(fuzzer):
    fuzz((), root_invocations(), fuzzer)
