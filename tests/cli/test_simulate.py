"""``swarmtag simulate``: conditions, outputs, determinism through the CLI, bad input."""

from __future__ import annotations

import json
import os
import re
import signal

import numpy as np
import pytest
from PIL import Image

from swarmtag._beside import can_fork
from swarmtag._threads import default_threads
from swarmtag.analysis import METRICS
from swarmtag.cli import main
from swarmtag.io import read_event_log

SMALL = ["--profile", "base", "--ticks", "400", "--resamples", "200", "--no-progress"]
"""The fast base world: these tests are about the command, not the model."""
DRAWS_BESIDE = pytest.mark.skipif(
    not can_fork(), reason="pictures are drawn in forked processes on Linux only"
)
"""For the tests of the drawing processes (elsewhere the command draws in its own)."""


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(["simulate", *argv])
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def test_json_has_every_condition_and_comparison(capsys):
    code, out, _ = run(
        capsys, *SMALL, "--runs", "3", "--condition", "proximity",
        "--condition", "urgency:alpha=9", "--condition", "weighted:w=0.5", "--json",
    )  # fmt: skip
    assert code == 0
    data = json.loads(out)
    assert [c["condition"] for c in data["conditions"]] == [
        "proximity", "urgency:alpha=9.0", "weighted:w=0.5",
    ]  # fmt: skip
    assert all(c["runs"] == 3 for c in data["conditions"])
    # SPEC §8.2's five, the censoring-aware latencies, and PA at delivery (simulated logs
    # carry each carrier's urgency at delivery or run end)
    metrics = {*METRICS, "pa_at_delivery"}
    assert {(c["condition"], c["metric"]) for c in data["comparisons"]} == {
        (name, metric) for name in ("urgency:alpha=9.0", "weighted:w=0.5") for metric in metrics
    }
    # The choice statistics of the simulated event table, one object per condition.
    assert list(data) == ["conditions", "comparisons", "choices"]
    assert [c["condition"] for c in data["choices"]] == [c["condition"] for c in data["conditions"]]
    assert all(c["runs"] == 3 and c["selections"] > 0 for c in data["choices"])


def test_table_output_names_the_scenario(capsys):
    code, out, _ = run(capsys, *SMALL, "--runs", "2", "--policy", "urgency", "--alpha", "3")
    assert code == 0
    assert (
        "3 robots, 7 carriers, 400 ticks of 0.1 s (growing urgency), disc perception, R = 1 m, "
        "profile base, 2 runs from run 0, seed 0"
    ) in out
    assert "urgency:alpha=3.0" in out
    assert "PA (5-50 %)" in out


def test_run_alone_equals_run_in_batch(capsys, tmp_path):
    batch, alone = tmp_path / "batch.csv", tmp_path / "alone.csv"
    assert run(capsys, *SMALL, "--runs", "4", "--seed", "7", "--events", str(batch))[0] == 0
    assert run(capsys, *SMALL, "--runs", "1", "--run-offset", "2", "--seed", "7",
               "--events", str(alone))[0] == 0  # fmt: skip
    header, *rows = batch.read_text().splitlines()
    run_column = header.split(",").index("run")
    in_batch = [r for r in rows if r.split(",")[run_column] == "2"]
    assert alone.read_text().splitlines() == [header, *in_batch]
    log = read_event_log(batch)
    assert sorted(np.unique(log.run).tolist()) == [0, 1, 2, 3]
    assert set(log.condition.tolist()) == {"proximity", "urgency:alpha=0.7"}


def test_same_initial_scene_in_every_condition(capsys, tmp_path):
    path = tmp_path / "events.csv"
    assert run(capsys, *SMALL, "--runs", "3", "--events", str(path))[0] == 0
    log = read_event_log(path)
    scenes = {}
    for name in ("proximity", "urgency:alpha=0.7"):
        rows = log.condition == name
        order = np.lexsort((log.carrier[rows], log.run[rows]))
        scenes[name] = (log.urgency0[rows][order].tolist(), log.order_time[rows][order].tolist())
    assert scenes["proximity"] == scenes["urgency:alpha=0.7"]


