"""The wireless simulation (manual section 3.2.4; protocol.md 12): three servers that carry
the robots' team communication only while the radio link between them would hold.

* The ComServer (WCS, TCP 5874, ``--wcs-port``; protocol.md 12.1), USARSim's in-simulator
  server: ``REGISTER name ip;``, ``LISTEN name port;``, ``OPEN a pa b pb;`` (the server
  connects out to both robots' listening ports and relays between them), ``GETSS a b;``;
  replies ``OK;``, ``Fail:<message>;`` and ``OK:<dBm>;``.  On a relayed link each robot sends
  ``SEND <n> <n bytes>;`` (binary-safe) and ``CLOSE;``; the other robot receives the bytes.
* The Wireless Simulation Server (WSS, TCP 50000, ``--wss-port``; protocol.md 12.2), the
  RoboCup one: ``INIT {Robot r} {Port p,...}``, ``GETSS``, ``DNS``, ``REVERSEDNS``, and a relay
  port per ordered robot pair that copies bytes both ways and refuses connections while
  the link is down.
* The ComServerInterface (TCP 7435, ``--cominterface-port``; protocol.md 12.3): ``GETPOS``
  and ``GETOBS``, what the WSS's propagation models asked the simulator.

Link state follows simulated time: the signal is computed on the simulation thread from
the simulated poses (:class:`usarsim.sim.radio.RadioNet`) when a link is opened or a relay
port allocated, and after every advance of the clock (every STEP in lock-step); a link
whose signal falls below the cutoff is closed before anything else happens at that
instant (in lock-step, before the STEPPED reply), and nothing is relayed on it after.

Bad input never takes a server down: a malformed command gets the documented error reply,
or is ignored where the protocol has none; each kind is logged once per connection.
"""

from __future__ import annotations

import asyncio
import collections
import logging
import math
import socket
from dataclasses import dataclass
from typing import Any, Callable

from usarsim.config.world import WirelessConfig
from usarsim.errors import ProtocolError
from usarsim.protocol.framing import LineBuffer
from usarsim.protocol.grammar import parse_line, parse_vector
from usarsim.protocol.numbers import vec4
from usarsim.server.listener import ReadGate, TcpListener
from usarsim.sim.facade import SimFacade
from usarsim.sim.radio import Link, Pair, RadioModel, RadioNet, pair_key, resolve_model

log = logging.getLogger("usarsim.wireless")

WCS_PORT = 5874
WSS_PORT = 50000
INTERFACE_PORT = 7435
# Longest ComServer command up to its ';' (the manual's are a few dozen characters).
MAX_COMMAND_BYTES = 1024
# Longest message of one SEND on a ComServer link; a longer one is dropped.
MAX_SEND_BYTES = 1 << 20
# Outside lock-step the links are evaluated at most this often (simulated seconds).
CLOCKED_INTERVAL_S = 0.02
# Wall-clock limit on the server's own connection to a robot's listening port.
CONNECT_TIMEOUT_S = 5.0
# Requests of one connection waiting to be answered; beyond them its socket is not read
# until they are answered.
MAX_QUEUED = 256
# Robot names registered with the ComServer, and (robot, port) pairs listening, at most:
# more would let one client grow them without bound.
MAX_REGISTERED = 1024
MAX_LISTENING = 4096
# ComServer links (two sockets each) open at once at most.
MAX_LINKS = 512
# WSS relay ports (listening sockets, one per robot pair and port asked for) at most.
MAX_RELAY_PORTS = 1024
# Kinds of problem logged once per connection at most.
MAX_LOGGED_KINDS = 32
# Connections per server at most (``usarsim serve --max-wireless-connections``).
MAX_CONNECTIONS = 64


@dataclass(frozen=True)
class WirelessOptions:
    """How ``usarsim serve`` runs the wireless simulation: the ports (0 picks a free one),
    the radio model named on the command line and the configuration file's layer (both
    None: the world's ``wireless`` section, else ``waf``), and ``bDebug``."""

    wcs_port: int = WCS_PORT
    wss_port: int = WSS_PORT
    interface_port: int = INTERFACE_PORT
    model: str | None = None
    config: WirelessConfig | None = None
    debug: bool = False
    max_connections: int = MAX_CONNECTIONS


def _fmt_wcs_dbm(x: float) -> str:
    """A ComServer GETSS value: 2 decimals, as UnrealScript printed floats."""
    s = "%.2f" % x
    return "0.00" if s == "-0.00" else s


def _fmt_wss_dbm(x: float) -> str:
    """A WSS strength: 6 significant digits, as the C++ WSS streamed doubles."""
    return "%.6g" % x


def _port(text: str) -> int | None:
    t = text.strip()
    if not t.isdigit() or len(t) > 5 or not 0 < int(t) <= 65535:
        return None
    return int(t)


# --------------------------------------------------------------------------- shared


