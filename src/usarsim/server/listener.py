"""One asyncio TCP listener and the connections it accepted (the control port, the
ground-truth service, the image server, the wireless servers): open it, and on stop close
it and every connection.  The connections themselves share
:class:`~usarsim.server.connection.ServerConnection`."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from typing import Any, Protocol


class Listening(Protocol):
    """What every listener of a server offers: its port (the one taken, once started), and an
    asynchronous start and stop."""

    @property
    def port(self) -> int: ...
    async def start(self) -> object: ...  # what it returns (a port) is not used
    async def stop(self) -> None: ...


@dataclass(frozen=True)
class Service:
    """One listener of a ``usarsim serve``, as the server starts, stops, logs and names it:
    ``name`` (``control``, ``truth``, ...), the ``server``, what it is called in an error
    (``the ground-truth port``) and the option that sets its port (``--truth-port``)."""

    name: str
    server: Listening
    what: str
    option: str

    def describe(self) -> str:
        """``the ground-truth port 3989 (--truth-port)``: how an error names it."""
        return f"{self.what} {self.server.port} ({self.option})"


def call_on_loop(loop: asyncio.AbstractEventLoop | None, fn, *args) -> None:
    """Have ``loop`` call ``fn(*args)``, from any thread; dropped once the loop is closed.
    On the loop's own thread (a lock-step STEP run there) it is queued without waking the
    loop, behind what other threads queued before."""
    if loop is not None and not loop.is_closed():
        if asyncio._get_running_loop() is loop:
            loop.call_soon(fn, *args)
            return
        try:
            loop.call_soon_threadsafe(fn, *args)
        except RuntimeError:  # the loop closed meanwhile
            pass


class TcpListener:
    """Subclasses give ``make_protocol()``; their connections add themselves to
    ``connections`` (a set, or a dict whose values they are) and have a ``transport``."""

    # A recording's tap (usarsim.server.recording): set before start() to note every
    # connection's traffic under ``tap_name``; ``tap_binary``: outputs noted by size only.
    tap: Any = None  # a Recorder; Any: the recording package sits above the servers
    tap_name = "?"
    tap_binary = False

    def __init__(self, host: str, port: int):
        self.host = host
        self.port = port
        self.connections: set[Any] | dict[int, Any] = set()
        self.loop: asyncio.AbstractEventLoop | None = None
        self._server: asyncio.base_events.Server | None = None

    def make_protocol(self) -> asyncio.Protocol:
        raise NotImplementedError

    def threadsafe(self, fn):
        """``fn`` to be called from another thread (the simulation's, the renderer's): it runs
        on the event loop; dropped once the loop is closed."""

        def call(*args) -> None:
            call_on_loop(self.loop, fn, *args)

        return call

    async def start(self) -> int:
        """Listen; returns the port (the one picked when asked for port 0)."""
        self.loop = asyncio.get_running_loop()
        factory = self.make_protocol
        if self.tap is not None:
            from usarsim.server.recording.tap import tapped

            factory = tapped(factory, self.tap, self.tap_name, self.tap_binary)
        self._server = await self.loop.create_server(factory, self.host, self.port, reuse_address=True)
        self.port = self._server.sockets[0].getsockname()[1]
        return self.port

    async def stop(self) -> None:
        server, self._server = self._server, None
        if server is not None:
            server.close()
        conns = self.connections
        for conn in list(conns.values() if isinstance(conns, dict) else conns):
            if conn.transport is not None:
                conn.transport.close()
        if server is not None:
            await server.wait_closed()
