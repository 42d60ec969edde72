"""The robot's cameras and the markers they look for: a small, typed, validated camera model.

Frames (all right-handed, metres):

- **robot**: origin on the floor under the robot's centre, ``x`` forward, ``y``
  left, ``z`` up; bearings are counter-clockwise from ``x`` (degrees).
- **camera** (OpenCV's): ``x`` right in the image, ``y`` down, ``z`` along the
  optical axis. A ``Mount`` places it on the robot: position, then ``yaw``
  (counter-clockwise from forward) and ``pitch`` (up from horizontal; 90 looks
  straight up).

A ``Rig`` is the robot's cameras (four perimeter cameras and one upward camera
on a DOTS-like robot) together with ``CarrierMarkers``: where a carrier carries
its 50 mm ``ARUCO_MIP_36h12`` markers. Rigs are read from a small TOML file
(docs/perception.md gives the layout); ``load_rig("dots-like")`` is the shipped one.

>>> rig = load_rig("dots-like")
>>> [camera.name for camera in rig.cameras]
['front', 'left', 'back', 'right', 'upward']
>>> round(rig.camera("front").intrinsics.horizontal_fov, 1)
102.0
"""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any, Final

import numpy as np
from numpy.typing import NDArray

from swarmtag._checks import (
    check_choice,
    check_instance,
    check_int,
    check_number,
    check_path_value,
    check_text,
    show,
)
from swarmtag._inputs import is_regular_file
from swarmtag._toml import read_toml
from swarmtag.errors import PerceptionError
from swarmtag.perception.marker_map import UndersideMap

__all__ = [
    "CAMERA_KINDS",
    "DEFAULT_RIG",
    "RIGS",
    "Camera",
    "CarrierMarkers",
    "Intrinsics",
    "Mount",
    "Rig",
    "load_rig",
    "read_rig_file",
    "rig_from_mapping",
    "rig_path",
]

Float = NDArray[np.float64]

CAMERA_KINDS: Final = ("perimeter", "upward")
"""What a camera looks at: carriers' side markers around the robot, or the underside marker."""
RIGS: Final = {"dots": "dots.toml", "dots-like": "dots-like.toml"}
"""Shipped rig files (in ``swarmtag/perception/rigs/``), by name."""
DEFAULT_RIG: Final = "dots-like"
"""The rig used when none is named."""
MAX_PIXELS: Final = 20_000
"""Largest image side accepted (pixels): well above any robot camera, far below memory limits."""
MAX_LENGTH: Final = 100.0
"""Largest length accepted in a rig file (m)."""
DISTORTION_LENGTHS: Final = (0, 4, 5, 8, 12, 14)
"""Distortion coefficient counts OpenCV accepts: k1 k2 p1 p2 [k3 [k4-k6 [s1-s4 [tx ty]]]]."""


def _number(
    name: str,
    value: object,
    *,
    low: float | None = None,
    high: float | None = None,
    low_open: bool = False,
) -> float:
    return check_number(name, value, low=low, high=high, low_open=low_open, error=PerceptionError)


