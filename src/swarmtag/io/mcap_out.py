"""Writing a recorded run as one MCAP file with ROS 2 message schemas (the ``bags`` extra).

``McapRecorder`` writes the ``swarmtag_msgs`` layout that the default bag mapping reads (so
``swarmtag log import`` gives the run's event log back) plus poses and a 3-D scene that
Foxglove draws. Channels (all CDR-encoded, schemas embedded as ``ros2msg``):

=========================  ===================================  ==============================
topic                      type                                 what
=========================  ===================================  ==============================
``/swarmtag/trial``        ``swarmtag_msgs/msg/Trial``          trial start and end
``/swarmtag/tag_status``   ``swarmtag_msgs/msg/TagStatusArray`` tag state changes
``/swarmtag/robot_events`` ``swarmtag_msgs/msg/RobotEventArray`` the long-format event table
``/swarmtag/robots``       ``geometry_msgs/msg/PoseArray``      robot poses, frame ``arena``
``/swarmtag/carriers``     ``geometry_msgs/msg/PoseArray``      carrier poses, frame ``arena``
``/swarmtag/scene``        ``visualization_msgs/msg/MarkerArray`` robots, carriers, labels
``/swarmtag/arena``        ``visualization_msgs/msg/MarkerArray`` floor and zones (once)
=========================  ===================================  ==============================

Messages are serialized with the ``rosbags`` type store and written with Foxglove's ``mcap``
writer (profile ``ros2``, zstd chunks, summary and statistics) with every CRC the MCAP spec
defines: each chunk's, the data section's and the summary's, so ``swarmtag log import`` and any
MCAP reader can tell a damaged file from a good one. The file is written beside the target
under a hidden name and moved into place when complete; an error leaves no file.
"""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import TYPE_CHECKING, Any, Final, Self

import numpy as np
from numpy.typing import NDArray

from swarmtag.errors import BagError
from swarmtag.io.ros_types import ROBOT_EVENT_ARRAY, TAG_STATUS_ARRAY, TRIAL, typestore

if TYPE_CHECKING:
    from typing import BinaryIO

    from mcap.writer import Writer

__all__ = ["CHANNELS", "FRAME", "Arena", "McapRecorder", "TrialInfo"]

FRAME: Final = "arena"
"""The frame every pose and marker is in: x, y in metres on the arena floor, z up."""
CHANNELS: Final = {
    "/swarmtag/trial": TRIAL,
    "/swarmtag/tag_status": TAG_STATUS_ARRAY,
    "/swarmtag/robot_events": ROBOT_EVENT_ARRAY,
    "/swarmtag/robots": "geometry_msgs/msg/PoseArray",
    "/swarmtag/carriers": "geometry_msgs/msg/PoseArray",
    "/swarmtag/scene": "visualization_msgs/msg/MarkerArray",
    "/swarmtag/arena": "visualization_msgs/msg/MarkerArray",
}
"""Every channel of the file: topic and ROS 2 message type."""
_LIBRARY: Final = "swarmtag"
"""The writer named in the file's header: the same for every version, so that a run's bytes are."""
_START, _END = 0, 1  # swarmtag_msgs/msg/Trial START, END
_AWAITING, _PICKED_UP = 1, 2
_ROBOT_HEIGHT, _CARRIER_HEIGHT, _LIFTED = 0.12, 0.06, 0.16
_ARROW, _CUBE, _CYLINDER, _TEXT = 0, 1, 3, 9  # visualization_msgs/msg/Marker types
_DELETE_ALL = 3  # Marker action: remove the markers of the previous time step
_PICKUP_RGBA: Final = (0.80, 0.92, 0.80, 1.0)
_DROPOFF_RGBA: Final = (0.80, 0.86, 0.97, 1.0)
_CELL_LOOK: Final = {
    "shelf": ((0.45, 0.45, 0.45, 1.0), 0.5, 1.0),
    "pickup": (_PICKUP_RGBA, -0.003, 0.004),
    "dropoff": (_DROPOFF_RGBA, -0.003, 0.004),
}
"""A warehouse cell's colour, height of its centre and thickness: shelves stand 1 m tall."""


@dataclass(frozen=True, slots=True)
class Arena:
    """The static picture: a square arena of side ``size`` (m), zones and body sizes."""

    size: float
    pickup_right: float
    dropoff_left: float
    robot_radius: float
    carrier_size: float
    height: float = 0.0
    """Extent in y (0: square, ``size``)."""
    cells: tuple[tuple[str, float, float, float], ...] = ()
    """A warehouse's cells instead of the lab's two areas: (kind, x, y, side), kind
    ``shelf``, ``pickup`` or ``dropoff``, (x, y) the lower left corner."""


