"""Watching a robot that another client drives, from the operator console (``/ws/watch?robot=name``).

A watched robot is never operated: the page receives the lines the simulation sends that
robot's client (its status and sensor lines, the results of its commands), a description of
its mounted items (GEO and CONF lines, as GETGEO and GETCONF would answer) and, when the robot
leaves the world, a last message that says so.  Nothing the page sends on that socket goes
anywhere.  The outputs of watched robots come from the simulation thread (the facade's output
watchers) and reach each page on the event loop.

:class:`WatchRoutes` is a part of :class:`usarsim.web.console.WebConsole`: it uses the
console's ``app``, its open WebSockets (``_sockets``), its watches (``_watches``, ``_watched``),
its event loop (``_loop``) and ``_spawn``.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections import deque
from collections.abc import Callable, Coroutine
from typing import Any

from aiohttp import web

from usarsim.protocol import messages as M
from usarsim.server.control import output_to_message
from usarsim.server.listener import call_on_loop
from usarsim.sim.api import RobotEntry
from usarsim.web.bridge import CLOSE_TIMEOUT_S, MAX_PAGE_MESSAGE, NAME_RE

log = logging.getLogger("usarsim.web")

WATCH_FIND_S = 3.0  # how long a watch waits for a robot that is still being spawned
WATCH_CHECK_S = 0.2  # how often a watch checks that its robot is still in the world
WATCH_MAX_PENDING = 512  # lines waiting for a slow page, beyond which only the latest of each stream is kept


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


class WatchRoutes:
    """The console's watched robots (see the module's description)."""

    app: Any  # the console's usarsim.server.app.Application
    _sockets: set[web.WebSocketResponse]
    _watches: set[RobotWatch]
    _watched: frozenset[int]  # uids of the watched robots (read on the simulation thread)
    _loop: asyncio.AbstractEventLoop | None
    _spawn: Callable[[Coroutine[Any, Any, None]], asyncio.Task]

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
