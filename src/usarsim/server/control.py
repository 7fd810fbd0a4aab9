"""The control server (TCP 3000): one robot per connection.

asyncio glue only: bytes -> lines (protocol.framing) -> session -> simulation
facade; simulation outputs -> protocol messages -> the owning connection.

Slow readers: periodic messages (STA, SEN) are latest-wins per stream while the
socket's send buffer is above its high-water mark; replies (NFO, GEO, CONF, RES,
STEPPED) are always queued.  What every port shares (limits, log-once, flow control) is
in :mod:`usarsim.server.connection`; a flood of the same DRIVE line is cut short by the
connection's line buffer (:mod:`usarsim.protocol.framing`).
"""

from __future__ import annotations

import asyncio
import logging
import socket
import time
from asyncio.trsock import TransportSocket
from collections import deque
from typing import Any

from usarsim.protocol import messages as M
from usarsim.protocol.framing import LineBuffer
from usarsim.protocol.outputs import message_for
from usarsim.readings import PackageState
from usarsim.server.connection import ServerConnection
from usarsim.server.image import CameraBindings
from usarsim.server.listener import TcpListener
from usarsim.server.ordering import STEP_GRACE_S, StepOrder
from usarsim.server.session import ALIVE, CLOSED, NEW, SPAWNING, Session, SessionContext
from usarsim.sim.api import Facade
from usarsim.sim.types import Output

log = logging.getLogger("usarsim.server")

HIGH_WATER = 256 * 1024
# Replies unread beyond this many high-water marks: the client's further lines wait (its
# sensor lines are held latest-wins already, and its replies are never dropped).
REPLY_CAP_FACTOR = 4
# A connection's lines are handled for at most this long at a time (s); the rest wait while
# its socket is not read, so that one client flooding the port slows only itself (TCP pushes
# back on it) and never the event loop, the other clients or the physics.
LINE_BUDGET_S = 0.002
# Linux's option to acknowledge received segments at once (usarsim.server.ordering); None elsewhere
TCP_QUICKACK = getattr(socket, "TCP_QUICKACK", None)


def output_to_message(o: Output) -> Any:
    """The protocol message of a simulation output (:func:`usarsim.protocol.outputs.message_for`)."""
    return message_for(o.value, o.time)


def actuator_status(o: Output) -> M.ActuatorStatus:
    """The ASTA line of a mission package's state (UDK actuator API), sent after its MISSTA to
    clients that use that API."""
    v: PackageState = o.value
    t = o.time
    assert t is not None  # a package's state always has its time (its MISSTA was formatted first)
    return M.ActuatorStatus(time=t, name=v.name, links=v.links)


