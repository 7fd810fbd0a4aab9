"""One asyncio TCP listener and the connections it accepted (the ground-truth service, the
image server, the wireless servers): open it, and on stop close it and every connection."""

from __future__ import annotations

import asyncio


class TcpListener:
    """Subclasses give ``make_protocol()``; their connections add themselves to
    ``connections`` and have a ``transport``."""

    def __init__(self, host: str, port: int):
        self.host = host
        self.port = port
        self.connections: set = set()
        self.loop: asyncio.AbstractEventLoop | None = None
        self._server: asyncio.base_events.Server | None = None

    def make_protocol(self) -> asyncio.Protocol:
        raise NotImplementedError

    async def start(self) -> int:
        """Listen; returns the port (the one picked when asked for port 0)."""
        self.loop = asyncio.get_running_loop()
        self._server = await self.loop.create_server(self.make_protocol, self.host, self.port, reuse_address=True)
        self.port = self._server.sockets[0].getsockname()[1]
        return self.port

    async def stop(self) -> None:
        server, self._server = self._server, None
        if server is not None:
            server.close()
        for conn in list(self.connections):
            if conn.transport is not None:
                conn.transport.close()
        if server is not None:
            await server.wait_closed()


class ReadGate:
    """Backpressure on one connection's requests: its socket is not read while ``limit``
    requests wait, and is read again once fewer than half of them do.  TCP then slows the
    sender down; nothing is dropped."""

    def __init__(self, limit: int):
        self.limit = limit
        self.reading = True

    def queued(self, transport, waiting: int) -> bool:
        """After requests were queued: True when this closed the gate (the caller logs it)."""
        if self.reading and waiting >= self.limit and transport is not None:
            self.reading = False
            transport.pause_reading()
            return True
        return False

    def taken(self, transport, waiting: int) -> None:
        """After a request was taken from the queue."""
        if not self.reading and waiting < self.limit // 2 and transport is not None:
            self.reading = True
            transport.resume_reading()
