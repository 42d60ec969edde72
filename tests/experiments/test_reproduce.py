"""``swarmtag reproduce --seeds K``: one seed as before, K seeds judged, stored, resumed; bad K."""

from __future__ import annotations

import json
import re

import pytest

from swarmtag._checks import MAX_SEED
from swarmtag.cli import main
from swarmtag.errors import StudyError
from swarmtag.experiments import (
    MAX_SEEDS,
    STORE_NAME,
    ResultsStore,
    load_study,
    reproduce,
    run_study,
    seed_folder,
    seeded_study,
    study_key,
)
from swarmtag.experiments.directions import CLOSE_MARGIN, SIGNIFICANCE
from swarmtag.experiments.report import StudyRecord, write_report, write_run_record

from .helpers import SMALL_TOML, write_study

# A tiny study under the scalability study's name, so that its published
# directions (every size, close, growing with size) judge it.
TINY_SCALABILITY = (
    SMALL_TOML.replace('name = "small"', 'name = "scalability"')
    .replace("quick_runs = 2", "quick_runs = 4")
    .replace("resamples = 50", "resamples = 200")
    .replace("[scenario]\nrobots = 3\ncarriers = 7\n", "")
    + '\n[scales."3x7"]\nrobots = 3\ncarriers = 7\n'
    + '\n[scales."4x8"]\nrobots = 4\ncarriers = 8\nticks = 200\n'
)
_WALL = re.compile(r"\d+\.\d s")


def cli(capsys, *argv):
    with pytest.raises(SystemExit) as exited:
        main(list(argv))
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def reproduce_cli(capsys, source, out, *extra):
    return cli(capsys, "reproduce", "--quick", "--study", str(source), "--out", str(out),
               "--workers", "1", "--no-progress", *extra)  # fmt: skip


def tree(folder):
    """Every file under ``folder`` by relative path, wall times and the store's bytes left out."""
    files = {}
    for path in sorted(folder.rglob("*")):
        if not path.is_file() or path.name == STORE_NAME:
            continue
        data = path.read_bytes()
        if path.name == "run.json":
            record = json.loads(data)
            record.pop("wall_time_s")
            data = json.dumps(record).encode()
        elif path.name == "report.html":
            data = _WALL.sub("<wall>", data.decode()).encode()
        files[path.relative_to(folder).as_posix()] = data
    return files


def test_one_seed_is_the_reproduction_as_it_was(tmp_path, capsys):
    source = write_study(tmp_path, TINY_SCALABILITY)
    study = load_study(source)
    # The reproduction as the command line composed it before --seeds existed.
    before = tmp_path / "before"
    result = run_study(study, out_dir=before, quick=True, workers=1)
    record = StudyRecord(wall_time_s=1.0, quick=True, computed_runs=result.computed_runs,
                         reused_runs=result.reused_runs)  # fmt: skip
    write_run_record(before, study, record)
    write_report(before, [study], computed=[result])
    code, plain, _ = reproduce_cli(capsys, source, tmp_path / "plain")
    assert code == 0
    code, one, _ = reproduce_cli(capsys, source, tmp_path / "one", "--seeds", "1")
    assert code == 0
    assert _WALL.sub("", one) == _WALL.sub("", plain).replace(str(tmp_path / "plain"),
                                                             str(tmp_path / "one"))  # fmt: skip
    assert plain.splitlines()[0].startswith("scalability: 16 runs computed, 0 reused, ")
    expected = tree(before)
    assert tree(tmp_path / "plain") == expected
    assert tree(tmp_path / "one") == expected
    assert "seeds.json" not in expected


def per_seed_metrics(out, offset, scale):
    path = seed_folder(out, offset) / "scalability" / scale / "metrics.json"
    return json.loads(path.read_text())


def comparison(metrics, metric):
    return next(c for c in metrics["comparisons"] if c["metric"] == metric)


def baseline_value(metrics, metric):
    return next(c for c in metrics["conditions"] if c["condition"] == "proximity")[metric]["value"]


