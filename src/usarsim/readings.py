"""Typed values that flow from the simulation to the protocol layer, and the typed
parameters of an operation on a mounted item that flow the other way.

Sensors produce these frozen dataclasses; effecters and cameras answer a SET with an
:class:`OperationResult` (or a :class:`ZoomResult`); only :mod:`usarsim.protocol` turns them
into text (``OK``/``Failed``, ``OPEN``/``CLOSED``, numbers at their precision).  This module
imports the standard library only, so both the simulation layer and the sans-IO protocol
layer may depend on it.

Conventions: metres, radians, seconds of simulated time; vectors and orientations
in the USARSim frame (X forward, Y right, Z down; roll, pitch, yaw with yaw
positive clockwise seen from above).
"""

from __future__ import annotations

from dataclasses import dataclass, field

Vec3 = tuple[float, float, float]
# A typed value of a CONF field or of an RES/EFF item-specific key (protocol.md 6.5-6.7):
# printed by the protocol layer (True/False, integers as they are, 4 decimals, comma lists).
FieldValue = bool | int | float | str | tuple[bool | int | float | str, ...]


@dataclass(frozen=True, slots=True)
class RangeItem:
    """One single-beam range value inside a packed Sonar/IR/RangeSensor line."""

    name: str
    range_m: float


@dataclass(frozen=True, slots=True)
class RangeReading:
    """All single-beam range sensors of one type on a robot (packed in one SEN line).

    ``sensor_type`` is the USARSim type name: ``Sonar``, ``IR`` or ``RangeSensor``.
    """

    sensor_type: str
    items: tuple[RangeItem, ...]


@dataclass(frozen=True, slots=True)
class RangeScanReading:
    """One sweep of a scanning range finder; ``ranges_m[0]`` is the rightmost beam.

    ``sensor_type`` is ``RangeScanner`` or ``IRScanner``.
    """

    sensor_type: str
    name: str
    resolution_rad: float
    fov_rad: float
    ranges_m: tuple[float, ...]


@dataclass(frozen=True, slots=True)
class RangeScan3DReading:
    """A 3D sweep, row-major: one horizontal line per vertical step.

    ``frames``: the sweep's rows (None: not known; a sweep read from the one-line form does
    not say).  ``split``: the sweep goes out as one SEN line per row, each naming its row with
    ``{Frames rows} {Frame k}`` (the opt-in split form), instead of the one line of
    protocol.md 6.3.  ``frame``: this value holds one row only, the ``frame``-th of ``frames``
    (0 = the top row), as read from a line of the split form.
    """

    name: str
    resolution_rad: tuple[float, float]  # vertical, horizontal
    fov_rad: tuple[float, float]  # vertical, horizontal
    ranges_m: tuple[float, ...]
    sensor_type: str = "RangeScanner3D"
    frames: int | None = None
    frame: int | None = None
    split: bool = False


@dataclass(frozen=True, slots=True)
class RangeImageReading:
    """A depth picture of a range imager (the UDK KinectDepth, protocol.md 6.3): ``pixels``
    (columns, rows), ``fov_rad`` (horizontal, vertical), ``ranges_m`` each pixel's depth (m
    along the optical axis) row by row, the top row first, each row left to right.

    On the wire a picture is ``frames`` lines, each holding ``rows / frames`` whole rows: a
    whole picture has ``frame`` None; a value read back from one line holds that line's rows
    only, the ``frame``-th (from 0) of ``frames``."""

    name: str
    pixels: tuple[int, int]
    fov_rad: tuple[float, float]
    ranges_m: tuple[float, ...]
    frames: int = 1
    frame: int | None = None


@dataclass(frozen=True, slots=True)
class OdometryReading:
    """``SEN {Type Odometry} {Pose x,y,theta}`` (protocol.md 6.3, 7.4): the pose dead-reckoned from the wheels, x and
    y in metres and theta in radians, relative to the pose at spawn or at the last reset."""

    name: str
    x_m: float
    y_m: float
    theta_rad: float


