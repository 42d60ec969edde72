"""``swarmtag aruco render|detect``: a synthetic photo and what the detector reads from it."""

from __future__ import annotations

import json
import sys

import pytest

from swarmtag.cli import main
from swarmtag.perception import NEEDS_EXTRA, rig_path

pytest.importorskip("cv2")


def run(capsys, *argv: str) -> tuple[int, str, str]:
    with pytest.raises(SystemExit) as exited:
        main(list(argv))
    out, err = capsys.readouterr()
    return int(exited.value.code or 0), out, err


def render(capsys, path, *extra: str) -> None:
    code, out, err = run(
        capsys,
        "aruco",
        "render",
        "--marker",
        "12",
        "--distance",
        "1.5",
        "--bearing",
        "20",
        "--out",
        str(path),
        *extra,
    )
    assert (code, err) == (0, ""), err
    assert out.startswith(f"wrote camera image: {path} (camera front, 1920x1080; marker 12")


def test_render_then_detect_gives_back_id_distance_and_bearing(capsys, tmp_path):
    image = tmp_path / "photo.png"
    render(capsys, image, "--turn", "15", "--blur", "0.5", "--noise", "2", "--seed", "3")
    assert image.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    code, out, err = run(capsys, "aruco", "detect", str(image), "--json")
    assert (code, err) == (0, "")
    report = json.loads(out)
    assert report["camera"] == "front"
    assert {m["id"] for m in report["markers"]} == {12}
    (carrier,) = report["carriers"]
    assert carrier["id"] == 12
    assert carrier["distance"] == pytest.approx(1.5, rel=0.03)
    # one marker from afar: its face may be the mirror image, which moves the carrier sideways
    assert carrier["bearing"] == pytest.approx(20.0, abs=5.0)
    assert report["centring"] is None
    # the carrier's faces point at 215 deg + k 90 (robot frame); heading 55 puts them on the axes
    code, out, _ = run(capsys, "aruco", "detect", str(image), "--heading", "55", "--json")
    squared = json.loads(out)["carriers"][0]
    assert squared["bearing"] == pytest.approx(20.0, abs=0.5)
    assert squared["yaw"] % 90 == pytest.approx(35.0, abs=1e-6)
    assert squared["predock"]["face"] == "south"  # 215 + 55 = 270 deg in the world
    code, out, _ = run(capsys, "aruco", "detect", str(image))
    assert code == 0
    lines = out.splitlines()
    assert lines[0] == "camera front: 1 marker(s), 1 carrier(s)"
    assert lines[2].split()[:2] == ["12", f"{carrier['distance']:.3f}"]


def test_the_upward_view_reports_the_centring_offset(capsys, tmp_path):
    image = tmp_path / "under.png"
    code, _, err = run(
        capsys,
        "aruco",
        "render",
        "--marker",
        "4",
        "--distance",
        "0.03",
        "--bearing",
        "0",
        "--view",
        "upward",
        "--out",
        str(image),
    )
    assert (code, err) == (0, "")
    code, out, _ = run(capsys, "aruco", "detect", str(image), "--view", "upward", "--json")
    centring = json.loads(out)["centring"]
    assert centring["id"] == 4
    assert centring["offset"] == pytest.approx([0.03, 0.0], abs=0.002)
    assert centring["centred"] is False
    code, out, _ = run(capsys, "aruco", "detect", str(image), "--view", "upward")
    assert "centring on 4: move (+3.0, +0.0) cm" in out


def test_the_dots_upward_camera_centres_on_the_underside_map(capsys, tmp_path):
    image = tmp_path / "map.png"
    argv = ["aruco", "render", "--camera", "dots", "--view", "cam4", "--marker", "7"]
    code, out, err = run(
        capsys, *argv, "--distance", "0.04", "--bearing", "30", "--turn", "10", "--noise", "2",
        "--out", str(image),
    )  # fmt: skip
    assert (code, err) == (0, "")
    assert "(camera cam4, 640x480; marker 7 at 0.04 m, bearing 30 deg)" in out
    code, out, _ = run(
        capsys, "aruco", "detect", str(image), "--camera", "dots", "--view", "cam4", "--json"
    )
    assert code == 0
    report = json.loads(out)
    ids = [m["id"] for m in report["markers"]]
    assert len(ids) >= 10
    assert all(200 <= i <= 248 for i in ids)  # map markers, not carrier ids
    assert all(len(m["map_offset"]) == 2 for m in report["markers"])
    assert report["carriers"] == []  # a map marker names no carrier
    centring = report["centring"]
    assert centring["id"] == 200
    assert centring["map_markers"] == len(ids)
    # the carrier 4 cm away at 30 deg, its east face at 30 + 180 + 10 = 220 deg
    assert centring["offset"] == pytest.approx([0.0346, 0.02], abs=0.001)
    assert centring["yaw"] == pytest.approx(-140.0, abs=0.5)
    code, out, _ = run(capsys, "aruco", "detect", str(image), "--camera", "dots", "--view", "cam4")
    assert f"camera cam4: {len(ids)} marker(s), 0 carrier(s)" in out
    assert f"centring on the underside map 200 ({len(ids)} markers): move (+3.5, +2.0) cm" in out
    code, _, err = run(
        capsys, *argv[:-1], "210", "--distance", "0", "--bearing", "0", "--out", str(image)
    )
    assert code == 2
    assert "marker 210: one of the carriers' underside map ids (200-248)" in err


def test_a_camera_file_is_read_and_a_photo_of_another_size_refused(capsys, tmp_path):
    small = tmp_path / "small.toml"
    text = rig_path("dots-like").read_text().replace("width = 1920", "width = 640")
    small.write_text(text.replace("height = 1080", "height = 480"))
    image = tmp_path / "small.png"
    code, out, err = run(
        capsys,
        "aruco",
        "render",
        "--marker",
        "1",
        "--distance",
        "0.8",
        "--bearing",
        "-90",
        "--camera",
        str(small),
        "--out",
        str(image),
    )
    assert (code, err) == (0, "")
    assert "camera right, 640x480" in out
    code, out, err = run(
        capsys, "aruco", "detect", str(image), "--camera", str(small), "--view", "right", "--json"
    )
    assert code == 0
    assert json.loads(out)["carriers"][0]["id"] == 1
    code, _, err = run(capsys, "aruco", "detect", str(image))
    assert code == 2
    assert err == (
        f"swarmtag: error: {image}: the image is 640x480 but camera 'front' is 1920x1080; "
        "give the camera file of the camera that took it\n"
    )


@pytest.mark.parametrize(
    ("argv", "words"),
    [
        (["detect", "{tmp}/none.png"], "no such image"),
        (["detect", "{tmp}/text.png"], "not an image whose size can be read before decoding"),
        (["detect", "{tmp}"], "is a folder"),
        (["detect", "{tmp}/text.png", "--camera", "nope"], "no such file or shipped rig"),
        (["detect", "{tmp}/text.png", "--view", "side"], "has no camera 'side'"),
        (["detect", "{tmp}/text.png", "--heading", "nan"], "--heading"),
        (
            [
                "render",
                "--marker",
                "250",
                "--distance",
                "1",
                "--bearing",
                "0",
                "--out",
                "{tmp}/a.png",
            ],
            "250 is not in the range 0<=x<=249",
        ),
        (
            [
                "render",
                "--marker",
                "1",
                "--distance",
                "inf",
                "--bearing",
                "0",
                "--out",
                "{tmp}/a.png",
            ],
            "--distance",
        ),
        (
            [
                "render",
                "--marker",
                "1",
                "--distance",
                "1",
                "--bearing",
                "0",
                "--occlusion",
                "2",
                "--out",
                "{tmp}/a.png",
            ],
            "occlusion",
        ),
        (
            [
                "render",
                "--marker",
                "1",
                "--distance",
                "1",
                "--bearing",
                "0",
                "--out",
                "{tmp}/a.jpg",
            ],
            "--out",
        ),
    ],
)
def test_bad_input_is_one_line_and_exit_2(capsys, tmp_path, argv, words):
    (tmp_path / "text.png").write_text("not a picture")
    code, _out, err = run(capsys, "aruco", *[a.format(tmp=tmp_path) for a in argv])
    assert code == 2
    assert err.startswith("swarmtag: error: ")
    assert err.count("\n") == 1
    assert words in err
    assert not (tmp_path / "a.png").exists()


def test_missing_opencv_is_one_line_naming_the_extra(capsys, tmp_path, monkeypatch):
    image = tmp_path / "photo.png"
    render(capsys, image)
    monkeypatch.setitem(sys.modules, "cv2", None)
    for argv in (
        ["detect", str(image)],
        [
            "render",
            "--marker",
            "1",
            "--distance",
            "1",
            "--bearing",
            "0",
            "--out",
            str(tmp_path / "b.png"),
        ],
    ):
        code, out, err = run(capsys, "aruco", *argv)
        assert (code, out) == (2, "")
        assert err == f"swarmtag: error: {NEEDS_EXTRA}\n"
    assert not (tmp_path / "b.png").exists()


# --- images and cameras checked before work (docs/perception.md, "Images and cameras") --------