@dataclass(frozen=True, slots=True)
class TrialInfo:
    """What a trial message states: condition, run, seed, time unit and the clock's tick (s)."""

    condition: str
    run: int
    seed: int
    time_unit: str
    tick: float


def _rgba(r: float, g: float, b: float, a: float = 1.0) -> tuple[float, float, float, float]:
    return (r, g, b, a)


def _urgency_colour(urgency: int) -> tuple[float, float, float, float]:
    """Yellow (0) to red (9) for carriers awaiting pickup."""
    share = min(max(urgency, 0), 9) / 9
    return _rgba(1.0, 0.85 * (1 - share) + 0.1 * share, 0.2 * (1 - share))


class McapRecorder:
    """A context manager writing one MCAP file at ``path`` (all or nothing).

    Stamps are nanoseconds; write messages in time order.
    """

    def __init__(self, path: str | os.PathLike[str]) -> None:
        self.path = Path(path)
        self._partial = self.path.with_name(f".{self.path.name}.partial")
        self._handle: BinaryIO | None = None
        self._writer: Writer | None = None
        self._channels: dict[str, int] = {}
        self._store: Any = None
        self._empty: dict[str, Any] = {}

    # -- the file -------------------------------------------------------------------------------

    def __enter__(self) -> Self:
        self._store = typestore()
        from mcap.writer import CompressionType, Writer  # noqa: PLC0415 - the bags extra

        try:
            self._handle = self._partial.open("wb")
        except OSError as error:
            msg = f"{self.path}: cannot write ({error.strerror or error})"
            raise BagError(msg) from None
        writer = Writer(
            self._handle, compression=CompressionType.ZSTD, enable_crcs=True, enable_data_crcs=True
        )
        writer.start(profile="ros2", library=_LIBRARY)
        for topic, msgtype in CHANNELS.items():
            definition, _ = self._store.generate_msgdef(msgtype, ros_version=2)
            schema = writer.register_schema(
                name=msgtype, encoding="ros2msg", data=definition.encode("utf-8")
            )
            self._channels[topic] = writer.register_channel(
                topic=topic, message_encoding="cdr", schema_id=schema
            )
        self._writer = writer
        self._cache()
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        trace: TracebackType | None,
    ) -> None:
        writer, self._writer = self._writer, None
        handle, self._handle = self._handle, None
        try:
            if writer is not None and handle is not None and kind is None:
                writer.finish()  # type: ignore[no-untyped-call]  # mcap leaves it unannotated
                handle.close()
                self._partial.replace(self.path)
        finally:
            if handle is not None:
                handle.close()
            self._partial.unlink(missing_ok=True)

    def _write(self, topic: str, at: int, message: object) -> None:
        assert self._writer is not None, "write inside the with block"
        data = self._store.serialize_cdr(message, CHANNELS[topic])
        self._writer.add_message(
            self._channels[topic], log_time=at, data=bytes(data), publish_time=at
        )

    def _type(self, name: str) -> Any:  # noqa: ANN401 - rosbags' generated message classes
        return self._store.types[name]

    def _cache(self) -> None:
        """Sub-messages every marker repeats (empty texture, no mesh, no lifetime)."""
        image = self._type("sensor_msgs/msg/CompressedImage")
        self._empty = {
            "texture": image(header=self._header(0), format="", data=np.zeros(0, dtype=np.uint8)),
            "mesh_file": self._type("visualization_msgs/msg/MeshFile")(
                filename="", data=np.zeros(0, dtype=np.uint8)
            ),
            "lifetime": self._type("builtin_interfaces/msg/Duration")(sec=0, nanosec=0),
            "orientation": self._type("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
        }

    # -- message parts --------------------------------------------------------------------------

    def _header(self, at: int, frame: str = "") -> Any:  # noqa: ANN401
        stamp = self._type("builtin_interfaces/msg/Time")(sec=at // 10**9, nanosec=at % 10**9)
        return self._type("std_msgs/msg/Header")(stamp=stamp, frame_id=frame)

    def _pose(self, x: float, y: float, z: float, yaw: float | None = None) -> Any:  # noqa: ANN401
        point = self._type("geometry_msgs/msg/Point")(x=float(x), y=float(y), z=float(z))
        if yaw is None:
            return self._type("geometry_msgs/msg/Pose")(
                position=point, orientation=self._empty["orientation"]
            )
        quaternion = self._type("geometry_msgs/msg/Quaternion")(
            x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2)
        )
        return self._type("geometry_msgs/msg/Pose")(position=point, orientation=quaternion)

    def _marker(
        self,
        header: Any,  # noqa: ANN401
        ns: str,
        ident: int,
        *,
        shape: int,
        pose: Any,  # noqa: ANN401
        scale: tuple[float, float, float],
        colour: tuple[float, float, float, float],
        text: str = "",
        action: int = 0,
    ) -> Any:  # noqa: ANN401
        """One ``visualization_msgs/Marker`` (no points, texture or mesh)."""
        marker = self._type("visualization_msgs/msg/Marker")
        return marker(
            header=header,
            ns=ns,
            id=ident,
            type=shape,
            action=action,
            pose=pose,
            scale=self._type("geometry_msgs/msg/Vector3")(x=scale[0], y=scale[1], z=scale[2]),
            color=self._type("std_msgs/msg/ColorRGBA")(
                r=colour[0], g=colour[1], b=colour[2], a=colour[3]
            ),
            lifetime=self._empty["lifetime"],
            frame_locked=False,
            points=[],
            colors=[],
            texture_resource="",
            texture=self._empty["texture"],
            uv_coordinates=[],
            text=text,
            mesh_resource="",
            mesh_file=self._empty["mesh_file"],
            mesh_use_embedded_materials=False,
        )

    # -- the swarmtag_msgs layout ---------------------------------------------------------------

    def trial(
        self,
        at: int,
        info: TrialInfo,
        *,
        starts: bool,
        markers: Sequence[int] = (),
        urgency0: Sequence[int] = (),
        order_time: Sequence[float] = (),
    ) -> None:
        """A trial start (with its carriers, urgencies and order times) or end message."""
        self._write(
            "/swarmtag/trial",
            at,
            self._type(TRIAL)(
                header=self._header(at),
                event=_START if starts else _END,
                condition=info.condition,
                run=info.run,
                seed=info.seed,
                time_unit=info.time_unit,
                tick=float(info.tick),
                markers=np.array(markers, dtype=np.uint8),
                urgency0=np.array(urgency0, dtype=np.uint8),
                order_time=np.array(order_time, dtype=np.float64),
            ),
        )

    def tag_changes(self, at: int, changes: Sequence[tuple[int, int, int, int]]) -> None:
        """Tag changes at ``at`` in the order they took effect: (marker, status, urgency, robot)."""
        entry = self._type("swarmtag_msgs/msg/TagStatus")
        tags = [
            entry(marker=m, urgency=u, status=s, destination=0, robot=r) for m, s, u, r in changes
        ]
        self._write(
            "/swarmtag/tag_status",
            at,
            self._type(TAG_STATUS_ARRAY)(header=self._header(at), tags=tags),
        )

    def robot_events(self, at: int, events: Sequence[tuple[str, int, int, float]]) -> None:
        """Events at ``at`` as they happened: (kind, robot, carrier, value); -1, NaN: none."""
        entry = self._type("swarmtag_msgs/msg/RobotEvent")
        rows = [entry(kind=k, robot=r, carrier=c, value=float(v)) for k, r, c, v in events]
        self._write(
            "/swarmtag/robot_events",
            at,
            self._type(ROBOT_EVENT_ARRAY)(header=self._header(at), events=rows),
        )

    # -- poses and the 3-D scene ----------------------------------------------------------------

    def arena(self, at: int, arena: Arena) -> None:
        """The floor, the pick-up area (x <= pickup_right) and the drop-off area (once)."""
        header = self._header(at, FRAME)
        height = arena.height or arena.size
        parts = [("floor", 0.0, 0.0, arena.size, height, _rgba(0.93, 0.93, 0.93), -0.005, 0.004)]
        if not arena.cells:
            parts += [
                ("pickup", 0.0, 0.0, arena.pickup_right, height, _PICKUP_RGBA, -0.003, 0.004),
                ("dropoff", arena.dropoff_left, 0.0, arena.size, height, _DROPOFF_RGBA, -0.003,
                 0.004),
            ]  # fmt: skip
        for kind, x, y, side in arena.cells:
            colour, z, tall = _CELL_LOOK[kind]
            parts.append((kind, x, y, x + side, y + side, colour, z, tall))
        counts: dict[str, int] = {}
        markers = []
        for name, left, low, right, high, colour, z, tall in parts:
            number = counts[name] = counts.get(name, -1) + 1  # ids count within a namespace
            markers.append(
                self._marker(
                    header,
                    name,
                    number,
                    shape=_CUBE,
                    pose=self._pose((left + right) / 2, (low + high) / 2, z),
                    scale=(right - left, high - low, tall),
                    colour=colour,
                )
            )
        array = self._type("visualization_msgs/msg/MarkerArray")
        self._write("/swarmtag/arena", at, array(markers=markers))

    def frame(
        self,
        at: int,
        arena: Arena,
        *,
        robot_xy: NDArray[np.float64],
        robot_heading: NDArray[np.float64],
        robot_labels: Sequence[str],
        markers: Sequence[int],
        carrier_xy: NDArray[np.float64],
        carrier_status: Sequence[int],
        carrier_urgency: Sequence[int],
        carrier_present: Sequence[bool],
    ) -> None:
        """One time step: robot and carrier poses, and the scene (delivered carriers left out)."""
        header = self._header(at, FRAME)
        yaws = np.arctan2(robot_heading[:, 1], robot_heading[:, 0]).tolist()
        robots = [
            self._pose(x, y, 0.0, yaw) for (x, y), yaw in zip(robot_xy.tolist(), yaws, strict=True)
        ]
        carriers = [
            self._pose(x, y, _LIFTED if status == _PICKED_UP else 0.0)
            for (x, y), status in zip(carrier_xy.tolist(), carrier_status, strict=True)
        ]
        poses = self._type("geometry_msgs/msg/PoseArray")
        self._write("/swarmtag/robots", at, poses(header=header, poses=robots))
        self._write("/swarmtag/carriers", at, poses(header=header, poses=carriers))
        scene = [
            self._marker(
                header,
                "",
                0,
                shape=_CUBE,
                pose=self._pose(0.0, 0.0, 0.0),
                scale=(1.0, 1.0, 1.0),
                colour=_rgba(0, 0, 0),
                action=_DELETE_ALL,
            )
        ]
        for index, (pose, label) in enumerate(zip(robots, robot_labels, strict=True)):
            scene += self._robot(
                header, index, pose.position, yaw=yaws[index], label=label, arena=arena
            )
        for marker, pose, status, urgency, present in zip(
            markers, carriers, carrier_status, carrier_urgency, carrier_present, strict=True
        ):
            if present:
                scene += self._carrier(
                    header,
                    int(marker),
                    pose.position,
                    status=int(status),
                    urgency=int(urgency),
                    arena=arena,
                )
        array = self._type("visualization_msgs/msg/MarkerArray")
        self._write("/swarmtag/scene", at, array(markers=scene))

    def _robot(
        self,
        header: Any,  # noqa: ANN401
        index: int,
        position: Any,  # noqa: ANN401
        *,
        yaw: float,
        label: str,
        arena: Arena,
    ) -> list[Any]:
        """A robot's body (cylinder), heading (arrow) and label."""
        x, y, diameter = position.x, position.y, 2 * arena.robot_radius
        return [
            self._marker(
                header,
                "robots",
                index,
                shape=_CYLINDER,
                pose=self._pose(x, y, _ROBOT_HEIGHT / 2),
                scale=(diameter, diameter, _ROBOT_HEIGHT),
                colour=_rgba(0.25, 0.25, 0.28),
            ),
            self._marker(
                header,
                "headings",
                index,
                shape=_ARROW,
                pose=self._pose(x, y, _ROBOT_HEIGHT + 0.01, yaw),
                scale=(arena.robot_radius, 0.03, 0.03),
                colour=_rgba(1.0, 1.0, 1.0),
            ),
            self._marker(
                header,
                "robot_labels",
                index,
                shape=_TEXT,
                pose=self._pose(x, y, _ROBOT_HEIGHT + 0.25),
                scale=(0.1, 0.1, 0.1),
                colour=_rgba(0.1, 0.1, 0.1),
                text=label,
            ),
        ]

    def _carrier(
        self,
        header: Any,  # noqa: ANN401
        marker: int,
        position: Any,  # noqa: ANN401
        *,
        status: int,
        urgency: int,
        arena: Arena,
    ) -> list[Any]:
        """A carrier (cube coloured by status and urgency) and its label ``7 u9``."""
        if status == _AWAITING:
            colour = _urgency_colour(urgency)
        elif status == _PICKED_UP:
            colour = _rgba(0.30, 0.50, 0.90)
        else:
            colour = _rgba(0.60, 0.60, 0.60)
        height = position.z + _CARRIER_HEIGHT / 2
        side = arena.carrier_size
        return [
            self._marker(
                header,
                "carriers",
                marker,
                shape=_CUBE,
                pose=self._pose(position.x, position.y, height),
                scale=(side, side, _CARRIER_HEIGHT),
                colour=colour,
            ),
            self._marker(
                header,
                "carrier_labels",
                marker,
                shape=_TEXT,
                pose=self._pose(position.x, position.y, height + 0.2),
                scale=(0.1, 0.1, 0.1),
                colour=_rgba(0.1, 0.1, 0.1),
                text=f"{marker} u{urgency}",
            ),
        ]
