"""A seeded fuzzer of the public library API: hostile values in, a result or a swarmtag error out.

Every public function of ``swarmtag.analysis``, ``swarmtag.calibration``,
``swarmtag.policy``, ``swarmtag.robot``, ``swarmtag.notebook``,
``swarmtag.io``, ``swarmtag.perception`` and ``swarmtag.experiments`` (and
the policies' and a few records' constructors) is called with arguments drawn per call: each one is
a valid value or, with a chance drawn per call (so that some calls are
wholly valid and reach deep), a hostile one: NaN, infinities, -1, 0, huge
integers, ``1e308``, ``-0.0``, booleans, ``None``, strings, empty and nested
lists, arrays holding NaN or ``±1e308``, objects of the wrong kind. A call
must return, or raise a ``SwarmtagError``: never a bare ``ValueError``,
``TypeError``, ``IndexError``, ``ZeroDivisionError`` or any other
exception, never a numpy ``RuntimeWarning`` (nonsense that got through),
never a confidence interval with ``low > high``, and never run past
``HANG_SECONDS``. A completeness check makes sure that a new public function
cannot skip the sweep (``SKIPPED`` names the few that are not called, and
why).

The seed is 0 unless pinned, and printed with every failure; ask for more
calls (the long mode) with ``SWARMTAG_API_FUZZ_CALLS``::

    SWARMTAG_FUZZ_SEED=7 SWARMTAG_API_FUZZ_CALLS=20000 pytest -q tests/test_api_fuzz.py
"""

from __future__ import annotations

import importlib
import inspect
import math
import os
import signal
import tempfile
import time
import warnings
from collections import Counter
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from swarmtag.errors import SwarmtagError

SEED = int(os.environ.get("SWARMTAG_FUZZ_SEED", "0"))
"""Seed of the generator (``SWARMTAG_FUZZ_SEED``)."""
CALLS = int(os.environ.get("SWARMTAG_API_FUZZ_CALLS", "0")) or 600
"""Calls in all (``SWARMTAG_API_FUZZ_CALLS``): a few seconds in the normal suite."""
HANG_SECONDS = 20
"""One call running longer than this is reported as a hang."""
BADNESS = (0.05, 0.2, 0.5, 0.9)
"""Chances that each argument of a call is a hostile one, one drawn per call."""
PACKAGES = (
    "swarmtag.analysis",
    "swarmtag.calibration",
    "swarmtag.policy",
    "swarmtag.robot",
    "swarmtag.notebook",
    "swarmtag.io",
    "swarmtag.perception",
    "swarmtag.experiments",
)
"""The packages whose public functions are fuzzed here (``swarmtag.tag``: tests/tag)."""


class Wrong:
    """An object of no kind any function takes."""

    def __repr__(self) -> str:
        return "Wrong()"


HOSTILE: tuple[object, ...] = (
    math.nan, math.inf, -math.inf, -1, 0, -5, 10**30, -(10**30), 2**63, 1e308, -1e308, -0.0,
    1e-320, 2.5, 101, True, False, None, "", "x", "\0", "proximity", b"\x00", [], [[1, 2]], {},
    [math.nan], [1e308, -1e308], [math.inf], ["a", 1], (1, "b"), np.array([]),
    np.array([math.nan, 1.0]), np.array([[1.0]]), np.int64(-3), np.float32("nan"), Wrong(),
    10**5000, range(3), Path("/proc/nope"), lambda *_: None,
)  # fmt: skip
"""Values that are wrong (or at an edge) for most parameters."""


@dataclass(frozen=True)
class Target:
    """A public callable and the valid values it is fuzzed with, by parameter (in order).

    A keyword-only parameter (or one for ``**kwargs``) is passed by its name;
    the others by position (their keys here are only labels).
    """

    name: str
    function: Callable[..., Any]
    valid: Mapping[str, tuple[object, ...]]
    keyword: frozenset[str] = frozenset()

    def call(self, arguments: Mapping[str, object]) -> object:
        parameters = inspect.signature(self.function).parameters
        kinds = {p.kind for p in parameters.values()}
        only = {n for n, p in parameters.items() if p.kind is inspect.Parameter.KEYWORD_ONLY}
        if inspect.Parameter.VAR_KEYWORD in kinds:  # scenario overrides (notebook.simulate)
            only |= set(arguments) - set(parameters)
        positional = [v for k, v in arguments.items() if k not in only]
        named = {k: v for k, v in arguments.items() if k in only}
        return self.function(*positional, **named)


