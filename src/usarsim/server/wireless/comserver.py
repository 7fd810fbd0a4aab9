"""The ComServer (WCS, TCP 5874, ``--wcs-port``; protocol.md 12.1), USARSim's
in-simulator wireless server: robots REGISTER, LISTEN, OPEN links and ask GETSS; on a link
the server opened it connects out to both robots' listening ports and relays what each
SENDs to the other while the radio link holds.

asyncio glue only: bytes -> commands (:class:`~usarsim.protocol.wireless.CommandSplitter`,
:func:`~usarsim.protocol.wireless.parse_wcs_request`) -> the ComServer's tables and the
radio (:class:`~usarsim.server.wireless.service.WirelessService`) -> a typed reply,
formatted by :func:`~usarsim.protocol.wireless.format_wcs_reply`.  An unknown command gets
``Fail: Unknown Message;``, a malformed one ``Fail: Incorrect Message;``; each kind is
logged once per connection.
"""

from __future__ import annotations

import asyncio
import functools
import logging
import math
from typing import cast

from usarsim.errors import ProtocolError
from usarsim.protocol.wireless import (
    FAIL_INCORRECT_MESSAGE,
    FAIL_NO_CONNECTION,
    FAIL_NO_SIGNAL,
    FAIL_THIRD_PARTY,
    FAIL_TOO_MANY_LISTENING,
    FAIL_TOO_MANY_REGISTERED,
    FAIL_UNKNOWN_MESSAGE,
    MAX_COMMAND_BYTES,
    WCS_PORT,
    CommandSplitter,
    Neighbor,
    SendClose,
    SendParser,
    WcsFail,
    WcsGetNeighbors,
    WcsListen,
    WcsNeighbors,
    WcsOk,
    WcsOpen,
    WcsRegister,
    WcsReply,
    WcsSignal,
    WcsUnknown,
    format_wcs_reply,
    parse_wcs_request,
    wcs_request_word,
)
from usarsim.server.connection import LogOnce, RelayEnd, write_open
from usarsim.sim.types import pair_key

from .service import (
    CONNECT_TIMEOUT_S,
    MAX_CONNECTIONS,
    WirelessConnection,
    WirelessServer,
    WirelessService,
    same_host,
)

log = logging.getLogger("usarsim.wireless")

MAX_REGISTERED = 1024
"""Robot names registered at most: more would let one client grow the table without bound."""
MAX_LISTENING = 4096
"""(robot, port) pairs listening at most, for the same reason."""
MAX_LINKS = 512
"""Links (two sockets each) open at once at most."""

_OK = WcsOk()


class _LinkEnd(RelayEnd):
    """The ComServer's connection to one robot of a link: what the robot sends is framed
    by a :class:`~usarsim.protocol.wireless.SendParser`."""

    def __init__(self, robot: str):
        self.robot = robot
        self.link: WcsLink | None = None
        self.transport: asyncio.Transport | None = None
        self.parser = SendParser()
        self.log_once = LogOnce(log, f"comserver link to {robot}", " (logged once)")

    def connection_made(self, transport) -> None:
        self.transport = transport
        if self.link is None:
            transport.pause_reading()  # until the link is set up

    def data_received(self, data: bytes) -> None:
        link = self.link
        if link is None or not link.open:
            return
        for ev in self.parser.feed(data):
            if isinstance(ev, bytes):
                link.relay(self, ev)
            elif isinstance(ev, SendClose):
                link.close(f"CLOSE from {self.robot}")
                return
            else:  # a dropped frame
                self.log_once(ev.kind, "from %s: %s; dropped", self.robot, ev)

    def connection_lost(self, exc) -> None:
        if self.link is not None:
            partial = " in the middle of a message" if self.parser.partial else ""
            self.link.close(f"{self.robot} closed its connection{partial}")

    def other_end(self) -> _LinkEnd | None:
        return self.link.other(self) if self.link is not None else None


class WcsLink:
    """A link the ComServer opened between two robots: what one robot SENDs, the other
    receives, while the radio link holds."""

    def __init__(self, server: ComServer, a: _LinkEnd, b: _LinkEnd, opened_at: float):
        self.server = server
        self.ends = (a, b)
        self.pair = pair_key(a.robot, b.robot)
        self.name = f"{a.robot}-{b.robot}"
        self.opened_at = opened_at
        self.open = True
        self.relayed = 0
        for end in self.ends:
            end.link = self
            end.log_once.label = f"comserver link {self.name}"
        # what delivers a message to each end when the channel hands it over (made once)
        self._deliver = {id(end): functools.partial(self._arrived, end) for end in self.ends}

    def start(self) -> None:
        for end in self.ends:
            if end.transport is not None and not end.transport.is_closing():
                end.transport.resume_reading()

    def other(self, end: _LinkEnd) -> _LinkEnd:
        return self.ends[1] if end is self.ends[0] else self.ends[0]

    def relay(self, src: _LinkEnd, payload: bytes) -> None:
        """What ``src`` SENDs: to the other end at once on the ideal channel, else when the
        channel delivers it (never, if it is lost on the way)."""
        if not self.open:
            return
        dst = self.other(src)
        svc = self.server.service
        if svc.ideal:
            self._arrived(dst, payload)
        else:
            svc.send(src.robot, dst.robot, payload, self._deliver[id(dst)])

    def _arrived(self, dst: _LinkEnd, payload: bytes) -> None:
        if self.open and write_open(dst.transport, payload):
            self.relayed += 1

    def close(self, why: str) -> None:
        if not self.open:
            return
        self.open = False
        for end in self.ends:
            if end.transport is not None:
                end.transport.close()
        self.server.links.discard(self)
        self.server.service.unwatch(self.pair)
        self.server.service.event("comserver link %s closed: %s (%d messages relayed)", self.name, why, self.relayed)


