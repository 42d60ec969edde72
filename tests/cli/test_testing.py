"""Mann-Whitney tests in a process forked as a command starts: scipy.stats imported there, the
same p-values here."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from swarmtag._beside import can_fork

_SCRIPT = """
import json, sys
import numpy as np
from swarmtag.analysis import ConditionRuns, compare_all, condition_statistics
from swarmtag.cli._testing import tests_beside
from tests.io.strategies import log_from_rows

rng = np.random.default_rng(3)
rows = [("a", run, 1, 5, 0.0, float(x)) for run, x in enumerate(rng.exponential(60, 30))]
rows += [("b", run, 1, 5, 0.0, float(x)) for run, x in enumerate(rng.exponential(40, 30))]
rows += [("b", 30 + run, 1, 5, 0.0, float(x)) for run, x in enumerate(rng.exponential(40, 4))]
log = log_from_rows(rows)
base, other = (
    condition_statistics(ConditionRuns.from_log(log, name), n_resamples=20) for name in "ab"
)
found = []
for _ in range(2):  # the second block tests here: the process imports scipy.stats once
    with tests_beside(comparing=sys.argv[1] == "beside"):
        ps = [c.p_mannwhitney for c in compare_all(other, base)]
    found.append({"ps": [None if p is None else p.hex() for p in ps],
                  "imported": "scipy.stats" in sys.modules})
print(json.dumps(found))
"""


def _ps(where: str) -> list[dict[str, object]]:
    done = subprocess.run(
        [sys.executable, "-c", _SCRIPT, where],
        cwd=Path(__file__).parents[2],  # the tests' helpers
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(done.stdout)


@pytest.mark.skipif(not can_fork(), reason="forks on Linux only")
def test_the_p_values_come_from_the_forked_process_bit_for_bit_once_a_process():
    (beside, again), (here, _) = _ps("beside"), _ps("here")
    assert here["imported"]
    assert not beside["imported"]  # scipy.stats was imported in the forked process only
    assert again["imported"]  # a second command in the process: tested here
    assert beside["ps"] == here["ps"] == again["ps"]
    assert sum(p is not None for p in here["ps"]) >= 6  # type: ignore[union-attr]
