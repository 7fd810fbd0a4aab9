"""The blocking client: a :class:`World` (one control connection, for STEP and queries) and a
:class:`Robot` per spawned robot (:mod:`usarsim.client.robot`: its own connection, as USARSim
has one robot per connection).  Every wait has a timeout and raises :class:`ClientTimeout`
naming what did not arrive; a server that closes the connection raises :class:`ClientError`."""

from __future__ import annotations

import selectors
import socket
import time
from collections.abc import Callable
from typing import Any

from usarsim.protocol import messages as M
from usarsim.protocol.truth import (
    DEFAULT_MAP_HEIGHT_M,
    DEFAULT_MAP_RESOLUTION_M,
    TruthObject,
    format_map_request,
    format_truth_request,
    parse_map_answer,
    parse_truth_object,
)

from .core import DEFAULT_TIMEOUT_S, ClientError, ClientTimeout, ConnectionState, init_line
from .robot import Robot
from .truthmap import GroundTruthGrid

__all__ = ["Robot", "World", "connect"]


class _Connection:
    """A socket and what was received on it."""

    def __init__(self, host: str, port: int, timeout: float, what: str):
        self.what = what
        self.timeout = timeout
        try:
            self.sock = socket.create_connection((host, port), timeout=timeout)
        except OSError as exc:
            raise ClientError(
                f"cannot connect to the simulator at {host}:{port} ({exc}); is 'usarsim serve' running there?"
            ) from exc
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.state = ConnectionState()
        self.sent = False  # a command went out since the last PING
        # every command is carried out before send() returns (an in-process simulator's
        # connection): no PING is needed to know it has arrived
        self.synchronous = False

    def send(self, line: str) -> None:
        if self.state.closed:
            raise ClientError(f"{self.what}: the connection is closed")
        self.sent = True
        try:
            self.sock.sendall(line.encode("ascii"))
        except OSError as exc:
            self.state.closed = True
            raise ClientError(f"{self.what}: the server closed the connection ({exc})") from exc

    def read(self, wait: float) -> bool:
        """Read what arrives within ``wait`` seconds (0: only what is there); False at EOF."""
        if self.state.closed:
            return False
        self.sock.settimeout(wait if wait > 0 else 0.0)
        try:
            data = self.sock.recv(1 << 18)
        except (BlockingIOError, TimeoutError):
            return True
        except OSError:
            data = b""
        if not data:
            self.close()  # the server closed it
            return False
        self.state.feed(data)
        return True

    def wait_for(
        self, accept: Callable[[Any], bool], what: str, command: str | None, timeout: float | None = None
    ) -> Any:
        """The first reply ``accept`` takes, reading until it comes; an ERROR about
        ``command`` raises :class:`ServerError`."""
        deadline = time.monotonic() + (self.timeout if timeout is None else timeout)
        while True:
            msg = self.state.claim(accept, command)
            if msg is not None:
                return msg
            left = deadline - time.monotonic()
            if left <= 0:
                raise ClientTimeout(
                    f"{self.what}: no {what} from the server within {self.timeout if timeout is None else timeout:g} s"
                )
            if not self.read(left):
                msg = self.state.claim(accept, command)
                if msg is not None:
                    return msg
                raise ClientError(f"{self.what}: the server closed the connection while waiting for {what}")

    def ping(self, timeout: float | None = None, command: str | None = None) -> M.Pong:
        """PING, and wait for its PONG: everything sent before it has been handled and every
        message produced so far has been read."""
        pid = self.state.next_ping()
        self.send(f"PING {{Id {pid}}}\r\n")
        self.sent = False
        return self.wait_for(
            lambda m: isinstance(m, M.Pong) and m.id == pid, "PONG (the reply to PING)", command, timeout
        )

    def close(self) -> None:
        self.state.closed = True
        try:
            self.sock.close()
        except OSError:
            pass


def _is_pong(pid: str) -> Callable[[Any], bool]:
    """Takes the PONG that answers the PING with id ``pid``."""
    return lambda m: isinstance(m, M.Pong) and m.id == pid


