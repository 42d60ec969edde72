"""Ctrl-C at random moments of real commands: out within a second, exit 130, nothing left behind.

Each command runs as the real console script in a fresh folder, once
uninterrupted (its duration and its outputs are the reference), then
``SWARMTAG_SIGINTS`` times (default 5; the longer mode of docs/reliability.md
uses 20) with one SIGINT at a random moment: the first within the start-up
and imports, the second near the end (while the outputs are written), the
others anywhere in the reference duration. Half of them go to the process
only, half to its process group (as Ctrl-C at a terminal does: the worker
processes get it too). Every interrupted command must

- exit within ``LIMIT_S`` of the signal, and so must its worker processes;
- exit 130 with ``swarmtag: error: aborted...`` as the last line of stderr and
  no traceback; or exit 0 if it had already finished, its stdout and outputs
  then complete;
- leave no new file but the resumable stores (study: the results store and
  ``progress.json``, only when they hold a stored chunk, never a ``.wal``;
  calibrate: the evaluation cache, whole lines only), and its planned outputs
  all or none (none unless the signal came after they were moved into
  place), byte-identical to the reference.

A signal within Python's own start-up, before any swarmtag code can have
installed the handler (the first ``_startup_s()`` seconds), gets Python's own
behaviour (death by SIGINT, or a traceback from the imports, or one printed
as "Exception ignored" from inside importlib, or none at all, after which the
command runs normally to its end); it still must leave nothing behind, and a
command that ran on must have written all its outputs and stdout as the
reference run did. The moments come from a seeded generator: the seed is
printed, pin it with ``SWARMTAG_SIGINT_SEED``.
"""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from swarmtag.experiments import ResultsStore
from tests.calibration.helpers import SMALL_TARGETS
from tests.experiments.helpers import SMALL_TOML

pytestmark = [
    pytest.mark.skipif(not hasattr(os, "killpg"), reason="POSIX signals"),
    pytest.mark.serial,  # exits within LIMIT_S: not beside other tests' load
]

SEED = int(os.environ.get("SWARMTAG_SIGINT_SEED") or random.SystemRandom().randrange(2**32))
COUNT = int(os.environ.get("SWARMTAG_SIGINTS") or 5)
CONCURRENT = 2
"""Interrupted commands running at once."""
LIMIT_S = 1.0
"""Most seconds from the signal to the exit of the command and of its workers."""
EARLY_S = 0.5
"""The first interrupt of each command comes within this much of the start (imports)."""
LATE = 0.85
"""The second comes in the last 15 % of the reference duration (outputs being written)."""
HUNG_S = 20.0
"""A command still running this long after the signal has ignored it."""
SCRIPT = Path(sys.executable).with_name("swarmtag")


def _startup_s() -> float:
    """A generous bound on Python's start-up until swarmtag's handler can be installed."""
    argv = [sys.executable, "-c", "import swarmtag.cli, swarmtag._interrupt"]
    times = []
    for _ in range(3):
        begin = time.monotonic()
        subprocess.run(argv, check=True)
        times.append(time.monotonic() - begin)
    return max(0.1, 4 * statistics.median(times))


# -- the commands -------------------------------------------------------------------------


def _png(path: Path) -> None:
    assert path.read_bytes().startswith(b"\x89PNG\r\n\x1a\n"), path


def _count_runs(store: Path) -> int:
    with ResultsStore(store, read_only=True) as results:
        return results.count_runs()


def _study_stores(folder: Path, new: set[str]) -> list[str]:
    """The study's resumable stores in ``new``: allowed only holding a stored chunk."""
    problems = []
    store = folder / "out" / "results.duckdb"
    progress = folder / "out" / "small" / "progress.json"
    wal = [name for name in new if name.endswith(".wal")]
    if wal:
        problems.append(f"DuckDB write-ahead log left behind: {wal}")
    elif store.exists():
        runs = _count_runs(store)
        if runs == 0:
            problems.append("an empty results store left behind")
        if progress.exists() and json.loads(progress.read_text())["done"] > runs:
            problems.append(f"progress.json claims more than the {runs} stored runs")
    elif progress.exists():
        problems.append("progress.json left without a results store")
    return problems


