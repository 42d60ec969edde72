"""Shared test configuration: Hypothesis profiles, the opt-in ``--radio`` tests, a locked folder."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, settings

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


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
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
