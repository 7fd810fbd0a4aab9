"""Small test tools shared by the suites: condition waits, an in-process server running
in its own thread, and a line-oriented USARSim test client over a real TCP socket.

Nothing here sleeps for a fixed time: every wait is on a condition with a timeout.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from typing import Any

DEFAULT_TIMEOUT = 10.0


class WaitTimeout(AssertionError):
    """A condition did not become true in time (an assertion failure, so tests fail cleanly)."""


def wait_for(
    predicate: Callable[[], Any], timeout: float = DEFAULT_TIMEOUT, *, interval: float = 0.005, what: str | None = None
) -> Any:
    """Poll ``predicate`` until it returns something truthy; return that value.

    Raises :class:`WaitTimeout` (an AssertionError) after ``timeout`` seconds.
    """
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value:
            return value
        if time.monotonic() >= deadline:
            raise WaitTimeout(f"timed out after {timeout:g} s waiting for {what or predicate!r}")
        time.sleep(interval)


# --------------------------------------------------------------------------- the client


@dataclass(frozen=True)
class Line:
    """One line received from the server: ``raw`` with its terminator, ``text`` without."""

    raw: bytes
    text: str

    @property
    def type(self) -> str:
        return self.text.split(" ", 1)[0].split("{", 1)[0]

    def segment(self, key: str) -> str | None:
        """The value of the first ``{key value}`` segment (exact key), else None."""
        return segments(self.text).get(key)


def broken_advance(seconds: float, *, waited: bool = False) -> None:
    """A stand-in for ``Simulation.advance`` with a bug: the simulation stops on its error."""
    raise RuntimeError("a physics bug")


def settled(value):
    """A future already settled with ``value`` (what the facade returns for a request it has
    carried out)."""
    from concurrent.futures import Future

    future = Future()
    future.set_result(value)
    return future


def same(a, b) -> bool:
    """Observations, rewards or infos equal to the last bit."""
    import numpy as np

    if isinstance(a, dict):
        return isinstance(b, dict) and a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, (tuple, list)):
        return isinstance(b, type(a)) and len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and a.dtype == b.dtype and np.array_equal(a, b)
    return type(a) is type(b) and a == b


def segments(text: str) -> dict[str, str]:
    """``{Key Value}`` segments of a line as a dict (first occurrence of a key wins)."""
    out: dict[str, str] = {}
    pos = 0
    while True:
        a = text.find("{", pos)
        if a < 0:
            return out
        b = text.find("}", a)
        if b < 0:
            return out
        body = text[a + 1 : b].strip()
        key, _, value = body.partition(" ")
        out.setdefault(key, value.strip())
        pos = b + 1


def segment_list(text: str) -> list[str]:
    """Every ``{...}`` segment body of a line, in order."""
    out = []
    pos = 0
    while True:
        a = text.find("{", pos)
        if a < 0:
            return out
        b = text.find("}", a)
        if b < 0:
            return out
        out.append(text[a + 1 : b])
        pos = b + 1


def vec(text: str) -> tuple[float, ...]:
    return tuple(float(v) for v in text.split(","))


def sen_type(line: Line | str) -> str | None:
    text = line.text if isinstance(line, Line) else line
    if not text.startswith("SEN "):
        return None
    return segments(text).get("Type")


def angle_diff(a: float, b: float) -> float:
    """a - b wrapped into (-pi, pi]."""
    d = (a - b) % (2 * math.pi)
    return d - 2 * math.pi if d > math.pi else d


class Client:
    """A blocking USARSim client for tests.

    Every received line is kept in ``history`` (in arrival order).  ``wait_line`` reads until
    a line matching a prefix arrives (lines read on the way stay in ``history``).  A client
    closes its socket on ``close`` or on exit from a ``with`` block.
    """

    def __init__(self, port: int, host: str = "127.0.0.1", *, timeout: float = DEFAULT_TIMEOUT):
        self.sock = socket.create_connection((host, port), timeout=timeout)
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.timeout = timeout
        self._buf = b""
        self.history: list[Line] = []
        self.eof = False

    # context manager --------------------------------------------------------------
    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self) -> None:
        if self.sock.fileno() != -1:
            self.sock.close()

    # sending ----------------------------------------------------------------------
    def send(self, line: str, terminator: bytes = b"\r\n") -> None:
        self.sock.sendall(line.encode("ascii") + terminator)

    def send_raw(self, data: bytes) -> None:
        self.sock.sendall(data)

    # receiving --------------------------------------------------------------------
    def _fill(self, deadline: float) -> bool:
        """Read more bytes; False on EOF.  Raises WaitTimeout at the deadline."""
        left = deadline - time.monotonic()
        if left <= 0:
            raise WaitTimeout("timed out waiting for data from the server")
        self.sock.settimeout(left)
        try:
            data = self.sock.recv(1 << 16)
        except TimeoutError:
            raise WaitTimeout("timed out waiting for data from the server") from None
        except ConnectionResetError:
            data = b""
        if not data:
            self.eof = True
            return False
        self._buf += data
        return True

    def _read_line(self, deadline: float) -> Line | None:
        while b"\n" not in self._buf:
            if self.eof or not self._fill(deadline):
                return None
        raw, self._buf = self._buf.split(b"\n", 1)
        raw += b"\n"
        line = Line(raw, raw.rstrip(b"\r\n").decode("ascii", "replace"))
        self.history.append(line)
        return line

    def next_line(self, timeout: float | None = None) -> Line:
        """The next line from the server."""
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        line = self._read_line(deadline)
        if line is None:
            raise WaitTimeout("the server closed the connection")
        return line

    def wait_line(self, prefix: str | Callable[[Line], bool], timeout: float | None = None) -> Line:
        """Read lines until one starts with ``prefix`` (or satisfies the predicate); return it."""
        match = prefix if callable(prefix) else (lambda ln: ln.text.startswith(prefix))
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while True:
            line = self._read_line(deadline)
            if line is None:
                raise WaitTimeout(f"the server closed the connection before a line matching {prefix!r}")
            if match(line):
                return line

    def lines_until(self, prefix: str, timeout: float | None = None) -> list[Line]:
        """Every line up to and including the first one that starts with ``prefix``."""
        out: list[Line] = []
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while True:
            line = self._read_line(deadline)
            if line is None:
                raise WaitTimeout(f"the server closed the connection before a line starting {prefix!r}")
            out.append(line)
            if line.text.startswith(prefix):
                return out

    def wait_closed(self, timeout: float | None = None) -> bytes:
        """Read until the server closes the connection; return whatever arrived before."""
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        start = len(self._buf)
        while not self.eof:
            self._fill(deadline)
        return self._buf[start:]

    # protocol conveniences ----------------------------------------------------------
    def nfo(self) -> Line:
        """The game-info line sent on connect."""
        return self.wait_line("NFO ")

    def step(self, seconds: float, timeout: float | None = None) -> list[Line]:
        """Lock-step: ``STEP {Time s}``; return every line up to and including STEPPED."""
        self.send(f"STEP {{Time {seconds:g}}}")
        return self.lines_until("STEPPED", timeout)

    def ask(self, line: str, reply_prefix: str, timeout: float | None = None) -> Line:
        self.send(line)
        return self.wait_line(reply_prefix, timeout)

    def sync(self, timeout: float | None = None) -> list[Line]:
        """Send GETSTARTPOSES and return every line up to its reply: proves the connection
        is alive and that everything sent before was handled."""
        self.send("GETSTARTPOSES")
        return self.lines_until("NFO {StartPoses", timeout)


def sensor_lines(lines: list[Line], stype: str) -> list[Line]:
    return [ln for ln in lines if sen_type(ln) == stype]


def ground_truth(lines: list[Line]) -> list[tuple[float, tuple[float, float, float], tuple[float, float, float]]]:
    """(time, location, orientation) of every GroundTruth line."""
    out = []
    for ln in sensor_lines(lines, "GroundTruth"):
        s = segments(ln.text)
        out.append((float(s["Time"]), vec(s["Location"]), vec(s["Orientation"])))
    return out


# --------------------------------------------------------------------------- in-process server


class ServerThread:
    """An :class:`usarsim.server.app.Application` served by its own asyncio loop in a thread."""

    def __init__(
        self,
        world,
        *,
        seed: int = 1,
        lockstep: bool = True,
        speed: float | None = None,
        max_connections: int = 64,
        robot_dirs: tuple[str, ...] = (),
        image=None,
        wireless_model: str | None = None,
        sim=None,
        **serve_options,
    ):
        """``sim``: the simulation's :class:`usarsim.sim.settings.SimSettings` (None: the defaults);
        ``serve_options``: more fields of :class:`usarsim.server.config.ServeConfig` (``record``,
        ``score_file``...)."""
        from usarsim.server.app import Application
        from usarsim.server.config import ServeConfig
        from usarsim.server.image import ImageSettings
        from usarsim.server.wireless import WirelessOptions

        # every listener on a free port (0), so that tests never collide
        wireless = WirelessOptions(wcs_port=0, wss_port=0, interface_port=0, model=wireless_model)
        self.app = Application(
            ServeConfig(
                world=world,
                host="127.0.0.1",
                port=0,
                seed=seed,
                speed=speed,
                lockstep=lockstep,
                max_connections=max_connections,
                robot_dirs=robot_dirs,
                truth_port=0,
                image_port=0,
                **({} if sim is None else {"sim": sim}),
                image=image if image is not None else ImageSettings(),
                wireless=wireless,
                web_port=0,
                **serve_options,
            )
        )
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._serve, name="test-server-loop", daemon=True)
        self.clients: list[Client] = []
        self._started = False

    def _serve(self) -> None:
        asyncio.set_event_loop(self.loop)
        self.loop.run_forever()

    def start(self) -> ServerThread:
        self._thread.start()
        asyncio.run_coroutine_threadsafe(self.app.start(), self.loop).result(DEFAULT_TIMEOUT)
        self._started = True
        return self

    @property
    def port(self) -> int:
        return self.app.control.port

    @property
    def sim(self):
        return self.app.facade.sim

    def connect(self, *, timeout: float = DEFAULT_TIMEOUT) -> Client:
        c = Client(self.port, timeout=timeout)
        self.clients.append(c)
        return c

    def on_loop(self, fn: Callable[[], Any]) -> Any:
        """Run ``fn()`` on the server's event loop and return its result."""

        async def run():
            return fn()

        return asyncio.run_coroutine_threadsafe(run(), self.loop).result(DEFAULT_TIMEOUT)

    def on_sim(self, fn: Callable[[Any], Any]) -> Any:
        """Run ``fn(sim)`` on the simulation thread (at once, also in lock-step) and return its result."""
        from concurrent.futures import TimeoutError as FutureTimeout

        try:
            return self.app.facade.call(fn, immediate=True).result(DEFAULT_TIMEOUT)
        except FutureTimeout:
            raise WaitTimeout("the simulation thread did not answer") from None

    def robot_count(self) -> int:
        return self.on_sim(lambda sim: len(sim.robots))

    def connection_count(self) -> int:
        return self.on_loop(lambda: len(self.app.control.connections))

    def stop(self) -> None:
        for c in self.clients:
            c.close()
        if self._started:
            asyncio.run_coroutine_threadsafe(self.app.stop(), self.loop).result(DEFAULT_TIMEOUT)
            self._started = False
        if self._thread.is_alive():
            # stop after the callbacks already queued (connection_lost of closed transports)
            self.loop.call_soon_threadsafe(self.loop.stop)
            self._thread.join(DEFAULT_TIMEOUT)
        if not self.loop.is_closed() and not self._thread.is_alive():
            self.loop.close()


