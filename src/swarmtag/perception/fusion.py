"""From marker detections to carriers: one position per carrier, its predock point, centring.

A carrier shows up to five markers, all with its own id (SPEC §7; docs/perception.md),
and several cameras may see it at once. ``fuse`` turns every detection of one
id into one ``CarrierEstimate``:

- each face marker puts the carrier's centre half a side behind it, along its
  (horizontal) normal; an underside marker puts it straight above;
- the estimates are averaged with weights ``side_pixels ** 4``: a marker's depth
  error grows with the square of its distance, so its variance with the fourth
  power, and its image size falls with distance;
- the carrier's orientation is known only up to its square's symmetry from a
  face marker (every face looks the same): the face directions are averaged
  modulo 90 degrees (the circular mean of four times the angle);
- a marker far away has two poses that reproject about equally well (mirror
  images about the line of sight); ``fuse`` keeps, for each detection, the
  candidate normal that agrees best with the others (the faces of a square are
  90 degrees apart) or, given the robot's ``heading``, with the world's axes
  (carriers stand square to the arena, as in the simulator); with a heading
  the face normals are then taken on those axes exactly.

``CarrierEstimate.predock`` is the point in front of the face nearest the robot
at ``predock_distance`` from that face (the simulator's rule, SPEC §3.2 and
§4.1), with the heading that faces the carrier. ``centring_offset`` reads the
upward camera's view of the underside marker: how far the carrier's centre is
from the robot's, and how it is turned, so the robot can centre under it.

A carrier with an underside map (``marker_map``; the DOTS carriers') shows the
upward camera many small markers, each at a known place on the map, and names
no carrier with them (every carrier carries the same map): ``fuse`` leaves map
markers out, and ``centring_offset`` combines every one in view the way ``fuse``
combines a carrier's markers: the map's turn is the weighted circular mean of
the markers' x axes, each marker then puts the map's centre its known offset
away along that turn, and the centres are averaged with weights
``side_pixels ** 4``. Any part of the map will do; more markers average more
corner noise away (docs/perception.md gives the accuracy).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import check_int, check_number
from swarmtag.errors import PerceptionError
from swarmtag.perception.camera import CarrierMarkers, check_carrier
from swarmtag.perception.markers import MARKER_IDS, Face, MarkerDetection, detection_items

__all__ = [
    "CENTRED_TOLERANCE",
    "PREDOCK_DISTANCE",
    "CarrierEstimate",
    "CentringOffset",
    "Predock",
    "centring_offset",
    "fuse",
]

Float = NDArray[np.float64]

PREDOCK_DISTANCE: Final = 0.175
"""Default predock distance (m, face to robot centre): the simulator's motion.predock_distance."""
CENTRED_TOLERANCE: Final = 0.01
"""Default centring tolerance (m): the simulator's ``motion.arrival_tolerance``."""
MAX_COMBINATIONS: Final = 256
"""Most combinations of candidate normals tried for one carrier (beyond: each keeps its own)."""


def _wrap(angle: float) -> float:
    """``angle`` (deg) in (-180, 180]."""
    wrapped = (angle + 180.0) % 360.0 - 180.0
    return 180.0 if wrapped == -180.0 else wrapped + 0.0


@dataclass(frozen=True, slots=True)
class Predock:
    """Where to stand before docking, in the robot frame.

    ``point`` (2,): the predock point; ``heading`` (deg): the direction that faces
    the carrier from there; ``face_direction`` (deg): the outward normal of the face
    it is in front of.
    """

    point: Float
    heading: float
    face_direction: float

    def face(self, heading: float) -> Face:
        """That face's name, for a robot whose heading is ``heading`` deg in the world frame."""
        return Face(round((heading + self.face_direction) / 90.0) % 4)


