"""The operator console's bridge to the simulator's TCP services: a page's robot sessions on
the control port (``/ws/control``), robot cameras' pictures from the image server
(``/ws/video``) and the ground-truth service's answers (:class:`TruthClient`).

For each robot the page operates, the bridge opens a connection to the control port and
relays protocol lines both ways: the page sends text lines, it receives every line the
simulator sends.  For pictures the bridge connects to the image port, binds that connection
to a robot camera with ``SET {Type Camera} {Robot r} {Name cam} {Client ip:port}`` over one of
the page's control connections, asks with ``OK`` and forwards each JPEG picture as a binary
WebSocket message.

:class:`BridgeRoutes` is a part of :class:`usarsim.web.console.WebConsole`: it uses the
console's ``app``, its open WebSockets (``_sockets``), its robot sessions (``_bridges``) and
``_spawn``.
"""

from __future__ import annotations

import asyncio
import io
import json
import logging
import re
import socket
import time
from collections.abc import Callable, Coroutine
from typing import Any

from aiohttp import WSMsgType, web

from usarsim.errors import ProtocolError
from usarsim.protocol import upis
from usarsim.protocol.framing import LineBuffer
from usarsim.protocol.grammar import parse_line
from usarsim.server.connection import peer_address, write_open

log = logging.getLogger("usarsim.web")

MAX_SERVER_LINE = 4 << 20  # the longest line relayed to the page (a 3D scanner's SEN line is long)
MAX_PAGE_MESSAGE = 64 * 1024  # the longest message a page may send
MAX_PICTURES_ASKED = 2  # pictures a page may have asked for and not yet received
TRUTH_MAX_AGE_S = 0.05  # answers of the ground-truth service younger than this are shared
TRUTH_TIMEOUT_S = 5.0
BIND_WAIT_S = 1.0  # how long a camera binding sent over a control connection may take to apply
CLOSE_TIMEOUT_S = 2.0  # how long a closing WebSocket waits for the browser's answer
NAME_RE = re.compile(r"[A-Za-z0-9_.\-]{1,64}\Z")  # robot and camera names the page may bind to


def _loopback(host: str) -> str:
    """Where the bridge reaches a listener bound to ``host``."""
    if host in ("", "0.0.0.0", "*"):
        return "127.0.0.1"
    if host == "::":
        return "::1"
    return host


def _no_delay(writer: asyncio.StreamWriter) -> None:
    sock = writer.get_extra_info("socket")
    if sock is not None:
        try:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        except OSError:
            pass


def raw_to_jpeg(payload: bytes) -> bytes:
    """A raw UPIS picture (16-bit width and height, then B, G, R rows) as a JPEG file."""
    import numpy as np
    from PIL import Image

    w, h, pixels = upis.parse_raw(payload)
    bgr = np.frombuffer(pixels, dtype=np.uint8).reshape(h, w, 3)
    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(bgr[:, :, ::-1])).save(buf, "JPEG", quality=85)
    return buf.getvalue()


def truth_row(text: str) -> dict | None:
    """One line of the ground-truth service as a dict, None if it is not one."""
    try:
        raw = parse_line("TRUTH " + text)
    except ProtocolError:
        return None
    seg = {s.key.lower(): s.value for s in raw.segments}
    try:
        return {
            "name": seg["name"],
            "class": seg["class"],
            "time": float(seg["time"]),
            "location": [float(v) for v in seg["location"].split(",")],
            "rotation": [float(v) for v in seg["rotation"].split(",")],
        }
    except (KeyError, ValueError):
        return None


class ControlBridge:
    """One page's robot session: a WebSocket and the control connection it is relayed to."""

    def __init__(self, page: str, writer: asyncio.StreamWriter):
        self.page = page
        self.writer = writer
        self.robot: str | None = None  # the Name of the INIT sent on it
        self.alive = False  # the simulator has sent status or sensor lines: the robot exists

    def note_sent(self, line: str) -> None:
        if line.lstrip()[:4].upper() != "INIT":
            return
        try:
            raw = parse_line(line)
        except ProtocolError:
            return
        for s in raw.segments:
            if s.key.lower() == "name" and s.value:
                self.robot = s.value.strip()

    def note_received(self, line: str) -> None:
        if not self.alive and (line.startswith("STA") or line.startswith("SEN")):
            self.alive = True

    def send_line(self, line: str) -> None:
        write_open(self.writer, line.encode("ascii", "replace") + b"\r\n")