def test_snapshot_and_animation_are_real_pictures(capsys, tmp_path):
    snap, anim = tmp_path / "snap.png", tmp_path / "run.gif"
    code, out, _ = run(
        capsys, *SMALL, "--runs", "1", "--condition", "urgency:alpha=0.7",
        "--snapshot", str(snap), "--animate", str(anim),
    )  # fmt: skip
    assert code == 0
    assert "snapshot of urgency:alpha=0.7 run 0 at tick" in out
    with Image.open(snap) as image:
        assert image.format == "PNG"
        assert image.size[0] > 400
        assert len(image.convert("RGB").getcolors(maxcolors=100_000) or []) > 20  # not blank
    with Image.open(anim) as movie:
        assert movie.format == "GIF"
        assert movie.n_frames > 3


def test_several_conditions_draw_one_file_each(capsys, tmp_path):
    snap = tmp_path / "snap.png"
    assert run(capsys, *SMALL, "--runs", "1", "--snapshot", str(snap))[0] == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "snap-proximity.png", "snap-urgency-alpha-0.7.png",
    ]  # fmt: skip


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["--condition", "proximity", "--policy", "urgency", "--alpha", "1"], "not both"),
        (["--policy", "urgency"], "takes --alpha"),
        (["--policy", "weighted", "--alpha", "1"], "takes --w"),
        (["--alpha", "0.7"], "need --policy"),
        (["--condition", "urgency:alpha=-1"], "alpha"),
        (["--condition", "fastest"], "fastest"),
        (["--condition", "proximity", "--condition", "proximity"], "given twice"),
        (["--snapshot", "out.jpg"], "--snapshot"),
        (["--animate", "out.avi"], "--animate"),
        (["--events", "no/such/folder/events.csv"], "does not exist"),
        (["--runs", "0"], "--runs"),
        (["--robots", "0"], "--robots"),
        (["--config", "missing.toml"], "missing.toml"),
        (["--baseline", "nonexistent"], "nonexistent"),
    ],
)
def test_bad_input_one_line_exit_2(capsys, tmp_path, monkeypatch, argv, words):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, *SMALL, "--runs", "1", *argv)
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1, err
    assert err.startswith("swarmtag: error: ")
    assert words in err
    assert list(tmp_path.iterdir()) == []  # nothing half-written


def test_bad_config_names_the_key(capsys, tmp_path):
    config = tmp_path / "scenario.toml"
    config.write_text("robots = 4\n[timing]\ndokc = 2.0\n")
    code, _, err = run(capsys, *SMALL, "--runs", "1", "--config", str(config))
    assert code == 2
    assert "timing.dokc" in err


def test_config_file_and_flags(capsys, tmp_path):
    config = tmp_path / "scenario.toml"
    config.write_text("robots = 4\ncarriers = 9\n")
    code, out, _ = run(
        capsys, *SMALL, "--runs", "1", "--config", str(config), "--robots", "2",
        "--detection-radius", "2.5",
    )  # fmt: skip
    assert code == 0
    assert "2 robots, 9 carriers" in out
    assert "R = 2.5 m" in out


def test_trajectories_saved_for_replay_match_a_recorded_run(capsys, tmp_path):
    import dataclasses

    from swarmtag.policy import Urgency
    from swarmtag.sim import Scenario, Trajectories, simulate
    from swarmtag.sim.outputs.render import snapshot

    path = tmp_path / "run.npz"
    code, out, _ = run(
        capsys, *SMALL, "--runs", "3", "--seed", "4", "--condition", "urgency:alpha=0.7",
        "--draw-run", "2", "--trajectories", str(path),
    )  # fmt: skip
    assert code == 0
    assert "trajectories of urgency:alpha=0.7 run 2" in out
    loaded = Trajectories.load(path)
    direct = simulate(
        Scenario(ticks=400), Urgency(alpha=0.7), seed=4, runs=1, run_offset=2, record=True
    )
    assert direct.trajectories is not None
    for field in dataclasses.fields(Trajectories):
        mine, theirs = getattr(loaded, field.name), getattr(direct.trajectories, field.name)
        if isinstance(mine, np.ndarray):
            assert mine.dtype == theirs.dtype, field.name
            assert np.array_equal(mine, theirs), field.name
        else:
            assert mine == theirs, field.name
    snapshot(loaded, tmp_path / "replay.png", run=2)  # a saved run can be drawn again
    assert (tmp_path / "replay.png").stat().st_size > 10_000


