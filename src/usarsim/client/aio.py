"""The asyncio client: the same names as the blocking one (:mod:`usarsim.client.blocking`),
as coroutines.  ``world = await connect(...)``, ``robot = await world.spawn("P2AT")``,
``await world.step(0.1)``, ``await robot.conf("RangeScanner")``; readings are plain
attributes, updated as lines arrive (each connection is read by a task of its own)."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

from usarsim.protocol import messages as M
from usarsim.protocol.truth import TruthObject, format_truth_request, parse_truth_object

from .core import (
    DEFAULT_TIMEOUT_S,
    ClientError,
    ClientTimeout,
    ConnectionState,
    Scan,
    accepts_reply,
    drive_line,
    first_scan_name,
    init_line,
    is_report_reply,
    max_range_of,
    mispkg_line,
    odometry_of,
    pose_of,
    query_line,
    report_line,
    scan_of,
    set_line,
    victims_of,
)


class _Connection:
    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, timeout: float, what: str):
        self.reader, self.writer, self.timeout, self.what = reader, writer, timeout, what
        self.state = ConnectionState()
        self.sent = False  # a command went out since the last PING
        self._arrived = asyncio.Event()
        self._task = asyncio.get_running_loop().create_task(self._read())

    @classmethod
    async def open(cls, host: str, port: int, timeout: float, what: str) -> _Connection:
        try:
            reader, writer = await asyncio.wait_for(asyncio.open_connection(host, port), timeout)
        except (TimeoutError, OSError) as exc:
            raise ClientError(
                f"cannot connect to the simulator at {host}:{port} ({exc}); is 'usarsim serve' running there?"
            ) from exc
        return cls(reader, writer, timeout, what)

    async def _read(self) -> None:
        try:
            while True:
                data = await self.reader.read(1 << 18)
                if not data:
                    break
                self.state.feed(data)
                self._arrived.set()
        except (OSError, asyncio.CancelledError):
            pass
        finally:
            self.state.closed = True
            self._arrived.set()

    async def send(self, line: str) -> None:
        if self.state.closed:
            raise ClientError(f"{self.what}: the connection is closed")
        self.sent = True
        self.writer.write(line.encode("ascii"))
        try:
            await self.writer.drain()
        except OSError as exc:
            raise ClientError(f"{self.what}: the server closed the connection ({exc})") from exc

    async def wait_for(
        self, accept: Callable[[Any], bool], what: str, command: str | None, timeout: float | None = None
    ) -> Any:
        limit = self.timeout if timeout is None else timeout
        loop = asyncio.get_running_loop()
        deadline = loop.time() + limit
        while True:
            msg = self.state.claim(accept, command)
            if msg is not None:
                return msg
            if self.state.closed:
                raise ClientError(f"{self.what}: the server closed the connection while waiting for {what}")
            left = deadline - loop.time()
            if left <= 0:
                raise ClientTimeout(f"{self.what}: no {what} from the server within {limit:g} s")
            self._arrived.clear()
            try:
                await asyncio.wait_for(self._arrived.wait(), left)
            except TimeoutError:
                pass

    async def ping(self, timeout: float | None = None, command: str | None = None) -> M.Pong:
        pid = self.state.next_ping()
        await self.send(f"PING {{Id {pid}}}\r\n")
        self.sent = False
        return await self.wait_for(
            lambda m: isinstance(m, M.Pong) and m.id == pid, "PONG (the reply to PING)", command, timeout
        )

    async def close(self) -> None:
        self._task.cancel()
        self.writer.close()
        try:
            await self.writer.wait_closed()
        except OSError:
            pass
        self.state.closed = True


class Robot:
    """One robot on its own connection (see :class:`usarsim.client.blocking.Robot`)."""

    def __init__(self, world: World, conn: _Connection, class_name: str, name: str):
        self.world, self._conn, self.class_name, self.name = world, conn, class_name, name
        self._max_ranges: dict[str, float | None] = {}

    @property
    def readings(self) -> dict[str, Any]:
        return self._conn.state.readings

    @property
    def status(self):
        return self._conn.state.status

    @property
    def time(self) -> float | None:
        return self._conn.state.time

    @property
    def messages(self) -> list[Any]:
        return self._conn.state.messages

    def take_messages(self) -> list[Any]:
        return self._conn.state.take_messages()

    def reading(self, name: str) -> Any:
        return self.readings.get(name)

    async def scan(self, name: str | None = None) -> Scan | None:
        name = name or first_scan_name(self.readings)
        r = self.readings.get(name) if name else None
        if name is None or r is None or not hasattr(r, "resolution_rad") or isinstance(r.resolution_rad, tuple):
            return None
        if name not in self._max_ranges:
            self._max_ranges[name] = max_range_of(await self.conf(r.sensor_type, name), name)
        return scan_of(self._conn.state.reading_times.get(name), r, self._max_ranges[name])

    def odometry(self) -> tuple[float, float, float] | None:
        return odometry_of(self.readings)

    def ground_truth(self) -> tuple[tuple, tuple] | None:
        return pose_of(self.readings, "GroundTruth")

    def victims(self) -> list:
        return victims_of(self.readings)

    async def drive(self, **keys: Any) -> None:
        await self._conn.send(drive_line(**keys))

    async def move(self, package: str, values: dict[int, float], order: int = 0) -> None:
        await self._conn.send(mispkg_line(package, values, order))

    def links(self, package: str) -> dict[int, float] | None:
        st = self._conn.state.packages.get(package)
        return None if st is None else {k.link: k.value for k in st.links}

    async def send(self, line: str) -> None:
        await self._conn.send(line if line.endswith("\n") else line + "\r\n")

    async def geo(self, type: str = "Robot", name: str | None = None) -> Any:  # noqa: A002
        await self._conn.send(query_line("GETGEO", type, name))
        return await self._conn.wait_for(accepts_reply("GETGEO", type), f"GEO of {type}", "GETGEO")

    async def conf(self, type: str = "Robot", name: str | None = None) -> Any:  # noqa: A002
        await self._conn.send(query_line("GETCONF", type, name))
        return await self._conn.wait_for(accepts_reply("GETCONF", type), f"CONF of {type}", "GETCONF")

    async def set(
        self,
        type: str,
        name: str | None = None,
        opcode: str | None = None,  # noqa: A002
        params: Any = None,
    ) -> M.Result | None:
        await self._conn.send(set_line(type, name, opcode, params))
        return await self._conn.wait_for(
            lambda m: isinstance(m, (M.Result, M.CameraZoomResult)), f"RES of SET {type}", "SET"
        )

    async def report_victim(self, location, name: str | None = None) -> M.Result:
        """Report a victim at ``location`` for the score (see the blocking client's)."""
        await self._conn.send(report_line(location, name))
        return await self._conn.wait_for(is_report_reply, "RES of REPORT", "REPORT")

    async def close(self) -> None:
        await self._conn.close()
        self.world._robots.pop(self.name, None)


class World:
    """A simulator to talk to (see :class:`usarsim.client.blocking.World`); make one with
    ``await connect(...)``."""

    def __init__(self, conn: _Connection, host: str, port: int, lockstep: bool, truth_port: int, timeout: float):
        self._conn, self.host, self.port, self.lockstep = conn, host, port, lockstep
        self.truth_port, self.timeout = truth_port, timeout
        self._robots: dict[str, Robot] = {}
        self._start_poses: list[M.StartPose] | None = None
        self.time = 0.0
        self.level = ""

    async def __aenter__(self) -> World:
        return self

    async def __aexit__(self, *exc: Any) -> None:
        await self.close()

    @property
    def robots(self) -> dict[str, Robot]:
        return dict(self._robots)

    async def start_poses(self) -> list[M.StartPose]:
        if self._start_poses is None:
            await self._conn.send("GETSTARTPOSES\r\n")
            reply = await self._conn.wait_for(
                lambda m: isinstance(m, M.StartPoses), "NFO {StartPoses}", "GETSTARTPOSES"
            )
            self._start_poses = list(reply.poses)
        return list(self._start_poses)

    async def spawn(
        self,
        class_name: str,
        name: str | None = None,
        *,
        start: str | None = None,
        location=None,
        rotation=None,
        timeout: float | None = None,
    ) -> Robot:
        name = name or f"Robot{len(self._robots) + 1}"
        if name in self._robots:
            raise ClientError(f"this client has a robot named {name!r} already")
        conn = await _Connection.open(
            self.host, self.port, self.timeout if timeout is None else timeout, f"robot {name}"
        )
        try:
            await conn.wait_for(lambda m: isinstance(m, M.GameInfo), "NFO greeting", None)
            await conn.send(init_line(class_name, name, start, location, rotation))
            await conn.ping(command="INIT")
            conn.state.claim(lambda m: False, "INIT")
        except BaseException:
            await conn.close()
            raise
        robot = Robot(self, conn, class_name.split(".")[-1], name)
        self._robots[name] = robot
        return robot

    async def step(self, seconds: float, timeout: float | None = None) -> float:
        if not self.lockstep:
            raise ClientError("step() needs a lock-step server; use wait(seconds) in real time")
        # the robots' commands reach the simulation before the STEP does (see the blocking client)
        await asyncio.gather(*(r._conn.ping(timeout) for r in list(self._robots.values()) if r._conn.sent))
        await self._conn.send(f"STEP {{Time {seconds!r}}}\r\n")
        stepped = await self._conn.wait_for(
            lambda m: isinstance(m, M.Stepped), f"STEPPED after STEP {seconds:g}", "STEP", timeout
        )
        self.time = stepped.time
        await asyncio.gather(*(r._conn.ping(timeout) for r in list(self._robots.values())))
        return self.time

    async def wait(self, seconds: float) -> None:
        """Real time: let ``seconds`` pass while every connection is read."""
        await asyncio.sleep(seconds)
        for robot in self._robots.values():
            t = robot._conn.state.time
            if t is not None and t > self.time:
                self.time = t

    async def truth(self, class_name: str | None = None, name: str | None = None) -> list[TruthObject]:
        try:
            reader, writer = await asyncio.wait_for(asyncio.open_connection(self.host, self.truth_port), self.timeout)
        except (TimeoutError, OSError) as exc:
            raise ClientError(
                f"cannot reach the ground-truth service at {self.host}:{self.truth_port} ({exc})"
            ) from exc
        out: list[TruthObject] = []
        try:
            writer.write(format_truth_request(class_name, name).encode("ascii"))
            while True:
                try:
                    line = await asyncio.wait_for(reader.readline(), self.timeout)
                except TimeoutError:
                    raise ClientTimeout(f"no {{End}} from the ground-truth service within {self.timeout:g} s") from None
                if not line:
                    raise ClientError("the ground-truth service closed the connection before {End}")
                obj = parse_truth_object(line.decode("ascii", "replace"))
                if obj is None:
                    return out
                out.append(obj)
        finally:
            writer.close()

    async def close(self) -> None:
        for robot in list(self._robots.values()):
            await robot.close()
        await self._conn.close()


async def connect(
    host: str = "127.0.0.1",
    port: int = 3000,
    *,
    lockstep: bool = False,
    truth_port: int | None = None,
    timeout: float = DEFAULT_TIMEOUT_S,
) -> World:
    conn = await _Connection.open(host, port, timeout, "world")
    try:
        info = await conn.wait_for(lambda m: isinstance(m, M.GameInfo), "NFO greeting", None)
    except BaseException:
        await conn.close()
        raise
    world = World(conn, host, port, lockstep, truth_port if truth_port is not None else port + 989, timeout)
    world.level = info.level
    return world
