"""What every connection of the simulator's ports shares (design.md 5: one connection base
holds flow control, log-once and limits for every port).

* :func:`transport_peer` and :func:`peer_address`: a peer as ``"ip:port"``, with its ip and
  port kept apart (the image server looks camera bindings up by both);
* :func:`refuse`: the logged refusal of a connection past its port's limit, naming the
  option that sets the limit (``--max-connections``, ``--max-viewers``, ...);
* :class:`LogOnce`: the first problem of each kind logged once per connection, within a
  bound on the kinds (``MAX_LOGGED_KINDS``, then one note);
* :func:`write_open`: a write that is dropped when the transport is closing;
* :class:`ReadGate`: read-side backpressure, the socket left unread while too much waits;
* :class:`ServerConnection`: a connection accepted on a port, holding all of these and the
  write-side flow control (``pause_writing``/``resume_writing``);
* :class:`RelayEnd`: one socket of a relay between two, whose unread output stops the
  other one being read.

What differs stays in each server: the control connection's latest-wins periodic lines and
its reply cap, the ground-truth and wireless request queues, the image server's binary
protocol.
"""

from __future__ import annotations

import asyncio
import logging

log = logging.getLogger("usarsim.server")

MAX_LOGGED_KINDS = 32
"""Kinds of problem logged once per connection at most; further kinds go to DEBUG."""


def peer_address(ip: str, port: int) -> str:
    """An address as the logs and camera bindings write it: ``ip:port``."""
    return f"{ip}:{port}"


def transport_peer(transport) -> tuple[str, int, str]:
    """(ip, port, ``"ip:port"``) of the other end of ``transport``; ("", 0, "?") if unknown."""
    peer = transport.get_extra_info("peername")
    if isinstance(peer, tuple) and len(peer) >= 2:
        return str(peer[0]), int(peer[1]), peer_address(peer[0], peer[1])
    return "", 0, str(peer) if peer else "?"


def refuse(
    logger: logging.Logger, label: str, count: int, limit: int, option: str, *, what: str = "", state: str = "already"
) -> None:
    """Log that a connection (or a request, ``what``) of ``label`` is refused: ``count``
    connections are open, ``limit`` is the most, set by the command-line ``option``."""
    logger.warning(
        "%s: refused%s: %d connections %s (limit %s %d)", label, f" {what}" if what else "", count, state, option, limit
    )


def write_open(transport, data: bytes) -> bool:
    """Write ``data`` unless the transport (or stream writer) is gone or closing; whether it
    was written."""
    if transport is None or transport.is_closing():
        return False
    transport.write(data)
    return True


class LogOnce:
    """Log the first problem of each kind at its level, and its repetitions at DEBUG.  Past
    ``MAX_LOGGED_KINDS`` kinds (a client sending ever new garbage) one note says so and
    every new kind goes to DEBUG too, so that the log and the set of kinds stay bounded.

    Lines read ``<label>: <message><suffix>``; the label is the peer, after the name of the
    port where there are several (``"wss 127.0.0.1:4321"``)."""

    __slots__ = ("logger", "label", "suffix", "_kinds", "_full")

    def __init__(self, logger: logging.Logger, label: str = "?", suffix: str = ""):
        self.logger = logger
        self.label = label
        self.suffix = suffix
        self._kinds: set[str] = set()
        self._full = False

    def __call__(self, kind: str, msg: str, *args, level: int = logging.WARNING) -> None:
        if kind not in self._kinds:
            if len(self._kinds) < MAX_LOGGED_KINDS:
                self._kinds.add(kind)
                self.logger.log(level, "%s: " + msg + self.suffix, self.label, *args)
                return
            if not self._full:
                self._full = True
                self.logger.warning(
                    "%s: more than %d kinds of problem on this connection; further ones are logged at debug level",
                    self.label,
                    MAX_LOGGED_KINDS,
                )
        self.logger.debug("%s: " + msg, self.label, *args)


class ReadGate:
    """Read-side backpressure on one connection: its socket is not read while the gate is
    closed, and TCP then slows the sender down; nothing is dropped.

    With a ``limit`` on waiting requests: closed once ``limit`` wait, opened again once
    fewer than half of them do (:meth:`queued`, :meth:`taken`)."""

    __slots__ = ("limit", "reading")

    def __init__(self, limit: int = 0):
        self.limit = limit
        self.reading = True

    def close(self, transport) -> bool:
        """Stop reading; True when this closed the gate (the caller may log it)."""
        if self.reading and transport is not None:
            self.reading = False
            transport.pause_reading()
            return True
        return False

    def open(self, transport) -> None:
        """Read again."""
        if not self.reading and transport is not None and not transport.is_closing():
            self.reading = True
            transport.resume_reading()

    def queued(self, transport, waiting: int) -> bool:
        """After requests were queued: True when this closed the gate (the caller logs it)."""
        return waiting >= self.limit and self.close(transport)

    def taken(self, transport, waiting: int) -> None:
        """After a request was taken from the queue."""
        if waiting < self.limit // 2:
            self.open(transport)


