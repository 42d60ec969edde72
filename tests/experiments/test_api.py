"""``swarmtag.experiments`` exports exactly its public names, and importing it stays light."""

from __future__ import annotations

import importlib
import subprocess
import sys


def test_all_is_the_public_namespace():
    module = importlib.import_module("swarmtag.experiments")
    public = {
        name
        for name, value in vars(module).items()
        if not name.startswith("_") and not isinstance(value, type(importlib))
        and name != "annotations"
    }  # fmt: skip
    assert set(module.__all__) == public


def test_duckdb_is_imported_only_when_a_store_opens():
    code = (
        "import sys, swarmtag.experiments, swarmtag.cli; "
        "swarmtag.experiments.load_study('scalability'); "
        "print('duckdb' in sys.modules, 'distributed' in sys.modules)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, check=True, text=True)
    assert out.stdout.split() == ["False", "False"]