def _calibrate_stores(folder: Path, new: set[str]) -> list[str]:
    """The evaluation cache: whole JSON lines of finished evaluations only."""
    cache = folder / "fit.cache.jsonl"
    if "fit.cache.jsonl" not in new:
        return []
    text = cache.read_text()
    if not text.endswith("\n"):
        return ["the evaluation cache ends in a cut-off line"]
    if not all("key" in json.loads(line) for line in text.splitlines()):
        return ["the evaluation cache holds a line that is not an evaluation"]
    return []


@dataclass(frozen=True)
class Command:
    """One command line, what it needs in its folder, what it writes and what it may keep."""

    name: str
    argv: tuple[str, ...]
    inputs: tuple[str, ...]
    outputs: tuple[str, ...]
    """The planned outputs (files; their folders count with them)."""
    stores: tuple[str, ...] = ()
    """Resumable stores that may be left after an interrupt."""
    check_stores: Callable[[Path, set[str]], list[str]] = lambda _folder, _new: []
    check_outputs: Callable[[Path], None] = lambda _folder: None
    """More checks of complete outputs (besides being byte-identical to the reference)."""


def _check_metrics_outputs(folder: Path) -> None:
    assert "proximity" in (folder / "report.md").read_text()
    assert (folder / "report.html").read_text().rstrip().endswith("</html>")


SIMULATE = (
    "simulate --profile base --runs 4 --ticks 400 --resamples 2000 --no-progress "
    "--events events.csv --event-table table.csv --snapshot snap.png --animate run.gif "
    "--mcap run.mcap"
)
METRICS = (
    "metrics log.csv --resamples 20000 --markdown report.md --html report.html --figures figures"
)
STUDY = "study run study.toml --out out --no-progress --workers"
CALIBRATE = (
    "calibrate --baseline targets.toml --profile base --out fit.toml --report fit.md "
    "--workers 2 --no-progress"
)

COMMANDS = [
    Command(
        "simulate",
        tuple(SIMULATE.split()),
        inputs=(),
        outputs=(
            "events.csv",
            "table.csv",
            "snap-proximity.png",
            "snap-urgency-alpha-0.7.png",
            "run-proximity.gif",
            "run-urgency-alpha-0.7.gif",
            "run-proximity.mcap",
            "run-urgency-alpha-0.7.mcap",
        ),
    ),
    Command(
        "log import",
        ("log", "import", "run.mcap", "--events", "events.csv", "--event-table", "table.csv"),
        inputs=("run.mcap",),
        outputs=("events.csv", "table.csv"),
    ),
    Command(
        "metrics",
        tuple(METRICS.split()),
        inputs=("log.csv",),
        outputs=(
            "report.md",
            "report.html",
            "figures/latency_curves.png",
            "figures/pa_curves.png",
            "figures/urgency_latency.png",
        ),
        check_outputs=_check_metrics_outputs,
    ),
    *(
        Command(
            f"study run --workers {workers}",
            (*STUDY.split(), str(workers)),
            inputs=("study.toml",),
            outputs=("out/small/default/metrics.json",),
            stores=("out/results.duckdb", "out/small/progress.json"),
            check_stores=_study_stores,
        )
        for workers in (1, 2)
    ),
    Command(
        "calibrate",
        tuple(CALIBRATE.split()),
        inputs=("targets.toml",),
        outputs=("fit.toml", "fit.md"),
        stores=("fit.cache.jsonl",),
        check_stores=_calibrate_stores,
    ),
]


def _with_folders(paths: tuple[str, ...]) -> set[str]:
    names = set(paths)
    for path in paths:
        names.update(parent.as_posix() for parent in Path(path).parents if parent != Path())
    return names


