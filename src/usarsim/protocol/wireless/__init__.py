"""The wireless simulation's three text protocols (protocol.md 12; manual 3.2.4), sans-IO:

* :mod:`.comserver`: the ComServer (WCS, TCP 5874): ``;``-ended commands, ``OK;`` /
  ``OK:<dBm>;`` / ``Fail: ...;`` replies, and the ``SEND <n> <bytes>;`` / ``CLOSE;``
  framing of the links it relays;
* :mod:`.wss`: the Wireless Simulation Server (TCP 50000): INIT, GETSS, DNS, REVERSEDNS
  and their replies;
* :mod:`.interface`: the ComServerInterface (TCP 7435): GETPOS, GETOBS, POSITIONS,
  NUMOBS.

Each request and reply is a frozen dataclass with one parse and one format function per
direction; parsing raises :class:`~usarsim.errors.ProtocolError` and nothing else.  Like
the rest of :mod:`usarsim.protocol` this imports the standard library only: the servers
(:mod:`usarsim.server.wireless`) do the sockets.
"""

from __future__ import annotations

from .common import MAX_PORT, parse_port
from .comserver import (
    CLOSE_FRAME,
    FAIL_INCORRECT_MESSAGE,
    FAIL_NO_CONNECTION,
    FAIL_NO_SIGNAL,
    FAIL_THIRD_PARTY,
    FAIL_TOO_MANY_LISTENING,
    FAIL_TOO_MANY_REGISTERED,
    FAIL_UNKNOWN_MESSAGE,
    MAX_COMMAND_BYTES,
    MAX_SEND_BYTES,
    WCS_PORT,
    CommandSplitter,
    SendClose,
    SendEvent,
    SendParser,
    SendProblem,
    WcsFail,
    WcsGetSS,
    WcsListen,
    WcsOk,
    WcsOpen,
    WcsRegister,
    WcsReply,
    WcsRequest,
    WcsSignal,
    WcsUnknown,
    fmt_wcs_dbm,
    format_send,
    format_wcs_reply,
    format_wcs_request,
    parse_wcs_reply,
    parse_wcs_request,
    wcs_request_word,
)
from .interface import (
    INTERFACE_PORT,
    GetObsIncomplete,
    GetObsPoints,
    GetObsRobots,
    GetPos,
    InterfaceReply,
    InterfaceRequest,
    InterfaceUnknown,
    NumObs,
    Positions,
    RobotPosition,
    format_interface_reply,
    format_interface_request,
    parse_interface_reply,
    parse_interface_request,
)
from .wss import (
    DNS_NO_ROBOT,
    DNS_NOT_LISTENING,
    REASON_EMPTY_NAME,
    REASON_INIT_FIRST,
    REASON_NO_RELAY_PORT,
    REASON_PORT_NOT_INTEGER,
    REASON_PORTS_NOT_INTEGER,
    REASON_ROBOT_EXISTS,
    REASON_UNKNOWN_METHOD,
    REVERSEDNS_UNKNOWN_PORT,
    SS_MODEL_NAN,
    SS_NO_ROBOT,
    SS_TO_SELF,
    WSS_PORT,
    WssDns,
    WssDnsReply,
    WssError,
    WssGetSS,
    WssInit,
    WssInitReply,
    WssInvalid,
    WssReply,
    WssRequest,
    WssReverseDns,
    WssReverseDnsReply,
    WssSignal,
    WssUnknown,
    fmt_wss_dbm,
    format_wss_reply,
    format_wss_request,
    parse_wss_reply,
    parse_wss_request,
)

__all__ = [
    "CLOSE_FRAME", "DNS_NOT_LISTENING", "DNS_NO_ROBOT", "FAIL_INCORRECT_MESSAGE", "FAIL_NO_CONNECTION",
    "FAIL_NO_SIGNAL", "FAIL_THIRD_PARTY", "FAIL_TOO_MANY_LISTENING", "FAIL_TOO_MANY_REGISTERED",
    "FAIL_UNKNOWN_MESSAGE", "INTERFACE_PORT", "MAX_COMMAND_BYTES", "MAX_PORT", "MAX_SEND_BYTES",
    "REASON_EMPTY_NAME", "REASON_INIT_FIRST", "REASON_NO_RELAY_PORT", "REASON_PORTS_NOT_INTEGER",
    "REASON_PORT_NOT_INTEGER", "REASON_ROBOT_EXISTS", "REASON_UNKNOWN_METHOD", "REVERSEDNS_UNKNOWN_PORT",
    "SS_MODEL_NAN", "SS_NO_ROBOT", "SS_TO_SELF", "WCS_PORT", "WSS_PORT",
    "CommandSplitter", "GetObsIncomplete", "GetObsPoints", "GetObsRobots", "GetPos", "InterfaceReply",
    "InterfaceRequest", "InterfaceUnknown", "NumObs", "Positions", "RobotPosition", "SendClose", "SendEvent",
    "SendParser", "SendProblem", "WcsFail", "WcsGetSS", "WcsListen", "WcsOk", "WcsOpen", "WcsRegister",
    "WcsReply", "WcsRequest", "WcsSignal", "WcsUnknown", "WssDns", "WssDnsReply", "WssError", "WssGetSS",
    "WssInit", "WssInitReply", "WssInvalid", "WssReply", "WssRequest", "WssReverseDns", "WssReverseDnsReply",
    "WssSignal", "WssUnknown",
    "fmt_wcs_dbm", "fmt_wss_dbm", "format_interface_reply", "format_interface_request", "format_send",
    "format_wcs_reply", "format_wcs_request", "format_wss_reply", "format_wss_request", "parse_interface_reply",
    "parse_interface_request", "parse_port", "parse_wcs_reply", "parse_wcs_request", "parse_wss_reply",
    "parse_wss_request", "wcs_request_word",
]
