"""What the three wireless servers share (protocol.md 12): the radio links, asked of the
simulation through the facade and followed as simulated time passes, and the connection
and listener bases of the three servers (their limits, log-once and backpressure are
:class:`~usarsim.server.connection.ServerConnection`'s, as on every port).

Link state follows simulated time: the facade computes the signal on the simulation
thread from the simulated poses when a link is opened or a relay port allocated
(:meth:`WirelessService.check`), and after every advance of the clock (every STEP in
lock-step) for the pairs the servers depend on (:meth:`WirelessService.watch`); the
changes come back to the event loop and on to each server's subscriber, so that a link
whose signal falls below the cutoff is closed before anything else happens at that
instant (in lock-step, before the STEPPED reply), and nothing is relayed on it after.
"""

from __future__ import annotations

import asyncio
import collections
import logging
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass
from typing import Any, TypeVar

from usarsim.config.channel import ChannelConfig
from usarsim.config.world import WirelessConfig
from usarsim.errors import ProtocolError
from usarsim.protocol.framing import LineBuffer
from usarsim.protocol.wireless import INTERFACE_PORT, WCS_PORT, WSS_PORT
from usarsim.server.connection import ServerConnection
from usarsim.server.listener import TcpListener, call_on_loop
from usarsim.sim.api import Facade
from usarsim.sim.types import LATER, Channel, Link, LinkCounts, LinkView, Pair, RadioModel, pair_key

T = TypeVar("T")

log = logging.getLogger("usarsim.wireless")

CONNECT_TIMEOUT_S = 5.0
"""Wall-clock limit on a server's own connection to a robot's listening port."""
MAX_QUEUED = 256
"""Requests of one connection waiting to be answered; beyond them its socket is not read
until they are answered."""
MAX_CONNECTIONS = 64
"""Connections per server at most (``usarsim serve --max-wireless-connections``)."""
MAX_LINE_BYTES = 4096
"""Longest request line of the WSS and the ComServerInterface; a longer one is dropped."""


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


def same_host(ip: str | None) -> str | None:
    """``ip`` with the spellings of the local host made one, to compare addresses."""
    if ip is None:
        return None
    return "127.0.0.1" if ip in ("localhost", "::1", "::ffff:127.0.0.1") else ip


