"""Small calibration problems for the tests: tiny simulations (two runs of 150 ticks)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from swarmtag.calibration import CalibrationProblem, KpiTarget, Setup, Targets, parse_free
from swarmtag.sim.config.profiles import load_profile

DATA = Path(__file__).parent / "data"
SMALL_TARGETS = DATA / "small-targets.toml"


def tiny_setup(name: str = "tiny", runs: int = 2, **scenario: Any) -> Setup:
    return Setup(
        name=name,
        runs=runs,
        scenario={"robots": 3, "carriers": 7, "ticks": 150, **scenario},
        kpis=(
            KpiTarget("p95_latency", value=300.0, low=250.0, high=350.0),
            KpiTarget("deliveries_per_run", value=1.5, low=1.0, high=2.0),
        ),
    )


def tiny_targets(*setups: Setup, **changes: Any) -> Targets:
    fields: dict[str, Any] = {
        "name": "tiny",
        "description": "tiny",
        "condition": "proximity",
        "seed": 0,
        "setups": setups or (tiny_setup(),),
        "source": "tiny.toml",
        "source_digest": "0" * 16,
    }
    return Targets(**{**fields, **changes})


def tiny_problem(*free: str, targets: Targets | None = None, **changes: Any) -> CalibrationProblem:
    fields: dict[str, Any] = {
        "targets": targets or tiny_targets(),
        "profile": load_profile("base"),
        "free": tuple(parse_free(text) for text in (free or ("timing.dock=0.5:8:log",))),
        "model": "test-model",
    }
    return CalibrationProblem(**{**fields, **changes})
