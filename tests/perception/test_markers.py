"""Marker detection and pose on synthetic images at known poses (SPEC §3.1, §7)."""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from swarmtag.errors import ConfigError, PerceptionError
from swarmtag.perception import (
    MARKER_IDS,
    NEEDS_EXTRA,
    Conditions,
    Face,
    Placement,
    detect_markers,
    load_rig,
    marker_frames,
    render,
)
from swarmtag.sim.geometry import FACE_NORMALS

pytest.importorskip("cv2")

RIG = load_rig()
FRONT = RIG.camera("front")


CLEAN = Conditions()


def image_of(placement, camera=FRONT, conditions=CLEAN, seed=0):
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    return render(camera, RIG.carrier, [placement], conditions, rng=rng)


def truth(placement, face, camera=FRONT):
    """The marker's true centre, normal (robot frame) and projected corners (px)."""
    frame = marker_frames(RIG.carrier)[face]
    centre = placement.to_robot(frame.centre)
    normal = placement.to_robot(frame.z) - placement.to_robot(np.zeros(3))
    corners = camera.mount.to_camera(placement.to_robot(frame.corners(RIG.carrier.marker_size)))
    pixels = corners @ camera.intrinsics.matrix.T
    return centre, normal, pixels[:, :2] / pixels[:, 2:]


def test_marker_frames_are_the_simulators_faces_and_right_handed():
    frames = marker_frames(RIG.carrier)
    assert [f.face for f in frames] == list(Face)
    assert np.allclose([f.z[:2] for f in frames[:4]], FACE_NORMALS)
    for frame in frames:
        assert np.allclose(np.cross(frame.x, frame.y), frame.z)
    east = frames[Face.EAST]
    assert np.allclose(east.centre, [0.1775, 0.0, 0.10])
    assert np.allclose(east.y, [0, 0, 1])  # printed upright on the face
    under = frames[Face.UNDERSIDE]
    assert np.allclose(under.centre, [0, 0, 0.20])
    assert np.allclose(under.z, [0, 0, -1])
    assert np.allclose(under.x, [1, 0, 0])  # the underside marker's x points east
    # OpenCV's corner order: top-left, top-right, bottom-right, bottom-left (seen from outside)
    corners = east.corners(0.05)
    assert np.allclose(corners[0], [0.1775, -0.025, 0.125])
    assert np.allclose(corners[2], [0.1775, 0.025, 0.075])


@pytest.mark.parametrize(
    ("distance", "bearing", "turn"),
    [(0.6, 0.0, 10.0), (1.0, 20.0, -25.0), (1.5, -35.0, 5.0)],
)
def test_id_corners_and_pose_are_recovered_at_known_poses(distance, bearing, turn):
    placement = Placement.at(42, distance, bearing, turn)
    found = detect_markers(image_of(placement), FRONT, RIG.carrier)
    assert {d.marker for d in found} == {42}  # one or two faces, all with the carrier's id
    centre, normal, pixels = truth(placement, Face.EAST)
    detection = min(found, key=lambda d: np.linalg.norm(d.position - centre))
    assert np.max(np.abs(detection.corners - pixels)) < 0.5  # px
    # position within 1.5 % of the camera distance; the normal within 5 degrees
    assert np.linalg.norm(detection.position - centre) < 0.015 * detection.camera_distance
    candidates = [detection.normal, *detection.alternatives]
    assert min(math.degrees(math.acos(min(1.0, n @ normal))) for n in candidates) < 5.0
    assert detection.distance == pytest.approx(math.hypot(*centre[:2]), rel=0.015)
    assert detection.bearing == pytest.approx(
        math.degrees(math.atan2(centre[1], centre[0])), abs=0.5
    )
    assert detection.reprojection_error < 0.5
    assert not detection.underside


def test_the_face_is_named_from_the_robots_heading():
    placement = Placement.at(3, 0.8, 0.0, 0.0)  # east face straight at the robot
    detection = detect_markers(image_of(placement), FRONT, RIG.carrier)[0]
    assert detection.face_direction() == pytest.approx(
        180.0, abs=3
    ) or detection.face_direction() == pytest.approx(-180.0, abs=3)
    # a robot heading 0 (east) looks at the carrier's west face, heading 90 at its south face
    assert detection.face(0.0) is Face.WEST
    assert detection.face(90.0) is Face.SOUTH


def test_upward_camera_sees_the_underside_marker():
    upward = RIG.camera("upward")
    placement = Placement(5, 0.03, -0.01, 20.0)
    found = detect_markers(image_of(placement, upward), upward, RIG.carrier)
    assert [d.marker for d in found] == [5]
    detection = found[0]
    assert detection.underside
    assert detection.face(123.0) is Face.UNDERSIDE
    assert np.allclose(detection.position, [0.03, -0.01, 0.20], atol=0.002)
    assert detection.face_direction() == pytest.approx(20.0, abs=1.0)
    assert np.allclose(detection.carrier_centre(RIG.carrier), [0.03, -0.01], atol=0.002)


def test_colour_images_are_read_and_an_empty_view_finds_nothing():
    placement = Placement.at(9, 1.0, 0.0, 15.0)
    gray = image_of(placement)
    colour = np.repeat(gray[:, :, None], 3, axis=2)
    assert [d.marker for d in detect_markers(colour, FRONT, RIG.carrier)] == [9]
    behind = Placement.at(9, 1.0, 180.0)
    assert detect_markers(image_of(behind), FRONT, RIG.carrier) == ()


@pytest.mark.parametrize(
    ("image", "words"),
    [
        (np.zeros((1080, 1920), dtype=np.float32), "8-bit"),
        ([[0, 1], [2, 3]], "8-bit"),
        (np.zeros((1080, 1920, 4), dtype=np.uint8), "neither grey"),
        (np.zeros((480, 640), dtype=np.uint8), "640x480 but camera 'front' is 1920x1080"),
    ],
)
def test_bad_images_are_refused(image, words):
    with pytest.raises(PerceptionError, match=words):
        detect_markers(image, FRONT, RIG.carrier)


def test_every_id_of_the_dictionary_can_be_drawn_and_no_other():
    assert MARKER_IDS == 250
    with pytest.raises(PerceptionError, match="marker: 250 is not an integer in 0-249"):
        Placement(250, 1.0, 0.0)


def test_missing_opencv_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "cv2", None)  # import cv2 now fails
    with pytest.raises(ConfigError) as refused:
        detect_markers(np.zeros((1080, 1920), np.uint8), FRONT, RIG.carrier)
    assert str(refused.value) == NEEDS_EXTRA
    assert "pip install 'swarmtag[vision]'" in NEEDS_EXTRA
    with pytest.raises(ConfigError, match="vision"):
        render(FRONT, RIG.carrier, [], rng=np.random.default_rng(0))