def test_trajectories_load_refuses_other_files(tmp_path):
    from swarmtag.errors import ConfigError
    from swarmtag.sim import Trajectories

    other = tmp_path / "other.npz"
    np.savez(other, x=np.zeros(3))
    with pytest.raises(ConfigError, match="not a swarmtag trajectories file"):
        Trajectories.load(other)
    junk = tmp_path / "junk.npz"
    junk.write_bytes(b"not a zip")
    with pytest.raises(ConfigError, match="cannot read trajectories"):
        Trajectories.load(junk)


def test_broken_toml_names_the_file_once(capsys, tmp_path):
    config = tmp_path / "broken.toml"
    config.write_text("robots = \n")
    code, _, err = run(capsys, *SMALL, "--runs", "1", "--config", str(config))
    assert code == 2
    assert err.count(str(config)) == 1
    assert "not valid TOML" in err


def test_both_backends_print_the_same_kpis(capsys):
    outputs = []
    for backend in ("reference", "fast"):
        code, out, _ = run(capsys, *SMALL, "--runs", "3", "--backend", backend, "--json")
        assert code == 0
        outputs.append(out)
    assert outputs[0] == outputs[1]


def test_an_unknown_backend_is_one_line(capsys):
    code, _, err = run(capsys, *SMALL, "--backend", "gpu")
    assert code == 2
    assert "--backend" in err
    assert len(err.strip().splitlines()) == 1


def test_a_first_compilation_is_announced_on_stderr(capsys, monkeypatch):
    from swarmtag.sim import fast

    monkeypatch.setattr(fast, "kernel_compiled", lambda: False)
    code, out, err = run(capsys, *SMALL, "--runs", "1", "--json")
    assert code == 0
    assert "compiling the fast simulation kernel" in err
    json.loads(out)  # stdout stays the JSON alone
    monkeypatch.setattr(fast, "kernel_compiled", lambda: True)
    code, _, err = run(capsys, *SMALL, "--runs", "1", "--json")
    assert "compiling" not in err
    code, _, err = run(capsys, *SMALL, "--runs", "1", "--json", "--backend", "reference")
    assert "compiling" not in err


def test_the_kernel_knows_it_is_compiled():
    from swarmtag.sim.fast import kernel_compiled

    run_once = ["simulate", *SMALL, "--runs", "1", "--json", "--backend", "fast"]
    with pytest.raises(SystemExit):
        main(run_once)
    assert kernel_compiled()


@pytest.mark.parametrize(("runs", "weak"), [(3, True), (10, False)])
def test_few_runs_mark_every_bootstrap_ci_and_p_underpowered(capsys, runs, weak):
    code, out, _ = run(capsys, *SMALL, "--runs", str(runs), "--json")
    assert code == 0
    comparisons = json.loads(out)["comparisons"]
    assert {c["underpowered"] for c in comparisons} == {weak}
    if weak:
        assert all(c["smallest_p_mannwhitney"] == pytest.approx(0.1) for c in comparisons)
    code, out, _ = run(capsys, *SMALL, "--runs", str(runs))
    assert ("underpowered" in out) is weak
    assert ("\N{DOUBLE DAGGER}" in out) is weak
    if weak:
        assert "smallest possible p here is 0.1" in out
        # every comparison underpowered: the mark heads the CI and bootstrap p columns once
        assert "Difference [95 % CI] \N{DOUBLE DAGGER}" in out
        assert "p (bootstrap) \N{DOUBLE DAGGER}" in out


