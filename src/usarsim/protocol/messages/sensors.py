"""Sensor messages: the ``SEN`` line of every kind of reading (protocol.md §6.3), its format
and its parser, one pair per reading type.  Time is printed with 4 decimals; ground truth,
INS and INU orientations are normalised into [0, 2 pi), scanner ``Resolution``/``FOV``
truncated rather than rounded (§2.4)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from usarsim.errors import ProtocolError
from usarsim.readings import (
    EncoderItem,
    EncoderReading,
    GpsReading,
    HumanMotionReading,
    ImuReading,
    OdometryReading,
    OrientationReading,
    PoseReading,
    RangeImageReading,
    RangeItem,
    RangeReading,
    RangeScan3DReading,
    RangeScanReading,
    Reading,
    RfidReading,
    RfidTag,
    SoundReading,
    TachometerReading,
    TouchItem,
    TouchReading,
    VictimPart,
    VictimReading,
)

from ..grammar import Segment, format_segment, parse_float, parse_int
from ..numbers import f4, vec4, vec_t4
from .common import _CRLF, _Reader
from .declare import (
    ANGLES4,
    BOOL,
    F4,
    INT,
    INTS,
    PAIR_T4,
    RANGES3,
    RANGES4,
    T4,
    TEXT,
    VALUES4,
    VEC4,
    Key,
    packed,
    reading,
)
from .results import UnknownMessage


@dataclass(frozen=True, slots=True)
class SensorMessage:
    """A ``SEN`` line (§6.3): ``{Time t}`` first (4 decimals) unless ``time`` is None."""

    time: float | None
    reading: Reading


# ---- SEN bodies: everything after "{Type T}" is produced per reading type.


def _range_list(values: tuple[float, ...]) -> str:
    return "{Range %s}" % vec4(values) if values else "{Range}"


def _sen_scan3d(r: RangeScan3DReading) -> str:
    # a line of the split form holds one row and names it like the RangeImager's frames
    # (protocol.md 6.3); a whole sweep is the one line of the RangeScanner3D row there
    frame = "" if r.frame is None else "{Frames %d} {Frame %d} " % (r.frames or 0, r.frame)
    return "{Type %s} {Name %s} %s{Resolution %s} {FOV %s} %s" % (
        r.sensor_type,
        r.name,
        frame,
        vec_t4(r.resolution_rad),
        vec_t4(r.fov_rad),
        _range_list(r.ranges_m),
    )


def _scan3d_rows(r: RangeScan3DReading) -> list[RangeScan3DReading] | None:
    """The rows of a whole 3D sweep to be sent split, each a reading of its own (None: it is
    not to be split, or has no known rows)."""
    rows = r.frames
    if not r.split or r.frame is not None or not rows or len(r.ranges_m) % rows:
        return None
    n = len(r.ranges_m) // rows
    return [
        RangeScan3DReading(
            r.name,
            r.resolution_rad,
            r.fov_rad,
            r.ranges_m[k * n : (k + 1) * n],
            sensor_type=r.sensor_type,
            frames=rows,
            frame=k,
            split=True,
        )
        for k in range(rows)
    ]


def image_frames(r: RangeImageReading) -> list[RangeImageReading]:
    """The lines of a whole depth picture (protocol.md 6.3: ``Frames`` lines, ``Frame`` from
    0, rows top to bottom), each a reading of its rows; the picture's rows must divide into
    its frames."""
    cols, rows = r.pixels
    if r.frames < 1 or rows % r.frames or len(r.ranges_m) != cols * rows:
        raise ValueError(f"a {cols}x{rows} picture of {len(r.ranges_m)} ranges does not split into {r.frames} frames")
    n = cols * rows // r.frames
    return [
        RangeImageReading(r.name, r.pixels, r.fov_rad, r.ranges_m[k * n : (k + 1) * n], frames=r.frames, frame=k)
        for k in range(r.frames)
    ]


def _sen_odometry(r: OdometryReading) -> str:
    # Theta is printed as the sensor integrated it (UT examples show values in [0, 2 pi)).
    return "{Type Odometry} {Name %s} {Pose %s,%s,%s}" % (
        r.name,
        f4(r.x_m),
        f4(r.y_m),
        f4(r.theta_rad),
    )


def _gps_coordinate(c: tuple[int, float, str]) -> str:
    return "%d,%s,%s" % (c[0], f4(c[1]), c[2])


def _sen_gps(r: GpsReading) -> str:
    if r.fix and r.latitude is not None and r.longitude is not None:
        return "{Type GPS} {Name %s} {Latitude %s} {Longitude %s} {Fix 1} {Satellites %d}" % (
            r.name,
            _gps_coordinate(r.latitude),
            _gps_coordinate(r.longitude),
            r.satellites,
        )
    return "{Type GPS} {Name %s} {Fix %d} {Satellites %d}" % (
        r.name,
        1 if r.fix else 0,
        r.satellites,
    )


def _sen_victim(r: VictimReading) -> str:
    if not r.parts:
        return "{Type VictSensor} {Status NoVictims}"
    parts = " ".join(["{PartName %s} {Location %s}" % (p.part_name, vec4(p.location)) for p in r.parts])
    return "{Type VictSensor} {Name %s} %s" % (r.name, parts)


def _rfid_tag(t: RfidTag) -> str:
    s = "{ID %d} {Location %s}" % (t.tag_id, vec4(t.location))
    if t.memory is not None:
        s += " " + format_segment("Mem", t.memory)
    return s


def _sen_rfid(r: RfidReading) -> str:
    if not r.tags:
        return "{Type RFID} {Name %s}" % r.name
    return "{Type RFID} {Name %s} %s" % (r.name, " ".join(map(_rfid_tag, r.tags)))


# the readings of fixed layout, declared: their SEN bodies and parsers follow
_SCAN = reading(
    RangeScanReading,
    sensor_type=Key("Type", TEXT),
    name=Key("Name", TEXT),
    resolution_rad=Key("Resolution", T4),
    fov_rad=Key("FOV", T4),
    ranges_m=Key("Range", RANGES4),
)
_POSE = reading(
    PoseReading,
    sensor_type=Key("Type", TEXT),
    name=Key("Name", TEXT),
    location=Key("Location", VEC4),
    orientation=Key("Orientation", ANGLES4),  # normalised like the other UT orientation sensors
)
_ORIENTATION = reading(
    OrientationReading, sensor_type=Key("Type", TEXT), name=Key("Name", TEXT), orientation=Key("Orientation", ANGLES4)
)
_TACHOMETER = reading(
    TachometerReading,
    fixed=(("Type", "Tachometer"),),
    name=Key("Name", TEXT),
    velocities_rad_s=Key("Vel", VALUES4),
    positions_rad=Key("Pos", VALUES4),
)
_IMU = reading(  # UDK layout; the rotation is printed as measured (not normalised)
    ImuReading,
    fixed=(("Type", "IMU"),),
    name=Key("Name", TEXT),
    acceleration=Key("XYZAcceleration", VEC4),
    angular_velocity=Key("AngularVel", VEC4),
    angular_acceleration=Key("AngularAccel", VEC4),
    orientation=Key("Rotation", VEC4),
)
_SOUND = reading(
    SoundReading,
    fixed=(("Type", "Sound"),),
    name=Key("Name", TEXT),
    loudness_db=Key("Loudness", F4),
    duration_s=Key("Duration", F4),
)
_HUMAN_MOTION = reading(
    HumanMotionReading, fixed=(("Type", "HumanMotion"),), name=Key("Name", TEXT), probability=Key("Prob", F4)
)
# a depth picture (the UDK KinectDepth), one line per frame of whole rows (split below)
_IMAGE = reading(
    RangeImageReading,
    fixed=(("Type", "RangeImager"),),
    name=Key("Name", TEXT),
    frames=Key("Frames", INT),
    frame=Key("Frame", INT),
    pixels=Key("Resolution", INTS),
    fov_rad=Key("FOV", PAIR_T4),
    ranges_m=Key("Range", RANGES3),
)
_RANGE = reading(RangeReading, sensor_type=Key("Type", TEXT), items=packed(RangeItem, "Range", F4))
_ENCODER = reading(EncoderReading, fixed=(("Type", "Encoder"),), items=packed(EncoderItem, "Tick", INT))
_TOUCH = reading(TouchReading, fixed=(("Type", "Touch"),), items=packed(TouchItem, "Touch", BOOL))
_DECLARED = {
    layout.cls: layout
    for layout in (
        _SCAN,
        _POSE,
        _ORIENTATION,
        _TACHOMETER,
        _IMU,
        _SOUND,
        _HUMAN_MOTION,
        _RANGE,
        _ENCODER,
        _TOUCH,
        _IMAGE,
    )
}

# the others (a GPS with and without a fix, a victim sensor with nothing in sight, tags with
# and without memory, a 3D sweep split into rows, the odometry's pose of three fields), by hand
_SEN_BODIES: dict[type, Callable[[Any], str]] = {
    RangeScan3DReading: _sen_scan3d,
    OdometryReading: _sen_odometry,
    GpsReading: _sen_gps,
    VictimReading: _sen_victim,
    RfidReading: _sen_rfid,
}


def format_reading(reading: Reading, time: float | None = None) -> str:
    """The SEN line for a reading (same as ``format_message(SensorMessage(...))``).

    A whole 3D sweep is one line (protocol.md 6.3) unless it asks for the split form
    (``split``): then it is written as one line per row, top row first, each with
    ``{Frames rows} {Frame k}`` after the Name and the same Time."""
    if isinstance(reading, RangeImageReading) and reading.frame is None:
        head = "SEN" if time is None else "SEN {Time %s}" % f4(time)
        return "".join([head + _IMAGE.format(part) + _CRLF for part in image_frames(reading)])
    declared = _DECLARED.get(type(reading))
    if declared is not None:
        return ("SEN" if time is None else "SEN {Time %s}" % f4(time)) + declared.format(reading) + _CRLF
    head = "SEN " if time is None else "SEN {Time %s} " % f4(time)
    if isinstance(reading, RangeScan3DReading) and reading.split:
        rows = _scan3d_rows(reading)
        if rows is not None:
            return "".join([head + _sen_scan3d(row) + _CRLF for row in rows])
    try:
        body = _SEN_BODIES[type(reading)](reading)
    except KeyError:
        raise TypeError(f"not a sensor reading: {reading!r}") from None
    return head + body + _CRLF


def _fmt_sensor(m: SensorMessage) -> str:
    return format_reading(m.reading, m.time)


# ---- parsing


def _sen_parse_scan3d(r: _Reader, t: str) -> Reading:
    frame = r.raw.get("Frame")
    return RangeScan3DReading(
        sensor_type=t,
        name=r.text("Name"),
        resolution_rad=r.vector("Resolution", r.text("Resolution"), 2),  # type: ignore[arg-type]
        fov_rad=r.vector("FOV", r.text("FOV"), 2),  # type: ignore[arg-type]
        ranges_m=r.vector("Range", r.text("Range"), None),
        frames=None if frame is None else r.req_int("Frames"),
        frame=None if frame is None else r.integer(Segment("Frame", frame)),
        split=frame is not None,
    )


def _sen_parse_odometry(r: _Reader, t: str) -> Reading:
    x, y, theta = r.req_vec3("Pose")
    return OdometryReading(name=r.text("Name"), x_m=x, y_m=y, theta_rad=theta)


def _gps_parse(r: _Reader, key: str) -> tuple[int, float, str] | None:
    value = r.raw.get(key)
    if value is None:
        return None
    parts = [p.strip() for p in value.split(",")]
    if len(parts) != 3 or parts[2] not in ("N", "S", "E", "W"):
        raise r.error(key, value, "degrees,minutes,hemisphere such as 39,8.0341,N")
    try:
        return parse_int(parts[0]), parse_float(parts[1]), parts[2]
    except ProtocolError as exc:
        raise r.error(key, value, "degrees,minutes,hemisphere such as 39,8.0341,N") from exc


def _sen_parse_gps(r: _Reader, t: str) -> Reading:
    return GpsReading(
        name=r.text("Name"),
        fix=r.req_int("Fix") != 0,
        satellites=r.req_int("Satellites"),
        latitude=_gps_parse(r, "Latitude"),
        longitude=_gps_parse(r, "Longitude"),
    )


def _sen_parse_victim(r: _Reader, t: str) -> Reading:
    parts: list[VictimPart] = []
    part: str | None = None
    for s in r.raw.segments:
        k = s.key.lower()
        if k == "partname":
            part = s.value
        elif k == "location":
            if part is None:
                raise r.error(s.key, s.value, "{PartName p} before each {Location}")
            location = r.vector(s.key, s.value)
            parts.append(VictimPart(part_name=part, location=location))  # type: ignore[arg-type]
            part = None
    # "{Status NoVictims}" lines carry no Name; the UT sensor is named VictSensor.
    return VictimReading(name=r.raw.get("Name") or "VictSensor", parts=tuple(parts))


def _rfid_tag_from(r: _Reader, tag: dict[str, Any]) -> RfidTag:
    if "location" not in tag:
        raise ProtocolError(f"{r.what}: {{ID {tag['tag_id']}}} has no {{Location x,y,z}}")
    return RfidTag(**tag)


def _sen_parse_rfid(r: _Reader, t: str) -> Reading:
    tags: list[RfidTag] = []
    tag: dict[str, Any] | None = None
    for s in r.raw.segments:
        k = s.key.lower()
        if k == "id":
            if tag is not None:
                tags.append(_rfid_tag_from(r, tag))
            tag = {"tag_id": r.integer(s)}
        elif tag is not None and k == "location":
            tag["location"] = r.vector(s.key, s.value)
        elif tag is not None and k == "mem":
            tag["memory"] = s.value
    if tag is not None:
        tags.append(_rfid_tag_from(r, tag))
    return RfidReading(name=r.text("Name"), tags=tuple(tags))


_SEN_PARSERS: dict[str, Callable[[_Reader, str], Reading]] = {
    "sonar": lambda r, t: _RANGE.parse(r),
    "ir": lambda r, t: _RANGE.parse(r),
    "rangesensor": lambda r, t: _RANGE.parse(r),
    "rangescanner": lambda r, t: _SCAN.parse(r),
    "irscanner": lambda r, t: _SCAN.parse(r),
    "rangeimager": lambda r, t: _IMAGE.parse(r),
    "rangescanner3d": _sen_parse_scan3d,
    "3drangescanner": _sen_parse_scan3d,
    "odometry": _sen_parse_odometry,
    "encoder": lambda r, t: _ENCODER.parse(r),
    "groundtruth": lambda r, t: _POSE.parse(r),
    "ins": lambda r, t: _POSE.parse(r),
    "inu": lambda r, t: _ORIENTATION.parse(r),
    "touch": lambda r, t: _TOUCH.parse(r),
    "gps": _sen_parse_gps,
    "tachometer": lambda r, t: _TACHOMETER.parse(r),
    "imu": lambda r, t: _IMU.parse(r),
    "victsensor": _sen_parse_victim,
    "rfid": _sen_parse_rfid,
    "sound": lambda r, t: _SOUND.parse(r),
    "humanmotion": lambda r, t: _HUMAN_MOTION.parse(r),
}


def _parse_sen(r: _Reader) -> SensorMessage | UnknownMessage:
    sensor_type = r.text("Type")
    parser = _SEN_PARSERS.get(sensor_type.lower())
    if parser is None:
        return UnknownMessage(type=r.raw.type, segments=r.raw.segments)
    return SensorMessage(time=r.opt_time(), reading=parser(r, sensor_type))


FORMATTERS: dict[type, Callable[[Any], str]] = {SensorMessage: _fmt_sensor}

PARSERS: dict[str, Callable[[_Reader], SensorMessage | UnknownMessage]] = {"SEN": _parse_sen}
