"""The WSS's relays (protocol.md 12.2): a :class:`RelayPort` per ordered robot pair and
destination port, listening while the radio link holds and refusing connections while it is
down (under the same number), and a :class:`Pipe` per connection through it, copying bytes
both ways between the robot that connected and the destination robot's listening port.  A
relay delivers what it accepted: the bytes read from one socket before it closed are written
to the other before that one is closed.
"""

from __future__ import annotations

import asyncio
import logging
import socket
from typing import TYPE_CHECKING

from usarsim.server.connection import RelayEnd, write_open
from usarsim.sim.types import pair_key

from .service import CONNECT_TIMEOUT_S, same_host

if TYPE_CHECKING:
    from .wss import WssServer

log = logging.getLogger("usarsim.wireless")


class _PipeEnd(RelayEnd):
    """One socket of a :class:`Pipe`: what arrives is written to the other one, whose
    backpressure pauses this one's reading."""

    def __init__(self, pipe: Pipe, robot: str):
        self.pipe = pipe
        self.robot = robot  # the robot on this socket's side
        self.peer: _PipeEnd | None = None
        self.transport: asyncio.Transport | None = None

    def connection_made(self, transport) -> None:
        self.transport = transport
        transport.pause_reading()  # until both ends are connected (Pipe.start)

    def data_received(self, data: bytes) -> None:
        """What this robot sent: to the other one at once on the ideal channel, else each chunk
        read as one message through the channel (delivered when it arrives, if the pipe is
        still open then)."""
        peer = self.peer
        if peer is None:
            return
        svc = self.pipe.port.server.service
        if svc.ideal:
            write_open(peer.transport, data)
        else:
            svc.send(self.robot, peer.robot, data, peer.receive)

    def receive(self, payload: bytes) -> None:
        """What the channel delivers to this end's robot."""
        write_open(self.transport, payload)

    def eof_received(self):
        return False  # closes the pipe: the WSS closes both sockets

    def connection_lost(self, exc) -> None:
        self.pipe.close()

    def other_end(self) -> _PipeEnd | None:
        return self.peer


class Pipe:
    """One connection through a relay port: the robot that connected, and the server's
    own connection to the destination robot's listening port."""

    def __init__(self, port: RelayPort, sock: socket.socket):
        self.port = port
        self.sock = sock  # the accepted connection, until its transport takes it
        self.ends: list[_PipeEnd] = []
        self.closed = False
        self.out_sock: socket.socket | None = None  # the socket to the destination, while it connects
        self.out_port = 0  # its local port: the peer port the destination sees
        self._task: asyncio.Task | None = None  # start(), while it runs

    async def start(self, dst_ip: str, dst_port: int) -> None:
        loop = asyncio.get_running_loop()
        self._task = asyncio.current_task()
        try:
            _, src = await loop.connect_accepted_socket(lambda: _PipeEnd(self, self.port.src), self.sock)
        except OSError:
            self.close()
            return
        self.ends.append(src)
        src_t = src.transport
        assert src_t is not None  # connect_accepted_socket returns once the connection is made
        if self.closed:
            src_t.close()
            return
        # The server's own socket to the destination is bound first and its port recorded
        # in ``outgoing`` before it connects: the destination may accept the connection and
        # ask REVERSEDNS with its peer port before this coroutine runs again, and must then
        # be told who is calling (protocol.md 12.2).
        try:
            sock = self._bound_socket(dst_ip)
        except OSError as exc:
            self.port.server.service.event("wss: no socket to connect to %s: %s", self.port.dst, exc)
            self.close()
            return
        self.out_sock = sock
        self.out_port = sock.getsockname()[1]
        self.port.server.outgoing[self.out_port] = self
        try:
            await asyncio.wait_for(loop.sock_connect(sock, (dst_ip, dst_port)), CONNECT_TIMEOUT_S)
            if self.closed:
                return
            self.out_sock = None  # the transport takes it
            dst_t, dst = await loop.create_connection(lambda: _PipeEnd(self, self.port.dst), sock=sock)
        except asyncio.CancelledError:  # closed while connecting (close()): the connect has let go of it
            sock.close()
            raise
        except (TimeoutError, OSError) as exc:
            sock.close()
            self.port.server.service.event(
                "wss: cannot connect to %s at %s:%d: %s", self.port.dst, dst_ip, dst_port, exc
            )
            self.close()
            return
        self.ends.append(dst)
        if self.closed:
            dst_t.close()
            return
        src.peer, dst.peer = dst, src
        src_t.resume_reading()
        dst_t.resume_reading()

    @staticmethod
    def _bound_socket(ip: str) -> socket.socket:
        """A non-blocking TCP socket for ``ip``'s family, bound to a port of its own."""
        sock = socket.socket(socket.AF_INET6 if ":" in ip else socket.AF_INET, socket.SOCK_STREAM)
        try:
            sock.setblocking(False)
            sock.bind(("", 0))
        except OSError:
            sock.close()
            raise
        return sock

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        if not self.ends:
            self.sock.close()
        if self.out_sock is not None:
            # a connect may still wait on it: it is cancelled, and start() closes the socket once
            # asyncio has let go of its descriptor (closed now, the descriptor could be reused
            # by another socket while asyncio still watches it)
            task = self._task
            if task is not None and not task.done() and task is not asyncio.current_task():
                task.cancel()
            else:
                self.out_sock.close()
            self.out_sock = None
        for end in self.ends:
            if end.transport is not None:
                end.transport.close()  # after writing what it still holds (asyncio's close)
        if self.port.server.outgoing.get(self.out_port) is self:
            del self.port.server.outgoing[self.out_port]
        self.port.pipe_closed(self)