# --------------------------------------------------------------------------- small worlds

TEST_WORLD = """\
# A test world: a 20 m x 20 m floor, one long wall whose face is at x = 5.0 m and a short
# wall on the right of the FacingWall pose whose face is at y = 1.5 m.
name: TestArena
description: flat floor and walls at known places (tests only)
floor:
  center: [0.0, 0.0]
  size: [20.0, 20.0]
materials:
  wall: {rgba: [0.9, 0.8, 0.4, 1.0], friction: 0.8}
objects:
  # face towards the robots at x = 5.0 (centre 5.05, 0.1 thick), 1.2 m tall
  - {name: wall_n, shape: box, center: [5.05, 0.0, -0.6], size: [0.1, 12.0, 1.2], material: wall}
  # face towards FacingWall at y = 1.5 (centre 1.55), from x = 2.0 to 4.0
  - {name: wall_e, shape: box, center: [3.0, 1.55, -0.6], size: [2.0, 0.1, 1.2], material: wall}
start_poses:
  - {name: Open, location: [-6.0, 0.0, -0.2], rotation: [0.0, 0.0, 0.0]}
  - {name: OpenEast, location: [-6.0, -6.0, -0.2], rotation: [0.0, 0.0, 1.5708]}
  - {name: FacingWall, location: [3.0, 0.0, -0.2], rotation: [0.0, 0.0, 0.0]}
  - {name: Far, location: [-6.0, 6.0, -0.2], rotation: [0.0, 0.0, 0.0]}
"""
WALL_FACE_X = 5.0
RIGHT_WALL_FACE_Y = 1.5


