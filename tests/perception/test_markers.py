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
    fuse,
    load_rig,
    marker_frames,
    render,
)
from swarmtag.perception._bits import read_candidate
from swarmtag.perception.markers import BORDER_PIXELS, _detector
from swarmtag.sim.model.geometry import FACE_NORMALS

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
    # position within 1.5 % of the camera distance; the normal within 6 degrees (a 50 mm
    # marker at 1.5 m spans about 40 px: OpenCV 5.0 gave 4.84 degrees at the third pose, 5.1
    # gives 5.01; a broken pose is tens of degrees off)
    assert np.linalg.norm(detection.position - centre) < 0.015 * detection.camera_distance
    candidates = [detection.normal, *detection.alternatives]
    assert min(math.degrees(math.acos(min(1.0, n @ normal))) for n in candidates) < 6.0
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


# The four images the range study (seed 0) missed inside its old 1.25-2.0 m band
# (docs/perception.md): (distance, bearing, turn) and the conditions as the study drew
# them, and a noise seed on which the detector before the fix missed the carrier too.
FORMER_MISSES = [
    ((1.25, 45.0, 4.61), Conditions(0.668, 1.17, 1.094), 0),  # surround runs off the image
    ((2.0, 0.0, 33.01), Conditions(0.921, 4.73, 0.725), 3),  # 2.3 px modules: bits misread
    ((2.0, 15.0, 30.45), Conditions(0.785, 1.01, 0.907), 0),
    ((2.0, 15.0, 40.65), Conditions(0.844, 1.93, 0.712), 50),
]


@pytest.mark.parametrize(("pose", "conditions", "seed"), FORMER_MISSES)
def test_the_range_studys_former_misses_are_identified_within_five_percent(pose, conditions, seed):
    distance, bearing, turn = pose
    image = image_of(Placement.at(7, distance, bearing, turn), conditions=conditions, seed=seed)
    carriers = fuse(detect_markers(image, FRONT, RIG.carrier), RIG.carrier)
    assert [carrier.marker for carrier in carriers] == [7]
    assert carriers[0].distance == pytest.approx(distance, rel=0.05)


def test_a_rejected_candidate_is_read_again_at_sub_pixel_corners_in_opencvs_order():
    image = image_of(Placement.at(42, 1.5, -20.0, -30.0), conditions=Conditions(0.5, 2.0))
    corners, ids, _ = _detector().detectMarkers(image)
    assert sorted(np.asarray(ids).ravel().tolist()) == [42, 42]  # two faces
    for points in corners:
        opencv_corners = np.asarray(points, dtype=np.float64).reshape(4, 2)
        for shift in range(4):  # a rejected candidate: integer corners, starting anywhere
            quad = np.round(np.roll(opencv_corners, shift, axis=0))
            read = read_candidate(image, quad, _detector())
            assert read is not None
            assert read[0] == 42
            assert np.max(np.abs(read[1] - opencv_corners)) < 0.25  # px, same order
    # squares that carry no code are refused: a checkerboard, a hollow square, a flat grey
    checker = np.full((200, 200), 200, np.uint8)
    checker[50:130, 50:130] = 20
    for y, x in np.argwhere(np.indices((6, 6)).sum(axis=0) % 2 == 1):
        checker[60 + 10 * y : 70 + 10 * y, 60 + 10 * x : 70 + 10 * x] = 200
    hollow = np.full((200, 200), 200, np.uint8)
    hollow[50:130, 50:130] = 20
    hollow[60:120, 60:120] = 200
    flat = np.full((200, 200), 90, np.uint8)
    square = np.array([[50.0, 50.0], [129.0, 50.0], [129.0, 129.0], [50.0, 129.0]])
    for picture in (checker, hollow, flat):
        assert read_candidate(picture, square, _detector()) is None


def test_a_marker_at_the_images_edge_is_dropped_and_one_just_inside_it_kept():
    image = image_of(Placement.at(7, 1.0, 0.0, 0.0), conditions=Conditions(0.5, 2.0))
    (face,) = [d for d in detect_markers(image, FRONT, RIG.carrier) if not d.underside]
    left = float(face.corners[:, 0].min())
    for gap, kept in ((1.0, False), (BORDER_PIXELS - 1, False), (BORDER_PIXELS + 3, True)):
        shift = round(left - gap)  # slide the image left: the marker's edge `gap` px inside
        moved = np.pad(image[:, shift:], ((0, 0), (0, shift)), mode="edge")
        found = [d for d in detect_markers(moved, FRONT, RIG.carrier) if not d.underside]
        assert bool(found) is kept, gap


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
