"""The recording's tap on a listener's connections: what each one received and sent, as it
crosses the socket, whatever the port's protocol.

A listener with a tap (:attr:`usarsim.server.listener.TcpListener.tap`) wraps each
connection's protocol in a :class:`TappedProtocol`: bytes received are noted before its
protocol sees them, and its protocol writes through a :class:`TappedTransport` that notes
what it sends.  Nothing else changes: flow control, limits and closing are the transport's
own."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Protocol, cast

from usarsim.server.connection import transport_peer


class Sink(Protocol):
    """Where a tap's notes go (:class:`usarsim.server.recording.Recorder`)."""

    def opened(self, port: str, peer: str) -> int: ...
    def note(self, conn: int, kind: str, data: bytes) -> None: ...
    def note_binary(self, conn: int, size: int) -> None: ...
    def closed(self, conn: int) -> None: ...


class TappedTransport:
    """A transport whose writes are noted; everything else is the transport's."""

    __slots__ = ("_t", "_sink", "_conn", "_binary")

    def __init__(self, transport: asyncio.Transport, sink: Sink, conn: int, binary: bool):
        self._t = transport
        self._sink = sink
        self._conn = conn
        self._binary = binary

    def write(self, data) -> None:
        if not self._t.is_closing():
            if self._binary:
                self._sink.note_binary(self._conn, len(data))
            else:
                self._sink.note(self._conn, "out", data if type(data) is bytes else bytes(data))
        self._t.write(data)

    def writelines(self, chunks) -> None:
        self.write(b"".join(chunks))

    # the transport's own, forwarded without a lookup (the servers call them per write)
    def is_closing(self) -> bool:
        return self._t.is_closing()

    def get_write_buffer_size(self) -> int:
        return self._t.get_write_buffer_size()

    def get_extra_info(self, name: str, default=None):
        return self._t.get_extra_info(name, default)

    def pause_reading(self) -> None:
        self._t.pause_reading()

    def resume_reading(self) -> None:
        self._t.resume_reading()

    def close(self) -> None:
        self._t.close()

    def __getattr__(self, name: str):
        return getattr(self._t, name)


class TappedProtocol(asyncio.Protocol):
    """A connection's protocol with its traffic noted (``binary``: its outputs are noted by
    size only, the image server's pictures)."""

    def __init__(self, inner: asyncio.Protocol, sink: Sink, port: str, binary: bool = False):
        self.inner = inner
        self.sink = sink
        self.port = port
        self.binary = binary
        self.conn = -1

    def connection_made(self, transport) -> None:
        self.conn = self.sink.opened(self.port, transport_peer(transport)[2])
        # a stand-in for the transport: what it does not note is the transport's own
        noted = cast(asyncio.Transport, TappedTransport(transport, self.sink, self.conn, self.binary))
        self.inner.connection_made(noted)

    def data_received(self, data: bytes) -> None:
        self.sink.note(self.conn, "in", data)
        self.inner.data_received(data)

    def eof_received(self):
        return self.inner.eof_received()

    def connection_lost(self, exc) -> None:
        try:
            self.inner.connection_lost(exc)
        finally:
            self.sink.closed(self.conn)

    def pause_writing(self) -> None:
        self.inner.pause_writing()

    def resume_writing(self) -> None:
        self.inner.resume_writing()

    def __getattr__(self, name: str):  # the inner protocol's own attributes (tests look at them)
        return getattr(self.inner, name)


def tapped(
    factory: Callable[[], asyncio.Protocol], sink: Sink, port: str, binary: bool = False
) -> Callable[[], asyncio.Protocol]:
    """A protocol factory whose connections are tapped."""
    return lambda: TappedProtocol(factory(), sink, port, binary)