def write_test_world(directory: Path) -> Path:
    p = Path(directory) / "TestArena.yaml"
    p.write_text(TEST_WORLD)
    return p


@cache
def gl_problem() -> str:
    """'' when an offscreen OpenGL context can be made here (pictures can be rendered), else why not."""
    import mujoco

    import usarsim  # noqa: F401  (chooses the offscreen GL backend, MUJOCO_GL, before the first context)

    box: dict[str, str] = {}

    def probe():
        try:
            m = mujoco.MjModel.from_xml_string("<mujoco><worldbody><geom size='1'/></worldbody></mujoco>")
            r = mujoco.Renderer(m, 8, 8)
            r.render()
            r.close()
            box["ok"] = ""
        except Exception as exc:  # no display, no EGL, no OSMesa
            box["ok"] = f"no OpenGL context for rendering: {exc}"

    t = threading.Thread(target=probe)
    t.start()
    t.join(60)
    return box.get("ok", "the OpenGL probe did not finish")


# Driving a robot of a Simulation directly (on its own thread, no server): the typed DRIVE
# commands of usarsim.controls, as the protocol makes them from DRIVE lines.


def drive_skid(sim, uid: int, left, right, normalized: bool = False, light=None) -> None:
    """``DRIVE {Left} {Right}``."""
    from usarsim.controls import DriveCommand, WheelSpeeds

    sim.drive(uid, DriveCommand(parts=(WheelSpeeds(left, right),), normalized=normalized, light=light))