def _listing(folder: Path) -> set[str]:
    return {path.relative_to(folder).as_posix() for path in folder.rglob("*")}


def _alive_in_group(group: int) -> list[int]:
    """Processes (not zombies) of process group ``group``."""
    alive = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == group and fields[0] != "Z":
            alive.append(int(stat.parent.name))
    return alive


@dataclass
class Trial:
    """What one interrupted (or reference) run did."""

    moment: float
    group: bool
    status: int | None = None
    finished_first: bool = False
    """The command had exited before the signal was sent."""
    exit_s: float = 0.0
    """Seconds from the signal to the exit of the command."""
    workers_s: float = 0.0
    """Seconds from the signal until no process of its group was left."""
    outputs: str = "none"
    """"none", "all" (moved into place before the signal took effect)."""
    stdout: bytes = b""
    stderr: str = ""
    left: list[str] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)


class Runner:
    """Runs the console script in fresh folders under ``root``."""

    def __init__(self, root: Path, log: Path, startup_s: float) -> None:
        self.root = root
        self.log = log
        self.startup_s = startup_s
        self.reference: dict[tuple[str, str], bytes] = {}
        self.reference_stdout: dict[str, bytes] = {}

    def _folder(self, command: Command, label: str) -> Path:
        folder = self.root / f"{command.name.replace(' ', '-')}-{label}"
        folder.mkdir()
        for name in command.inputs:
            shutil.copy(self.root / "inputs" / name, folder / name)
        return folder

    def start(self, command: Command, folder: Path) -> subprocess.Popen[bytes]:
        out = (self.log / f"{folder.name}.out").open("wb")
        err = (self.log / f"{folder.name}.err").open("wb")
        with out, err:
            return subprocess.Popen(
                [str(SCRIPT), *command.argv],
                cwd=folder,
                stdin=subprocess.DEVNULL,
                stdout=out,
                stderr=err,
                start_new_session=True,
            )

    def measure(self, command: Command) -> float:
        """Run ``command`` uninterrupted: its duration; its outputs become the reference."""
        folder = self._folder(command, "reference")
        begin = time.monotonic()
        child = self.start(command, folder)
        child.wait(timeout=120)
        duration = time.monotonic() - begin
        err = (self.log / f"{folder.name}.err").read_text()
        assert child.returncode == 0, err
        new = _listing(folder) - set(command.inputs)
        assert new == _with_folders(command.outputs + command.stores), sorted(new)
        command.check_outputs(folder)
        for name in command.outputs:
            if name.endswith(".png"):
                _png(folder / name)
            self.reference[command.name, name] = (folder / name).read_bytes()
        self.reference_stdout[command.name] = (self.log / f"{folder.name}.out").read_bytes()
        return duration

    def interrupt(self, command: Command, index: int, trial: Trial) -> Trial:
        folder = self._folder(command, str(index))
        before = _listing(folder)
        child = self.start(command, folder)
        begin = time.monotonic()
        time.sleep(max(0.0, begin + trial.moment - time.monotonic()))
        trial.finished_first = child.poll() is not None
        sent = time.monotonic()
        if not trial.finished_first:
            with_group = os.killpg if trial.group else os.kill
            with_group(child.pid, signal.SIGINT)
        while child.poll() is None and time.monotonic() - sent < HUNG_S:
            time.sleep(0.002)
        trial.exit_s = time.monotonic() - sent
        while _alive_in_group(child.pid) and time.monotonic() - sent < HUNG_S:
            time.sleep(0.005)
        trial.workers_s = time.monotonic() - sent
        leftover = _alive_in_group(child.pid)
        if leftover or child.poll() is None:
            os.killpg(child.pid, signal.SIGKILL)
            child.wait()
            trial.problems.append(f"still running {HUNG_S} s after the signal: {leftover}")
        trial.status = child.returncode
        trial.stdout = (self.log / f"{folder.name}.out").read_bytes()
        trial.stderr = (self.log / f"{folder.name}.err").read_text(errors="replace")
        self._check(command, folder, before, trial)
        return trial

    def _swallowed_by_python(self, trial: Trial) -> bool:
        """A Ctrl-C that CPython itself lost during its own start-up: the command ran on.

        Before swarmtag's handler exists, Python's default handler raises the
        interrupt wherever Python is; inside importlib's module-lock weakref
        callback it can only print it ("Exception ignored in ...") and go on,
        and the command then runs normally. Once (a fresh clone's suite, a
        signal 4 ms after the start) it was lost without a word: exit 0, empty
        stderr. Nothing of swarmtag's can see either; the command must then
        have run to its end (exit 0 with its whole stdout and every output,
        checked by ``_status_problems`` and ``_output_problems``).
        """
        return trial.moment < self.startup_s and trial.status == 0

    def _check(self, command: Command, folder: Path, before: set[str], trial: Trial) -> None:
        problems = trial.problems
        ran_on = self._swallowed_by_python(trial)  # the command ran to its end, as it should then
        if trial.exit_s > LIMIT_S and not ran_on:
            problems.append(f"exited {trial.exit_s:.2f} s after the signal")
        if trial.workers_s > LIMIT_S and not ran_on:
            problems.append(f"its processes were gone only {trial.workers_s:.2f} s after it")
        new = _listing(folder) - before
        present = [name for name in command.outputs if name in new]
        problems.extend(self._status_problems(command, trial, present))
        if present:
            trial.outputs = "all"
            problems.extend(self._output_problems(command, folder, present))
        allowed = _with_folders(command.stores)
        if present:
            allowed |= _with_folders(command.outputs)
        trial.left = sorted(new - allowed)
        if trial.left:
            problems.append(f"left behind: {trial.left}")
        problems.extend(command.check_stores(folder, new))
        if problems and trial.stderr:
            problems.append("stderr: " + trial.stderr[-2000:])

    def _status_problems(self, command: Command, trial: Trial, present: list[str]) -> list[str]:
        """Exit status, stderr and stdout as they must be."""
        # Before swarmtag's handler exists, Ctrl-C gets Python's own treatment.
        python_own = trial.status in (-signal.SIGINT, 1) and trial.moment < self.startup_s
        python_own = python_own or self._swallowed_by_python(trial)
        lines = trial.stderr.strip().splitlines()
        problems = []
        if trial.status == 0:
            if len(present) < len(command.outputs):
                problems.append(f"exit 0 without all its outputs: {present}")
            if trial.stdout != self.reference_stdout[command.name]:
                problems.append("exit 0 with incomplete stdout")
        elif trial.status == 130:
            if not lines or not lines[-1].startswith("swarmtag: error: aborted"):
                problems.append(f"last line of stderr: {lines[-1:]}")
        elif not python_own:
            problems.append(f"exit status {trial.status}")
        if ("Traceback" in trial.stderr or "Exception ignored" in trial.stderr) and not python_own:
            problems.append("a traceback on stderr")
        return problems

    def _output_problems(self, command: Command, folder: Path, present: list[str]) -> list[str]:
        """Outputs are all there or none, and then as the uninterrupted run wrote them."""
        if len(present) < len(command.outputs):
            return [f"only some planned outputs: {present}"]
        command.check_outputs(folder)
        return [
            f"{name} differs from the uninterrupted run's"
            for name in command.outputs
            if (folder / name).read_bytes() != self.reference[command.name, name]
        ]