class WirelessService:
    """What the three servers share: the radio links on the simulation thread, the pairs
    they depend on, the latest state reported for each pair."""

    def __init__(self, facade: SimFacade, model: RadioModel, *, debug: bool = False):
        self.facade = facade
        self.model = model
        self.debug = debug
        self.net = RadioNet(model)
        self.net.min_interval_s = 0.0 if facade.lockstep else CLOCKED_INTERVAL_S
        self.net.on_change = self._changes_threadsafe
        facade.sim.after_advance.append(self.net.evaluate)  # before the simulation thread starts
        self.loop: asyncio.AbstractEventLoop | None = None
        self.state: dict[Pair, tuple[float, bool]] = {}  # pair -> (simulated time, holds)
        self.subscribers: list[Callable[[Pair, bool, float], None]] = []
        self._refs: collections.Counter[Pair] = collections.Counter()

    def event(self, fmt: str, *args) -> None:
        """A link event: logged at INFO with bDebug, at DEBUG otherwise."""
        log.log(logging.INFO if self.debug else logging.DEBUG, fmt, *args)

    # pairs ------------------------------------------------------------------------------
    def watch(self, pair: Pair) -> None:
        self._refs[pair] += 1
        if self._refs[pair] == 1:
            self.net.watched = frozenset(self._refs)

    def unwatch(self, pair: Pair) -> None:
        self._refs[pair] -= 1
        if self._refs[pair] <= 0:
            del self._refs[pair]
            self.state.pop(pair, None)
            self.net.watched = frozenset(self._refs)

    def _changes_threadsafe(self, time: float, changes: list[tuple[Pair, bool]]) -> None:
        loop = self.loop
        if loop is not None and not loop.is_closed():
            try:
                loop.call_soon_threadsafe(self._apply, time, changes)
            except RuntimeError:  # the loop closed meanwhile
                pass

    def _apply(self, time: float, changes: list[tuple[Pair, bool]]) -> None:
        for pair, up in changes:
            if pair not in self._refs:
                continue  # nothing depends on it any more
            self.state[pair] = (time, up)
            self.event("link %s - %s %s at t=%.3f", pair[0], pair[1], "holds" if up else "is down", time)
            for fn in list(self.subscribers):
                try:
                    fn(pair, up, time)
                except Exception:
                    log.exception("wireless: error while applying a link change")

    def down_since(self, pair: Pair, time: float) -> bool:
        """Whether the pair was reported down at or after ``time``."""
        st = self.state.get(pair)
        return st is not None and st[0] >= time and not st[1]

    # the simulation ----------------------------------------------------------------------
    async def ask(self, fn: Callable[[Any], Any]) -> Any:
        """``fn(sim)`` on the simulation thread (at once, also in lock-step)."""
        loop = asyncio.get_running_loop()
        fut = loop.create_future()

        def settle(result, error):
            if not fut.done():
                if error is not None:
                    fut.set_exception(error)
                else:
                    fut.set_result(result)

        def done(result, error):
            if not loop.is_closed():
                try:
                    loop.call_soon_threadsafe(settle, result, error)
                except RuntimeError:
                    pass

        self.facade.call(fn, on_done=done)
        return await fut

    async def check(self, a: str, b: str) -> tuple[float, Link | None]:
        """(simulated time, link) for a link about to be opened; its state is recorded."""
        return await self.ask(lambda sim: (sim.time, self.net.check(sim, a, b)))

    async def signal(self, a: str, b: str) -> Link | None:
        return await self.ask(lambda sim: self.net.link(sim, a, b))


class _Connection(asyncio.Protocol):
    """A client connection whose requests are answered one after another, in order."""

    what = "wireless"

    def __init__(self, server):
        self.server = server
        self.transport: asyncio.Transport | None = None
        self.peer = "?"
        self.ip = ""
        self._queue: collections.deque = collections.deque()
        self._task: asyncio.Task | None = None
        self._warned: set[str] = set()
        self._writable = asyncio.Event()  # cleared while the client does not read its replies
        self._writable.set()
        self._gate = ReadGate(MAX_QUEUED)

    def connection_made(self, transport) -> None:
        self.transport = transport
        peer = transport.get_extra_info("peername")
        if isinstance(peer, tuple):
            self.ip, self.peer = str(peer[0]), f"{peer[0]}:{peer[1]}"
        limit = self.server.max_connections
        if len(self.server.connections) >= limit:
            log.warning("%s %s: refused: %d connections already (limit --max-wireless-connections %d)",
                        self.what, self.peer, len(self.server.connections), limit)
            transport.close()
            return
        self.server.connections.add(self)
        log.info("%s %s: connected", self.what, self.peer)

    def connection_lost(self, exc) -> None:
        if self not in self.server.connections:
            return
        self.server.connections.discard(self)
        if self._task is not None:
            self._task.cancel()
        self._queue.clear()
        log.info("%s %s: disconnected", self.what, self.peer)
        self.closed()

    def closed(self) -> None:
        """The client went away."""

    def split(self, data: bytes) -> list[str]:
        raise NotImplementedError

    async def handle(self, request: str) -> None:
        raise NotImplementedError

    def data_received(self, data: bytes) -> None:
        if self not in self.server.connections:
            return
        self._queue.extend(self.split(data))
        if self._gate.queued(self.transport, len(self._queue)):
            self.log_once("flood", "more than %d requests waiting; reading paused until they are answered",
                          MAX_QUEUED)
        if self._queue and (self._task is None or self._task.done()):
            self._task = asyncio.get_running_loop().create_task(self._work())

    def pause_writing(self) -> None:
        self._writable.clear()

    def resume_writing(self) -> None:
        self._writable.set()

    async def _work(self) -> None:
        while self._queue:
            # a client that does not read its replies is not answered further until it does,
            # so that its unread replies stay bounded (asyncio's high-water mark)
            await self._writable.wait()
            req = self._queue.popleft()
            self._gate.taken(self.transport, len(self._queue))
            try:
                await self.handle(req)
            except asyncio.CancelledError:
                raise
            except Exception:  # nothing a client sends may take the server down
                log.exception("%s %s: error while handling %.200r", self.what, self.peer, req)

    def write(self, text: str) -> None:
        if self.transport is not None and not self.transport.is_closing():
            self.transport.write(text.encode("ascii", "replace"))

    def log_once(self, key: str, fmt: str, *args) -> None:
        """The first problem of each kind at WARNING, once; past MAX_LOGGED_KINDS kinds (ever
        new garbage) only a note that more follow, so that the log and this set stay bounded."""
        if key in self._warned:
            return
        if len(self._warned) >= MAX_LOGGED_KINDS:
            key, fmt, args = "(more)", "more than %d kinds of problem; further ones are not logged", \
                (MAX_LOGGED_KINDS,)
            if key in self._warned:
                return
        self._warned.add(key)
        log.warning("%s %s: " + fmt + " (logged once per connection)", self.what, self.peer, *args)


