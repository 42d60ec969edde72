"""Camera images read from files: sized from the header, refused before decoding; narrow lenses."""

from __future__ import annotations

import struct
import zlib

import numpy as np
import pytest

from swarmtag.errors import PerceptionError
from swarmtag.perception import Conditions, Placement, detect_markers, images, render
from swarmtag.perception.camera import Camera, CarrierMarkers, Intrinsics, Mount

cv2 = pytest.importorskip("cv2")


def _png(path, width: int, height: int) -> None:
    def chunk(kind: bytes, data: bytes) -> bytes:
        crc = zlib.crc32(kind + data) & 0xFFFFFFFF
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", crc)

    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IEND", b""))


def _camera(width: int = 64, height: int = 48, fx: float = 64.0) -> Camera:
    lens = Intrinsics(width, height, fx, fx, (width - 1) / 2, (height - 1) / 2)
    return Camera("front", "perimeter", lens, Mount(0.12, 0.0, 0.1))


def test_the_size_comes_from_the_header_alone(tmp_path):
    path = tmp_path / "claims.png"
    _png(path, 70_000, 3)  # no pixel data at all
    assert images.image_size(path) == (70_000, 3, 1)


def test_images_over_the_pixel_limit_or_memory_or_of_another_size_are_refused(
    tmp_path, monkeypatch
):
    path = tmp_path / "claims.png"
    _png(path, 20_001, 20_000)
    with pytest.raises(PerceptionError, match=r"20001x20000 pixels \(400,020,000\); at most 400,"):
        images.read_image(path, _camera())
    _png(path, 5000, 5000)
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "100MiB")
    with pytest.raises(PerceptionError, match=r"a 5000x5000 image .* needs about 405.3 MiB"):
        images.read_image(path, _camera())
    monkeypatch.delenv("SWARMTAG_MEMORY_LIMIT")
    _png(path, 65, 48)
    with pytest.raises(PerceptionError, match=r"the image is 65x48 but camera 'front' is 64x48"):
        images.read_image(path, _camera())


def test_a_camera_is_checked_against_the_memory_limit(monkeypatch):
    monkeypatch.setenv("SWARMTAG_MEMORY_LIMIT", "1MiB")
    with pytest.raises(PerceptionError, match=r"^rig.toml: camera 'front': width x height 640x480"):
        images.check_camera(_camera(640, 480), "rig.toml")
    images.check_camera(_camera(64, 48), "rig.toml")


@pytest.mark.parametrize("fov", [1.0, 3.0, 5.0])
def test_a_narrow_lens_poses_a_far_marker_with_ippe_alone(fov):
    lens = Intrinsics.from_fov(1920, 1080, fov)
    camera = Camera("front", "perimeter", lens, Mount(0.12, 0.0, 0.1))
    carrier = CarrierMarkers()
    distance = 0.05 * lens.fx / 40  # the marker about 40 px across: too small for SQPnP
    image = render(
        camera,
        carrier,
        [Placement.at(3, distance, 0.0)],
        Conditions(),
        rng=np.random.default_rng(0),
    )
    (found,) = detect_markers(image, camera, carrier)
    assert found.marker == 3
    assert found.distance + carrier.half == pytest.approx(distance, rel=0.05)
