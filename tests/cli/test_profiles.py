"""``swarmtag profiles`` and ``--profile`` / ``--set`` on the simulating commands."""

from __future__ import annotations

import json

import pytest
from rich.console import Console

from swarmtag.cli import main
from swarmtag.sim.config.mapping import flat_keys
from swarmtag.sim.config.profiles import DEFAULT_PROFILE, PROFILES, load_profile


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(list(argv))
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def test_profiles_lists_the_shipped_ones_with_their_values(capsys):
    code, out, _ = run(capsys, "profiles")
    assert code == 0
    for name in ("paper-sim (default)", "lab", "base"):
        assert name in out
    assert "camera.range" in out
    assert "0.01934" in out  # the fitted tick of paper-sim
    assert "calibration:" in out  # the record of how a shipped profile was fitted


def test_profiles_shows_a_file(capsys, tmp_path):
    path = tmp_path / "mine.toml"
    path.write_text('tick = 0.05\n[profile]\nname = "mine"\ndescription = "my arena"\n')
    code, out, _ = run(capsys, "profiles", str(path))
    assert code == 0
    assert "mine" in out
    assert "my arena" in out


def test_explicit_flags_and_set_win_over_the_profile(capsys):
    code, out, _ = run(
        capsys, "simulate", "--profile", "lab", "--tick", "0.05", "--set", "camera.range=2.0",
        "--runs", "1", "--ticks", "200", "--resamples", "50", "--no-progress",
    )  # fmt: skip
    assert code == 0
    assert "200 ticks of 0.05 s" in out
    assert "camera 2 m" in out
    assert "profile lab" in out


def check_record(record, profile):
    """One ``--json`` record holds the profile object's own values, defaults and records."""
    own = flat_keys(profile.values)
    resolved = flat_keys(profile.scenario().to_mapping())
    assert record["name"] == profile.name
    assert record["description"] == profile.description
    assert record["calibration"] == profile.calibration
    assert set(record["set_by_profile"]) == set(own)
    for key, value in own.items():
        assert record["values"][key] == value, key
    for key, value in record["values"].items():
        assert value == resolved[key], key
    left_out = set(resolved) - set(record["values"])  # what a study or the command line sets
    assert {key.split(".")[0] for key in left_out} <= {
        "robots", "carriers", "ticks", "reprioritisations", "arena"
    }  # fmt: skip


def test_profiles_json_holds_every_shipped_profile_s_values_and_calibration(capsys):
    code, out, err = run(capsys, "profiles", "--json")
    assert (code, err) == (0, "")
    records = json.loads(out)["profiles"]
    assert [record["name"] for record in records] == list(PROFILES)
    for record in records:
        check_record(record, load_profile(record["name"]))
        assert record["shipped"] is True
        assert record["file"] is None
        assert record["default"] is (record["name"] == DEFAULT_PROFILE)
    paper = records[0]
    assert paper["values"]["tick"] == 0.01934  # the fitted tick, as in the table
    assert paper["calibration"]["fitted"] == {"tick": 0.01934}
    assert paper["calibration"]["command"].startswith("swarmtag calibrate ")
    assert "camera.range" in paper["set_by_profile"]
    assert records[2]["calibration"] == {}  # base was not fitted


def test_profiles_json_of_one_name_or_file(capsys, tmp_path):
    code, out, _ = run(capsys, "profiles", "lab", "--json")
    assert code == 0
    (record,) = json.loads(out)["profiles"]
    check_record(record, load_profile("lab"))
    assert record["values"]["time_unit"] == "s"
    path = tmp_path / "mine.toml"
    path.write_text('tick = 0.05\n[profile]\nname = "mine"\ndescription = "my arena"\n')
    code, out, _ = run(capsys, "profiles", str(path), "--json")
    assert code == 0
    (record,) = json.loads(out)["profiles"]
    check_record(record, load_profile(path))
    assert (record["shipped"], record["default"], record["file"]) == (False, False, str(path))
    assert record["set_by_profile"] == ["tick"]
    assert record["values"]["tick"] == 0.05


@pytest.mark.parametrize("argv", [["nope"], ["nope", "--json"], ["--json", "missing.toml"]])
def test_profiles_of_an_unknown_name_is_one_line_and_exit_2(capsys, argv, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys, "profiles", *argv)
    assert (code, out) == (2, "")
    assert err.startswith("swarmtag: error: ")
    assert err.count("\n") == 1
    assert ("no such shipped profile (shipped: paper-sim, lab, base)" in err) is (argv[0] == "nope")


def test_profiles_wraps_descriptions_and_calibration_to_the_terminal(capsys, monkeypatch):
    monkeypatch.setattr(
        "swarmtag.cli.profiles.make_console", lambda: Console(width=80, highlight=False)
    )
    code, out, _ = run(capsys, "profiles")
    assert code == 0
    lines = out.splitlines()
    assert max(len(line) for line in lines) <= 80
    start = lines.index(next(line for line in lines if line.startswith("paper-sim: ")))
    assert lines[start + 1].startswith("  ")  # the description goes on, indented
    calibration = next(i for i, line in enumerate(lines) if line.startswith("  calibration: "))
    assert lines[calibration + 1].startswith("    ")
    text = " ".join(line.strip() for line in lines[calibration:])
    assert "fitted.tick = 0.01934" in text
    assert "free = tick=0.01:0.05:log" in text


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--profile", "nope"], "no such shipped profile"),
        (["--set", "camera.rnage=2"], "camera.rnage: unknown key"),
        (["--set", "nothing"], "is not KEY=VALUE"),
        (["--set", "camera.range=-1"], "camera.range: -1 is not a number in (0, 100000]"),
    ],
)
def test_bad_profile_or_setting_is_one_line_and_exit_2(capsys, argv, message):
    code, out, err = run(capsys, "simulate", "--runs", "1", *argv)
    assert code == 2
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert out == ""