class WcsConnection(WirelessConnection):
    """A ComServer command connection: ``;``-ended commands, one reply each."""

    what = "comserver"

    def __init__(self, server):
        super().__init__(server)
        self._commands = CommandSplitter(MAX_COMMAND_BYTES)
        self.robots: set[str] = set()  # the names this connection REGISTERed

    def closed(self) -> None:
        self.owner.unregister(self)

    def split(self, data: bytes) -> list[str]:
        before = self._commands.dropped_commands
        out = self._commands.feed(data)
        if self._commands.dropped_commands != before:
            self.log_once("too-long", "dropped a command longer than %d bytes", MAX_COMMAND_BYTES)
        return out

    async def handle(self, text: str) -> None:
        self.write_text(format_wcs_reply(await self._answer(text)))

    async def _answer(self, text: str) -> WcsReply:
        try:
            cmd = parse_wcs_request(text)
        except ProtocolError as exc:
            self.log_once(f"incorrect-{wcs_request_word(text)}", "%s", exc)
            return FAIL_INCORRECT_MESSAGE
        if isinstance(cmd, WcsUnknown):
            self.log_once("unknown", "unknown message %.80r", cmd.text)
            return FAIL_UNKNOWN_MESSAGE
        srv: ComServer = self.owner
        if isinstance(cmd, WcsRegister):
            return srv.register(cmd.name, cmd.ip, self)
        if isinstance(cmd, WcsListen):
            return srv.listen(cmd.name, cmd.port)
        if isinstance(cmd, WcsOpen):
            return await srv.open(cmd)
        if isinstance(cmd, WcsGetNeighbors):
            return await srv.neighbours(cmd.name, self.ip)
        return await srv.getss(cmd.a, cmd.b, self.ip)  # WcsGetSS, the last kind