@dataclass(frozen=True, slots=True)
class Intrinsics:
    """A pinhole camera with lens distortion, as OpenCV calibrates it.

    ``width`` x ``height`` pixels; focal lengths ``fx``, ``fy`` and principal
    point ``cx``, ``cy`` in pixels (pixel centres at integer coordinates);
    ``distortion`` in OpenCV's order (k1, k2, p1, p2, k3, ...), empty for none.
    """

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    distortion: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        for name in ("width", "height"):
            size = check_int(
                name, getattr(self, name), low=16, high=MAX_PIXELS, error=PerceptionError
            )
            object.__setattr__(self, name, size)
        for name in ("fx", "fy"):
            focal = _number(name, getattr(self, name), low=0.0, low_open=True, high=1e6)
            object.__setattr__(self, name, focal)
        object.__setattr__(self, "cx", _number("cx", self.cx, low=0.0, high=float(self.width)))
        object.__setattr__(self, "cy", _number("cy", self.cy, low=0.0, high=float(self.height)))
        given: object = self.distortion  # checked at run time: rig files are user input
        if not isinstance(given, tuple | list):
            msg = f"distortion: {show(given)} is not a list of numbers"
            raise PerceptionError(msg)
        if len(given) not in DISTORTION_LENGTHS:
            allowed = ", ".join(map(str, DISTORTION_LENGTHS))
            msg = f"distortion: {len(given)} coefficients (OpenCV takes {allowed})"
            raise PerceptionError(msg)
        coefficients = tuple(
            _number(f"distortion[{i}]", c, low=-1e3, high=1e3)
            for i, c in enumerate(self.distortion)
        )
        object.__setattr__(self, "distortion", coefficients)

    @classmethod
    def from_fov(
        cls, width: int, height: int, horizontal_fov: float, distortion: tuple[float, ...] = ()
    ) -> Intrinsics:
        """Square pixels, principal point at the image centre, ``horizontal_fov`` degrees across.

        >>> round(Intrinsics.from_fov(1920, 1080, 90.0).fx, 3)
        960.0
        """
        width = check_int("width", width, low=16, high=MAX_PIXELS, error=PerceptionError)
        height = check_int("height", height, low=16, high=MAX_PIXELS, error=PerceptionError)
        fov = _number("horizontal_fov", horizontal_fov, low=1.0, high=179.0)
        focal = (width / 2) / math.tan(math.radians(fov) / 2)
        return cls(width, height, focal, focal, (width - 1) / 2, (height - 1) / 2, distortion)

    @property
    def matrix(self) -> Float:
        """The 3 x 3 camera matrix K."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    @property
    def coefficients(self) -> Float:
        """The distortion coefficients as OpenCV takes them (five zeros when there are none)."""
        return np.array(self.distortion or (0.0,) * 5, dtype=np.float64)

    @property
    def distorted(self) -> bool:
        """Whether the lens distorts (any coefficient non-zero)."""
        return any(self.distortion)

    @property
    def horizontal_fov(self) -> float:
        """Horizontal field of view of the pinhole model, degrees."""
        return math.degrees(2 * math.atan((self.width / 2) / self.fx))

    @property
    def vertical_fov(self) -> float:
        """Vertical field of view of the pinhole model, degrees."""
        return math.degrees(2 * math.atan((self.height / 2) / self.fy))


@dataclass(frozen=True, slots=True)
class Mount:
    """Where a camera sits on the robot: position (m, robot frame), ``yaw`` and ``pitch`` (deg).

    >>> Mount(0.12, 0.0, 0.1).to_camera(np.array([1.12, 0.0, 0.1])).round(6)
    array([0., 0., 1.])
    """

    x: float
    y: float
    z: float
    yaw: float = 0.0
    pitch: float = 0.0

    def __post_init__(self) -> None:
        for name in ("x", "y", "z"):
            value = _number(name, getattr(self, name), low=-MAX_LENGTH, high=MAX_LENGTH)
            object.__setattr__(self, name, value)
        object.__setattr__(self, "yaw", _number("yaw", self.yaw, low=-360.0, high=360.0))
        object.__setattr__(self, "pitch", _number("pitch", self.pitch, low=-90.0, high=90.0))

    @property
    def position(self) -> Float:
        """The camera's optical centre in the robot frame, shape (3,)."""
        return np.array([self.x, self.y, self.z])

    @property
    def rotation(self) -> Float:
        """Robot-from-camera rotation: its columns are the camera's axes in the robot frame."""
        yaw, pitch = math.radians(self.yaw), math.radians(self.pitch)
        forward = np.array(
            [math.cos(pitch) * math.cos(yaw), math.cos(pitch) * math.sin(yaw), math.sin(pitch)]
        )
        right = np.array([math.sin(yaw), -math.cos(yaw), 0.0])
        down = np.cross(forward, right)
        return np.column_stack([right, down, forward])

    def to_camera(self, points: Float) -> Float:
        """Robot-frame points (..., 3) in this camera's frame."""
        return (np.asarray(points, dtype=np.float64) - self.position) @ self.rotation

    def to_robot(self, points: Float) -> Float:
        """Camera-frame points (..., 3) in the robot frame."""
        return np.asarray(points, dtype=np.float64) @ self.rotation.T + self.position


