"""What each package exports is exactly what is public, and every export exists."""

from __future__ import annotations

import importlib

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
        assert issubclass(getattr(errors, attr), errors.SwarmtagError)