class ServerConnection(asyncio.Protocol):
    """A connection accepted on one of the simulator's ports.

    ``server`` has ``connections`` (those accepted, a set; the control server keeps a dict
    and overrides :meth:`register` and :meth:`release`) and ``max_connections``.  A subclass
    names its port in log lines (``what``; the control port's lines name the peer alone),
    the option that sets the limit (``limit_option``), its logger, and the most requests
    that may wait before its socket is not read (``max_waiting``, for :attr:`gate`).

    It gives: ``ip``, ``port`` and ``peer`` (``"ip:port"``) of the client; the limit, its
    refusal logged; "connected" and "disconnected" logged; ``log_once``; ``writable``
    (False while the client does not read what was sent: asyncio's high-water mark), with
    :meth:`writing_resumed` called when it reads again; :meth:`write`, dropped once the
    connection is closing; and ``gate``, a :class:`ReadGate`."""

    what = ""
    limit_option = "--max-connections"
    logger = log
    log_suffix = ""  # after each log-once line
    max_waiting = 0
    waiting_note = "more than %d requests waiting; reading paused until they are answered"
    waiting_level = logging.WARNING

    def __init__(self, server):
        self.server = server
        self.transport: asyncio.Transport | None = None
        self.ip, self.port, self.peer = "", 0, "?"
        self.accepted = False
        self.writable = True
        self.log_once = LogOnce(self.logger, suffix=self.log_suffix)
        self.gate = ReadGate(self.max_waiting)

    @property
    def label(self) -> str:
        """What names this connection in log lines: the port's name and the peer."""
        return f"{self.what} {self.peer}" if self.what else self.peer

    # asyncio.Protocol -----------------------------------------------------------------
    def connection_made(self, transport) -> None:
        self.transport = transport
        self.ip, self.port, self.peer = transport_peer(transport)
        self.log_once.label = self.label
        count, limit = len(self.server.connections), self.server.max_connections
        if count >= limit:
            refuse(self.logger, self.label, count, limit, self.limit_option)
            transport.close()
            return
        self.accepted = True
        self.register()
        self.opened()

    def connection_lost(self, exc) -> None:
        self.transport = None  # nothing more is written or read
        if not self.accepted:
            return  # refused: nothing to undo
        self.accepted = False
        self.release()
        self.logger.info("%s: disconnected%s", self.label, f" ({exc})" if exc else "")
        self.closed()

    def pause_writing(self) -> None:
        self.writable = False

    def resume_writing(self) -> None:
        self.writable = True
        self.writing_resumed()

    # hooks ------------------------------------------------------------------------------
    def register(self) -> None:
        """Add this connection to the server's (it is within the limit)."""
        self.server.connections.add(self)

    def release(self) -> None:
        """Remove this connection from the server's."""
        self.server.connections.discard(self)

    def opened(self) -> None:
        """The connection was accepted and registered."""
        self.logger.info("%s: connected", self.label)

    def closed(self) -> None:
        """The client went away (after it was accepted)."""

    def writing_resumed(self) -> None:
        """The client reads again what was sent."""

    # helpers ----------------------------------------------------------------------------
    def write(self, data: bytes) -> bool:
        """Send ``data``, unless the connection is closing; whether it was sent."""
        return write_open(self.transport, data)

    def write_text(self, text: str) -> bool:
        """Send formatted text (ASCII; anything else is replaced)."""
        return write_open(self.transport, text.encode("ascii", "replace"))

    def queued(self, waiting: int) -> None:
        """After requests were queued (``waiting`` now): past ``max_waiting`` the socket is
        not read until they are answered (``waiting_note``, logged once)."""
        if self.gate.queued(self.transport, waiting):
            self.log_once("waiting", self.waiting_note, self.max_waiting, level=self.waiting_level)

    def taken(self, waiting: int) -> None:
        """After a request was taken from the queue (``waiting`` left)."""
        self.gate.taken(self.transport, waiting)


class RelayEnd(asyncio.Protocol):
    """One socket of a relay between two (a ComServer link, a WSS relay pipe): while what
    is written to this one waits unread, the other one is not read."""

    transport: asyncio.Transport | None = None

    def other_end(self) -> RelayEnd | None:
        """The socket whose bytes are written to this one."""
        raise NotImplementedError

    def pause_writing(self) -> None:
        other = self.other_end()
        if other is not None and other.transport is not None:
            other.transport.pause_reading()

    def resume_writing(self) -> None:
        other = self.other_end()
        if other is not None and other.transport is not None and not other.transport.is_closing():
            other.transport.resume_reading()
