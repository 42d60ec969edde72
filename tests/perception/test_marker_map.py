"""The carriers' underside marker map: the dots rig's 7 x 7 map, rendered, read and centred on."""

from __future__ import annotations

import dataclasses
import math
import tomllib

import numpy as np
import pytest

from swarmtag.errors import PerceptionError
from swarmtag.perception import (
    Conditions,
    Face,
    Placement,
    UndersideMap,
    centring_offset,
    detect_markers,
    fuse,
    load_rig,
    marker_frames,
    render,
    rig_from_mapping,
    rig_path,
    visible_markers,
)
from swarmtag.perception._opencv import opencv

pytest.importorskip("cv2")

RIG = load_rig("dots")
UP = RIG.camera("cam4")
GRID = RIG.carrier.underside_map
SEEN = Conditions(blur=0.6, noise=3.0, exposure=0.9)
OFFSET_TOLERANCE = 0.001
"""Most error (m) of the recovered offset: measured at most 0.7 mm, 0.3 mm near the centre."""
TURN_TOLERANCE = 0.5
"""Most error (deg) of the recovered turn: measured at most 0.3 deg."""


def upward_view(placement, carrier=RIG.carrier, conditions=SEEN, seed=0):
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    image = render(UP, carrier, [placement], conditions, rng=rng)
    return image, detect_markers(image, UP, carrier)


def turn_error(a, b):
    return abs((a - b + 180.0) % 360.0 - 180.0)


def test_the_dots_rig_carries_the_robots_map():
    assert RIG.carrier.underside_map == UndersideMap(7, 7, 0.0234, 0.0351, 200)
    assert GRID.ids == range(200, 249)
    assert GRID.extent == pytest.approx(6 * 0.0351 + 0.0234)  # 0.234 m on a 0.355 m underside
    # the layout of the lab's map file: id 200 at the corner of smallest x and y, rows along x
    assert np.allclose(GRID.offset(200), [-3 * 0.0351, -3 * 0.0351])
    assert np.allclose(GRID.offset(206), [3 * 0.0351, -3 * 0.0351])
    assert np.allclose(GRID.offset(207), [-3 * 0.0351, -2 * 0.0351])
    assert np.allclose(GRID.offset(224), [0.0, 0.0])
    assert RIG.carrier.size_of(224) == 0.0234
    assert RIG.carrier.size_of(7) == 0.04  # side markers keep theirs
    assert load_rig("dots-like").carrier.underside_map is None


def test_the_map_is_rendered_and_read_at_the_docking_pose():
    image, found = upward_view(Placement(7, 0.0, 0.0, 0.0))
    ids = {d.marker for d in found}
    assert ids <= set(GRID.ids)  # only map markers: the carrier's id is not underneath
    assert len(ids) == len(found) >= 12  # the camera sees a 5 x 3 patch of the map
    assert 224 in ids  # the centre marker, straight above the camera
    for d in found:
        assert d.in_map
        assert d.map_id == 200
        assert np.array_equal(d.map_offset, GRID.offset(d.marker))
        assert d.position[2] == pytest.approx(RIG.carrier.underside_height, abs=0.002)
    assert fuse(found, RIG.carrier) == ()  # map markers name no carrier
    centring = centring_offset(found)
    assert centring is not None
    assert centring.marker == 200  # the map, as the robot's vision node reports it
    assert centring.markers == len(found)
    assert centring.error < OFFSET_TOLERANCE
    assert turn_error(centring.yaw, 0.0) < TURN_TOLERANCE
    assert centring.height == pytest.approx(RIG.carrier.underside_height, abs=0.002)
    assert centring.centred()
    # ink and white paper (0.06 and 0.92 of white, times the exposure 0.9)
    assert int(np.percentile(image, 5)) < 40
    assert int(np.percentile(image, 95)) > 180


@pytest.mark.parametrize(
    ("x", "y", "yaw"),
    [(0.03, -0.02, 25.0), (-0.06, 0.04, -120.0), (0.10, 0.05, 170.0), (0.0, -0.12, 60.0)],
)
def test_the_offset_and_turn_are_recovered_off_centre(x, y, yaw):
    _, found = upward_view(Placement(7, x, y, yaw), seed=3)
    centring = centring_offset(found)
    assert centring is not None
    assert centring.markers >= 4
    assert np.hypot(*(centring.offset - [x, y])) < OFFSET_TOLERANCE
    assert turn_error(centring.yaw, yaw) < TURN_TOLERANCE
    assert not centring.centred()