class _LineConnection(_Connection):
    """Requests are text lines (brace syntax, CR LF)."""

    def __init__(self, server):
        super().__init__(server)
        self._lines = LineBuffer(max_line_bytes=4096)

    def split(self, data: bytes) -> list[str]:
        before = self._lines.dropped_lines
        lines = self._lines.feed(data)
        if self._lines.dropped_lines != before:
            self.log_once("too-long", "dropped a line longer than %d bytes", self._lines.max_line_bytes)
        return lines

    def parse(self, line: str):
        """The line's type and segments, or None (logged once) when it is malformed."""
        try:
            return parse_line(line)
        except ProtocolError as exc:
            self.log_once("malformed", "%s", exc)
            return None


class _Listener(TcpListener):
    """A TCP server of one kind of :class:`_Connection`."""

    def __init__(self, factory, owner, host: str, port: int, max_connections: int):
        super().__init__(host, port)
        self._factory = factory
        self.owner = owner  # the server the connections serve
        self.max_connections = max_connections

    def make_protocol(self):
        return self._factory(self)


class _WirelessServer:
    """One of the three servers: its listener of ``connection`` objects and its port."""

    connection: type[_Connection]

    def __init__(self, service: "WirelessService", host: str, port: int, max_connections: int):
        self.service = service
        self.listener = _Listener(self.connection, self, host, port, max(1, max_connections))

    @property
    def port(self) -> int:
        return self.listener.port

    async def start(self) -> int:
        return await self.listener.start()

    async def stop(self) -> None:
        await self.listener.stop()


# --------------------------------------------------------------------------- ComServer


def _skip_space(buf: bytearray) -> None:
    """Drop the blanks and line breaks at the start of ``buf``."""
    i = 0
    while i < len(buf) and buf[i] in b" \t\r\n":
        i += 1
    del buf[:i]


class SendParser:
    """The framing of a relayed ComServer link (manual 3.2.4.3): ``SEND <n> <n bytes>;``
    (binary-safe) and ``CLOSE;``, both words case-sensitive; whitespace between frames is
    skipped.  ``feed`` returns the events the bytes complete: a message (bytes), ``CLOSE``,
    or an error text for a frame that was dropped (the parser then skips to the next ``;``).
    A SEND whose length does not end at a ``;`` is dropped whole, never delivered in part."""

    CLOSE = "CLOSE"

    def __init__(self, max_bytes: int = MAX_SEND_BYTES):
        self.max_bytes = max_bytes
        self._buf = bytearray()
        self._state = "head"
        self._digits = b""
        self._need = 0
        self._body = bytearray()

    def feed(self, data: bytes) -> list:
        """The messages completed by ``data``: payload bytes, CLOSE, or the text of a problem."""
        buf = self._buf
        buf += data
        out: list = []
        while True:
            st = self._state
            if st == "head":
                _skip_space(buf)
                if not buf:
                    break
                head = bytes(buf[:5])
                if head == b"SEND ":
                    del buf[:5]
                    self._state, self._digits = "length", b""
                elif head == b"CLOSE":
                    del buf[:5]
                    self._state = "close"
                elif len(head) < 5 and (b"SEND ".startswith(head) or b"CLOSE".startswith(head)):
                    break
                else:
                    out.append(f"unknown message {head!r}...")
                    self._state = "skip"
            elif st == "length":
                i = 0
                while i < len(buf) and 48 <= buf[i] <= 57 and len(self._digits) + i < 10:
                    i += 1
                self._digits += bytes(buf[:i])
                del buf[:i]
                if not buf:
                    break
                if buf[0] == 32 and self._digits:
                    del buf[:1]
                    n = int(self._digits)
                    if n > self.max_bytes:
                        out.append(f"SEND of {n} bytes, more than {self.max_bytes}")
                        self._state = "skip"
                    else:
                        self._need, self._body = n, bytearray()
                        self._state = "body"
                else:
                    out.append("SEND without a length")
                    self._state = "skip"
            elif st == "body":
                take = min(self._need, len(buf))
                self._body += buf[:take]
                del buf[:take]
                self._need -= take
                if self._need:
                    break
                self._state = "end"
            elif st == "end":
                if not buf:
                    break
                if buf[0] == 59:  # ;
                    del buf[:1]
                    out.append(bytes(self._body))
                    self._state = "head"
                else:
                    out.append(f"SEND of {len(self._body)} bytes not followed by ';' (a wrong length)")
                    self._state = "skip"
                self._body = bytearray()
            elif st == "close":
                _skip_space(buf)
                if not buf:
                    break
                if buf[0] == 59:
                    del buf[:1]
                    out.append(self.CLOSE)
                    self._state = "head"
                else:
                    out.append("CLOSE not followed by ';'")
                    self._state = "skip"
            else:  # skip to the next ';'
                j = buf.find(b";")
                if j < 0:
                    buf.clear()
                    break
                del buf[:j + 1]
                self._state = "head"
        return out

    @property
    def partial(self) -> bool:
        """A frame was begun and not finished."""
        return self._state != "head" or bool(self._buf)