class RelayPort:
    """The WSS's port for one ordered robot pair (and one listening port of the
    destination): it listens while the link holds and refuses connections otherwise,
    always under the same number.  Once one of its robots has left it is retired: it no
    longer listens, and its relays already connected run on until either end closes them or
    the link goes down."""

    def __init__(self, server: WssServer, src: str, dst: str, dst_port: int):
        self.server = server
        self.src, self.dst, self.dst_port = src, dst, dst_port
        self.pair = pair_key(src, dst)
        self.number = 0
        self.up = False
        self.checked_at = 0.0
        self.pipes: set[Pipe] = set()
        self.retired = False
        self._sock: socket.socket | None = None
        self._listening = False

    def _bind(self) -> None:
        host = self.server.listener.host
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_STREAM)
        try:
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            sock.bind((host, self.number))
            sock.setblocking(False)
        except OSError:
            sock.close()
            raise
        self._sock = sock
        self.number = sock.getsockname()[1]

    def open(self, up: bool, at: float) -> None:
        """Reserve the port number (raises OSError when none is free) and set the state."""
        self._bind()
        self.set_up(up, at)

    def set_up(self, up: bool, at: float) -> None:
        self.checked_at = at
        self.up = up
        loop = asyncio.get_running_loop()
        if self.retired:  # listens no more; a link going down still ends its relays
            if not up:
                for pipe in list(self.pipes):
                    pipe.close()
            return
        if up and not self._listening:
            if self._sock is None:
                try:
                    self._bind()
                except OSError as exc:
                    log.error(
                        "wss: cannot listen again on relay port %d (%s -> %s): %s", self.number, self.src, self.dst, exc
                    )
                    return
            sock = self._sock
            assert sock is not None  # bound above, or still bound
            sock.listen(16)
            loop.add_reader(sock.fileno(), self._accept)
            self._listening = True
        elif not up:
            for pipe in list(self.pipes):
                pipe.close()
            if self._listening:
                self._release()
                try:  # keep the number, without listening: connections are refused
                    self._bind()
                except OSError as exc:
                    log.warning("wss: relay port %d lost while the link is down: %s", self.number, exc)

    def _accept(self, most: int | None = 16) -> None:
        """Take up to ``most`` connections waiting on the port (None: all of them)."""
        sock = self._sock
        if sock is None:  # released meanwhile: nothing to take
            return
        taken = 0
        while most is None or taken < most:
            taken += 1
            try:
                conn, addr = sock.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return
            robot = self.server.robots.get(self.src)
            dst = self.server.robots.get(self.dst)
            if not self.up or robot is None or dst is None or same_host(addr[0]) != same_host(robot.ip):
                conn.close()
                continue
            conn.setblocking(False)
            pipe = Pipe(self, conn)
            self.pipes.add(pipe)
            task = asyncio.get_running_loop().create_task(pipe.start(dst.ip, self.dst_port))
            self.server.tasks.add(task)
            task.add_done_callback(self.server.tasks.discard)

    def _release(self) -> None:
        if self._sock is not None:
            if self._listening:
                asyncio.get_running_loop().remove_reader(self._sock.fileno())
            self._sock.close()
        self._sock = None
        self._listening = False

    def retire(self) -> None:
        """One of the robots left: the connections that reached the port already are taken
        (their bytes were accepted), then it stops listening; its relays run on."""
        if self._listening:
            self._accept(None)
        self.retired = True
        self._release()
        if not self.pipes:
            self.server.retired_port_done(self)
        else:
            self.server.retired.add(self)

    def pipe_closed(self, pipe: Pipe) -> None:
        self.pipes.discard(pipe)
        if self.retired and not self.pipes:
            self.server.retired_port_done(self)

    def close(self) -> None:
        for pipe in list(self.pipes):
            pipe.close()
        self._release()