class ComServer(WirelessServer):
    """The WCS (protocol.md 12.1): robots register, listen and open links through it."""

    connection = WcsConnection

    def __init__(
        self,
        service: WirelessService,
        *,
        host: str = "127.0.0.1",
        port: int = WCS_PORT,
        max_connections: int = MAX_CONNECTIONS,
    ):
        super().__init__(service, host, port, max_connections)
        self.registered: dict[str, str] = {}  # robot name -> the IP its client listens on
        self.holders: dict[str, WcsConnection | None] = {}  # robot name -> the connection that registered it
        self.listening: dict[tuple[str, int], None] = {}  # (robot, port) waiting for a link, in order
        self.links: set[WcsLink] = set()
        service.subscribers.append(self._on_pair)

    async def stop(self) -> None:
        await super().stop()
        for link in list(self.links):
            link.close("server stopping")

    def _on_pair(self, pair, up: bool, time: float) -> None:
        if up:
            return
        for link in [ln for ln in self.links if ln.pair == pair and time >= ln.opened_at]:
            link.close(f"signal below the cutoff at t={time:.3f}")

    # commands ---------------------------------------------------------------------------
    def register(self, name: str, ip: str, conn: WcsConnection | None = None) -> WcsReply:
        """REGISTER name ip from ``conn``.  A name belongs to the connection that registered
        it until that connection closes: from any other connection, whatever the address,
        REGISTER of it fails as in USARSim's ComServer (``Fail: Robot with name <n> already
        registered;``, protocol.md 12.1), so that no controller takes over another's robot.
        The holder saying it again with the same address is answered ``OK;``."""
        known = self.registered.get(name)
        if known is not None:
            if self.holders.get(name) is conn and known == ip:
                return _OK
            return WcsFail.already_registered(name)
        if len(self.registered) >= MAX_REGISTERED:
            log.warning("comserver: REGISTER %.80s refused: %d robots registered already", name, MAX_REGISTERED)
            return FAIL_TOO_MANY_REGISTERED
        self.registered[name] = ip
        self.holders[name] = conn
        if conn is not None:
            conn.robots.add(name)
        self.service.event("comserver: %s registered at %s", name, ip)
        return _OK

    def unregister(self, conn: WcsConnection) -> None:
        """``conn`` closed: the names it registered are free again, and their LISTEN entries
        go with them (links already open keep running on their own sockets)."""
        gone = {name for name in conn.robots if self.holders.get(name) is conn}
        conn.robots.clear()
        if not gone:
            return
        for name in gone:
            del self.registered[name]
            del self.holders[name]
        self.listening = {key: None for key in self.listening if key[0] not in gone}
        self.service.event("comserver: %s unregistered (connection closed)", ", ".join(sorted(gone)))

    def listen(self, name: str, port: int) -> WcsReply:
        if name not in self.registered:
            return WcsFail.not_registered(name)
        if (name, port) in self.listening:
            return WcsFail.already_listening(name, port)
        if len(self.listening) >= MAX_LISTENING:
            log.warning("comserver: LISTEN %.80s %d refused: %d ports listening already", name, port, MAX_LISTENING)
            return FAIL_TOO_MANY_LISTENING
        self.listening[(name, port)] = None
        return _OK

    async def open(self, cmd: WcsOpen) -> WcsReply:
        """OPEN a pa b pb: ``b`` must be listening on ``pb`` (the entry is used up by the
        link, as in USARSim's ComServer); the server connects to both robots' ports."""
        a, pa, b, pb = cmd.src, cmd.src_port, cmd.dst, cmd.dst_port
        if (b, pb) not in self.listening:
            return WcsFail.not_listening(b, pb)
        if a not in self.registered:
            return WcsFail.not_registered(a)
        if a.lower() == b.lower():
            return WcsFail.cannot_connect(b)
        if len(self.links) >= MAX_LINKS:  # two sockets each: keep file descriptors for the rest
            log.warning("comserver: OPEN %.80s -> %.80s refused: %d links open already", a, b, MAX_LINKS)
            return FAIL_NO_CONNECTION
        svc = self.service
        pair = pair_key(a, b)
        svc.watch(pair)  # while the link is being set up
        try:
            t, ln = await svc.check(a, b)
            if ln is None or not ln.holds:
                svc.event(
                    "comserver: %s - %s out of range (%s)",
                    a,
                    b,
                    "no such robot"
                    if ln is None
                    else f"{ln.signal_dbm:.2f} dBm, {ln.walls} walls, {ln.distance_m:.2f} m",
                )
                return WcsFail.cannot_connect(b)
            # a robot's registration ends with its connection, which may close meanwhile
            if (b, pb) not in self.listening:
                return WcsFail.not_listening(b, pb)
            if a not in self.registered:
                return WcsFail.not_registered(a)
            ends = await self._connect((a, self.registered[a], pa), (b, self.registered[b], pb))
            if ends is None:
                return FAIL_NO_CONNECTION
            if (b, pb) not in self.listening or svc.down_since(pair, t):
                for end in ends:
                    if end.transport is not None:  # connected: always
                        end.transport.close()
                return WcsFail.cannot_connect(b) if svc.down_since(pair, t) else WcsFail.not_listening(b, pb)
            del self.listening[(b, pb)]
            link = WcsLink(self, ends[0], ends[1], t)
            svc.watch(pair)  # for as long as the link lives
            self.links.add(link)
            link.start()
            svc.event("comserver link %s opened at t=%.3f (%.2f dBm)", link.name, t, ln.signal_dbm)
            return _OK
        finally:
            svc.unwatch(pair)

    async def _connect(self, *targets: tuple[str, str, int]) -> tuple[_LinkEnd, ...] | None:
        loop = asyncio.get_running_loop()

        async def one(robot, ip, port):
            _, end = await asyncio.wait_for(
                loop.create_connection(lambda: _LinkEnd(robot), ip, port), CONNECT_TIMEOUT_S
            )
            return end

        results = await asyncio.gather(*(one(*t) for t in targets), return_exceptions=True)
        if all(isinstance(r, _LinkEnd) for r in results):
            return cast(tuple[_LinkEnd, ...], tuple(results))  # every one is (checked just above)
        for r, (robot, ip, port) in zip(results, targets):
            if isinstance(r, _LinkEnd):
                if r.transport is not None:  # connected: always
                    r.transport.close()
            else:
                self.service.event("comserver: cannot connect to %s at %s:%d: %s", robot, ip, port, r)
        return None

    async def neighbours(self, name: str, peer_ip: str) -> WcsReply:
        """GETNEIGHBORS name (an extension): only from the IP of ``name``, as GETSS is only
        answered to one of its two robots; a name nobody registered is refused as OPEN's."""
        ip = self.registered.get(name)
        if ip is None:
            return WcsFail.not_registered(name)
        if same_host(peer_ip) != same_host(ip):
            return FAIL_THIRD_PARTY
        found = await self.service.neighbours(name)
        return WcsNeighbors(tuple(Neighbor(b, ln.signal_dbm, q) for b, ln, q in found))

    async def getss(self, a: str, b: str, peer_ip: str) -> WcsReply:
        """GETSS a b: only from the IP of one of the two robots (USARSim's rule)."""
        ips = {same_host(self.registered.get(a)), same_host(self.registered.get(b))}
        if same_host(peer_ip) not in ips:
            return FAIL_THIRD_PARTY
        ln = await self.service.signal(a, b)
        if ln is None or not math.isfinite(ln.signal_dbm):
            return FAIL_NO_SIGNAL
        return WcsSignal(ln.signal_dbm)
