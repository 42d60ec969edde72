"""The public camera functions refuse wrong arguments with ``PerceptionError`` (issue 35, item 7).

Each call here once escaped as a bare ``TypeError``, ``AttributeError``,
``ValueError`` or ``OverflowError`` from deep inside (``os.fspath``, numpy, OpenCV).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from swarmtag.errors import PerceptionError
from swarmtag.perception import (
    Conditions,
    Intrinsics,
    Placement,
    RangeStudy,
    centring_offset,
    detect_markers,
    fuse,
    load_rig,
    marker_frames,
    plot_range_study,
    read_rig_file,
    render,
    rig_from_mapping,
    rig_path,
    run_range_study,
    to_gray,
    visible_markers,
)

RIG = load_rig()
FRONT = RIG.camera("front")
CARRIER = RIG.carrier
PLACEMENT = Placement.at(7, 1.0, 0.0)
IMAGE = np.zeros((FRONT.intrinsics.height, FRONT.intrinsics.width), dtype=np.uint8)
HUGE = pytest.param(10**5000, id="10**5000")
NOT_OBJECTS = [None, 1.5, "front", [], {}, np.array([1.0])]


@pytest.mark.parametrize("path", [None, 3, math.nan, ["a.toml"], {}, "", "a\0.toml", HUGE])
@pytest.mark.parametrize(("read", "name"), [(read_rig_file, "path"), (load_rig, "name_or_path")])
def test_rig_readers_refuse_what_is_no_path(read, name, path):
    with pytest.raises(PerceptionError, match=rf"^{name}: .* is not a path"):
        read(path)


@pytest.mark.parametrize("name", [None, 3, [], {}, HUGE])
def test_rig_path_refuses_a_name_that_is_no_string(name):
    with pytest.raises(PerceptionError, match=r"^name: .* is not a string"):
        rig_path(name)


@pytest.mark.parametrize("data", [None, 1.5, "rig", ["name"], HUGE])
def test_rig_from_mapping_refuses_data_that_is_no_table(data):
    with pytest.raises(PerceptionError, match=r"^data: .* is not a mapping"):
        rig_from_mapping(data)


@pytest.mark.parametrize("source", [3, math.nan, np.array([]), Path("rig.toml")])
def test_rig_from_mapping_refuses_a_source_that_is_no_string(source):
    with pytest.raises(PerceptionError, match=r"^source: .* is not a string"):
        rig_from_mapping({"name": "x"}, source=source)


@pytest.mark.parametrize(
    ("width", "height", "name"),
    [(None, 48, "width"), ("64", 48, "width"), (10**5000, 48, "width"), (64, [], "height")],
    ids=["none", "text", "huge", "list"],
)
def test_intrinsics_from_fov_checks_the_size_first(width, height, name):
    with pytest.raises(PerceptionError, match=rf"^{name}: "):
        Intrinsics.from_fov(width, height, 90.0)


@pytest.mark.parametrize("camera", NOT_OBJECTS)
@pytest.mark.parametrize(
    "call",
    [
        lambda camera: to_gray(IMAGE, camera),
        lambda camera: detect_markers(IMAGE, camera, CARRIER),
        lambda camera: render(camera, CARRIER, [PLACEMENT], rng=np.random.default_rng(0)),
        lambda camera: visible_markers(camera, CARRIER, [PLACEMENT]),
    ],
)
def test_camera_arguments_must_be_cameras(call, camera):
    with pytest.raises(PerceptionError, match=r"^camera: .* is not a Camera"):
        call(camera)


@pytest.mark.parametrize("carrier", NOT_OBJECTS)
@pytest.mark.parametrize(
    "call",
    [
        marker_frames,
        lambda carrier: detect_markers(IMAGE, FRONT, carrier),
        lambda carrier: fuse([], carrier),
        lambda carrier: render(FRONT, carrier, [PLACEMENT], rng=np.random.default_rng(0)),
        lambda carrier: visible_markers(FRONT, carrier, [PLACEMENT]),
    ],
)
def test_carrier_arguments_must_be_carrier_markers(call, carrier):
    with pytest.raises(PerceptionError, match=r"^carrier: .* is not a CarrierMarkers"):
        call(carrier)


@pytest.mark.parametrize("placements", [None, 1.5, "x", PLACEMENT, ["x"], [[7, 1.0, 0.0]]])
@pytest.mark.parametrize(
    "call",
    [
        lambda p: render(FRONT, CARRIER, p, rng=np.random.default_rng(0)),
        lambda p: visible_markers(FRONT, CARRIER, p),
    ],
)
def test_placements_must_be_a_list_of_placements(call, placements):
    with pytest.raises(PerceptionError, match=r"^placements: "):
        call(placements)


@pytest.mark.parametrize("conditions", [None, 0.5, {"blur": 1.0}])
def test_render_refuses_conditions_of_another_kind(conditions):
    with pytest.raises(PerceptionError, match=r"^conditions: .* is not a Conditions"):
        render(FRONT, CARRIER, [PLACEMENT], conditions, rng=np.random.default_rng(0))


@pytest.mark.parametrize("margin", [None, "1", [], math.nan, -1.0, HUGE])
def test_visible_markers_refuses_a_bad_margin(margin):
    with pytest.raises(PerceptionError, match=r"^margin: "):
        visible_markers(FRONT, CARRIER, [PLACEMENT], margin=margin)


@pytest.mark.parametrize("detections", [None, 1.5, True, HUGE, "abc", {"a": 1}])
@pytest.mark.parametrize("call", [lambda d: fuse(d, CARRIER), centring_offset])
def test_detections_must_be_iterable(call, detections):
    with pytest.raises(PerceptionError, match=r"^detections: .* is not a list of MarkerDetection"):
        call(detections)


@pytest.mark.parametrize("marker", ["7", 7.0, math.nan, -1, 250, HUGE])
def test_centring_offset_refuses_a_marker_that_is_no_id(marker):
    with pytest.raises(PerceptionError, match=r"^marker: "):
        centring_offset([], marker)


@pytest.mark.parametrize(
    ("arguments", "name"),
    [
        ({"rig": None}, "rig"),
        ({"rig": "dots-like"}, "rig"),
        ({"distances": 1.0}, "distances"),
        ({"bearings": None}, "bearings"),
        ({"nuisance": Conditions()}, "nuisance"),
        ({"progress": 3}, "progress"),
    ],
)
def test_run_range_study_refuses_bad_arguments(arguments, name):
    given = {"rig": RIG, "distances": [1.0], "bearings": [0.0], "samples": 1, **arguments}
    with pytest.raises(PerceptionError, match=rf"^{name}: "):
        run_range_study(**given)


@pytest.mark.parametrize(
    ("arguments", "name"),
    [
        ({"study": None}, "study"),
        ({"path": None}, "path"),
        ({"path": "a\0.png"}, "path"),
        ({"marks": 3.6}, "marks"),
        ({"marks": [3.6]}, "marks"),
        ({"marks": [(math.nan, "x")]}, "marks"),
        ({"marks": [(3.6, 5)]}, "marks"),
    ],
)
def test_plot_range_study_refuses_bad_arguments_before_drawing(arguments, name, tmp_path):
    study = RangeStudy.__new__(RangeStudy)  # never drawn: the arguments are refused first
    given = {"study": study, "path": tmp_path / "range.png", **arguments}
    with pytest.raises(PerceptionError, match=rf"^{name}: "):
        plot_range_study(given.pop("study"), given.pop("path"), **given)
    assert list(tmp_path.iterdir()) == []
