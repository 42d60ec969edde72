"""The Mann-Whitney tests of a command, in a process that imports scipy.stats as it starts.

Importing scipy.stats takes about half a second, longer than the rest of
the statistics of a usual ``simulate``. Forked before the command loads its
compiled code (one core busy, the other idle), the process imports it
beside the command; when the command's statistics come to the tests, it sends the
samples there and gets the p-values back: scipy's own arithmetic, the same
bits. Where no process can be forked (``swarmtag._beside.can_fork``), the
command imports scipy.stats itself, as before.

Once per process: one that runs command after command (the tests, a script
calling ``swarmtag.cli.main``) would otherwise import scipy.stats afresh in
a new child for each, and wait for it; from its second command on (or once
scipy.stats is imported) it tests in process, importing scipy.stats once.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Iterator
from contextlib import contextmanager

from swarmtag.analysis.compare import Samples, mann_whitney_by, mann_whitney_ps

__all__ = ["tests_beside"]


class _Tester:
    """A ``swarmtag._beside.Service``: imports scipy.stats, then tests the samples it is sent."""

    def prepare(self) -> None:
        """Import scipy.stats (half a second) before the first samples come."""
        importlib.import_module("scipy.stats")

    def answer(self, item: Samples) -> list[float | None]:
        """The p-values of the samples, as the command would have computed them."""
        return mann_whitney_ps(item)


_STATE = {"forked": False}
"""Whether this process has forked a tester yet (module docstring: once per process)."""


@contextmanager
def tests_beside(comparing: bool) -> Iterator[None]:
    """Within this block, Mann-Whitney tests run in a forked process (if ``comparing``).

    Not where scipy.stats is imported already, nor after a first such block in this process.
    """
    if not comparing or _STATE["forked"] or "scipy.stats" in sys.modules:
        yield
        return
    _STATE["forked"] = True
    from swarmtag._beside import beside  # noqa: PLC0415 - multiprocessing: 15 ms, when forking

    with beside(_Tester()) as children:
        if not children:
            yield
            return
        with mann_whitney_by(children[0].ask):
            yield