class _LinkEnd(asyncio.Protocol):
    """The ComServer's connection to one robot of a link."""

    def __init__(self, robot: str):
        self.robot = robot
        self.link: WcsLink | None = None
        self.transport: asyncio.Transport | None = None
        self.parser = SendParser()
        self._warned: set[str] = set()

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
            elif ev == SendParser.CLOSE:
                link.close(f"CLOSE from {self.robot}")
                return
            elif ev.split(" ", 1)[0] not in self._warned:
                self._warned.add(ev.split(" ", 1)[0])
                log.warning("comserver link %s: from %s: %s; dropped (logged once)", link.name, self.robot, ev)

    def connection_lost(self, exc) -> None:
        if self.link is not None:
            partial = " in the middle of a message" if self.parser.partial else ""
            self.link.close(f"{self.robot} closed its connection{partial}")

    def pause_writing(self) -> None:
        other = self.link.other(self) if self.link is not None else None
        if other is not None and other.transport is not None:
            other.transport.pause_reading()

    def resume_writing(self) -> None:
        other = self.link.other(self) if self.link is not None else None
        if other is not None and other.transport is not None and not other.transport.is_closing():
            other.transport.resume_reading()


class WcsLink:
    """A link the ComServer opened between two robots: what one robot SENDs, the other
    receives, while the radio link holds."""

    def __init__(self, server: "ComServer", a: _LinkEnd, b: _LinkEnd, opened_at: float):
        self.server = server
        self.ends = (a, b)
        self.pair = pair_key(a.robot, b.robot)
        self.name = f"{a.robot}-{b.robot}"
        self.opened_at = opened_at
        self.open = True
        self.relayed = 0
        for end in self.ends:
            end.link = self

    def start(self) -> None:
        for end in self.ends:
            if end.transport is not None and not end.transport.is_closing():
                end.transport.resume_reading()

    def other(self, end: _LinkEnd) -> _LinkEnd:
        return self.ends[1] if end is self.ends[0] else self.ends[0]

    def relay(self, src: _LinkEnd, payload: bytes) -> None:
        dst = self.other(src)
        if self.open and dst.transport is not None and not dst.transport.is_closing():
            dst.transport.write(payload)
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


class WcsConnection(_Connection):
    """A ComServer command connection: ``;``-terminated commands, words separated by spaces."""

    what = "comserver"

    def __init__(self, server):
        super().__init__(server)
        self._buf = bytearray()
        self._dropping = False

    def split(self, data: bytes) -> list[str]:
        out = []
        self._buf += data
        while True:
            j = self._buf.find(b";")
            if j < 0:
                if len(self._buf) > MAX_COMMAND_BYTES:
                    self._buf.clear()
                    if not self._dropping:
                        self._dropping = True
                        self.log_once("too-long", "dropped a command longer than %d bytes", MAX_COMMAND_BYTES)
                break
            text = self._buf[:j].decode("ascii", "replace")
            del self._buf[:j + 1]
            if self._dropping:  # the end of an over-long command
                self._dropping = False
                continue
            if len(text) > MAX_COMMAND_BYTES:
                self.log_once("too-long", "dropped a command longer than %d bytes", MAX_COMMAND_BYTES)
                continue
            out.append(text)
        return out

    async def handle(self, text: str) -> None:
        words = text.split()
        if not words:
            return
        srv: ComServer = self.server.owner
        cmd = words[0].upper()
        if cmd not in ("REGISTER", "LISTEN", "OPEN", "GETSS"):
            self.log_once("unknown", "unknown message %.80r", text.strip())
            self.write("Fail: Unknown Message;")
            return
        if len(words) != (5 if cmd == "OPEN" else 3):
            self.log_once(f"incorrect-{cmd}", "%s with %d words: %.80r", cmd, len(words), text.strip())
            self.write("Fail: Incorrect Message;")
            return
        if cmd == "REGISTER":
            self.write(srv.register(words[1], words[2]))
        elif cmd == "LISTEN":
            self.write(srv.listen(words[1], words[2]))
        elif cmd == "OPEN":
            self.write(await srv.open(words[1], words[2], words[3], words[4]))
        else:
            self.write(await srv.getss(words[1], words[2], self.ip))