@dataclass(frozen=True, slots=True)
class Camera:
    """One camera of the robot: its ``name``, ``kind`` (perimeter or upward), lens and mount."""

    name: str
    kind: str
    intrinsics: Intrinsics
    mount: Mount

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            msg = f"camera name: {show(self.name)} is not a non-empty string"
            raise PerceptionError(msg)
        kind = check_choice(
            f"camera {self.name!r}: kind", self.kind, CAMERA_KINDS, error=PerceptionError
        )
        object.__setattr__(self, "kind", kind)

    @property
    def upward(self) -> bool:
        """Whether this camera looks up at a carrier's underside marker."""
        return self.kind == "upward"


@dataclass(frozen=True, slots=True)
class CarrierMarkers:
    """A carrier's shape and where its markers are (SPEC §4.1, §7; docs/perception.md).

    ``side`` (m): the square carrier's side (SPEC: 0.355). ``marker_size`` (m):
    the side of each marker's black square (SPEC: 50 mm). One marker is centred
    on each of the four faces with its centre ``marker_height`` above the floor,
    facing out; one is centred on the underside, ``underside_height`` above the
    floor, facing down. All five carry the carrier's own marker id, unless
    ``underside_map`` is given: then the underside carries that grid of markers
    (``marker_map``; the DOTS carriers' 7 x 7 map, ids 200-248) instead of the
    fifth marker, the same on every carrier.
    """

    side: float = 0.355
    marker_size: float = 0.05
    marker_height: float = 0.10
    underside_height: float = 0.20
    underside_map: UndersideMap | None = None

    def __post_init__(self) -> None:
        side = _number("carrier.side", self.side, low=0.0, low_open=True, high=MAX_LENGTH)
        size = _number("carrier.marker_size", self.marker_size, low=0.0, low_open=True, high=side)
        height = _number("carrier.marker_height", self.marker_height, low=size / 2, high=MAX_LENGTH)
        underside = _number(
            "carrier.underside_height",
            self.underside_height,
            low=0.0,
            low_open=True,
            high=MAX_LENGTH,
        )
        for name, value in (
            ("side", side),
            ("marker_size", size),
            ("marker_height", height),
            ("underside_height", underside),
        ):
            object.__setattr__(self, name, value)
        grid: object = self.underside_map  # checked at run time: rig files are user input
        if grid is not None and not isinstance(grid, UndersideMap):
            msg = f"carrier.underside_map: {show(grid)} is not an UndersideMap"
            raise PerceptionError(msg)
        if self.underside_map is not None and self.underside_map.extent > side:
            msg = f"carrier.underside_map: {self.underside_map.extent:g} m across, wider than "
            msg += f"the carrier ({side:g} m; columns, rows and pitch set its size)"
            raise PerceptionError(msg)

    @property
    def half(self) -> float:
        """Half the carrier's side: from its centre to a face (m)."""
        return self.side / 2

    def in_map(self, marker: int) -> bool:
        """Whether ``marker`` is one of the underside map's ids (never, without a map)."""
        return self.underside_map is not None and self.underside_map.holds(marker)

    def size_of(self, marker: int) -> float:
        """The black square's side (m) of marker ``marker``: a map marker's, or ``marker_size``."""
        if self.underside_map is not None and self.underside_map.holds(marker):
            return self.underside_map.marker_size
        return self.marker_size


@dataclass(frozen=True, slots=True)
class Rig:
    """The robot's cameras and the carriers' markers they look for."""

    name: str
    cameras: tuple[Camera, ...]
    carrier: CarrierMarkers = CarrierMarkers()
    description: str = ""

    def __post_init__(self) -> None:
        if not self.cameras:
            msg = f"rig {self.name!r}: no cameras (give at least one [[cameras]] table)"
            raise PerceptionError(msg)
        names = [camera.name for camera in self.cameras]
        twice = sorted({name for name in names if names.count(name) > 1})
        if twice:
            msg = f"rig {self.name!r}: camera {twice[0]!r} is named twice"
            raise PerceptionError(msg)

    def camera(self, name: str) -> Camera:
        """The camera called ``name``; ``PerceptionError`` listing the names otherwise."""
        for camera in self.cameras:
            if camera.name == name:
                return camera
        msg = f"rig {self.name!r} has no camera {name!r} (it has: "
        msg += ", ".join(camera.name for camera in self.cameras) + ")"
        raise PerceptionError(msg)

    @property
    def perimeter(self) -> tuple[Camera, ...]:
        """The cameras that look outward at carriers' side markers."""
        return tuple(camera for camera in self.cameras if not camera.upward)

    def facing(self, bearing: float) -> Camera:
        """The perimeter camera whose yaw is nearest ``bearing`` (deg; the first on a tie)."""
        if not self.perimeter:
            msg = f"rig {self.name!r} has no perimeter camera"
            raise PerceptionError(msg)

        def off(camera: Camera) -> float:
            return abs((bearing - camera.mount.yaw + 180.0) % 360.0 - 180.0)

        return min(self.perimeter, key=off)