@dataclass(frozen=True, eq=False)
class CarrierEstimate:
    """One carrier as the cameras see it now, in the robot frame.

    ``marker``: its id; ``position`` (2,): its centre (m); ``yaw``: the
    direction of one of its face normals (deg), exact modulo 90 (its faces are
    alike) unless the underside marker was seen (then the east face's);
    ``markers``: how many detections were fused; ``spread``: the largest
    distance between one detection's centre and the fused one (m), a check on
    consistency; ``cameras``: which cameras saw it.
    """

    marker: int
    position: Float
    yaw: float
    markers: int
    spread: float
    cameras: tuple[str, ...]

    @property
    def distance(self) -> float:
        """Distance from the robot's centre to the carrier's (m): the ``d`` of SPEC §3.3."""
        return float(np.hypot(self.position[0], self.position[1]))

    @property
    def bearing(self) -> float:
        """Direction of the carrier's centre (deg, counter-clockwise from forward)."""
        return math.degrees(math.atan2(self.position[1], self.position[0]))

    def predock(
        self, carrier: CarrierMarkers, predock_distance: float = PREDOCK_DISTANCE
    ) -> Predock:
        """The predock point of the face whose point is nearest the robot (ties: lowest angle)."""
        gap = check_number(
            "predock_distance", predock_distance, low=0.0, high=100.0, error=PerceptionError
        )
        offset = carrier.half + gap
        best: tuple[float, Float, float] | None = None
        for k in range(4):
            direction = _wrap(self.yaw + 90.0 * k)
            angle = math.radians(direction)
            point = self.position + offset * np.array([math.cos(angle), math.sin(angle)])
            reach = float(np.hypot(point[0], point[1]))
            if best is None or reach < best[0] - 1e-12:
                best = (reach, point, direction)
        assert best is not None
        _, point, direction = best
        heading = _wrap(direction + 180.0)
        return Predock(point.round(12) + 0.0, heading, direction)


def fuse(
    detections: Iterable[MarkerDetection], carrier: CarrierMarkers, *, heading: float | None = None
) -> tuple[CarrierEstimate, ...]:
    """One estimate per marker id among ``detections`` (any cameras), sorted by id.

    ``heading`` (deg, world frame), where the robot knows it, lets the faces be
    taken on the world's axes. Markers of an underside map are left out: they name
    no carrier (``centring_offset`` reads them).
    """
    check_carrier(carrier)
    if heading is not None:
        heading = check_number("heading", heading, low=-1e4, high=1e4, error=PerceptionError)
    groups: dict[int, list[MarkerDetection]] = {}
    for item in detection_items("detections", detections):
        detection: object = item  # checked at run time: a library entry point
        if not isinstance(detection, MarkerDetection):
            msg = f"fuse: expected MarkerDetection items, got {type(detection).__name__}"
            raise PerceptionError(msg)
        if not detection.in_map:
            groups.setdefault(detection.marker, []).append(detection)
    return tuple(_fuse_one(marker, groups[marker], carrier, heading) for marker in sorted(groups))


def _agreement(directions: Float, weights: Float) -> float:
    """How well face directions (deg) agree modulo 90: the weighted resultant of 4 x angle."""
    angles = np.radians(4.0 * directions)
    return float(np.hypot(weights @ np.cos(angles), weights @ np.sin(angles)))


def _resolve(
    group: list[MarkerDetection], weights: Float, heading: float | None
) -> list[MarkerDetection]:
    """Each detection with the candidate normal that agrees best (see the module docstring)."""
    options = [[d, *(d.with_normal(n) for n in d.alternatives)] for d in group]
    if heading is not None:

        def off_axes(d: MarkerDetection) -> float:
            return 1.0 - math.cos(math.radians(4.0 * (d.face_direction() + heading)))

        return [min(choices, key=off_axes) for choices in options]
    if len(group) < 2 or math.prod(len(choices) for choices in options) > MAX_COMBINATIONS:
        return group
    best, score = group, _agreement(np.array([d.face_direction() for d in group]), weights)
    for combination in itertools.product(*options):
        candidate = _agreement(np.array([d.face_direction() for d in combination]), weights)
        if candidate > score + 1e-12:
            best, score = list(combination), candidate
    return best


