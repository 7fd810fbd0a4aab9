"""A robot's radio through the simulator's ComServer (docs/wireless.md,
protocol.md 12.1, manual 3.2.4): the messages get through only while the simulated link
between the two robots holds.

Each :class:`Radio` registers its robot's name with the ComServer and listens on a port of
its own; to link two robots, the one says ``LISTEN`` and the other ``OPEN`` (each OPEN
uses up a LISTEN), and the ComServer connects to both robots' ports and relays
``SEND <n> <bytes>;`` frames between them: the other robot receives the bytes of each SEND
as a stream, without the framing, so every message here starts with its length (4 bytes,
big-endian).  :func:`link` opens a link between two radios of this process; a link the
ComServer closes (the signal fell below the cutoff) is dropped and can be opened again
later.  The protocol's words are :mod:`usarsim.protocol.wireless`'s.
"""

from __future__ import annotations

import logging
import socket
import struct
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

from usarsim.errors import ProtocolError
from usarsim.protocol.wireless import (
    CommandSplitter,
    Neighbor,
    WcsFail,
    WcsGetNeighbors,
    WcsGetSS,
    WcsListen,
    WcsNeighbors,
    WcsOk,
    WcsOpen,
    WcsRegister,
    WcsReply,
    WcsSignal,
    format_send,
    format_wcs_request,
    parse_wcs_neighbors,
    parse_wcs_reply,
)

log = logging.getLogger("usarsim.client.radio")
_LENGTH = struct.Struct(">I")  # a message's length, before it


class RadioError(RuntimeError):
    """The ComServer refused or did not answer."""


@dataclass
class Link:
    """One end of a relayed link: its socket and what is half received on it."""

    peer: str
    sock: socket.socket
    buffer: bytearray = field(default_factory=bytearray)


