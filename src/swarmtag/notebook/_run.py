"""``simulate``: the conditions of a notebook run on one scenario, then summarized.

The same runs and numbers as ``swarmtag simulate --condition A --condition B
--runs N --seed S --json``: the scenario is the profile with the overrides on
top, each condition's runs come from ``swarmtag.sim.simulate`` (run ``i`` is
the same in any batch), and the statistics are ``swarmtag.analysis.summarize``
with the master seed. Every input is checked before the first run.
"""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Iterable, Mapping, Sequence
from typing import Final

from swarmtag._checks import MAX_RESAMPLES, MAX_RUN_INDEX, MAX_SEED, check_int, show
from swarmtag._resources import check_memory
from swarmtag.analysis import summarize
from swarmtag.analysis.resampling import bootstrap_memory
from swarmtag.errors import ConfigError, PolicyError, StatisticsError
from swarmtag.io import CarrierLog, EventTable
from swarmtag.notebook._result import PANDAS_HINT, NotebookResult, check_baseline
from swarmtag.policy import Policy, load_checked_rule, parse_policy
from swarmtag.sim import DEFAULT_PROFILE, Backend, Controller, Profile, Scenario, load_profile
from swarmtag.sim import simulate as simulate_runs
from swarmtag.sim.runner import LOG_BYTES_PER_CARRIER, batch_memory
from swarmtag.sim.simulation import backend_for

__all__ = ["CHUNK_RUNS", "simulate"]

CHUNK_RUNS: Final = 50
"""Runs simulated per call: bounds memory (results do not depend on it)."""
_LONGEST_NAME: Final = 200
"""Longer condition names are refused before they are parsed (and shown cut)."""
_LONGEST_RULE: Final = 4096
"""Longer ``FILE.py:FUNCTION`` specs are refused before a file is looked for."""
_LONGEST_MESSAGE: Final = 400
"""A scenario refusal longer than this is shown cut in the middle (a value's repr can be huge)."""


def _require_pandas() -> None:
    """Refuse at once, not after the runs, where pandas (the ``pandas`` extra) is missing."""
    if importlib.util.find_spec("pandas") is None:
        raise ImportError(PANDAS_HINT)


def _named(given: object, what: str) -> list[object]:
    """One item (a name, a policy) or a list of them, as a list."""
    if isinstance(given, str | Policy):
        return [given]
    if not isinstance(given, Iterable) or isinstance(given, Mapping | bytes):
        msg = f"{what}: a {type(given).__name__} is not a name or a list of names"
        raise PolicyError(msg)
    return list(given)


def _policy(item: object, where: str) -> Policy:
    """A condition given as a name or a ``swarmtag.policy.Policy``."""
    if isinstance(item, Policy):
        return item
    if not isinstance(item, str):
        msg = f"{where}: a {type(item).__name__} is not a condition name or a Policy"
        raise PolicyError(msg)
    if len(item) > _LONGEST_NAME:
        msg = f"{where}: {show(item)} ({len(item)} characters) is not a condition name"
        raise PolicyError(msg)
    return parse_policy(item)


def _rule(item: object, where: str) -> Policy:
    """A score rule of one's own, ``FILE.py:FUNCTION`` (checked as ``--policy-file`` is)."""
    if not isinstance(item, str) or len(item) > _LONGEST_RULE:
        shown = show(item) if isinstance(item, str) else f"a {type(item).__name__}"
        msg = f"{where}: {shown} is not FILE.py:FUNCTION"
        raise PolicyError(msg)
    return load_checked_rule(item)


def _policies(conditions: object, policy_files: object) -> list[Policy]:
    """The conditions to run, in order: the named ones, then the rule files; none twice."""
    if conditions is None:
        from swarmtag.cli.simulate import DEFAULT_CONDITIONS  # noqa: PLC0415 - the command's

        conditions = DEFAULT_CONDITIONS
    named = _named(conditions, "conditions")
    chosen = [_policy(item, f"conditions[{i}]") for i, item in enumerate(named)]
    rules = _named(policy_files, "policy_files")
    chosen += [_rule(item, f"policy_files[{i}]") for i, item in enumerate(rules)]
    if not chosen:
        raise PolicyError("conditions: the list is empty; name at least one condition")
    names = [policy.name for policy in chosen]
    repeated = sorted({name for name in names if names.count(name) > 1})
    if repeated:
        raise PolicyError(f"condition given twice: {', '.join(repeated)}")
    return chosen


def _bounded(message: str) -> str:
    """``message`` cut in the middle to at most about ``_LONGEST_MESSAGE`` characters."""
    if len(message) <= _LONGEST_MESSAGE:
        return message
    half = _LONGEST_MESSAGE // 2
    return f"{message[:half]} ... {message[-half:]}"


def _scenario_keys(overrides: Mapping[str, object]) -> dict[str, object]:
    """Keyword overrides as scenario keys: ``camera__range``, ``camera_range``: ``camera.range``.

    Besides the scenario's own keys (``robots``, ``ticks``, ``camera={...}``),
    a double underscore is a dot, and the named flags of ``swarmtag simulate``
    (``camera_range``, ``urgency_model``, ...) set the key they set there.
    """
    from swarmtag.cli._scenario import SCENARIO_FLAGS  # noqa: PLC0415 - the flags' one table

    keys: dict[str, object] = {}
    given: dict[str, str] = {}
    for name, value in overrides.items():
        key = SCENARIO_FLAGS.get(name, name.replace("__", "."))
        if key in given:
            msg = f"{given[key]} and {name} both set the scenario key {key}; give one"
            raise ConfigError(msg)
        given[key] = name
        keys[key] = value
    return keys


