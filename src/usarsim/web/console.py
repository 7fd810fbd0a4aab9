"""The operator console: a web page served by the simulator (successor of USARSim's USAR_UI,
SimpleUI and the Unreal spectator, manual 5.1, 5.2.1, 5.2.5), and the bridge between the
page and the simulator's own TCP services.

The console is a client like any other.  For each robot the page operates, the bridge
opens a connection to the control port and relays protocol lines both ways (``/ws/control``:
the page sends text lines, it receives every line the simulator sends).  Pictures come from
the image server (``/ws/video``): the bridge connects to the image port, binds that
connection to a robot camera with ``SET {Type Camera} {Robot r} {Name cam} {Client ip:port}``
over one of the page's control connections, asks with ``OK`` and forwards each JPEG picture
as a binary WebSocket message.  The world view polls the ground-truth service
(``/api/truth``) and draws the world's static geometry (``/api/world``).

The 3-D view (``/api/view3d``) is a picture of the world from a free camera that the page
moves: each request carries the camera (the point it orbits, azimuth, elevation and
distance, as MuJoCo's free camera has them, or a robot to follow) and the answer is one JPEG
picture rendered for it by the image server's render thread from a snapshot of the state,
with the camera it was seen from in the ``X-View`` header (JSON).  The page asks only when
its view changed or, while something moves, at a few pictures a second; the physics never
waits for a picture.

A robot that another client drives is watched, never operated (``/ws/watch?robot=name``):
the page receives the lines the simulation sends that robot's client (its status and sensor
lines, the results of its commands), a description of its mounted items (GEO and CONF
lines, as GETGEO and GETCONF would answer) and, when the robot leaves the world, a last
message that says so.  Nothing the page sends on that socket goes anywhere.

Routes: ``/`` the page, ``/static/*`` its files, ``/api/info``, ``/api/world``,
``/api/classes``, ``/api/truth``, ``/api/view3d``, ``/ws/control``, ``/ws/video``, ``/ws/watch``.
"""

from __future__ import annotations

import asyncio
import io
import json
import logging
import math
import re
import socket
import struct
import time
from collections import deque
from pathlib import Path

from aiohttp import WSMsgType, web

from usarsim import __version__
from usarsim.errors import ProtocolError, UsarsimError
from usarsim.protocol import messages as M
from usarsim.protocol.framing import LineBuffer
from usarsim.protocol.grammar import parse_line
from usarsim.server.connection import peer_address, refuse, write_open
from usarsim.server.control import output_to_message
from usarsim.server.listener import call_on_loop
from usarsim.sim.api import RobotEntry

log = logging.getLogger("usarsim.web")

STATIC_DIR = Path(__file__).resolve().parent / "static"
MAX_SERVER_LINE = 4 << 20  # the longest line relayed to the page (a 3D scanner's SEN line is long)
MAX_PAGE_MESSAGE = 64 * 1024  # the longest message a page may send
MAX_PICTURES_ASKED = 2  # pictures a page may have asked for and not yet received
TRUTH_MAX_AGE_S = 0.05  # answers of the ground-truth service younger than this are shared
TRUTH_TIMEOUT_S = 5.0
BIND_WAIT_S = 1.0  # how long a camera binding sent over a control connection may take to apply
CLOSE_TIMEOUT_S = 2.0  # how long a closing WebSocket waits for the browser's answer
MAX_CONNECTIONS = 64  # open connections on the web port at most (``usarsim serve --max-web-connections``)
NAME_RE = re.compile(r"[A-Za-z0-9_.\-]{1,64}\Z")  # robot and camera names the page may bind to
WATCH_FIND_S = 3.0  # how long a watch waits for a robot that is still being spawned
WATCH_CHECK_S = 0.2  # how often a watch checks that its robot is still in the world
WATCH_MAX_PENDING = 512  # lines waiting for a slow page, beyond which only the latest of each stream is kept
VIEW3D_MAX_RENDERING = 4  # 3-D view pictures being made at once, all pages together; more are answered 503
VIEW3D_MAX_SIZE = (1280, 960)  # the largest 3-D view picture (width, height)
VIEW3D_MIN_SIZE = 16
VIEW3D_DISTANCE_M = (0.2, 2000.0)  # how near and how far the free camera may be from the point it orbits
VIEW3D_TIMEOUT_S = 30.0
VIEW3D_JPEG_QUALITY = 80  # libjpeg's 1..100 scale


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

    w, h = struct.unpack(">HH", payload[:4])
    bgr = np.frombuffer(payload[4 : 4 + 3 * w * h], dtype=np.uint8).reshape(h, w, 3)
    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(bgr[:, :, ::-1])).save(buf, "JPEG", quality=85)
    return buf.getvalue()


