"""What the client knows of a connection, without any I/O: the lines it received, parsed by
the protocol layer (:mod:`usarsim.protocol`), kept as the latest reading per sensor, the
latest status and the replies waiting to be claimed; and the command lines it sends.

The blocking client (:mod:`usarsim.client.blocking`) and the asyncio one
(:mod:`usarsim.client.aio`) feed bytes in and take lines out; everything else is here.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from usarsim.errors import ProtocolError, UsarsimError
from usarsim.protocol import commands as C
from usarsim.protocol import messages as M
from usarsim.protocol.framing import LineBuffer
from usarsim.protocol.grammar import format_segment
from usarsim.readings import (
    OdometryReading,
    PackageState,
    PoseReading,
    RangeScanReading,
    RobotStatus,
    VictimPart,
    VictimReading,
)

# The longest line the client accepts: a camera-free robot's lines are a few kB; a RangeScanner3D
# sweep that fits one line stays under 4 kB, but servers of other kinds may send more.
MAX_LINE_BYTES = 1 << 22
DEFAULT_TIMEOUT_S = 10.0


class ClientError(UsarsimError):
    """Something the client asked for did not happen (the server closed, refused, ...)."""


class ClientTimeout(ClientError, TimeoutError):
    """A wait ran out: the message names what did not arrive."""


class ServerError(ClientError):
    """The server answered ``ERROR {Command c} {Reason r}``."""

    def __init__(self, command: str, reason: str):
        super().__init__(f"the server refused {command}: {reason}")
        self.command = command
        self.reason = reason


@dataclass(frozen=True)
class Scan:
    """A laser sweep.  ``ranges`` in metres, in the order USARSim sends them (the first is
    the rightmost beam); ``angles`` the beam directions in radians, 0 straight ahead,
    counter-clockwise positive seen from above (negative = to the right); ``max_range`` the
    scanner's (from its CONF; None when unknown)."""

    time: float | None
    name: str
    ranges: np.ndarray
    angles: np.ndarray
    max_range: float | None = None

    def points(self) -> np.ndarray:
        """The beams' end points as an (n, 2) array in the robot's USARSim frame (X forward,
        Y to the right), metres."""
        return np.column_stack((self.ranges * np.cos(self.angles), -self.ranges * np.sin(self.angles)))


def scan_of(time: float | None, r: RangeScanReading, max_range: float | None) -> Scan:
    ranges = np.asarray(r.ranges_m, dtype=float)
    n = len(ranges)
    half = (n - 1) * r.resolution_rad / 2.0 if n > 1 else 0.0
    return Scan(time, r.name, ranges, np.linspace(-half, half, n) if n else np.zeros(0), max_range)


def reading_key(reading: Any) -> str:
    """The key of a reading in :attr:`RobotState.readings`: the sensor's name, or for a
    packed reading of several sensors (Sonar, Encoder, Touch) its type."""
    name = getattr(reading, "name", None)
    if name:
        return name
    return getattr(reading, "sensor_type", None) or type(reading).__name__.removesuffix("Reading")


# Messages a client waits for (the rest stream: STA, SEN, MISSTA, ASTA)
REPLIES = (
    M.GameInfo,
    M.StartPoses,
    M.RobotGeometry,
    M.RobotConfiguration,
    M.ItemGeometry,
    M.EmptyGeometry,
    M.ItemConfiguration,
    M.EmptyConfiguration,
    M.MisPkgGeometry,
    M.MisPkgConfiguration,
    M.ActuatorConfiguration,
    M.ActuatorGeometry,
    M.Result,
    M.CameraZoomResult,
    M.ViewportsResult,
    M.Stepped,
    M.Pong,
    M.ErrorReply,
)