def _scenario(profile: object, overrides: Mapping[str, object]) -> tuple[Profile, Scenario]:
    """The profile (a name, a file or a ``Profile``) with the overrides on top."""
    if isinstance(profile, Profile):
        chosen = profile
    elif isinstance(profile, str | os.PathLike):
        chosen = load_profile(profile)
    else:
        msg = f"profile: a {type(profile).__name__} is not a profile name, file or Profile"
        raise ConfigError(msg)
    try:
        return chosen, chosen.scenario(_scenario_keys(overrides))
    except ConfigError as error:
        raise ConfigError(_bounded(str(error))) from None


def _check_work(
    scenario: Scenario, conditions: int, runs: int, resamples: int, backend: str
) -> None:
    """Refuse runs whose logs, or a bootstrap whose values, cannot fit in memory (before a run)."""
    check_memory(
        f"runs={runs} of {conditions} condition(s) with {scenario.carriers} carriers",
        conditions * runs * scenario.carriers * LOG_BYTES_PER_CARRIER
        + batch_memory(scenario, min(runs, CHUNK_RUNS), backend=backend),
        error=ConfigError,
    )
    check_memory(
        f"resamples={resamples} over {conditions} condition(s)",
        bootstrap_memory(resamples, conditions=conditions, width=max(1, runs * scenario.carriers)),
        error=StatisticsError,
    )


def _run(
    scenario: Scenario,
    policies: Sequence[Policy],
    *,
    seed: int,
    runs: int,
    run_offset: int,
    controller: Controller | str,
    backend: Backend | str | None,
) -> tuple[CarrierLog, EventTable]:
    """Every condition's runs, in chunks; the logs of all conditions, concatenated."""
    logs: list[CarrierLog] = []
    tables: list[EventTable] = []
    for policy in policies:
        for start in range(0, runs, CHUNK_RUNS):
            result = simulate_runs(
                scenario,
                policy,
                seed=seed,
                runs=min(CHUNK_RUNS, runs - start),
                run_offset=run_offset + start,
                controller=controller,
                backend=backend,
            )
            logs.append(result.carriers)
            tables.append(result.events)
    return CarrierLog.concat(logs), EventTable.concat(tables)


def simulate(
    *,
    profile: str | os.PathLike[str] | Profile = DEFAULT_PROFILE,
    conditions: str | Policy | Sequence[str | Policy] | None = None,
    runs: int = 30,
    seed: int = 0,
    run_offset: int = 0,
    policy_files: str | Sequence[str] = (),
    baseline: str | None = None,
    resamples: int = 10_000,
    controller: Controller | str = "builtin",
    backend: Backend | str | None = None,
    **scenario_overrides: object,
) -> NotebookResult:
    """Simulate several conditions on one scenario; KPIs and comparisons as DataFrames.

    ``profile``: a shipped profile's name, a profile file or a
    ``swarmtag.sim.Profile``; ``scenario_overrides`` go on top of it, as
    ``swarmtag simulate``'s flags do: scenario keys (``robots=5``,
    ``ticks=600``, ``camera={"range": 2.0}``), ``part__key`` for one key of
    a part (``camera__range=2.0``), or the command's flag names
    (``camera_range=2.0``). ``conditions``: names (``"urgency:alpha=0.7"``)
    or ``swarmtag.policy.Policy`` objects, default proximity and
    urgency:alpha=0.7; ``policy_files`` adds rules of one's own
    (``"rules.py:urgency_first"``). ``runs`` runs per condition from
    ``run_offset`` under master ``seed``, which also seeds the bootstrap
    (``resamples`` resamples); ``baseline`` is what ``compare()`` compares
    with by default. ``controller`` and ``backend`` are passed to
    ``swarmtag.sim.simulate`` (a controller object serves every batch: give
    a stateless one, or a name).

    Run ``i`` gives the same rows as ``swarmtag simulate --run-offset i
    --runs 1`` with the same seed, and the report the same numbers as its
    ``--json``. Bad input is one short ``ValueError`` (a ``SwarmtagError``)
    naming what was wrong, raised before any run; without pandas, an
    ``ImportError`` naming the ``pandas`` extra.
    """
    _require_pandas()
    runs = check_int("runs", runs, low=1, high=MAX_RUN_INDEX)
    seed = check_int("seed", seed, low=0, high=MAX_SEED)
    run_offset = check_int("run_offset", run_offset, low=0, high=MAX_RUN_INDEX - runs)
    resamples = check_int("resamples", resamples, low=1, high=MAX_RESAMPLES, error=StatisticsError)
    policies = _policies(conditions, policy_files)
    names = tuple(policy.name for policy in policies)
    chosen = check_baseline(names, baseline)
    used, scenario = _scenario(profile, scenario_overrides)
    resolved = backend_for(controller, backend).name  # a bad name or a missing extra, first
    if resolved == "fast" and all(not policy.compiled for policy in policies):
        resolved = "reference"  # every condition falls back (simulate warns)
    _check_work(scenario, len(policies), runs, resamples, resolved)
    log, table = _run(
        scenario,
        policies,
        seed=seed,
        runs=runs,
        run_offset=run_offset,
        controller=controller,
        backend=backend,
    )
    return NotebookResult(
        report=summarize(log, baseline=chosen, n_resamples=resamples, seed=seed),
        log=log,
        table=table,
        scenario=scenario,
        profile=used.name,
        conditions=names,
        runs=runs,
        seed=seed,
        run_offset=run_offset,
    )