class Connection(ServerConnection):
    """A control connection: its lines go to its session, within a time budget; its
    outputs come back, the periodic ones latest-wins while the client does not read."""

    def __init__(self, server: ControlServer):
        super().__init__(server)
        self.buffer = LineBuffer(max_line_bytes=server.max_line_bytes, drop_repeated_drives=True)
        self.session: Session | None = None
        self._held: dict[str, bytes] = {}  # latest periodic line per stream while not writable
        self.dropped_periodic = 0
        self._backlog: deque[str] = deque()  # lines received, not handled yet
        self._step_out: list[bytes] = []  # outputs while a STEP runs: sent with the next reply
        self.last_read = 0.0  # time.perf_counter() of the last read (usarsim.server.ordering)
        # the socket, to acknowledge what arrives at once (TCP_QUICKACK)
        self._sock: TransportSocket | None = None

    @property
    def repeats_skipped(self) -> int:
        """Repeated DRIVE lines dropped unhandled (sending the same speeds again changes nothing)."""
        return self.buffer.repeated_drives

    # ServerConnection -------------------------------------------------------------------
    def connection_made(self, transport) -> None:
        transport.set_write_buffer_limits(high=self.server.max_pending_bytes)
        if TCP_QUICKACK is not None:
            self._sock = transport.get_extra_info("socket")
            self._quickack()
        super().connection_made(transport)

    def _quickack(self) -> None:
        """Acknowledge the next segments at once, and what arrived and is not acknowledged yet
        now: a client's Nagle algorithm then never holds a line back behind an unacknowledged
        one for the 40 ms of a delayed acknowledgement (usarsim.server.ordering).  Linux
        leaves quick-acknowledgement mode again when the server answers soon after it read
        ("ping-pong" traffic), so this is asked again after every read and every write."""
        sock = self._sock
        assert sock is not None and TCP_QUICKACK is not None  # asked only where the option is
        try:
            sock.setsockopt(socket.IPPROTO_TCP, TCP_QUICKACK, 1)
        except OSError:  # closed meanwhile
            self._sock = None

    def write(self, data: bytes) -> bool:
        sent = super().write(data)
        if self._sock is not None and sent:
            self._quickack()
        return sent

    def register(self) -> None:
        srv = self.server
        uid = srv.next_uid()
        self.session = Session(
            SessionContext(
                facade=srv.facade,
                peer=self.peer,
                emit=self.send_reply,
                threadsafe=srv.threadsafe,
                admit=srv.admit,
                robot_dirs=srv.robot_dirs,
                camera_bindings=srv.camera_bindings,
                log_once=self.log_once,
                resume=self._drain,
                step_order=srv.step_order,
                reader=self,
            ),
            uid,
        )
        srv.connections[uid] = self

    def release(self) -> None:
        assert self.session is not None  # registered
        self.server.connections.pop(self.session.uid, None)

    def opened(self) -> None:
        srv = self.server
        assert self.session is not None  # registered
        log.info("%s: connected (robot id %d)", self.peer, self.session.uid)
        self.send_reply(M.GameInfo(level=srv.facade.world_name, time_limit=srv.facade.world.time_limit_min))

    def closed(self) -> None:
        s = self.session
        assert s is not None  # registered
        if s.state != NEW:
            self.server.facade.remove(s.uid)
        s.state = CLOSED

    def writing_resumed(self) -> None:
        held, self._held = self._held, {}
        if held:
            self.write(b"".join(held.values()))
        if self._backlog:
            self._drain()

    # Input -----------------------------------------------------------------------------
    # usarsim.server.ordering.Reader ------------------------------------------------------
    def unhandled(self) -> bool:
        return bool(self._backlog) and not self.holds_step()

    def holds_step(self) -> bool:
        return self.session is not None and self.session.step_held

    def data_received(self, data: bytes) -> None:
        self.last_read = time.perf_counter()
        if self._sock is not None:
            self._quickack()
        if self.session is None:
            return
        before = self.buffer.dropped_lines
        lines = self.buffer.feed(data)
        if self.buffer.dropped_lines != before:
            self.log_once("too-long", "dropped a line longer than %d bytes", self.buffer.max_line_bytes)
        self._backlog.extend(lines)
        self._drain()

    def _drain(self) -> None:
        """Handle waiting lines within the time budget; the rest wait, the socket unread."""
        session = self.session
        if session is None or session.state == CLOSED:
            self._backlog.clear()
            return
        start = time.perf_counter()
        backlog = self._backlog
        n = 0
        while backlog:
            if session.holding:
                # a request of its own is not answered yet (an INIT, a SET, a PING...), or its
                # STEP waits for the other connections: the next lines wait (answers in order;
                # lines after a STEP are for the next one), the socket unread (the session's
                # resume drains them)
                self.gate.close(self.transport)
                return
            if (
                not self.writable
                and self.transport is not None
                and self.transport.get_write_buffer_size() > REPLY_CAP_FACTOR * self.server.max_pending_bytes
            ):
                # the client asks and asks but does not read the replies: its further lines
                # wait, its socket unread, until it reads (writing_resumed drains them)
                if self.gate.close(self.transport):
                    self.log_once(
                        "unread-replies",
                        "more than %d kB of replies unread; the next lines wait until the client reads",
                        REPLY_CAP_FACTOR * self.server.max_pending_bytes // 1024,
                    )
                return
            line = backlog.popleft()
            try:
                session.handle_line(line)
            except Exception:  # nothing a client sends may take the server down
                log.exception("%s: error while handling %.200r", self.peer, line)
            n += 1
            if n % 32 == 0 and backlog and time.perf_counter() - start > LINE_BUDGET_S:
                self.gate.close(self.transport)
                asyncio.get_running_loop().call_later(LINE_BUDGET_S / 2, self._drain)
                return
        self.gate.open(self.transport)

    # Output ----------------------------------------------------------------------------
    def send_reply(self, msg) -> None:
        data = M.format_message(msg).encode("ascii", "replace")
        if self._step_out:  # the outputs held for it first, in the same write
            self._step_out.append(data)
            data, self._step_out = b"".join(self._step_out), []
        self.write(data)

    def send_outputs(self, data: bytes) -> None:
        """The robot's outputs (sensor lines, statuses, results); while a STEP of its client
        runs they are held and sent with its STEPPED in one write: a lock-step controller reads
        them all before the STEPPED anyway, and one write to the socket costs what two do."""
        session = self.session
        if session is not None and session.steps_waiting > 0:
            self._step_out.append(data)
        else:
            self.write(data)

    def send_periodic(self, key: str, data: bytes) -> None:
        if self.writable:
            self.write(data)
        elif self.transport is not None and not self.transport.is_closing():
            if key in self._held:
                self.dropped_periodic += 1
            self._held[key] = data  # held, latest-wins