def _moments(rng: random.Random, duration: float, count: int) -> list[float]:
    moments = [rng.uniform(0.0, min(EARLY_S, duration))]
    if count > 1:
        moments.append(rng.uniform(LATE * duration, duration))
    moments.extend(rng.uniform(0.0, duration) for _ in range(count - 2))
    return moments[:count]


@pytest.fixture(scope="module")
def workspace(tmp_path_factory) -> Runner:
    root = tmp_path_factory.mktemp("sigint")
    log = tmp_path_factory.mktemp("sigint-logs")
    inputs = root / "inputs"
    inputs.mkdir()
    (inputs / "study.toml").write_text(SMALL_TOML)
    shutil.copy(SMALL_TARGETS, inputs / "targets.toml")
    # A log that metrics takes 1-2 s over (with 20000 resamples and every output).
    argv = "simulate --profile base --runs 20 --ticks 1000 --resamples 10 --no-progress --events"
    subprocess.run(
        [str(SCRIPT), *argv.split(), str(inputs / "log.csv")], check=True, stdout=subprocess.DEVNULL
    )
    # A recorded run for log import (one trial of 2000 ticks, one condition: one file).
    argv = "simulate --profile base --runs 1 --ticks 2000 --resamples 10 --no-progress "
    argv += "--condition proximity --mcap"
    subprocess.run(
        [str(SCRIPT), *argv.split(), str(inputs / "run.mcap")],
        check=True,
        stdout=subprocess.DEVNULL,
    )
    return Runner(root, log, _startup_s())


