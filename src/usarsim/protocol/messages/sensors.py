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

from ..grammar import Segment, parse_float, parse_int
from ..numbers import f4
from .common import _CRLF, _Reader
from .declare import Key, Variants, items, joined, key_spec, packed, reading
from .kinds import ANGLES4, BOOL, F4, INT, INTS, PAIR_T4, RANGES3, RANGES4, T4, TEXT, VALUES4, VEC4, Kind
from .results import UnknownMessage


@dataclass(frozen=True, slots=True)
class SensorMessage:
    """A ``SEN`` line (§6.3): ``{Time t}`` first (4 decimals) unless ``time`` is None."""

    time: float | None
    reading: Reading


# ---- SEN bodies: everything after "{Type T}" is produced per reading type.


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
# the odometry's pose of three fields in one segment (Theta as the sensor integrated it: UT
# examples show values in [0, 2 pi))
_ODOMETRY = reading(
    OdometryReading,
    fixed=(("Type", "Odometry"),),
    read_first=("pose",),
    name=Key("Name", TEXT),
    pose=joined("Pose", F4, "x_m", "y_m", "theta_rad"),
)


def _gps_coordinate(r: _Reader, seg: Segment, wire: str) -> tuple[int, float, str]:
    parts = [p.strip() for p in seg.value.split(",")]
    if len(parts) != 3 or parts[2] not in ("N", "S", "E", "W"):
        raise r.error(wire, seg.value, "degrees,minutes,hemisphere such as 39,8.0341,N")
    try:
        return parse_int(parts[0]), parse_float(parts[1]), parts[2]
    except ProtocolError as exc:
        raise r.error(wire, seg.value, "degrees,minutes,hemisphere such as 39,8.0341,N") from exc


# degrees, minutes (4 decimals) and hemisphere: 39,8.0341,N
COORDINATE = Kind("%s", lambda c: "%d,%s,%s" % (c[0], f4(c[1]), c[2]), _gps_coordinate)
FIX = Kind("%d", int, lambda r, seg, wire: r.integer(seg) != 0)  # {Fix 1}, {Fix 0}
_GPS_KEYS: dict[str, Any] = {
    "name": Key("Name", TEXT),
    "latitude": key_spec("Latitude", COORDINATE, optional=True),
    "longitude": key_spec("Longitude", COORDINATE, optional=True),
    "fix": Key("Fix", FIX),
    "satellites": Key("Satellites", INT),
}
_GPS_FIX = reading(
    GpsReading, fixed=(("Type", "GPS"),), read_first=("name", "fix", "satellites", "latitude"), **_GPS_KEYS
)
_GPS_NO_FIX = reading(
    GpsReading,
    fixed=(("Type", "GPS"),),
    name=_GPS_KEYS["name"],
    fix=_GPS_KEYS["fix"],
    satellites=_GPS_KEYS["satellites"],
)
_GPS = Variants(
    GpsReading,
    ((lambda g: g.fix and g.latitude is not None and g.longitude is not None, _GPS_FIX), (None, _GPS_NO_FIX)),
    _GPS_FIX.parse,  # the coordinates whenever the line has them
)

# a 3D sweep: one line, or one line a row ({Frames rows} {Frame k} after the Name); a row's
# number is named as declared in errors, its count as the line spells it
FRAMES = Kind("%d", lambda n: n or 0, lambda r, seg, wire: r.integer(seg))
FRAME = Kind("%d", None, lambda r, seg, wire: r.integer(Segment(wire, seg.value)))
_SCAN3D_KEYS: dict[str, Any] = {
    "sensor_type": Key("Type", TEXT),
    "name": Key("Name", TEXT),
    "frames": Key("Frames", FRAMES),
    "frame": Key("Frame", FRAME),
    "resolution_rad": Key("Resolution", PAIR_T4),
    "fov_rad": Key("FOV", PAIR_T4),
    "ranges_m": Key("Range", RANGES4),
}
_SCAN3D_FIRST = ("sensor_type", "name", "resolution_rad", "fov_rad", "ranges_m")
_SCAN3D_ROW = reading(RangeScan3DReading, read_first=_SCAN3D_FIRST, constants={"split": True}, **_SCAN3D_KEYS)
_SCAN3D_WHOLE = reading(
    RangeScan3DReading,
    read_first=_SCAN3D_FIRST,
    **{k: v for k, v in _SCAN3D_KEYS.items() if k not in ("frames", "frame")},
)
_SCAN3D = Variants(
    RangeScan3DReading,
    ((lambda r: r.frame is not None, _SCAN3D_ROW), (None, _SCAN3D_WHOLE)),
    lambda r: (_SCAN3D_ROW if r.raw.get("Frame") is not None else _SCAN3D_WHOLE).parse(r),
)


def _victim_parts(r: _Reader) -> VictimReading:
    """A victim sensor's line: each part's {PartName} before its {Location} (a name without a
    location is left out, as UT's sensor never sent one); "{Status NoVictims}" lines carry no
    Name, and the UT sensor is named VictSensor."""
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
    return VictimReading(name=r.raw.get("Name") or "VictSensor", parts=tuple(parts))