# --- the valid values: small inputs built once ---------------------------------------------


@cache
def world() -> dict[str, Any]:
    """Small valid inputs: a log of two conditions, its tables, statistics, targets, a tree."""
    from swarmtag.analysis import (
        censored_latencies,
        condition_kpis,
        condition_statistics,
        run_values,
        split_conditions,
    )
    from swarmtag.calibration import KpiTarget, load_baseline
    from swarmtag.io import CarrierLog, EventTable
    from swarmtag.policy import Proximity, Urgency
    from swarmtag.robot import ControllerConfig, create_tree
    from swarmtag.sim import load_profile, make_params, simulate

    scenario = load_profile("base").scenario({"robots": 2, "carriers": 3, "ticks": 300})
    results = [simulate(scenario, p, seed=0, runs=3) for p in (Proximity(), Urgency(alpha=0.7))]
    log = CarrierLog.concat([r.carriers for r in results])
    events = EventTable.concat([r.events for r in results])
    runs = split_conditions(log)
    first, second = (runs[name] for name in log.conditions)
    stats = [condition_statistics(r, n_resamples=20) for r in (first, second)]
    values = run_values(first)
    folder = Path(tempfile.mkdtemp(prefix="api-fuzz-"))
    targets_file = folder / "targets.toml"
    from tests.cli.fuzz_files import TINY_TARGETS

    targets_file.write_text(TINY_TARGETS, encoding="utf-8")
    targets = load_baseline(str(targets_file))
    target = KpiTarget("pa", value=0.3, low=0.2, high=0.4)
    config = ControllerConfig.from_params(make_params(scenario, Proximity()))
    return {
        "log": log,
        "events": events,
        "runs": first,
        "other_runs": second,
        "stats": stats,
        "values": values,
        "kpis": condition_kpis(values),
        "latencies": censored_latencies(first),
        "targets": targets,
        "targets_file": targets_file,
        "target": target,
        "config": config,
        "tree": create_tree(config),
        "folder": folder,
    }