# What each scalability claim reads, written out again here as the test's own oracle.
TRENDS = {"pa-gain-grows": "pa", "p95-gain-grows": "p95_latency",
          "throughput-cost-shrinks": "throughput"}  # fmt: skip
CLOSE = {"throughput-close": "throughput", "deliveries-close": "deliveries_per_run"}
SHIFTS = {"pa-raised": ("pa", 1), "p95-lowered": ("p95_latency", -1)}


def relative(metrics, metric):
    return comparison(metrics, metric)["diff"] / baseline_value(metrics, metric)


def check_against_metrics(out, claim, offset, entry):
    """A seed's judged parts are those of that seed's metrics.json, by the declared rules."""
    name = claim["direction"]
    for judged in entry["parts"]:
        if name in TRENDS:  # the two ends, first -> last
            first, last = (per_seed_metrics(out, offset, s) for s in judged["scale"].split("->"))
            change = relative(last, TRENDS[name]) - relative(first, TRENDS[name])
            assert judged["value"] == pytest.approx(change)
            continue
        metrics = per_seed_metrics(out, offset, judged["scale"])
        if name in CLOSE:
            value = relative(metrics, CLOSE[name])
            assert judged["value"] == pytest.approx(value)
            assert judged["appears"] == (abs(value) <= CLOSE_MARGIN)
            continue
        metric, sign = SHIFTS[name]
        found = comparison(metrics, metric)
        assert judged["value"] == found["diff"]
        assert judged["p_bootstrap"] == found["p_bootstrap"]
        assert judged["appears"] == (sign * found["diff"] > 0)
        assert judged["significant"] == (judged["appears"] and found["p_bootstrap"] < SIGNIFICANCE)


@pytest.mark.first
def test_k_seeds_are_stored_apart_judged_and_resumed(tmp_path, capsys):
    source = write_study(tmp_path, TINY_SCALABILITY)
    out = tmp_path / "out"
    code, text, err = reproduce_cli(capsys, source, out, "--seeds", "2")
    assert (code, err) == (0, "")
    lines = text.splitlines()
    assert lines[0].startswith("scalability (seed 0): 16 runs computed, 0 reused, ")
    assert lines[1].startswith("scalability (seed 1): 16 runs computed, 0 reused, ")
    # one line per claim of the scalability study, then the files and the report
    assert len(lines) == 2 + 7 + 3
    assert lines[2].startswith(
        "urgency-aware selection raises PA at every alpha and every scale [scalability]: "
        "appears in "
    )
    assert lines[-3:-1] == [f"seeds summary: {out / 'seeds.json'}",
                            f"seeds summary: {out / 'seeds.md'}"]  # fmt: skip
    # every seed's runs in the one store, under their own master seed
    with ResultsStore(out / STORE_NAME, read_only=True) as store:
        study = load_study(source)
        for offset in (0, 1):
            seeded = seeded_study(study, offset)
            assert seeded.seed == offset
            key = study_key(seeded, "4x8")
            assert store.stored_runs(key, "proximity") == {0, 1, 2, 3}
        assert store.count_runs() == 2 * 16
    # seed 0 where a single seed goes; seed 1 beside it, with its own report
    assert (out / "scalability" / "3x7" / "metrics.json").is_file()
    assert (out / "seed+1" / "scalability" / "20x40").exists() is False
    assert (out / "seed+1" / "scalability" / "4x8" / "tables.md").is_file()
    assert "master seed</dt><dd>1<" in (out / "seed+1" / "report.html").read_text()
    assert per_seed_metrics(out, 0, "3x7") != per_seed_metrics(out, 1, "3x7")
    summary = json.loads((out / "seeds.json").read_text())
    assert summary["seeds"] == {"scalability": [0, 1]}
    assert len(summary["claims"]) == 7
    for claim in summary["claims"]:
        assert claim["seeds"] == [0, 1]
        assert claim["appeared"] == sum(entry["appears"] for entry in claim["per_seed"])
        assert claim["significant"] == sum(entry["significant"] for entry in claim["per_seed"])
        for offset, entry in enumerate(claim["per_seed"]):
            assert entry["appears"] == all(part["appears"] for part in entry["parts"])
            check_against_metrics(out, claim, offset, entry)
    markdown = (out / "seeds.md").read_text()
    assert "| the throughput cost shrinks with swarm size | scalability |" in markdown
    assert "over 2 master seeds" in (out / "report.html").read_text()
    # a third seed: the first two come from the store, the summary keeps their outcomes
    code, text, _ = reproduce_cli(capsys, source, out, "--seeds", "3")
    assert code == 0
    lines = text.splitlines()
    assert lines[0].startswith("scalability (seed 0): 0 runs computed, 16 reused, ")
    assert lines[1].startswith("scalability (seed 1): 0 runs computed, 16 reused, ")
    assert lines[2].startswith("scalability (seed 2): 16 runs computed, 0 reused, ")
    again = json.loads((out / "seeds.json").read_text())
    for old, new in zip(summary["claims"], again["claims"], strict=True):
        assert new["per_seed"][:2] == old["per_seed"]