@pytest.mark.parametrize("command", COMMANDS, ids=[c.name for c in COMMANDS])
def test_ctrl_c_at_random_moments(workspace, command):
    duration = workspace.measure(command)
    rng = random.Random(f"{SEED}-{command.name}")
    trials = [
        Trial(moment=moment, group=index % 2 == 1)
        for index, moment in enumerate(_moments(rng, duration, COUNT))
    ]
    with ThreadPoolExecutor(CONCURRENT) as pool:
        done = list(pool.map(lambda item: workspace.interrupt(command, *item), enumerate(trials)))
    exits = sorted(trial.exit_s for trial in done if not trial.finished_first)
    statuses = [trial.status for trial in done]
    print(
        f"\n{command.name}: seed {SEED} (SWARMTAG_SIGINT_SEED), {len(done)} SIGINTs, "
        f"reference {duration:.2f} s; exit 130: {statuses.count(130)}, exit 0: "
        f"{statuses.count(0)} ({sum(t.finished_first for t in done)} finished before the "
        f"signal), in Python's own start-up (first {workspace.startup_s:.3f} s): "
        f"{len(done) - statuses.count(130) - statuses.count(0)}; "
        f"130 after the outputs were in place: "
        f"{sum(t.status == 130 and t.outputs == 'all' for t in done)}; signal to exit: "
        f"median {statistics.median(exits) if exits else 0:.3f} s, max "
        f"{max(exits, default=0):.3f} s; files left behind: "
        f"{sum(len(t.left) for t in done)}"
    )
    failures = [
        f"#{index} at {trial.moment:.3f} s ({'group' if trial.group else 'process'}), exit "
        f"{trial.status}: " + "; ".join(trial.problems)
        for index, trial in enumerate(done)
        if trial.problems
    ]
    assert not failures, f"seed {SEED}:\n" + "\n".join(failures)


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc")
def test_pool_workers_leave_ctrl_c_to_the_parent_and_stop_ends_them_at_once():
    from concurrent.futures import ProcessPoolExecutor

    from swarmtag._pools import spawn_context, stop

    pool = ProcessPoolExecutor(max_workers=1, mp_context=spawn_context())
    try:
        status = pool.submit(Path.read_text, Path("/proc/self/status")).result(timeout=60)
        blocked = next(line for line in status.splitlines() if line.startswith("SigBlk:"))
        assert int(blocked.split()[1], 16) & (1 << (signal.SIGINT - 1))
        busy = pool.submit(time.sleep, 60)
        time.sleep(0.2)  # the worker has taken the job
        (worker,) = pool._processes
        os.kill(worker, signal.SIGINT)  # blocked in the worker: nothing happens
        time.sleep(0.1)
        assert not busy.done()
    finally:
        begin = time.monotonic()
        stop(pool)  # does not wait the minute the job would take
    assert time.monotonic() - begin < LIMIT_S
    assert not Path(f"/proc/{worker}").exists()