def analysis_targets(w: dict[str, Any]) -> list[Target]:
    import swarmtag.analysis as a

    log, runs, events = w["log"], w["runs"], w["events"]
    names = log.conditions
    levels = (0.5, 0.9, 0.95, 0.99)
    statistics = {"n_resamples": (1, 5, 20), "seed": (0, 3), "confidence_level": levels}
    kw = frozenset({"n_resamples", "seed", "confidence_level", "compiled", "log", "conditions"})
    return [
        Target("alignment_k", a.alignment_k, {"p": (0, 35, 100), "n": ([20, 7, 1], [0])}),
        Target("bootstrap_p_value", a.bootstrap_p_value, {"d": ([1.0, -2.0], [math.nan, 0.0])}),
        Target("censored_latencies", a.censored_latencies, {"runs": (runs,)}),
        Target(
            "choice_statistics",
            a.choice_statistics,
            {"events": (events,), "log": (None, log), "conditions": (None, names), **statistics},
            kw,
        ),
        Target("choose_baseline", a.choose_baseline, {"c": (names,), "r": (None, names[0])}),
        Target(
            "compare",
            a.compare,
            {"c": (w["stats"][1],), "b": (w["stats"][0],), "metric": ("pa", "p95_latency")},
        ),
        Target("compare_all", a.compare_all, {"c": (w["stats"][1],), "b": (w["stats"][0],)}),
        Target("condition_kpis", a.condition_kpis, {"values": (w["values"],)}),
        Target("condition_seed_sequence", a.condition_seed_sequence, {"s": (0, 7), "c": names}),
        Target(
            "condition_statistics",
            a.condition_statistics,
            {
                "runs": (runs,),
                **statistics,
                "curve_thresholds": ((5, 50), a.CURVE_THRESHOLDS),
                "curve_percentiles": ((0, 50.5, 100),),
                "compiled": (None, False),
            },
            kw | {"curve_thresholds", "curve_percentiles"},
        ),
        Target(
            "double_pursuits",
            a.double_pursuits,
            {
                "run": (events.run,),
                "time": (events.time,),
                "kind": (events.kind,),
                "carrier": (events.carrier,),
                "robot": (events.robot,),
            },
        ),
        Target("km_quantile", a.km_quantile, {"lat": (w["latencies"],), "q": (0, 50, 95, 100)}),
        Target("latency_by_urgency", a.latency_by_urgency, {"r": (runs,), "l": ((9, 0), [5])}),
        Target("mann_whitney_p", a.mann_whitney_p, {"x": ([1.0, 2.0],), "y": ([3.0, math.nan],)}),
        Target(
            "percentile_interval",
            a.percentile_interval,
            {"rep": ([1.0, 5.0, math.nan], np.arange(9.0)), "confidence_level": levels},
            frozenset({"confidence_level"}),
        ),
        Target(
            "priority_alignment",
            a.priority_alignment,
            {"runs": (runs,), "t": ((5, 50),), "urgency": (None, runs.urgency0)},
            frozenset({"urgency"}),
        ),
        Target("run_ends", a.run_ends, {"runs": (runs,)}),
        Target("run_values", a.run_values, {"runs": (runs,), "curve_thresholds": ((5,),)}, kw),
        Target("split_conditions", a.split_conditions, {"log": (log,)}),
        Target(
            "summarize",
            a.summarize,
            {"log": (log,), "baseline": (None, names[1]), **statistics, "compiled": (False,)},
            kw | {"baseline"},
        ),
        Target("trim_warmup", a.trim_warmup, {"log": (log,), "warmup": (0, 0.5)}),
        Target(
            "undelivered_differs", a.undelivered_differs, {"c": (w["kpis"],), "b": (w["kpis"],)}
        ),
    ]


def calibration_targets(w: dict[str, Any]) -> list[Target]:
    import swarmtag.calibration as c

    target, targets = w["target"], w["targets"]
    achieved = {setup.name: {"pa": 0.3} for setup in targets.setups}
    rows = c.fit_rows(targets, achieved)
    digest = ("0123456789abcdef",)
    return [
        Target("check_evaluations", c.check_evaluations, {"n": (1, 5000)}),
        Target("default_cache_path", c.default_cache_path, {"out": (Path("out/lab.toml"),)}),
        Target("fit_rows", c.fit_rows, {"targets": (targets,), "achieved": (achieved,)}),
        Target("half_width", c.half_width, {"target": (target,), "achieved": (0.1, 0.5)}),
        Target("load_baseline", c.load_baseline, {"text": (str(w["targets_file"]),)}),
        Target("objective", c.objective, {"rows": (rows, ())}),
        Target("parse_free", c.parse_free, {"text": ("timing.dock=0.5:8:log",)}),
        Target("parse_free_list", c.parse_free_list, {"texts": (["tick=0.05:0.2"],)}),
        Target("read_target_file", c.read_target_file, {"path": (w["targets_file"],)}),
        Target("residual", c.residual, {"target": (target,), "achieved": (None, 0.35)}),
        Target(
            "search",
            c.search,
            {
                "evaluate": (lambda points: [float(sum(p)) for p in points],),
                "dims": (1, 2),
                "budget": (1, 4),
                "seed": (0,),
            },
            frozenset({"budget", "seed"}),
        ),
        Target("target_kpis", c.target_kpis, {}),
        Target("target_path", c.target_path, {"name": ("lab",)}),
        Target(
            "targets_from_log",
            c.targets_from_log,
            {
                "log": (w["log"],),
                "source": ("x.csv",),
                "source_digest": digest,
                "condition": (None, "proximity"),
            },
            frozenset({"source", "source_digest", "condition"}),
        ),
    ]