class WirelessService:
    """What the three servers share: the radio links (computed by the facade on the
    simulation thread), the pairs the servers depend on, the latest state reported for
    each pair, and the servers that follow the changes (``subscribers``)."""

    def __init__(self, facade: Facade, model: RadioModel, *, channel: ChannelConfig | None = None, debug: bool = False):
        self.facade = facade
        self.model = model
        self.debug = debug
        self.channel = channel if channel is not None else ChannelConfig()
        # the ideal channel (USARSim's): servers relay what robots send at once, while the link holds
        self.ideal = self.channel.ideal
        # the messages under way (None: the ideal channel), driven here on the event loop by the
        # links the simulation thread computes (_views_threadsafe)
        self._carrier: Channel | None = facade.open_radio(  # before the simulation thread starts
            model,
            self._changes_threadsafe,
            channel=self.channel,
            on_views=None if self.ideal else self._views_threadsafe,
        )
        self.now = 0.0  # the simulated time of the latest links the channel was given
        self.loop: asyncio.AbstractEventLoop | None = None
        self.state: dict[Pair, tuple[float, bool]] = {}  # pair -> (simulated time, holds)
        self.subscribers: list[Callable[[Pair, bool, float], None]] = []
        self._refs: collections.Counter[Pair] = collections.Counter()

    def event(self, fmt: str, *args) -> None:
        """A link event: logged at INFO with bDebug, at DEBUG otherwise."""
        log.log(logging.INFO if self.debug else logging.DEBUG, fmt, *args)

    # pairs ------------------------------------------------------------------------------
    def watch(self, pair: Pair) -> None:
        """One more thing (a link, a relay port, a link being opened) depends on ``pair``."""
        self._refs[pair] += 1
        if self._refs[pair] == 1:
            self.facade.radio_watch(frozenset(self._refs))

    def unwatch(self, pair: Pair) -> None:
        """One thing less depends on ``pair``; with none left it is no longer evaluated."""
        self._refs[pair] -= 1
        if self._refs[pair] <= 0:
            del self._refs[pair]
            self.state.pop(pair, None)
            self.facade.radio_watch(frozenset(self._refs))

    def _changes_threadsafe(self, time: float, changes: list[tuple[Pair, bool]]) -> None:
        """The facade's ``on_change`` (simulation thread): handed to the event loop."""
        call_on_loop(self.loop, self._apply, time, changes)

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

    # messages ---------------------------------------------------------------------------
    def send(self, src: str, dst: str, payload: bytes, deliver: Callable[[bytes], object]) -> None:
        """Carry ``payload`` from robot ``src`` to robot ``dst`` through the channel (not the
        ideal one), handed over at the simulated time of the latest links (:attr:`now`):
        ``deliver(payload)`` is called on the event loop when it arrives, never if it is lost."""
        assert self._carrier is not None, "the ideal channel relays at once"
        drop = self._carrier.submit(self.now, src, dst, payload, deliver)
        if drop is not None:
            self.event("message %s -> %s (%d bytes) dropped: %s", drop.src, drop.dst, drop.nbytes, drop.cause)

    def _views_threadsafe(self, time: float, views: dict[Pair, LinkView | None]) -> None:
        """The facade's ``on_views`` (simulation thread): handed to the event loop."""
        call_on_loop(self.loop, self._due, time, views)

    def _due(self, time: float, views: dict[Pair, LinkView | None]) -> None:
        """The links at ``time``: what the channel delivers and drops by then, judged by them."""
        assert self._carrier is not None
        self.now = max(self.now, time)

        def view(src: str, dst: str) -> LinkView | None:
            return views.get(pair_key(src, dst), LATER)

        deliveries, drops = self._carrier.due(time, view)
        for d in deliveries:
            try:
                d.token(d.payload)
            except Exception:
                log.exception("wireless: error while delivering a message")
        for x in drops:
            self.event("message %s -> %s (%d bytes) dropped at t=%.3f: %s", x.src, x.dst, x.nbytes, x.at, x.cause)

    async def counts(self) -> dict[tuple[str, str], LinkCounts]:
        """What each link carried through the channel so far (sender, receiver)."""
        return await self.ask(self.facade.radio_counts)

    def down_since(self, pair: Pair, time: float) -> bool:
        """Whether the pair was reported down at or after ``time``."""
        st = self.state.get(pair)
        return st is not None and st[0] >= time and not st[1]

    # the simulation ----------------------------------------------------------------------
    async def ask(self, method: Callable[..., Future[T]], *args) -> T:
        """The result of ``method(*args)``, a facade method whose future is settled on the
        simulation thread (at once, also in lock-step), awaited on the event loop."""
        return await asyncio.wrap_future(method(*args))

    async def check(self, a: str, b: str) -> tuple[float, Link | None]:
        """(simulated time, link) for a link about to be opened; its state is reported."""
        return await self.ask(self.facade.radio_check, a, b)

    async def neighbours(self, a: str) -> list[tuple[str, Link, float]]:
        """Every robot whose link with ``a`` holds now: (name, link, quality)."""
        return await self.ask(self.facade.radio_neighbours, a)

    async def signal(self, a: str, b: str) -> Link | None:
        """The link between two robots now (None: either is not in the simulation)."""
        return await self.ask(self.facade.radio_link, a, b)

    async def positions(self) -> list[tuple[str, tuple[float, float, float], bool]]:
        """(name, location, battery empty) of every robot."""
        return await self.ask(self.facade.robot_positions)

    async def walls_between_robots(self, a: str, b: str) -> int:
        """Walls between two robots (-1: either is unknown)."""
        return await self.ask(self.facade.walls_between_robots, a, b)

    async def walls_between(self, start, end) -> int:
        """Walls between two points of the world."""
        return await self.ask(self.facade.walls_between, start, end)