class World:
    """A simulator to talk to: start poses, spawning robots, lock-step STEPs, ground truth."""

    def __init__(
        self,
        host: str = "127.0.0.1",
        port: int = 3000,
        *,
        lockstep: bool = False,
        truth_port: int | None = None,
        image_port: int | None = None,
        comserver_port: int | None = None,
        timeout: float = DEFAULT_TIMEOUT_S,
    ):
        self.host, self.port, self.lockstep, self.timeout = host, port, lockstep, timeout
        self.image_port = image_port if image_port is not None else port + 2003  # 3000 -> 5003
        self.comserver_port = comserver_port if comserver_port is not None else port + 2874  # 3000 -> 5874
        self.truth_port = truth_port if truth_port is not None else port + 989  # 3000 -> 3989
        self._conn = self._open("world", timeout)
        try:
            info = self._conn.wait_for(lambda m: isinstance(m, M.GameInfo), "NFO greeting", None)
        except BaseException:
            self._conn.close()
            raise
        self.level: str = info.level
        self._robots: dict[str, Robot] = {}
        self._start_poses: list[M.StartPose] | None = None
        self.time = 0.0

    def _open(self, what: str, timeout: float) -> _Connection:
        """A new connection to the simulator (``what``: who it is for, as errors name it)."""
        return _Connection(self.host, self.port, timeout, what)

    def __enter__(self) -> World:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    @property
    def robots(self) -> dict[str, Robot]:
        return dict(self._robots)

    @property
    def start_poses(self) -> list[M.StartPose]:
        if self._start_poses is None:
            self._conn.send("GETSTARTPOSES\r\n")
            reply = self._conn.wait_for(lambda m: isinstance(m, M.StartPoses), "NFO {StartPoses}", "GETSTARTPOSES")
            self._start_poses = list(reply.poses)
        return list(self._start_poses)

    def spawn(
        self,
        class_name: str,
        name: str | None = None,
        *,
        start: str | None = None,
        location=None,
        rotation=None,
        timeout: float | None = None,
    ) -> Robot:
        """A robot of ``class_name`` (``P2AT`` or ``USARBot.P2AT``) at start pose ``start``, or
        at ``location``/``rotation``, or at the world's first start pose.  Returns once it
        stands in the world; raises :class:`ServerError` with the server's reason if not."""
        name = name or f"Robot{len(self._robots) + 1}"
        if name in self._robots:
            raise ClientError(f"this client has a robot named {name!r} already")
        conn = self._open(f"robot {name}", self.timeout if timeout is None else timeout)
        try:
            conn.wait_for(lambda m: isinstance(m, M.GameInfo), "NFO greeting", None)
            conn.send(init_line(class_name, name, start, location, rotation))
            conn.ping(command="INIT")  # after the spawn, or after its ERROR
            conn.state.claim(lambda m: False, "INIT")  # an ERROR that came with the PONG
        except BaseException:
            conn.close()
            raise
        robot = Robot(self, conn, class_name.split(".")[-1], name)
        self._robots[name] = robot
        return robot

    def step(self, seconds: float, timeout: float | None = None) -> float:
        """Lock-step: advance ``seconds`` of simulated time.  Returns the new simulated time
        once every robot of this client has read every message up to it."""
        if not self.lockstep:
            raise ClientError(
                "step() needs a lock-step server (usarsim serve --lockstep, or launch(lockstep=True)); "
                "use wait(seconds) in real time"
            )
        # the robots' commands (DRIVE, SET...) reach the simulation before the STEP does: each
        # robot connection is a socket of its own, and the server reads them in no fixed order
        self._sync(timeout, only_sent=True)
        self._conn.send(f"STEP {{Time {seconds!r}}}\r\n")
        stepped = self._conn.wait_for(
            lambda m: isinstance(m, M.Stepped), f"STEPPED after STEP {seconds:g}", "STEP", timeout
        )
        self.time = stepped.time
        self._sync(timeout)
        return self.time

    def _sync(self, timeout: float | None, only_sent: bool = False) -> None:
        """Every robot connection read up to now, and its commands handed to the simulation
        (a PING each, sent together; ``only_sent``: only those that sent something since)."""
        pending = []
        for robot in list(self._robots.values()):
            conn = robot._conn
            if conn.synchronous or (only_sent and not conn.sent):
                continue
            pid = conn.state.next_ping()
            conn.send(f"PING {{Id {pid}}}\r\n")
            conn.sent = False
            pending.append((conn, pid))
        for conn, pid in pending:
            conn.wait_for(_is_pong(pid), "PONG (the reply to PING)", None, timeout)

    def wait(self, seconds: float) -> None:
        """Real time: read every robot's messages for ``seconds`` of wall time."""
        deadline = time.monotonic() + seconds
        sel = selectors.DefaultSelector()
        try:
            for robot in self._robots.values():
                if not robot._conn.state.closed:
                    sel.register(robot._conn.sock, selectors.EVENT_READ, robot._conn)
            while True:
                left = deadline - time.monotonic()
                if left <= 0:
                    break
                if not sel.get_map():
                    time.sleep(left)
                    break
                for key, _ in sel.select(left):
                    conn = key.data
                    if not conn.read(0.0):
                        sel.unregister(conn.sock)
        finally:
            sel.close()
        for robot in self._robots.values():
            t = robot._conn.state.time
            if t is not None and t > self.time:
                self.time = t

    def truth(self, class_name: str | None = None, name: str | None = None) -> list[TruthObject]:
        """Where things are now, from the ground-truth service: robots, victims, RFID tags,
        false alarms and movable objects (``class_name``/``name`` filter)."""
        return self._truth(class_name, name)

    def _truth(self, class_name: str | None, name: str | None) -> list[TruthObject]:
        out: list[TruthObject] = []
        for line in self._truth_lines(format_truth_request(class_name, name)):
            obj = parse_truth_object(line)
            if obj is not None:
                out.append(obj)
        return out

    def ground_truth_map(
        self, resolution: float = DEFAULT_MAP_RESOLUTION_M, height: float = DEFAULT_MAP_HEIGHT_M
    ) -> GroundTruthGrid:
        """The world's ground-truth occupancy map from the ground-truth service (``{Map}``, our
        extension): the world as served (its variant applied), ``resolution`` metres a cell,
        ``height`` metres above the floor (docs/scoring.md, "Map quality")."""
        import zlib

        import numpy as np

        lines = self._truth_lines(format_map_request(resolution, height))
        header, payload = parse_map_answer(lines)
        data = np.frombuffer(zlib.decompress(payload), np.int8).reshape(header.height, header.width)
        return GroundTruthGrid(header, data)

    def _truth_lines(self, request: str) -> list[str]:
        """The lines of the ground-truth service's answer to ``request``, before ``{End}``."""
        try:
            s = socket.create_connection((self.host, self.truth_port), timeout=self.timeout)
        except OSError as exc:
            raise ClientError(
                f"cannot reach the ground-truth service at {self.host}:{self.truth_port} ({exc})"
            ) from exc
        out: list[str] = []
        with s:
            s.sendall(request.encode("ascii"))
            buf = b""
            deadline = time.monotonic() + self.timeout
            while True:
                while b"\n" in buf:
                    raw, buf = buf.split(b"\n", 1)
                    line = raw.decode("ascii", "replace")
                    if line.strip() == "{End}":
                        return out
                    out.append(line)
                left = deadline - time.monotonic()
                if left <= 0:
                    raise ClientTimeout(f"no {{End}} from the ground-truth service within {self.timeout:g} s")
                s.settimeout(left)
                try:
                    data = s.recv(1 << 16)
                except TimeoutError:
                    continue
                if not data:
                    raise ClientError("the ground-truth service closed the connection before {End}")
                buf += data

    def close(self) -> None:
        for robot in list(self._robots.values()):
            robot.close()
        self._conn.close()


def connect(
    host: str = "127.0.0.1",
    port: int = 3000,
    *,
    lockstep: bool = False,
    truth_port: int | None = None,
    image_port: int | None = None,
    comserver_port: int | None = None,
    timeout: float = DEFAULT_TIMEOUT_S,
) -> World:
    """Connect to a running simulator (``lockstep=True`` if it was started with
    ``--lockstep``: then :meth:`World.step` drives its clock)."""
    return World(
        host,
        port,
        lockstep=lockstep,
        truth_port=truth_port,
        image_port=image_port,
        comserver_port=comserver_port,
        timeout=timeout,
    )