def rgb_to_jpeg(rgb, quality: int = VIEW3D_JPEG_QUALITY) -> bytes:
    """An RGB picture (rows top to bottom) as a JPEG file."""
    import numpy as np
    from PIL import Image

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(rgb)).save(buf, "JPEG", quality=quality)
    return buf.getvalue()


def view3d_request(query) -> dict:
    """The free camera a 3-D view request asks for (the keyword arguments of the render
    thread's ``render_free``), from the query: ``lookat=x,y,z`` (MuJoCo's frame: X forward,
    Y left, Z up, metres), ``azimuth`` and ``elevation`` (degrees), ``distance`` (metres),
    ``width`` and ``height`` (pixels), and optionally ``follow``, a robot's name.  Raises
    ValueError with what is wrong."""

    def number(key: str) -> float:
        text = query.get(key)
        if text is None:
            raise ValueError(f"{key} is missing")
        value = float(text)
        if not math.isfinite(value):
            raise ValueError(f"{key} is not a finite number: {text!r}")
        return value

    parts = str(query.get("lookat", "")).split(",")
    if len(parts) != 3:
        raise ValueError("lookat must be three numbers x,y,z")
    lookat = [float(v) for v in parts]
    if not all(math.isfinite(v) and abs(v) < 1e6 for v in lookat):
        raise ValueError("lookat must be three finite numbers")
    width, height = int(number("width")), int(number("height"))
    if not (VIEW3D_MIN_SIZE <= width <= VIEW3D_MAX_SIZE[0] and VIEW3D_MIN_SIZE <= height <= VIEW3D_MAX_SIZE[1]):
        raise ValueError(
            f"the picture must be {VIEW3D_MIN_SIZE}x{VIEW3D_MIN_SIZE}.."
            f"{VIEW3D_MAX_SIZE[0]}x{VIEW3D_MAX_SIZE[1]}, not {width}x{height}"
        )
    follow = query.get("follow") or None
    if follow is not None and not NAME_RE.match(follow):
        raise ValueError(f"not a robot name: {follow!r}")
    return {
        "width": width,
        "height": height,
        "lookat": lookat,
        "azimuth": math.remainder(number("azimuth"), 360.0),
        "elevation": min(90.0, max(-90.0, number("elevation"))),
        "distance": min(VIEW3D_DISTANCE_M[1], max(VIEW3D_DISTANCE_M[0], number("distance"))),
        "follow": follow,
    }


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


class RobotWatch:
    """A page watching a robot that another connection drives: the outputs the simulation
    sends that robot's client, read-only.  While the page reads slowly, the status and sensor
    lines wait latest-wins per stream, as for a slow client."""

    def __init__(self, entry: RobotEntry):
        self.entry = entry  # the robot in the facade's directory
        self.uid = entry.uid
        self.name = entry.name
        self.pending: deque = deque()
        self.ready = asyncio.Event()

    def put(self, outs: list) -> None:
        self.pending.extend(o for o in outs if o.uid == self.uid)
        if len(self.pending) > WATCH_MAX_PENDING:
            self._compact()
        if self.pending:
            self.ready.set()

    def _compact(self) -> None:
        latest = {o.key: o for o in self.pending if o.periodic}
        kept = [o for o in self.pending if not o.periodic or latest[o.key] is o]
        self.pending = deque(kept[-WATCH_MAX_PENDING:])

    def take(self) -> list:
        out = list(self.pending)
        self.pending.clear()
        self.ready.clear()
        return out


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
        rows = []
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