def test_part_of_the_map_is_enough_and_one_marker_gives_a_rougher_answer():
    x, y, yaw = 0.16, 0.02, 35.0  # most of the map out of view
    _, found = upward_view(Placement(7, x, y, yaw), seed=5)
    assert 2 <= len(found) <= 9
    centring = centring_offset(found)
    assert centring is not None
    assert np.hypot(*(centring.offset - [x, y])) < OFFSET_TOLERANCE
    one = centring_offset(found[:1])
    assert one is not None
    assert one.markers == 1
    assert np.hypot(*(one.offset - [x, y])) < 0.005
    assert turn_error(one.yaw, yaw) < 2.0
    # the map's first id picks the map; a carrier id picks nothing under a map carrier
    assert centring_offset(found, marker=200).markers == len(found)
    assert centring_offset(found, marker=7) is None


def test_an_occluder_on_every_map_marker_hides_most_of_it_and_shows_in_the_fit():
    """A bar on each marker's border hides most; those still read fit a square badly."""
    placement = Placement(7, 0.02, 0.01, 10.0)
    _, clear = upward_view(placement, conditions=Conditions())
    _, found = upward_view(placement, conditions=Conditions(occlusion=0.1))
    assert 1 <= len(found) < len(clear) / 2
    assert max(d.reprojection_error for d in clear) < 0.3  # px
    assert min(d.reprojection_error for d in found) > 0.5  # the bar bends the outline
    assert centring_offset(found).markers == len(found)  # not rejected: docs/perception.md


def test_the_alignment_comes_from_the_map_not_from_one_marker_under_the_camera():
    """Each marker is its map offset away from the centre: without the map it is wrong."""
    x, y, yaw = 0.05, -0.03, 40.0
    image, found = upward_view(Placement(7, x, y, yaw), seed=7)
    assert len({d.marker for d in found}) >= 10
    # every marker alone already points at the same centre, through its own offset
    centres = np.array([d.carrier_centre(RIG.carrier) for d in found])
    assert np.max(np.linalg.norm(centres - [x, y], axis=1)) < 0.005
    assert np.max(np.linalg.norm([d.position[:2] for d in found] - np.array([x, y]), axis=1)) > 0.05
    # read as single underside markers (no map), the same image says something else
    plain = dataclasses.replace(RIG.carrier, underside_map=None)
    unmapped = detect_markers(image, UP, plain)
    assert not any(d.in_map for d in unmapped)
    wrong = centring_offset(unmapped)
    assert wrong is not None
    assert wrong.markers == 1
    assert np.hypot(*(wrong.offset - [x, y])) > 0.01
    assert len(fuse(unmapped, plain)) >= 10  # each map marker taken for a carrier


def test_a_perimeter_camera_sees_the_map_from_below_but_never_as_a_carrier():
    placement = Placement.at(7, 0.5, 17.0, 0.0)
    front = RIG.camera("cam0")
    assert (7, Face.UNDERSIDE) in visible_markers(front, RIG.carrier, [placement])
    rng = np.random.default_rng(0)
    found = detect_markers(render(front, RIG.carrier, [placement], rng=rng), front, RIG.carrier)
    assert [e.marker for e in fuse(found, RIG.carrier)] == [7]


def test_the_map_lies_where_the_rig_says():
    """The rendered marker corners are where the map puts them (the renderer's geometry)."""
    placement = Placement(7, 0.01, 0.02, 30.0)
    _, found = upward_view(placement, conditions=Conditions())
    under = marker_frames(RIG.carrier)[Face.UNDERSIDE]
    cv2 = opencv()
    lens = UP.intrinsics
    for d in found:
        corners = placement.to_robot(under.shifted(GRID.offset(d.marker)).corners(0.0234))
        pixels, _ = cv2.projectPoints(
            UP.mount.to_camera(corners), np.zeros(3), np.zeros(3), lens.matrix, lens.coefficients
        )
        assert np.max(np.abs(d.corners - pixels.reshape(4, 2))) < 0.5  # px