def policy_targets(w: dict[str, Any]) -> list[Target]:
    import swarmtag.policy as p

    floats = (np.array([1.0, 2.0]),)
    urgency = {"urgency": floats, "distance": floats, "marker": (np.array([1, 2]),)}
    return [
        Target("Urgency", p.Urgency, {"alpha": (0.7, 9.0)}),
        Target("Weighted", p.Weighted, {"w": (0.0, 0.5)}),
        Target("Threshold", p.Threshold, {"theta": (5.0,)}),
        Target("Adaptive", p.Adaptive, {"rate": (0.1,)}),
        Target("Candidate", p.Candidate, {"m": (7,), "u": (9,), "d": (2.7, math.inf)}),
        Target(
            "best_of",
            p.best_of,
            {
                "scores": floats,
                "distance": floats,
                "marker": (np.array([1, 2]),),
                "available": (None, np.array([True, False])),
            },
            frozenset({"distance", "marker", "available"}),
        ),
        Target("choose", p.choose, {"p": (p.Proximity(),), "c": ([p.Candidate(7, 9, 2.7)], [])}),
        Target("kernel_score", p.kernel_score, {"k": (0, 1), "a": (0.5,), "u": (4.0,), "d": (1,)}),
        Target("parse_policy", p.parse_policy, {"name": ("proximity", "urgency:alpha=0.7")}),
        Target("proximity_term", p.proximity_term, {"d": (1.8, [0.0, 9.0])}),
        Target("registered_rule", p.registered_rule, {"name": ("nope",)}),
        Target("rule_entry_points", p.rule_entry_points, {}),
        Target(
            "select",
            p.select,
            {"policy": (p.Urgency(alpha=0.7),), **urgency, "available": (None,)},
            frozenset(urgency) | {"available"},
        ),
    ]


def robot_targets(w: dict[str, Any]) -> list[Target]:
    import swarmtag.notebook as n
    import swarmtag.robot as r

    cheap = {"profile": ("base",), "runs": (1,), "resamples": (5,), "ticks": (20,)}
    return [
        Target("ascii_picture", r.ascii_picture, {"tree": (w["tree"],)}),
        Target("create_tree", r.create_tree, {"config": (w["config"],), "ns": ("/robot",)}),
        Target(
            "dot_picture",
            r.dot_picture,
            {"tree": (w["tree"],), "folder": (w["folder"],), "name": ("tree",)},
        ),
        Target(
            "tag_states",
            r.tag_states,
            {"sightings": ({}, []), "carriers": (1, 3), "now": (0.0, 5.0), "tick": (0.1,)},
            frozenset({"carriers", "now", "tick"}),
        ),
        Target(
            "notebook.simulate",
            n.simulate,
            {**cheap, "seed": (0,), "conditions": (None, "proximity"), "baseline": (None,)},
            frozenset({*cheap, "seed", "conditions", "baseline"}),
        ),
    ]


@cache
def edge_world() -> dict[str, Any]:
    """Valid inputs of the io, perception and experiments functions: files, a rig, a study."""
    from swarmtag.experiments import ResultsStore, load_study
    from swarmtag.io import format_csv, write_event_log, write_event_table
    from swarmtag.perception import Placement, detect_markers, load_rig, render

    w = world()
    folder = Path(tempfile.mkdtemp(prefix="api-fuzz-edge-"))
    for suffix in ("csv", "parquet"):
        write_event_log(w["log"], folder / f"log.{suffix}")
        write_event_table(w["events"], folder / f"events.{suffix}")
    rig = load_rig()
    front = rig.camera("front")
    placement = Placement.at(7, 1.0, 0.0)
    image = render(front, rig.carrier, [placement], rng=np.random.default_rng(0))
    study = load_study("controller-selection")
    return {
        "folder": folder,
        "log_csv": format_csv(w["log"]),
        "events_csv": format_csv(w["events"]),
        "rig": rig,
        "front": front,
        "placement": placement,
        "image": image,
        "detections": detect_markers(image, front, rig.carrier),
        "study": study,
        "store": ResultsStore(folder / "results.duckdb"),
    }