class TruthClient:
    """A connection to the ground-truth service, shared by every page: one request at a
    time, answers shared for ``TRUTH_MAX_AGE_S``."""

    def __init__(self, host: str, port: int):
        self.host, self.port = host, port
        self._lock = asyncio.Lock()
        self._reader: asyncio.StreamReader | None = None
        self._writer: asyncio.StreamWriter | None = None
        self._answer: list[dict] = []
        self._at = -1.0

    async def query(self) -> list[dict]:
        async with self._lock:
            if time.monotonic() - self._at < TRUTH_MAX_AGE_S:
                return self._answer
            for attempt in (0, 1):  # a connection the service closed is opened again once
                try:
                    rows = await asyncio.wait_for(self._ask(), TRUTH_TIMEOUT_S)
                    break
                except (TimeoutError, OSError, asyncio.IncompleteReadError, ConnectionError):
                    self.close()
                    if attempt:
                        raise
            self._answer, self._at = rows, time.monotonic()
            return rows

    async def _ask(self) -> list[dict]:
        if self._writer is None:
            self._reader, self._writer = await asyncio.open_connection(self.host, self.port)
            _no_delay(self._writer)
        assert self._reader is not None
        self._writer.write(b"{Class}\r\n")  # no class and no name given: everything
        await self._writer.drain()
        rows: list[dict] = []
        while True:
            line = await self._reader.readline()
            if not line:
                raise ConnectionError("the ground-truth service closed the connection")
            text = line.decode("ascii", "replace").strip()
            if text == "{End}":
                return rows
            row = truth_row(text)
            if row is not None:
                rows.append(row)

    def close(self) -> None:
        if self._writer is not None:
            self._writer.close()
        self._reader = self._writer = None