def test_a_ctrl_c_while_a_worker_starts_waits_for_it_and_stop_still_ends_it(monkeypatch):
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    from swarmtag._pools import _Worker, spawn_context, stop

    real_popen = _Worker._Popen

    def popen(process):
        started = real_popen(process)
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C just as the worker is forked
        return started

    monkeypatch.setattr(_Worker, "_Popen", staticmethod(popen))
    pool = ProcessPoolExecutor(max_workers=1, mp_context=spawn_context())
    with pytest.raises(KeyboardInterrupt):
        pool.submit(time.sleep, 60)
    assert pool._processes == {}  # raised before the pool recorded its worker
    workers = [p for p in multiprocessing.active_children() if isinstance(p, _Worker)]
    assert len(workers) == 1
    begin = time.monotonic()
    stop(pool)
    assert time.monotonic() - begin < LIMIT_S
    assert not [p for p in multiprocessing.active_children() if isinstance(p, _Worker)]


def test_an_interrupted_command_ends_without_finalizing_what_it_loaded():
    """After a Ctrl-C the console script's process ends with 130 without the teardown.

    An interrupt can leave a native library's object half handed over (llvmlite:
    a module LLVM freed, its wrapper not yet told); its finalizer at the
    interpreter's shutdown then crashed the process (exit -11 after ``aborted``).
    The object here crashes when it is finalized, with the frames that the
    interrupt unwound (as llvmlite's was); atexit handlers still run.
    """
    code = (
        "import atexit, ctypes, os, signal, sys, threading\n"
        "class FreedTwice:\n"
        "    def __del__(self):\n"
        "        ctypes.string_at(0)\n"
        "atexit.register(lambda: print('atexit ran', flush=True))\n"
        "from swarmtag.cli import _main, main\n"
        "command = _main.run\n"
        "def run(argv):\n"
        "    held = FreedTwice()  # freed with the frames the interrupt unwinds, at exit\n"
        "    command(argv)\n"
        "_main.run = run\n"
        "sys.argv = ['swarmtag', *sys.argv[1:]]\n"
        "threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT)).start()\n"
        "main()\n"
    )
    long_run = ["simulate", "--backend", "reference", "--runs", "64", "--ticks", "100000"]
    done = subprocess.run(
        [sys.executable, "-c", code, *long_run, "--no-progress"],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )
    assert done.returncode == 130, done.stderr
    assert done.stderr.splitlines()[-1] == "swarmtag: error: aborted", done.stderr
    assert done.stdout.splitlines()[-1] == "atexit ran", done.stdout