def io_targets(w: dict[str, Any]) -> list[Target]:
    import swarmtag.io as i

    e = edge_world()
    folder = e["folder"]
    tables = (w["log"], w["events"])
    logs = (folder / "log.csv", folder / "log.parquet")
    events = (folder / "events.csv", folder / "events.parquet")
    out = (str(folder / "out.csv"), folder / "out.parquet")
    source = frozenset({"source"})
    return [
        Target("format_csv", i.format_csv, {"table": tables}),
        Target("parse_carrier_csv", i.parse_carrier_csv, {"t": (e["log_csv"],), "source": (None, "x.csv")}, source),
        Target("parse_event_csv", i.parse_event_csv, {"t": (e["events_csv"],), "source": (None,)}, source),
        Target("read_carrier_csv", i.read_carrier_csv, {"path": logs[:1]}),
        Target("read_carrier_parquet", i.read_carrier_parquet, {"path": logs[1:]}),
        Target("read_event_csv", i.read_event_csv, {"path": events[:1]}),
        Target("read_event_parquet", i.read_event_parquet, {"path": events[1:]}),
        Target("read_event_log", i.read_event_log, {"path": logs}),
        Target("read_event_table", i.read_event_table, {"path": events}),
        Target("write_csv", i.write_csv, {"table": tables, "path": out[:1]}),
        Target("write_parquet", i.write_parquet, {"table": tables, "path": out[1:]}),
        Target("write_event_log", i.write_event_log, {"log": tables[:1], "path": out}),
        Target("write_event_table", i.write_event_table, {"table": tables[1:], "path": out}),
        Target("CarrierLog.concat", i.CarrierLog.concat, {"tables": ([w["log"]],)}),
        Target("EventTable.concat", i.EventTable.concat, {"tables": ([w["events"]],)}),
    ]  # fmt: skip


def few_samples(rig: object, *, samples: object, **kwargs: Any) -> object:
    """``run_range_study`` with a legal count above 3 (an image takes a second) drawn as 3."""
    from swarmtag.perception import run_range_study

    if isinstance(samples, int) and not isinstance(samples, bool) and 3 < samples < 10**6:
        samples = 3
    return run_range_study(rig, samples=samples, **kwargs)


def perception_targets(w: dict[str, Any]) -> list[Target]:
    import swarmtag.perception as p

    e = edge_world()
    rig, front, carrier = e["rig"], e["front"], e["rig"].carrier
    placements = ([e["placement"]], [])
    mapping = {
        "name": "x",
        "cameras": [
            {
                "name": "front",
                "kind": "perimeter",
                "width": 64,
                "height": 48,
                "horizontal_fov": 90.0,
                "x": 0.1,
                "y": 0.0,
                "z": 0.1,
            }
        ],
    }
    return [
        Target("centring_offset", p.centring_offset, {"d": (e["detections"], []), "m": (None, 7)}),
        Target("detect_markers", p.detect_markers, {"i": (e["image"],), "c": (front,), "k": (carrier,)}),
        Target("fuse", p.fuse, {"d": (e["detections"],), "k": (carrier,), "heading": (None, 0.0)}, frozenset({"heading"})),
        Target("load_rig", p.load_rig, {"name": ("dots-like", "dots")}),
        Target("marker_frames", p.marker_frames, {"carrier": (carrier,)}),
        Target("read_rig_file", p.read_rig_file, {"path": (p.rig_path("dots"),)}),
        Target(
            "render",
            p.render,
            {"c": (front,), "k": (carrier,), "p": placements, "n": (p.Conditions(),),
             "rng": (np.random.default_rng(0),)},
            frozenset({"rng"}),
        ),
        Target("rig_from_mapping", p.rig_from_mapping, {"data": (mapping,), "source": (None, "x")}, frozenset({"source"})),
        Target("rig_path", p.rig_path, {"name": ("dots",)}),
        Target(
            "run_range_study",
            few_samples,
            {"rig": (rig,), "distances": ((1.0,),), "bearings": ((0.0,),), "samples": (1,),
             "seed": (0,), "marker": (7,)},
            frozenset({"distances", "bearings", "samples", "seed", "marker"}),
        ),
        Target("to_gray", p.to_gray, {"image": (e["image"],), "camera": (front,)}),
        Target(
            "visible_markers",
            p.visible_markers,
            {"c": (front,), "k": (carrier,), "p": placements, "margin": (1.0, 0.0)},
            frozenset({"margin"}),
        ),
        Target("Intrinsics.from_fov", p.Intrinsics.from_fov, {"w": (64,), "h": (48,), "fov": (90.0,)}),
        Target("Placement.at", p.Placement.at, {"m": (7,), "d": (1.0,), "b": (0.0,), "t": (0.0,)}),
    ]  # fmt: skip


