"""The ComServer's words (WCS, USARSim's in-simulator wireless server; protocol.md 12.1,
manual section 3.2.4.3).

Robots speak to it on TCP 5874 in ASCII commands of space-separated words, each ended by
``;`` (no braces, no line breaks needed): ``REGISTER name ip;``, ``LISTEN name port;``,
``OPEN src srcPort dst dstPort;``, ``GETSS name1 name2;``.  The command word is
case-insensitive.  Replies are ``OK;``, ``OK:<dBm>;`` (GETSS) and ``Fail: <reason>;``.

* :class:`CommandSplitter` cuts the byte stream into commands (without their ``;``).
* :func:`parse_wcs_request` / :func:`format_wcs_request`: the typed commands.
* :func:`format_wcs_reply` / :func:`parse_wcs_reply`: the typed replies; the documented
  ``Fail`` reasons are the ``FAIL_*`` constants and the :class:`WcsFail` constructors.
* :class:`SendParser` / :func:`format_send`: the framing of a relayed link,
  ``SEND <n> <n bytes>;`` (binary-safe) and ``CLOSE;``.
"""

from __future__ import annotations

from dataclasses import astuple, dataclass
from typing import ClassVar, Self

from usarsim.errors import ProtocolError

from ..grammar import parse_float
from ..numbers import f2
from .common import check_port, check_word, parse_port, shorten

__all__ = [
    "CLOSE_FRAME",
    "FAIL_INCORRECT_MESSAGE",
    "FAIL_NO_CONNECTION",
    "FAIL_NO_SIGNAL",
    "FAIL_THIRD_PARTY",
    "FAIL_TOO_MANY_LISTENING",
    "FAIL_TOO_MANY_REGISTERED",
    "FAIL_UNKNOWN_MESSAGE",
    "MAX_COMMAND_BYTES",
    "MAX_SEND_BYTES",
    "WCS_PORT",
    "CommandSplitter",
    "SendClose",
    "SendEvent",
    "SendParser",
    "SendProblem",
    "WcsFail",
    "WcsGetSS",
    "WcsListen",
    "WcsOk",
    "WcsOpen",
    "WcsRegister",
    "WcsReply",
    "WcsRequest",
    "WcsSignal",
    "WcsUnknown",
    "fmt_wcs_dbm",
    "format_send",
    "format_wcs_reply",
    "format_wcs_request",
    "parse_wcs_reply",
    "parse_wcs_request",
    "wcs_request_word",
]

WCS_PORT = 5874
"""The ComServer's TCP port (``--wcs-port``)."""

MAX_COMMAND_BYTES = 1024
"""Longest ComServer command up to its ``;`` (the manual's are a few dozen characters);
a longer one is dropped whole."""

MAX_SEND_BYTES = 1 << 20
"""Longest message of one SEND on a relayed link; a longer one is dropped."""

_FORBIDDEN = ";"  # a word of a command cannot hold the command's end


# --------------------------------------------------------------------------- the command stream


class CommandSplitter:
    """Incremental splitter of a ComServer command connection: bytes in, the commands they
    complete out, without their ``;``.

    * Bytes are decoded as ASCII; any other byte becomes U+FFFD, so garbage never raises.
    * Blank commands (``;;``, ``; ;``) are skipped: the ComServer does not answer them.
    * A command longer than ``max_bytes`` is dropped whole, including what of it arrives in
      later reads up to its ``;``, and counted in ``dropped_commands`` (the caller logs it).

    ``feed`` never raises, and holds at most ``max_bytes`` bytes between calls.
    """

    __slots__ = ("_buf", "_dropping", "dropped_commands", "max_bytes")

    def __init__(self, max_bytes: int = MAX_COMMAND_BYTES):
        if max_bytes < 1:
            raise ValueError(f"max_bytes must be at least 1, got {max_bytes}")
        self.max_bytes = max_bytes
        self.dropped_commands = 0
        self._buf = bytearray()
        self._dropping = False  # skipping the rest of an over-long command (counted already)

    @property
    def pending_bytes(self) -> int:
        """Bytes of an unfinished command held until its ``;`` arrives."""
        return len(self._buf)

    def feed(self, data: bytes) -> list[str]:
        """Add received bytes; return the commands they complete, in order."""
        buf = self._buf
        buf += data
        out: list[str] = []
        start = 0
        while True:
            end = buf.find(b";", start)
            if end < 0:
                break
            if self._dropping:  # the end of an over-long command
                self._dropping = False
            elif end - start > self.max_bytes:
                self.dropped_commands += 1
            else:
                text = buf[start:end].decode("ascii", "replace")
                if text.split():
                    out.append(text)
            start = end + 1
        del buf[:start]
        if len(buf) > self.max_bytes:
            if not self._dropping:
                self._dropping = True
                self.dropped_commands += 1
            buf.clear()
        elif self._dropping:
            buf.clear()
        return out


