"""Finding a carrier's ArUco markers in one camera image: id, corners and pose (SPEC §3.1, §7).

Carriers carry 50 mm markers of OpenCV's ``DICT_ARUCO_MIP_36h12`` (6 x 6 bits,
250 ids, minimum Hamming distance 12) on their four faces and their underside.
``detect_markers`` finds them with ``cv2.aruco.ArucoDetector`` (sub-pixel
corner refinement), reads the candidates it rejected a second time at sub-pixel
corners (``_bits``), and recovers each marker's pose with ``cv2.solvePnPGeneric``
and ``SOLVEPNP_IPPE_SQUARE``, which returns both poses a square admits; the one
whose normal fits where a marker can hang (on a vertical face, or on the
underside facing down; never facing up) is kept when the two reproject about
equally well (far away, they do).

Each ``MarkerDetection`` is in the robot frame (``swarmtag.perception.camera``):
the marker's centre, its outward normal, the horizontal ``distance`` and
``bearing`` from the robot's centre, and the carrier centre it implies.

The marker frames on a carrier (``marker_frames``) are the one definition both
the detector and the synthetic renderer (``synth``) use: a face marker's x axis
runs along the face (to the right, seen from outside), its y axis up, its z
axis out of the face; the underside marker's x axis points to the carrier's
east face and its z axis down.

A carrier with an underside map (``marker_map``; the DOTS carriers') carries a
grid of smaller markers there instead of the fifth marker: ``detect_markers``
takes each map id's pose with the map's marker size and marks the detection
with the map (``map_id``) and the marker's place on it (``map_offset``), so the
carrier's centre can be found from any part of the map (``fusion``).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from enum import IntEnum
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag import _interrupt
from swarmtag._checks import show
from swarmtag.errors import PerceptionError
from swarmtag.perception._bits import read_candidate
from swarmtag.perception._opencv import opencv
from swarmtag.perception.camera import Camera, CarrierMarkers, check_camera, check_carrier

__all__ = [
    "DICTIONARY",
    "MARKER_IDS",
    "Face",
    "MarkerDetection",
    "MarkerFrame",
    "detect_markers",
    "marker_frames",
    "to_gray",
]

Float = NDArray[np.float64]

DICTIONARY: Final = "DICT_ARUCO_MIP_36h12"
"""The markers' OpenCV dictionary (SPEC §7: ``ARUCO_MIP_36h12``)."""
MARKER_IDS: Final = 250
"""Ids the dictionary holds: 0-249 (a tag's marker byte may say 250-255: no marker prints)."""
AMBIGUITY_PIXELS: Final = 0.5
"""Two IPPE poses whose reprojection errors differ by less than this (px) are a tie."""
REFINEMENT_MODULES: Final = 1.0
"""Corner refinement window, in marker modules (see ``_detector``)."""
MIN_PERIMETER_RATE: Final = 0.02
"""Smallest marker perimeter tried, as a share of the image's larger side: 38 px at 1920 px,
a side of about 1.2 px per module, where the bits stop being readable (see ``_detector``)."""
BORDER_PIXELS: Final = 3.0
"""A marker with a corner nearer the image's edge than this (px) is dropped: it may be cut off.
OpenCV's ``minDistanceToBorder`` default, applied to the marker itself (see ``_detector``)."""
SECOND_READ_RMS: Final = 1.0
"""Most RMS reprojection error (px) of a marker found only by the second read (``_bits``):
its corners must fit a square; a candidate with a stray corner can still decode."""
UNDERSIDE_COSINE: Final = math.cos(math.radians(45.0))
"""A marker whose normal points down by more than 45 degrees is an underside marker."""
SQPNP_MIN_SPREAD: Final = 2e-5
"""Least spread (variance, both axes summed) of a marker's corners in normalized image
coordinates for which ``SOLVEPNP_SQPNP`` is asked: OpenCV's solver asserts at 1e-5
(``POINT_VARIANCE_THRESHOLD``), which a marker under 0.45 % of the focal length across
falls below (a 20 px marker under a 4,500 px focal length: a narrow lens). Twice that, so
that rounding never reaches OpenCV's assertion; IPPE alone poses such a marker."""


class Face(IntEnum):
    """Which face a marker is on: the simulator's face order, then the underside."""

    EAST = 0
    NORTH = 1
    WEST = 2
    SOUTH = 3
    UNDERSIDE = 4


