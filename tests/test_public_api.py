"""What each package exports is exactly what is public, and every export exists."""

from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

PACKAGES = [
    "swarmtag",
    "swarmtag.tag",
    "swarmtag.tag.backends",
    "swarmtag.policy",
    "swarmtag.errors",
    "swarmtag.cli",
    "swarmtag.io",
    "swarmtag.analysis",
    "swarmtag.data",
    "swarmtag.sim",
    "swarmtag.robot",
    "swarmtag.experiments",
    "swarmtag.calibration",
    "swarmtag.perception",
    "swarmtag.notebook",
]


@pytest.mark.parametrize("name", PACKAGES)
def test_all_is_the_public_namespace(name):
    module = importlib.import_module(name)
    public = {
        attr
        for attr, value in vars(module).items()
        if not attr.startswith("_")
        and not isinstance(value, type(importlib))
        and attr not in {"annotations", "TYPE_CHECKING"}  # typing sentinels, not API
    }
    # names a module imports on first use (its ``__getattr__``) are public too
    lazy = {attr for attr in module.__all__ if attr not in public}
    if "__getattr__" not in vars(module):
        lazy &= {"__version__"}
    assert set(module.__all__) == public | lazy
    for attr in module.__all__:
        assert hasattr(module, attr), f"{name}.__all__ names missing {attr}"


def test_error_tree_is_rooted():
    from swarmtag import errors

    for attr in errors.__all__:
        kind = getattr(errors, attr)
        if issubclass(kind, Warning):  # the notes (BackendFallback) are warnings, not errors
            assert issubclass(kind, UserWarning)
        else:
            assert issubclass(kind, errors.SwarmtagError)


ENTRY_POINTS = {
    "BUILTIN": "swarmtag.sim",
    "Scenario": "swarmtag.sim",
    "load_profile": "swarmtag.sim",
    "parse_policy": "swarmtag.policy",
    "read_event_log": "swarmtag.io",
    "simulate": "swarmtag.notebook",
    "summarize": "swarmtag.analysis",
}
"""What ``import swarmtag`` offers (on first use), by home module."""


def test_import_swarmtag_stays_light():
    # a fresh interpreter (this one has numpy already): the entry points wait until asked for
    script = (
        "import sys, swarmtag; "
        "print(sorted({'numpy', 'pandas', 'swarmtag.sim', 'swarmtag.notebook'} & set(sys.modules)))"
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, check=True, timeout=60
    )
    assert done.stdout.strip() == "[]"


@pytest.mark.parametrize(("name", "home"), sorted(ENTRY_POINTS.items()))
def test_entry_points_are_their_home_modules_objects(name, home):
    import swarmtag

    assert name in swarmtag.__all__
    assert name in dir(swarmtag)
    assert getattr(swarmtag, name) is getattr(importlib.import_module(home), name)


def test_the_top_level_offers_the_entry_points_and_the_version_only():
    import swarmtag

    assert set(swarmtag.__all__) == {*ENTRY_POINTS, "__version__"}
    with pytest.raises(AttributeError, match="has no attribute 'nope'"):
        _ = swarmtag.nope
