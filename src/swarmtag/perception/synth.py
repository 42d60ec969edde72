"""Synthetic camera images of carriers at known poses: the ground truth for tests and evidence.

``render`` draws what one of the robot's cameras sees of carriers placed in the
robot frame (``Placement``): each face as a grey panel with a white label and
its ``cv2.aruco.generateImageMarker`` marker, the underside as a board with
its marker (or, on a carrier with an underside map, with the map's grid of
markers on white paper), over a uniform floor. Every face is a plane drawn through its
exact homography (no approximation), with 2-4x supersampling and area
averaging so that edges are anti-aliased as a sensor integrates them; faces
turned away are culled and nearer faces painted over farther ones; parts
behind the camera are clipped. A distorting lens is applied afterwards as a
remap of the ideal image (``cv2.undistortPoints`` gives, for every pixel, the
ideal ray it sees).

``Conditions`` then degrade the image the way a camera does: Gaussian blur
(defocus, motion), an exposure gain (clipped at white), Gaussian sensor noise,
and an optional partial occlusion: a dark bar over a fraction of every
marker's width, on a side drawn from the generator. Every random draw comes
from the ``numpy.random.Generator`` passed in, so one seed gives the same bytes.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import check_instance, check_int, check_number, check_sequence
from swarmtag.errors import PerceptionError
from swarmtag.perception._opencv import opencv
from swarmtag.perception.camera import (
    Camera,
    CarrierMarkers,
    Intrinsics,
    check_camera,
    check_carrier,
)
from swarmtag.perception.markers import MARKER_IDS, Face, MarkerFrame, marker_frames

__all__ = ["Conditions", "Placement", "render", "visible_markers"]

Float = NDArray[np.float64]

TEXELS_PER_MODULE: Final = 8
"""Texture resolution: texels per marker module (a module is 1/8 of the marker's side)."""
PANEL_HEIGHT: Final = 0.12
"""Height of the grey panel each face marker sits on (m), centred on the marker."""
NEAR: Final = 0.005
"""Nearest distance drawn in front of a camera (m); nearer parts are clipped."""
SHADES: Final = {
    "floor": 0.40,
    "panel": 0.62,
    "board": 0.55,
    "label": 0.92,
    "ink": 0.06,
    "occluder": 0.25,
}
"""Reflectances (0 black - 1 white) of the floor, face panel, underside board, label, ink."""


@dataclass(frozen=True, slots=True)
class Placement:
    """A carrier in the robot frame: its ``marker`` id, centre ``x``, ``y`` (m), ``yaw`` (deg).

    ``yaw`` is the direction of its east face's normal (robot frame).
    """

    marker: int
    x: float
    y: float
    yaw: float = 0.0

    def __post_init__(self) -> None:
        marker = check_int("marker", self.marker, low=0, high=MARKER_IDS - 1, error=PerceptionError)
        object.__setattr__(self, "marker", marker)
        for name in ("x", "y"):
            value = check_number(
                name, getattr(self, name), low=-1e3, high=1e3, error=PerceptionError
            )
            object.__setattr__(self, name, value)
        yaw = check_number("yaw", self.yaw, low=-1e4, high=1e4, error=PerceptionError)
        object.__setattr__(self, "yaw", yaw)

    @classmethod
    def at(cls, marker: int, distance: float, bearing: float, turn: float = 0.0) -> Placement:
        """The carrier ``distance`` m away at ``bearing`` deg, turned ``turn`` deg off square.

        ``turn`` 0: one face looks straight at the robot's centre.

        >>> Placement.at(7, 2.0, 90.0)
        Placement(marker=7, x=0.0, y=2.0, yaw=270.0)
        """
        d = check_number("distance", distance, low=0.0, high=1e3, error=PerceptionError)
        b = check_number("bearing", bearing, low=-360.0, high=360.0, error=PerceptionError)
        t = check_number("turn", turn, low=-360.0, high=360.0, error=PerceptionError)
        angle = math.radians(b)
        x, y = (round(d * math.cos(angle), 12) + 0.0, round(d * math.sin(angle), 12) + 0.0)
        return cls(marker, x, y, b + 180.0 + t)

    def to_robot(self, points: Float) -> Float:
        """Carrier-frame points (..., 3) in the robot frame."""
        yaw = math.radians(self.yaw)
        c, s = math.cos(yaw), math.sin(yaw)
        rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
        moved: Float = np.asarray(points, dtype=np.float64) @ rotation.T
        moved += np.array([self.x, self.y, 0.0])
        return moved


@dataclass(frozen=True, slots=True)
class Conditions:
    """How the camera degrades the image: blur (px), noise (grey levels), exposure, occlusion.

    ``blur``: Gaussian sigma in pixels (0: none); ``noise``: sigma of additive
    Gaussian noise in grey levels of 255; ``exposure``: gain on the scene's
    brightness (1: white paper at 235 of 255; above ~1.1 white clips);
    ``occlusion``: fraction (0-1) of each marker's width hidden behind a dark bar.
    """

    blur: float = 0.0
    noise: float = 0.0
    exposure: float = 1.0
    occlusion: float = 0.0

    def __post_init__(self) -> None:
        limits = {
            "blur": (0.0, 50.0),
            "noise": (0.0, 255.0),
            "exposure": (0.0, 10.0),
            "occlusion": (0.0, 1.0),
        }
        for name, (low, high) in limits.items():
            value = check_number(
                name, getattr(self, name), low=low, high=high, error=PerceptionError
            )
            object.__setattr__(self, name, value)


# --- textures ------------------------------------------------------------------------------------


@functools.cache
def _marker_image(marker: int) -> NDArray[np.float32]:
    """The marker's black square as reflectances, ``TEXELS_PER_MODULE`` texels per module."""
    cv2 = opencv()
    dictionary = cv2.aruco.getPredefinedDictionary(cv2.aruco.DICT_ARUCO_MIP_36h12)
    modules = dictionary.markerSize + 2  # the data bits and a one-module black border
    bits = cv2.aruco.generateImageMarker(dictionary, marker, modules * TEXELS_PER_MODULE, 1)
    ink, label = SHADES["ink"], SHADES["label"]
    image: NDArray[np.float32] = np.where(bits > 127, label, ink).astype(np.float32)
    return image


@dataclass(frozen=True, eq=False)
class _Texture:
    """A face's picture: reflectances (rows, cols), the size of one texel (m), its markers.

    ``squares``: the top and left texel of each marker's black square (empty: one
    marker, at the centre).
    """

    image: NDArray[np.float32]
    texel: float
    squares: tuple[tuple[int, int], ...] = ()


def _texture(marker: int, frame: MarkerFrame, carrier: CarrierMarkers) -> _Texture:
    """The face panel (or underside board) with the white-labelled marker at its centre."""
    if frame.face is Face.UNDERSIDE and carrier.underside_map is not None:
        return _map_texture(carrier)
    core = _marker_image(marker)
    side = core.shape[0]
    texel = carrier.marker_size / side
    if frame.face is Face.UNDERSIDE:
        width = height = carrier.side
        shade = SHADES["board"]
    else:
        width, shade = carrier.side, SHADES["panel"]
        height = min(PANEL_HEIGHT, 2 * carrier.marker_height)
    cols = side + 2 * max(round((width - carrier.marker_size) / 2 / texel), 0)
    rows = side + 2 * max(round((height - carrier.marker_size) / 2 / texel), 0)
    image = np.full((rows, cols), shade, dtype=np.float32)
    quiet = TEXELS_PER_MODULE  # one module of white paper around the black square
    top, left = (rows - side) // 2, (cols - side) // 2
    image[max(top - quiet, 0) : top + side + quiet, max(left - quiet, 0) : left + side + quiet] = (
        SHADES["label"]
    )
    image[top : top + side, left : left + side] = core
    return _Texture(image, texel)


@functools.cache
def _map_texture(carrier: CarrierMarkers) -> _Texture:
    """The underside board with the carrier's marker map on white paper, centred.

    The texel is the map marker's module over ``TEXELS_PER_MODULE``; each marker's
    place is rounded to the nearest texel (exact when the pitch is a whole number of
    texels, as on the DOTS map: 96). The paper reaches one module past the outer
    markers. Cached (read-only) per carrier: it is the same on every carrier.
    """
    grid = carrier.underside_map
    if grid is None:  # pragma: no cover - only called for a carrier with a map
        msg = "the carrier has no underside map"
        raise PerceptionError(msg)
    side = _marker_image(0).shape[0]
    texel = grid.marker_size / side
    size = side + 2 * max(round((carrier.side - grid.marker_size) / 2 / texel), 0)
    image = np.full((size, size), SHADES["board"], dtype=np.float32)
    squares = []
    for marker in grid.ids:
        u, v = grid.offset(marker) / texel  # texture rows run down, against the map's y
        squares.append((round((size - side) / 2 - v), round((size - side) / 2 + u)))
    tops, lefts = [top for top, _ in squares], [left for _, left in squares]
    quiet = TEXELS_PER_MODULE
    paper = (
        slice(max(min(tops) - quiet, 0), max(tops) + side + quiet),
        slice(max(min(lefts) - quiet, 0), max(lefts) + side + quiet),
    )
    image[paper] = SHADES["label"]
    for marker, (top, left) in zip(grid.ids, squares, strict=True):
        image[top : top + side, left : left + side] = _marker_image(marker)
    image.flags.writeable = False
    return _Texture(image, texel, tuple(squares))


def _occlude(texture: _Texture, fraction: float, rng: np.random.Generator) -> None:
    """Hide ``fraction`` of each marker's width behind a dark bar, at its left or right edge."""
    image = texture.image
    side = _marker_image(0).shape[0]
    rows, cols = image.shape
    width = round(fraction * side)
    if width == 0:
        return
    for top, left in texture.squares or (((rows - side) // 2, (cols - side) // 2),):
        start = left if rng.integers(2) == 0 else left + side - width
        bottom = min(top + side + TEXELS_PER_MODULE, rows)
        image[max(top - TEXELS_PER_MODULE, 0) : bottom, start : start + width] = SHADES["occluder"]


# --- drawing one plane ---------------------------------------------------------------------------


def _clip_near(points: Float) -> Float:
    """The polygon ``points`` (N, 3, camera frame) clipped to z >= NEAR (Sutherland-Hodgman)."""
    kept = []
    for i in range(len(points)):
        a, b = points[i], points[(i + 1) % len(points)]
        if a[2] >= NEAR:
            kept.append(a)
        if (a[2] >= NEAR) != (b[2] >= NEAR):
            share = (NEAR - a[2]) / (b[2] - a[2])
            kept.append(a + share * (b - a))
    return np.array(kept).reshape(-1, 3)


def _supersampling(pixels: int) -> int:
    """Samples per pixel side for a patch of ``pixels`` pixels (fewer for huge patches)."""
    return 4 if pixels <= 300_000 else 2 if pixels <= 1_200_000 else 1


def _draw(canvas: NDArray[np.float32], lens: Float, texture: _Texture, pose: Float) -> None:
    """Paint a textured plane on ``canvas``; ``pose`` rows: centre, right and up axes (camera)."""
    centre, x, y = pose[0], pose[1], pose[2]
    cv2 = opencv()
    rows, cols = texture.image.shape
    t = texture.texel
    # texel coordinates (OpenCV: texel centres at integers) -> plane point in the camera frame
    origin = centre + x * (0.5 - cols / 2) * t - y * (0.5 - rows / 2) * t
    plane = np.column_stack([x * t, -y * t, origin])
    corners = np.array(
        [
            origin + x * u * t - y * v * t
            for u, v in (
                (-0.5, -0.5),
                (cols - 0.5, -0.5),
                (cols - 0.5, rows - 0.5),
                (-0.5, rows - 0.5),
            )
        ]
    )
    clipped = _clip_near(corners)
    if len(clipped) < 3:
        return
    projected = clipped @ lens.T
    projected = projected[:, :2] / projected[:, 2:]
    height, width = canvas.shape
    x0, y0 = (max(math.floor(v) - 1, 0) for v in projected.min(axis=0))
    x1 = min(math.ceil(projected[:, 0].max()) + 2, width)
    y1 = min(math.ceil(projected[:, 1].max()) + 2, height)
    if x1 <= x0 or y1 <= y0:
        return
    pw, ph = x1 - x0, y1 - y0
    s = _supersampling(pw * ph)
    to_canvas = np.array(
        [[1 / s, 0, x0 + 0.5 / s - 0.5], [0, 1 / s, y0 + 0.5 / s - 0.5], [0, 0, 1.0]]
    )
    homography = np.linalg.inv(to_canvas) @ lens @ plane
    size = (pw * s, ph * s)
    colour = cv2.warpPerspective(
        texture.image,
        homography,
        size,
        flags=cv2.INTER_NEAREST,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=0.0,
    )
    ones = np.ones_like(texture.image)
    cover = cv2.warpPerspective(
        ones,
        homography,
        size,
        flags=cv2.INTER_NEAREST,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=0.0,
    )
    # keep only samples whose ray meets the plane in front of the camera
    normal = np.cross(x, y)
    facing = normal @ np.linalg.inv(lens) @ to_canvas  # n . ray, linear in the sample grid
    cols_grid = np.arange(size[0], dtype=np.float64)
    rows_grid = np.arange(size[1], dtype=np.float64)[:, None]
    ahead = (facing[0] * cols_grid + facing[1] * rows_grid + facing[2]) * np.sign(normal @ centre)
    cover = np.where(ahead > 0, cover, 0.0).astype(np.float32)
    alpha = cv2.resize(cover, (pw, ph), interpolation=cv2.INTER_AREA)
    paint = cv2.resize(colour * cover, (pw, ph), interpolation=cv2.INTER_AREA)
    region = canvas[y0:y1, x0:x1]
    region *= 1.0 - alpha
    region += paint


# --- the lens ------------------------------------------------------------------------------------


@functools.cache
def _lens_maps(
    lens: Intrinsics,
) -> tuple[NDArray[np.float32], NDArray[np.float32], int, int, int, int]:
    """For a distorting lens: where each pixel looks in the ideal image, and that image's extent.

    Returns map x, map y (canvas coordinates) and the canvas's offset and size.
    """
    cv2 = opencv()
    grid = np.stack(
        np.meshgrid(
            np.arange(lens.width, dtype=np.float64), np.arange(lens.height, dtype=np.float64)
        ),
        axis=-1,
    )
    ideal = cv2.undistortPoints(
        grid.reshape(-1, 1, 2), lens.matrix, lens.coefficients, P=lens.matrix
    ).reshape(lens.height, lens.width, 2)
    low = np.floor(ideal.min(axis=(0, 1))).astype(int) - 2
    high = np.ceil(ideal.max(axis=(0, 1))).astype(int) + 2
    low = np.maximum(low, [-lens.width, -lens.height])
    high = np.minimum(high, [2 * lens.width, 2 * lens.height])
    map_x = (ideal[..., 0] - low[0]).astype(np.float32)
    map_y = (ideal[..., 1] - low[1]).astype(np.float32)
    return map_x, map_y, int(low[0]), int(low[1]), int(high[0] - low[0]), int(high[1] - low[1])


# --- the scene -----------------------------------------------------------------------------------


def _faces(
    camera: Camera, carrier: CarrierMarkers, placements: Sequence[Placement]
) -> list[tuple[float, Placement, MarkerFrame, Float]]:
    """Every marker plane that faces the camera: (distance, placement, frame, camera-frame pose)."""
    mount = camera.mount
    found = []
    for placement in placements:
        for frame in marker_frames(carrier):
            centre = mount.to_camera(placement.to_robot(frame.centre))
            axes = (
                placement.to_robot(np.stack([frame.x, frame.y, frame.z]))
                - placement.to_robot(np.zeros(3))
            ) @ mount.rotation
            if float(axes[2] @ centre) >= 0.0:  # turned away (or edge-on)
                continue
            found.append(
                (float(np.linalg.norm(centre)), placement, frame, np.vstack([centre, axes]))
            )
    return sorted(found, key=lambda item: -item[0])


def visible_markers(
    camera: Camera, carrier: CarrierMarkers, placements: Sequence[Placement], *, margin: float = 1.0
) -> tuple[tuple[int, Face], ...]:
    """The (marker id, face) pairs whose whole black square lies in the image, facing the camera.

    Nearer carriers are not tested as occluders: this is what the camera could see.
    An underside map counts as seen (under the carrier's id) when one of its markers is.
    """
    placements = _check_scene(camera, carrier, placements)
    margin = check_number("margin", margin, low=0.0, high=1e4, error=PerceptionError)
    _check_ids(carrier, placements)
    cv2 = opencv()
    lens = camera.intrinsics
    limit = np.array([lens.width, lens.height]) - 0.5 - margin
    seen = []
    for _, placement, frame, _pose in _faces(camera, carrier, placements):
        squares = [(frame, carrier.marker_size)]
        if frame.face is Face.UNDERSIDE and carrier.underside_map is not None:
            grid = carrier.underside_map
            squares = [(frame.shifted(grid.offset(m)), grid.marker_size) for m in grid.ids]
        for square, size in squares:
            corners = camera.mount.to_camera(placement.to_robot(square.corners(size)))
            if np.any(corners[:, 2] < NEAR):
                continue
            pixels, _ = cv2.projectPoints(
                corners, np.zeros(3), np.zeros(3), lens.matrix, lens.coefficients
            )
            pixels = pixels.reshape(-1, 2)
            if np.all((pixels >= margin - 0.5) & (pixels <= limit)):
                seen.append((placement.marker, frame.face))
                break
    return tuple(seen)


def _check_scene(camera: object, carrier: object, placements: object) -> tuple[Placement, ...]:
    """The public entries' camera, carrier and placements, checked; the placements as a tuple."""
    check_camera(camera)
    check_carrier(carrier)
    items = check_sequence("placements", placements, error=PerceptionError)
    for item in items:
        check_instance("placements", item, Placement, error=PerceptionError)
    return tuple(items)


def _check_ids(carrier: CarrierMarkers, placements: Sequence[Placement]) -> None:
    """Refuse a carrier whose own id is one of the underside map's: it would read as the map."""
    for placement in placements:
        if carrier.underside_map is not None and carrier.in_map(placement.marker):
            msg = f"marker {placement.marker}: one of the carriers' underside map ids "
            msg += f"({carrier.underside_map.describe()}); give the carrier an id outside them"
            raise PerceptionError(msg)


def render(
    camera: Camera,
    carrier: CarrierMarkers,
    placements: Sequence[Placement],
    conditions: Conditions = Conditions(),
    *,
    rng: np.random.Generator,
) -> NDArray[np.uint8]:
    """The 8-bit grey image (height, width) ``camera`` takes of the carriers at ``placements``.

    ``rng`` is the only source of randomness (noise, occlusion sides).
    """
    cv2 = opencv()
    source: object = rng  # checked at run time: a RandomState would break determinism
    if not isinstance(source, np.random.Generator):
        msg = f"rng: expected a numpy.random.Generator, got {type(source).__name__}"
        raise PerceptionError(msg)
    placements = _check_scene(camera, carrier, placements)
    check_instance("conditions", conditions, Conditions, error=PerceptionError)
    _check_ids(carrier, placements)
    lens = camera.intrinsics
    if lens.distorted:
        map_x, map_y, left, top, width, height = _lens_maps(lens)
    else:
        left, top, width, height = 0, 0, lens.width, lens.height
    matrix = lens.matrix.copy()
    matrix[0, 2] -= left
    matrix[1, 2] -= top
    canvas = np.full((height, width), SHADES["floor"], dtype=np.float32)
    for _, placement, frame, pose in _faces(camera, carrier, placements):
        texture = _texture(placement.marker, frame, carrier)
        if conditions.occlusion > 0:
            texture = _Texture(texture.image.copy(), texture.texel, texture.squares)
            _occlude(texture, conditions.occlusion, rng)
        _draw(canvas, matrix, texture, pose)
    image: Any = canvas
    if lens.distorted:
        image = cv2.remap(canvas, map_x, map_y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    if conditions.blur > 0:
        image = cv2.GaussianBlur(image, (0, 0), conditions.blur)
    image = image * (255.0 * conditions.exposure)
    if conditions.noise > 0:
        image = image + rng.normal(0.0, conditions.noise, image.shape)
    result: NDArray[np.uint8] = np.clip(np.rint(image), 0, 255).astype(np.uint8)
    return result
