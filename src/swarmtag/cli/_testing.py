"""The Mann-Whitney tests of a command, in a process that imports scipy.stats as it starts.

Importing scipy.stats takes about half a second, longer than the rest of
the statistics of a usual ``simulate``. Forked before the command loads its
compiled code (one core busy, the other idle), the process imports it
beside the command; when the command's statistics come to the tests, it sends the
samples there and gets the p-values back: scipy's own arithmetic, the same
bits. Where no process can be forked (``swarmtag._beside.can_fork``), the
command imports scipy.stats itself, as before.
"""

from __future__ import annotations

import importlib
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


@contextmanager
def tests_beside(comparing: bool) -> Iterator[None]:
    """Within this block, Mann-Whitney tests run in a forked process (if ``comparing``)."""
    if not comparing:
        yield
        return
    from swarmtag._beside import beside  # noqa: PLC0415 - multiprocessing: 15 ms, when forking

    with beside(_Tester()) as children:
        if not children:
            yield
            return
        with mann_whitney_by(children[0].ask):
            yield
