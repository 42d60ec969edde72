"""``swarmtag profiles`` and ``--profile`` / ``--set`` on the simulating commands."""

from __future__ import annotations

import pytest

from swarmtag.cli import main


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
