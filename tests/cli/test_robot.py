"""``swarmtag robot tree``: the tree as text, and which picture files ``--out`` wrote."""

from __future__ import annotations

import pytest

from swarmtag.cli import main

pytest.importorskip("py_trees")


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(["robot", "tree", *argv])
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def test_without_graphviz_one_line_names_the_dot_file_and_what_png_needs(
    capsys, tmp_path, monkeypatch
):
    monkeypatch.setattr("swarmtag.robot.tree.shutil.which", lambda name: None)
    code, out, err = run(capsys, "--out", str(tmp_path / "tree"))
    assert code == 0
    assert out.strip()  # the tree as text still
    assert [p.name for p in (tmp_path / "tree").iterdir()] == ["robot-tree.dot"]
    dot = tmp_path / "tree" / "robot-tree.dot"
    hint = "PNG and SVG need Graphviz (its `dot` program on the PATH)"
    assert err.splitlines() == [f"wrote {dot} only: {hint}"]


def test_with_graphviz_one_line_names_every_file(capsys, tmp_path, monkeypatch):
    def three_files(tree, folder, name="robot-tree"):
        written = [folder / f"{name}.{suffix}" for suffix in ("dot", "png", "svg")]
        for path in written:
            path.write_text("picture")
        return written

    monkeypatch.setattr("swarmtag.robot.tree.dot_picture", three_files)
    code, _, err = run(capsys, "--out", str(tmp_path))
    assert code == 0
    names = ", ".join(str(tmp_path / f"robot-tree.{s}") for s in ("dot", "png", "svg"))
    assert err.splitlines() == [f"wrote {names}"]


def test_without_out_nothing_is_written(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, out, err = run(capsys)
    assert code == 0
    assert "wrote" not in err
    assert out.strip()
    assert list(tmp_path.iterdir()) == []
