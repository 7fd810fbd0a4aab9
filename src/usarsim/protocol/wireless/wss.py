"""The Wireless Simulation Server's words (WSS, the RoboCup one by M. Pfingsthorn;
protocol.md 12.2).

Robots keep a control connection to TCP 50000 and speak USARSim's brace syntax, one
request a line (CR LF): ``INIT {Robot r} {Port p[,p2...]}``, ``GETSS {Robot r}``,
``DNS {Robot r} [{Port p}]``, ``REVERSEDNS {Port p}``.  Replies are ``INITREPLY``, ``SS``,
``DNSREPLY``, ``REVERSEDNSREPLY`` and ``ERROR {Reason ...}``, whose reasons are the WSS's
own dotted words (spelling included: ``Robot.Alread.Exists``).

* :func:`parse_wss_request` / :func:`format_wss_request`: the typed requests; a known
  request with a bad value is a :class:`WssInvalid` naming the ERROR reason it gets.
* :func:`format_wss_reply` / :func:`parse_wss_reply`: the typed replies.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

from usarsim.errors import ProtocolError

from ..grammar import (
    RawMessage,
    Segment,
    format_segment,
    parse_float,
    parse_int,
    parse_line,
)
from .common import check_port, check_value, format_unknown, parse_port

__all__ = [
    "DNS_NOT_LISTENING",
    "DNS_NO_ROBOT",
    "REASON_EMPTY_NAME",
    "REASON_INIT_FIRST",
    "REASON_NO_RELAY_PORT",
    "REASON_PORTS_NOT_INTEGER",
    "REASON_PORT_NOT_INTEGER",
    "REASON_ROBOT_EXISTS",
    "REASON_UNKNOWN_METHOD",
    "REVERSEDNS_UNKNOWN_PORT",
    "SS_MODEL_NAN",
    "SS_NO_ROBOT",
    "SS_TO_SELF",
    "WSS_PORT",
    "WssDns",
    "WssDnsReply",
    "WssError",
    "WssGetSS",
    "WssInit",
    "WssInitReply",
    "WssInvalid",
    "WssReply",
    "WssRequest",
    "WssReverseDns",
    "WssReverseDnsReply",
    "WssSignal",
    "WssUnknown",
    "fmt_wss_dbm",
    "format_wss_reply",
    "format_wss_request",
    "parse_wss_reply",
    "parse_wss_request",
]

WSS_PORT = 50000
"""The WSS's control port (``--wss-port``)."""

# ERROR {Reason ...}: the reasons, in the WSS's words
REASON_INIT_FIRST = "Must.Use.INIT.Method.First"
"""Any request but INIT before INIT."""
REASON_PORTS_NOT_INTEGER = "Ports.List.Must.Be.Integer"
"""INIT with a Port list that is not ports."""
REASON_EMPTY_NAME = "Robot.Name.Must.Not.Be.Empty"
"""INIT, GETSS or DNS without a robot name."""
REASON_ROBOT_EXISTS = "Robot.Alread.Exists"  # sic
"""INIT of a name another connection registered."""
REASON_PORT_NOT_INTEGER = "Port.Must.Be.Integer"
"""DNS or REVERSEDNS with a Port that is not a port."""
REASON_NO_RELAY_PORT = "Could.Not.Allocate.Port"
"""DNS when the server cannot open a relay port."""
REASON_UNKNOWN_METHOD = "Method.Unknown.Or.Can.INIT.only.once"
"""An unknown or malformed request, or a second INIT."""

# SS {Robot r} {Strength s} {Error ...}
SS_TO_SELF = "SS.To.Self"
"""GETSS of the asking robot itself (strength INF)."""
SS_NO_ROBOT = "Robot.Does.Not.Exist"
"""GETSS of a robot that did not INIT (strength NaN)."""
SS_MODEL_NAN = "Model.Returned.NaN"
"""GETSS the radio model cannot answer, e.g. a robot not in the simulation (strength NaN)."""

# DNSREPLY {Robot r} {Port -1} {Error ...} and REVERSEDNSREPLY {Port p} {Error ...}
DNS_NO_ROBOT = "NoSuchRobot"
"""DNS of a robot that did not INIT (or of the asking robot)."""
DNS_NOT_LISTENING = "RobotDoesNotListenOnThisPort"
"""DNS naming a port the robot did not declare in its INIT."""
REVERSEDNS_UNKNOWN_PORT = "UnknownOrIllegalPort"
"""REVERSEDNS of a port that leads to no robot."""

_CRLF = "\r\n"


# --------------------------------------------------------------------------- requests


@dataclass(frozen=True, slots=True)
class WssInit:
    """``INIT {Robot r} {Port p,...}``: this connection is robot ``robot``, which accepts
    connections on ``ports`` (the first is the one DNS gives by default).  A port 0 in the
    list, which the reference WSS accepts, is no listening port: the WSS skips it."""

    type: ClassVar[str] = "INIT"
    robot: str
    ports: tuple[int, ...] = ()


