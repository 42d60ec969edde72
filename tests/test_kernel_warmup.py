"""The statistics warm-up compiles every loop a real summary then uses: nothing is left to compile.

``make demo`` runs ``python -m tests.kernel_warmup statistics`` during its
install so that the demo's first ``simulate`` loads the bootstrap's machine
code instead of compiling it. Checked in a numba cache folder of its own: a
summary of simulated runs (some carriers undelivered, so the censored and
Kaplan-Meier paths run) after the warm-up adds no file to that folder.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

pytest.importorskip("numba")

ROOT = Path(__file__).resolve().parent.parent

SUMMARY = """
from dataclasses import replace

from swarmtag.analysis import summarize
from swarmtag.io import CarrierLog
from swarmtag.policy import parse_policy
from swarmtag.sim import Scenario, simulate

scenario = replace(Scenario.default(3, 7), ticks=2000)
logs = [
    simulate(scenario, parse_policy(name), seed=0, runs=6, backend="reference").carriers
    for name in ("proximity", "urgency:alpha=0.7")
]
log = CarrierLog.concat(logs)
assert 0 < int(log.delivery_time.size - (log.delivery_time >= 0).sum()) < log.delivery_time.size
report = summarize(log, n_resamples=300, compiled=True)
assert [c.diff for c in report.comparisons if c.metric == "km_p95_latency"] != [None]
"""


def _cached(folder: Path) -> set[str]:
    return {path.name for path in folder.rglob("*") if path.suffix in {".nbi", ".nbc"}}


def _run(code: list[str], cache: Path) -> None:
    environment = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    subprocess.run(
        [sys.executable, *code], cwd=ROOT, env=environment, check=True, capture_output=True
    )


@pytest.mark.first
def test_statistics_warmup_leaves_nothing_for_a_summary_to_compile(tmp_path: Path) -> None:
    _run(["-m", "tests.kernel_warmup", "statistics"], tmp_path)
    warmed = _cached(tmp_path)
    assert any(name.startswith("_compiled.km_reached") for name in warmed)
    _run(["-c", SUMMARY], tmp_path)
    assert _cached(tmp_path) == warmed
