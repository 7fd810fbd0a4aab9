"""The ComServerInterface's words (protocol.md 12.3): what the WSS's propagation models
ask the simulator on TCP 7435, in brace syntax, one request a line (CR LF).

* ``GETPOS`` -> ``POSITIONS {Robots n} {Name r Location x,y,z BatteryEmpty False} ...``
  (world frame, metres, 4 decimals);
* ``GETOBS {From r1} {To r2}`` or ``GETOBS {Start x,y,z} {End x,y,z}`` ->
  ``NUMOBS {From r1} {To r2} {ObstCount n}`` (the query echoed as it was sent; -1 when it
  cannot be answered), and ``NUMOBS {ObstCount -1}`` to a GETOBS with neither pair.

:func:`parse_interface_request` / :func:`format_interface_request` and
:func:`format_interface_reply` / :func:`parse_interface_reply` convert them.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, fields
from typing import ClassVar

from usarsim.errors import ProtocolError

from ..grammar import (
    RawMessage,
    Segment,
    parse_bool,
    parse_int,
    parse_line,
    parse_vector,
)
from ..numbers import bool_str, vec4
from .common import check_value, format_unknown, shorten

__all__ = [
    "INTERFACE_PORT",
    "GetObsIncomplete",
    "GetObsPoints",
    "GetObsRobots",
    "GetPos",
    "InterfaceReply",
    "InterfaceRequest",
    "InterfaceUnknown",
    "NumObs",
    "Positions",
    "RobotPosition",
    "format_interface_reply",
    "format_interface_request",
    "parse_interface_reply",
    "parse_interface_request",
]

INTERFACE_PORT = 7435
"""The ComServerInterface's TCP port (``--cominterface-port``); explicitly not 3000."""

Vec3 = tuple[float, float, float]

_CRLF = "\r\n"
_ROBOT_RE = re.compile(r"(.+?)\s+Location\s+(\S+)\s+BatteryEmpty\s+(\S+)\Z", re.DOTALL)


# --------------------------------------------------------------------------- requests


@dataclass(frozen=True, slots=True)
class GetPos:
    """``GETPOS``: where every robot is."""

    type: ClassVar[str] = "GETPOS"


@dataclass(frozen=True, slots=True)
class GetObsRobots:
    """``GETOBS {From r1} {To r2}``: walls between two robots' antennas."""

    type: ClassVar[str] = "GETOBS"
    from_robot: str
    to_robot: str


@dataclass(frozen=True, slots=True)
class GetObsPoints:
    """``GETOBS {Start x,y,z} {End x,y,z}``: walls between two points.  The text is kept as
    sent, since the reply echoes it; :meth:`points` reads it."""

    type: ClassVar[str] = "GETOBS"
    start: str
    end: str

    def points(self) -> tuple[Vec3, Vec3]:
        """The two points (metres, world frame).  Text that is not three finite numbers
        raises :class:`~usarsim.errors.ProtocolError` (answered ``{ObstCount -1}``)."""
        p, q = parse_vector(self.start), parse_vector(self.end)
        if not all(math.isfinite(v) for v in p + q):
            raise ProtocolError(
                f"GETOBS: Start and End must be finite, got {shorten(self.start)} and {shorten(self.end)}"
            )
        return p, q  # type: ignore[return-value]


@dataclass(frozen=True, slots=True)
class GetObsIncomplete:
    """``GETOBS`` with neither ``{From} {To}`` nor ``{Start} {End}`` (answered
    ``NUMOBS {ObstCount -1}``)."""

    type: ClassVar[str] = "GETOBS"


@dataclass(frozen=True, slots=True)
class InterfaceUnknown:
    """A request word the ComServerInterface does not know (it is ignored)."""

    type: str
    segments: tuple[Segment, ...] = ()


InterfaceRequest = GetPos | GetObsRobots | GetObsPoints | GetObsIncomplete | InterfaceUnknown
GetObsQuery = GetObsRobots | GetObsPoints


def _getobs(raw: RawMessage) -> GetObsQuery | GetObsIncomplete:
    """From/To wins over Start/End; an empty value counts as missing."""
    a, b = raw.get("From"), raw.get("To")
    if a and b:
        return GetObsRobots(a, b)
    start, end = raw.get("Start"), raw.get("End")
    if start and end:
        return GetObsPoints(start, end)
    return GetObsIncomplete()


