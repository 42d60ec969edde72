"""The ``swarmtag_msgs`` ROS 2 message types; ``rosbags`` imported on first use (``bags`` extra).

The message definitions ship as ``.msg`` files in ``swarmtag/data/swarmtag_msgs/msg`` (the
layout of the default bag mapping, written by ``swarmtag simulate --mcap``);
``typestore()`` is the ROS 2 Humble type store of ``rosbags`` with them registered, for
reading bags that carry no definitions and for writing. Without ``rosbags`` installed, every
entry point here raises one ``BagError`` naming the extra to install.

>>> sorted(message_definitions())[:2]
['swarmtag_msgs/msg/RobotEvent', 'swarmtag_msgs/msg/RobotEventArray']
"""

from __future__ import annotations

import importlib
from importlib.resources import files
from typing import TYPE_CHECKING, Final

from swarmtag.errors import BagError

if TYPE_CHECKING:
    from rosbags.typesys.store import Typestore

__all__ = [
    "NEEDS_EXTRA",
    "ROBOT_EVENT",
    "ROBOT_EVENT_ARRAY",
    "TAG_STATUS",
    "TAG_STATUS_ARRAY",
    "TRIAL",
    "message_definitions",
    "require_rosbags",
    "typestore",
]

NEEDS_EXTRA: Final = "ROS 2 bags and MCAP files need the 'bags' extra: pip install 'swarmtag[bags]'"
PACKAGE: Final = "swarmtag_msgs"
TRIAL: Final = f"{PACKAGE}/msg/Trial"
TAG_STATUS: Final = f"{PACKAGE}/msg/TagStatus"
TAG_STATUS_ARRAY: Final = f"{PACKAGE}/msg/TagStatusArray"
ROBOT_EVENT: Final = f"{PACKAGE}/msg/RobotEvent"
ROBOT_EVENT_ARRAY: Final = f"{PACKAGE}/msg/RobotEventArray"
_MESSAGES: Final = (TRIAL, TAG_STATUS, TAG_STATUS_ARRAY, ROBOT_EVENT, ROBOT_EVENT_ARRAY)


def message_definitions() -> dict[str, str]:
    """Each ``swarmtag_msgs`` type name and its ``.msg`` text (the shipped files)."""
    folder = files("swarmtag.data").joinpath(PACKAGE, "msg")
    return {
        name: folder.joinpath(f"{name.rsplit('/', 1)[1]}.msg").read_text(encoding="utf-8")
        for name in _MESSAGES
    }


def require_rosbags() -> None:
    """Import the ``bags`` extra now (``rosbags``, ``mcap``), or raise ``BagError`` naming it."""
    try:
        importlib.import_module("rosbags.typesys")
        importlib.import_module("rosbags.rosbag2")
        importlib.import_module("rosbags.highlevel")
        importlib.import_module("mcap.reader")
        importlib.import_module("mcap.writer")
    except ImportError:
        raise BagError(NEEDS_EXTRA) from None


def typestore() -> Typestore:
    """A new ROS 2 Humble type store with the ``swarmtag_msgs`` types registered.

    New on every call (about 10 ms), so that types a caller registers stay its own.
    """
    require_rosbags()
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore  # noqa: PLC0415

    store = get_typestore(Stores.ROS2_HUMBLE)
    types = {}
    for name, text in message_definitions().items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store
