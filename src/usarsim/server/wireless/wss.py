"""The Wireless Simulation Server (WSS, TCP 50000, ``--wss-port``; protocol.md 12.2), the
RoboCup one: robots INIT with the ports they listen on, ask GETSS, DNS and REVERSEDNS, and
connect to a relay port per ordered robot pair that copies bytes both ways while the radio
link holds and refuses connections while it is down (under the same number).  A relay
delivers what it accepted: the bytes read from one socket before it closed are written to the
other before that one is closed, and a robot that leaves (its control connection closes) stops
its relay ports from listening but leaves the relays already connected running, as the
reference WSS of protocol.md 12.2 did: a robot leaving took only its registration away, and a
relay read its sockets until one closed, writing each read to the other before closing both.

asyncio glue only: lines (:class:`~usarsim.protocol.framing.LineBuffer`) -> requests
(:func:`~usarsim.protocol.wireless.parse_wss_request`) -> the registered robots, relay
ports and the radio -> a typed reply, formatted by
:func:`~usarsim.protocol.wireless.format_wss_reply`.  A malformed or unknown request gets
the WSS's ``ERROR {Reason ...}``; each kind is logged once per connection.
"""

from __future__ import annotations

import asyncio
import logging
import math
import socket

from usarsim.protocol.wireless import (
    DNS_NO_ROBOT,
    DNS_NOT_LISTENING,
    REASON_INIT_FIRST,
    REASON_NO_RELAY_PORT,
    REASON_ROBOT_EXISTS,
    REASON_UNKNOWN_METHOD,
    REVERSEDNS_UNKNOWN_PORT,
    SS_MODEL_NAN,
    SS_NO_ROBOT,
    SS_TO_SELF,
    WSS_PORT,
    WssDns,
    WssDnsReply,
    WssError,
    WssGetSS,
    WssInit,
    WssInitReply,
    WssInvalid,
    WssReply,
    WssRequest,
    WssReverseDns,
    WssReverseDnsReply,
    WssSignal,
    format_wss_reply,
    parse_wss_request,
)
from usarsim.server.connection import RelayEnd, write_open
from usarsim.sim.types import Pair, pair_key

from .service import (
    CONNECT_TIMEOUT_S,
    MAX_CONNECTIONS,
    LineConnection,
    WirelessServer,
    WirelessService,
    same_host,
)

log = logging.getLogger("usarsim.wireless")

MAX_RELAY_PORTS = 1024
"""Relay ports (listening sockets, one per robot pair and port asked for) at most."""


class _PipeEnd(RelayEnd):
    """One socket of a :class:`Pipe`: what arrives is written to the other one, whose
    backpressure pauses this one's reading."""

    def __init__(self, pipe: Pipe):
        self.pipe = pipe
        self.peer: _PipeEnd | None = None
        self.transport: asyncio.Transport | None = None

    def connection_made(self, transport) -> None:
        self.transport = transport
        transport.pause_reading()  # until both ends are connected (Pipe.start)

    def data_received(self, data: bytes) -> None:
        if self.peer is not None:
            write_open(self.peer.transport, data)

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
            _, src = await loop.connect_accepted_socket(lambda: _PipeEnd(self), self.sock)
        except OSError:
            self.close()
            return
        self.ends.append(src)
        if self.closed:
            src.transport.close()
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
            dst_t, dst = await loop.create_connection(lambda: _PipeEnd(self), sock=sock)
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
        src.transport.resume_reading()
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
            self._sock.listen(16)
            loop.add_reader(self._sock.fileno(), self._accept)
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
        taken = 0
        while most is None or taken < most:
            taken += 1
            try:
                conn, addr = self._sock.accept()
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


class WssRobot:
    """A robot registered by INIT: its name, the address of its control connection and the
    ports it listens on."""

    def __init__(self, name: str, ip: str, ports: tuple[int, ...], conn: WssConnection):
        self.name, self.ip, self.ports, self.conn = name, ip, ports, conn


