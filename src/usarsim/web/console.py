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
``/api/classes``, ``/api/truth``, ``/api/radio``, ``/api/view3d``, ``/ws/control``, ``/ws/video``,
``/ws/watch``.
The robot sessions and pictures are :class:`usarsim.web.bridge.BridgeRoutes`, the watched
robots :class:`usarsim.web.watch.WatchRoutes`: parts of :class:`WebConsole`.
"""

from __future__ import annotations

import asyncio
import io
import json
import logging
import math
from pathlib import Path

from aiohttp import web

from usarsim import __version__
from usarsim.errors import UsarsimError
from usarsim.server.connection import refuse
from usarsim.sim.types import describe_channel
from usarsim.web.bridge import MAX_PAGE_MESSAGE, NAME_RE, BridgeRoutes, ControlBridge, TruthClient
from usarsim.web.bridge import raw_to_jpeg as raw_to_jpeg
from usarsim.web.bridge import truth_row as truth_row
from usarsim.web.watch import RobotWatch, WatchRoutes

log = logging.getLogger("usarsim.web")

STATIC_DIR = Path(__file__).resolve().parent / "static"
MAX_CONNECTIONS = 64  # open connections on the web port at most (``usarsim serve --max-web-connections``)
VIEW3D_MAX_RENDERING = 4  # 3-D view pictures being made at once, all pages together; more are answered 503
VIEW3D_MAX_SIZE = (1280, 960)  # the largest 3-D view picture (width, height)
VIEW3D_MIN_SIZE = 16
VIEW3D_DISTANCE_M = (0.2, 2000.0)  # how near and how far the free camera may be from the point it orbits
VIEW3D_TIMEOUT_S = 30.0
VIEW3D_JPEG_QUALITY = 80  # libjpeg's 1..100 scale


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


class WebConsole(BridgeRoutes, WatchRoutes):
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
        web_app.router.add_get("/api/radio", self._radio_json)
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
                robot = resolve_robot(name, extra_dirs=dirs)
                facade = self.app.facade
                out.append(robot_class_json(robot, facade.lowest_point_m(robot), facade.velocity_limits(robot)))
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

    async def _radio_json(self, request: web.Request) -> web.Response:
        """What the radio channel carried, link by link (docs/wireless.md): ``channel`` in a few
        words (None without wireless servers; ``ideal``, USARSim's, counts nothing) and each
        link's messages delivered and dropped by cause, and their mean delay."""
        wireless = self.app.wireless
        if wireless is None or wireless.service.ideal:
            return web.json_response({"channel": None if wireless is None else "ideal", "links": []})
        svc = wireless.service
        counts = await svc.counts()
        links = [{"from": a, "to": b, **c.as_dict()} for (a, b), c in counts.items()]
        return web.json_response({"channel": describe_channel(svc.channel), "links": links})

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