def _fuse_one(
    marker: int, group: list[MarkerDetection], carrier: CarrierMarkers, heading: float | None
) -> CarrierEstimate:
    weights = np.array([d.side_pixels for d in group]) ** 4
    weights = weights / weights.sum()
    group = _resolve(group, weights, heading)
    directions = np.array([d.face_direction() for d in group])
    if heading is not None:  # the faces lie on the world's axes: take the nearest
        directions = np.round((directions + heading) / 90.0) * 90.0 - heading
    underside = [i for i, d in enumerate(group) if d.underside]
    if underside:  # the underside marker knows which face is east
        best = max(underside, key=lambda i: group[i].side_pixels)
        yaw = _wrap(float(directions[best]))
    else:
        angles = np.radians(4.0 * directions)
        mean = math.atan2(float(weights @ np.sin(angles)), float(weights @ np.cos(angles)))
        yaw = _wrap(math.degrees(mean) / 4.0)
    centres = np.array(
        [d.carrier_centre(carrier, float(a)) for d, a in zip(group, directions, strict=True)]
    )
    position = weights @ centres
    spread = float(np.max(np.linalg.norm(centres - position, axis=1)))
    cameras = tuple(sorted({d.camera for d in group}))
    return CarrierEstimate(marker, position, yaw, len(group), spread, cameras)


@dataclass(frozen=True, slots=True)
class CentringOffset:
    """What the upward camera says about the carrier above the robot.

    ``marker``: its id (from an underside map: the map's first id, as the DOTS
    robot reports it); ``offset`` (2,): the carrier's centre minus the robot's (m,
    robot frame: the move that centres the robot); ``yaw``: the carrier's east face
    direction relative to the robot's forward axis (deg); ``height``: the underside
    marker's height above the floor (m); ``markers``: how many markers it comes
    from (one underside marker, or the map markers in view).
    """

    marker: int
    offset: Float
    yaw: float
    height: float
    markers: int = 1

    @property
    def error(self) -> float:
        """How far off centre the robot is (m)."""
        return float(np.hypot(self.offset[0], self.offset[1]))

    def centred(self, tolerance: float = CENTRED_TOLERANCE) -> bool:
        """Whether the robot is within ``tolerance`` m of the carrier's centre."""
        limit = check_number("tolerance", tolerance, low=0.0, high=10.0, error=PerceptionError)
        return self.error <= limit


def centring_offset(
    detections: Iterable[MarkerDetection], marker: int | None = None
) -> CentringOffset | None:
    """The centring offset from the upward camera's detections (None if it sees no marker).

    ``marker`` picks the carrier being docked (or an underside map, by its first
    id); without it the map's markers in view are combined (module docstring) or,
    on carriers without a map, the largest marker in view is used. Detections from
    other cameras are refused: only the upward camera looks at an underside.
    """
    if marker is not None:
        marker = check_int("marker", marker, low=0, high=MARKER_IDS - 1, error=PerceptionError)
    chosen = []
    for item in detection_items("detections", detections):
        detection: object = item  # checked at run time: a library entry point
        if not isinstance(detection, MarkerDetection):
            msg = f"centring_offset: expected MarkerDetection items, got {type(detection).__name__}"
            raise PerceptionError(msg)
        if not detection.upward:
            msg = f"centring_offset: camera {detection.camera!r} is not the upward camera"
            raise PerceptionError(msg)
        if marker is None or marker in (detection.marker, detection.map_id):
            chosen.append(detection)
    if not chosen:
        return None
    mapped = [d for d in chosen if d.in_map]
    if mapped:
        return _map_alignment(mapped)
    best = max(chosen, key=lambda d: d.side_pixels)
    offset = best.position[:2].round(12) + 0.0
    height = float(best.position[2])
    return CentringOffset(best.marker, offset, _wrap(best.face_direction()), height)


def _map_alignment(group: list[MarkerDetection]) -> CentringOffset:
    """The carrier's centre and turn from the map markers in view (module docstring)."""
    weights = np.array([d.side_pixels for d in group]) ** 4
    weights = weights / weights.sum()
    angles = np.radians([d.face_direction() for d in group])
    yaw = math.degrees(math.atan2(float(weights @ np.sin(angles)), float(weights @ np.cos(angles))))
    centre = weights @ np.array([d.map_centre(yaw) for d in group])
    first = group[0].map_id
    assert first is not None  # only map markers are grouped here
    offset = centre[:2].round(12) + 0.0
    return CentringOffset(first, offset, _wrap(yaw), float(centre[2]), len(group))