THREE = ("--condition", "proximity", "--condition", "urgency:alpha=0.7",
         "--condition", "urgency:alpha=9")  # fmt: skip
NAMES = ("proximity", "urgency:alpha=0.7", "urgency:alpha=9.0")
PAPER = ("--runs", "12", "--resamples", "300", "--no-progress")
"""The paper-sim world (urgency matters there), enough runs not to be underpowered."""
TITLES = ("Metrics by condition", "Differences from the baseline", "Choice statistics by")


def _tables(out: str) -> list[tuple[list[str], list[str]]]:
    """Each table of the output: the legend lines just above its title, and its lines."""
    lines = out.splitlines()
    found = []
    for index, line in enumerate(lines):
        if line.startswith(TITLES):
            legend = []
            above = index - 1
            while above >= 0 and (lines[above].startswith(("Conditions: ", "    "))):
                legend.insert(0, lines[above])
                above -= 1
            end = next(
                (i for i in range(index + 1, len(lines)) if not lines[i].strip()
                 or lines[i].startswith((*TITLES, "Conditions: ", "Left out", "Latency", "PA at",
                                         "Shares", "Times"))),
                len(lines),
            )  # fmt: skip
            found.append((legend, lines[index:end]))
    return found


@pytest.mark.parametrize("width", [80, 120])
def test_default_output_tells_every_condition_apart_at_the_width(capsys, monkeypatch, width):
    monkeypatch.setenv("COLUMNS", str(width))
    code, out, _ = run(capsys, *PAPER, *THREE)
    assert code == 0
    lines = out.splitlines()
    assert max(len(line) for line in lines) <= width
    assert "\N{HORIZONTAL ELLIPSIS}" not in out  # rich cuts what does not fit with an ellipsis
    for line in lines:  # every interval on one line: "0.41 [0.38, 0.44]" is never wrapped
        assert line.count("[") == line.count("]"), line
    tables = _tables(out)
    assert [table[1][0].split(" (")[0].split(":")[0] for table in tables] == [
        "Metrics by condition", "Differences from the baseline proximity",
        "Choice statistics by condition", "Choice statistics by condition",
    ][: len(tables)]  # fmt: skip
    assert len(tables) >= 3
    for legend, table in tables:
        text = "\n".join(table)
        shown = [name for name in NAMES if name in text]
        if len(shown) < len(NAMES) - (1 if table[0].startswith("Differences") else 0):
            # short labels: the legend names every condition, the table heads its columns by label
            entries = dict(part.strip().split(" = ") for part in " ".join(legend)[12:].split(";"))
            assert sorted(entries.values()) == sorted(
                n for n in NAMES if not (table[0].startswith("Differences") and n == "proximity")
            )
            assert all(label in table[1] for label in entries)


def test_narrow_tables_go_long_and_wide_ones_stay_side_by_side(capsys, monkeypatch):
    monkeypatch.setenv("COLUMNS", "80")
    code, out, _ = run(capsys, *PAPER, *THREE)
    assert code == 0
    # three intervals side by side do not fit 80 columns: one row per metric and condition
    assert re.search(r"^Metric +Condition +Value$", out, re.MULTILINE)
    assert re.search(r"^PA \(5-50 %\) +proximity +\S", out, re.MULTILINE)
    assert re.search(r"^ +urgency:alpha=9\.0 +0\.\d{4} \[", out, re.MULTILINE)
    monkeypatch.setenv("COLUMNS", "200")
    code, out, _ = run(capsys, *PAPER, *THREE)
    header = next(line for line in out.splitlines() if line.startswith("Metric "))
    assert header.split() == ["Metric", *NAMES]


