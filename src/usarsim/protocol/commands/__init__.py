"""Client commands (protocol.md §5 and §18) as typed values.

:func:`parse_command` turns one line into one of the frozen dataclasses below;
:func:`format_command` writes a command the way a client would send it.

Parsing rules, common to every command:

* The command word and the keys are case-insensitive (MOAST sends ``Drive`` and
  ``{Classname ...}``, RDK test code ``{RIGHT 1.0}``).
* Unknown keys are ignored (the NIST Iridium UI sends extras).  An unknown command word gives
  :class:`UnknownCommand`, which is not an error: servers ignore such lines.
* A key that occurs twice counts once, the first time (the UDK server's lookup did the same);
  keys that start or continue a repeated group (DRIVE joints and wheels, MISPKG/ACT links)
  are read in order instead.
* A malformed line, or a value that a known key cannot take, raises
  :class:`~usarsim.errors.ProtocolError` naming the command, the key, the value received and
  what is allowed.  NaN and infinite numbers are never accepted.
* A field is ``None`` when its key was not sent; the session keeps the previous value.

Commands are frozen, keyword-only dataclasses; the small group records inside them
(:class:`WheelDrive`, :class:`JointDrive`, :class:`LinkCommand`) and :class:`UnknownCommand`
also accept positional arguments.

Each command is declared once: every field of its dataclass says its key on the wire and the
kind of its value (:mod:`.declare`), and both its parser and its format follow from that.
One module per family of commands holds the declarations:

* :mod:`.robot`: INIT, DRIVE and MULTIDRIVE (§5.1, §5.3), and :mod:`.parts`: MISPKG, CAMERA
  and ACT (§5.6 to §5.8);
* :mod:`.queries`: GETSTARTPOSES, GETGEO, GETCONF and the path nodes (§5.2, §5.5, §5.8);
* :mod:`.control`: SET, CONTROL, MOVE, GOTO and TEST (§5.4, §5.8);
* :mod:`.extensions`: STEP, PING, REPORT and unknown command words (§18);
* :mod:`.declare`: the declarations (keys, repeated groups, numbered keys, name-number pairs,
  the segments no key took), compiled once per command into its parser and its format;
* :mod:`.common`: what they share (the value readers, the line builder).

This module dispatches on them: a line's command word to its parser, a command's class to its
format.  :func:`as_parsed` gives, without the text, the command a server parses from a line a
client formatted (the in-process direct path hands commands over so).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import Any

from ..grammar import RawMessage, parse_line
from . import control, extensions, parts, queries, robot
from .common import Vec3
from .control import Control, Goto, Move, Set, Test
from .extensions import REPORT_TYPES as REPORT_TYPES
from .extensions import Ping, Report, Step, UnknownCommand
from .parts import LINK_ORDERS, Act, Camera, LinkCommand, MisPkg
from .queries import GetClosestPathNode, GetConf, GetGeo, GetPathNodes, GetStartPoses
from .robot import JOINT_ORDERS, Drive, Init, JointDrive, MultiDrive, WheelDrive

__all__ = [
    "DRIVE_FLAGS",
    "DRIVE_NUMBERS",
    "Act",
    "as_parsed",
    "Camera",
    "Command",
    "Control",
    "Drive",
    "GetClosestPathNode",
    "GetConf",
    "GetGeo",
    "GetPathNodes",
    "GetStartPoses",
    "Ping",
    "Report",
    "Goto",
    "Init",
    "JOINT_ORDERS",
    "JointDrive",
    "LINK_ORDERS",
    "LinkCommand",
    "MisPkg",
    "Move",
    "MultiDrive",
    "Set",
    "Step",
    "Test",
    "UnknownCommand",
    "Vec3",
    "WheelDrive",
    "command_from_raw",
    "format_command",
    "parse_command",
]

Command = (
    Init
    | GetStartPoses
    | Drive
    | MultiDrive
    | Set
    | GetGeo
    | GetConf
    | MisPkg
    | Camera
    | Act
    | Control
    | Move
    | Goto
    | GetPathNodes
    | GetClosestPathNode
    | Test
    | Step
    | Ping
    | Report
    | UnknownCommand
)


_PARSERS: dict[str, Callable[[RawMessage], Command]] = {
    **robot.PARSERS,
    **parts.PARSERS,
    **queries.PARSERS,
    **control.PARSERS,
    **extensions.PARSERS,
}


def command_from_raw(raw: RawMessage) -> Command:
    """The command for an already split line (see :func:`parse_command`)."""
    parser = _PARSERS.get(raw.type)
    if parser is None:
        return UnknownCommand(type=raw.type, segments=raw.segments)
    return parser(raw)


# ``STEP {Time s}`` as lock-step controllers write it, thousands of times a second: read
# without splitting the line (anything else, a STEP written otherwise included, is split).
_PLAIN_STEP = re.compile(r"STEP \{Time ((?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\}")


def parse_command(line: str) -> Command:
    """Parse one client line (without its terminator) into a command.

    Raises :class:`~usarsim.errors.ProtocolError` for a malformed line or a bad value of a
    known key, and nothing else.
    """
    m = _PLAIN_STEP.fullmatch(line)
    if m is not None:
        seconds = float(m.group(1))
        if 0.0 < seconds < math.inf:  # else the general path says what is wrong
            return Step(time_s=seconds)
    return command_from_raw(parse_line(line))


_FORMATTERS: dict[type, Callable[[Any], str]] = {
    **robot.FORMATTERS,
    **parts.FORMATTERS,
    **queries.FORMATTERS,
    **control.FORMATTERS,
    **extensions.FORMATTERS,
}


# the number keys and the flags of a plain DRIVE (no wheel or joint groups), as its fields
DRIVE_NUMBERS = (
    "left",
    "right",
    "speed",
    "front_steer",
    "rear_steer",
    "altitude_velocity",
    "linear_velocity",
    "lateral_velocity",
    "rotational_velocity",
    "propeller",
    "rudder",
    "stern_plane",
)
DRIVE_FLAGS = ("normalized", "light", "flip")


def as_parsed(cmd: Command) -> Command | None:
    """What :func:`parse_command` makes of :func:`format_command` ``(cmd)``, when a quick
    rule is sure of it; None otherwise (format it and parse it).  Numbers are written exactly,
    so a finite one reads back as the same float and a flag as the same bool; a ``DRIVE`` of
    such keys alone (no wheel or joint groups) is covered."""
    if type(cmd) is not Drive or cmd.wheels or cmd.joints:
        return None
    values: dict[str, Any] = {}
    for name in DRIVE_NUMBERS:
        v = getattr(cmd, name)
        if v is None:
            continue
        if type(v) not in (float, int) or not math.isfinite(v):  # a bool, NaN, an infinity: the parser says
            return None
        values[name] = float(v)
    for name in DRIVE_FLAGS:
        v = getattr(cmd, name)
        if v is not None:
            if type(v) is not bool:
                return None
            values[name] = v
    return Drive(**values) if values else None


def format_command(cmd: Command) -> str:
    """The line a client sends for ``cmd``, canonical key spelling, ending with CR LF.

    Numbers are written exactly (shortest form that reads back as the same float, no
    exponent).  Text containing braces or line breaks cannot be sent and raises
    :class:`~usarsim.errors.ProtocolError`.
    """
    try:
        formatter = _FORMATTERS[type(cmd)]
    except KeyError:
        raise TypeError(f"not a command: {cmd!r}") from None
    return formatter(cmd)