def parse_interface_request(line: str) -> InterfaceRequest:
    """One request line (with or without its CR LF); the word and keys are
    case-insensitive.  A line that is not ``TYPE {Key Value} ...`` raises
    :class:`~usarsim.errors.ProtocolError`, and nothing else is raised."""
    raw = parse_line(line.rstrip("\r\n"))
    if raw.type == "GETPOS":
        return GetPos()
    if raw.type == "GETOBS":
        return _getobs(raw)
    return InterfaceUnknown(raw.type, raw.segments)


def _query(q: GetObsQuery) -> str:
    if isinstance(q, GetObsRobots):
        return f"{{From {q.from_robot}}} {{To {q.to_robot}}}"
    return f"{{Start {q.start}}} {{End {q.end}}}"


def _checked(q: GetObsQuery) -> GetObsQuery:
    for f in fields(q):
        check_value(getattr(q, f.name), f.name)
    return q


def format_interface_request(req: InterfaceRequest) -> str:
    """The line a client (a WSS propagation model) sends, ending with CR LF.  Text that
    cannot be read back as sent raises :class:`~usarsim.errors.ProtocolError`."""
    if isinstance(req, GetPos):
        return "GETPOS" + _CRLF
    if isinstance(req, (GetObsRobots, GetObsPoints)):
        return "GETOBS " + _query(_checked(req)) + _CRLF
    if isinstance(req, GetObsIncomplete):
        return "GETOBS" + _CRLF
    if isinstance(req, InterfaceUnknown):
        return format_unknown(req.type, req.segments)
    raise TypeError(f"not a ComServerInterface request: {req!r}")


# --------------------------------------------------------------------------- replies


@dataclass(frozen=True, slots=True)
class RobotPosition:
    """One robot of POSITIONS: its name, location (metres, world frame) and whether its
    battery is empty."""

    name: str
    location: Vec3
    battery_empty: bool = False


@dataclass(frozen=True, slots=True)
class Positions:
    """``POSITIONS {Robots n} {Name ...} ...``: every robot of the simulation."""

    robots: tuple[RobotPosition, ...] = ()


@dataclass(frozen=True, slots=True)
class NumObs:
    """``NUMOBS <query> {ObstCount n}``: the walls crossed for the GETOBS ``query`` (None:
    the GETOBS had neither pair), -1 when it cannot be answered."""

    count: int
    query: GetObsQuery | None = None


InterfaceReply = Positions | NumObs


def format_interface_reply(reply: InterfaceReply) -> str:
    """The line the ComServerInterface sends for ``reply``, ending with CR LF."""
    if isinstance(reply, Positions):
        parts = [f"POSITIONS {{Robots {len(reply.robots)}}}"]
        parts += [
            f"{{Name {r.name} Location {vec4(r.location)} BatteryEmpty {bool_str(r.battery_empty)}}}"
            for r in reply.robots
        ]
        return " ".join(parts) + _CRLF
    if isinstance(reply, NumObs):
        query = _query(reply.query) + " " if reply.query is not None else ""
        return f"NUMOBS {query}{{ObstCount {reply.count:d}}}\r\n"
    raise TypeError(f"not a ComServerInterface reply: {reply!r}")


def _robot_position(value: str) -> RobotPosition:
    m = _ROBOT_RE.match(value)
    if m is None:
        raise ProtocolError(f"POSITIONS: expected {{Name r Location x,y,z BatteryEmpty b}}, got {shorten(value)}")
    return RobotPosition(m.group(1), parse_vector(m.group(2)), parse_bool(m.group(3)))  # type: ignore[arg-type]


def parse_interface_reply(line: str) -> InterfaceReply:
    """One line from the ComServerInterface (with or without its CR LF), as a WSS model
    reads it.  Anything else, or a POSITIONS whose count disagrees with its robots, raises
    :class:`~usarsim.errors.ProtocolError`."""
    raw = parse_line(line.rstrip("\r\n"))
    if raw.type == "POSITIONS":
        count = raw.get("Robots")
        if count is None:
            raise ProtocolError("POSITIONS: missing {Robots n}")
        robots = tuple(_robot_position(v) for v in raw.get_all("Name"))
        if parse_int(count) != len(robots):
            raise ProtocolError(f"POSITIONS: {{Robots {count}}} but {len(robots)} robots follow")
        return Positions(robots)
    if raw.type == "NUMOBS":
        count = raw.get("ObstCount")
        if count is None:
            raise ProtocolError("NUMOBS: missing {ObstCount n}")
        query = _getobs(raw)
        return NumObs(parse_int(count), None if isinstance(query, GetObsIncomplete) else query)
    raise ProtocolError(f"expected a ComServerInterface reply (POSITIONS, NUMOBS), got {raw.type}")