def test_headlines_come_first_and_hold_the_comparisons(capsys, monkeypatch):
    from swarmtag.analysis.headline import signed
    from swarmtag.analysis.tables import format_number

    monkeypatch.setenv("COLUMNS", "80")
    code, out, _ = run(capsys, *PAPER, *THREE, "--json")
    document = json.loads(out)
    code, out, _ = run(capsys, *PAPER, *THREE)
    assert code == 0
    lines = out.splitlines()
    first = lines.index("") + 1  # after the scenario sentence
    values = {c["condition"]: c for c in document["conditions"]}
    for name in NAMES[1:]:
        found = {c["metric"]: c for c in document["comparisons"] if c["condition"] == name}
        pa, p95, throughput = found["pa"], found["p95_latency"], found["throughput"]
        start = next(i for i, line in enumerate(lines) if line.startswith(f"{name} vs proximity: "))
        assert start < lines.index(next(x for x in lines if x.startswith("Metrics by condition")))
        assert start >= first
        text = " ".join(line.strip() for line in lines[start : start + 3])
        low, high = (format_number(x) for x in pa["ci"])
        assert f"PA {signed(pa['diff'])} [{low}, {high}] p" in text
        assert pa["p_bootstrap"] < 0.05  # urgency-aware selection aligns with priorities
        low, high = (format_number(x) for x in p95["ci"])
        assert f"P95 {signed(p95['diff'])} [{low}, {high}] ticks p" in text
        change = 100 * throughput["diff"] / values["proximity"]["throughput"]["value"]
        p = throughput["p_bootstrap"]
        assert f"throughput {change:+.1f} % p={p:.3g}" in text
        assert "\N{DOUBLE DAGGER}" not in text  # 12 runs each


def test_rows_that_repeat_others_are_left_out_with_a_note(capsys):
    code, out, _ = run(capsys, *PAPER, *THREE, "--json")
    document = json.loads(out)
    assert {c["undelivered"] for c in document["conditions"]} == {0}
    deliveries = [c for c in document["comparisons"] if c["metric"] == "deliveries_per_run"]
    assert {(c["diff"], *c["ci"]) for c in deliveries} == {(0, 0, 0)}
    code, out, _ = run(capsys, *PAPER, *THREE)
    assert code == 0
    text = " ".join(out.split())  # the note is one line, wrapped at the console's width
    assert "Left out: the censored latencies, KM P95 and the undelivered counts" in text
    assert (
        "Left out as 0 [0, 0] for every condition: the differences in Deliveries per run." in text
    )
    rows = [line.strip() for line in out.splitlines()]
    for label in ("P95 latency, censored", "Mean latency, censored", "KM P95 latency",
                  "Undelivered carriers"):  # fmt: skip
        assert not any(row.startswith(label) for row in rows), label
    assert sum(row.startswith("Deliveries per run") for row in rows) == 1  # values, no difference
    assert json.loads(run(capsys, *PAPER, *THREE, "--json")[1]) == document  # JSON keeps all


@DRAWS_BESIDE
def test_a_drawing_process_killed_mid_way_fails_the_command_and_writes_nothing(
    capsys, monkeypatch, tmp_path
):
    from swarmtag.sim.outputs import render

    test_process = os.getpid()  # drawn here instead, the stand-in would kill the test worker

    def killed(*args, **kwargs):
        assert os.getpid() != test_process, "drawn in the test's own process"
        os.kill(os.getpid(), signal.SIGKILL)  # in the drawing process: out of memory, say

    monkeypatch.setattr(render, "animate", killed)
    code, out, err = run(
        capsys,
        *SMALL,
        "--runs", "2", "--condition", "proximity",
        "--events", str(tmp_path / "e.csv"), "--animate", str(tmp_path / "a.gif"),
    )  # fmt: skip
    assert code == 2
    assert "Metrics by condition" in out  # the tables came first
    assert err == (
        "swarmtag: error: the process working beside the command ended before it was done "
        "(killed by signal 9)\n"
    )
    assert list(tmp_path.iterdir()) == []  # all outputs or none