class WssConnection(LineConnection):
    """A robot's control connection to the WSS (protocol.md 12.2)."""

    what = "wss"

    def __init__(self, server):
        super().__init__(server)
        self.robot: WssRobot | None = None

    def closed(self) -> None:
        if self.robot is not None:
            self.owner.unregister(self.robot)

    async def handle(self, line: str) -> None:
        self.write_text(format_wss_reply(await self._answer(self.parse(line, parse_wss_request))))

    async def _answer(self, req: WssRequest | None) -> WssReply:
        """The reply to ``req`` (None: a malformed line, logged already)."""
        srv: WssServer = self.owner
        kind = req.type if req is not None else ""
        if self.robot is None:
            if kind != "INIT":
                return WssError(REASON_INIT_FIRST)
            if isinstance(req, WssInvalid):
                return WssError(req.reason)
            return self._init(req)
        me = self.robot.name
        if isinstance(req, WssInvalid) and kind != "INIT":
            return WssError(req.reason)
        if isinstance(req, WssGetSS):
            return await srv.getss(me, req.robot)
        if isinstance(req, WssDns):
            return await srv.dns(me, req)
        if isinstance(req, WssReverseDns):
            who = srv.reverse_dns(me, req.port)
            return (
                WssReverseDnsReply(req.port, robot=who)
                if who is not None
                else WssReverseDnsReply(req.port, error=REVERSEDNS_UNKNOWN_PORT)
            )
        if req is not None:  # unknown, or INIT again
            self.log_once(f"unknown-{kind}", "unknown or repeated command %s", kind)
        return WssError(REASON_UNKNOWN_METHOD)

    def _init(self, req: WssInit) -> WssReply:
        srv: WssServer = self.owner
        if req.robot in srv.robots:
            return WssError(REASON_ROBOT_EXISTS)
        # 0 in the list (accepted, protocol.md 12.2) is not a listening port: see dns()
        ports = tuple(dict.fromkeys(p for p in req.ports if p))
        self.robot = WssRobot(req.robot, self.ip, ports, self)
        srv.robots[req.robot] = self.robot
        srv.service.event("wss: %s registered at %s, ports %s", req.robot, self.ip, list(ports))
        return WssInitReply()