@dataclass(frozen=True, eq=False)
class MarkerFrame:
    """One marker on a carrier, in the carrier's frame (origin on the floor under its centre).

    ``centre`` and the unit axes ``x``, ``y``, ``z`` (z out of the marker) are shape (3,).
    """

    face: Face
    centre: Float
    x: Float
    y: Float
    z: Float

    def corners(self, size: float) -> Float:
        """The black square's corners (4, 3) in OpenCV's order: top-left, top-right, ..."""
        half = size / 2
        signs = np.array([[-1.0, 1.0], [1.0, 1.0], [1.0, -1.0], [-1.0, -1.0]]) * half
        return self.centre + signs[:, :1] * self.x + signs[:, 1:] * self.y

    def shifted(self, offset: Float) -> MarkerFrame:
        """This frame moved in its own plane by ``offset`` (2,) along ``x`` and ``y`` (m).

        A map marker's frame: the underside frame moved to the marker's place on the map.
        """
        shift = float(offset[0]) * self.x + float(offset[1]) * self.y
        return MarkerFrame(self.face, self.centre + shift, self.x, self.y, self.z)


def marker_frames(carrier: CarrierMarkers) -> tuple[MarkerFrame, ...]:
    """The carrier's five markers: one per face (east, north, west, south), then the underside.

    >>> [frame.face.name for frame in marker_frames(CarrierMarkers())][:2]
    ['EAST', 'NORTH']
    """
    check_carrier(carrier)
    up = np.array([0.0, 0.0, 1.0])
    frames = []
    for face in (Face.EAST, Face.NORTH, Face.WEST, Face.SOUTH):
        angle = math.pi / 2 * face
        normal = np.array([math.cos(angle), math.sin(angle), 0.0]).round(15)
        centre = normal * carrier.half + up * carrier.marker_height
        frames.append(MarkerFrame(face, centre, np.cross(up, normal), up, normal))
    down = -up
    east = np.array([1.0, 0.0, 0.0])
    centre = up * carrier.underside_height
    frames.append(MarkerFrame(Face.UNDERSIDE, centre, east, np.cross(down, east), down))
    return tuple(frames)


def _horizontal(vector: Float) -> Float:
    flat = np.array([vector[0], vector[1], 0.0])
    norm = float(np.hypot(flat[0], flat[1]))
    return flat / norm if norm > 1e-12 else np.array([1.0, 0.0, 0.0])


