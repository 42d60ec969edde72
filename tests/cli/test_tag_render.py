"""``swarmtag tag render``: the E-ink picture from the shell (SPEC §2.4)."""

from __future__ import annotations

import sys

import pytest

from swarmtag.cli import main
from swarmtag.tag import TagState, TagStatus
from swarmtag.tag.eink import png_bytes

STATE = ["--urgency", "9", "--status", "awaiting_pickup", "--destination", "0", "--marker", "3"]


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(list(argv))
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def test_render_writes_the_png_and_says_so(capsys, tmp_path):
    from PIL import Image

    out = tmp_path / "tag.png"
    code, stdout, err = run(capsys, "tag", "render", *STATE, "--out", str(out))
    assert (code, err) == (0, "")
    assert stdout == f"wrote E-ink picture: {out}\n"
    expected = TagState(urgency=9, status=TagStatus.AWAITING_PICKUP, destination=0, marker=3)
    assert out.read_bytes() == png_bytes(expected)
    with Image.open(out) as image:
        assert (image.size, image.mode) == ((250, 122), "1")
    assert [p.name for p in tmp_path.iterdir()] == ["tag.png"]  # no staging folder left


def test_render_replaces_an_existing_file(capsys, tmp_path):
    out = tmp_path / "tag.png"
    out.write_bytes(b"old")
    argv = [*STATE[:2], "--status", "picked_up", *STATE[4:], "--out", str(out)]
    code, _, _ = run(capsys, "tag", "render", *argv)
    assert code == 0
    assert out.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (("--status", "lost"), "'lost' is not a tag status"),
        (("--urgency", "10"), "'--urgency': 10 is not in the range 0<=x<=9"),
        (("--marker", "256"), "'--marker'"),
        (("--destination", "-1"), "'--destination'"),
        (("--out", "{tmp}/missing/tag.png"), "does not exist"),
        (("--out", "{tmp}/tag.gif"), "must end in .png"),
        (("--out", "{tmp}/folder.png"), "is a folder"),
    ],
    ids=["status", "urgency", "marker", "destination", "missing-folder", "suffix", "folder"],
)
def test_bad_input_is_one_line_exit_2_and_writes_nothing(capsys, tmp_path, change, message):
    options = dict(zip(STATE[::2], STATE[1::2], strict=True))
    options["--out"] = str(tmp_path / "tag.png")
    option, value = change
    options[option] = value.format(tmp=tmp_path)
    (tmp_path / "folder.png").mkdir()
    before = sorted(p.name for p in tmp_path.iterdir())
    code, out, err = run(capsys, "tag", "render", *(x for kv in options.items() for x in kv))
    assert code == 2
    assert out == ""
    assert err.startswith("swarmtag: error: ")
    assert message in err
    assert len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == before


def test_missing_option_is_one_line_exit_2(capsys, tmp_path):
    code, _, err = run(capsys, "tag", "render", *STATE[:6], "--out", str(tmp_path / "t.png"))
    assert code == 2
    assert "--marker" in err
    assert len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_missing_pillow_is_one_line_exit_2(capsys, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "PIL", None)
    code, _, err = run(capsys, "tag", "render", *STATE, "--out", str(tmp_path / "tag.png"))
    assert code == 2
    assert "pip install 'swarmtag[eink]'" in err
    assert len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []
