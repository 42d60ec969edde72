"""The camera model and rig files: frames, intrinsics, validation (docs/perception.md)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmtag.errors import PerceptionError
from swarmtag.perception import (
    Camera,
    CarrierMarkers,
    Intrinsics,
    Mount,
    Rig,
    load_rig,
    read_rig_file,
    rig_from_mapping,
)

LENS = {"width": 640, "height": 480, "fx": 500.0, "fy": 500.0, "cx": 319.5, "cy": 239.5}


def rig_data(**changes):
    data = {
        "name": "t",
        "intrinsics": dict(LENS),
        "cameras": [{"name": "front", "position": [0.1, 0.0, 0.1]}],
    }
    data.update(changes)
    return data


def test_shipped_rig_is_the_documented_dots_like_robot():
    rig = load_rig("dots-like")
    assert [c.name for c in rig.cameras] == ["front", "left", "back", "right", "upward"]
    assert [c.kind for c in rig.cameras] == ["perimeter"] * 4 + ["upward"]
    lens = rig.camera("front").intrinsics
    assert (lens.width, lens.height) == (1920, 1080)
    assert lens.horizontal_fov == pytest.approx(102.0)
    assert lens.fx == pytest.approx(960 / math.tan(math.radians(51)))
    assert rig.carrier == CarrierMarkers(0.355, 0.05, 0.10, 0.20)  # SPEC: 0.355 m, 50 mm
    yaws = sorted(c.mount.yaw % 360 for c in rig.perimeter)
    assert yaws == [0.0, 90.0, 180.0, 270.0]
    # four perimeter cameras of 102 degrees cover 360 degrees (SPEC §4.2a)
    assert 4 * lens.horizontal_fov > 360


def test_mount_axes_follow_opencv_and_the_robot_frame():
    front = Mount(0.12, 0.0, 0.1, yaw=0.0, pitch=0.0)
    # camera x right (= robot -y), y down (= robot -z), z forward (= robot +x)
    assert np.allclose(front.rotation, [[0, 0, 1], [-1, 0, 0], [0, -1, 0]])
    left = Mount(0.0, 0.12, 0.1, yaw=90.0)
    assert np.allclose(left.to_camera(np.array([0.0, 1.12, 0.1])), [0, 0, 1])
    up = Mount(0.0, 0.0, 0.1, yaw=90.0, pitch=90.0)
    assert np.allclose(up.to_camera(np.array([0.0, 0.0, 0.3])), [0, 0, 0.2])
    assert np.allclose(up.rotation[:, 0], [1, 0, 0])  # image right = robot forward
    points = np.random.default_rng(0).normal(size=(5, 3))
    tilted = Mount(0.1, -0.2, 0.3, yaw=33.0, pitch=-12.0)
    assert np.allclose(tilted.to_robot(tilted.to_camera(points)), points)
    assert np.allclose(tilted.rotation.T @ tilted.rotation, np.eye(3))
    assert np.linalg.det(tilted.rotation) == pytest.approx(1.0)


def test_intrinsics_matrix_and_fields_of_view():
    lens = Intrinsics(**LENS, distortion=(0.1, -0.01, 0.0, 0.0))
    assert np.array_equal(lens.matrix, [[500, 0, 319.5], [0, 500, 239.5], [0, 0, 1]])
    assert lens.coefficients.tolist() == [0.1, -0.01, 0.0, 0.0]
    assert lens.distorted
    assert not Intrinsics(**LENS).distorted
    assert Intrinsics(**LENS).coefficients.tolist() == [0.0] * 5
    assert lens.horizontal_fov == pytest.approx(2 * math.degrees(math.atan(320 / 500)))


@pytest.mark.parametrize(
    ("change", "words"),
    [
        ({"width": 0}, "width"),
        ({"fx": float("nan")}, "fx"),
        ({"cx": 700.0}, "cx"),
        ({"distortion": (0.1, 0.2, 0.3)}, "3 coefficients"),
        ({"distortion": (float("inf"), 0, 0, 0)}, r"distortion\[0\]"),
        ({"height": True}, "height"),
    ],
)
def test_bad_intrinsics_are_refused(change, words):
    with pytest.raises(PerceptionError, match=words):
        Intrinsics(**{**LENS, **change})


@pytest.mark.parametrize(
    ("data", "words"),
    [
        (rig_data(cameras=[]), "cameras: missing"),
        (rig_data(nope=1), "rig.nope: unknown key"),
        (rig_data(intrinsics={**LENS, "fov": 3}), "intrinsics.fov: unknown key"),
        (rig_data(intrinsics={**LENS, "horizontal_fov": 90}), "horizontal_fov or cx"),
        (rig_data(intrinsics={"width": 640, "height": 480, "fx": 5.0}), "intrinsics.fy: missing"),
        (rig_data(cameras=[{"name": "a", "position": [0, 0]}]), "position"),
        (rig_data(cameras=[{"name": "a", "position": [0, 0, 0], "kind": "down"}]), "kind"),
        (rig_data(cameras=[{"name": "a", "position": [0, 0, 0], "pitch": 120}]), "pitch"),
        (rig_data(cameras=[{"name": "a", "position": [0, 0, 0]}] * 2), "named twice"),
        (rig_data(cameras=[{"position": [0, 0, 0]}]), "cameras\\[0\\].name"),
        (rig_data(carrier={"side": -1}), "carrier.side"),
        (rig_data(carrier={"marker_size": 1.0}), "carrier.marker_size"),
        ({"cameras": [{"name": "a", "position": [0, 0, 0]}]}, "no intrinsics"),
        (rig_data(cameras=[7]), "cameras\\[0\\]: 7 is not a table"),
    ],
)
def test_bad_rig_files_name_the_key(data, words):
    with pytest.raises(PerceptionError, match=words):
        rig_from_mapping(data, source="mine.toml")


def test_rig_file_errors_name_the_file(tmp_path):
    path = tmp_path / "robot.toml"
    path.write_text("name = 'r'\n[intrinsics]\nwidth = 640\nheight = 480\nhorizontal_fov = 90\n")
    with pytest.raises(PerceptionError, match=r"robot\.toml: cameras: missing"):
        read_rig_file(path)
    path.write_text("this is = not toml =")
    with pytest.raises(PerceptionError, match="not valid TOML"):
        load_rig(path)
    with pytest.raises(PerceptionError, match="no such camera file"):
        load_rig(tmp_path / "missing.toml")
    with pytest.raises(PerceptionError, match="no such file or shipped rig"):
        load_rig("dots-lite")


def test_a_rig_file_reads_back_and_a_camera_may_have_its_own_lens(tmp_path):
    path = tmp_path / "one.toml"
    path.write_text(
        'name = "mine"\n[[cameras]]\nname = "cam"\nposition = [0.1, 0.0, 0.2]\nyaw = 10\n'
        "[cameras.intrinsics]\nwidth = 800\nheight = 600\nhorizontal_fov = 60\n"
    )
    rig = load_rig(str(path))
    camera = rig.camera("cam")
    assert camera.intrinsics.width == 800
    assert camera.intrinsics.horizontal_fov == pytest.approx(60.0)
    assert camera.mount == Mount(0.1, 0.0, 0.2, yaw=10.0)
    assert rig.carrier == CarrierMarkers()
    with pytest.raises(PerceptionError, match="has no camera 'front' \\(it has: cam\\)"):
        rig.camera("front")


def test_facing_picks_the_perimeter_camera_nearest_the_bearing():
    rig = load_rig()
    assert [rig.facing(b).name for b in (0, 44, 46, 135, -179, -91)] == [
        "front",
        "front",
        "left",
        "left",
        "back",
        "right",
    ]
    lone = Rig("up", (Camera("u", "upward", Intrinsics(**LENS), Mount(0, 0, 0, pitch=90)),))
    with pytest.raises(PerceptionError, match="no perimeter camera"):
        lone.facing(0.0)