def _png(path, width: int, height: int, rows: bytes = b"") -> None:
    """A grey PNG whose header says ``width`` x ``height``; ``rows`` is its compressed content."""
    import struct
    import zlib

    def chunk(kind: bytes, data: bytes) -> bytes:
        crc = zlib.crc32(kind + data) & 0xFFFFFFFF
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)

    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", rows) + chunk(b"IEND", b"")
    )


def _zeros(width: int, height: int) -> bytes:
    """The compressed rows of an all-black grey image (a decompression bomb when large)."""
    import zlib

    packer = zlib.compressobj(9)
    row = b"\x00" * (width + 1)
    return b"".join(packer.compress(row) for _ in range(height)) + packer.flush()


def test_an_image_claiming_huge_size_is_refused_from_its_header(capsys, tmp_path):
    image = tmp_path / "huge.png"
    _png(image, 100_000, 100_000, b"x\x9c\x03\x00\x00\x00\x00\x01")
    assert image.stat().st_size < 100
    code, out, err = run(capsys, "aruco", "detect", str(image))
    assert (code, out) == (2, "")
    assert err == (
        f"swarmtag: error: {image}: the image is 100000x100000 pixels (10,000,000,000); "
        "at most 400,000,000 are read (the largest camera a camera file may give)\n"
    )


def test_a_decompression_bomb_is_refused_before_it_is_decoded(capsys, tmp_path, monkeypatch):
    image = tmp_path / "bomb.png"
    _png(image, 12_000, 12_000, _zeros(12_000, 12_000))
    assert image.stat().st_size < 200_000  # 144 megapixels in 140 KB
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "512MiB")
    import cv2

    def never(*_args):
        raise AssertionError("decoded")

    monkeypatch.setattr(cv2, "imdecode", never)
    code, out, err = run(capsys, "aruco", "detect", str(image))
    assert (code, out) == (2, "")
    assert err.startswith(f"swarmtag: error: {image}: decoding and searching a 12000x12000 image")
    assert "512.0 MiB is available" in err
    assert err.count("\n") == 1


def test_a_damaged_image_is_one_line_and_libpng_stays_quiet(capfd, tmp_path):
    image = tmp_path / "photo.png"
    with pytest.raises(SystemExit):
        main(
            [
                *["aruco", "render", "--marker", "3", "--distance", "1", "--bearing", "0", "--out"],
                str(image),
            ]
        )
    capfd.readouterr()
    data = bytearray(image.read_bytes())
    data[100] ^= 0xFF  # inside the compressed pixels: libpng complains while decoding
    image.write_bytes(bytes(data))
    with pytest.raises(SystemExit) as exited:
        main(["aruco", "detect", str(image)])
    out, err = capfd.readouterr()
    assert (exited.value.code, out) == (2, "")
    assert err == (
        f"swarmtag: error: {image}: a damaged image: OpenCV could not decode it "
        "(PNG, JPEG, BMP, TIFF, WebP, PNM)\n"
    )


def test_a_narrow_camera_detects_instead_of_failing_in_opencv(capsys, tmp_path):
    camera = tmp_path / "narrow.toml"
    text = (
        rig_path("dots-like").read_text().replace("horizontal_fov = 102.0", "horizontal_fov = 1.0")
    )
    camera.write_text(text)
    image = tmp_path / "far.png"
    code, _, err = run(
        capsys, "aruco", "render", "--marker", "3", "--distance", "20", "--bearing", "0",
        "--camera", str(camera), "--out", str(image),
    )  # fmt: skip
    assert (code, err) == (0, "")
    code, out, err = run(capsys, "aruco", "detect", str(image), "--camera", str(camera), "--json")
    assert (code, err) == (0, "")
    (carrier,) = json.loads(out)["carriers"]
    assert carrier["id"] == 3
    assert carrier["distance"] == pytest.approx(20.0, rel=0.01)


def test_a_camera_too_large_for_memory_is_refused_before_the_image_is_read(
    capsys, tmp_path, monkeypatch
):
    camera = tmp_path / "big.toml"
    text = rig_path("dots-like").read_text().replace("width = 1920", "width = 20000")
    camera.write_text(text.replace("height = 1080", "height = 20000"))
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "1GiB")
    code, out, err = run(
        capsys, "aruco", "detect", str(tmp_path / "none.png"), "--camera", str(camera)
    )
    assert (code, out) == (2, "")
    assert err.startswith(
        f"swarmtag: error: {camera}: camera 'front': width x height 20000x20000 "
        "(decoding and searching one of its colour images) needs about 7.1 GiB of memory; "
        "1.0 GiB is available"
    )
