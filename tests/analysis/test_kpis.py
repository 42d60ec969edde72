"""KPIs of SPEC §5 against values worked out by hand (the same example as docs/metrics.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from swarmtag.analysis import (
    ConditionRuns,
    condition_kpis,
    latency_by_urgency,
    run_values,
    split_conditions,
)
from swarmtag.io import CarrierLog
from tests.io.strategies import carrier_logs, log_from_rows, permuted

# The worked example of docs/metrics.md: one condition, three runs.
#
# run 0, n = 5          urgency0  order  delivery  latency
#   carrier 1               9      -10      12        22
#   carrier 2               7       -6      30        36
#   carrier 3               7       -8      20        28   (urgency tie with 2: earlier order first)
#   carrier 4               2       -2      20        22   (delivery tie with 3: marker 3 first)
#   carrier 5               0        0     never       -
# run 1, n = 3
#   carrier 1               5       -4      10        14   (the run's only delivery)
#   carrier 2               8       -9     never       -
#   carrier 3               1        0     never       -
# run 2, n = 2
#   carrier 1               3       -1      15        16   (first == last delivery time)
#   carrier 2               3       -1      15        16
WORKED = [
    ("proximity", 0, 1, 9, -10.0, 12.0),
    ("proximity", 0, 2, 7, -6.0, 30.0),
    ("proximity", 0, 3, 7, -8.0, 20.0),
    ("proximity", 0, 4, 2, -2.0, 20.0),
    ("proximity", 0, 5, 0, 0.0, None),
    ("proximity", 1, 1, 5, -4.0, 10.0),
    ("proximity", 1, 2, 8, -9.0, None),
    ("proximity", 1, 3, 1, 0.0, None),
    ("proximity", 2, 1, 3, -1.0, 15.0),
    ("proximity", 2, 2, 3, -1.0, 15.0),
]


@pytest.fixture
def worked() -> ConditionRuns:
    return ConditionRuns.from_log(log_from_rows(WORKED), "proximity")


def test_pooled_latency(worked):
    kpis = condition_kpis(run_values(worked))
    # Pooled latencies, sorted: 14, 16, 16, 22, 22, 28, 36 -> mean 154 / 7 = 22.
    assert kpis.mean_latency == 22.0
    # P95: position 0.95 * (7 - 1) = 5.7 -> 28 + 0.7 * (36 - 28) = 33.6.
    assert kpis.p95_latency == pytest.approx(33.6, rel=1e-12)


def test_throughput_only_from_runs_that_have_one(worked):
    values = run_values(worked)
    # Run 0: 100 * 4 / (30 - 12) = 200 / 9; run 1 has one delivery; run 2 has t_last == t_first.
    assert values.throughput[0] == pytest.approx(200 / 9, rel=1e-15)
    assert np.isnan(values.throughput[1:]).all()
    assert condition_kpis(values).throughput == pytest.approx(200 / 9, rel=1e-15)


def test_deliveries_and_undelivered(worked):
    kpis = condition_kpis(run_values(worked))
    assert kpis.runs == 3
    assert kpis.total_deliveries == 7
    assert kpis.deliveries_per_run == pytest.approx(7 / 3)
    assert kpis.undelivered == 3


def test_priority_alignment(worked):
    values = run_values(worked)
    # Run 0 (n = 5): k = 1,1,1,1,2,2,2,2,3,3 for p = 5..50; PA = 1 at k = 1 and 2,
    # 2/3 at k = 3 (top {1,3,2}, first {1,3,4}): mean (8 + 4/3) / 10 = 28/30.
    # Run 1 (n = 3): k = 1 for p <= 30 (PA 0: top {2}, first {1}), k = 2 for p >= 35 (PA 1/2).
    # Run 2 (n = 2): k = 1 everywhere; both ties pick marker 1 -> PA 1.
    assert values.pa == pytest.approx([28 / 30, 6 / 30, 1.0], rel=1e-12)
    assert condition_kpis(values).pa == pytest.approx(32 / 45, rel=1e-12)


def test_per_run_latency_values(worked):
    values = run_values(worked)
    assert values.mean_latency == pytest.approx([27.0, 14.0, 16.0])
    assert values.p95_latency == pytest.approx(
        [np.percentile([22, 36, 28, 22], 95), 14.0, 16.0], rel=1e-15
    )
    assert values.deliveries.tolist() == [4, 1, 2]
    assert values.carriers.tolist() == [5, 3, 2]


def test_condition_without_deliveries_has_no_latency_or_throughput():
    log = log_from_rows([("c", 0, 1, 5, -1.0, None), ("c", 1, 1, 5, -1.0, None)])
    kpis = condition_kpis(run_values(ConditionRuns.from_log(log, "c")))
    assert kpis.p95_latency is None
    assert kpis.mean_latency is None
    assert kpis.throughput is None
    assert kpis.pa == 0.0
    assert kpis.deliveries_per_run == 0.0
    assert kpis.undelivered == 2


def test_latency_by_urgency():
    rows = [*WORKED, ("proximity", 3, 1, 9, -30.0, 10.0)]
    levels = latency_by_urgency(ConditionRuns.from_log(log_from_rows(rows), "proximity"))
    assert [level.urgency for level in levels] == list(range(10))
    nine = levels[9]
    # Urgency 9: run 0 carrier 1 (22) and run 3 carrier 1 (40).
    assert (nine.carriers, nine.delivered, nine.mean, nine.median) == (2, 2, 31.0, 31.0)
    assert nine.p95 == pytest.approx(22 + 0.95 * 18)
    eight = levels[8]  # run 1 carrier 2, never delivered
    assert (eight.carriers, eight.delivered, eight.undelivered, eight.mean) == (1, 0, 1, None)
    assert levels[4].carriers == 0


def _figures(log: CarrierLog) -> dict[str, tuple[object, ...]]:
    result = {}
    for name, runs in split_conditions(log).items():
        kpis = condition_kpis(run_values(runs))
        result[name] = (
            kpis.runs,
            kpis.p95_latency,
            kpis.mean_latency,
            kpis.throughput,
            kpis.pa,
            kpis.deliveries_per_run,
            kpis.total_deliveries,
            kpis.undelivered,
        )
    return result


def _close(first: dict[str, tuple[object, ...]], second: dict[str, tuple[object, ...]]) -> bool:
    if first.keys() != second.keys():
        return False
    for name, figures in first.items():
        for a, b in zip(figures, second[name], strict=True):
            if (a is None) != (b is None):
                return False
            if a is not None and not math.isclose(a, b, rel_tol=1e-12, abs_tol=1e-12):
                return False
    return True


@given(carrier_logs(), st.integers(0, 2**32 - 1))
def test_permuting_rows_changes_nothing(log, seed):
    assert _figures(permuted(log, seed)) == _figures(log)


@given(carrier_logs(), st.integers(0, 2**32 - 1))
def test_renaming_runs_changes_nothing(log, seed):
    ids = np.unique(log.run)
    new_ids = np.random.default_rng(seed).permutation(10_000)[: ids.size]
    columns = log.columns()
    columns["run"] = new_ids[np.searchsorted(ids, log.run)]
    renamed = CarrierLog(**columns, time_unit=log.time_unit)
    assert _close(_figures(renamed), _figures(log))


@given(carrier_logs())
def test_duplicating_every_run_keeps_run_averages(log):
    columns = log.columns()
    offset = int(log.run.max()) + 1
    doubled = CarrierLog(
        **{name: np.concatenate([column, column]) for name, column in columns.items()}
        | {"run": np.concatenate([log.run, log.run + offset])},
        time_unit=log.time_unit,
    )
    for name, runs in split_conditions(log).items():
        once = condition_kpis(run_values(runs))
        twice = condition_kpis(run_values(ConditionRuns.from_log(doubled, name)))
        assert twice.runs == 2 * once.runs
        assert twice.total_deliveries == 2 * once.total_deliveries
        for metric in ("mean_latency", "throughput", "pa", "deliveries_per_run"):
            a, b = once.value(metric), twice.value(metric)
            assert (a is None) == (b is None)
            if a is not None:
                assert b == pytest.approx(a, rel=1e-12, abs=1e-12), metric


def test_kpis_scale_to_a_hundred_thousand_runs():
    # 10^5 runs of 7 carriers: vectorised over runs (this would take minutes with a loop per run).
    rng = np.random.default_rng(3)
    n_runs, per_run = 100_000, 7
    rows = n_runs * per_run
    delivered = rng.random(rows) < 0.9
    delivery = np.where(delivered, rng.integers(1, 3000, rows).astype(float), np.nan)
    log = CarrierLog(
        condition=np.full(rows, "proximity"),
        run=np.repeat(np.arange(n_runs), per_run),
        seed=np.zeros(rows, dtype=np.int64),
        carrier=np.tile(np.arange(per_run), n_runs),
        urgency0=rng.integers(0, 10, rows),
        order_time=-rng.integers(0, 3000, rows).astype(float),
        pickup_time=delivery,
        delivery_time=delivery,
        robot=np.where(delivered, 0, -1),
    )
    values = run_values(ConditionRuns.from_log(log, "proximity"))
    kpis = condition_kpis(values)
    latency = delivery[delivered] - log.order_time[delivered]
    assert kpis.mean_latency == pytest.approx(latency.mean(), rel=1e-12)
    assert kpis.p95_latency == np.percentile(latency, 95)
    assert kpis.total_deliveries == int(delivered.sum())
    # Spot-check a few runs against a direct computation.
    for run in (0, 4_321, 99_999):
        block = slice(run * per_run, (run + 1) * per_run)
        times = np.sort(delivery[block][delivered[block]])
        expected = (
            100 * times.size / (times[-1] - times[0])
            if times.size >= 2 and times[-1] > times[0]
            else np.nan
        )
        assert values.throughput[run] == pytest.approx(expected, nan_ok=True)


@settings(max_examples=60)
@given(carrier_logs())
def test_the_kaplan_meier_p95_is_scipys(log):
    from scipy import stats

    for runs in split_conditions(log).values():
        values = run_values(runs)
        censored = values.censored
        sample = stats.CensoredData(
            uncensored=censored.values[censored.observed], right=censored.values[~censored.observed]
        )
        cdf = stats.ecdf(sample).cdf
        reached = np.flatnonzero(cdf.probabilities >= 0.95 - 1e-9)
        expected = float(cdf.quantiles[reached[0]]) if reached.size else None
        assert condition_kpis(values).km_p95_latency == expected
