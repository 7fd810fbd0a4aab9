"""The ground-truth service (TCP 3989 by default, ``--truth-port``; protocol.md 12.4, the
UDK's USARTruth): scoring and test tools ask where things are.

asyncio glue only: lines (protocol.framing) -> request (protocol.truth) -> a snapshot
taken on the simulation thread -> one line per object, then ``{End}``.  The connection
stays open for further requests.  An unparseable line is logged once per connection and
answered with a bare ``{End}``.

A connection's requests are answered one after another, one at a time on the simulation
thread, so that a flood of requests cannot stall the world: beyond MAX_WAITING waiting
requests its socket is not read until they are answered, and while its unread answers
exceed asyncio's high-water mark no further request is asked.
"""

from __future__ import annotations

import asyncio
import collections
import logging

from usarsim.errors import ProtocolError
from usarsim.protocol.framing import LineBuffer
from usarsim.protocol.truth import END, TruthObject, format_truth_object, parse_truth_request
from usarsim.server.listener import ReadGate, TcpListener
from usarsim.sim.facade import SimFacade

log = logging.getLogger("usarsim.server")

MAX_WAITING = 64  # requests of one connection waiting; beyond them its socket is not read


class TruthConnection(asyncio.Protocol):
    def __init__(self, server: "TruthServer"):
        self.server = server
        self.transport: asyncio.Transport | None = None
        self.buffer = LineBuffer(max_line_bytes=4096)
        self.peer = "?"
        self._warned = False
        self.waiting: collections.deque = collections.deque()  # parsed requests (None: unparseable)
        self._busy = False  # a request is being answered on the simulation thread
        self._writable = True  # False while the client does not read its answers
        self._gate = ReadGate(MAX_WAITING)

    def connection_made(self, transport) -> None:
        self.transport = transport
        peer = transport.get_extra_info("peername")
        self.peer = f"{peer[0]}:{peer[1]}" if peer else "?"
        if len(self.server.connections) >= self.server.max_connections:
            log.warning("truth %s: refused: %d connections already", self.peer, len(self.server.connections))
            transport.close()
            return
        self.server.connections.add(self)
        log.info("truth %s: connected", self.peer)

    def connection_lost(self, exc) -> None:
        self.server.connections.discard(self)
        self.waiting.clear()
        self.transport = None

    def data_received(self, data: bytes) -> None:
        for line in self.buffer.feed(data):
            if not line.strip():
                continue
            try:
                self.waiting.append(parse_truth_request(line))
            except ProtocolError as exc:
                if not self._warned:
                    log.warning("truth %s: %s", self.peer, exc)
                    self._warned = True
                self.waiting.append(None)  # answered with a bare {End}, in its turn
        if self._gate.queued(self.transport, len(self.waiting)):
            log.info("truth %s: more than %d requests waiting; reading paused until they are answered",
                     self.peer, MAX_WAITING)
        self._next()

    def pause_writing(self) -> None:
        self._writable = False

    def resume_writing(self) -> None:
        self._writable = True
        self._next()

    def _next(self) -> None:
        """Ask the next waiting request, unless one is being answered or the client is not
        reading its answers."""
        while not self._busy and self._writable and self.waiting and self.transport is not None:
            request = self.waiting.popleft()
            self._gate.taken(self.transport, len(self.waiting))
            if request is None:
                self._write(END)
                continue
            self._busy = True
            self.server.facade.truth(request.class_name, request.name, on_done=self._answer_threadsafe)

    def _answer_threadsafe(self, rows, error) -> None:
        loop = self.server.loop
        if loop is not None and not loop.is_closed():
            loop.call_soon_threadsafe(self._answer, rows or [], error)

    def _answer(self, rows, error) -> None:
        self._busy = False
        if error is not None:
            log.error("truth %s: %s", self.peer, error)
        text = "".join(format_truth_object(TruthObject(*row)) for row in rows) + END
        self._write(text)
        self._next()

    def _write(self, text: str) -> None:
        if self.transport is not None and not self.transport.is_closing():
            self.transport.write(text.encode("ascii", "replace"))


class TruthServer(TcpListener):
    def __init__(self, facade: SimFacade, *, host: str = "127.0.0.1", port: int = 3989, max_connections: int = 16):
        super().__init__(host, port)
        self.facade = facade
        self.max_connections = max_connections

    def make_protocol(self) -> TruthConnection:
        return TruthConnection(self)