@dataclass(frozen=True, slots=True)
class WssGetSS:
    """``GETSS {Robot r}``: the signal strength from the asking robot to ``robot``."""

    type: ClassVar[str] = "GETSS"
    robot: str


@dataclass(frozen=True, slots=True)
class WssDns:
    """``DNS {Robot r} [{Port p}]``: the relay port that reaches ``robot`` on ``port``
    (None: its first declared port; ``{Port 0}`` reads as None)."""

    type: ClassVar[str] = "DNS"
    robot: str
    port: int | None = None


@dataclass(frozen=True, slots=True)
class WssReverseDns:
    """``REVERSEDNS {Port p}``: which robot is at the other end of ``port``."""

    type: ClassVar[str] = "REVERSEDNS"
    port: int


@dataclass(frozen=True, slots=True)
class WssUnknown:
    """A request word the WSS does not know (answered ``REASON_UNKNOWN_METHOD``)."""

    type: str
    segments: tuple[Segment, ...] = ()


@dataclass(frozen=True, slots=True)
class WssInvalid:
    """A known request (``type``) with a missing or bad value: answered
    ``ERROR {Reason <reason>}`` (one of the ``REASON_*`` constants)."""

    type: str
    reason: str


WssRequest = WssInit | WssGetSS | WssDns | WssReverseDns | WssUnknown | WssInvalid


def _robot(raw: RawMessage) -> str:
    return (raw.get("Robot") or "").strip()


def _parse_init(raw: RawMessage) -> WssRequest:
    # Port 0 is accepted in INIT's list, as the reference WSS reads the list as unsigned
    # integers (protocol.md 12.2): controllers that only connect out send {Port 0}.  It is
    # kept here as sent; to the server 0 is no listening port (see WssServer.dns).
    ports = []
    for p in (raw.get("Port") or "").replace(" ", "").split(","):
        if p:
            try:
                ports.append(parse_port(p, zero=True))
            except ProtocolError:
                return WssInvalid("INIT", REASON_PORTS_NOT_INTEGER)
    name = _robot(raw)
    if not name:
        return WssInvalid("INIT", REASON_EMPTY_NAME)
    return WssInit(name, tuple(ports))


def _parse_getss(raw: RawMessage) -> WssRequest:
    name = _robot(raw)
    return WssGetSS(name) if name else WssInvalid("GETSS", REASON_EMPTY_NAME)


def _parse_dns(raw: RawMessage) -> WssRequest:
    # {Port 0} asks for the default port, as no Port at all: the reference WSS reads 0 as
    # "not given" (protocol.md 12.2)
    port = None
    if raw.has("Port"):
        try:
            port = parse_port(raw.get("Port") or "", zero=True) or None
        except ProtocolError:
            return WssInvalid("DNS", REASON_PORT_NOT_INTEGER)
    name = _robot(raw)
    return WssDns(name, port) if name else WssInvalid("DNS", REASON_EMPTY_NAME)


def _parse_reverse_dns(raw: RawMessage) -> WssRequest:
    try:
        return WssReverseDns(parse_port(raw.get("Port") or ""))
    except ProtocolError:
        return WssInvalid("REVERSEDNS", REASON_PORT_NOT_INTEGER)


_REQUEST_PARSERS = {"INIT": _parse_init, "GETSS": _parse_getss, "DNS": _parse_dns, "REVERSEDNS": _parse_reverse_dns}


def parse_wss_request(line: str) -> WssRequest:
    """One request line (with or without its CR LF).  The request word and the keys are
    case-insensitive; unknown keys are ignored.  An unknown word gives :class:`WssUnknown`,
    a known request with a bad or missing value :class:`WssInvalid` (checked in the WSS's
    order: INIT's ports before its name, DNS's port before its robot).  A line that is not
    ``TYPE {Key Value} ...`` raises :class:`~usarsim.errors.ProtocolError`, and nothing
    else is raised."""
    raw = parse_line(line.rstrip("\r\n"))
    parser = _REQUEST_PARSERS.get(raw.type)
    if parser is None:
        return WssUnknown(raw.type, raw.segments)
    return parser(raw)


