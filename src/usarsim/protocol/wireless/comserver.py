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
* the framing of a relayed link, ``SEND <n> <n bytes>;`` (binary-safe) and ``CLOSE;``, is
  :mod:`.sendframes`'s.
"""

from __future__ import annotations

from dataclasses import astuple, dataclass
from typing import ClassVar

from usarsim.errors import ProtocolError

from ..grammar import parse_float
from ..numbers import f2
from .common import check_port, check_word, parse_port, shorten

__all__ = [
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
    "format_wcs_reply",
    "format_wcs_request",
    "parse_wcs_neighbors",
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
class WcsGetNeighbors:
    """``GETNEIGHBORS name;`` (an extension): every robot whose link with ``name`` holds now,
    with its signal strength and link quality."""

    type: ClassVar[str] = "GETNEIGHBORS"
    name: str


@dataclass(frozen=True, slots=True)
class WcsUnknown:
    """A command whose first word the ComServer does not know (``text`` as sent, trimmed);
    answered ``Fail: Unknown Message;``."""

    text: str


WcsRequest = WcsRegister | WcsListen | WcsOpen | WcsGetSS | WcsGetNeighbors | WcsUnknown

# command word -> (class, what its words are, which of them are ports)
_COMMANDS: dict[str, tuple[type, str, tuple[bool, ...]]] = {
    "REGISTER": (WcsRegister, "robotName ip", (False, False)),
    "LISTEN": (WcsListen, "robotName port", (False, True)),
    "OPEN": (WcsOpen, "srcName srcPort dstName dstPort", (False, True, False, True)),
    "GETSS": (WcsGetSS, "name1 name2", (False, False)),
    "GETNEIGHBORS": (WcsGetNeighbors, "robotName", (False,)),
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
        raise ProtocolError("an empty ComServer command: expected REGISTER, LISTEN, OPEN, GETSS or GETNEIGHBORS")
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
class Neighbor:
    """A robot in reach: its name, the signal strength (dBm) and the link's quality (the share
    of 1,024-byte messages its signal alone lets through, 0 to 1)."""

    name: str
    dbm: float
    quality: float


@dataclass(frozen=True, slots=True)
class WcsNeighbors:
    """``OK:<name> <dBm> <quality> ...;``: the answer to GETNEIGHBORS, a triple for each robot
    in reach (dBm with 2 decimals, quality with 3), by name; ``OK:;`` when none is."""

    neighbors: tuple[Neighbor, ...]


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

WcsReply = WcsOk | WcsSignal | WcsNeighbors | WcsFail


def format_wcs_reply(reply: WcsReply) -> str:
    """The reply as the ComServer sends it: ``OK;``, ``OK:-60.57;``, ``Fail: <reason>;``."""
    if isinstance(reply, WcsOk):
        return "OK;"
    if isinstance(reply, WcsSignal):
        return f"OK:{fmt_wcs_dbm(reply.dbm)};"
    if isinstance(reply, WcsNeighbors):
        return "OK:" + " ".join(f"{n.name} {fmt_wcs_dbm(n.dbm)} {n.quality:.3f}" for n in reply.neighbors) + ";"
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


def parse_wcs_neighbors(text: str) -> WcsNeighbors | WcsFail:
    """The reply to GETNEIGHBORS (with or without its ``;``): ``OK:<name> <dBm> <quality> ...;``
    (``OK:;``: none) or a ``Fail``.  Anything else raises :class:`~usarsim.errors.ProtocolError`."""
    t = text.strip().removesuffix(";")
    if t.startswith("Fail:"):
        return WcsFail(t[5:].strip())
    words = t[3:].split() if t.startswith("OK:") else None
    if words is None or len(words) % 3:
        raise ProtocolError(f"expected OK:<name> <dBm> <quality> ...; or Fail: <reason>;, got {shorten(text)}")
    return WcsNeighbors(
        tuple(Neighbor(words[i], parse_float(words[i + 1]), parse_float(words[i + 2])) for i in range(0, len(words), 3))
    )