def experiments_targets(w: dict[str, Any]) -> list[Target]:
    import swarmtag.experiments as x

    e = edge_world()
    study, folder = e["study"], e["folder"]
    scale = study.scales[0]
    return [
        Target("kpi_log", x.kpi_log, {"log": (w["log"],), "scale": (scale,)}),
        Target("load_study", x.load_study, {"name": ("controller-selection",)}),
        Target("plan_chunks", x.plan_chunks, {"study": (study,), "store": (e["store"],), "quick": (True,)}, frozenset({"quick"})),
        Target("read_study_file", x.read_study_file, {"path": (x.study_path("scalability"),)}),
        Target("seed_folder", x.seed_folder, {"out": (folder,), "offset": (0, 3)}),
        Target("seeded_study", x.seeded_study, {"study": (study,), "offset": (0, 3)}),
        Target("split_runs", x.split_runs, {"runs": ([0, 1, 2, 5],), "size": (1, 2)}),
        Target("study_key", x.study_key, {"study": (study,), "scale": (scale.key,)}),
        Target("study_path", x.study_path, {"name": ("scalability",)}),
        Target("Study.from_mapping", x.Study.from_mapping, {"data": ({"name": "x"},)}),
    ]  # fmt: skip


SKIPPED = {
    "swarmtag.calibration.calibrate": "runs simulations for each point; refusals: test_calibrate",
    "swarmtag.calibration.fit_table": "takes a finished calibration only (type checked)",
    "swarmtag.calibration.markdown_report": "takes a finished calibration only (type checked)",
    "swarmtag.policy.check_rule": "runs a rule of one's own; tests/policy/test_check.py",
    "swarmtag.policy.load_checked_rule": "imports Python files; tests/policy/test_rules.py",
    "swarmtag.policy.load_rule": "imports Python files; tests/policy/test_rules.py",
    "swarmtag.policy.register_rule": "changes the process's registry; tests/policy",
    "swarmtag.robot.check_controller": "is swarmtag.sim.check_controller (tests/sim)",
    "swarmtag.perception.plot_range_study": "draws a figure (seconds); test_bad_arguments",
    "swarmtag.perception.run_range_study": "fuzzed as few_samples: at most 3 images per cell",
    "swarmtag.experiments.reproduce": "runs whole studies; tests/experiments/test_bad_arguments.py",
    "swarmtag.experiments.run_study": "runs a whole study; tests/experiments/test_bad_arguments.py",
    "swarmtag.experiments.simulate_chunk": "runs simulations; tests/experiments/test_bad_arguments",
}
"""Public functions not called here, and why."""


@cache
def targets() -> tuple[Target, ...]:
    w = world()
    return tuple(
        analysis_targets(w)
        + calibration_targets(w)
        + policy_targets(w)
        + robot_targets(w)
        + io_targets(w)
        + perception_targets(w)
        + experiments_targets(w)
    )


# --- drawing, calling and judging ----------------------------------------------------------