@dataclass(frozen=True, eq=False)
class MarkerDetection:
    """One marker found in one image, its pose in the robot frame.

    ``marker``: its id; ``camera``: the camera's name, ``upward`` whether it is
    the upward camera (then this is an underside marker); ``corners`` (4, 2):
    image corners in OpenCV's order (pixels); ``position`` (3,): the marker's
    centre; ``normal`` (3,): its outward unit normal; ``axis`` (3,): its x axis;
    ``camera_distance``: from the camera to the marker's centre (m);
    ``reprojection_error``: RMS of the kept pose (px); ``alternatives``: the
    normals (3,) of the other poses that reproject about as well (a square's
    pose is ambiguous from afar), which ``fuse`` may pick instead.

    A marker of the carrier's underside map also has ``map_id``, the map's first id
    (the id the DOTS robot's vision node reports for the whole map: 200), and
    ``map_offset`` (2,), its centre in the map's frame (m; ``marker_map``); both are
    None for any other marker. A map marker names no carrier (every carrier carries
    the same map): ``fuse`` leaves it out and ``centring_offset`` reads it.
    """

    marker: int
    camera: str
    upward: bool
    corners: Float
    position: Float
    normal: Float
    axis: Float
    camera_distance: float
    reprojection_error: float
    alternatives: tuple[Float, ...] = ()
    map_id: int | None = None
    map_offset: Float | None = None

    @property
    def in_map(self) -> bool:
        """Whether this is a marker of the carrier's underside map (it names no carrier)."""
        return self.map_id is not None

    @property
    def distance(self) -> float:
        """Horizontal distance from the robot's centre to the marker's centre (m)."""
        return float(np.hypot(self.position[0], self.position[1]))

    @property
    def bearing(self) -> float:
        """Direction of the marker's centre from the robot's centre (deg, counter-clockwise)."""
        return math.degrees(math.atan2(self.position[1], self.position[0]))

    @property
    def underside(self) -> bool:
        """Whether this is an underside marker: seen by the upward camera, or facing down."""
        return self.upward or float(self.normal[2]) < -UNDERSIDE_COSINE

    @property
    def side_pixels(self) -> float:
        """Mean side of the marker in the image (px): how well it is resolved."""
        sides = np.linalg.norm(self.corners - np.roll(self.corners, -1, axis=0), axis=1)
        return float(sides.mean())

    def face_direction(self) -> float:
        """Direction (deg, robot frame) of the face normal (side) or of the carrier's east face."""
        vector = self.axis if self.underside else _horizontal(self.normal)
        return math.degrees(math.atan2(vector[1], vector[0]))

    def with_normal(self, normal: Float) -> MarkerDetection:
        """This detection with another of its candidate normals kept (the rest alternatives)."""
        candidates = [self.normal, *self.alternatives]
        rest = tuple(n for n in candidates if not np.array_equal(n, normal))
        if len(rest) == len(candidates):
            msg = f"marker {self.marker}: {np.round(normal, 3)} is not one of its candidate normals"
            raise PerceptionError(msg)
        return dataclasses.replace(self, normal=normal, alternatives=rest)

    def carrier_centre(self, carrier: CarrierMarkers, direction: float | None = None) -> Float:
        """The carrier's centre (2,) this marker implies: behind a face marker by half a side.

        ``direction`` (deg, robot frame) replaces the measured face normal's direction
        (a map marker's: the carrier's east face direction, which places the marker on
        the map). An underside marker is under the centre; a map marker is its
        ``map_offset`` away from it.
        """
        if self.map_offset is not None:
            return self.map_centre(direction)[:2]
        if self.underside:
            return self.position[:2].copy()
        if direction is None:
            normal = _horizontal(self.normal)[:2]
        else:
            angle = math.radians(direction)
            normal = np.array([math.cos(angle), math.sin(angle)])
        return self.position[:2] - normal * carrier.half

    def map_centre(self, direction: float | None = None) -> Float:
        """The underside map's centre (3,) this map marker implies: the carrier's centre above.

        The map's frame is placed by the marker's own axis or, given ``direction``
        (deg, robot frame), by that east face direction on a level underside.
        """
        if self.map_offset is None:
            msg = f"marker {self.marker} is not a map marker"
            raise PerceptionError(msg)
        x_axis, normal = self.axis, self.normal
        if direction is not None:
            angle = math.radians(direction)
            x_axis = np.array([math.cos(angle), math.sin(angle), 0.0])
            normal = np.array([0.0, 0.0, -1.0])
        y_axis = np.cross(normal, x_axis)
        shift = float(self.map_offset[0]) * x_axis + float(self.map_offset[1]) * y_axis
        centre: Float = self.position - shift
        return centre

    def face(self, heading: float) -> Face:
        """The face this marker is on, for a robot whose heading is ``heading`` deg (world frame).

        Carriers stand square to the world's axes, as in the simulator; the face is
        the world direction of the marker's normal, to the nearest 90 degrees.
        """
        if self.underside:
            return Face.UNDERSIDE
        world = heading + self.face_direction()
        return Face(round(world / 90.0) % 4)


# --- detection --------------------------------------------------------------------------------


@functools.cache
def _detector() -> Any:  # noqa: ANN401 - a cv2.aruco.ArucoDetector
    """The detector: OpenCV's defaults but three, each measured on the range study's images.

    ``cornerSubPix`` searches ``min(cornerRefinementWinSize, relativeCornerRefinmentWinSize
    x module)`` pixels around each corner. OpenCV's default factor (0.3 of a module) leaves
    a far marker's corners almost unrefined, and they sit inside the true corners (the
    marker looks smaller, so farther: +2 % at 2 m on the range study's images); one module,
    the width of the black border and of the white quiet zone around it, keeps the window
    on the corner alone and halves that error (docs/perception.md). The size filter
    (``minMarkerPerimeterRate``, a share of the image's larger side) is lowered from 0.03
    to ``MIN_PERIMETER_RATE``: 0.03 of 1920 px refused far markers whose bits were still
    readable, and a 36h12 code (Hamming distance 12) keeps false ids out either way.

    ``minDistanceToBorder`` is 0 and ``detect_markers`` applies ``BORDER_PIXELS`` to each
    marker's own corners instead: recent OpenCV (since opencv/opencv#26968, 2025) groups a
    marker's nested contours (its black square, its white surround, the panel around that)
    and tests only the group's largest against the image's edge, so a whole 90 px marker
    15 px from the edge was dropped because the panel around it ran off the image
    (docs/perception.md).
    """
    cv2 = opencv()
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_ARUCO_MIP_36h12)
    parameters = cv2.aruco.DetectorParameters()
    parameters.cornerRefinementMethod = cv2.aruco.CORNER_REFINE_SUBPIX
    parameters.relativeCornerRefinmentWinSize = REFINEMENT_MODULES
    parameters.minMarkerPerimeterRate = MIN_PERIMETER_RATE
    parameters.minDistanceToBorder = 0
    return cv2.aruco.ArucoDetector(dictionary, parameters)


