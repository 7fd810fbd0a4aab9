"""Server messages (protocol.md §6 and §18) as typed values.

:func:`format_message` writes the exact line UT2004 USARSim sent: key spelling and order,
precision, one space between segments, CR LF at the end.  :func:`parse_message` reads such a
line back (a client-side parser, used by tests and tools); a value read back equals the
original up to the printed precision.

Precision per key (protocol.md §2.4):

* ``Time``: 4 decimals in SEN, EFF and STEPPED; 2 decimals in STA, MISSTA and RES.
* Start poses and path nodes: 2 decimals.
* Everything else: 4 decimals; scanner ``Resolution``/``FOV`` and mission-package geometry
  truncated rather than rounded (see :func:`usarsim.protocol.numbers.t4`).
* Ground truth, INS and INU orientations: normalised into [0, 2 pi).

Names and other text fields are written as given; they come from validated configuration
and must not contain braces or line breaks.

Every class is a frozen dataclass.  ``GameInfo``, the two STA classes, ``RobotGeometry`` and
``RobotConfiguration`` (a required field follows a defaulted one) take keyword arguments
only; the others also accept their fields positionally, in the order listed.

A message of fixed layout is declared once: every field of its dataclass says its key, how
its value is printed and how it is read back (:mod:`.declare`), and both its format and its
parser follow: the status messages; the GEO and CONF of the robot, of its mission packages
and actuators, and the empty ones; NFO's game and closest path node; the zoom RES, DIE,
STEPPED, PONG and ERROR; the SEN bodies of the readings of fixed layout.  The others are
written and read by hand in their modules.
One module per family of messages holds each message's class, format and parser:

* :mod:`.info`: NFO, the game, start poses and path nodes (§6.1, §5.2);
* :mod:`.status`: STA, MISSTA and ASTA (§6.2, §6.4);
* :mod:`.sensors`: SEN, one format and one parser per reading type (§6.3);
* :mod:`.geometry`: GEO and CONF of the robot and its items (§6.7, §6.8), and
  :mod:`.articulated`, those of mission packages and actuators;
* :mod:`.results`: RES, EFF, DIE, STEPPED, PONG, ERROR and unknown lines (§6.5, §6.6, §6.9, §18);
* :mod:`.declare`: the declarations (keys, name-value pairs, repeated groups), compiled once
  per message into its format and its parser;
* :mod:`.common`: what they share (the line limit, field values, the segment reader).

This module dispatches on them: a message's class to its format, a line's type to its parser.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from ..grammar import RawMessage, parse_line
from . import articulated, geometry, info, results, sensors, status
from .articulated import (
    ActuatorConfig,
    ActuatorConfiguration,
    ActuatorGeometry,
    ActuatorLinkConfiguration,
    ActuatorLinkGeometry,
    ActuatorPose,
    LinkConfiguration,
    LinkGeometry,
    MisPkgConfiguration,
    MisPkgGeometry,
    PackageConfiguration,
    PackageGeometry,
)
from .common import LINE_LIMIT, Vec3, _Reader, format_value
from .geometry import (
    EmptyConfiguration,
    EmptyGeometry,
    ItemConf,
    ItemConfiguration,
    ItemGeometry,
    ItemPose,
    RobotConfiguration,
    RobotGeometry,
)
from .info import ClosestPathNode, GameInfo, PathNodes, StartPose, StartPoses
from .results import (
    CameraZoom,
    CameraZoomResult,
    Die,
    EffecterStatus,
    ErrorReply,
    Pong,
    Result,
    Stepped,
    UnknownMessage,
    ViewportsResult,
    ViewportState,
    error_reply,
)
from .sensors import SensorMessage, format_reading
from .status import ActuatorStatus, MisPkgMessage, StatusMessage

__all__ = [
    "ActuatorConfig",
    "ActuatorConfiguration",
    "ActuatorGeometry",
    "ActuatorLinkConfiguration",
    "ActuatorLinkGeometry",
    "ActuatorPose",
    "ActuatorStatus",
    "CameraZoom",
    "CameraZoomResult",
    "ClosestPathNode",
    "Die",
    "EffecterStatus",
    "EmptyConfiguration",
    "EmptyGeometry",
    "GameInfo",
    "ItemConf",
    "ItemConfiguration",
    "ItemGeometry",
    "ItemPose",
    "LINE_LIMIT",
    "LinkConfiguration",
    "LinkGeometry",
    "Message",
    "MisPkgConfiguration",
    "MisPkgGeometry",
    "MisPkgMessage",
    "PackageConfiguration",
    "PackageGeometry",
    "PathNodes",
    "Pong",
    "Result",
    "RobotConfiguration",
    "RobotGeometry",
    "SensorMessage",
    "StatusMessage",
    "StartPose",
    "StartPoses",
    "Stepped",
    "ErrorReply",
    "error_reply",
    "UnknownMessage",
    "Vec3",
    "ViewportState",
    "ViewportsResult",
    "format_message",
    "format_reading",
    "format_value",
    "message_from_raw",
    "parse_message",
]

Message = (
    GameInfo
    | StartPoses
    | PathNodes
    | ClosestPathNode
    | StatusMessage
    | SensorMessage
    | RobotGeometry
    | RobotConfiguration
    | ItemGeometry
    | EmptyGeometry
    | ItemConfiguration
    | EmptyConfiguration
    | MisPkgGeometry
    | MisPkgConfiguration
    | MisPkgMessage
    | ActuatorConfiguration
    | ActuatorGeometry
    | ActuatorStatus
    | Result
    | CameraZoomResult
    | ViewportsResult
    | EffecterStatus
    | Die
    | Stepped
    | Pong
    | ErrorReply
    | UnknownMessage
)

_FORMATTERS: dict[type, Callable[[Any], str]] = {
    **info.FORMATTERS,
    **status.FORMATTERS,
    **sensors.FORMATTERS,
    **geometry.FORMATTERS,
    **articulated.FORMATTERS,
    **results.FORMATTERS,
}


def format_message(msg: Message) -> str:
    """The exact line for ``msg``, including the trailing CR LF (a 3D sweep too long for one
    line: one line per row, see :func:`format_reading`)."""
    try:
        formatter = _FORMATTERS[type(msg)]
    except KeyError:
        raise TypeError(f"not a server message: {msg!r}") from None
    return formatter(msg)


_MESSAGE_PARSERS: dict[str, Callable[[_Reader], Message]] = {
    **info.PARSERS,
    **status.PARSERS,
    **sensors.PARSERS,
    **geometry.PARSERS,
    **results.PARSERS,
}


def message_from_raw(raw: RawMessage) -> Message:
    """The message for an already split line (see :func:`parse_message`)."""
    parser = _MESSAGE_PARSERS.get(raw.type)
    if parser is None:
        return UnknownMessage(type=raw.type, segments=raw.segments)
    return parser(_Reader(raw, raw.type))


def parse_message(line: str) -> Message:
    """Parse one server line (with or without its CR LF) into a message.

    Unknown message types and sensor types give :class:`UnknownMessage`.  Raises
    :class:`~usarsim.errors.ProtocolError` when a known message lacks a key or has a bad value.
    """
    return message_from_raw(parse_line(line.rstrip("\r\n")))