# --- the rig file ------------------------------------------------------------------------------

_TOP: Final = ("name", "description", "intrinsics", "carrier", "cameras")
_INTRINSICS: Final = ("width", "height", "fx", "fy", "cx", "cy", "horizontal_fov", "distortion")
_CAMERA: Final = ("name", "kind", "position", "yaw", "pitch", "intrinsics")
_CARRIER: Final = ("side", "marker_size", "marker_height", "underside_height", "underside_map")
_MAP: Final = ("columns", "rows", "marker_size", "pitch", "first_id")


def _table(value: object, where: str) -> Mapping[str, Any]:
    if not isinstance(value, Mapping):
        msg = f"{where}: {show(value)} is not a table"
        raise PerceptionError(msg)
    return value


def _known(table: Mapping[str, Any], keys: tuple[str, ...], where: str) -> None:
    unknown = sorted(set(table) - set(keys))
    if unknown:
        msg = f"{where}.{unknown[0]}: unknown key ({where} has keys {', '.join(sorted(keys))})"
        raise PerceptionError(msg)


def _intrinsics(table: Mapping[str, Any], where: str) -> Intrinsics:
    _known(table, _INTRINSICS, where)
    distortion = table.get("distortion", [])
    if not isinstance(distortion, list):
        msg = f"{where}.distortion: {show(distortion)} is not a list of numbers"
        raise PerceptionError(msg)
    try:
        for key in ("width", "height"):
            if key not in table:
                msg = f"{where}.{key}: missing (give width, height and fx, fy, cx, cy or "
                msg += "horizontal_fov)"
                raise PerceptionError(msg)
        if "horizontal_fov" in table:
            extra = sorted({"fx", "fy", "cx", "cy"} & set(table))
            if extra:
                msg = f"{where}: give horizontal_fov or {extra[0]} (fx, fy, cx, cy), not both"
                raise PerceptionError(msg)
            return Intrinsics.from_fov(
                table["width"], table["height"], table["horizontal_fov"], tuple(distortion)
            )
        missing = [key for key in ("width", "height", "fx", "fy", "cx", "cy") if key not in table]
        if missing:
            msg = f"{where}.{missing[0]}: missing (give width, height, fx, fy, cx, cy or "
            msg += "width, height, horizontal_fov)"
            raise PerceptionError(msg)
        return Intrinsics(
            table["width"],
            table["height"],
            table["fx"],
            table["fy"],
            table["cx"],
            table["cy"],
            tuple(distortion),
        )
    except PerceptionError as error:
        text = str(error)
        raise PerceptionError(text if text.startswith(where) else f"{where}.{text}") from None


def _camera(table: Mapping[str, Any], index: int, shared: Intrinsics | None) -> Camera:
    where = f"cameras[{index}]"
    _known(table, _CAMERA, where)
    name = table.get("name")
    if not isinstance(name, str) or not name.strip():
        msg = f"{where}.name: {show(name)} is not a non-empty string"
        raise PerceptionError(msg)
    where = f"camera {name!r}"
    if "intrinsics" in table:
        lens = _intrinsics(
            _table(table["intrinsics"], f"{where}.intrinsics"), f"{where}.intrinsics"
        )
    elif shared is not None:
        lens = shared
    else:
        msg = f"{where}: no intrinsics (give [intrinsics] for all cameras or one for this camera)"
        raise PerceptionError(msg)
    position = table.get("position")
    if not isinstance(position, list) or len(position) != 3:
        msg = f"{where}.position: {show(position)} is not a list of three numbers [x, y, z] (m)"
        raise PerceptionError(msg)
    try:
        x, y, z = position
        mount = Mount(x, y, z, yaw=table.get("yaw", 0.0), pitch=table.get("pitch", 0.0))
        return Camera(name, table.get("kind", "perimeter"), lens, mount)
    except PerceptionError as error:
        text = str(error)
        raise PerceptionError(text if text.startswith("camera") else f"{where}: {text}") from None