class ConnectionState:
    """One connection's received lines: the latest status, reading per sensor and time, every
    message (until taken), and the replies not yet claimed by a wait."""

    def __init__(self) -> None:
        self.buffer = LineBuffer(max_line_bytes=MAX_LINE_BYTES)
        self.readings: dict[str, Any] = {}
        self.reading_times: dict[str, float | None] = {}
        self.status: RobotStatus | None = None  # the latest STA's
        self.packages: dict[str, PackageState] = {}  # the latest MISSTA of each mission package
        self.time: float | None = None
        self.messages: list[Any] = []
        self.replies: deque[Any] = deque()
        self.bad_lines = 0
        self.closed = False
        self._ping = 0

    def feed(self, data: bytes) -> list[Any]:
        """Bytes received: every complete line parsed and recorded; the messages returned."""
        out = []
        for line in self.buffer.feed(data):
            try:
                msg = M.parse_message(line)
            except ProtocolError:
                self.bad_lines += 1
                continue
            self.record(msg)
            out.append(msg)
        return out

    def record(self, msg: Any) -> None:
        self.messages.append(msg)
        t = getattr(msg, "time", None)
        if isinstance(t, float) and math.isfinite(t) and (self.time is None or t > self.time):
            self.time = t
        if isinstance(msg, M.SensorMessage):
            key = reading_key(msg.reading)
            self.readings[key] = msg.reading
            self.reading_times[key] = msg.time
        elif isinstance(msg, M.StatusMessage):
            self.status = msg.status
        elif isinstance(msg, M.MisPkgMessage):
            self.packages[msg.state.name] = msg.state
        elif isinstance(msg, REPLIES):
            self.replies.append(msg)

    def take_messages(self) -> list[Any]:
        out, self.messages = self.messages, []
        return out

    def claim(self, accept: Callable[[Any], bool], command: str | None) -> Any:
        """The first waiting reply ``accept`` takes (removed), or None.  An ``ERROR`` about
        ``command`` is raised as :class:`ServerError`."""
        for i, msg in enumerate(self.replies):
            if isinstance(msg, M.ErrorReply) and command is not None and msg.command.upper() == command.upper():
                del self.replies[i]
                raise ServerError(msg.command, msg.reason)
            if accept(msg):
                del self.replies[i]
                return msg
        return None

    def next_ping(self) -> str:
        self._ping += 1
        return f"c{self._ping}"


# Command lines ---------------------------------------------------------------------------


def _floats(values: Iterable[float]) -> C.Vec3:
    """``values`` (x, y, z) as floats, as many as given: a location or rotation of another length
    goes out as it is, for the server to answer."""
    return tuple(map(float, values))  # type: ignore[return-value]  # its length is the caller's


def init_line(
    class_name: str,
    name: str | None,
    start: str | None,
    location: Iterable[float] | None,
    rotation: Iterable[float] | None,
) -> str:
    cls = class_name if "." in class_name else f"USARBot.{class_name}"
    return C.format_command(
        C.Init(
            class_name=cls,
            name=name,
            start=start,
            location=None if location is None else _floats(location),
            rotation=None if rotation is None else _floats(rotation),
        )
    )


# the keys of a plain DRIVE: skid speeds and the flags first, as most robots are driven
DRIVE_KEYS = (*C.DRIVE_NUMBERS[:2], *C.DRIVE_FLAGS, *C.DRIVE_NUMBERS[2:])


def drive_command(**kwargs: Any) -> C.Drive:
    """``DRIVE`` with the keys given: skid ``left``/``right`` (rad/s, or percent with
    ``normalized=True``), Ackermann ``speed``/``front_steer``/``rear_steer``, aerial and legged
    ``altitude_velocity``/``linear_velocity``/``lateral_velocity``/``rotational_velocity``,
    nautical ``propeller``/``rudder``/``stern_plane``, and ``light``/``flip`` for any robot."""
    unknown = sorted(set(kwargs) - set(DRIVE_KEYS))
    if unknown:
        raise TypeError(f"drive() got unknown keys {unknown}; known: {', '.join(DRIVE_KEYS)}")
    values = {k: v for k, v in kwargs.items() if v is not None}
    if not values:
        raise TypeError("drive() needs at least one key, e.g. drive(left=1.0, right=1.0)")
    return C.Drive(**values)


def drive_line(**kwargs: Any) -> str:
    """The line of :func:`drive_command` ``(**kwargs)``."""
    return C.format_command(drive_command(**kwargs))


def mispkg_line(package: str, values: dict[int, float], order: int = 0) -> str:
    """``MISPKG {Name p} {Link k} {Value v} {Order o} ...`` (order 0: an angle or position)."""
    if not values:
        raise TypeError("move() needs at least one link: move('CameraPanTilt', {1: 0.3})")
    links = tuple(C.LinkCommand(int(k), float(v), order) for k, v in sorted(values.items()))
    return C.format_command(C.MisPkg(name=package, links=links))


def report_line(location: Iterable[float], name: str | None = None) -> str:
    """``REPORT {Type Victim} {Location x,y,z} [{Name label}]`` (an extension, docs/scoring.md)."""
    return C.format_command(C.Report(type="Victim", location=_floats(location), name=name))


def is_report_reply(msg: Any) -> bool:
    return isinstance(msg, M.Result) and msg.item_type == "Victim"


