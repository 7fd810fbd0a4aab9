"""The blocking client: a :class:`World` (one control connection, for STEP and queries) and a
:class:`Robot` per spawned robot (its own connection, as USARSim has one robot per
connection).  Every wait has a timeout and raises :class:`ClientTimeout` naming what did not
arrive; a server that closes the connection raises :class:`ClientError`."""

from __future__ import annotations

import selectors
import socket
import time
from collections.abc import Callable
from typing import Any

from usarsim.protocol import messages as M
from usarsim.protocol.truth import TruthObject, format_truth_request, parse_truth_object

from .core import (
    DEFAULT_TIMEOUT_S,
    PICTURE_HEADER,
    ClientError,
    ClientTimeout,
    ConnectionState,
    Scan,
    accepts_reply,
    decode_picture,
    drive_line,
    first_scan_name,
    init_line,
    is_report_reply,
    max_range_of,
    mispkg_line,
    odometry_of,
    picture_size,
    pose_of,
    query_line,
    report_line,
    scan_of,
    set_line,
    victims_of,
)


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


class Robot:
    """One robot in the world, on its own connection.  Its latest readings update whenever
    the client reads (:meth:`World.step`, :meth:`World.wait`, :meth:`update`)."""

    def __init__(self, world: World, conn: _Connection, class_name: str, name: str):
        self.world = world
        self._conn = conn
        self.class_name = class_name
        self.name = name
        self._max_ranges: dict[str, float | None] = {}
        self._image: socket.socket | None = None
        self._image_camera: str | None = None
        self._radio = None  # usarsim.client.radio.Radio, made on first use

    # what it knows ----------------------------------------------------------------------
    @property
    def readings(self) -> dict[str, Any]:
        """The latest reading of each sensor, by name (packed sensors by type: ``Sonar``)."""
        return self._conn.state.readings

    @property
    def status(self):
        """The latest STA (typed: battery, steer angles, ...), or None."""
        return self._conn.state.status

    @property
    def time(self) -> float | None:
        """The simulated time of the latest message received for this robot."""
        return self._conn.state.time

    @property
    def messages(self) -> list[Any]:
        """Every message received since :meth:`take_messages` was last called."""
        return self._conn.state.messages

    def take_messages(self) -> list[Any]:
        return self._conn.state.take_messages()

    def fileno(self) -> int:
        """The connection's socket, for a selector that waits on many robots (then
        :meth:`update` reads what came)."""
        return self._conn.sock.fileno()

    @property
    def closed(self) -> bool:
        """True once the server closed this robot's connection (or :meth:`close` did)."""
        return self._conn.state.closed

    def reading(self, name: str) -> Any:
        return self.readings.get(name)

    def scan(self, name: str | None = None) -> Scan | None:
        """The latest laser sweep (the first RangeScanner when no name is given), or None."""
        name = name or first_scan_name(self.readings)
        r = self.readings.get(name) if name else None
        if r is None or not hasattr(r, "resolution_rad") or isinstance(r.resolution_rad, tuple):
            return None
        if name not in self._max_ranges:
            self._max_ranges[name] = max_range_of(self.conf(r.sensor_type, name), name)
        return scan_of(self._conn.state.reading_times.get(name), r, self._max_ranges[name])

    def odometry(self) -> tuple[float, float, float] | None:
        """The Odometry sensor's (x, y, yaw) (USARSim frame, yaw clockwise), or None."""
        return odometry_of(self.readings)

    def ground_truth(self) -> tuple[tuple, tuple] | None:
        """The GroundTruth sensor's (location, orientation), or None."""
        return pose_of(self.readings, "GroundTruth")

    def victims(self) -> list:
        """The victim parts the VictSensor sees now (``part_name``, ``location`` in the victim
        sensor's frame, as the server reports them: add the sensor's mount from
        ``geo("VictSensor")`` for the robot's frame)."""
        return victims_of(self.readings)

    # commands ---------------------------------------------------------------------------
    def drive(self, **keys: Any) -> None:
        """``DRIVE``: ``drive(left=2, right=2)``; see :func:`usarsim.client.core.drive_line`."""
        self._conn.send(drive_line(**keys))

    def move(self, package: str, values: dict[int, float], order: int = 0) -> None:
        """Mission-package links (an arm, a pan-tilt) to positions: ``move("CameraPanTilt",
        {1: 0.3, 2: -0.1})`` (rad or m; ``order`` as MISPKG's)."""
        self._conn.send(mispkg_line(package, values, order))

    def links(self, package: str) -> dict[int, float] | None:
        """The latest position of each link of a mission package (its MISSTA), or None."""
        st = self._conn.state.packages.get(package)
        return None if st is None else {k.link: k.value for k in st.links}

    def send(self, line: str) -> None:
        """A raw protocol line (CR LF added when missing)."""
        self._conn.send(line if line.endswith("\n") else line + "\r\n")

    def geo(self, type: str = "Robot", name: str | None = None) -> Any:  # noqa: A002 (the protocol's key)
        self._conn.send(query_line("GETGEO", type, name))
        return self._conn.wait_for(accepts_reply("GETGEO", type), f"GEO of {type}", "GETGEO")

    def conf(self, type: str = "Robot", name: str | None = None) -> Any:  # noqa: A002
        self._conn.send(query_line("GETCONF", type, name))
        return self._conn.wait_for(accepts_reply("GETCONF", type), f"CONF of {type}", "GETCONF")

    def set(
        self,
        type: str,
        name: str | None = None,
        opcode: str | None = None,  # noqa: A002
        params: Any = None,
    ) -> M.Result | None:
        """``SET`` on a mounted item: waits for and returns its RES (in lock-step too: the
        server carries it out at once, at the current simulated time)."""
        self._conn.send(set_line(type, name, opcode, params))
        return self._conn.wait_for(lambda m: isinstance(m, (M.Result, M.CameraZoomResult)), f"RES of SET {type}", "SET")

    def report_victim(self, location, name: str | None = None) -> M.Result:
        """Report a victim at ``location`` (world frame, USARSim axes, metres) for the score:
        ``REPORT {Type Victim}`` (an extension, docs/scoring.md); returns the server's RES."""
        self._conn.send(report_line(location, name))
        return self._conn.wait_for(is_report_reply, "RES of REPORT", "REPORT")

    def picture(self, camera: str = "Camera", timeout: float | None = None) -> Any:
        """A picture of the robot's camera ``camera`` from the image server, as a (height,
        width, 3) uint8 RGB NumPy array (the server needs its image service: ``launch(...,
        image=True)``; the size is its ``--image-size``)."""
        limit = self._conn.timeout if timeout is None else timeout
        if self._image is None:
            port = self.world.image_port
            try:
                self._image = socket.create_connection((self.world.host, port), timeout=limit)
            except OSError as exc:
                raise ClientError(
                    f"cannot reach the image server at {self.world.host}:{port} ({exc}); "
                    f"launch(..., image=True) starts it"
                ) from exc
        if self._image_camera != camera:
            local_port = self._image.getsockname()[1]
            self.send(
                set_line("Camera", camera, None, None).rstrip("\r\n")
                + f" {{Robot {self.name}}} {{Client 127.0.0.1:{local_port}}}"
            )
            self._conn.ping(limit)  # the binding is in place
            self._image_camera = camera
        self._image.settimeout(limit)
        try:
            self._image.sendall(b"OK")
            header = self._recv_exactly(PICTURE_HEADER)
            image_type, length = picture_size(header)
            return decode_picture(image_type, self._recv_exactly(length))
        except TimeoutError:
            raise ClientTimeout(f"robot {self.name}: no picture of {camera} within {limit:g} s") from None

    def _recv_exactly(self, n: int) -> bytes:
        assert self._image is not None
        chunks, got = [], 0
        while got < n:
            data = self._image.recv(min(n - got, 1 << 20))
            if not data:
                raise ClientError(f"robot {self.name}: the image server closed the connection")
            chunks.append(data)
            got += len(data)
        return b"".join(chunks)

    # the radio (the simulator's ComServer: launch(..., wireless=True)) -------------------
    def radio(self):
        """This robot's :class:`usarsim.client.radio.Radio`, registered with the ComServer."""
        if self._radio is None:
            from .radio import Radio, RadioError

            try:
                self._radio = Radio(self.world.host, self.world.comserver_port, self.name, timeout=self._conn.timeout)
            except RadioError as exc:
                raise ClientError(f"robot {self.name}: {exc} (launch(..., wireless=True) starts it)") from exc
        return self._radio

    def signal_to(self, other: Robot | str) -> float | None:
        """The signal strength (dBm) from this robot to ``other`` under the simulator's radio
        model, or None when there is none."""
        return self.radio().signal(other if isinstance(other, str) else other.name)

    def send_to(self, other: Robot, data: bytes) -> bool:
        """Send ``data`` to another robot of this client over the simulated radio: a link is
        opened through the ComServer when there is none; False when the ComServer refuses it
        (no signal) or closed it.  The other robot gets it from :meth:`received`."""
        from .radio import link

        mine, theirs = self.radio(), other.radio()
        if other.name not in mine.links and not link(mine, theirs):
            return False
        return mine.send(other.name, data)

    def received(self) -> list[tuple[str, bytes]]:
        """The messages other robots sent to this one since the last call: (sender, bytes)."""
        return [] if self._radio is None else self._radio.poll()

    def update(self, wait: float = 0.0) -> None:
        """Read what has arrived (waiting up to ``wait`` seconds for something)."""
        if not self._conn.read(wait) and not self._conn.state.messages:
            raise ClientError(f"robot {self.name}: the server closed the connection")

    def close(self) -> None:
        """Close the connection: the robot leaves the world."""
        if self._radio is not None:
            self._radio.close()
            self._radio = None
        if self._image is not None:
            self._image.close()
            self._image = None
        self._conn.close()
        self.world._robots.pop(self.name, None)


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
        self._conn = _Connection(host, port, timeout, "world")
        try:
            info = self._conn.wait_for(lambda m: isinstance(m, M.GameInfo), "NFO greeting", None)
        except BaseException:
            self._conn.close()
            raise
        self.level: str = info.level
        self._robots: dict[str, Robot] = {}
        self._start_poses: list[M.StartPose] | None = None
        self.time = 0.0

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
        conn = _Connection(self.host, self.port, self.timeout if timeout is None else timeout, f"robot {name}")
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
            if only_sent and not conn.sent:
                continue
            pid = conn.state.next_ping()
            conn.send(f"PING {{Id {pid}}}\r\n")
            conn.sent = False
            pending.append((conn, pid))
        for conn, pid in pending:
            conn.wait_for(
                lambda m, pid=pid: isinstance(m, M.Pong) and m.id == pid, "PONG (the reply to PING)", None, timeout
            )

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
        try:
            s = socket.create_connection((self.host, self.truth_port), timeout=self.timeout)
        except OSError as exc:
            raise ClientError(
                f"cannot reach the ground-truth service at {self.host}:{self.truth_port} ({exc})"
            ) from exc
        out: list[TruthObject] = []
        with s:
            s.sendall(format_truth_request(class_name, name).encode("ascii"))
            buf = b""
            deadline = time.monotonic() + self.timeout
            while True:
                while b"\n" in buf:
                    line, buf = buf.split(b"\n", 1)
                    obj = parse_truth_object(line.decode("ascii", "replace"))
                    if obj is None:
                        return out
                    out.append(obj)
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