@DRAWS_BESIDE
def test_where_the_copies_sent_beside_do_not_fit_the_drawing_is_done_here(
    capsys, monkeypatch, tmp_path
):
    from swarmtag.cli import simulate as command
    from swarmtag.cli._scenario import build_scenario
    from swarmtag.sim.outputs import render

    scenario = build_scenario(profile="base", config=None, flags={"ticks": 400}, settings=())
    planned = {
        drawers: command._work_bytes(scenario, 1, 1, record=True, drawers=drawers, backend="fast")
        for drawers in (0, 1)
    }
    assert planned[1] > planned[0]
    drawn_in: list[int] = []

    def snapshot(*args, **kwargs):
        drawn_in.append(os.getpid())
        return real(*args, **kwargs)

    real = render.snapshot
    monkeypatch.setattr(render, "snapshot", snapshot)
    argv = ("--runs", "1", "--condition", "proximity", "--backend", "fast")
    for limit, here in ((2 * planned[1], []), (sum(planned.values()) / 2, [os.getpid()])):
        monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", str(int(limit)))
        code, _, err = run(capsys, *SMALL, *argv, "--snapshot", str(tmp_path / "s.png"))
        assert code == 0, err
        assert drawn_in == here  # drawn beside, the list here stays empty
        assert (tmp_path / "s.png").exists()


@pytest.mark.parametrize("forks", [True, False], ids=["drawn beside", "drawn here"])
def test_tables_are_printed_before_the_pictures_are_drawn(capsys, monkeypatch, tmp_path, forks):
    from swarmtag import _beside
    from swarmtag.cli import simulate as command
    from swarmtag.sim.outputs import render

    monkeypatch.setattr(_beside, "can_fork", lambda: forks)
    monkeypatch.setattr(command, "can_fork", lambda: forks)
    order = tmp_path / "order.txt"  # appended to by this process and by the drawing one

    def noted(what, real):
        def call(*args, **kwargs):
            with order.open("a") as log:
                log.write(f"{what} {os.getpid()}\n")
            return real(*args, **kwargs)

        return call

    monkeypatch.setattr(render, "snapshot", noted("snapshot", render.snapshot))
    monkeypatch.setattr(command, "render_choices", noted("tables", command.render_choices))
    code, out, _ = run(capsys, *SMALL, "--runs", "2", "--snapshot", str(tmp_path / "s.png"))
    assert code == 0
    events = [line.split() for line in order.read_text().splitlines()]
    assert [what for what, _ in events] == ["tables", "snapshot", "snapshot"]  # one a condition
    drawn_in = {pid for what, pid in events if what == "snapshot"}
    assert (drawn_in == {str(os.getpid())}) is not forks
    if forks and default_threads() > 1:
        assert len(drawn_in) == 2  # a drawing process a condition
    assert out.index("Choice statistics by condition") < out.index("snapshot of")
    assert out.index("snapshot of proximity run 0 at tick") < out.index(
        "snapshot of urgency:alpha=0.7 run 0 at tick"
    )
    assert f"{tmp_path / 's-urgency-alpha-0.7.png'}" in out


def test_help_says_which_outputs_are_one_file_per_condition(capsys):
    code, out, _ = run(capsys, "--help")
    assert code == 0
    text = " ".join(out.split())
    for option, suffix in (("--snapshot", ".png"), ("--animate", ".gif or .mp4"),
                           ("--trajectories", ".npz"), ("--mcap", ".mcap")):  # fmt: skip
        sentence = f"With several conditions, one file per condition: STEM-<condition>{suffix}."
        assert sentence in text.split(option, 1)[1], option
    assert "event log of every condition, in one file" in text


def test_compilation_shows_on_the_progress_line_and_says_how_long(capsys, monkeypatch):
    from swarmtag.sim import fast

    monkeypatch.setattr(fast, "kernel_compiled", lambda: False)
    code, out, err = run(capsys, *SMALL[:-1], "--progress", "--runs", "1", "--json")
    assert code == 0
    json.loads(out)
    assert re.search(r"swarmtag: compiled the fast kernel in \d+ s", err)
    assert "once: about a minute or two" not in err  # the progress line says it instead
    code, out, err = run(capsys, *SMALL, "--runs", "1", "--json")  # no progress line
    assert "compiling the fast simulation kernel" in err
    assert re.search(r"compiled the fast kernel in \d+ s", err)
