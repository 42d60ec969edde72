"""swarmtag: urgency-aware robot-swarm intralogistics.

Smart BLE tags on carriers broadcast how urgent their item is; robots hear
them and each decides on its own which carrier to fetch. This package holds
the tag protocol (``swarmtag.tag``), the selection policies
(``swarmtag.policy``) and the tools built on them: the simulator
(``swarmtag.sim``), event logs (``swarmtag.io``) and their analysis
(``swarmtag.analysis``).

The main entry points are offered here too, imported on first use so that
``import swarmtag`` stays cheap (no numpy, no pandas)::

    import swarmtag

    result = swarmtag.simulate(conditions=["proximity", "urgency:alpha=0.7"], runs=10, seed=3)
    result.kpis(), result.compare()      # pandas DataFrames (the pandas extra)
    log = swarmtag.read_event_log("trial.csv")
    report = swarmtag.summarize(log)
    scenario = swarmtag.Scenario.default(5, 10)
    policy = swarmtag.parse_policy("urgency:alpha=0.7")

``simulate`` is the notebook API of SPEC §8.5 (``swarmtag.notebook``:
several conditions in one call, results as DataFrames; docs/notebook.md).
``Scenario``, ``load_profile`` and ``BUILTIN`` are ``swarmtag.sim``'s,
``parse_policy`` is ``swarmtag.policy``'s, ``read_event_log``
``swarmtag.io``'s and ``summarize`` ``swarmtag.analysis``'s. The
simulator's own entry point, one condition at a time with its event logs as
arrays, is ``swarmtag.sim.simulate(scenario, policy, ...)``.
"""

from __future__ import annotations

TYPE_CHECKING = False  # not typing's: importing typing would delay the CLI's SIGINT handler
if TYPE_CHECKING:
    from swarmtag.analysis import summarize
    from swarmtag.io import read_event_log
    from swarmtag.notebook import simulate
    from swarmtag.policy import parse_policy
    from swarmtag.sim import BUILTIN, Scenario, load_profile

__all__ = [
    "BUILTIN",
    "Scenario",
    "__version__",
    "load_profile",
    "parse_policy",
    "read_event_log",
    "simulate",
    "summarize",
]

__version__: str
"""The installed version, looked up on first use (see ``__getattr__``)."""

_LAZY = {
    "BUILTIN": "swarmtag.sim",
    "Scenario": "swarmtag.sim",
    "load_profile": "swarmtag.sim",
    "parse_policy": "swarmtag.policy",
    "read_event_log": "swarmtag.io",
    "simulate": "swarmtag.notebook",
    "summarize": "swarmtag.analysis",
}
"""The entry points offered here, by the module that defines them (imported on first use)."""


def __getattr__(name: str) -> object:
    """``__version__`` and the entry points of ``_LAZY``, imported when first asked for.

    Lazy because they are heavy: the entry points bring numpy, and even
    ``importlib.metadata`` (for ``__version__``) takes tens of milliseconds;
    until ``swarmtag.cli.main`` has installed its SIGINT handler a Ctrl-C
    ends in a traceback, so the command line must reach it as fast as it can.
    """
    if name == "__version__":
        value: object = _version()
    elif name in _LAZY:
        import importlib  # noqa: PLC0415 - see above

        value = getattr(importlib.import_module(_LAZY[name]), name)
    else:
        msg = f"module {__name__!r} has no attribute {name!r}"
        raise AttributeError(msg)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The module's names, the lazy ones included."""
    return sorted({*globals(), *__all__})


def _version() -> str:
    """The installed distribution's version (``0+unknown`` in a source tree)."""
    from importlib import metadata  # noqa: PLC0415 - see __getattr__

    try:
        return metadata.version("swarmtag")
    except metadata.PackageNotFoundError:  # pragma: no cover - source tree, not installed
        return "0+unknown"