def to_gray(image: object, camera: Camera) -> NDArray[np.uint8]:
    """``image`` as an 8-bit grey array of the camera's size; ``PerceptionError`` otherwise.

    Accepts (H, W) grey or (H, W, 3) BGR arrays of dtype uint8.
    """
    check_camera(camera)
    if not isinstance(image, np.ndarray) or image.dtype != np.uint8:
        kind = image.dtype if isinstance(image, np.ndarray) else type(image).__name__
        msg = f"image: expected an 8-bit (uint8) numpy array, got {kind}"
        raise PerceptionError(msg)
    array: NDArray[np.uint8] = image
    if array.ndim == 3 and array.shape[2] == 3:
        array = opencv().cvtColor(array, opencv().COLOR_BGR2GRAY)
    if array.ndim != 2:
        msg = f"image: shape {array.shape} is neither grey (H, W) nor colour (H, W, 3)"
        raise PerceptionError(msg)
    lens = camera.intrinsics
    if array.shape != (lens.height, lens.width):
        msg = f"image is {array.shape[1]}x{array.shape[0]} but camera {camera.name!r} is "
        msg += f"{lens.width}x{lens.height}; give the camera file of the camera that took it"
        raise PerceptionError(msg)
    gray: NDArray[np.uint8] = np.ascontiguousarray(array)
    return gray


def _square(size: float) -> Float:
    """The marker's object points in its own frame, in IPPE_SQUARE's required order."""
    half = size / 2
    return np.array(
        [[-half, half, 0.0], [half, half, 0.0], [half, -half, 0.0], [-half, -half, 0.0]]
    )


def _misfit(normal: Float, *, upward: bool) -> float:
    """How far a normal is from where a marker can hang (0: on a vertical face, or facing down).

    The upward camera sees only underside markers; a perimeter camera sees face markers
    and, from below at a slant, underside markers too; no marker ever faces up.
    """
    down = 1.0 + float(normal[2])
    return down if upward else min(abs(float(normal[2])), down)


def _spread(corners: Float, camera: Camera) -> float:
    """Variance of the corners in normalized image coordinates, as OpenCV's SQPnP computes it."""
    lens = camera.intrinsics
    points = (
        opencv()
        .undistortPoints(
            np.ascontiguousarray(corners, dtype=np.float64).reshape(-1, 1, 2),
            lens.matrix,
            lens.coefficients,
        )
        .reshape(-1, 2)
    )
    return float(np.mean(np.sum(points**2, axis=1)) - np.sum(points.mean(axis=0) ** 2))


def _pose(
    corners: Float, camera: Camera, size: float
) -> tuple[Float, Float, float, tuple[Float, ...]] | None:
    """The marker's pose, and the normals of the poses that tie with it; None if none is possible.

    The pose: rotation (3, 3), translation (3,) in the camera frame, RMS error (px);
    the tied normals are in the robot frame.

    IPPE_SQUARE gives the two poses a square admits; SQPNP is asked too, because
    OpenCV's IPPE returns a zero rotation for an exactly symmetric view (its
    rotation-to-vector step divides by sin(pi) there), unless the marker is too small
    a part of the view for it (``SQPNP_MIN_SPREAD``). Poses facing up are impossible
    (no marker faces up) and are dropped: they come from markers seen nearly edge-on,
    such as an underside seen by a perimeter camera from far below its plane.
    """
    cv2 = opencv()
    lens = camera.intrinsics
    options = []
    methods = [cv2.SOLVEPNP_IPPE_SQUARE]
    if _spread(corners, camera) >= SQPNP_MIN_SPREAD:
        methods.append(cv2.SOLVEPNP_SQPNP)
    for method in methods:
        count, rotations, translations, errors = cv2.solvePnPGeneric(
            _square(size), corners, lens.matrix, lens.coefficients, flags=method
        )
        rms = np.asarray(errors, dtype=np.float64).ravel()
        for i in range(int(count)):
            translation = np.asarray(translations[i], dtype=np.float64).ravel()
            if not (np.all(np.isfinite(rotations[i])) and np.all(np.isfinite(translation))):
                continue
            rotation, _ = cv2.Rodrigues(rotations[i])
            normal = camera.mount.rotation @ rotation[:, 2]
            if float(normal[2]) > UNDERSIDE_COSINE:  # facing up: impossible
                continue
            options.append(
                (rotation, translation, float(rms[i]), _misfit(normal, upward=camera.upward))
            )
    if not options:
        return None
    best = min(error for _, _, error, _ in options)
    tied = sorted((o for o in options if o[2] <= best + AMBIGUITY_PIXELS), key=lambda o: o[3])
    rotation, translation, error, _ = tied[0]
    kept = camera.mount.rotation @ rotation[:, 2]
    others: list[Float] = []
    for other, _, _, _ in tied[1:]:
        normal = camera.mount.rotation @ other[:, 2]
        if all(float(normal @ seen) < 0.999 for seen in [kept, *others]):  # a different pose
            others.append(normal)
    return rotation, translation, error, tuple(others)


