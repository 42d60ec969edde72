"""Carrier fusion, predock points and the upward camera's centring offset."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarmtag.errors import PerceptionError
from swarmtag.perception import (
    CENTRED_TOLERANCE,
    PREDOCK_DISTANCE,
    CarrierEstimate,
    Conditions,
    Face,
    Placement,
    centring_offset,
    detect_markers,
    fuse,
    load_rig,
    render,
    visible_markers,
)
from swarmtag.sim.config.scenario import Motion

pytest.importorskip("cv2")

RIG = load_rig()


BLURRED = Conditions(blur=0.5, noise=2.0)


def detections(placement, cameras=RIG.perimeter, conditions=BLURRED):
    rng = np.random.default_rng(np.random.SeedSequence(1))
    found = []
    for camera in cameras:
        if visible_markers(camera, RIG.carrier, [placement]):
            image = render(camera, RIG.carrier, [placement], conditions, rng=rng)
            found += detect_markers(image, camera, RIG.carrier)
    return found


def test_defaults_are_the_simulators():
    assert Motion().predock_distance == PREDOCK_DISTANCE
    assert Motion().arrival_tolerance == CENTRED_TOLERANCE


def test_two_faces_and_two_cameras_fuse_into_one_carrier():
    placement = Placement.at(11, 1.5, 45.0, 0.0)  # between the front and left cameras
    found = detections(placement)
    assert {d.camera for d in found} == {"front", "left"}
    (estimate,) = fuse(found, RIG.carrier)
    assert estimate.marker == 11
    assert estimate.markers == len(found) >= 2
    assert np.linalg.norm(estimate.position - [placement.x, placement.y]) < 0.02
    assert estimate.distance == pytest.approx(1.5, rel=0.02)
    assert estimate.bearing == pytest.approx(45.0, abs=1.0)
    assert estimate.cameras == ("front", "left")
    assert estimate.spread < 0.03
    # the faces are 90 degrees apart: the yaw is the placement's, modulo 90
    assert (estimate.yaw - placement.yaw + 45) % 90 - 45 == pytest.approx(0.0, abs=2.0)


def test_ambiguous_faces_are_resolved_by_agreement_and_by_the_heading():
    placement = Placement.at(9, 1.2, 0.0, 40.0)  # two faces, one seen 50 degrees off
    found = detections(placement, cameras=[RIG.camera("front")])
    assert len(found) == 2
    (free,) = fuse(found, RIG.carrier)
    assert np.linalg.norm(free.position - [placement.x, placement.y]) < 0.03
    heading = 90.0 - placement.yaw  # a world heading that puts the faces on the axes
    (square,) = fuse(found, RIG.carrier, heading=heading)
    assert (square.yaw + heading) % 90 == pytest.approx(0.0, abs=1e-9)
    assert np.linalg.norm(square.position - [placement.x, placement.y]) < 0.03


def test_the_underside_marker_fixes_which_face_is_east():
    upward = RIG.camera("upward")
    found = detections(Placement(4, 0.02, 0.0, 100.0), cameras=[upward])
    (estimate,) = fuse(found, RIG.carrier)
    assert estimate.yaw == pytest.approx(100.0, abs=1.0)


def test_predock_is_in_front_of_the_nearest_face():
    estimate = CarrierEstimate(3, np.array([1.0, 0.0]), 10.0, 1, 0.0, ("front",))
    predock = estimate.predock(RIG.carrier)
    offset = RIG.carrier.half + PREDOCK_DISTANCE  # 0.3525 m: the simulator's predock_offset
    expected = np.array([1.0, 0.0]) + offset * np.array(
        [-math.cos(math.radians(10)), -math.sin(math.radians(10))]
    )
    assert np.allclose(predock.point, expected)
    assert predock.face_direction == pytest.approx(-170.0)
    assert predock.heading == pytest.approx(10.0)  # facing the carrier from the point
    assert predock.face(170.0) is Face.EAST  # heading 170: that face points east
    near = estimate.predock(RIG.carrier, predock_distance=0.0)
    assert np.linalg.norm(near.point - estimate.position) == pytest.approx(RIG.carrier.half)
    with pytest.raises(PerceptionError, match="predock_distance"):
        estimate.predock(RIG.carrier, predock_distance=-1.0)


def test_centring_offset_says_how_far_and_how_turned():
    upward = RIG.camera("upward")
    found = detections(Placement(8, 0.04, -0.015, -30.0), cameras=[upward])
    offset = centring_offset(found)
    assert offset is not None
    assert offset.marker == 8
    assert np.allclose(offset.offset, [0.04, -0.015], atol=0.002)
    assert offset.yaw == pytest.approx(-30.0, abs=1.0)
    assert offset.height == pytest.approx(RIG.carrier.underside_height, abs=0.003)
    assert offset.error == pytest.approx(math.hypot(0.04, 0.015), abs=0.002)
    assert not offset.centred()
    assert offset.centred(tolerance=0.05)
    centred = centring_offset(detections(Placement(8, 0.0, 0.0, 0.0), cameras=[upward]))
    assert centred is not None
    assert centred.centred()
    assert centring_offset(found, marker=99) is None
    assert centring_offset([]) is None


def test_bad_inputs_are_refused():
    side = detections(Placement.at(2, 0.8, 0.0, 5.0), cameras=[RIG.camera("front")])
    with pytest.raises(PerceptionError, match="'front' is not the upward camera"):
        centring_offset(side)
    with pytest.raises(PerceptionError, match="expected MarkerDetection"):
        fuse([object()], RIG.carrier)
    with pytest.raises(PerceptionError, match="heading"):
        fuse(side, RIG.carrier, heading=float("nan"))
    (estimate,) = fuse(side, RIG.carrier)
    with pytest.raises(PerceptionError, match="tolerance"):
        centring_offset(detections(Placement(8, 0.0, 0.0), cameras=[RIG.camera("upward")])).centred(
            tolerance=-1
        )
    assert estimate.marker == 2