# --------------------------------------------------------------------------- commands


@dataclass(frozen=True, slots=True)
class WcsRegister:
    """``REGISTER name ip;``: the robot ``name`` (as in its INIT) is reached at ``ip``."""

    type: ClassVar[str] = "REGISTER"
    name: str
    ip: str


@dataclass(frozen=True, slots=True)
class WcsListen:
    """``LISTEN name port;``: the robot accepts one link on ``port``."""

    type: ClassVar[str] = "LISTEN"
    name: str
    port: int


@dataclass(frozen=True, slots=True)
class WcsOpen:
    """``OPEN src srcPort dst dstPort;``: link ``src`` (listening on ``src_port``) to
    ``dst``, which must have said ``LISTEN dst dstPort``; the server connects to both."""

    type: ClassVar[str] = "OPEN"
    src: str
    src_port: int
    dst: str
    dst_port: int


@dataclass(frozen=True, slots=True)
class WcsGetSS:
    """``GETSS name1 name2;``: the signal strength between two robots."""

    type: ClassVar[str] = "GETSS"
    a: str
    b: str


@dataclass(frozen=True, slots=True)
class WcsUnknown:
    """A command whose first word the ComServer does not know (``text`` as sent, trimmed);
    answered ``Fail: Unknown Message;``."""

    text: str


WcsRequest = WcsRegister | WcsListen | WcsOpen | WcsGetSS | WcsUnknown

# command word -> (class, what its words are, which of them are ports)
_COMMANDS: dict[str, tuple[type, str, tuple[bool, ...]]] = {
    "REGISTER": (WcsRegister, "robotName ip", (False, False)),
    "LISTEN": (WcsListen, "robotName port", (False, True)),
    "OPEN": (WcsOpen, "srcName srcPort dstName dstPort", (False, True, False, True)),
    "GETSS": (WcsGetSS, "name1 name2", (False, False)),
}


def wcs_request_word(text: str) -> str:
    """The command word of a ComServer command, upper-cased ("" for a blank one): what a
    server names a kind of bad command by."""
    words = text.split()
    return words[0].upper() if words else ""


def parse_wcs_request(text: str) -> WcsRequest:
    """One ComServer command (without its ``;``, as :class:`CommandSplitter` gives it).

    An unknown command word gives :class:`WcsUnknown`.  A blank command, a known command
    with the wrong number of words or a port that is not 1-65535 raises
    :class:`~usarsim.errors.ProtocolError` (answered ``Fail: Incorrect Message;``), and
    nothing else is raised.
    """
    words = text.split()
    if not words:
        raise ProtocolError("an empty ComServer command: expected REGISTER, LISTEN, OPEN or GETSS")
    word = words[0].upper()
    spec = _COMMANDS.get(word)
    if spec is None:
        return WcsUnknown(text.strip())
    cls, usage, ports = spec
    args = words[1:]
    if len(args) != len(ports):
        raise ProtocolError(
            f"{word} takes {len(ports)} words ({word} {usage};), got {len(args)} in {shorten(text.strip())}"
        )
    values = [parse_port(a, f"{word}: a port") if is_port else a for a, is_port in zip(args, ports)]
    command: WcsRequest = cls(*values)
    return command


def format_wcs_request(cmd: WcsRequest) -> str:
    """The command a robot sends for ``cmd``, ended by ``;``.  A name or address that is not
    one word free of ``;`` raises :class:`~usarsim.errors.ProtocolError`."""
    if isinstance(cmd, WcsUnknown):
        if not cmd.text.split() or _FORBIDDEN in cmd.text:
            raise ProtocolError(f"cannot send the command {shorten(cmd.text)}: it must hold words and no ';'")
        return cmd.text + ";"
    spec = _COMMANDS.get(getattr(cmd, "type", ""))
    if spec is None or not isinstance(cmd, spec[0]):
        raise TypeError(f"not a ComServer command: {cmd!r}")
    words = [
        check_port(v, f"{cmd.type} port") if is_port else check_word(v, f"{cmd.type} word", _FORBIDDEN)
        for v, is_port in zip(astuple(cmd), spec[2])
    ]
    return " ".join([cmd.type, *words]) + ";"