def _inside(points: Float, gray: NDArray[np.uint8]) -> bool:
    """Whether every corner is at least ``BORDER_PIXELS`` inside the image."""
    high = np.array([gray.shape[1], gray.shape[0]], dtype=np.float64) - 1.0 - BORDER_PIXELS
    return bool(np.all((points >= BORDER_PIXELS) & (points <= high)))


def _found(gray: NDArray[np.uint8]) -> list[tuple[int, Float, bool]]:
    """(id, corners (4, 2), whether by the second read) of every marker in the image.

    OpenCV's detections first; then each candidate it rejected is read again at
    sub-pixel corners (``_bits``), unless it touches the image's edge (it would be
    dropped) or its centre lies in a marker already found (the inner contours of a
    found marker are candidates too).
    """
    cv2 = opencv()
    detector = _detector()
    corners, ids, rejected = detector.detectMarkers(gray)
    marker_ids = np.zeros(0, dtype=np.int32) if ids is None else np.asarray(ids).ravel()
    found = [
        (int(marker), np.asarray(points, dtype=np.float64).reshape(4, 2), False)
        for marker, points in zip(marker_ids, corners, strict=True)
    ]
    for candidate in rejected:
        quad = np.asarray(candidate, dtype=np.float64).reshape(4, 2)
        if not _inside(quad, gray):
            continue
        centre = (float(quad[:, 0].mean()), float(quad[:, 1].mean()))
        if any(
            cv2.pointPolygonTest(points.astype(np.float32), centre, False) >= 0
            for _, points, _ in found
        ):
            continue
        read = read_candidate(gray, quad, detector)
        if read is not None:
            found.append((read[0], read[1], True))
    return found


def detect_markers(
    image: object, camera: Camera, carrier: CarrierMarkers
) -> tuple[MarkerDetection, ...]:
    """Every marker of the dictionary found in ``image`` taken by ``camera``, sorted by id.

    ``carrier`` gives the markers' size (pose) and where they hang; an id of its
    underside map (if it has one) is a map marker, posed with the map's marker size
    and marked with its place on the map. Left out: a marker
    with a corner within ``BORDER_PIXELS`` of the image's edge (it may be cut off), one
    with no possible pose (see ``_pose``), and one found only by the second read whose
    corners do not fit a square (``SECOND_READ_RMS``). Raises ``PerceptionError`` for an
    image that is not this camera's, ``ConfigError`` when OpenCV (the ``vision`` extra)
    is missing. The search runs in a helper thread (``_interrupt.in_thread``), so that
    Ctrl-C ends it at once even on a large image.
    """
    check_camera(camera)
    check_carrier(carrier)
    opencv()  # refuses in one line when the extra is missing (the detector may be cached)
    gray = to_gray(image, camera)
    mount = camera.mount
    grid = carrier.underside_map
    found = []
    for marker, image_points, second in _interrupt.in_thread(lambda: _found(gray)):
        _interrupt.checkpoint()
        if not _inside(image_points, gray):
            continue
        pose = _pose(image_points, camera, carrier.size_of(marker))
        if pose is None:
            continue
        rotation, translation, error, others = pose
        if second and error > SECOND_READ_RMS:
            continue
        found.append(
            MarkerDetection(
                marker=marker,
                camera=camera.name,
                upward=camera.upward,
                corners=image_points,
                position=mount.to_robot(translation),
                normal=mount.rotation @ rotation[:, 2],
                axis=mount.rotation @ rotation[:, 0],
                camera_distance=float(np.linalg.norm(translation)),
                reprojection_error=error,
                alternatives=others,
                map_id=grid.first_id if grid is not None and grid.holds(marker) else None,
                map_offset=grid.offset(marker) if grid is not None and grid.holds(marker) else None,
            )
        )
    return tuple(sorted(found, key=lambda d: (d.marker, d.corners[0, 0], d.corners[0, 1])))


def detection_items(name: str, detections: object) -> Iterable[object]:
    """``detections`` if it can be iterated (a list, tuple, generator), else ``PerceptionError``."""
    if isinstance(detections, str | bytes | Mapping) or not isinstance(detections, Iterable):
        msg = f"{name}: {show(detections)} is not a list of MarkerDetection"
        raise PerceptionError(msg)
    return detections