def rig_from_mapping(data: Mapping[str, Any], *, source: str | None = None) -> Rig:
    """A rig from its TOML layout (docs/perception.md); errors name ``source`` and the key."""
    if source is not None:
        source = check_text("source", source, error=PerceptionError)
    given: object = data  # checked at run time: a library entry point
    if not isinstance(given, Mapping):
        msg = f"data: {show(given)} is not a mapping (a TOML table)"
        raise PerceptionError(msg)
    prefix = f"{source}: " if source else ""
    try:
        _known(data, _TOP, "rig")
        name = data.get("name", Path(source).stem if source else "rig")
        if not isinstance(name, str):
            msg = f"rig.name: {show(name)} is not a string"
            raise PerceptionError(msg)
        description = data.get("description", "")
        if not isinstance(description, str):
            msg = f"rig.description: {show(description)} is not a string"
            raise PerceptionError(msg)
        shared = None
        if "intrinsics" in data:
            shared = _intrinsics(_table(data["intrinsics"], "intrinsics"), "intrinsics")
        carrier_table = dict(_table(data.get("carrier", {}), "carrier"))
        _known(carrier_table, _CARRIER, "carrier")
        if "underside_map" in carrier_table:
            where = "carrier.underside_map"
            map_table = _table(carrier_table["underside_map"], where)
            _known(map_table, _MAP, where)
            try:
                carrier_table["underside_map"] = UndersideMap(**map_table)
            except PerceptionError as error:
                raise PerceptionError(f"carrier.{error}") from None
        carrier = CarrierMarkers(**carrier_table)
        cameras = data.get("cameras")
        if not isinstance(cameras, list) or not cameras:
            msg = "cameras: missing (give one [[cameras]] table per camera)"
            raise PerceptionError(msg)
        built = tuple(
            _camera(_table(table, f"cameras[{i}]"), i, shared) for i, table in enumerate(cameras)
        )
        return Rig(name, built, carrier, description)
    except PerceptionError as error:
        raise PerceptionError(f"{prefix}{error}") from None


def rig_path(name: str) -> Path:
    """The file of the shipped rig ``name``; ``PerceptionError`` listing the names otherwise."""
    name = check_text("name", name, error=PerceptionError)
    if name not in RIGS:
        msg = f"camera {name!r}: no such file or shipped rig (shipped: {', '.join(RIGS)})"
        raise PerceptionError(msg)
    return Path(str(resources.files("swarmtag.perception") / "rigs" / RIGS[name]))


def read_rig_file(path: str | os.PathLike[str]) -> Rig:
    """Read and check a rig TOML file; every refusal is a ``PerceptionError`` naming it."""
    path = check_path_value("path", path, error=PerceptionError)
    data = read_toml(path, what="camera file", error=PerceptionError)
    return rig_from_mapping(data, source=os.fspath(path))


def load_rig(name_or_path: str | os.PathLike[str] = DEFAULT_RIG) -> Rig:
    """A shipped rig by name (``"dots-like"``) or a rig file by path (``"robot.toml"``)."""
    text = check_path_value("name_or_path", name_or_path, error=PerceptionError)
    if isinstance(name_or_path, os.PathLike) or text.endswith(".toml") or is_regular_file(text):
        return read_rig_file(text)
    return read_rig_file(rig_path(text))


def check_camera(value: object) -> Camera:
    """``value`` if it is a ``Camera``, else a ``PerceptionError`` naming ``camera``."""
    return check_instance("camera", value, Camera, error=PerceptionError)


def check_carrier(value: object) -> CarrierMarkers:
    """``value`` if it is a ``CarrierMarkers``, else a ``PerceptionError`` naming ``carrier``."""
    return check_instance("carrier", value, CarrierMarkers, error=PerceptionError)