class WebConsole:
    """The console's HTTP and WebSocket server for one :class:`usarsim.server.app.Application`
    (its ports, world and robot folders)."""

    def __init__(self, app, host: str = "127.0.0.1", port: int = 8080, max_connections: int = MAX_CONNECTIONS):
        self.app = app
        self.host = host
        self.port = port
        self.max_connections = max(2, max_connections)
        self.refused = 0  # requests answered 503 because of the limit
        self._refused_at = 0  # open connections at the last refusal
        self._runner: web.AppRunner | None = None
        self._sockets: set[web.WebSocketResponse] = set()
        self._bridges: set[ControlBridge] = set()
        self._tasks: set[asyncio.Task] = set()
        self._truth: TruthClient | None = None
        self._watches: set[RobotWatch] = set()
        self._watched: frozenset[int] = frozenset()  # uids of the watched robots (read on the simulation thread)
        self._loop: asyncio.AbstractEventLoop | None = None
        self._world_json: dict | None = None
        self._classes: list[dict] | None = None
        self._renderer = None  # the render thread the 3-D view uses (the image server's, when there is one)
        self._own_renderer = False
        self._view3d_rendering = 0
        self._stopped = False

    # lifecycle --------------------------------------------------------------------------
    async def start(self) -> int:
        web_app = web.Application(client_max_size=MAX_PAGE_MESSAGE, middlewares=[self._limit])
        web_app.router.add_get("/", self._index)
        web_app.router.add_get("/favicon.ico", self._favicon)
        web_app.router.add_get("/api/info", self._info)
        web_app.router.add_get("/api/world", self._world)
        web_app.router.add_get("/api/classes", self._classes_json)
        web_app.router.add_get("/api/truth", self._truth_json)
        web_app.router.add_get("/api/view3d", self._view3d)
        web_app.router.add_get("/ws/control", self._control_ws)
        web_app.router.add_get("/ws/video", self._video_ws)
        web_app.router.add_get("/ws/watch", self._watch_ws)
        web_app.router.add_static("/static/", STATIC_DIR)
        web_app.on_response_prepare.append(self._no_cache)
        self._runner = web.AppRunner(web_app, access_log=None, shutdown_timeout=1.0)
        await self._runner.setup()
        site = web.TCPSite(self._runner, self.host, self.port, reuse_address=True)
        try:
            await site.start()
        except OSError:
            await self._runner.cleanup()
            self._runner = None
            raise
        self.port = self._runner.addresses[0][1]
        self._loop = asyncio.get_running_loop()
        self.app.facade.add_output_watcher(self._outputs_seen)
        return self.port

    async def stop(self) -> None:
        self._stopped = True
        self.app.facade.remove_output_watcher(self._outputs_seen)
        await asyncio.gather(
            *(ws.close(code=1001, message=b"the simulator is shutting down") for ws in list(self._sockets)),
            return_exceptions=True,
        )
        for task in list(self._tasks):
            task.cancel()
        for b in list(self._bridges):
            b.writer.close()
        if self._truth is not None:
            self._truth.close()
        if self._runner is not None:
            await self._runner.cleanup()
            self._runner = None
        if self._own_renderer and self._renderer is not None:
            await asyncio.get_running_loop().run_in_executor(None, self._renderer.stop)
        self._renderer = None

    @web.middleware
    async def _limit(self, request: web.Request, handler) -> web.StreamResponse:
        """A request on a connection beyond ``max_connections`` open ones is answered 503 and
        its connection closed, so that a crowd of browsers or scripts cannot exhaust the
        simulator's sockets; the first refusal of a burst is logged."""
        runner = self._runner
        open_now = len(runner.server.connections) if runner is not None and runner.server is not None else 0
        if open_now <= self.max_connections:
            return await handler(request)
        if self.refused == 0 or open_now > self._refused_at:
            refuse(
                log,
                f"console {request.remote}",
                open_now,
                self.max_connections,
                "--max-web-connections",
                what=request.path,
                state="open",
            )
        self.refused += 1
        self._refused_at = open_now
        return web.Response(
            status=503,
            text=f"usarsim: more than {self.max_connections} connections to the web console; close a page and retry\n",
            headers={"Connection": "close", "Retry-After": "5"},
        )

    @property
    def service_host(self) -> str:
        return _loopback(self.app.host)

    def _spawn(self, coro) -> asyncio.Task:
        task = asyncio.get_running_loop().create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return task

    # pages and JSON ---------------------------------------------------------------------
    @staticmethod
    async def _no_cache(request: web.Request, response: web.StreamResponse) -> None:
        if not isinstance(response, web.WebSocketResponse):
            response.headers["Cache-Control"] = "no-cache"

    async def _index(self, request: web.Request) -> web.StreamResponse:
        return web.FileResponse(STATIC_DIR / "index.html")

    async def _favicon(self, request: web.Request) -> web.StreamResponse:
        return web.FileResponse(STATIC_DIR / "favicon.svg", headers={"Content-Type": "image/svg+xml"})

    async def _info(self, request: web.Request) -> web.Response:
        a = self.app
        image = a.image
        return web.json_response(
            {
                "version": __version__,
                "world": a.world.name,
                "lockstep": bool(a.facade.lockstep),
                "ports": {
                    "control": a.control.port,
                    "truth": a.truth.port if a.truth is not None else None,
                    "image": image.port if image is not None else None,
                    "web": self.port,
                },
                "image_size": [a.image_settings.width, a.image_settings.height] if image is not None else None,
            }
        )

    async def _world(self, request: web.Request) -> web.Response:
        if self._world_json is None:
            from usarsim.web.geometry import world_json

            self._world_json = await asyncio.get_running_loop().run_in_executor(None, world_json, self.app.world)
        return web.json_response(self._world_json)

    def _load_classes(self) -> list[dict]:
        from usarsim.config.catalog import resolve_robot, robot_files
        from usarsim.web.geometry import robot_class_json

        dirs = tuple(self.app.control.robot_dirs)
        out = []
        for name in robot_files(dirs):
            try:
                out.append(robot_class_json(resolve_robot(name, extra_dirs=dirs)))
            except UsarsimError as exc:
                log.warning("console: robot class %s left out: %s", name, exc)
        return out

    async def _classes_json(self, request: web.Request) -> web.Response:
        if self._classes is None:
            self._classes = await asyncio.get_running_loop().run_in_executor(None, self._load_classes)
        return web.json_response(self._classes)

    async def _truth_json(self, request: web.Request) -> web.Response:
        truth = self.app.truth
        if truth is None:
            return web.json_response({"error": "no ground-truth service (usarsim serve --truth-port)", "objects": []})
        if self._truth is None:
            self._truth = TruthClient(self.service_host, truth.port)
        try:
            rows = await self._truth.query()
        except (TimeoutError, OSError, ConnectionError, asyncio.IncompleteReadError) as exc:
            return web.json_response(
                {"error": f"the ground-truth service did not answer: {exc}", "objects": []}, status=503
            )
        return web.json_response({"objects": rows})

    # the 3-D view ---------------------------------------------------------------------------
    def _view_renderer(self):
        """The render thread of the image server (one GL context and one frame budget for
        every picture), or without an image server one of the console's own."""
        if self._renderer is None:
            image = self.app.image
            if image is not None:
                self._renderer = image.renderer
            else:
                self._renderer = self.app.facade.render_service(self.app.image_settings.max_fps)
                self._own_renderer = True
        return self._renderer

    async def _view3d(self, request: web.Request) -> web.Response:
        """One picture of the 3-D view: see the module's description."""
        try:
            req = view3d_request(request.query)
        except ValueError as exc:
            return web.json_response({"error": str(exc)}, status=400)
        if self._stopped:
            return web.json_response({"error": "the simulator is shutting down"}, status=503)
        if self._view3d_rendering >= VIEW3D_MAX_RENDERING:
            return web.json_response({"error": "the 3-D view is busy: retry"}, status=503, headers={"Retry-After": "1"})
        self._view3d_rendering += 1
        try:
            fut = self._view_renderer().render_free(**req)
            picture, camera = await asyncio.wait_for(asyncio.wrap_future(fut), VIEW3D_TIMEOUT_S)
            jpeg = await asyncio.get_running_loop().run_in_executor(None, rgb_to_jpeg, picture)
        except Exception as exc:  # no GL context here, a snapshot that timed out: said to the page
            log.debug("console: no 3-D view picture: %s", exc)
            return web.json_response({"error": f"no 3-D view: {exc}"}, status=503)
        finally:
            self._view3d_rendering -= 1
        camera["width"], camera["height"] = req["width"], req["height"]
        return web.Response(
            body=jpeg, content_type="image/jpeg", headers={"X-View": json.dumps(camera, separators=(",", ":"))}
        )

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

    # watching another controller's robot -----------------------------------------------------
    def _find_robot(self, name: str) -> RobotEntry | None:
        """The robot called ``name`` (exactly, else ignoring case) in the facade's directory."""
        return self.app.facade.find_robot(name)

    def _present(self, w: RobotWatch) -> bool:
        """Whether the watched robot is still in the world (in the facade's directory)."""
        return self.app.facade.robot(w.uid) is w.entry

    def _describe(self, uid: int, robot) -> list[str]:
        """GEO and CONF lines of every mounted item of the robot, as GETGEO and GETCONF of its
        controller would answer them (the page draws its range sensors with them)."""
        facade = self.app.facade
        by_type: dict[str, list] = {}
        for d in facade.describe(robot):
            by_type.setdefault(d.item_type, []).append(d)
        lines = []
        for item_type, items in by_type.items():
            geo = M.ItemGeometry(
                item_type=item_type,
                items=tuple(
                    M.ItemPose(name=d.name, location=d.location, orientation=d.orientation, mount=d.mount)
                    for d in items
                ),
            )
            conf = M.ItemConfiguration(
                item_type=item_type,
                items=tuple(
                    M.ItemConf(name=d.name, fields=tuple(facade.live_conf(uid, d.item_type, d.name) or d.conf))
                    for d in items
                ),
            )
            lines += [M.format_message(geo).rstrip("\r\n"), M.format_message(conf).rstrip("\r\n")]
        return lines

    def _set_watched(self) -> None:
        self._watched = frozenset(w.uid for w in self._watches)

    def _outputs_seen(self, outs: list) -> None:
        """Every batch of outputs, on the simulation thread: those of watched robots go to
        the event loop; nothing else is done here."""
        watched = self._watched
        if not watched:
            return
        mine = [o for o in outs if o.uid in watched]
        if mine:
            call_on_loop(self._loop, self._fan_out, mine)

    def _fan_out(self, outs: list) -> None:
        for w in self._watches:
            w.put(outs)

    async def _watch_ws(self, request: web.Request) -> web.WebSocketResponse:
        """A robot another client drives, watched read-only: see the module's description."""
        ws = web.WebSocketResponse(max_msg_size=MAX_PAGE_MESSAGE, timeout=CLOSE_TIMEOUT_S)
        await ws.prepare(request)
        self._sockets.add(ws)
        name = request.query.get("robot", "")
        watch = None
        pump = None
        try:
            if not NAME_RE.match(name):
                await ws.send_json({"error": f"not a robot name: {name!r}"})
                return ws
            found = self._find_robot(name)
            deadline = time.monotonic() + WATCH_FIND_S
            while found is None and time.monotonic() < deadline and not ws.closed:
                await asyncio.sleep(0.05)
                found = self._find_robot(name)
            if found is None:
                await ws.send_json({"error": f"no robot called {name} in the world"})
                return ws
            watch = RobotWatch(found)
            self._watches.add(watch)
            self._set_watched()
            robot = found.robot
            await ws.send_json(
                {
                    "watching": watch.name,
                    "class": robot.class_name,
                    "controller": found.controller,
                    "time": round(self.app.facade.time, 3),
                    "describe": self._describe(found.uid, robot),
                }
            )
            log.info("console %s: watching robot %s of %s", request.remote, watch.name, found.controller)
            pump = self._spawn(self._relay_watch(ws, watch))
            async for _ in ws:
                pass  # read-only: nothing the page sends here reaches the robot or its controller
        except (ConnectionError, OSError):
            pass
        finally:
            self._sockets.discard(ws)
            if watch is not None:
                self._watches.discard(watch)
                self._set_watched()
            if pump is not None:
                pump.cancel()
            if not ws.closed:
                await ws.close()
        return ws

    async def _relay_watch(self, ws: web.WebSocketResponse, w: RobotWatch) -> None:
        """The watched robot's lines, one WebSocket message each, then ``{"left": name}`` and
        the end of the socket once the robot has left the world."""
        try:
            while True:
                try:
                    await asyncio.wait_for(w.ready.wait(), WATCH_CHECK_S)
                except TimeoutError:
                    pass
                for o in w.take():
                    try:
                        text = M.format_message(output_to_message(o)).rstrip("\r\n")
                    except Exception:
                        log.exception("cannot format %r", o)
                        continue
                    await ws.send_str(text)
                if not self._present(w):
                    await ws.send_json(
                        {
                            "left": w.name,
                            "time": round(self.app.facade.time, 3),
                            "reason": "its controller's connection closed",
                        }
                    )
                    await ws.close(code=1000, message=b"the robot left the world")
                    return
        except (ConnectionError, OSError, RuntimeError):
            return

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
                        writer.write(b"OK")
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
                kind, length = struct.unpack(">BI", await reader.readexactly(5))
                payload = await reader.readexactly(length)
                asked[0] = max(0, asked[0] - 1)
                if kind == 0:
                    payload = await loop.run_in_executor(None, raw_to_jpeg, payload)
                await ws.send_bytes(payload)
        except (asyncio.IncompleteReadError, ConnectionError, OSError, RuntimeError):
            if not ws.closed:
                await ws.close(code=1011, message=b"the image server closed the connection")