class Radio:
    """The radio of robot ``name``, through the ComServer at ``host``:``port``."""

    def __init__(self, host: str, port: int, name: str, *, timeout: float = 10.0, address: str = "127.0.0.1"):
        self.name, self.timeout = name, timeout
        try:
            self._ctl = socket.create_connection((host, port), timeout=timeout)
        except OSError as exc:
            raise RadioError(
                f"cannot reach the ComServer at {host}:{port} ({exc}); is the server's wireless on?"
            ) from exc
        self._splitter = CommandSplitter()
        self._replies: list[str] = []
        self._server = socket.create_server((address, 0))
        self._server.settimeout(timeout)
        self.port = self._server.getsockname()[1]
        self.links: dict[str, Link] = {}
        self.received = 0  # messages received
        self.sent = 0  # messages sent (one per link they went out on)
        reply = self.ask(WcsRegister(name, address))
        if not isinstance(reply, WcsOk):
            self.close()
            raise RadioError(f"REGISTER {name}: {reply}")

    def ask(self, request: WcsRegister | WcsListen | WcsOpen | WcsGetSS | WcsGetNeighbors) -> WcsReply:
        """Send one command, return its reply."""
        self._ctl.sendall(format_wcs_request(request).encode("ascii"))
        return self._reply(request)

    def _reply(self, request: WcsRegister | WcsListen | WcsOpen | WcsGetSS | WcsGetNeighbors) -> WcsReply:
        """The next reply, to ``request``."""
        deadline = time.monotonic() + self.timeout
        while not self._replies:
            left = deadline - time.monotonic()
            if left <= 0:
                raise RadioError(f"no reply from the ComServer to {request.type} within {self.timeout:g} s")
            self._ctl.settimeout(left)
            try:
                data = self._ctl.recv(4096)
            except TimeoutError:
                continue
            if not data:
                raise RadioError("the ComServer closed the connection")
            self._replies.extend(self._splitter.feed(data))
        text = self._replies.pop(0)
        try:
            if isinstance(request, WcsGetNeighbors):
                return parse_wcs_neighbors(text)
            return parse_wcs_reply(text)
        except ProtocolError as exc:
            raise RadioError(f"unexpected ComServer reply to {request.type}: {text!r}") from exc

    def accept(self, peer: str) -> None:
        """Take the connection the ComServer makes for a new link with ``peer``."""
        try:
            sock, _ = self._server.accept()
        except TimeoutError as exc:
            raise RadioError(f"{self.name}: the ComServer did not connect for the link with {peer}") from exc
        sock.setblocking(False)
        old = self.links.pop(peer, None)
        if old is not None:
            old.sock.close()
        self.links[peer] = Link(peer, sock)

    def signal(self, peer: str) -> float | None:
        """The signal strength (dBm) from this robot to ``peer`` under the simulator's radio
        model (GETSS), or None when the ComServer cannot give one."""
        reply = self.ask(WcsGetSS(self.name, peer))
        return reply.dbm if isinstance(reply, WcsSignal) else None

    def signals(self, peers: Sequence[str]) -> list[float | None]:
        """:meth:`signal` to each of ``peers``, asked in one write."""
        self.ask_signals(peers)
        return self.read_signals(peers)

    def ask_signals(self, peers: Sequence[str]) -> None:
        """Ask the signal to each of ``peers`` in one write; :meth:`read_signals` reads them
        (the radios of a team ask, then read, in two rounds: one round trip in all)."""
        if peers:
            self._ctl.sendall("".join(format_wcs_request(WcsGetSS(self.name, p)) for p in peers).encode("ascii"))

    def read_signals(self, peers: Sequence[str]) -> list[float | None]:
        """The answers to :meth:`ask_signals` of ``peers``: dBm, or None."""
        return [r.dbm if isinstance(r := self._reply(WcsGetSS(self.name, p)), WcsSignal) else None for p in peers]

    def neighbours(self) -> list[Neighbor]:
        """Every robot whose link with this one holds now, with its signal strength (dBm) and
        the link's quality (0 to 1), by name (GETNEIGHBORS, an extension of the ComServer)."""
        reply = self.ask(WcsGetNeighbors(self.name))
        if not isinstance(reply, WcsNeighbors):
            raise RadioError(f"GETNEIGHBORS {self.name}: {getattr(reply, 'reason', reply)}")
        return list(reply.neighbors)

    def send(self, peer: str, payload: bytes) -> bool:
        """Send ``payload`` on the open link with ``peer``; False when there is none (never
        opened, or closed by the ComServer when the signal fell below the cutoff)."""
        link = self.links.get(peer)
        return link is not None and self._send_on([link], payload) == 1

    def broadcast(self, payload: bytes) -> int:
        """Send ``payload`` on every open link; returns on how many it went."""
        return self._send_on(list(self.links.values()), payload)

    def _send_on(self, links: list[Link], payload: bytes) -> int:
        frame = format_send(_LENGTH.pack(len(payload)) + payload)
        n = 0
        for link in links:
            try:
                link.sock.setblocking(True)
                link.sock.settimeout(self.timeout)
                link.sock.sendall(frame)
                link.sock.setblocking(False)
                n += 1
            except OSError:
                self._drop(link)
        self.sent += n
        return n

    def poll(self) -> list[tuple[str, bytes]]:
        """The messages received since the last poll, as (peer, payload); links the
        ComServer closed are dropped."""
        out: list[tuple[str, bytes]] = []
        for link in list(self.links.values()):
            while True:
                try:
                    data = link.sock.recv(1 << 16)
                except BlockingIOError:
                    break
                except OSError:
                    data = b""
                if not data:
                    self._drop(link)
                    break
                buf = link.buffer
                buf += data
                while len(buf) >= _LENGTH.size:
                    (n,) = _LENGTH.unpack_from(buf)
                    if len(buf) < _LENGTH.size + n:
                        break
                    out.append((link.peer, bytes(buf[_LENGTH.size : _LENGTH.size + n])))
                    del buf[: _LENGTH.size + n]
        self.received += len(out)
        return out

    def forget(self, peer: str) -> None:
        """Close the link with ``peer``, if there is one."""
        link = self.links.get(peer)
        if link is not None:
            self._drop(link)

    def _drop(self, link: Link) -> None:
        if self.links.get(link.peer) is link:
            del self.links[link.peer]
            log.info("%s: the link with %s closed", self.name, link.peer)
        link.sock.close()

    def close(self) -> None:
        for link in list(self.links.values()):
            link.sock.close()
        self.links.clear()
        self._server.close()
        self._ctl.close()


def link(a: Radio, b: Radio) -> bool:
    """Open a link between two radios of this process (b listens, a opens); False when the
    ComServer refuses (no signal between them, ...)."""
    listen = b.ask(WcsListen(b.name, b.port))
    # a LISTEN left from an OPEN that failed is still there: fine
    if not isinstance(listen, WcsOk) and "already listening" not in getattr(listen, "reason", ""):
        return False
    reply = a.ask(WcsOpen(a.name, a.port, b.name, b.port))
    if isinstance(reply, WcsFail):
        log.info("no link %s - %s: %s", a.name, b.name, reply.reason)
        return False
    a.accept(b.name)
    b.accept(a.name)
    return True
