"""The ground-truth service (TCP 3989 by default, ``--truth-port``; protocol.md 12.4, the
UDK's USARTruth): scoring and test tools ask where things are.

asyncio glue only: lines (protocol.framing) -> request (protocol.truth) -> a snapshot
taken on the simulation thread -> one line per object, then ``{End}``.  The connection
stays open for further requests.  An unparseable line is logged once per connection and
answered with a bare ``{End}``, as an empty line is.

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
from usarsim.protocol.truth import (
    END,
    MapHeader,
    MapRequest,
    TruthObject,
    format_map_answer,
    format_truth_object,
    parse_truth_request,
)
from usarsim.server.connection import ServerConnection
from usarsim.server.listener import TcpListener
from usarsim.sim.api import Facade, when_done

log = logging.getLogger("usarsim.server")

MAX_WAITING = 64  # requests of one connection waiting; beyond them its socket is not read


class TruthConnection(ServerConnection):
    """A ground-truth client's connection (protocol.md 12.4): its request lines are answered in order, one at a time,
    from a snapshot the simulation thread takes, each answer ending with ``{End}``."""

    what = "truth"
    limit_option = "--max-viewers"
    max_waiting = MAX_WAITING
    waiting_level = logging.INFO

    def __init__(self, server: TruthServer):
        super().__init__(server)
        self.buffer = LineBuffer(max_line_bytes=4096, empty_lines=True)  # an empty line is answered too
        self.waiting: collections.deque = collections.deque()  # parsed requests (None: unparseable)
        self._busy = False  # a request is being answered on the simulation thread
        self._answer_threadsafe = server.threadsafe(self._answer)

    def closed(self) -> None:
        self.waiting.clear()

    def writing_resumed(self) -> None:
        self._next()

    def data_received(self, data: bytes) -> None:
        for line in self.buffer.feed(data):
            if not line.strip():
                self.waiting.append(None)  # an empty request: answered with a bare {End}, in its turn
                continue
            try:
                self.waiting.append(parse_truth_request(line))
            except ProtocolError as exc:
                self.log_once("malformed", "%s", exc)
                self.waiting.append(None)  # answered with a bare {End}, in its turn
        self.queued(len(self.waiting))
        self._next()

    def _next(self) -> None:
        """Ask the next waiting request, unless one is being answered or the client is not
        reading its answers."""
        while not self._busy and self.writable and self.waiting and self.transport is not None:
            request = self.waiting.popleft()
            self.taken(len(self.waiting))
            if request is None:
                self.write_text(END)
                continue
            self._busy = True
            if request.map is not None:
                self.server.ground_truth_map(request.map).add_done_callback(self._answer_map)
                continue
            when_done(self.server.facade.truth(request.class_name, request.name), self._answer_threadsafe)

    def _answer_map(self, future: asyncio.Future) -> None:
        self._busy = False
        if future.cancelled():
            return
        exc = future.exception()
        if exc is not None:
            log.error("%s: no ground-truth map: %s", self.label, exc)
            self.write_text(END)
        else:
            self.write_text(future.result())
        self._next()

    def _answer(self, rows, error) -> None:
        self._busy = False
        if error is not None:
            log.error("%s: %s", self.label, error)
        self.write_text("".join(format_truth_object(TruthObject(*row)) for row in rows or ()) + END)
        self._next()


class TruthServer(TcpListener):
    """The ground-truth service's listener (protocol.md 12.4, TCP 3989 by default): it admits clients up to its limit
    and asks the simulation facade for the objects a request names."""

    def __init__(self, facade: Facade, *, host: str = "127.0.0.1", port: int = 3989, max_connections: int = 16):
        super().__init__(host, port)
        self.facade = facade
        self.max_connections = max_connections
        self._maps: dict[tuple[float, float], asyncio.Future] = {}

    def make_protocol(self) -> TruthConnection:
        return TruthConnection(self)

    def ground_truth_map(self, request: MapRequest) -> asyncio.Future:
        """The answer to a ``{Map}`` request (a text), made once per resolution and height on a
        worker thread (usarsim.maps.truth: the world as served, its variant applied)."""
        key = (request.resolution, request.height)
        future = self._maps.get(key)
        if future is None or (future.done() and future.exception() is not None):
            future = asyncio.get_running_loop().run_in_executor(None, map_answer, self.facade.world, request)
            self._maps[key] = future
        return future


# the most cells a ground-truth map may have (a 200 x 200 m world at 5 cm)
MAX_MAP_CELLS = 16_000_000


def map_answer(world, request: MapRequest) -> str:
    import math
    import zlib

    from usarsim.maps.truth import ground_truth_map

    (sx, sy) = world.floor.size
    cells = math.ceil(sx / request.resolution) * math.ceil(sy / request.resolution)
    if cells > MAX_MAP_CELLS:
        raise ValueError(f"{cells} cells at {request.resolution:g} m: more than {MAX_MAP_CELLS}; ask a coarser one")
    truth = ground_truth_map(world, resolution=request.resolution, height=request.height, variant=world.variant)
    g = truth.grid
    header = MapHeader(
        world=world.name,
        variant=-1 if world.variant is None else int(world.variant),
        resolution=g.resolution,
        origin=g.origin,
        width=g.shape[1],
        height=g.shape[0],
        sensing_height=request.height,
    )
    return format_map_answer(header, zlib.compress(g.data.astype("int8").tobytes(), 6))