def test_the_console_script_skips_the_last_collections_at_exit():
    """The objects loaded by a command are frozen out of the interpreter's final collections.

    Those collections walked numba's and matplotlib's objects for 0.3-0.6 s after
    the command was done, which put a Ctrl-C's exit that much later (over the
    second on a slow machine). Library calls (``main(argv)``) leave the collector alone.
    """
    code = (
        "import atexit, gc, sys\n"
        "atexit.register(lambda: print('frozen', gc.get_freeze_count() > 0))\n"
        "from swarmtag.cli import main\n"
        "sys.argv = ['swarmtag', '--version']\n"
        "main()\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.splitlines()[-1] == "frozen True", done.stdout
    code = code.replace("main()", "main(['--version'])")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.splitlines()[-1] == "frozen False", done.stdout


# -- Ctrl-C inside one long call of compiled code: route search, marker detection -------------


def _aisles_map(side: int) -> str:
    """A ``side`` x ``side`` floor of short shelf rows, four destinations in the corners."""
    rows = []
    for r in range(side):
        line = ["."] * side
        if r % 4 == 1:
            for c in range(2, side - 2, 6):
                line[c] = line[c + 1] = "#"
        rows.append(line)
    for c in range(0, 40, 2):
        rows[-1][c] = "P"
    rows[0][-1], rows[-1][-1], rows[0][0], rows[side // 2][side // 2] = "0", "1", "2", "3"
    return "\n".join("".join(line) for line in rows) + "\n"


def _interrupted_at(argv: list[str], folder: Path, moment: float) -> tuple[int, float, str]:
    """Run ``argv`` in ``folder``, SIGINT its group at ``moment`` s: (status, s to exit, stderr)."""
    child = subprocess.Popen(
        [str(SCRIPT), *argv],
        cwd=folder,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,
    )
    time.sleep(moment)
    if child.poll() is not None:
        child.communicate()  # its pipe closed before the failure
        pytest.fail(f"finished before the signal at {moment:.2f} s")
    sent = time.monotonic()
    os.killpg(child.pid, signal.SIGINT)
    _, err = child.communicate(timeout=HUNG_S)
    exit_s = time.monotonic() - sent
    while _alive_in_group(child.pid) and time.monotonic() - sent < HUNG_S:
        time.sleep(0.005)
    return child.returncode, max(exit_s, time.monotonic() - sent), err.decode(errors="replace")


def test_ctrl_c_while_a_large_map_s_routes_are_searched(tmp_path):
    # 2048 x 2048 cells, four destinations: the routes take seconds of compiled code,
    # searched in a worker process (sim.config.routes); the command must stop at once.
    # The search's worker runs from about 0.4 s to 4.5-6.4 s in (of 8.5 s, the VM at its
    # slower speed, which moves by up to a factor of two): the moments fall inside the
    # search on a machine twice as slow, and within the command on one twice as fast.
    (tmp_path / "hall.txt").write_text(_aisles_map(2048))
    argv = "simulate --profile lab --robots 8 --ticks 30 --runs 1 --resamples 10 --no-progress"
    argv += " --set warehouse.map=hall.txt --events events.csv"
    for moment in (1.0, 1.75, 2.5):
        status, exit_s, err = _interrupted_at(argv.split(), tmp_path, moment)
        assert status == 130, err
        assert err.strip().splitlines()[-1] == "swarmtag: error: aborted"
        assert exit_s < LIMIT_S, f"{exit_s:.2f} s after a SIGINT at {moment:.2f} s"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["hall.txt"]


def test_ctrl_c_while_markers_are_searched_in_a_large_image(tmp_path):
    # A 10000 x 10000 image of random blocks: OpenCV's search takes seconds in one call.
    pytest.importorskip("cv2")
    import cv2
    import numpy as np

    rng = np.random.default_rng(0)
    blocks = rng.integers(0, 2, (1250, 1250), dtype=np.uint8) * 255
    image = np.kron(blocks, np.ones((8, 8), dtype=np.uint8))
    assert cv2.imwrite(str(tmp_path / "big.png"), image)
    (tmp_path / "big.toml").write_text(
        "[intrinsics]\nwidth = 10000\nheight = 10000\nhorizontal_fov = 60.0\n"
        '[[cameras]]\nname = "front"\nposition = [0.12, 0.0, 0.10]\n'
    )
    argv = ["aruco", "detect", "big.png", "--camera", "big.toml"]
    begin = time.monotonic()
    reference = subprocess.run([str(SCRIPT), *argv], cwd=tmp_path, capture_output=True, check=True)
    duration = time.monotonic() - begin
    assert b"marker(s)" in reference.stdout
    for share in (0.4, 0.55, 0.7):
        status, exit_s, err = _interrupted_at(argv, tmp_path, share * duration)
        assert status == 130, err
        assert err.strip().splitlines()[-1] == "swarmtag: error: aborted"
        assert exit_s < LIMIT_S, f"{exit_s:.2f} s after a SIGINT at {share * duration:.2f} s"
