"""``swarmtag.calibration`` exports exactly its public namespace, and its modules stay small."""

from __future__ import annotations

import importlib
from pathlib import Path

import swarmtag.calibration


def test_all_is_the_public_namespace():
    module = swarmtag.calibration
    public = {
        attr
        for attr, value in vars(module).items()
        if not attr.startswith("_")
        and not isinstance(value, type(importlib))
        and attr != "annotations"
    }
    assert set(module.__all__) == public
    for attr in module.__all__:
        assert hasattr(module, attr)


def test_no_module_is_a_god_module():
    folder = Path(swarmtag.calibration.__file__).parent
    for path in folder.glob("*.py"):
        assert len(path.read_text(encoding="utf-8").splitlines()) <= 500, path.name
