"""The robot's cameras (SPEC §3.1, §3.2, §7): ArUco markers, carrier poses, centring, range.

Carriers carry 50 mm ``ARUCO_MIP_36h12`` markers on their four faces and their
underside, all with the carrier's own marker id, or, like the DOTS carriers, a
map of small markers on the underside (ids 200-248, the same on every carrier;
docs/perception.md). This
package finds them in camera images with OpenCV (the ``vision`` extra, imported
on first use) and turns them into what the controller needs::

    from swarmtag.perception import detect_markers, fuse, load_rig

    rig = load_rig("dots-like")                     # or your own camera file
    front = rig.camera("front")
    found = detect_markers(image, front, rig.carrier)  # id, corners, pose
    for carrier in fuse(found, rig.carrier):        # one estimate per carrier
        carrier.distance, carrier.bearing, carrier.predock(rig.carrier)

- ``camera``: the typed camera model (intrinsics, distortion, mount) and rig files;
- ``marker_map``: an underside marker map (``UndersideMap``: grid, marker size, pitch, ids);
- ``markers``: detection and pose (``detect_markers``, ``MarkerDetection``);
- ``fusion``: one position per carrier, its predock point, the upward camera's
  centring offset from the underside marker or map (``fuse``, ``centring_offset``);
- ``synth``: synthetic camera images at known poses (``render``);
- ``range_study``: detection rate and distance error against distance and bearing.
"""

from __future__ import annotations

from swarmtag.perception._opencv import NEEDS_EXTRA
from swarmtag.perception.camera import (
    CAMERA_KINDS,
    DEFAULT_RIG,
    RIGS,
    Camera,
    CarrierMarkers,
    Intrinsics,
    Mount,
    Rig,
    load_rig,
    read_rig_file,
    rig_from_mapping,
    rig_path,
)
from swarmtag.perception.fusion import (
    CENTRED_TOLERANCE,
    PREDOCK_DISTANCE,
    CarrierEstimate,
    CentringOffset,
    Predock,
    centring_offset,
    fuse,
)
from swarmtag.perception.marker_map import UndersideMap
from swarmtag.perception.markers import (
    DICTIONARY,
    MARKER_IDS,
    Face,
    MarkerDetection,
    MarkerFrame,
    detect_markers,
    marker_frames,
    to_gray,
)
from swarmtag.perception.range_study import (
    LOOSE_RATE,
    MIN_RATE,
    Nuisance,
    RangeStudy,
    plot_range_study,
    run_range_study,
)
from swarmtag.perception.synth import Conditions, Placement, render, visible_markers

__all__ = [
    "CAMERA_KINDS",
    "CENTRED_TOLERANCE",
    "DEFAULT_RIG",
    "DICTIONARY",
    "LOOSE_RATE",
    "MARKER_IDS",
    "MIN_RATE",
    "NEEDS_EXTRA",
    "PREDOCK_DISTANCE",
    "RIGS",
    "Camera",
    "CarrierEstimate",
    "CarrierMarkers",
    "CentringOffset",
    "Conditions",
    "Face",
    "Intrinsics",
    "MarkerDetection",
    "MarkerFrame",
    "Mount",
    "Nuisance",
    "Placement",
    "Predock",
    "RangeStudy",
    "Rig",
    "UndersideMap",
    "centring_offset",
    "detect_markers",
    "fuse",
    "load_rig",
    "marker_frames",
    "plot_range_study",
    "read_rig_file",
    "render",
    "rig_from_mapping",
    "rig_path",
    "run_range_study",
    "to_gray",
    "visible_markers",
]