_VICTIM = Variants(
    VictimReading,
    (
        (lambda v: not v.parts, reading(VictimReading, fixed=(("Type", "VictSensor"), ("Status", "NoVictims")))),
        (
            None,
            reading(
                VictimReading,
                fixed=(("Type", "VictSensor"),),
                name=Key("Name", TEXT),
                parts=items(VictimPart, part_name=Key("PartName", TEXT), location=Key("Location", VEC4)),
            ),
        ),
    ),
    _victim_parts,
)

# a tag's memory is {Mem text}, {Mem} when empty, left out when it has none
MEMORY = Kind("%s", None, lambda r, seg, wire: seg.value, empty="")


def _tag(r: _Reader, tag: dict[str, Any]) -> RfidTag:
    if "location" not in tag:
        raise ProtocolError(f"{r.what}: {{ID {tag['tag_id']}}} has no {{Location x,y,z}}")
    return RfidTag(**tag)


def _rfid_tags(r: _Reader) -> RfidReading:
    """An RFID reader's line: each tag from its {ID}, its {Location} required, its {Mem} if any."""
    tags: list[RfidTag] = []
    tag: dict[str, Any] | None = None
    for s in r.raw.segments:
        k = s.key.lower()
        if k == "id":
            if tag is not None:
                tags.append(_tag(r, tag))
            tag = {"tag_id": r.integer(s)}
        elif tag is not None and k == "location":
            tag["location"] = r.vector(s.key, s.value)
        elif tag is not None and k == "mem":
            tag["memory"] = s.value
    if tag is not None:
        tags.append(_tag(r, tag))
    return RfidReading(name=r.text("Name"), tags=tuple(tags))


_RFID_LAYOUT = reading(
    RfidReading,
    fixed=(("Type", "RFID"),),
    name=Key("Name", TEXT),
    tags=items(
        RfidTag, tag_id=Key("ID", INT), location=Key("Location", VEC4), memory=key_spec("Mem", MEMORY, optional=True)
    ),
)
_RFID = Variants(RfidReading, ((None, _RFID_LAYOUT),), _rfid_tags)
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
        _ODOMETRY,
        _GPS,
        _SCAN3D,
        _VICTIM,
        _RFID,
    )
}


def format_reading(reading: Reading, time: float | None = None) -> str:
    """The SEN line for a reading (same as ``format_message(SensorMessage(...))``).

    A whole 3D sweep is one line (protocol.md 6.3) unless it asks for the split form
    (``split``): then it is written as one line per row, top row first, each with
    ``{Frames rows} {Frame k}`` after the Name and the same Time."""
    if isinstance(reading, RangeImageReading) and reading.frame is None:
        head = "SEN" if time is None else "SEN {Time %s}" % f4(time)
        return "".join([head + _IMAGE.format(part) + _CRLF for part in image_frames(reading)])
    if isinstance(reading, RangeScan3DReading) and reading.split and reading.frame is None:
        rows = _scan3d_rows(reading)
        if rows is not None:
            head = "SEN" if time is None else "SEN {Time %s}" % f4(time)
            return "".join([head + _SCAN3D.format(row) + _CRLF for row in rows])
    declared = _DECLARED.get(type(reading))
    if declared is None:
        raise TypeError(f"not a sensor reading: {reading!r}")
    return ("SEN" if time is None else "SEN {Time %s}" % f4(time)) + declared.format(reading) + _CRLF


def _fmt_sensor(m: SensorMessage) -> str:
    return format_reading(m.reading, m.time)


# ---- parsing


_SEN_PARSERS: dict[str, Callable[[_Reader, str], Reading]] = {
    "sonar": lambda r, t: _RANGE.parse(r),
    "ir": lambda r, t: _RANGE.parse(r),
    "rangesensor": lambda r, t: _RANGE.parse(r),
    "rangescanner": lambda r, t: _SCAN.parse(r),
    "irscanner": lambda r, t: _SCAN.parse(r),
    "rangeimager": lambda r, t: _IMAGE.parse(r),
    "rangescanner3d": lambda r, t: _SCAN3D.parse(r),
    "3drangescanner": lambda r, t: _SCAN3D.parse(r),
    "odometry": lambda r, t: _ODOMETRY.parse(r),
    "encoder": lambda r, t: _ENCODER.parse(r),
    "groundtruth": lambda r, t: _POSE.parse(r),
    "ins": lambda r, t: _POSE.parse(r),
    "inu": lambda r, t: _ORIENTATION.parse(r),
    "touch": lambda r, t: _TOUCH.parse(r),
    "gps": lambda r, t: _GPS.parse(r),
    "tachometer": lambda r, t: _TACHOMETER.parse(r),
    "imu": lambda r, t: _IMU.parse(r),
    "victsensor": lambda r, t: _VICTIM.parse(r),
    "rfid": lambda r, t: _RFID.parse(r),
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
