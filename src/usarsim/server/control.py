"""The control server (TCP 3000): one robot per connection.

asyncio glue only: bytes -> lines (protocol.framing) -> session -> simulation
facade; simulation outputs -> protocol messages -> the owning connection.

Slow readers: periodic messages (STA, SEN) are latest-wins per stream while the
socket's send buffer is above its high-water mark; replies (NFO, GEO, CONF, RES,
STEPPED) are always queued.
"""

from __future__ import annotations

import asyncio
import logging
import re
import time
from collections import deque
from typing import Any

from usarsim.protocol import messages as M
from usarsim.protocol.framing import LineBuffer
from usarsim.readings import CommandResult, EffecterState, PackageState, RobotStatus, ZoomResult
from usarsim.server.session import ALIVE, CLOSED, SPAWNING, Session, SessionContext
from usarsim.sim.facade import SimFacade
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
# A run of the same repeatable DRIVE line (speeds or lights, no joint Order, no Flip) in one
# read collapses to one line before the lines are even split: sending it again changes nothing.
_REPEATED_DRIVE = re.compile(rb"(?:^|(?<=[\r\n]))(DRIVE(?:(?![Oo]rder|[Ff]lip)[^\r\n])*[\r\n]+)(?:\1)+")


def output_to_message(o: Output) -> Any:
    v = o.value
    if isinstance(v, RobotStatus):
        if v.vehicle_type == "AerialVehicle":
            return M.AerialVehicleStatus(time=o.time, light_toggle=v.light_toggle, light_intensity=v.light_intensity,
                                         battery_s=v.battery_s, view=v.view)
        return M.GroundVehicleStatus(time=o.time, front_steer=v.front_steer, rear_steer=v.rear_steer, joints=v.joints,
                                     light_toggle=v.light_toggle, light_intensity=v.light_intensity,
                                     battery_s=v.battery_s, view=v.view, vehicle_type=v.vehicle_type)
    if isinstance(v, EffecterState):
        return M.EffecterStatus(time=o.time, effecter_type=v.effecter_type, name=v.name, status=v.status)
    if isinstance(v, PackageState):
        return M.MisPkgStatus(time=o.time, name=v.name,
                              links=tuple(M.LinkState(link=n, value=q, torque=f) for n, q, f in v.links))
    if isinstance(v, ZoomResult):
        return M.CameraZoomResult(time=o.time, cameras=tuple(M.CameraZoom(n, f, st) for n, f, st in v.cameras))
    if isinstance(v, CommandResult):
        return M.Result(time=o.time, item_type=v.item_type, name=v.name, status=v.status, extra=v.extra)
    return M.SensorMessage(time=o.time, reading=v)


