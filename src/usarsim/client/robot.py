"""The blocking client's :class:`Robot`: one robot in the world on its own connection (as
USARSim has one robot per connection), its latest readings and the commands it sends, its
camera's pictures and its radio."""

from __future__ import annotations

import socket
from typing import TYPE_CHECKING, Any

from usarsim.protocol import messages as M

from .core import (
    PICTURE_HEADER,
    ClientError,
    ClientTimeout,
    Scan,
    accepts_reply,
    decode_picture,
    drive_command,
    drive_line,
    first_scan_name,
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

if TYPE_CHECKING:
    from .blocking import World, _Connection


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
        if name is None or r is None or not hasattr(r, "resolution_rad") or isinstance(r.resolution_rad, tuple):
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
        """``DRIVE``: ``drive(left=2, right=2)``; see :func:`usarsim.client.core.drive_command`."""
        send_command = getattr(self._conn, "send_command", None)
        if send_command is not None:  # the direct path: the command without its text
            send_command(drive_command(**keys))
        else:
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

    def read_only(self, *wanted: str) -> None:
        """Have an in-process simulator (``launch(..., transport="inproc")``) measure only this
        robot's sensors of these types or names (``read_only("RangeScanner", "Odometry")``;
        none given: every one again).  The others send nothing; the readings of those named
        are the same, bit for bit, as when every sensor is measured.  A server over TCP
        measures every sensor: there it raises :class:`ClientError`."""
        read_only = getattr(self._conn, "read_only", None)
        if read_only is None:
            raise ClientError("only an in-process simulator (transport='inproc') measures some sensors only")
        read_only(frozenset(wanted) if wanted else None)

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

    def neighbours(self) -> list:
        """Every robot whose radio link with this one holds now:
        :class:`usarsim.protocol.wireless.Neighbor` (name, dbm, quality), by name."""
        return self.radio().neighbours()

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