@dataclass(frozen=True, slots=True)
class EncoderItem:
    """One wheel encoder of a packed Encoder line (protocol.md 6.3, 7.5): its name and its accumulated ticks (the
    wheel's turn over the encoder's resolution)."""

    name: str
    tick: int


@dataclass(frozen=True, slots=True)
class EncoderReading:
    """All encoders of a robot (packed in one SEN line)."""

    items: tuple[EncoderItem, ...]


@dataclass(frozen=True, slots=True)
class PoseReading:
    """A pose sensor: ``GroundTruth`` or ``INS`` (orientation in [0, 2 pi))."""

    sensor_type: str
    name: str
    location: Vec3
    orientation: Vec3


@dataclass(frozen=True, slots=True)
class OrientationReading:
    """``INU`` (old orientation-only sensor)."""

    name: str
    orientation: Vec3
    sensor_type: str = "INU"


@dataclass(frozen=True, slots=True)
class TouchItem:
    """One touch sensor of a packed Touch line (protocol.md 6.3): its name and whether it is in contact."""

    name: str
    touching: bool


@dataclass(frozen=True, slots=True)
class TouchReading:
    """All touch sensors of a robot (packed in one SEN line, protocol.md 6.3)."""

    items: tuple[TouchItem, ...]


@dataclass(frozen=True, slots=True)
class GpsReading:
    """``latitude``/``longitude`` are (degrees, minutes, hemisphere) or None without a fix."""

    name: str
    fix: bool
    satellites: int
    latitude: tuple[int, float, str] | None = None
    longitude: tuple[int, float, str] | None = None


@dataclass(frozen=True, slots=True)
class TachometerReading:
    """``SEN {Type Tachometer} {Vel ...} {Pos ...}`` (protocol.md 6.3, 7.5): each wheel's spin speed (rad/s) and
    accumulated angle (rad), one value per wheel."""

    name: str
    velocities_rad_s: tuple[float, ...]
    positions_rad: tuple[float, ...]


@dataclass(frozen=True, slots=True)
class ImuReading:
    """UDK-style IMU: accelerations, angular velocities and orientation."""

    name: str
    acceleration: Vec3
    angular_velocity: Vec3
    angular_acceleration: Vec3
    orientation: Vec3


@dataclass(frozen=True, slots=True)
class VictimPart:
    """One ``{PartName p} {Location x,y,z}`` pair of a victim sensor line (protocol.md 6.3, 7.9): a body part seen,
    and where, relative to the sensor (metres)."""

    part_name: str
    location: Vec3
    # the victim whose part it is, in the simulation (the score's ground truth); never on the
    # wire: None for a false alarm and in a reading parsed from a line
    victim: str | None = field(default=None, compare=False)


@dataclass(frozen=True, slots=True)
class VictimReading:
    """``SEN {Type VictSensor}`` (protocol.md 6.3, 7.9): the victim body parts (and false alarms) the sensor's rays
    hit; none: ``{Status NoVictims}``."""

    name: str
    parts: tuple[VictimPart, ...]


@dataclass(frozen=True, slots=True)
class RfidTag:
    """One ``{ID id} {Location x,y,z}`` pair of an RFID line (protocol.md 6.3, 7.10): a tag in range and where it is
    relative to the sensor (metres), with ``{Mem text}`` when its memory is not blank."""

    tag_id: int
    location: Vec3
    memory: str | None = None


@dataclass(frozen=True, slots=True)
class RfidReading:
    """``SEN {Type RFID}`` (protocol.md 6.3, 7.10): the tags within the reader's range; with none, the line names the
    reader only."""

    name: str
    tags: tuple[RfidTag, ...]