class WssServer(WirelessServer):
    """The Wireless Simulation Server (protocol.md 12.2)."""

    connection = WssConnection

    def __init__(
        self,
        service: WirelessService,
        *,
        host: str = "127.0.0.1",
        port: int = WSS_PORT,
        max_connections: int = MAX_CONNECTIONS,
    ):
        super().__init__(service, host, port, max_connections)
        self.robots: dict[str, WssRobot] = {}
        self.ports: dict[tuple[str, str, int], RelayPort] = {}
        self.by_number: dict[int, RelayPort] = {}
        self.outgoing: dict[int, Pipe] = {}  # the local port of the server's own end of each pipe -> the pipe
        self.retired: set[RelayPort] = set()  # relay ports of robots that left, while relays run through them
        self.tasks: set[asyncio.Task] = set()  # pipes being connected
        service.subscribers.append(self._on_pair)

    async def stop(self) -> None:
        await super().stop()
        for rp in [*self.ports.values(), *self.retired]:
            rp.close()
        self.ports.clear()
        self.by_number.clear()
        self.retired.clear()
        for task in list(self.tasks):
            task.cancel()
        if self.tasks:
            await asyncio.gather(*self.tasks, return_exceptions=True)

    def _on_pair(self, pair: Pair, up: bool, time: float) -> None:
        for rp in [*self.ports.values(), *self.retired]:
            if rp.pair == pair and time >= rp.checked_at and rp.up != up:
                rp.set_up(up, time)
                self.service.event(
                    "wss relay port %d (%s -> %s) %s",
                    rp.number,
                    rp.src,
                    rp.dst,
                    "listening" if up else "refusing connections",
                )

    # requests ---------------------------------------------------------------------------
    async def getss(self, me: str, other: str) -> WssSignal:
        """GETSS from ``me``: INF to itself, NaN for a robot that did not INIT or that the
        model cannot answer for, else the strength in dBm."""
        if other == me:
            return WssSignal(other, math.inf, SS_TO_SELF)
        if other not in self.robots:
            return WssSignal(other, math.nan, SS_NO_ROBOT)
        ln = await self.service.signal(me, other)
        if ln is None or not math.isfinite(ln.signal_dbm) or ln.signal_dbm > 0:
            return WssSignal(other, math.nan, SS_MODEL_NAN)
        return WssSignal(other, ln.signal_dbm)

    async def dns(self, me: str, req: WssDns) -> WssReply:
        """DNS from ``me``: the relay port to ``req.robot`` on ``req.port`` (default: the
        first port it declared)."""
        other = req.robot
        dst = self.robots.get(other)
        if dst is None or other == me:
            return WssDnsReply(other, -1, DNS_NO_ROBOT)
        if req.port is not None and req.port not in dst.ports:
            return WssDnsReply(other, -1, DNS_NOT_LISTENING)
        # Port 0 in an INIT list (accepted as the reference WSS does, protocol.md 12.2) is no
        # port a robot listens on: dst.ports holds only the others, and the default port is
        # the first of them.  A robot that declared none (only 0, or no Port) gets
        # RobotDoesNotListenOnThisPort at once, where the reference would hand out a relay
        # port whose every connection it closes (it would connect to port 0).
        dst_port = req.port or (dst.ports[0] if dst.ports else 0)
        if not dst_port:
            return WssDnsReply(other, -1, DNS_NOT_LISTENING)
        port = await self.relay_port(me, other, dst_port)
        return WssError(REASON_NO_RELAY_PORT) if port is None else WssDnsReply(other, port)

    async def relay_port(self, src: str, dst: str, dst_port: int) -> int | None:
        key = (src, dst, dst_port)
        rp = self.ports.get(key)
        if rp is not None:
            return rp.number
        if not dst_port:
            return None
        if len(self.ports) >= MAX_RELAY_PORTS:  # each is a listening socket: keep file descriptors for the rest
            log.warning("wss: no relay port for %s -> %s:%d: %d allocated already", src, dst, dst_port, MAX_RELAY_PORTS)
            return None
        pair = pair_key(src, dst)
        self.service.watch(pair)
        try:
            t, ln = await self.service.check(src, dst)
        except BaseException:
            self.service.unwatch(pair)
            raise
        rp = self.ports.get(key)  # allocated meanwhile
        if rp is not None or src not in self.robots or dst not in self.robots:
            self.service.unwatch(pair)
            return rp.number if rp is not None else None
        rp = RelayPort(self, src, dst, dst_port)
        up = ln is not None and ln.holds and not self.service.down_since(pair, t)
        try:
            rp.open(up, t)
        except OSError as exc:
            log.error("wss: cannot allocate a relay port for %s -> %s: %s", src, dst, exc)
            self.service.unwatch(pair)
            return None
        self.ports[key] = rp
        self.by_number[rp.number] = rp
        self.service.event(
            "wss relay port %d for %s -> %s:%d (%s)", rp.number, src, dst, dst_port, "listening" if up else "link down"
        )
        return rp.number

    def reverse_dns(self, me: str, port: int) -> str | None:
        """The robot at the other end of ``port``: the server's end of a pipe into ``me``
        (the peer port of a connection ``me`` accepted), or a relay port of ``me``."""
        pipe = self.outgoing.get(port)
        if pipe is not None and pipe.port.dst == me:
            return pipe.port.src
        rp = self.by_number.get(port)
        if rp is not None and me in (rp.src, rp.dst):
            return rp.dst if rp.src == me else rp.src
        return None

    def unregister(self, robot: WssRobot) -> None:
        """``robot``'s control connection closed: its name is free again and its relay ports
        retire (their relays run on, as in the reference WSS, whose robot leaving took only
        its registration away: protocol.md 12.2)."""
        if self.robots.get(robot.name) is not robot:
            return
        gone = [(key, rp) for key, rp in self.ports.items() if robot.name in (rp.src, rp.dst)]
        for _, rp in gone:  # while both robots are still registered
            rp.retire()
        del self.robots[robot.name]
        for key, rp in gone:
            del self.ports[key]
            self.by_number.pop(rp.number, None)
        self.service.event("wss: %s left", robot.name)

    def retired_port_done(self, rp: RelayPort) -> None:
        """A retired port has no relay left (none at all, or its last one closed): its pair
        is no longer watched."""
        if rp in self.retired or not rp.pipes:
            self.retired.discard(rp)
            self.service.unwatch(rp.pair)
