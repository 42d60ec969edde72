"""Run the docstring examples of every module: documentation that cannot drift."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import swarmtag

OPTIONAL = {
    "swarmtag.tag.backends.bleak": "bleak",
    "swarmtag.tag.backends.bleak_writer": "bleak",
    "swarmtag.tag.backends.bless": "bless",
    "swarmtag.tag.backends.loopback": "bleak",
}
"""Modules that need an extra: skipped (not failed) where it is not installed."""
MODULES = sorted(info.name for info in pkgutil.walk_packages(swarmtag.__path__, prefix="swarmtag."))


@pytest.mark.parametrize("name", MODULES)
def test_module_doctests(name):
    if name in OPTIONAL:
        pytest.importorskip(OPTIONAL[name])
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0, f"{result.failed} doctest(s) failed in {name}"