@dataclass(frozen=True, slots=True)
class SoundReading:
    """``{Loudness l} {Duration d}``: the loudest sound heard (dB at the sensor) and how
    long it lasts (s); 0, 0 when all is quiet."""

    name: str
    loudness_db: float
    duration_s: float


@dataclass(frozen=True, slots=True)
class HumanMotionReading:
    """``{Prob p}``: probability that a human moves in the sensor's view."""

    name: str
    probability: float


Reading = (
    RangeReading
    | RangeScanReading
    | RangeScan3DReading
    | RangeImageReading
    | OdometryReading
    | EncoderReading
    | PoseReading
    | OrientationReading
    | TouchReading
    | GpsReading
    | TachometerReading
    | ImuReading
    | VictimReading
    | RfidReading
    | SoundReading
    | HumanMotionReading
)


@dataclass(frozen=True, slots=True)
class RobotStatus:
    """The STA values of a robot at one instant."""

    vehicle_type: str
    battery_s: int
    front_steer: float = 0.0
    rear_steer: float = 0.0
    joints: tuple[tuple[str, float], ...] = ()
    light_toggle: bool = False
    light_intensity: int = 0
    view: int = -1


@dataclass(frozen=True, slots=True)
class PackageLink:
    """One link of a mission package at one instant: its number (from 1), its joint's position
    (rad, or m for a prismatic joint) and the torque it applies."""

    link: int
    value: float
    torque: float


@dataclass(frozen=True, slots=True)
class PackageState:
    """MISSTA: a mission package's links at one instant."""

    name: str
    links: tuple[PackageLink, ...]


@dataclass(frozen=True, slots=True)
class EffecterState:
    """EFF: an effecter's state after an operation (protocol.md 6.6): a gripper's fingers
    ``closed`` (printed ``{Status CLOSED}``) or open (``{Status OPEN}``)."""

    effecter_type: str
    name: str
    closed: bool


@dataclass(frozen=True, slots=True)
class ItemParams:
    """The parameters of ``SET {Type T} {Name N} {Opcode op} {Params p}`` (protocol.md 5.4),
    typed by the protocol layer.

    ``values``: the numbers of ``{Params}`` split on commas and blanks (``0.87``,
    ``1.0,2.0,-0.5,0,0,0.5``); None when Params was not sent, is empty, or is not a list of
    finite numbers.  ``text``: Params as sent, for an item whose parameters are text (an RFID
    write: ``<tagID> <data...>``, the data may contain blanks and commas).
    """

    values: tuple[float, ...] | None = None
    text: str | None = None


@dataclass(frozen=True, slots=True)
class OperationResult:
    """What an item's operation did (protocol.md 5.4, 6.5): ``ok`` (RES ``{Status OK}``, else
    ``{Status Failed}``) and item-specific typed (key, value) pairs printed after Status (an
    RFID read: ``(("ID", 11137), ("Mem", "victim here"))``)."""

    ok: bool
    extra: tuple[tuple[str, FieldValue], ...] = ()


@dataclass(frozen=True, slots=True)
class ZoomResult:
    """The outcome of ``SET {Type Camera} {Opcode Zoom}`` (protocol.md 5.4): (name, field of
    view in rad, ok) per camera; not ok when the value was clamped or reset."""

    cameras: tuple[tuple[str, float, bool], ...]
    camera_type: str = "Camera"  # the item type of the RES line: Camera or OmniCam


@dataclass(frozen=True, slots=True)
class Refusal:
    """A request the simulation could not carry out (``command`` its word, ``reason`` why),
    answered with the protocol's ERROR line instead of silence."""

    command: str
    reason: str


@dataclass(frozen=True, slots=True)
class CommandResult:
    """The outcome of a SET on a robot's item (an RES line, protocol.md 6.5): ``ok`` and the
    item-specific typed (key, value) pairs of its :class:`OperationResult`."""

    item_type: str
    name: str
    ok: bool
    extra: tuple[tuple[str, FieldValue], ...] = ()