class ComServer(_WirelessServer):
    """The WCS (protocol.md 12.1): robots register, listen and open links through it."""

    connection = WcsConnection

    def __init__(self, service: WirelessService, *, host: str = "127.0.0.1", port: int = WCS_PORT,
                 max_connections: int = MAX_CONNECTIONS):
        super().__init__(service, host, port, max_connections)
        self.registered: dict[str, str] = {}  # robot name -> the IP its client listens on
        self.listening: dict[tuple[str, int], None] = {}  # (robot, port) waiting for a link, in order
        self.links: set[WcsLink] = set()
        service.subscribers.append(self._on_pair)

    async def stop(self) -> None:
        await super().stop()
        for link in list(self.links):
            link.close("server stopping")

    def _on_pair(self, pair: Pair, up: bool, time: float) -> None:
        if up:
            return
        for link in [ln for ln in self.links if ln.pair == pair and time >= ln.opened_at]:
            link.close(f"signal below the cutoff at t={time:.3f}")

    # commands ---------------------------------------------------------------------------
    def register(self, name: str, ip: str) -> str:
        known = self.registered.get(name)
        if known is not None and known != ip:
            return f"Fail: Robot with name {name} already registered;"
        if known is None and len(self.registered) >= MAX_REGISTERED:
            log.warning("comserver: REGISTER %.80s refused: %d robots registered already", name, MAX_REGISTERED)
            return "Fail: Too many robots registered;"
        self.registered[name] = ip
        self.service.event("comserver: %s registered at %s", name, ip)
        return "OK;"

    def listen(self, name: str, port_text: str) -> str:
        if name not in self.registered:
            return f"Fail: Robot {name} not registered;"
        port = _port(port_text)
        if port is None:
            return "Fail: Incorrect Message;"
        if (name, port) in self.listening:
            return f"Fail: Robot with name {name} already listening at port {port};"
        if len(self.listening) >= MAX_LISTENING:
            log.warning("comserver: LISTEN %.80s %d refused: %d ports listening already", name, port, MAX_LISTENING)
            return "Fail: Too many robots listening;"
        self.listening[(name, port)] = None
        return "OK;"

    async def open(self, a: str, pa_text: str, b: str, pb_text: str) -> str:
        """OPEN a pa b pb: ``b`` must be listening on ``pb`` (the entry is used up by the
        link, as in USARSim's ComServer); the server connects to both robots' ports."""
        pa, pb = _port(pa_text), _port(pb_text)
        if pa is None or pb is None:
            return "Fail: Incorrect Message;"
        if (b, pb) not in self.listening:
            return f"Fail: {b} not listening on port {pb};"
        if a not in self.registered:
            return f"Fail: Robot {a} not registered;"
        if a.lower() == b.lower():
            return f"Fail: Cannot connect to {b};"
        if len(self.links) >= MAX_LINKS:  # two sockets each: keep file descriptors for the rest
            log.warning("comserver: OPEN %.80s -> %.80s refused: %d links open already", a, b, MAX_LINKS)
            return "Fail: Could not establish connection;"
        svc = self.service
        pair = pair_key(a, b)
        svc.watch(pair)  # while the link is being set up
        try:
            t, ln = await svc.check(a, b)
            if ln is None or not ln.holds:
                svc.event("comserver: %s - %s out of range (%s)", a, b, "no such robot" if ln is None else
                          f"{ln.signal_dbm:.2f} dBm, {ln.walls} walls, {ln.distance_m:.2f} m")
                return f"Fail: Cannot connect to {b};"
            ends = await self._connect((a, self.registered[a], pa), (b, self.registered[b], pb))
            if ends is None:
                return "Fail: Could not establish connection;"
            if (b, pb) not in self.listening or svc.down_since(pair, t):
                for end in ends:
                    end.transport.close()
                return f"Fail: Cannot connect to {b};" if svc.down_since(pair, t) else \
                    f"Fail: {b} not listening on port {pb};"
            del self.listening[(b, pb)]
            link = WcsLink(self, ends[0], ends[1], t)
            svc.watch(pair)  # for as long as the link lives
            self.links.add(link)
            link.start()
            svc.event("comserver link %s opened at t=%.3f (%.2f dBm)", link.name, t, ln.signal_dbm)
            return "OK;"
        finally:
            svc.unwatch(pair)

    async def _connect(self, *targets: tuple[str, str, int]) -> tuple[_LinkEnd, ...] | None:
        loop = asyncio.get_running_loop()

        async def one(robot, ip, port):
            _, end = await asyncio.wait_for(loop.create_connection(lambda: _LinkEnd(robot), ip, port),
                                            CONNECT_TIMEOUT_S)
            return end

        results = await asyncio.gather(*(one(*t) for t in targets), return_exceptions=True)
        if all(isinstance(r, _LinkEnd) for r in results):
            return tuple(results)
        for r, (robot, ip, port) in zip(results, targets):
            if isinstance(r, _LinkEnd):
                r.transport.close()
            else:
                self.service.event("comserver: cannot connect to %s at %s:%d: %s", robot, ip, port, r)
        return None

    async def getss(self, a: str, b: str, peer_ip: str) -> str:
        """GETSS a b: only from the IP of one of the two robots (USARSim's rule)."""
        ips = {_same_host(self.registered.get(a)), _same_host(self.registered.get(b))}
        if _same_host(peer_ip) not in ips:
            return "Fail: Server does not accept third party requests;"
        ln = await self.service.signal(a, b)
        if ln is None or not math.isfinite(ln.signal_dbm):
            return "Fail: Could not calculate signal strength;"
        return f"OK:{_fmt_wcs_dbm(ln.signal_dbm)};"


