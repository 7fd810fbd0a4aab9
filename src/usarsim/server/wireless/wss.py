"""The Wireless Simulation Server (WSS, TCP 50000, ``--wss-port``; protocol.md 12.2), the
RoboCup one: robots INIT with the ports they listen on, ask GETSS, DNS and REVERSEDNS, and
connect to a relay port per ordered robot pair (:mod:`usarsim.server.wireless.relay`) that
copies bytes both ways while the radio link holds and refuses connections while it is down
(under the same number).  A relay delivers what it accepted: the bytes read from one socket
before it closed are written to the other before that one is closed, and a robot that leaves
(its control connection closes) stops its relay ports from listening but leaves the relays
already connected running, as the reference WSS of protocol.md 12.2 did: a robot leaving took
only its registration away, and a relay read its sockets until one closed, writing each read
to the other before closing both.

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
from typing import cast

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
from usarsim.sim.types import Pair, pair_key

from .relay import Pipe, RelayPort
from .service import MAX_CONNECTIONS, LineConnection, WirelessServer, WirelessService

__all__ = ["MAX_RELAY_PORTS", "Pipe", "RelayPort", "WssConnection", "WssRobot", "WssServer"]

log = logging.getLogger("usarsim.wireless")

MAX_RELAY_PORTS = 1024
"""Relay ports (listening sockets, one per robot pair and port asked for) at most."""


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
            return self._init(cast(WssInit, req))  # an INIT that is not WssInvalid
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