class WirelessConnection(ServerConnection):
    """A client connection of one of the servers, whose requests are answered one after
    another, in order.  Subclasses split the bytes into requests (``split``) and answer
    one (``handle``); this holds the queue, and the pause while the client does not read
    its replies; the connection limit, log-once and the queue's backpressure are the
    :class:`~usarsim.server.connection.ServerConnection`'s."""

    what = "wireless"  # names the server in log lines, before the peer address
    limit_option = "--max-wireless-connections"
    logger = log
    log_suffix = " (logged once per connection)"
    max_waiting = MAX_QUEUED

    def __init__(self, server: WirelessListener):
        super().__init__(server)
        self._queue: collections.deque = collections.deque()
        self._task: asyncio.Task | None = None
        self._resumed = asyncio.Event()  # set while the client reads its replies
        self._resumed.set()

    @property
    def owner(self):
        """The server (ComServer, WSS, ComServerInterface) this connection serves."""
        return self.server.owner

    def connection_lost(self, exc) -> None:
        if self._task is not None:
            self._task.cancel()
        self._queue.clear()
        super().connection_lost(exc)

    def split(self, data: bytes) -> list[str]:
        """The requests ``data`` completes."""
        raise NotImplementedError

    async def handle(self, request: str) -> None:
        """Answer one request."""
        raise NotImplementedError

    def data_received(self, data: bytes) -> None:
        if not self.accepted:
            return
        self._queue.extend(self.split(data))
        self.queued(len(self._queue))
        if self._queue and (self._task is None or self._task.done()):
            self._task = asyncio.get_running_loop().create_task(self._work())

    def pause_writing(self) -> None:
        super().pause_writing()
        self._resumed.clear()

    def writing_resumed(self) -> None:
        self._resumed.set()

    async def _work(self) -> None:
        while self._queue:
            # a client that does not read its replies is not answered further until it does,
            # so that its unread replies stay bounded (asyncio's high-water mark)
            await self._resumed.wait()
            req = self._queue.popleft()
            self.taken(len(self._queue))
            try:
                await self.handle(req)
            except asyncio.CancelledError:
                raise
            except Exception:  # nothing a client sends may take the server down
                log.exception("%s: error while handling %.200r", self.label, req)


class LineConnection(WirelessConnection):
    """A connection whose requests are text lines (brace syntax, CR LF): the WSS and the
    ComServerInterface."""

    def __init__(self, server: WirelessListener):
        super().__init__(server)
        self._lines = LineBuffer(max_line_bytes=MAX_LINE_BYTES)

    def split(self, data: bytes) -> list[str]:
        before = self._lines.dropped_lines
        lines = self._lines.feed(data)
        if self._lines.dropped_lines != before:
            self.log_once("too-long", "dropped a line longer than %d bytes", self._lines.max_line_bytes)
        return lines

    def parse(self, line: str, parser: Callable[[str], Any]) -> Any:
        """``parser(line)``, or None (logged once) when the line is malformed."""
        try:
            return parser(line)
        except ProtocolError as exc:
            self.log_once("malformed", "%s", exc)
            return None


class WirelessListener(TcpListener):
    """The TCP listener of one server, making its kind of :class:`WirelessConnection`."""

    def __init__(
        self, factory: type[WirelessConnection], owner: WirelessServer, host: str, port: int, max_connections: int
    ):
        super().__init__(host, port)
        self._factory = factory
        self.owner = owner  # the server the connections serve
        self.max_connections = max_connections

    def make_protocol(self) -> WirelessConnection:
        return self._factory(self)


class WirelessServer:
    """One of the three servers: its listener of ``connection`` objects and its port."""

    connection: type[WirelessConnection]

    def __init__(self, service: WirelessService, host: str, port: int, max_connections: int):
        self.service = service
        self.listener = WirelessListener(self.connection, self, host, port, max(1, max_connections))

    @property
    def port(self) -> int:
        return self.listener.port

    async def start(self) -> int:
        return await self.listener.start()

    async def stop(self) -> None:
        await self.listener.stop()