def test_a_carrier_id_on_the_map_is_refused():
    with pytest.raises(PerceptionError, match=r"marker 210: one of .* map ids \(200-248\)"):
        render(UP, RIG.carrier, [Placement(210, 0.0, 0.0)], rng=np.random.default_rng(0))
    with pytest.raises(PerceptionError, match="marker 248"):
        visible_markers(UP, RIG.carrier, [Placement(248, 0.0, 0.0)])
    assert visible_markers(UP, RIG.carrier, [Placement(249, 0.0, 0.0)])


def test_single_marker_rigs_are_unchanged():
    rig = load_rig("dots-like")
    upward = rig.camera("upward")
    placement = Placement(5, 0.03, -0.01, 20.0)
    rng = np.random.default_rng(0)
    image = render(upward, rig.carrier, [placement], rng=rng)
    (detection,) = detect_markers(image, upward, rig.carrier)
    assert (detection.marker, detection.map_id, detection.map_offset) == (5, None, None)
    centring = centring_offset([detection])
    assert (centring.marker, centring.markers) == (5, 1)
    (estimate,) = fuse([detection], rig.carrier)
    assert estimate.marker == 5
    # a rig file without a map is read as before: one underside marker with the carrier's id
    text = rig_path("dots").read_text(encoding="utf-8")
    plain = text[: text.index("[carrier.underside_map]")] + text[text.index("[[cameras]]") :]
    carrier = rig_from_mapping(tomllib.loads(plain)).carrier
    assert carrier.underside_map is None
    assert carrier == dataclasses.replace(RIG.carrier, underside_map=None)


def test_the_map_in_a_camera_file():
    data = {
        "cameras": [{"name": "up", "kind": "upward", "position": [0, 0, 0.1], "pitch": 90}],
        "intrinsics": {"width": 640, "height": 480, "horizontal_fov": 90.0},
        "carrier": {"underside_map": {"columns": 5, "rows": 3, "marker_size": 0.03}},
    }
    grid = rig_from_mapping(data).carrier.underside_map
    assert grid == UndersideMap(5, 3, 0.03, 0.0351, 200)  # the DOTS map's values by default
    assert grid.ids == range(200, 215)
    assert np.allclose(grid.offset(214), [2 * 0.0351, 0.0351])


@pytest.mark.parametrize(
    ("table", "words"),
    [
        ({"colour": 1}, "carrier.underside_map.colour: unknown key"),
        ({"rows": 0}, "carrier.underside_map.rows: 0 is not an integer in 1-50"),
        ({"pitch": 0.024}, "carrier.underside_map.pitch: 0.024 is not a number in [0.026325"),
        ({"first_id": 210}, "carrier.underside_map.first_id: 210 is not an integer in 0-201"),
        ({"pitch": 0.06}, "carrier.underside_map: 0.3834 m across, wider than the carrier"),
        ({"marker_size": "big"}, "carrier.underside_map.marker_size"),
    ],
)
def test_bad_maps_are_refused_naming_the_key(table, words):
    data = {
        "cameras": [{"name": "up", "kind": "upward", "position": [0, 0, 0.1], "pitch": 90}],
        "intrinsics": {"width": 640, "height": 480, "horizontal_fov": 90.0},
        "carrier": {"underside_map": table},
    }
    with pytest.raises(PerceptionError) as refused:
        rig_from_mapping(data, source="robot.toml")
    assert str(refused.value).startswith(f"robot.toml: {words}")
    with pytest.raises(PerceptionError, match="is not a table"):
        rig_from_mapping({**data, "carrier": {"underside_map": 7}})
    with pytest.raises(PerceptionError, match="not an UndersideMap"):
        dataclasses.replace(RIG.carrier, underside_map=(7, 7))


def test_a_map_offset_needs_a_map_id():
    with pytest.raises(PerceptionError, match="marker 7 is not on the underside map"):
        GRID.offset(7)
    assert math.isclose(GRID.pitch / GRID.marker_size, 1.5)