# --------------------------------------------------------------------------- replies


def fmt_wcs_dbm(x: float) -> str:
    """A GETSS signal strength: 2 decimals, as UnrealScript printed floats (``-0.00`` is
    printed ``0.00``)."""
    return f2(x)


@dataclass(frozen=True, slots=True)
class WcsOk:
    """``OK;``: the command was carried out."""


@dataclass(frozen=True, slots=True)
class WcsSignal:
    """``OK:<dBm>;``: the answer to GETSS, 2 decimals (:func:`fmt_wcs_dbm`)."""

    dbm: float


@dataclass(frozen=True, slots=True)
class WcsFail:
    """``Fail: <reason>;``.  The reasons the ComServer gives are the ``FAIL_*`` constants
    and the constructors below (USARSim's own words)."""

    reason: str

    @classmethod
    def already_registered(cls, name: str) -> WcsFail:
        """REGISTER of a name registered at another address."""
        return cls(f"Robot with name {name} already registered")

    @classmethod
    def not_registered(cls, name: str) -> WcsFail:
        """LISTEN or OPEN for a robot that did not REGISTER."""
        return cls(f"Robot {name} not registered")

    @classmethod
    def already_listening(cls, name: str, port: int) -> WcsFail:
        """LISTEN a second time on the same port."""
        return cls(f"Robot with name {name} already listening at port {port}")

    @classmethod
    def not_listening(cls, name: str, port: int) -> WcsFail:
        """OPEN to a robot that is not (or no longer) listening on that port."""
        return cls(f"{name} not listening on port {port}")

    @classmethod
    def cannot_connect(cls, name: str) -> WcsFail:
        """OPEN of a link that does not hold (out of range, or to itself)."""
        return cls(f"Cannot connect to {name}")


FAIL_UNKNOWN_MESSAGE = WcsFail("Unknown Message")
"""A command word the ComServer does not know."""
FAIL_INCORRECT_MESSAGE = WcsFail("Incorrect Message")
"""A known command with the wrong words."""
FAIL_TOO_MANY_REGISTERED = WcsFail("Too many robots registered")
"""REGISTER past the server's limit of names."""
FAIL_TOO_MANY_LISTENING = WcsFail("Too many robots listening")
"""LISTEN past the server's limit of listening ports."""
FAIL_NO_CONNECTION = WcsFail("Could not establish connection")
"""OPEN: the server could not connect to a robot's listening port."""
FAIL_THIRD_PARTY = WcsFail("Server does not accept third party requests")
"""GETSS from an address that is neither robot's."""
FAIL_NO_SIGNAL = WcsFail("Could not calculate signal strength")
"""GETSS for a robot that is not in the simulation."""

WcsReply = WcsOk | WcsSignal | WcsFail


def format_wcs_reply(reply: WcsReply) -> str:
    """The reply as the ComServer sends it: ``OK;``, ``OK:-60.57;``, ``Fail: <reason>;``."""
    if isinstance(reply, WcsOk):
        return "OK;"
    if isinstance(reply, WcsSignal):
        return f"OK:{fmt_wcs_dbm(reply.dbm)};"
    if isinstance(reply, WcsFail):
        return f"Fail: {reply.reason};"
    raise TypeError(f"not a ComServer reply: {reply!r}")


def parse_wcs_reply(text: str) -> WcsReply:
    """One reply (with or without its ``;``) as a robot reads it.  Anything else raises
    :class:`~usarsim.errors.ProtocolError`."""
    t = text.strip().removesuffix(";")
    if t == "OK":
        return WcsOk()
    if t.startswith("OK:"):
        return WcsSignal(parse_float(t[3:]))
    if t.startswith("Fail:"):
        return WcsFail(t[5:].strip())
    raise ProtocolError(f"expected a ComServer reply OK;, OK:<dBm>; or Fail: <reason>;, got {shorten(text)}")


# --------------------------------------------------------------------------- relayed links


@dataclass(frozen=True, slots=True)
class SendClose:
    """``CLOSE;`` on a relayed link: the robot ends the link."""


class SendProblem(str):
    """A frame of a relayed link that was dropped: the text says why; ``kind`` is one of
    ``unknown`` (not SEND or CLOSE), ``no-length``, ``too-long``, ``wrong-length`` (the
    bytes are not followed by ``;``) and ``close`` (CLOSE not followed by ``;``), what a
    server logs once each."""

    kind: str

    def __new__(cls, kind: str, text: str) -> Self:
        self = super().__new__(cls, text)
        self.kind = kind
        return self