def _same_host(ip: str | None) -> str | None:
    if ip is None:
        return None
    return "127.0.0.1" if ip in ("localhost", "::1", "::ffff:127.0.0.1") else ip


# --------------------------------------------------------------------------- WSS


class _PipeEnd(asyncio.Protocol):
    def __init__(self, pipe: "Pipe"):
        self.pipe = pipe
        self.peer: _PipeEnd | None = None
        self.transport: asyncio.Transport | None = None

    def connection_made(self, transport) -> None:
        self.transport = transport
        transport.pause_reading()  # until both ends are connected (Pipe.start)

    def data_received(self, data: bytes) -> None:
        peer = self.peer
        if peer is not None and peer.transport is not None and not peer.transport.is_closing():
            peer.transport.write(data)

    def eof_received(self):
        return False  # closes the pipe: the WSS closes both sockets

    def connection_lost(self, exc) -> None:
        self.pipe.close()

    def pause_writing(self) -> None:
        if self.peer is not None and self.peer.transport is not None:
            self.peer.transport.pause_reading()

    def resume_writing(self) -> None:
        if self.peer is not None and self.peer.transport is not None and not self.peer.transport.is_closing():
            self.peer.transport.resume_reading()


class Pipe:
    """One connection through a relay port: the robot that connected, and the server's
    own connection to the destination robot's listening port."""

    def __init__(self, port: "RelayPort", sock: socket.socket):
        self.port = port
        self.sock = sock  # the accepted connection, until its transport takes it
        self.ends: list[_PipeEnd] = []
        self.closed = False
        self.out_port = 0

    async def start(self, dst_ip: str, dst_port: int) -> None:
        loop = asyncio.get_running_loop()
        try:
            _, src = await loop.connect_accepted_socket(lambda: _PipeEnd(self), self.sock)
        except OSError:
            self.close()
            return
        self.ends.append(src)
        if self.closed:
            src.transport.close()
            return
        try:
            dst_t, dst = await asyncio.wait_for(loop.create_connection(lambda: _PipeEnd(self), dst_ip, dst_port),
                                                CONNECT_TIMEOUT_S)
        except (OSError, asyncio.TimeoutError) as exc:
            self.port.server.service.event("wss: cannot connect to %s at %s:%d: %s", self.port.dst, dst_ip,
                                           dst_port, exc)
            self.close()
            return
        self.ends.append(dst)
        if self.closed:
            dst_t.close()
            return
        self.out_port = dst_t.get_extra_info("sockname")[1]
        self.port.server.outgoing[self.out_port] = self.port
        src.peer, dst.peer = dst, src
        src.transport.resume_reading()
        dst_t.resume_reading()

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        if not self.ends:
            self.sock.close()
        for end in self.ends:
            if end.transport is not None:
                end.transport.close()
        self.port.pipes.discard(self)
        if self.out_port:
            self.port.server.outgoing.pop(self.out_port, None)


class RelayPort:
    """The WSS's port for one ordered robot pair (and one listening port of the
    destination): it listens while the link holds and refuses connections otherwise,
    always under the same number."""

    def __init__(self, server: "WssServer", src: str, dst: str, dst_port: int):
        self.server = server
        self.src, self.dst, self.dst_port = src, dst, dst_port
        self.pair = pair_key(src, dst)
        self.number = 0
        self.up = False
        self.checked_at = 0.0
        self.pipes: set[Pipe] = set()
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
        if up and not self._listening:
            if self._sock is None:
                try:
                    self._bind()
                except OSError as exc:
                    log.error("wss: cannot listen again on relay port %d (%s -> %s): %s", self.number, self.src,
                              self.dst, exc)
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

    def _accept(self) -> None:
        for _ in range(16):
            try:
                conn, addr = self._sock.accept()
            except (BlockingIOError, InterruptedError):
                return
            except OSError:
                return
            robot = self.server.robots.get(self.src)
            dst = self.server.robots.get(self.dst)
            if not self.up or robot is None or dst is None or _same_host(addr[0]) != _same_host(robot.ip):
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

    def close(self) -> None:
        for pipe in list(self.pipes):
            pipe.close()
        self._release()


class WssRobot:
    def __init__(self, name: str, ip: str, ports: list[int], conn: "WssConnection"):
        self.name, self.ip, self.ports, self.conn = name, ip, ports, conn