def draw(rng: np.random.Generator, target: Target) -> dict[str, object]:
    badness = BADNESS[rng.integers(len(BADNESS))]
    arguments = {}
    for name, good in target.valid.items():
        pool = HOSTILE if rng.random() < badness else good
        arguments[name] = pool[rng.integers(len(pool))]
    return arguments


class Hang(BaseException):
    """A call ran past ``HANG_SECONDS``."""


def _alarm(_signum: int, _frame: object) -> None:
    raise Hang


def intervals(result: object) -> Iterator[tuple[str, object]]:
    """The confidence intervals in a result: its own, its estimates', its comparisons'."""
    from swarmtag.analysis import ConditionStatistics, ConfidenceInterval, MetricsReport

    if isinstance(result, ConfidenceInterval):
        yield "result", result
    found = getattr(result, "confidence_interval", None)
    if isinstance(found, ConfidenceInterval):
        yield "confidence_interval", found
    if isinstance(result, ConditionStatistics):
        for metric in result.metrics:
            yield metric, result.estimate(metric).confidence_interval
    if isinstance(result, MetricsReport):
        for comparison in result.comparisons:
            yield comparison.metric, comparison.confidence_interval
        for condition in result.conditions:
            yield from intervals(condition)


def show(arguments: Mapping[str, object]) -> str:
    parts = []
    for name, value in arguments.items():
        huge = isinstance(value, int) and value.bit_length() > 64
        text = f"<int of {value.bit_length()} bits>" if huge else repr(value)  # type: ignore[union-attr]
        parts.append(f"{name}={text[:80]}")
    return ", ".join(parts)


def judge(target: Target, arguments: dict[str, object]) -> str | None:
    """What went wrong in one call, or None."""
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, HANG_SECONDS)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            result = target.call(arguments)
    except SwarmtagError:
        return None
    except Hang:
        return f"ran past {HANG_SECONDS} s"
    except BaseException as exc:  # noqa: BLE001 - anything else is the bug looked for
        return f"raised {type(exc).__name__}: {str(exc)[:300]}"
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    for where, ci in intervals(result):
        low, high = ci.low, ci.high  # type: ignore[attr-defined]
        if low is not None and high is not None and not low <= high:
            return f"gave an inverted interval at {where}: {low!r} > {high!r}"
    return None


# --- the tests ------------------------------------------------------------------------------


def public_functions() -> set[str]:
    found = set()
    for package in PACKAGES:
        module = importlib.import_module(package)
        for name in module.__all__:
            if inspect.isfunction(getattr(module, name)):
                found.add(f"{package}.{name}")
    return found


def test_every_public_function_is_fuzzed_or_skipped_with_a_reason():
    fuzzed = set()
    for target in targets():
        module = inspect.getmodule(target.function)
        short = target.name.removeprefix("notebook.")
        for package in PACKAGES:
            if getattr(importlib.import_module(package), short, None) is target.function:
                fuzzed.add(f"{package}.{short}")
        assert module is not None
    missing = public_functions() - fuzzed - set(SKIPPED)
    assert not missing, f"public functions neither fuzzed nor skipped: {sorted(missing)}"
    assert not set(SKIPPED) & fuzzed


def test_public_api_fuzz(tmp_path, monkeypatch):
    chosen = targets()
    monkeypatch.chdir(tmp_path)  # a hostile path such as "x" is written here, not in the tree
    rng = np.random.default_rng(SEED)
    counts: Counter[str] = Counter()
    started = time.perf_counter()
    for _ in range(CALLS):
        target = chosen[rng.integers(len(chosen))]
        arguments = draw(rng, target)
        counts[target.name] += 1
        problem = judge(target, arguments)
        if problem is not None:
            pytest.fail(
                f"{target.name}({show(arguments)}) {problem}\n"
                f"  seed: SWARMTAG_FUZZ_SEED={SEED} (calls: SWARMTAG_API_FUZZ_CALLS={CALLS})",
                pytrace=False,
            )
    took = time.perf_counter() - started
    print(f"api fuzz: {CALLS} calls over {len(counts)} functions in {took:.1f} s, seed {SEED}")
