"""Shared test configuration: Hypothesis profiles, the opt-in ``--radio`` tests, a locked folder.

Before any test, the fast kernel's two entry points and the bootstrap's
compiled loops are compiled (or loaded) side by side in three processes
(``tests/kernel_warmup.py``), while the tests are collected.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from collections.abc import Generator
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

from tests.kernel_warmup import ENTRIES

# CI machines are small and shared: no per-example deadline, and a fixed
# number of examples so the suite's length is predictable.
settings.register_profile(
    "ci",
    deadline=None,
    max_examples=200,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile("dev", deadline=None, max_examples=100)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if os.environ.get("CI") else "dev"))


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--radio",
        action="store_true",
        default=False,
        help="also run the tests marked 'radio', which scan with a real Bluetooth adapter",
    )


def pytest_configure(config: pytest.Config) -> None:
    """No inherited terminal width; then have the fast kernel's machine code cached.

    pytest-xdist exports ``COLUMNS=80`` to its workers, and the command line
    honours an exported ``COLUMNS`` even in a pipe: without this the
    console's width would depend on how the suite is run. Tests that want
    a width set it themselves.
    """
    os.environ.pop("COLUMNS", None)
    os.environ.pop("LINES", None)
    _compile_kernel(config)


_WARMUP = pytest.StashKey[subprocess.Popen[str]]()


def _compile_kernel(config: pytest.Config) -> None:
    """Start having the fast kernel's machine code cached; the tests wait for it (``_kernel_ready``).

    Its first compilation takes a minute or more on one core. Done here, the
    two entry points (and the statistics' loops) compile side by side;
    without it, each test worker (and each command-line test's own process)
    would compile the kernel again while the first was still at it, and the
    command-line tests would see the first-compilation note on stderr. Once
    cached, this loads it in a few seconds. It runs beside the collection
    (the test workers' too), and waits for a warm-up that ``make`` started
    during the install (its lock). An xdist worker skips it: its controller
    does it.
    """
    if (
        hasattr(config, "workerinput")
        or config.option.collectonly
        or importlib.util.find_spec("numba") is None
    ):
        return
    root = Path(__file__).resolve().parent.parent
    config.stash[_WARMUP] = subprocess.Popen(
        [sys.executable, "-m", "tests.kernel_warmup", *ENTRIES],
        cwd=root,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )


@pytest.hookimpl(wrapper=True, tryfirst=True)
def pytest_runtestloop(session: pytest.Session) -> Generator[None, object, object]:
    """Run the tests once the kernel warm-up ``_compile_kernel`` started has ended, or stop."""
    _kernel_ready(session.config)
    return (yield)


def _kernel_ready(config: pytest.Config) -> None:
    """Wait for the kernel warm-up; a failed one stops the run with its output."""
    process = config.stash.get(_WARMUP, None)
    if process is None:
        return
    output = process.communicate()[0]  # interrupted here, pytest_unconfigure stops it
    del config.stash[_WARMUP]
    if process.returncode:
        raise pytest.UsageError("compiling the fast kernel failed:\n" + output)


def pytest_unconfigure(config: pytest.Config) -> None:
    """A run that ended before its tests (interrupted, or refused) stops its warm-up."""
    process = config.stash.get(_WARMUP, None)
    if process is not None:
        process.terminate()
        process.communicate()


def pytest_ignore_collect(collection_path: Path, config: pytest.Config) -> bool | None:
    """With ``-m serial`` alone, pass over test modules that never write ``serial``.

    ``make test``'s second part runs the few serial tests; collecting the
    whole suite for them took 7 of its 45 seconds. A test is marked serial
    in its own module (``pytest.mark.serial``), so a module without the word
    holds none. ``None`` leaves every other path to pytest's own rules.
    """
    if (
        config.option.markexpr != "serial"
        or collection_path.suffix != ".py"
        or not collection_path.name.startswith("test_")
    ):
        return None
    return "serial" not in collection_path.read_text(encoding="utf-8") or None


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The ``first`` tests to the front (a stable sort: the same order on every worker); radio skips."""
    items.sort(key=lambda item: "first" not in item.keywords)
    if config.getoption("--radio"):
        return
    skip = pytest.mark.skip(reason="needs a Bluetooth adapter: run with --radio")
    for item in items:
        if "radio" in item.keywords:
            item.add_marker(skip)


@pytest.fixture
def unwritable_dir(tmp_path: Path) -> Path:
    """A folder no file can be created in, for root too: /proc (chmod does not stop root)."""
    if os.geteuid() == 0:
        return Path("/proc")
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o555)
    return folder


@pytest.fixture
def no_resent_interrupt(monkeypatch: pytest.MonkeyPatch) -> None:
    """For a test that sends itself SIGINT: the watchdog it starts sends none again.

    ``_interrupt``'s watchdog re-sends an interrupt nobody acknowledged every
    ``RESEND_S``; on a loaded machine (one pytest worker per core) that 0.2 s
    can pass before the test's ``restore()``, and a re-sent SIGINT would then
    end the test process. The re-sending is tested in subprocesses.
    """
    from swarmtag import _interrupt

    monkeypatch.setattr(_interrupt, "RESEND_S", 3600.0)