SendEvent = bytes | SendClose | SendProblem

CLOSE_FRAME = b"CLOSE;"
"""What a robot sends to end a relayed link."""

_BLANKS = b" \t\r\n"


def format_send(payload: bytes) -> bytes:
    """The frame that relays ``payload`` (any bytes, ``;`` and line breaks included)."""
    return b"SEND %d %s;" % (len(payload), payload)


def _skip_blanks(buf: bytearray) -> None:
    """Drop the blanks and line breaks at the start of ``buf``."""
    i = 0
    while i < len(buf) and buf[i] in _BLANKS:
        i += 1
    del buf[:i]


class SendParser:
    """The framing of a relayed ComServer link (manual 3.2.4.3): ``SEND <n> <n bytes>;``
    (binary-safe) and ``CLOSE;``, both words case-sensitive; blanks and line breaks between
    frames are skipped.

    ``feed`` returns the events the bytes complete, in order: a message (``bytes``), ``CLOSE``
    (a :class:`SendClose`), or a :class:`SendProblem` for a frame that was dropped, after
    which the parser skips to the next ``;``.  A SEND is delivered only once its ``n`` bytes
    and its ``;`` have arrived: one whose length does not end at a ``;`` is dropped whole,
    never delivered in part, and one cut off by the end of the connection shows as
    ``partial``.  The result does not depend on how the bytes are split between calls, and
    ``feed`` never raises.
    """

    CLOSE: ClassVar[SendClose] = SendClose()

    def __init__(self, max_bytes: int = MAX_SEND_BYTES):
        self.max_bytes = max_bytes
        self._buf = bytearray()
        self._state = "head"
        self._digits = b""
        self._need = 0
        self._body = bytearray()

    def feed(self, data: bytes) -> list[SendEvent]:
        """The events completed by ``data``: payload bytes, CLOSE, or the problem of a dropped frame."""
        buf = self._buf
        buf += data
        out: list[SendEvent] = []
        while True:
            st = self._state
            if st == "head":
                _skip_blanks(buf)
                if not buf:
                    break
                head = bytes(buf[:5])
                if head == b"SEND ":
                    del buf[:5]
                    self._state, self._digits = "length", b""
                elif head == b"CLOSE":
                    del buf[:5]
                    self._state = "close"
                elif len(head) < 5 and (b"SEND ".startswith(head) or b"CLOSE".startswith(head)):
                    break
                else:
                    out.append(SendProblem("unknown", f"unknown message {head!r}..."))
                    self._state = "skip"
            elif st == "length":
                i = 0
                while i < len(buf) and 48 <= buf[i] <= 57 and len(self._digits) + i < 10:
                    i += 1
                self._digits += bytes(buf[:i])
                del buf[:i]
                if not buf:
                    break
                if buf[0] == 32 and self._digits:
                    del buf[:1]
                    n = int(self._digits)
                    if n > self.max_bytes:
                        out.append(SendProblem("too-long", f"SEND of {n} bytes, more than {self.max_bytes}"))
                        self._state = "skip"
                    else:
                        self._need, self._body = n, bytearray()
                        self._state = "body"
                else:
                    out.append(SendProblem("no-length", "SEND without a length"))
                    self._state = "skip"
            elif st == "body":
                take = min(self._need, len(buf))
                self._body += buf[:take]
                del buf[:take]
                self._need -= take
                if self._need:
                    break
                self._state = "end"
            elif st == "end":
                if not buf:
                    break
                if buf[0] == 59:  # ;
                    del buf[:1]
                    out.append(bytes(self._body))
                    self._state = "head"
                else:
                    out.append(
                        SendProblem(
                            "wrong-length", f"SEND of {len(self._body)} bytes not followed by ';' (a wrong length)"
                        )
                    )
                    self._state = "skip"
                self._body = bytearray()
            elif st == "close":
                _skip_blanks(buf)
                if not buf:
                    break
                if buf[0] == 59:
                    del buf[:1]
                    out.append(self.CLOSE)
                    self._state = "head"
                else:
                    out.append(SendProblem("close", "CLOSE not followed by ';'"))
                    self._state = "skip"
            else:  # skip to the next ';'
                j = buf.find(b";")
                if j < 0:
                    buf.clear()
                    break
                del buf[: j + 1]
                self._state = "head"
        return out

    @property
    def partial(self) -> bool:
        """A frame was begun and not finished."""
        return self._state != "head" or bool(self._buf)