def drive_velocities(sim, uid: int, altitude, linear, lateral, rotational, normalized: bool = False) -> None:
    """``DRIVE {AltitudeVelocity} {LinearVelocity} {LateralVelocity} {RotationalVelocity}``."""
    from usarsim.controls import DriveCommand, Velocities

    sim.drive(uid, DriveCommand(parts=(Velocities(altitude, linear, lateral, rotational),), normalized=normalized))


def drive_ackermann(sim, uid: int, speed, front, rear, normalized: bool = False) -> None:
    """``DRIVE {Speed} {FrontSteer} {RearSteer}``."""
    from usarsim.controls import AckermannDrive, DriveCommand

    sim.drive(uid, DriveCommand(parts=(AckermannDrive(speed, front, rear),), normalized=normalized))


def drive_wheels(sim, uid: int, wheels, normalized: bool = False) -> None:
    """``DRIVE {WheelNumber n} {WheelSpeed v} {WheelSteer a} ...``: ``wheels`` as (n, v, a)."""
    from usarsim.controls import DriveCommand, SteeredWheel, SteeredWheels

    sim.drive(uid, DriveCommand(parts=(SteeredWheels(tuple(SteeredWheel(*w) for w in wheels)),), normalized=normalized))


def drive_joint(sim, uid: int, name: str, value: float, order: int = 0) -> bool:
    """A joint order; False when the robot has no such joint (or no power)."""
    from usarsim.sim import joints

    r = sim.robots.get(uid)
    return r is not None and joints.order(sim, r, name, value, order)


class Tap:
    """A TCP relay between a client under test and the server at ``port`` (the client connects to
    ``tap.port``): every byte passes both ways, and the lines the server sends are kept, in
    order, as text."""

    def __init__(self, port: int):
        self.target = port
        self.listener = socket.create_server(("127.0.0.1", 0))
        self.port = self.listener.getsockname()[1]
        self.lines: list[str] = []
        self._lock = threading.Lock()
        self.pumps: list[threading.Thread] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                client, _ = self.listener.accept()
            except OSError:
                return
            server = socket.create_connection(("127.0.0.1", self.target))
            for sock in (client, server):
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            for args in ((client, server, False), (server, client, True)):
                self.pumps.append(threading.Thread(target=self._pump, args=args, daemon=True))
                self.pumps[-1].start()

    def _pump(self, src: socket.socket, dst: socket.socket, keep: bool) -> None:
        rest = b""
        try:
            while data := src.recv(1 << 16):
                dst.sendall(data)
                if keep:
                    *lines, rest = (rest + data).split(b"\r\n")
                    with self._lock:
                        self.lines.extend(line.decode("ascii", "replace") for line in lines)
        except OSError:
            pass
        finally:
            with contextlib.suppress(OSError):
                dst.shutdown(socket.SHUT_RDWR)
            src.close()

    def sen(self, sensor_type: str) -> list[str]:
        with self._lock:
            return [line for line in self.lines if line.startswith("SEN ") and f"{{Type {sensor_type}}}" in line]

    def close(self) -> None:
        self.listener.close()
        for pump in self.pumps:
            pump.join(5)
