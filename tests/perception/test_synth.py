"""Synthetic images: exact geometry, the camera's degradations, determinism."""

from __future__ import annotations

import numpy as np
import pytest

from swarmtag.errors import PerceptionError
from swarmtag.perception import (
    Camera,
    Conditions,
    Face,
    Intrinsics,
    Placement,
    detect_markers,
    load_rig,
    marker_frames,
    render,
    visible_markers,
)

pytest.importorskip("cv2")

RIG = load_rig()
FRONT = RIG.camera("front")


def rng(seed=0):
    return np.random.default_rng(np.random.SeedSequence(seed))


def test_placement_at_puts_a_face_square_to_the_robot():
    placement = Placement.at(1, 2.0, 30.0)
    assert placement.x == pytest.approx(2.0 * np.cos(np.radians(30)))
    assert placement.yaw == pytest.approx(210.0)  # the east face points back at the robot
    east = marker_frames(RIG.carrier)[Face.EAST]
    centre = placement.to_robot(east.centre)
    assert np.hypot(*centre[:2]) == pytest.approx(2.0 - RIG.carrier.half)
    with pytest.raises(PerceptionError, match="distance"):
        Placement.at(1, float("inf"), 0.0)


def test_same_seed_same_bytes_and_noise_comes_from_the_generator():
    placement = Placement.at(7, 1.0, 5.0, 12.0)
    noisy = Conditions(blur=0.7, noise=4.0, exposure=0.9, occlusion=0.2)
    first = render(FRONT, RIG.carrier, [placement], noisy, rng=rng(3))
    again = render(FRONT, RIG.carrier, [placement], noisy, rng=rng(3))
    other = render(FRONT, RIG.carrier, [placement], noisy, rng=rng(4))
    assert first.dtype == np.uint8
    assert first.shape == (1080, 1920)
    assert first.tobytes() == again.tobytes()
    assert first.tobytes() != other.tobytes()
    clean = render(FRONT, RIG.carrier, [placement], rng=rng(3))
    assert clean.tobytes() == render(FRONT, RIG.carrier, [placement], rng=rng(9)).tobytes()


@pytest.mark.parametrize(("distance", "turn"), [(0.6, 0.0), (2.0, 30.0), (3.0, 5.0)])
def test_a_face_covers_exactly_its_projected_area(distance, turn):
    """The renderer's geometry: a uniform face's coverage sums to its analytic image area."""
    from swarmtag.perception.synth import _draw, _faces, _Texture, _texture

    placement = Placement.at(7, distance, 0.0, turn)
    (face,) = [f for f in _faces(FRONT, RIG.carrier, [placement]) if f[2].face is Face.EAST]
    _, _, frame, pose = face
    texture = _texture(7, frame, RIG.carrier)
    canvas = np.zeros((1080, 1920), np.float32)
    _draw(
        canvas, FRONT.intrinsics.matrix, _Texture(np.ones_like(texture.image), texture.texel), pose
    )
    rows, cols = texture.image.shape
    half_w, half_h = cols * texture.texel / 2, rows * texture.texel / 2
    centre, x, y = pose[0], pose[1], pose[2]
    corners = [
        centre + x * a * half_w + y * b * half_h for a, b in ((-1, 1), (1, 1), (1, -1), (-1, -1))
    ]
    pixels = np.array(corners) @ FRONT.intrinsics.matrix.T
    u, v = (pixels[:, :2] / pixels[:, 2:]).T
    area = 0.5 * abs(u @ np.roll(v, 1) - v @ np.roll(u, 1))
    assert canvas.sum() == pytest.approx(area, rel=0.005)
    assert canvas.max() <= 1.0 + 1e-6


def test_exposure_scales_brightness_and_clips_at_white():
    placement = Placement.at(7, 0.6, 0.0, 5.0)
    normal = render(FRONT, RIG.carrier, [placement], rng=rng())
    bright = render(FRONT, RIG.carrier, [placement], Conditions(exposure=2.0), rng=rng())
    assert int(normal.max()) == 235  # white paper at 0.92 of full scale
    assert int(bright.max()) == 255
    assert np.mean(bright) > 1.8 * np.mean(normal)


def test_an_empty_scene_is_the_floor():
    image = render(FRONT, RIG.carrier, [], rng=rng())
    assert set(np.unique(image)) == {102}  # 0.40 of 255


def test_occlusion_hides_the_marker_from_the_detector():
    placement = Placement.at(7, 0.8, 0.0, 10.0)
    seen = render(FRONT, RIG.carrier, [placement], Conditions(occlusion=0.0), rng=rng())
    # a bar over a tenth of its width cuts the black border, which ArUco needs whole
    hidden = render(FRONT, RIG.carrier, [placement], Conditions(occlusion=0.1), rng=rng())
    assert hidden.tobytes() != seen.tobytes()
    found = detect_markers(seen, FRONT, RIG.carrier)
    assert sorted(d.underside for d in found) == [False, True]  # the face; the underside above
    assert {d.marker for d in found} == {7}
    assert detect_markers(hidden, FRONT, RIG.carrier) == ()


def test_nearer_faces_hide_farther_ones():
    near = Placement.at(1, 0.8, 0.0, 0.0)
    far = Placement.at(2, 1.6, 0.0, 0.0)  # straight behind the near carrier
    image = render(FRONT, RIG.carrier, [far, near], rng=rng())
    found = detect_markers(image, FRONT, RIG.carrier)
    assert {d.marker for d in found} == {1}  # its face (and, seen from below, its underside)
    assert (2, Face.EAST) in visible_markers(FRONT, RIG.carrier, [far])


def test_a_distorting_lens_is_rendered_and_undone_by_the_detector():
    lens = FRONT.intrinsics
    barrel = Intrinsics(
        lens.width, lens.height, lens.fx, lens.fy, lens.cx, lens.cy, (-0.25, 0.05, 0.0, 0.0, 0.0)
    )
    camera = Camera("wide", "perimeter", barrel, FRONT.mount)
    placement = Placement.at(6, 1.2, 35.0, 8.0)  # off-axis, where the lens bends most
    image = render(camera, RIG.carrier, [placement], rng=rng())
    found = detect_markers(image, camera, RIG.carrier)
    east = marker_frames(RIG.carrier)[Face.EAST]
    centre = placement.to_robot(east.centre)
    detection = min(found, key=lambda d: np.linalg.norm(d.position - centre))
    assert detection.marker == 6
    assert np.linalg.norm(detection.position - centre) < 0.02
    # the same pixels read with the pinhole model put the marker elsewhere
    pinhole = detect_markers(image, FRONT, RIG.carrier)
    assert min(np.linalg.norm(d.position - centre) for d in pinhole) > 0.05


def test_bad_conditions_and_generators_are_refused():
    with pytest.raises(PerceptionError, match="occlusion"):
        Conditions(occlusion=1.5)
    with pytest.raises(PerceptionError, match="noise"):
        Conditions(noise=float("nan"))
    with pytest.raises(PerceptionError, match=r"numpy\.random\.Generator"):
        render(FRONT, RIG.carrier, [], rng=np.random.RandomState(0))  # type: ignore[arg-type]