class BridgeRoutes:
    """The console's robot sessions and pictures (see the module's description)."""

    app: Any  # the console's usarsim.server.app.Application
    _sockets: set[web.WebSocketResponse]
    _bridges: set[ControlBridge]
    _spawn: Callable[[Coroutine[Any, Any, None]], asyncio.Task]

    @property
    def service_host(self) -> str:
        return _loopback(self.app.host)

    # robot sessions -----------------------------------------------------------------------
    async def _control_ws(self, request: web.Request) -> web.WebSocketResponse:
        ws = web.WebSocketResponse(max_msg_size=MAX_PAGE_MESSAGE, timeout=CLOSE_TIMEOUT_S)
        await ws.prepare(request)
        self._sockets.add(ws)
        bridge = None
        pump = None
        try:
            try:
                reader, writer = await asyncio.open_connection(self.service_host, self.app.control.port)
            except OSError as exc:
                await ws.close(code=1011, message=f"cannot reach the control port: {exc.strerror}".encode()[:120])
                return ws
            _no_delay(writer)
            bridge = ControlBridge(request.query.get("page", ""), writer)
            self._bridges.add(bridge)
            log.info("console %s: robot session opened on the control port", request.remote)
            pump = self._spawn(self._relay_lines(reader, ws, bridge))
            async for msg in ws:
                if msg.type != WSMsgType.TEXT:
                    continue
                for line in msg.data.replace("\r", "\n").split("\n"):
                    if line.strip():
                        bridge.note_sent(line)
                        bridge.send_line(line)
                await writer.drain()
        except (ConnectionError, OSError):
            pass
        finally:
            self._sockets.discard(ws)
            if bridge is not None:
                self._bridges.discard(bridge)
                bridge.writer.close()  # closing the connection removes the robot
                log.info("console %s: robot session %s closed", request.remote, bridge.robot or "")
            if pump is not None:
                pump.cancel()
            if not ws.closed:
                await ws.close()
        return ws

    async def _relay_lines(
        self, reader: asyncio.StreamReader, ws: web.WebSocketResponse, bridge: ControlBridge
    ) -> None:
        """Every line the simulator sends on a control connection, one WebSocket message each.
        A page that reads slowly slows this down, and the simulator then keeps only the
        latest status and sensor lines for it, as for any slow client."""
        lines = LineBuffer(max_line_bytes=MAX_SERVER_LINE)
        try:
            while True:
                data = await reader.read(1 << 16)
                if not data:
                    break
                for line in lines.feed(data):
                    bridge.note_received(line)
                    await ws.send_str(line)
        except (ConnectionError, OSError, RuntimeError):
            return
        if not ws.closed:
            await ws.close(code=1000, message=b"the simulator closed the connection")

    # pictures ------------------------------------------------------------------------------
    def _bridge_for(self, page: str, robot: str) -> ControlBridge | None:
        """The control connection a camera binding is sent over: the one of the robot
        itself, else another of the same page whose robot exists."""
        best = None
        for b in self._bridges:
            if not b.alive or b.writer.is_closing():
                continue
            if b.robot is not None and b.robot.lower() == robot.lower():
                return b
            if b.page and b.page == page and best is None:
                best = b
        return best

    async def _bind(self, page: str, client: tuple[str, int], robot: str | None, camera: str) -> dict:
        """Show the image connection at ``client`` a robot camera (None: release it)."""
        bindings = self.app.camera_bindings
        address = peer_address(*client)
        if robot is None:
            bindings.release(address)
            return {"bound": None}
        bridge = self._bridge_for(page, robot)
        line = f"SET {{Type Camera}} {{Robot {robot}}} {{Name {camera}}} {{Client {address}}}"
        if bridge is None:
            # no robot of this page to speak for it (a spectator): the binding is made
            # directly, as the control server would make it
            if not bindings.bind(address, robot, camera):
                return {"error": f"no camera binding: {len(bindings)} viewers bound already"}
            return {"bound": robot, "camera": camera, "via": "direct"}
        bridge.send_line(line)
        deadline = time.monotonic() + BIND_WAIT_S
        while bindings.lookup(*client) != (robot, camera) and time.monotonic() < deadline:
            await asyncio.sleep(0.01)
        return {"bound": robot, "camera": camera, "via": "control", "robot": bridge.robot, "line": line}

    async def _video_ws(self, request: web.Request) -> web.WebSocketResponse:
        # JPEG pictures do not compress further: no per-message deflate
        ws = web.WebSocketResponse(max_msg_size=MAX_PAGE_MESSAGE, timeout=CLOSE_TIMEOUT_S, compress=False)
        await ws.prepare(request)
        self._sockets.add(ws)
        image = self.app.image
        page = request.query.get("page", "")
        writer = None
        frames = None
        client = ("", 0)
        try:
            if image is None:
                await ws.send_json({"error": "no image server (usarsim serve was started with --no-image)"})
                return ws
            try:
                reader, writer = await asyncio.open_connection(self.service_host, image.port)
            except OSError as exc:
                await ws.send_json({"error": f"cannot reach the image port: {exc.strerror}"})
                return ws
            _no_delay(writer)
            sockname = writer.get_extra_info("sockname")
            client = (sockname[0], sockname[1])
            asked = [0]
            frames = self._spawn(self._relay_pictures(reader, ws, asked))
            async for msg in ws:
                if msg.type != WSMsgType.TEXT:
                    continue
                if msg.data.strip() == "OK":
                    if asked[0] < MAX_PICTURES_ASKED:
                        asked[0] += 1
                        writer.write(upis.ask_whole())
                    continue
                try:
                    req = json.loads(msg.data)
                except ValueError:
                    continue
                if not isinstance(req, dict) or "bind" not in req:
                    continue
                robot, camera = req.get("bind"), str(req.get("camera") or "Camera")
                if robot is not None and not (NAME_RE.match(str(robot)) and NAME_RE.match(camera)):
                    await ws.send_json({"error": f"not a robot and camera name: {robot!r} {camera!r}"})
                    continue
                await ws.send_json(await self._bind(page, client, None if robot is None else str(robot), camera))
        except (ConnectionError, OSError):
            pass
        finally:
            self._sockets.discard(ws)
            if client[1]:
                self.app.camera_bindings.release(peer_address(*client))
            if frames is not None:
                frames.cancel()
            if writer is not None:
                writer.close()
            if not ws.closed:
                await ws.close()
        return ws

    async def _relay_pictures(self, reader: asyncio.StreamReader, ws: web.WebSocketResponse, asked: list) -> None:
        """Each UPIS picture as one binary WebSocket message holding a JPEG file."""
        loop = asyncio.get_running_loop()
        try:
            while True:
                kind, length = upis.HEADER.unpack(await reader.readexactly(upis.HEADER.size))
                payload = await reader.readexactly(length)
                asked[0] = max(0, asked[0] - 1)
                if kind == upis.RAW:
                    payload = await loop.run_in_executor(None, raw_to_jpeg, payload)
                await ws.send_bytes(payload)
        except (asyncio.IncompleteReadError, ConnectionError, OSError, RuntimeError):
            if not ws.closed:
                await ws.close(code=1011, message=b"the image server closed the connection")