@pytest.mark.first
def test_an_interrupted_k_seed_run_resumes(tmp_path):
    study = load_study(write_study(tmp_path, TINY_SCALABILITY))
    out = tmp_path / "out"

    def stop_after_seed_one(run):
        if run.offset == 1:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        reproduce([study], out_dir=out, seeds=3, quick=True, workers=1,
                  on_study=stop_after_seed_one)  # fmt: skip
    assert not (out / "seeds.json").exists()
    done = reproduce([study], out_dir=out, seeds=3, quick=True, workers=1)
    assert [(r.seed, r.computed_runs, r.reused_runs) for r in done.runs] == [
        (0, 0, 16), (1, 0, 16), (2, 16, 0),
    ]  # fmt: skip
    assert done.summary_files == (out / "seeds.json", out / "seeds.md")
    assert [s.seeds for s in done.robustness] == [(0, 1, 2)] * 7
    # the same as a run never interrupted
    fresh = reproduce([study], out_dir=tmp_path / "fresh", seeds=3, quick=True, workers=1)
    assert fresh.summary_files[0].read_text() == done.summary_files[0].read_text()


@pytest.mark.parametrize(
    ("value", "message"),
    [
        ("0", "'--seeds': 0 is not in the range x>=1"),
        ("-2", "'--seeds'"),
        ("two", "'--seeds': 'two' is not a valid integer"),
        (str(MAX_SEEDS + 1), f"--seeds: {MAX_SEEDS + 1} is not an integer in 1-{MAX_SEEDS}"),
        (str(10**30), f"--seeds: {10**30} is not an integer in 1-{MAX_SEEDS}"),
    ],
)
def test_a_bad_seed_count_is_one_line_and_exit_2(tmp_path, capsys, value, message):
    source = write_study(tmp_path, TINY_SCALABILITY)
    out = tmp_path / "out"
    code, text, err = reproduce_cli(capsys, source, out, "--seeds", value)
    assert (code, text) == (2, "")
    assert err.startswith("swarmtag: error: ")
    assert len(err.strip().splitlines()) == 1
    assert message in err
    assert not out.exists()  # refused before any work


def test_seeds_past_the_largest_master_seed_are_refused_before_any_work(tmp_path):
    study = load_study(write_study(tmp_path, TINY_SCALABILITY))
    last = seeded_study(study, MAX_SEED)
    assert last.seed == MAX_SEED
    with pytest.raises(StudyError, match=r"--seeds 2: study scalability starts at master seed"):
        reproduce([last], out_dir=tmp_path / "out", seeds=2)
    with pytest.raises(StudyError, match="--seeds: 0 is not"):
        reproduce([study], out_dir=tmp_path / "out", seeds=0)
    assert not (tmp_path / "out").exists()