class WssConnection(_LineConnection):
    """A robot's control connection to the WSS (protocol.md 12.2)."""

    what = "wss"

    def __init__(self, server):
        super().__init__(server)
        self.robot: WssRobot | None = None

    def closed(self) -> None:
        if self.robot is not None:
            self.server.owner.unregister(self.robot)

    async def handle(self, line: str) -> None:
        srv: WssServer = self.server.owner
        raw = self.parse(line)
        kind = raw.type if raw is not None else ""
        if self.robot is None:
            if kind != "INIT":
                self.write("ERROR {Reason Must.Use.INIT.Method.First}\r\n")
                return
            name = (raw.get("Robot") or "").strip()
            ports = []
            for p in (raw.get("Port") or "").replace(" ", "").split(","):
                if p:
                    v = _port(p)
                    if v is None:
                        self.write("ERROR {Reason Ports.List.Must.Be.Integer}\r\n")
                        return
                    ports.append(v)
            if not name:
                self.write("ERROR {Reason Robot.Name.Must.Not.Be.Empty}\r\n")
            elif name in srv.robots:
                self.write("ERROR {Reason Robot.Alread.Exists}\r\n")  # sic, the WSS's words
            else:
                self.robot = WssRobot(name, self.ip, ports, self)
                srv.robots[name] = self.robot
                srv.service.event("wss: %s registered at %s, ports %s", name, self.ip, ports)
                self.write("INITREPLY {Status OK}\r\n")
            return
        me = self.robot.name
        if kind == "GETSS":
            other = (raw.get("Robot") or "").strip()
            if not other:
                self.write("ERROR {Reason Robot.Name.Must.Not.Be.Empty}\r\n")
                return
            error = ""
            if other == me:
                strength, error = "INF", "SS.To.Self"
            elif other not in srv.robots:
                strength, error = "NaN", "Robot.Does.Not.Exist"
            else:
                ln = await srv.service.signal(me, other)
                if ln is None or not math.isfinite(ln.signal_dbm) or ln.signal_dbm > 0:
                    strength, error = "NaN", "Model.Returned.NaN"
                else:
                    strength = _fmt_wss_dbm(ln.signal_dbm)
            self.write(f"SS {{Robot {other}}} {{Strength {strength}}}" + (f" {{Error {error}}}" if error else "")
                       + "\r\n")
        elif kind == "DNS":
            other = (raw.get("Robot") or "").strip()
            want = 0
            if raw.has("Port"):
                v = _port(raw.get("Port") or "")
                if v is None:
                    self.write("ERROR {Reason Port.Must.Be.Integer}\r\n")
                    return
                want = v
            if not other:
                self.write("ERROR {Reason Robot.Name.Must.Not.Be.Empty}\r\n")
                return
            dst = srv.robots.get(other)
            if dst is None or other == me:
                self.write(f"DNSREPLY {{Robot {other}}} {{Port -1}} {{Error NoSuchRobot}}\r\n")
                return
            if want and want not in dst.ports:
                self.write(f"DNSREPLY {{Robot {other}}} {{Port -1}} {{Error RobotDoesNotListenOnThisPort}}\r\n")
                return
            port = await srv.relay_port(me, other, want or (dst.ports[0] if dst.ports else 0))
            if port is None:
                self.write("ERROR {Reason Could.Not.Allocate.Port}\r\n")
            else:
                self.write(f"DNSREPLY {{Robot {other}}} {{Port {port}}}\r\n")
        elif kind == "REVERSEDNS":
            v = _port(raw.get("Port") or "")
            if v is None:
                self.write("ERROR {Reason Port.Must.Be.Integer}\r\n")
                return
            who = srv.reverse_dns(me, v)
            if who is None:
                self.write(f"REVERSEDNSREPLY {{Port {v}}} {{Error UnknownOrIllegalPort}}\r\n")
            else:
                self.write(f"REVERSEDNSREPLY {{Port {v}}} {{Robot {who}}}\r\n")
        else:
            if raw is not None:
                self.log_once(f"unknown-{kind}", "unknown or repeated command %s", kind)
            self.write("ERROR {Reason Method.Unknown.Or.Can.INIT.only.once}\r\n")