class Connection(asyncio.Protocol):
    def __init__(self, server: "ControlServer"):
        self.server = server
        self.transport: asyncio.Transport | None = None
        self.peer = "?"
        self.buffer = LineBuffer(max_line_bytes=server.max_line_bytes)
        self.session: Session | None = None
        self._paused = False
        self._held: dict[str, bytes] = {}  # latest periodic line per stream while paused
        self.dropped_periodic = 0
        self._backlog: deque[str] = deque()  # lines received, not handled yet
        self._last_line = ""
        self._reading_paused = False
        self.repeats_skipped = 0

    # asyncio.Protocol -----------------------------------------------------------------
    def connection_made(self, transport) -> None:
        self.transport = transport
        transport.set_write_buffer_limits(high=self.server.max_pending_bytes)
        peer = transport.get_extra_info("peername")
        self.peer = f"{peer[0]}:{peer[1]}" if isinstance(peer, tuple) else str(peer)
        srv = self.server
        if len(srv.connections) >= srv.max_connections:
            log.warning("%s: refused: %d connections already (limit --max-connections %d)", self.peer,
                        len(srv.connections), srv.max_connections)
            transport.close()
            return
        uid = srv.next_uid()
        self.session = Session(SessionContext(facade=srv.facade, peer=self.peer, emit=self.send_reply,
                                              threadsafe=srv.threadsafe, admit=srv.admit, robot_dirs=srv.robot_dirs,
                                              camera_bindings=srv.camera_bindings), uid)
        srv.connections[uid] = self
        log.info("%s: connected (robot id %d)", self.peer, uid)
        self.send_reply(M.GameInfo(level=srv.facade.world_name, time_limit=srv.facade.world.time_limit_min))

    def data_received(self, data: bytes) -> None:
        if self.session is None:
            return
        before = self.buffer.dropped_lines
        if len(data) > 2048 and b"DRIVE" in data:
            data = _REPEATED_DRIVE.sub(rb"\1", data)
        lines = self.buffer.feed(data)
        if self.buffer.dropped_lines != before:
            self.session.log_once("too-long", "dropped a line longer than %d bytes", self.buffer.max_line_bytes)
        self._backlog.extend(lines)
        self._drain()

    @staticmethod
    def _repeatable(line: str) -> bool:
        """A DRIVE that sets speeds or lights only: sending it again changes nothing."""
        head = line[:5].upper()
        if head != "DRIVE":
            return False
        low = line.lower()
        return "order" not in low and "flip" not in low

    def _drain(self) -> None:
        """Handle waiting lines within the time budget; the same repeatable DRIVE sent again
        and again is handled once (a flood of identical commands costs almost nothing)."""
        session = self.session
        if session is None or session.state == CLOSED:
            self._backlog.clear()
            return
        start = time.perf_counter()
        backlog, prev = self._backlog, self._last_line
        n = 0
        while backlog:
            if self._paused and self.transport is not None and \
                    self.transport.get_write_buffer_size() > REPLY_CAP_FACTOR * self.server.max_pending_bytes:
                # the client asks and asks but does not read the replies: its further lines
                # wait, its socket unread, until it reads (resume_writing drains them)
                self._last_line = prev
                if not self._reading_paused:
                    self.transport.pause_reading()
                    self._reading_paused = True
                    self.session.log_once("unread-replies", "more than %d kB of replies unread; the next lines "
                                          "wait until the client reads", REPLY_CAP_FACTOR *
                                          self.server.max_pending_bytes // 1024)
                return
            line = backlog.popleft()
            if line == prev and self._repeatable(line):
                self.repeats_skipped += 1
                continue
            prev = line
            try:
                session.handle_line(line)
            except Exception:  # nothing a client sends may take the server down
                log.exception("%s: error while handling %.200r", self.peer, line)
            n += 1
            if n % 32 == 0 and backlog and time.perf_counter() - start > LINE_BUDGET_S:
                self._last_line = prev
                if not self._reading_paused and self.transport is not None:
                    self.transport.pause_reading()
                    self._reading_paused = True
                asyncio.get_running_loop().call_later(LINE_BUDGET_S / 2, self._drain)
                return
        self._last_line = prev
        if self._reading_paused and self.transport is not None and not self.transport.is_closing():
            self.transport.resume_reading()
            self._reading_paused = False

    def connection_lost(self, exc) -> None:
        s = self.session
        if s is None:
            return
        self.server.connections.pop(s.uid, None)
        if s.state != "new":
            self.server.facade.remove(s.uid)
        s.state = CLOSED
        log.info("%s: disconnected%s", self.peer, f" ({exc})" if exc else "")

    def pause_writing(self) -> None:
        self._paused = True

    def resume_writing(self) -> None:
        self._paused = False
        held, self._held = self._held, {}
        if held and self.transport is not None:
            self.transport.write(b"".join(held.values()))
        if self._backlog:
            self._drain()

    # Output ----------------------------------------------------------------------------
    def send_reply(self, msg) -> None:
        if self.transport is not None and not self.transport.is_closing():
            self.transport.write(M.format_message(msg).encode("ascii", "replace"))

    def send_periodic(self, key: str, data: bytes) -> None:
        if self.transport is None or self.transport.is_closing():
            return
        if self._paused:
            if key in self._held:
                self.dropped_periodic += 1
            self._held[key] = data
            return
        self.transport.write(data)


class ControlServer:
    def __init__(self, facade: SimFacade, *, host: str = "127.0.0.1", port: int = 3000,
                 max_connections: int = 64, max_line_bytes: int = 8192, robot_dirs: tuple[str, ...] = (),
                 max_pending_bytes: int = HIGH_WATER, max_robots: int | None = None):
        self.facade = facade
        self.robot_dirs = robot_dirs  # extra folders of robot files (serve --robot-dir)
        from usarsim.server.image import CameraBindings

        self.camera_bindings = CameraBindings()  # SET {Type Camera} {Client ip}; shared with the image server
        self.host = host
        self.port = port
        self.max_connections = max_connections
        self.max_line_bytes = max_line_bytes
        # output waiting for a slow client beyond which its sensor lines are held latest-wins
        self.max_pending_bytes = max(4096, int(max_pending_bytes))
        self.max_robots = max_connections if max_robots is None else max(0, int(max_robots))
        self.connections: dict[int, Connection] = {}
        self._uid = 0
        self._server: asyncio.base_events.Server | None = None
        self.loop: asyncio.AbstractEventLoop | None = None

    def next_uid(self) -> int:
        self._uid += 1
        return self._uid

    def admit(self) -> str | None:
        """Why one more robot is refused (None: it is admitted)."""
        robots = sum(1 for c in self.connections.values() if c.session is not None
                     and c.session.state in (SPAWNING, ALIVE))
        if robots >= self.max_robots:
            return f"the world has {robots} robots already (limit --max-robots {self.max_robots})"
        return None

    def threadsafe(self, fn):
        """``fn`` to be called from another thread (the simulation's): it runs on the event loop."""
        def call(*args) -> None:
            loop = self.loop
            if loop is not None and not loop.is_closed():
                try:
                    loop.call_soon_threadsafe(fn, *args)
                except RuntimeError:  # the loop closed meanwhile
                    pass

        return call

    async def start(self) -> int:
        self.loop = asyncio.get_running_loop()
        self.facade.set_deliver(self._deliver_threadsafe)
        self._server = await self.loop.create_server(lambda: Connection(self), self.host, self.port,
                                                     reuse_address=True)
        self.port = self._server.sockets[0].getsockname()[1]
        return self.port

    def _deliver_threadsafe(self, outs: list[Output]) -> None:
        loop = self.loop
        if loop is not None and not loop.is_closed():
            try:
                loop.call_soon_threadsafe(self.dispatch, outs)
            except RuntimeError:  # the loop closed meanwhile
                pass

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
            if o.periodic and conn._paused:
                conn.send_periodic(o.key, data)  # held, latest-wins
            else:
                batches.setdefault(o.uid, []).append(data)
        for uid, chunks in batches.items():
            conn = conns[uid]
            if conn.transport is not None and not conn.transport.is_closing():
                conn.transport.write(chunks[0] if len(chunks) == 1 else b"".join(chunks))

    async def stop(self) -> None:
        if self._server is not None:
            self._server.close()
        for conn in list(self.connections.values()):
            if conn.transport is not None:
                conn.transport.close()
        if self._server is not None:
            await self._server.wait_closed()