class ControlServer(TcpListener):
    """The control port's listener (protocol.md 1, TCP 3000 by default): it admits connections up to its limits, one
    robot each, and hands each connection the simulation's outputs for its robot as protocol lines."""

    def __init__(
        self,
        facade: Facade,
        *,
        host: str = "127.0.0.1",
        port: int = 3000,
        max_connections: int = 64,
        max_line_bytes: int = 8192,
        robot_dirs: tuple[str, ...] = (),
        max_pending_bytes: int = HIGH_WATER,
        max_robots: int | None = None,
        step_grace_s: float = STEP_GRACE_S,
        camera_bindings: CameraBindings | None = None,
    ):
        super().__init__(host, port)
        self.facade = facade
        self.robot_dirs = robot_dirs  # extra folders of robot files (serve --robot-dir)
        # SET {Type Camera} {Client ip}; shared with the image server
        self.camera_bindings = camera_bindings if camera_bindings is not None else CameraBindings()
        self.max_connections = max_connections
        self.max_line_bytes = max_line_bytes
        # output waiting for a slow client beyond which its sensor lines are held latest-wins
        self.max_pending_bytes = max(4096, int(max_pending_bytes))
        self.max_robots = max_connections if max_robots is None else max(0, int(max_robots))
        self.connections: dict[int, Connection] = {}  # by robot id
        self._uid = 0
        # lock-step: each STEP carried out after every line read before it (usarsim.server.ordering)
        self.step_order = StepOrder(self.connections.values, step_grace_s) if facade.lockstep else None

    def make_protocol(self) -> Connection:
        return Connection(self)

    def next_uid(self) -> int:
        self._uid += 1
        return self._uid

    def admit(self) -> str | None:
        """Why one more robot is refused (None: it is admitted)."""
        robots = sum(
            1 for c in self.connections.values() if c.session is not None and c.session.state in (SPAWNING, ALIVE)
        )
        if robots >= self.max_robots:
            return f"the world has {robots} robots already (limit --max-robots {self.max_robots})"
        return None

    async def start(self) -> int:
        self.loop = asyncio.get_running_loop()
        self.facade.set_deliver(self.threadsafe(self.dispatch))
        return await super().start()

    async def stop(self) -> None:
        if self.step_order is not None:
            self.step_order.cancel()  # the connections close: their STEPs are not carried out
        await super().stop()

    def dispatch(self, outs: list[Output]) -> None:
        """Format a batch of outputs and write them, one write per connection."""
        conns = self.connections
        batches: dict[int, list[bytes]] = {}
        for o in outs:
            conn = conns.get(o.uid)
            if conn is None:
                continue
            try:
                data = M.format_message(output_to_message(o)).encode("ascii", "replace")
            except Exception:
                log.exception("cannot format %r", o)
                continue
            if isinstance(o.value, PackageState) and conn.session is not None and conn.session.actuator_api:
                data += M.format_message(actuator_status(o)).encode("ascii", "replace")
            if o.periodic and not conn.writable:
                conn.send_periodic(o.key, data)  # held, latest-wins
            else:
                batches.setdefault(o.uid, []).append(data)
        for uid, chunks in batches.items():
            conns[uid].send_outputs(chunks[0] if len(chunks) == 1 else b"".join(chunks))