class WssServer(_WirelessServer):
    """The Wireless Simulation Server (protocol.md 12.2)."""

    connection = WssConnection

    def __init__(self, service: WirelessService, *, host: str = "127.0.0.1", port: int = WSS_PORT,
                 max_connections: int = MAX_CONNECTIONS):
        super().__init__(service, host, port, max_connections)
        self.robots: dict[str, WssRobot] = {}
        self.ports: dict[tuple[str, str, int], RelayPort] = {}
        self.by_number: dict[int, RelayPort] = {}
        self.outgoing: dict[int, RelayPort] = {}  # the server's own end of each pipe -> its relay port
        self.tasks: set[asyncio.Task] = set()  # pipes being connected
        service.subscribers.append(self._on_pair)

    async def stop(self) -> None:
        await super().stop()
        for rp in list(self.ports.values()):
            rp.close()
        self.ports.clear()
        self.by_number.clear()
        for task in list(self.tasks):
            task.cancel()
        if self.tasks:
            await asyncio.gather(*self.tasks, return_exceptions=True)

    def _on_pair(self, pair: Pair, up: bool, time: float) -> None:
        for rp in list(self.ports.values()):
            if rp.pair == pair and time >= rp.checked_at and rp.up != up:
                rp.set_up(up, time)
                self.service.event("wss relay port %d (%s -> %s) %s", rp.number, rp.src, rp.dst,
                                   "listening" if up else "refusing connections")

    async def relay_port(self, src: str, dst: str, dst_port: int) -> int | None:
        key = (src, dst, dst_port)
        rp = self.ports.get(key)
        if rp is not None:
            return rp.number
        if not dst_port:
            return None
        if len(self.ports) >= MAX_RELAY_PORTS:  # each is a listening socket: keep file descriptors for the rest
            log.warning("wss: no relay port for %s -> %s:%d: %d allocated already", src, dst, dst_port,
                        MAX_RELAY_PORTS)
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
        self.service.event("wss relay port %d for %s -> %s:%d (%s)", rp.number, src, dst, dst_port,
                           "listening" if up else "link down")
        return rp.number

    def reverse_dns(self, me: str, port: int) -> str | None:
        """The robot at the other end of ``port``: the server's end of a pipe into ``me``
        (the peer port of a connection ``me`` accepted), or a relay port of ``me``."""
        rp = self.outgoing.get(port)
        if rp is not None and rp.dst == me:
            return rp.src
        rp = self.by_number.get(port)
        if rp is not None and me in (rp.src, rp.dst):
            return rp.dst if rp.src == me else rp.src
        return None

    def unregister(self, robot: WssRobot) -> None:
        if self.robots.get(robot.name) is not robot:
            return
        del self.robots[robot.name]
        for key, rp in list(self.ports.items()):
            if robot.name in (rp.src, rp.dst):
                rp.close()
                del self.ports[key]
                self.by_number.pop(rp.number, None)
                self.service.unwatch(rp.pair)
        self.service.event("wss: %s left", robot.name)


# --------------------------------------------------------------------------- ComServerInterface


class InterfaceConnection(_LineConnection):
    """``GETPOS`` and ``GETOBS`` (protocol.md 12.3)."""

    what = "cominterface"

    async def handle(self, line: str) -> None:
        raw = self.parse(line)
        if raw is None:
            return
        svc: WirelessService = self.server.owner.service
        if raw.type == "GETPOS":
            rows = await svc.ask(RadioNet.positions)
            parts = [f"POSITIONS {{Robots {len(rows)}}}"]
            parts += [f"{{Name {n} Location {vec4(loc)} BatteryEmpty {'True' if empty else 'False'}}}"
                      for n, loc, empty in rows]
            self.write(" ".join(parts) + "\r\n")
        elif raw.type == "GETOBS":
            a, b = raw.get("From"), raw.get("To")
            start, end = raw.get("Start"), raw.get("End")
            if a and b:
                n = await svc.ask(lambda sim: RadioNet.walls_between_robots(sim, a, b))
                self.write(f"NUMOBS {{From {a}}} {{To {b}}} {{ObstCount {n}}}\r\n")
            elif start and end:
                try:
                    p, q = parse_vector(start), parse_vector(end)
                    if not all(math.isfinite(v) for v in p + q):
                        raise ProtocolError("not finite")
                except ProtocolError as exc:
                    self.log_once("getobs-vector", "GETOBS with a bad Start or End: %s", exc)
                    n = -1
                else:
                    n = await svc.ask(lambda sim: RadioNet.walls_between(sim, p, q))
                self.write(f"NUMOBS {{Start {start}}} {{End {end}}} {{ObstCount {n}}}\r\n")
            else:
                self.log_once("getobs", "GETOBS needs {From r} {To r} or {Start x,y,z} {End x,y,z}")
                self.write("NUMOBS {ObstCount -1}\r\n")
        else:
            self.log_once(f"unknown-{raw.type}", "unknown command %s; ignored", raw.type)


class ComInterfaceServer(_WirelessServer):
    """The ComServerInterface (protocol.md 12.3): robot positions and walls between two points."""

    connection = InterfaceConnection

    def __init__(self, service: WirelessService, *, host: str = "127.0.0.1", port: int = INTERFACE_PORT,
                 max_connections: int = MAX_CONNECTIONS):
        super().__init__(service, host, port, max_connections)


# --------------------------------------------------------------------------- together


class WirelessServers:
    """The three servers and what they share, as one ``usarsim serve`` runs them."""

    def __init__(self, facade: SimFacade, options: WirelessOptions, *, host: str = "127.0.0.1"):
        model = resolve_model(facade.world.wireless, options.config, model=options.model)
        self.service = WirelessService(facade, model, debug=options.debug)
        limit = options.max_connections
        self.comserver = ComServer(self.service, host=host, port=options.wcs_port, max_connections=limit)
        self.wss = WssServer(self.service, host=host, port=options.wss_port, max_connections=limit)
        self.interface = ComInterfaceServer(self.service, host=host, port=options.interface_port,
                                            max_connections=limit)
        log.info("wireless: radio model %s", model.describe())

    def servers(self) -> list[tuple[Any, str, str]]:
        """(server, listener name, what names its port in an error)."""
        return [(self.comserver, "comserver", "the ComServer port %s (--wcs-port)"),
                (self.wss, "wss", "the WSS port %s (--wss-port)"),
                (self.interface, "cominterface", "the ComServerInterface port %s (--cominterface-port)")]

    def bind_loop(self) -> None:
        self.service.loop = asyncio.get_running_loop()