def format_wss_request(req: WssRequest) -> str:
    """The line a robot sends for ``req``, ending with CR LF.  Text that cannot be read back
    as sent (braces, line breaks, blanks at its ends) raises
    :class:`~usarsim.errors.ProtocolError`; a :class:`WssInvalid` cannot be sent
    (TypeError)."""
    if isinstance(req, WssInit):
        parts = ["INIT", format_segment("Robot", check_value(req.robot, "robot name"))]
        if req.ports:
            parts.append(format_segment("Port", ",".join(check_port(p, zero=True) for p in req.ports)))
    elif isinstance(req, WssGetSS):
        parts = ["GETSS", format_segment("Robot", check_value(req.robot, "robot name"))]
    elif isinstance(req, WssDns):
        parts = ["DNS", format_segment("Robot", check_value(req.robot, "robot name"))]
        if req.port is not None:
            parts.append(format_segment("Port", check_port(req.port)))
    elif isinstance(req, WssReverseDns):
        parts = ["REVERSEDNS", format_segment("Port", check_port(req.port))]
    elif isinstance(req, WssUnknown):
        return format_unknown(req.type, req.segments)
    else:
        raise TypeError(f"not a WSS request that can be sent: {req!r}")
    return " ".join(parts) + _CRLF


# --------------------------------------------------------------------------- replies


def fmt_wss_dbm(x: float) -> str:
    """A GETSS strength: 6 significant digits, as the C++ WSS streamed doubles; NaN and
    infinities as the WSS wrote them (``NaN``, ``INF``)."""
    if math.isnan(x):
        return "NaN"
    if math.isinf(x):
        return "INF" if x > 0 else "-INF"
    return f"{x:.6g}"


@dataclass(frozen=True, slots=True)
class WssInitReply:
    """``INITREPLY {Status OK}``: the robot is registered."""

    status: str = "OK"


@dataclass(frozen=True, slots=True)
class WssSignal:
    """``SS {Robot r} {Strength dBm} [{Error e}]``: the answer to GETSS; ``strength_dbm`` is
    NaN or INF when there is none, and ``error`` (an ``SS_*`` constant) says why."""

    robot: str
    strength_dbm: float
    error: str | None = None


@dataclass(frozen=True, slots=True)
class WssDnsReply:
    """``DNSREPLY {Robot r} {Port p} [{Error e}]``: the relay port to connect to, or port -1
    and an error (``DNS_*``)."""

    robot: str
    port: int
    error: str | None = None


@dataclass(frozen=True, slots=True)
class WssReverseDnsReply:
    """``REVERSEDNSREPLY {Port p} {Robot r}``, or ``{Error e}`` instead of the robot."""

    port: int
    robot: str | None = None
    error: str | None = None


@dataclass(frozen=True, slots=True)
class WssError:
    """``ERROR {Reason r}`` (``REASON_*``)."""

    reason: str


WssReply = WssInitReply | WssSignal | WssDnsReply | WssReverseDnsReply | WssError


def _error(error: str | None) -> str:
    return f" {{Error {error}}}" if error else ""


def format_wss_reply(reply: WssReply) -> str:
    """The line the WSS sends for ``reply``, ending with CR LF."""
    if isinstance(reply, WssInitReply):
        return f"INITREPLY {{Status {reply.status}}}\r\n"
    if isinstance(reply, WssSignal):
        strength = fmt_wss_dbm(reply.strength_dbm)
        return f"SS {{Robot {reply.robot}}} {{Strength {strength}}}{_error(reply.error)}\r\n"
    if isinstance(reply, WssDnsReply):
        return f"DNSREPLY {{Robot {reply.robot}}} {{Port {reply.port:d}}}{_error(reply.error)}\r\n"
    if isinstance(reply, WssReverseDnsReply):
        robot = f" {{Robot {reply.robot}}}" if reply.robot is not None else ""
        return f"REVERSEDNSREPLY {{Port {reply.port:d}}}{robot}{_error(reply.error)}\r\n"
    if isinstance(reply, WssError):
        return f"ERROR {{Reason {reply.reason}}}\r\n"
    raise TypeError(f"not a WSS reply: {reply!r}")


def _required(raw: RawMessage, key: str) -> str:
    value = raw.get(key)
    if value is None:
        raise ProtocolError(f"{raw.type}: missing {{{key} ...}}")
    return value


def parse_wss_reply(line: str) -> WssReply:
    """One line from the WSS (with or without its CR LF), as a robot reads it.  A line that
    is not one of the replies, or lacks one of its keys, raises
    :class:`~usarsim.errors.ProtocolError`."""
    raw = parse_line(line.rstrip("\r\n"))
    kind = raw.type
    if kind == "INITREPLY":
        return WssInitReply(_required(raw, "Status"))
    if kind == "SS":
        return WssSignal(_required(raw, "Robot"), parse_float(_required(raw, "Strength")), raw.get("Error"))
    if kind == "DNSREPLY":
        return WssDnsReply(_required(raw, "Robot"), parse_int(_required(raw, "Port")), raw.get("Error"))
    if kind == "REVERSEDNSREPLY":
        return WssReverseDnsReply(parse_int(_required(raw, "Port")), raw.get("Robot"), raw.get("Error"))
    if kind == "ERROR":
        return WssError(_required(raw, "Reason"))
    raise ProtocolError(f"expected a WSS reply (INITREPLY, SS, DNSREPLY, REVERSEDNSREPLY, ERROR), got {kind}")
