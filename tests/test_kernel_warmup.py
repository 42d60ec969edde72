"""The statistics warm-up compiles every loop a real summary then uses: nothing is left to compile.

``make demo`` runs ``python -m tests.kernel_warmup statistics`` during its
install so that the demo's first ``simulate`` loads the bootstrap's machine
code instead of compiling it. Checked in a numba cache folder of its own: a
summary of simulated runs (some carriers undelivered, so the censored and
Kaplan-Meier paths run) after the warm-up adds no file to that folder.
And a warm-up started while another holds the cache's lock waits for it,
the phases compiled ahead of a cold ``batched`` warm-up are the ones it
loads, and the kernel's warm-up imports only what ``make`` installs before
starting it.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.kernel_warmup import (
    KERNEL_PACKAGES,
    WAITING,
    ahead_signatures,
    kernel_requirements,
    lock,
)

pytest.importorskip("numba")

ROOT = Path(__file__).resolve().parent.parent

SUMMARY = """
from dataclasses import replace

from swarmtag.analysis import summarize
from swarmtag.io import CarrierLog
from swarmtag.policy import parse_policy
from swarmtag.sim import Scenario, simulate

scenario = replace(Scenario.default(3, 7), ticks=2000)
logs = [
    simulate(scenario, parse_policy(name), seed=0, runs=6, backend="reference").carriers
    for name in ("proximity", "urgency:alpha=0.7")
]
log = CarrierLog.concat(logs)
assert 0 < int(log.delivery_time.size - (log.delivery_time >= 0).sum()) < log.delivery_time.size
report = summarize(log, n_resamples=300, compiled=True)
assert [c.diff for c in report.comparisons if c.metric == "km_p95_latency"] != [None]
"""


def _cached(folder: Path) -> set[str]:
    return {path.name for path in folder.rglob("*") if path.suffix in {".nbi", ".nbc"}}


def _run(code: list[str], cache: Path) -> None:
    environment = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    subprocess.run(
        [sys.executable, *code], cwd=ROOT, env=environment, check=True, capture_output=True
    )


@pytest.mark.first
def test_statistics_warmup_leaves_nothing_for_a_summary_to_compile(tmp_path: Path) -> None:
    _run(["-m", "tests.kernel_warmup", "statistics"], tmp_path)
    warmed = _cached(tmp_path)
    assert any(name.startswith("_compiled.km_reached") for name in warmed)
    _run(["-c", SUMMARY], tmp_path)
    assert _cached(tmp_path) == warmed


def test_a_warm_up_started_while_another_runs_waits_for_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # make starts pytest while its install's warm-up is still compiling: the tests' warm-up
    # (and make demo's --wait) must wait for that one's lock, in the cache they share.
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    command = [sys.executable, "-m", "tests.kernel_warmup", "--wait"]
    with lock():  # taken before the second one starts
        waiting = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, text=True)
        assert waiting.stdout is not None
        said = waiting.stdout.readline().strip()
        still = waiting.poll() is None
    with waiting:
        assert said == WAITING  # it found the lock held
        assert still  # and waited for it
        assert waiting.wait(timeout=60) == 0
    free = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=True)
    assert free.stdout == ""  # nobody holds it: no wait, nothing said


def test_the_phases_compiled_ahead_have_the_types_a_batched_run_calls_them_with() -> None:
    # The suite's warm-up left the batched kernel cached (the ahead process's phases with it,
    # from a cold cache): each phase loads for the predicted types, and its cache holds one
    # compiled version. Wrong types would be compiled here (a cache miss), or would have
    # left two versions: the ahead process's and the one the kernel compiled itself.
    for dispatcher, signature in ahead_signatures():
        dispatcher.compile(signature)
        stats = dispatcher.stats
        assert not stats.cache_misses, dispatcher.py_func.__qualname__
        module = dispatcher.py_func.__module__.rpartition(".")[2]
        versions = Path(stats.cache_path).glob(f"{module}.{dispatcher.py_func.__qualname__}-*.nbc")
        assert len(list(versions)) == 1, dispatcher.py_func.__qualname__


ONLY_THE_KERNEL_PACKAGES = """
import importlib.abc, importlib.metadata, sys

allowed = set(sys.argv[1:])
blocked = {
    name
    for name, distributions in importlib.metadata.packages_distributions().items()
    if not {d.lower() for d in distributions} & allowed
}


class Blocked(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.partition(".")[0] in blocked:
            raise ImportError(f"{name} is not installed yet when make starts the warm-up")


sys.meta_path.insert(0, Blocked())
from tests.kernel_warmup import ahead_signatures, warm

warm("batched")
ahead_signatures()
"""


def test_the_kernel_warm_up_needs_only_the_packages_make_installs_before_it() -> None:
    # make installs kernel_requirements (and so numba's own llvmlite), starts the warm-up
    # from the sources, then installs the rest: the batched warm-up and the ahead process's
    # run import nothing else (scipy, rich, ...).
    allowed = [*KERNEL_PACKAGES, "llvmlite", "swarmtag"]
    command = [sys.executable, "-c", ONLY_THE_KERNEL_PACKAGES, *allowed]
    subprocess.run(command, cwd=ROOT, check=True)


def test_the_kernel_requirements_are_pyproject_s_own(tmp_path: Path) -> None:
    pyproject = tmp_path / "pyproject.toml"
    pyproject.write_text(
        '[project]\ndependencies = ["NumPy >= 2", "scipy>=1"]\n'
        '[project.optional-dependencies]\nfast = ["numba<1,>=0.59"]\n',
        encoding="utf-8",
    )
    assert kernel_requirements(pyproject) == ["NumPy >= 2", "numba<1,>=0.59"]
    pyproject.write_text(
        '[project]\ndependencies = ["numpy"]\n[project.optional-dependencies]\nfast = []\n',
        encoding="utf-8",
    )
    with pytest.raises(ValueError, match="not one requirement each"):
        kernel_requirements(pyproject)