def set_line(item_type: str, name: str | None, opcode: str | None, params: Any) -> str:
    parts = ["SET", format_segment("Type", item_type)]
    if name:
        parts.append(format_segment("Name", name))
    if opcode:
        parts.append(format_segment("Opcode", opcode))
    if params is not None:
        if isinstance(params, (list, tuple)):
            params = ",".join(str(float(v)) for v in params)
        parts.append(format_segment("Params", str(params)))
    return " ".join(parts) + "\r\n"


def query_line(word: str, item_type: str, name: str | None) -> str:
    cls = C.GetGeo if word == "GETGEO" else C.GetConf
    return C.format_command(cls(type=item_type, name=name))


def accepts_reply(word: str, item_type: str) -> Callable[[Any], bool]:
    """Which message answers GETGEO/GETCONF of ``item_type``."""
    geo = word == "GETGEO"
    t = item_type.lower()

    def ok(msg: Any) -> bool:
        if t == "robot":
            return isinstance(msg, M.RobotGeometry if geo else M.RobotConfiguration)
        kinds = (
            (M.ItemGeometry, M.EmptyGeometry, M.MisPkgGeometry, M.ActuatorGeometry)
            if geo
            else (M.ItemConfiguration, M.EmptyConfiguration, M.MisPkgConfiguration, M.ActuatorConfiguration)
        )
        return isinstance(msg, kinds)

    return ok


# Readings as a controller wants them --------------------------------------------------------


def odometry_of(readings: dict[str, Any]) -> tuple[float, float, float] | None:
    for r in readings.values():
        if isinstance(r, OdometryReading):
            return (r.x_m, r.y_m, r.theta_rad)
    return None


def pose_of(readings: dict[str, Any], sensor_type: str) -> tuple[tuple, tuple] | None:
    for r in readings.values():
        if isinstance(r, PoseReading) and r.sensor_type == sensor_type:
            return (tuple(r.location), tuple(r.orientation))
    return None


def victims_of(readings: dict[str, Any]) -> list[VictimPart]:
    for r in readings.values():
        if isinstance(r, VictimReading):
            return list(r.parts)
    return []


def first_scan_name(readings: dict[str, Any]) -> str | None:
    for key, r in readings.items():
        if isinstance(r, RangeScanReading) and r.sensor_type == "RangeScanner":
            return key
    for key, r in readings.items():
        if isinstance(r, RangeScanReading):
            return key
    return None


def max_range_of(conf: Any, name: str) -> float | None:
    if isinstance(conf, M.ItemConfiguration):
        for item in conf.items:
            if item.name == name:
                for k, v in item.fields:
                    if k.lower() == "maxrange":
                        if isinstance(v, tuple):  # not a number (float() would raise TypeError)
                            return None
                        try:
                            return float(v)
                        except (TypeError, ValueError):
                            return None
    return None


# Pictures (the image server, protocol.md 10) ------------------------------------------------

PICTURE_HEADER = 5  # a type byte and a 4-byte big-endian length


def picture_size(header: bytes) -> tuple[int, int]:
    """(image type, payload length) of a picture's header."""
    return header[0], int.from_bytes(header[1:5], "big")


def decode_picture(image_type: int, payload: bytes) -> np.ndarray:
    """A picture as an (height, width, 3) uint8 RGB array: raw (type 0: 16-bit width and
    height, then B, G, R rows top to bottom) or JPEG (types 1 to 5).  A PNG (type 6, the
    pictures of depth, thermal and label cameras) as what it holds: depths in millimetres
    (height, width) uint16, temperatures (height, width) uint8 at 0.2 degrees a level, or each
    pixel's class and instance (height, width, 2) uint16."""
    if image_type == 6:
        import io

        from PIL import Image

        with Image.open(io.BytesIO(payload)) as im:
            a = np.asarray(im)
        if a.ndim == 3:  # labels: red the class, green and blue the instance's high and low byte
            return np.stack([a[..., 0], (a[..., 1].astype(np.uint16) << 8) | a[..., 2]], axis=-1).astype(np.uint16)
        return a.astype(np.uint16 if a.dtype != np.uint8 else np.uint8).copy()
    if image_type == 0:
        w, h = int.from_bytes(payload[0:2], "big"), int.from_bytes(payload[2:4], "big")
        bgr = np.frombuffer(payload, dtype=np.uint8, count=w * h * 3, offset=4).reshape(h, w, 3)
        return bgr[:, :, ::-1].copy()
    import io

    from PIL import Image

    with Image.open(io.BytesIO(payload)) as im:
        return np.asarray(im.convert("RGB")).copy()
