"""Server messages (protocol.md §6 and §18) as typed values.

:func:`format_message` writes the exact line UT2004 USARSim sent: key spelling and order,
precision, one space between segments, CR LF at the end.  :func:`parse_message` reads such a
line back (a client-side parser, used by tests and tools); a value read back equals the
original up to the printed precision.

Precision per key (protocol.md §2.4):

* ``Time``: 4 decimals in SEN, EFF and STEPPED; 2 decimals in STA, MISSTA and RES.
* Start poses and path nodes: 2 decimals.
* Everything else: 4 decimals; scanner ``Resolution``/``FOV`` and mission-package geometry
  truncated rather than rounded (see :func:`usarsim.protocol.numbers.t4`).
* Ground truth, INS and INU orientations: normalised into [0, 2 pi).

Names and other text fields are written as given; they come from validated configuration
and must not contain braces or line breaks.

Every class is a frozen dataclass.  ``GameInfo``, the two STA classes, ``RobotGeometry`` and
``RobotConfiguration`` (a required field follows a defaulted one) take keyword arguments
only; the others also accept their fields positionally, in the order listed.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from usarsim.errors import ProtocolError
from usarsim.readings import (
    EncoderItem,
    EncoderReading,
    FieldValue,
    GpsReading,
    HumanMotionReading,
    ImuReading,
    OdometryReading,
    OrientationReading,
    PoseReading,
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

from .grammar import RawMessage, Segment, format_segment, parse_bool, parse_float, parse_int, parse_line, parse_vector
from .numbers import bool_str, f2, f4, t4, vec2, vec4, vec_angle4, vec_t4

__all__ = [
    "ActuatorConfig",
    "ActuatorConfiguration",
    "ActuatorGeometry",
    "ActuatorLinkConfiguration",
    "ActuatorLinkGeometry",
    "ActuatorPose",
    "ActuatorStatus",
    "AerialVehicleStatus",
    "CameraZoom",
    "CameraZoomResult",
    "ClosestPathNode",
    "Die",
    "EffecterStatus",
    "EmptyConfiguration",
    "EmptyGeometry",
    "GameInfo",
    "GroundVehicleStatus",
    "ItemConf",
    "ItemConfiguration",
    "ItemGeometry",
    "ItemPose",
    "LINE_LIMIT",
    "LinkConfiguration",
    "LinkGeometry",
    "LinkState",
    "Message",
    "MisPkgConfiguration",
    "MisPkgGeometry",
    "MisPkgStatus",
    "PackageConfiguration",
    "PackageGeometry",
    "PathNodes",
    "Pong",
    "Result",
    "RobotConfiguration",
    "RobotGeometry",
    "SensorMessage",
    "StartPose",
    "StartPoses",
    "Stepped",
    "ErrorReply",
    "error_reply",
    "UnknownMessage",
    "Vec3",
    "ViewportState",
    "ViewportsResult",
    "format_message",
    "format_reading",
    "format_value",
    "message_from_raw",
    "parse_message",
]

Vec3 = tuple[float, float, float]


# --------------------------------------------------------------------------- NFO


@dataclass(frozen=True, slots=True, kw_only=True)
class GameInfo:
    """``NFO {Gametype g} {Level map} {TimeLimit minutes}``, sent on connect (§6.1)."""

    gametype: str = "BotDeathMatch"
    level: str
    time_limit: int = 0


@dataclass(frozen=True, slots=True)
class StartPose:
    """A named pose: start poses and path nodes (metres, radians, Z down)."""

    name: str
    location: Vec3
    rotation: Vec3


@dataclass(frozen=True, slots=True)
class StartPoses:
    """Reply to GETSTARTPOSES: all poses in one segment, 2 decimals (§5.2)."""

    poses: tuple[StartPose, ...] = ()


@dataclass(frozen=True, slots=True)
class PathNodes:
    """Reply to GETPATHNODES (UDK): same layout as start poses under ``PathNodes``."""

    nodes: tuple[StartPose, ...] = ()


@dataclass(frozen=True, slots=True)
class ClosestPathNode:
    """Reply to GETCLOSESTPATHNODE (UDK): ``NFO {Pathnode name} {Location x,y,z}``."""

    name: str
    location: Vec3


# --------------------------------------------------------------------------- STA


@dataclass(frozen=True, slots=True, kw_only=True)
class GroundVehicleStatus:
    """Periodic ``STA`` of a ground robot (§6.2).

    ``joints`` are flipper angles printed after ``RearSteer`` (TeleMax).  ``battery_s`` is the
    remaining battery life in whole seconds.  ``vehicle_type`` names the other non-aerial
    kinds (``LeggedRobot``, ``NauticalVehicle``, ``StaticPlatform``) with the same layout.
    """

    time: float
    front_steer: float = 0.0
    rear_steer: float = 0.0
    joints: tuple[tuple[str, float], ...] = ()
    light_toggle: bool = False
    light_intensity: int = 0
    battery_s: int
    view: int = -1
    vehicle_type: str = "GroundVehicle"


@dataclass(frozen=True, slots=True, kw_only=True)
class AerialVehicleStatus:
    """Periodic ``STA {Type AerialVehicle}`` of an aerial robot (§6.2)."""

    time: float
    light_toggle: bool = False
    light_intensity: int = 0
    battery_s: int
    view: int = -1


# --------------------------------------------------------------------------- SEN


@dataclass(frozen=True, slots=True)
class SensorMessage:
    """A ``SEN`` line (§6.3): ``{Time t}`` first (4 decimals) unless ``time`` is None."""

    time: float | None
    reading: Reading


# --------------------------------------------------------------------------- GEO / CONF


@dataclass(frozen=True, slots=True, kw_only=True)
class RobotGeometry:
    """Reply to ``GETGEO {Type Robot}`` (§6.8); ``Name`` carries the robot class.

    The wheel keys are left out when None (robots without wheels).
    """

    vehicle_type: str = "GroundVehicle"
    class_name: str
    dimensions: Vec3
    cog: Vec3 = (0.0, 0.0, 0.0)
    wheel_radius: float | None = None
    wheel_separation: float | None = None
    wheel_base: float | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class RobotConfiguration:
    """Reply to ``GETCONF {Type Robot}`` (§6.7); ``Name`` carries the robot class."""

    vehicle_type: str = "GroundVehicle"
    class_name: str
    steering_type: str
    mass_kg: float
    max_speed: float
    max_torque: float
    max_front_steer: float = 0.0
    max_rear_steer: float = 0.0


@dataclass(frozen=True, slots=True)
class ItemPose:
    """Mount pose of one sensor or effecter, relative to ``mount`` (``HARD`` = chassis)."""

    name: str
    location: Vec3
    orientation: Vec3
    mount: str = "HARD"


@dataclass(frozen=True, slots=True)
class ItemGeometry:
    """``GEO {Type T} {Name N Location ... Orientation ... Mount M} ...`` (packed, §6.8)."""

    item_type: str
    items: tuple[ItemPose, ...] = ()


@dataclass(frozen=True, slots=True)
class EmptyGeometry:
    """``GEO {Type T}`` or ``GEO {Type T} {Name N}``: nothing matched the query (§5.5)."""

    item_type: str
    name: str | None = None


@dataclass(frozen=True, slots=True)
class ItemConf:
    """Configuration of one item: typed ``(key, value)`` pairs in order, printed by
    :func:`format_value` (a value read back from a line is its text, printed as it is)."""

    name: str
    fields: tuple[tuple[str, FieldValue], ...] = ()


@dataclass(frozen=True, slots=True)
class ItemConfiguration:
    """``CONF {Type T} {Name N1} {Key v} ... {Name N2} ...`` (repeated-key groups, §6.7).

    Every item type has its own keys; their typed values are printed by
    :func:`format_value`.  A single item without fields prints exactly like
    :class:`EmptyConfiguration` with a name, and is read back as one.
    """

    item_type: str
    items: tuple[ItemConf, ...] = ()


@dataclass(frozen=True, slots=True)
class EmptyConfiguration:
    """``CONF {Type T}`` or ``CONF {Type T} {Name N}``: nothing matched the query (§5.5)."""

    item_type: str
    name: str | None = None


@dataclass(frozen=True, slots=True)
class LinkGeometry:
    """One link of a mission package GEO: pose relative to ``parent_link`` (-1 = chassis)."""

    link: int
    parent_link: int
    location: Vec3
    orientation: Vec3


@dataclass(frozen=True, slots=True)
class PackageGeometry:
    name: str
    links: tuple[LinkGeometry, ...] = ()


@dataclass(frozen=True, slots=True)
class MisPkgGeometry:
    """``GEO {Type MisPkg} {Name P} {Link 1} {ParentLink -1} {Location ...} {Orientation ...}``.

    Several packages follow each other in one line when the query named none.  Locations and
    orientations are truncated to 4 decimals, as in the UT output (``3.1415``, ``1.5707``).
    """

    packages: tuple[PackageGeometry, ...] = ()


@dataclass(frozen=True, slots=True)
class LinkConfiguration:
    """One link of a mission package CONF; ``min_range > max_range`` = unlimited joint."""

    link: int
    joint_type: str
    max_speed: float
    max_torque: float
    min_range: float
    max_range: float


@dataclass(frozen=True, slots=True)
class PackageConfiguration:
    name: str
    links: tuple[LinkConfiguration, ...] = ()


@dataclass(frozen=True, slots=True)
class MisPkgConfiguration:
    """``CONF {Type MisPkg} {Name P} {Link 1} {JointType Revolute} {MaxSpeed ...} ...``."""

    packages: tuple[PackageConfiguration, ...] = ()


# --------------------------------------------------------------------------- Actuator (UDK)


@dataclass(frozen=True, slots=True)
class ActuatorLinkConfiguration:
    """One link of an actuator CONF (UDK API): joint type, torque limit and the range of
    its Value (rad or m)."""

    link: int
    joint_type: str
    max_torque: float
    min_value: float
    max_value: float


@dataclass(frozen=True, slots=True)
class ActuatorConfig:
    name: str
    links: tuple[ActuatorLinkConfiguration, ...] = ()


@dataclass(frozen=True, slots=True)
class ActuatorConfiguration:
    """``CONF {Type Actuator} {Name arm} {Link 1} {JointType Revolute} {MaxTorque t}
    {MinValue a} {MaxValue b} ...`` (§6.7, UDK); several actuators follow each other."""

    actuators: tuple[ActuatorConfig, ...] = ()


@dataclass(frozen=True, slots=True)
class ActuatorLinkGeometry:
    """One link of an actuator GEO: its joint's pose relative to its parent; ``parent`` is
    the parent link's index plus one, 0 when the link sits on the actuator's base (as the UDK
    server printed it: ``{Link 2} {Parent 1}``)."""

    link: int
    parent: int
    location: Vec3
    orientation: Vec3


@dataclass(frozen=True, slots=True)
class ActuatorPose:
    name: str
    location: Vec3
    orientation: Vec3
    mount: str
    links: tuple[ActuatorLinkGeometry, ...] = ()


@dataclass(frozen=True, slots=True)
class ActuatorGeometry:
    """``GEO {Type Actuator} {Name arm} {Location x,y,z} {Orientation r,p,y} {Mount Robot}
    {Link 1} {Parent -1} {Location ...} {Orientation ...} ...`` (§6.8, UDK)."""

    actuators: tuple[ActuatorPose, ...] = ()


@dataclass(frozen=True, slots=True)
class ActuatorStatus:
    """``ASTA {Time t} {Name arm} {Link 1} {Value v} {Torque q} ... [{Gripper g}]`` (§6.4,
    UDK): an actuator's links every status period; Time with 4 decimals as UDK wrote it."""

    time: float
    name: str
    links: tuple[LinkState, ...] = ()
    gripper: int | None = None


# --------------------------------------------------------------------------- MISSTA


@dataclass(frozen=True, slots=True)
class LinkState:
    link: int
    value: float
    torque: float


@dataclass(frozen=True, slots=True)
class MisPkgStatus:
    """``MISSTA {Time t} {Name P} {Link 1} {Value v} {Torque q} ...`` (§6.4)."""

    time: float
    name: str
    links: tuple[LinkState, ...] = ()


# --------------------------------------------------------------------------- RES / EFF / DIE


@dataclass(frozen=True, slots=True)
class Result:
    """``RES {Time t} {Type T} {Name N} {Status S}`` plus item-specific ``extra`` segments.

    ``extra`` holds ``(key, value)`` pairs printed after Status by :func:`format_value`, e.g.
    an RFID read ``(("ID", 11137), ("Mem", "hello"))``.  ``name`` None leaves the Name
    segment out.
    """

    time: float
    item_type: str
    name: str | None
    status: str = "OK"
    extra: tuple[tuple[str, FieldValue], ...] = ()


@dataclass(frozen=True, slots=True)
class CameraZoom:
    name: str
    fov: float
    status: str = "OK"


@dataclass(frozen=True, slots=True)
class CameraZoomResult:
    """``RES {Time t} {Type Camera} {Name cam} {FOV f} {Status OK|Failed}``.

    One Name/FOV/Status triple per camera; ``camera_type`` is the zoomed item's type
    (``Camera``, or ``OmniCam`` for an omnidirectional camera).
    """

    time: float
    cameras: tuple[CameraZoom, ...] = ()
    camera_type: str = "Camera"


@dataclass(frozen=True, slots=True)
class ViewportState:
    """``{ViewportN camera} {Status s}``: camera is a name, ``Disabled`` or ``None``."""

    index: int
    camera: str
    status: str = "OK"


@dataclass(frozen=True, slots=True)
class ViewportsResult:
    """``RES {Time t} {Type Viewports} {Config c} {Status s} {Viewport1 cam} {Status s} ...``."""

    time: float
    config: str
    config_status: str = "OK"
    viewports: tuple[ViewportState, ...] = ()


@dataclass(frozen=True, slots=True)
class EffecterStatus:
    """``EFF {Time t} {Type T} {Name N} {Status S}`` plus ``extra`` (§6.6).

    ``extra`` pairs are printed by :func:`format_value`; an empty value prints as a bare
    segment (``{On}``).
    """

    time: float | None
    effecter_type: str
    name: str
    status: str | None = None
    extra: tuple[tuple[str, FieldValue], ...] = ()


@dataclass(frozen=True, slots=True)
class Die:
    """``DIE {Killer name} {DamageType type}`` (§6.9)."""

    killer: str
    damage_type: str


@dataclass(frozen=True, slots=True)
class Stepped:
    """``STEPPED {Time t}``: the lock-step interval is done (§18), 4 decimals."""

    time: float


@dataclass(frozen=True, slots=True)
class Pong:
    """``PONG [{Id text}] [{Time t}]``: the answer to ``PING`` (an extension), after every
    request sent before it was carried out and everything it produced was written; ``time``
    the simulated time then (4 decimals)."""

    id: str | None = None
    time: float | None = None


@dataclass(frozen=True, slots=True)
class ErrorReply:
    """``ERROR {Command c} {Reason r}``: the request ``c`` (its command word) could not be
    carried out, and why.  An extension of this project, like STEPPED: an INIT that spawns
    nothing, a query before INIT, a bad STEP, a SET to a robot without power get it instead
    of silence; clients that do not know it skip it as an unknown message.  The reason names
    the problem and what is allowed; braces and line breaks in it are sent as parentheses
    and spaces (:func:`error_reply`)."""

    command: str
    reason: str


def error_reply(command: str, reason: str) -> ErrorReply:
    """An :class:`ErrorReply` whose reason is safe on the wire (no braces, no line breaks)."""
    safe = reason.replace("{", "(").replace("}", ")").replace("\r", " ").replace("\n", " ")
    return ErrorReply(command=command.upper(), reason=" ".join(safe.split()))


@dataclass(frozen=True, slots=True)
class UnknownMessage:
    """A line :func:`parse_message` does not know; formatted back as it was."""

    type: str
    segments: tuple[Segment, ...] = ()


Message = (
    GameInfo
    | StartPoses
    | PathNodes
    | ClosestPathNode
    | GroundVehicleStatus
    | AerialVehicleStatus
    | SensorMessage
    | RobotGeometry
    | RobotConfiguration
    | ItemGeometry
    | EmptyGeometry
    | ItemConfiguration
    | EmptyConfiguration
    | MisPkgGeometry
    | MisPkgConfiguration
    | MisPkgStatus
    | ActuatorConfiguration
    | ActuatorGeometry
    | ActuatorStatus
    | Result
    | CameraZoomResult
    | ViewportsResult
    | EffecterStatus
    | Die
    | Stepped
    | Pong
    | ErrorReply
    | UnknownMessage
)


# =========================================================================== formatting

_CRLF = "\r\n"

# Lines are kept shorter than this many bytes, CR LF included (protocol.md 1: the Player
# driver reads a line into a 4096-byte buffer).  A 3D scanner's configuration is refused when
# its sweep (or, in the opt-in split form, its row) would make a longer line
# (usarsim.sensors.scanner.LINE_LIMIT, the same bound).
LINE_LIMIT = 4096


def _poses(poses: tuple[StartPose, ...]) -> str:
    return " ".join("%s %s %s" % (p.name, vec2(p.location), vec2(p.rotation)) for p in poses)


def _fmt_game_info(m: GameInfo) -> str:
    return "NFO {Gametype %s} {Level %s} {TimeLimit %d}\r\n" % (m.gametype, m.level, m.time_limit)


def _fmt_start_poses(m: StartPoses) -> str:
    if not m.poses:
        return "NFO {StartPoses 0}\r\n"
    return "NFO {StartPoses %d} {%s}\r\n" % (len(m.poses), _poses(m.poses))


def _fmt_path_nodes(m: PathNodes) -> str:
    if not m.nodes:
        return "NFO {PathNodes 0}\r\n"
    return "NFO {PathNodes %d} {%s}\r\n" % (len(m.nodes), _poses(m.nodes))


def _fmt_closest_path_node(m: ClosestPathNode) -> str:
    return "NFO {Pathnode %s} {Location %s}\r\n" % (m.name, vec2(m.location))


def _fmt_ground_status(m: GroundVehicleStatus) -> str:
    joints = "".join(" {%s %s}" % (name, f4(angle)) for name, angle in m.joints)
    return (
        "STA {Type %s} {Time %s} {FrontSteer %s} {RearSteer %s}%s {LightToggle %s} "
        "{LightIntensity %d} {Battery %d} {View %d}\r\n"
        % (
            m.vehicle_type,
            f2(m.time),
            f4(m.front_steer),
            f4(m.rear_steer),
            joints,
            bool_str(m.light_toggle),
            m.light_intensity,
            m.battery_s,
            m.view,
        )
    )


def _fmt_aerial_status(m: AerialVehicleStatus) -> str:
    return "STA {Type AerialVehicle} {Time %s} {LightToggle %s} {LightIntensity %d} {Battery %d} {View %d}\r\n" % (
        f2(m.time),
        bool_str(m.light_toggle),
        m.light_intensity,
        m.battery_s,
        m.view,
    )


# ---- SEN bodies: everything after "{Type T}" is produced per reading type.


def _sen_range(r: RangeReading) -> str:
    body = " ".join(["{Name %s Range %s}" % (i.name, f4(i.range_m)) for i in r.items])
    return "{Type %s} %s" % (r.sensor_type, body) if body else "{Type %s}" % r.sensor_type


def _range_list(values: tuple[float, ...]) -> str:
    return "{Range %s}" % vec4(values) if values else "{Range}"


def _sen_scan(r: RangeScanReading) -> str:
    return "{Type %s} {Name %s} {Resolution %s} {FOV %s} %s" % (
        r.sensor_type,
        r.name,
        t4(r.resolution_rad),
        t4(r.fov_rad),
        _range_list(r.ranges_m),
    )


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


def _sen_odometry(r: OdometryReading) -> str:
    # Theta is printed as the sensor integrated it (UT examples show values in [0, 2 pi)).
    return "{Type Odometry} {Name %s} {Pose %s,%s,%s}" % (
        r.name,
        f4(r.x_m),
        f4(r.y_m),
        f4(r.theta_rad),
    )


def _sen_encoder(r: EncoderReading) -> str:
    body = " ".join(["{Name %s Tick %d}" % (i.name, i.tick) for i in r.items])
    return "{Type Encoder} " + body if body else "{Type Encoder}"


def _sen_pose(r: PoseReading) -> str:
    return "{Type %s} {Name %s} {Location %s} {Orientation %s}" % (
        r.sensor_type,
        r.name,
        vec4(r.location),
        vec_angle4(r.orientation),
    )


def _sen_orientation(r: OrientationReading) -> str:
    # INU orientation: normalised into [0, 2 pi) like the other UT orientation sensors.
    return "{Type %s} {Name %s} {Orientation %s}" % (
        r.sensor_type,
        r.name,
        vec_angle4(r.orientation),
    )


def _sen_touch(r: TouchReading) -> str:
    body = " ".join(["{Name %s Touch %s}" % (i.name, bool_str(i.touching)) for i in r.items])
    return "{Type Touch} " + body if body else "{Type Touch}"


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


def _sen_tachometer(r: TachometerReading) -> str:
    return "{Type Tachometer} {Name %s} {Vel %s} {Pos %s}" % (
        r.name,
        vec4(r.velocities_rad_s),
        vec4(r.positions_rad),
    )


def _sen_imu(r: ImuReading) -> str:
    # UDK layout; the rotation is printed as measured (not normalised).
    return "{Type IMU} {Name %s} {XYZAcceleration %s} {AngularVel %s} {AngularAccel %s} {Rotation %s}" % (
        r.name,
        vec4(r.acceleration),
        vec4(r.angular_velocity),
        vec4(r.angular_acceleration),
        vec4(r.orientation),
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


def _sen_sound(r: SoundReading) -> str:
    return "{Type Sound} {Name %s} {Loudness %s} {Duration %s}" % (r.name, f4(r.loudness_db), f4(r.duration_s))


def _sen_human_motion(r: HumanMotionReading) -> str:
    return "{Type HumanMotion} {Name %s} {Prob %s}" % (r.name, f4(r.probability))


_SEN_BODIES: dict[type, Callable[[Any], str]] = {
    RangeReading: _sen_range,
    RangeScanReading: _sen_scan,
    RangeScan3DReading: _sen_scan3d,
    OdometryReading: _sen_odometry,
    EncoderReading: _sen_encoder,
    PoseReading: _sen_pose,
    OrientationReading: _sen_orientation,
    TouchReading: _sen_touch,
    GpsReading: _sen_gps,
    TachometerReading: _sen_tachometer,
    ImuReading: _sen_imu,
    VictimReading: _sen_victim,
    RfidReading: _sen_rfid,
    SoundReading: _sen_sound,
    HumanMotionReading: _sen_human_motion,
}


def format_reading(reading: Reading, time: float | None = None) -> str:
    """The SEN line for a reading (same as ``format_message(SensorMessage(...))``).

    A whole 3D sweep is one line (protocol.md 6.3) unless it asks for the split form
    (``split``): then it is written as one line per row, top row first, each with
    ``{Frames rows} {Frame k}`` after the Name and the same Time."""
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


def _fmt_robot_geometry(m: RobotGeometry) -> str:
    s = "GEO {Type %s} {Name %s} {Dimensions %s} {COG %s}" % (
        m.vehicle_type,
        m.class_name,
        vec4(m.dimensions),
        vec4(m.cog),
    )
    if m.wheel_radius is not None:
        s += " {WheelRadius %s}" % f4(m.wheel_radius)
    if m.wheel_separation is not None:
        s += " {WheelSeparation %s}" % f4(m.wheel_separation)
    if m.wheel_base is not None:
        s += " {WheelBase %s}" % f4(m.wheel_base)
    return s + _CRLF


def _fmt_robot_configuration(m: RobotConfiguration) -> str:
    return (
        "CONF {Type %s} {Name %s} {SteeringType %s} {Mass %s} {MaxSpeed %s} {MaxTorque %s} "
        "{MaxFrontSteer %s} {MaxRearSteer %s}\r\n"
        % (
            m.vehicle_type,
            m.class_name,
            m.steering_type,
            f4(m.mass_kg),
            f4(m.max_speed),
            f4(m.max_torque),
            f4(m.max_front_steer),
            f4(m.max_rear_steer),
        )
    )


def _fmt_item_geometry(m: ItemGeometry) -> str:
    items = "".join(
        " {Name %s Location %s Orientation %s Mount %s}" % (i.name, vec4(i.location), vec4(i.orientation), i.mount)
        for i in m.items
    )
    return "GEO {Type %s}%s\r\n" % (m.item_type, items)


def _type_and_name(head: str, item_type: str, name: str | None) -> str:
    if name is None:
        return "%s {Type %s}\r\n" % (head, item_type)
    return "%s {Type %s} {Name %s}\r\n" % (head, item_type, name)


def format_value(v: FieldValue) -> str:
    """A typed CONF field or RES/EFF key value as USARSim printed it (§2.4, §6.7): ``True`` /
    ``False``, an integer as it is, any other number at 4 decimals, a sequence comma-joined
    (its numbers at 4 decimals, integers included), text as it is."""
    if isinstance(v, bool):
        return bool_str(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return f4(v)
    if isinstance(v, (tuple, list)):
        return ",".join(
            format_value(float(x)) if isinstance(x, (int, float)) and not isinstance(x, bool) else format_value(x)
            for x in v
        )
    return str(v)


def _fields(pairs: tuple[tuple[str, FieldValue], ...]) -> list[str]:
    return [format_segment(k, format_value(v)) for k, v in pairs]


def _fmt_item_configuration(m: ItemConfiguration) -> str:
    parts = ["CONF {Type %s}" % m.item_type]
    for item in m.items:
        parts.append("{Name %s}" % item.name)
        parts.extend(_fields(item.fields))
    return " ".join(parts) + _CRLF


def _fmt_mispkg_geometry(m: MisPkgGeometry) -> str:
    parts = ["GEO {Type MisPkg}"]
    for pkg in m.packages:
        parts.append("{Name %s}" % pkg.name)
        parts.extend(
            "{Link %d} {ParentLink %d} {Location %s} {Orientation %s}"
            % (k.link, k.parent_link, vec_t4(k.location), vec_t4(k.orientation))
            for k in pkg.links
        )
    return " ".join(parts) + _CRLF


def _fmt_mispkg_configuration(m: MisPkgConfiguration) -> str:
    parts = ["CONF {Type MisPkg}"]
    for pkg in m.packages:
        parts.append("{Name %s}" % pkg.name)
        parts.extend(
            "{Link %d} {JointType %s} {MaxSpeed %s} {MaxTorque %s} {MinRange %s} {MaxRange %s}"
            % (
                k.link,
                k.joint_type,
                f4(k.max_speed),
                f4(k.max_torque),
                f4(k.min_range),
                f4(k.max_range),
            )
            for k in pkg.links
        )
    return " ".join(parts) + _CRLF


def _fmt_mispkg_status(m: MisPkgStatus) -> str:
    links = "".join(" {Link %d} {Value %s} {Torque %s}" % (k.link, f4(k.value), f4(k.torque)) for k in m.links)
    return "MISSTA {Time %s} {Name %s}%s\r\n" % (f2(m.time), m.name, links)


def _fmt_actuator_configuration(m: ActuatorConfiguration) -> str:
    parts = ["CONF {Type Actuator}"]
    for act in m.actuators:
        parts.append("{Name %s}" % act.name)
        parts.extend(
            "{Link %d} {JointType %s} {MaxTorque %s} {MinValue %s} {MaxValue %s}"
            % (k.link, k.joint_type, f4(k.max_torque), f4(k.min_value), f4(k.max_value))
            for k in act.links
        )
    return " ".join(parts) + _CRLF


def _fmt_actuator_geometry(m: ActuatorGeometry) -> str:
    parts = ["GEO {Type Actuator}"]
    for act in m.actuators:
        parts.append(
            "{Name %s} {Location %s} {Orientation %s} {Mount %s}"
            % (act.name, vec4(act.location), vec4(act.orientation), act.mount)
        )
        parts.extend(
            "{Link %d} {Parent %d} {Location %s} {Orientation %s}"
            % (k.link, k.parent, vec4(k.location), vec4(k.orientation))
            for k in act.links
        )
    return " ".join(parts) + _CRLF


def _fmt_actuator_status(m: ActuatorStatus) -> str:
    links = "".join(" {Link %d} {Value %s} {Torque %s}" % (k.link, f4(k.value), f4(k.torque)) for k in m.links)
    gripper = "" if m.gripper is None else " {Gripper %d}" % m.gripper
    return "ASTA {Time %s} {Name %s}%s%s\r\n" % (f4(m.time), m.name, links, gripper)


def _fmt_result(m: Result) -> str:
    parts = ["RES {Time %s} {Type %s}" % (f2(m.time), m.item_type)]
    if m.name is not None:
        parts.append("{Name %s}" % m.name)
    parts.append("{Status %s}" % m.status)
    # {key value} even when the value is empty: a blank tag reads {Mem } (protocol.md 5.4,
    # "{Mem <data>}" with no data), which a client looking for "{Mem " still finds
    parts.extend(["{%s %s}" % (k, format_value(v)) for k, v in m.extra])
    return " ".join(parts) + _CRLF


def _fmt_camera_zoom(m: CameraZoomResult) -> str:
    cams = "".join(" {Name %s} {FOV %s} {Status %s}" % (c.name, f4(c.fov), c.status) for c in m.cameras)
    return "RES {Time %s} {Type %s}%s\r\n" % (f2(m.time), m.camera_type, cams)


def _fmt_viewports(m: ViewportsResult) -> str:
    views = "".join(" {Viewport%d %s} {Status %s}" % (v.index, v.camera, v.status) for v in m.viewports)
    return "RES {Time %s} {Type Viewports} {Config %s} {Status %s}%s\r\n" % (
        f2(m.time),
        m.config,
        m.config_status,
        views,
    )


def _fmt_effecter(m: EffecterStatus) -> str:
    parts = ["EFF"]
    if m.time is not None:
        parts.append("{Time %s}" % f4(m.time))
    parts.append("{Type %s} {Name %s}" % (m.effecter_type, m.name))
    if m.status is not None:
        parts.append("{Status %s}" % m.status)
    parts.extend(_fields(m.extra))
    return " ".join(parts) + _CRLF


def _fmt_unknown(m: UnknownMessage) -> str:
    return " ".join([m.type, *(format_segment(s.key, s.value) for s in m.segments)]) + _CRLF


_FORMATTERS: dict[type, Callable[[Any], str]] = {
    GameInfo: _fmt_game_info,
    StartPoses: _fmt_start_poses,
    PathNodes: _fmt_path_nodes,
    ClosestPathNode: _fmt_closest_path_node,
    GroundVehicleStatus: _fmt_ground_status,
    AerialVehicleStatus: _fmt_aerial_status,
    SensorMessage: _fmt_sensor,
    RobotGeometry: _fmt_robot_geometry,
    RobotConfiguration: _fmt_robot_configuration,
    ItemGeometry: _fmt_item_geometry,
    EmptyGeometry: lambda m: _type_and_name("GEO", m.item_type, m.name),
    ItemConfiguration: _fmt_item_configuration,
    EmptyConfiguration: lambda m: _type_and_name("CONF", m.item_type, m.name),
    MisPkgGeometry: _fmt_mispkg_geometry,
    MisPkgConfiguration: _fmt_mispkg_configuration,
    MisPkgStatus: _fmt_mispkg_status,
    ActuatorConfiguration: _fmt_actuator_configuration,
    ActuatorGeometry: _fmt_actuator_geometry,
    ActuatorStatus: _fmt_actuator_status,
    Result: _fmt_result,
    CameraZoomResult: _fmt_camera_zoom,
    ViewportsResult: _fmt_viewports,
    EffecterStatus: _fmt_effecter,
    Die: lambda m: "DIE {Killer %s} {DamageType %s}\r\n" % (m.killer, m.damage_type),
    Stepped: lambda m: "STEPPED {Time %s}\r\n" % f4(m.time),
    Pong: lambda m: (
        "PONG%s%s\r\n"
        % ("" if m.id is None else " {Id %s}" % m.id, "" if m.time is None else " {Time %s}" % f4(m.time))
    ),
    ErrorReply: lambda m: "ERROR {Command %s} {Reason %s}\r\n" % (m.command, m.reason),
    UnknownMessage: _fmt_unknown,
}


def format_message(msg: Message) -> str:
    """The exact line for ``msg``, including the trailing CR LF (a 3D sweep too long for one
    line: one line per row, see :func:`format_reading`)."""
    try:
        formatter = _FORMATTERS[type(msg)]
    except KeyError:
        raise TypeError(f"not a server message: {msg!r}") from None
    return formatter(msg)


# =========================================================================== parsing


class _Reader:
    """Typed access to the segments of one message, with errors naming the message."""

    __slots__ = ("raw", "what")

    def __init__(self, raw: RawMessage, what: str):
        self.raw = raw
        self.what = what

    def error(self, key: str, value: str, expected: str) -> ProtocolError:
        return ProtocolError(f"{self.what}: bad value {value!r} for key {key}: expected {expected}")

    def missing(self, key: str) -> ProtocolError:
        return ProtocolError(f"{self.what}: missing {{{key} ...}}")

    def text(self, key: str) -> str:
        v = self.raw.get(key)
        if v is None:
            raise self.missing(key)
        return v

    def number(self, seg: Segment) -> float:
        try:
            return parse_float(seg.value)
        except ProtocolError as exc:
            raise self.error(seg.key, seg.value, "a number") from exc

    def integer(self, seg: Segment) -> int:
        try:
            return parse_int(seg.value)
        except ProtocolError as exc:
            raise self.error(seg.key, seg.value, "an integer") from exc

    def bool(self, seg: Segment) -> bool:
        try:
            return parse_bool(seg.value)
        except ProtocolError as exc:
            raise self.error(seg.key, seg.value, "True or False") from exc

    def vector(self, key: str, value: str, n: int | None = 3) -> tuple[float, ...]:
        if n is None and not value:
            return ()
        try:
            return parse_vector(value, n)
        except ProtocolError as exc:
            raise self.error(key, value, f"{n or 'some'} comma-separated numbers") from exc

    def seg(self, key: str) -> Segment:
        wanted = key.lower()
        for s in self.raw.segments:
            if s.key.lower() == wanted:
                return s
        raise self.missing(key)

    def opt_float(self, key: str) -> float | None:
        v = self.raw.get(key)
        return None if v is None else self.number(Segment(key, v))

    def req_float(self, key: str) -> float:
        return self.number(self.seg(key))

    def req_int(self, key: str) -> int:
        return self.integer(self.seg(key))

    def req_vec3(self, key: str) -> Vec3:
        return self.vector(key, self.text(key))  # type: ignore[return-value]

    def opt_time(self) -> float | None:
        return self.opt_float("Time")


def _split_poses(r: _Reader, seg: Segment) -> tuple[StartPose, ...]:
    tokens = ([seg.key] + seg.value.split()) if seg.value else [seg.key]
    if len(tokens) % 3:
        raise r.error(seg.key, seg.value, "'name x,y,z roll,pitch,yaw' triples")
    poses = []
    for i in range(0, len(tokens), 3):
        poses.append(
            StartPose(
                name=tokens[i],
                location=r.vector("location", tokens[i + 1]),  # type: ignore[arg-type]
                rotation=r.vector("rotation", tokens[i + 2]),  # type: ignore[arg-type]
            )
        )
    return tuple(poses)


def _parse_nfo(r: _Reader) -> Message:
    raw = r.raw
    segs = raw.segments
    # a pose list: its kind is the first StartPoses or PathNodes segment (a pose further on
    # may itself be named so)
    idx = next((i for i, s in enumerate(segs) if s.key.lower() in ("startposes", "pathnodes")), None)
    if idx is not None:
        key = "StartPoses" if segs[idx].key.lower() == "startposes" else "PathNodes"
        count = r.req_int(key)
        poses = _split_poses(r, segs[idx + 1]) if count and idx + 1 < len(segs) else ()
        if len(poses) != count:
            raise r.error(key, str(count), f"the number of poses listed ({len(poses)})")
        return StartPoses(poses=poses) if key == "StartPoses" else PathNodes(nodes=poses)
    if raw.has("Pathnode"):
        return ClosestPathNode(name=r.text("Pathnode"), location=r.req_vec3("Location"))
    return GameInfo(gametype=r.text("Gametype"), level=r.text("Level"), time_limit=r.req_int("TimeLimit"))


_STA_KEYS = frozenset({"type", "time", "frontsteer", "rearsteer", "lighttoggle", "lightintensity", "battery", "view"})


def _parse_sta(r: _Reader) -> Message:
    # Type, Time and Battery are required; UDK lines may lack the others (defaults used).
    vehicle_type = r.text("Type")
    time = r.req_float("Time")
    battery = r.req_int("Battery")
    light = r.bool(r.seg("LightToggle")) if r.raw.has("LightToggle") else False
    intensity = r.req_int("LightIntensity") if r.raw.has("LightIntensity") else 0
    view = r.req_int("View") if r.raw.has("View") else -1
    if vehicle_type == "AerialVehicle":
        return AerialVehicleStatus(
            time=time, light_toggle=light, light_intensity=intensity, battery_s=battery, view=view
        )
    joints = tuple((s.key, r.number(s)) for s in r.raw.segments if s.key.lower() not in _STA_KEYS)
    return GroundVehicleStatus(
        vehicle_type=vehicle_type,
        time=time,
        front_steer=r.opt_float("FrontSteer") or 0.0,
        rear_steer=r.opt_float("RearSteer") or 0.0,
        joints=joints,
        light_toggle=light,
        light_intensity=intensity,
        battery_s=battery,
        view=view,
    )


# ---- SEN


def _packed(r: _Reader, seg: Segment, field: str) -> tuple[str, str]:
    """``{Name n Field v}`` -> (n, v)."""
    tokens = seg.value.split()
    if len(tokens) != 3 or tokens[1].lower() != field.lower():
        raise r.error(seg.key, seg.value, f"'name {field} value'")
    return tokens[0], tokens[2]


def _named_values(r: _Reader, field: str) -> list[tuple[str, Segment]]:
    """Items of packed (``{Name n Field v}``) or separate (``{Name n} {Field v}``) layout."""
    out: list[tuple[str, Segment]] = []
    pending: str | None = None
    for s in r.raw.segments:
        k = s.key.lower()
        if k == "name":
            if len(s.value.split()) == 1:
                pending = s.value
            else:
                name, value = _packed(r, s, field)
                out.append((name, Segment(field, value)))
        elif k == field.lower() and pending is not None:
            out.append((pending, s))
            pending = None
    return out


def _sen_parse_range(r: _Reader, t: str) -> Reading:
    return RangeReading(
        sensor_type=t,
        items=tuple(RangeItem(name=n, range_m=r.number(s)) for n, s in _named_values(r, "Range")),
    )


def _sen_parse_scan(r: _Reader, t: str) -> Reading:
    return RangeScanReading(
        sensor_type=t,
        name=r.text("Name"),
        resolution_rad=r.req_float("Resolution"),
        fov_rad=r.req_float("FOV"),
        ranges_m=r.vector("Range", r.text("Range"), None),
    )


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


def _sen_parse_encoder(r: _Reader, t: str) -> Reading:
    return EncoderReading(items=tuple(EncoderItem(name=n, tick=r.integer(s)) for n, s in _named_values(r, "Tick")))


def _sen_parse_pose(r: _Reader, t: str) -> Reading:
    return PoseReading(
        sensor_type=t,
        name=r.text("Name"),
        location=r.req_vec3("Location"),
        orientation=r.req_vec3("Orientation"),
    )


def _sen_parse_orientation(r: _Reader, t: str) -> Reading:
    return OrientationReading(sensor_type=t, name=r.text("Name"), orientation=r.req_vec3("Orientation"))


def _sen_parse_touch(r: _Reader, t: str) -> Reading:
    return TouchReading(items=tuple(TouchItem(name=n, touching=r.bool(s)) for n, s in _named_values(r, "Touch")))


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


def _sen_parse_tachometer(r: _Reader, t: str) -> Reading:
    return TachometerReading(
        name=r.text("Name"),
        velocities_rad_s=r.vector("Vel", r.text("Vel"), None),
        positions_rad=r.vector("Pos", r.text("Pos"), None),
    )


def _sen_parse_imu(r: _Reader, t: str) -> Reading:
    return ImuReading(
        name=r.text("Name"),
        acceleration=r.req_vec3("XYZAcceleration"),
        angular_velocity=r.req_vec3("AngularVel"),
        angular_acceleration=r.req_vec3("AngularAccel"),
        orientation=r.req_vec3("Rotation"),
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


def _sen_parse_sound(r: _Reader, t: str) -> Reading:
    return SoundReading(name=r.text("Name"), loudness_db=r.req_float("Loudness"), duration_s=r.req_float("Duration"))


def _sen_parse_human_motion(r: _Reader, t: str) -> Reading:
    return HumanMotionReading(name=r.text("Name"), probability=r.req_float("Prob"))


_SEN_PARSERS: dict[str, Callable[[_Reader, str], Reading]] = {
    "sonar": _sen_parse_range,
    "ir": _sen_parse_range,
    "rangesensor": _sen_parse_range,
    "rangescanner": _sen_parse_scan,
    "irscanner": _sen_parse_scan,
    "rangescanner3d": _sen_parse_scan3d,
    "3drangescanner": _sen_parse_scan3d,
    "odometry": _sen_parse_odometry,
    "encoder": _sen_parse_encoder,
    "groundtruth": _sen_parse_pose,
    "ins": _sen_parse_pose,
    "inu": _sen_parse_orientation,
    "touch": _sen_parse_touch,
    "gps": _sen_parse_gps,
    "tachometer": _sen_parse_tachometer,
    "imu": _sen_parse_imu,
    "victsensor": _sen_parse_victim,
    "rfid": _sen_parse_rfid,
    "sound": _sen_parse_sound,
    "humanmotion": _sen_parse_human_motion,
}


def _parse_sen(r: _Reader) -> Message:
    sensor_type = r.text("Type")
    parser = _SEN_PARSERS.get(sensor_type.lower())
    if parser is None:
        return UnknownMessage(type=r.raw.type, segments=r.raw.segments)
    return SensorMessage(time=r.opt_time(), reading=parser(r, sensor_type))


# ---- GEO / CONF


def _groups(segments: tuple[Segment, ...], start: str) -> list[list[Segment]]:
    """Split segments into groups, each beginning with a segment keyed ``start``."""
    groups: list[list[Segment]] = []
    wanted = start.lower()
    for s in segments:
        if s.key.lower() == wanted:
            groups.append([s])
        elif groups:
            groups[-1].append(s)
    return groups


def _only_type_and_name(raw: RawMessage) -> bool:
    keys = [s.key.lower() for s in raw.segments]
    if keys == ["type"]:
        return True
    return keys == ["type", "name"] and len(raw.segments[1].value.split()) == 1


def _parse_geo(r: _Reader) -> Message:
    raw = r.raw
    item_type = r.text("Type")
    if _only_type_and_name(raw):
        return EmptyGeometry(item_type=item_type, name=raw.get("Name"))
    if raw.has("Dimensions"):
        return RobotGeometry(
            vehicle_type=item_type,
            class_name=r.text("Name"),
            dimensions=r.req_vec3("Dimensions"),
            cog=r.req_vec3("COG"),
            wheel_radius=r.opt_float("WheelRadius"),
            wheel_separation=r.opt_float("WheelSeparation"),
            wheel_base=r.opt_float("WheelBase"),
        )
    if item_type.lower() == "actuator":
        return _parse_actuator_geometry(r)
    if item_type.lower() == "mispkg":
        packages = []
        for group in _groups(raw.segments, "Name"):
            links = []
            for link in _groups(tuple(group[1:]), "Link"):
                lr = _Reader(RawMessage(raw.type, tuple(link)), r.what)
                links.append(
                    LinkGeometry(
                        link=lr.req_int("Link"),
                        parent_link=lr.req_int("ParentLink"),
                        location=lr.req_vec3("Location"),
                        orientation=lr.req_vec3("Orientation"),
                    )
                )
            packages.append(PackageGeometry(name=group[0].value, links=tuple(links)))
        return MisPkgGeometry(packages=tuple(packages))
    items = []
    for group in _groups(raw.segments, "Name"):
        tokens = group[0].value.split()
        if len(tokens) > 1 and len(tokens) % 2:  # packed UT layout: name, then key value pairs
            fields = {tokens[i].lower(): tokens[i + 1] for i in range(1, len(tokens), 2)}
            name = tokens[0]
        else:  # separate UDK layout: {Name n} {Location ...} {Orientation ...} {Mount m}
            fields = {s.key.lower(): s.value for s in group[1:]}
            name = group[0].value
        if "location" not in fields or "orientation" not in fields:
            raise r.error("Name", group[0].value, "'name Location x,y,z Orientation r,p,y Mount m'")
        location = r.vector("Location", fields["location"])
        orientation = r.vector("Orientation", fields["orientation"])
        items.append(
            ItemPose(
                name=name,
                location=location,  # type: ignore[arg-type]
                orientation=orientation,  # type: ignore[arg-type]
                mount=fields.get("mount", "HARD"),
            )
        )
    return ItemGeometry(item_type=item_type, items=tuple(items))


def _parse_conf(r: _Reader) -> Message:
    raw = r.raw
    item_type = r.text("Type")
    if _only_type_and_name(raw):
        return EmptyConfiguration(item_type=item_type, name=raw.get("Name"))
    if raw.has("SteeringType"):
        return RobotConfiguration(
            vehicle_type=item_type,
            class_name=r.text("Name"),
            steering_type=r.text("SteeringType"),
            mass_kg=r.req_float("Mass"),
            max_speed=r.req_float("MaxSpeed"),
            max_torque=r.req_float("MaxTorque"),
            max_front_steer=r.opt_float("MaxFrontSteer") or 0.0,
            max_rear_steer=r.opt_float("MaxRearSteer") or 0.0,
        )
    if item_type.lower() == "actuator":
        return _parse_actuator_configuration(r)
    if item_type.lower() == "mispkg":
        packages = []
        for group in _groups(raw.segments, "Name"):
            links = []
            for link in _groups(tuple(group[1:]), "Link"):
                lr = _Reader(RawMessage(raw.type, tuple(link)), r.what)
                links.append(
                    LinkConfiguration(
                        link=lr.req_int("Link"),
                        joint_type=lr.text("JointType"),
                        max_speed=lr.req_float("MaxSpeed"),
                        max_torque=lr.req_float("MaxTorque"),
                        min_range=lr.req_float("MinRange"),
                        max_range=lr.req_float("MaxRange"),
                    )
                )
            packages.append(PackageConfiguration(name=group[0].value, links=tuple(links)))
        return MisPkgConfiguration(packages=tuple(packages))
    items = tuple(
        ItemConf(name=g[0].value, fields=tuple((s.key, s.value) for s in g[1:])) for g in _groups(raw.segments, "Name")
    )
    return ItemConfiguration(item_type=item_type, items=items)


def _parse_actuator_geometry(r: _Reader) -> ActuatorGeometry:
    raw = r.raw
    actuators = []
    for group in _groups(raw.segments, "Name"):
        links = _groups(tuple(group[1:]), "Link")
        head = _Reader(RawMessage(raw.type, tuple(group[1 : len(group) - sum(len(g) for g in links)])), r.what)
        parsed = []
        for link in links:
            lr = _Reader(RawMessage(raw.type, tuple(link)), r.what)
            parsed.append(
                ActuatorLinkGeometry(
                    link=lr.req_int("Link"),
                    parent=lr.req_int("Parent"),
                    location=lr.req_vec3("Location"),
                    orientation=lr.req_vec3("Orientation"),
                )
            )
        actuators.append(
            ActuatorPose(
                name=group[0].value,
                location=head.req_vec3("Location"),
                orientation=head.req_vec3("Orientation"),
                mount=head.text("Mount"),
                links=tuple(parsed),
            )
        )
    return ActuatorGeometry(actuators=tuple(actuators))


def _parse_actuator_configuration(r: _Reader) -> ActuatorConfiguration:
    actuators = []
    for group in _groups(r.raw.segments, "Name"):
        links = []
        for link in _groups(tuple(group[1:]), "Link"):
            lr = _Reader(RawMessage(r.raw.type, tuple(link)), r.what)
            links.append(
                ActuatorLinkConfiguration(
                    link=lr.req_int("Link"),
                    joint_type=lr.text("JointType"),
                    max_torque=lr.req_float("MaxTorque"),
                    min_value=lr.req_float("MinValue"),
                    max_value=lr.req_float("MaxValue"),
                )
            )
        actuators.append(ActuatorConfig(name=group[0].value, links=tuple(links)))
    return ActuatorConfiguration(actuators=tuple(actuators))


def _parse_asta(r: _Reader) -> Message:
    links = []
    for group in _groups(r.raw.segments, "Link"):
        lr = _Reader(RawMessage(r.raw.type, tuple(s for s in group if s.key.lower() != "gripper")), r.what)
        links.append(
            LinkState(link=lr.req_int("Link"), value=lr.req_float("Value"), torque=lr.opt_float("Torque") or 0.0)
        )
    gripper = r.raw.get("Gripper")
    return ActuatorStatus(
        time=r.req_float("Time"),
        name=r.text("Name"),
        links=tuple(links),
        gripper=None if gripper is None else r.req_int("Gripper"),
    )


def _parse_missta(r: _Reader) -> Message:
    links = []
    for group in _groups(r.raw.segments, "Link"):
        lr = _Reader(RawMessage(r.raw.type, tuple(group)), r.what)
        links.append(
            LinkState(
                link=lr.req_int("Link"),
                value=lr.req_float("Value"),
                torque=lr.req_float("Torque"),
            )
        )
    return MisPkgStatus(time=r.req_float("Time"), name=r.text("Name"), links=tuple(links))


_VIEWPORT_KEY = re.compile(r"viewport([0-9]+)\Z", re.IGNORECASE)


def _parse_res(r: _Reader) -> Message:
    raw = r.raw
    time = r.req_float("Time")
    item_type = r.text("Type")
    if item_type in ("Camera", "OmniCam") and raw.has("FOV"):
        cams = []
        for g in _groups(raw.segments, "Name"):
            gr = _Reader(RawMessage(raw.type, tuple(g)), r.what)
            cams.append(CameraZoom(name=g[0].value, fov=gr.req_float("FOV"), status=gr.text("Status")))
        return CameraZoomResult(time=time, cameras=tuple(cams), camera_type=item_type)
    if item_type == "Viewports":
        views = []
        segs = raw.segments
        for i, s in enumerate(segs):
            m = _VIEWPORT_KEY.match(s.key)
            if m is not None:
                has_status = i + 1 < len(segs) and segs[i + 1].key == "Status"
                status = segs[i + 1].value if has_status else ""
                views.append(ViewportState(index=int(m.group(1)), camera=s.value, status=status))
        return ViewportsResult(
            time=time,
            config=r.text("Config"),
            config_status=r.text("Status"),
            viewports=tuple(views),
        )
    # Everything after the first Status is item-specific.
    rest = list(raw.segments)
    head: dict[str, str] = {}
    extra: list[tuple[str, str]] = []
    for s in rest:
        k = s.key.lower()
        if "status" not in head and k in ("time", "type", "name", "status") and k not in head:
            head[k] = s.value
        else:
            extra.append((s.key, s.value))
    if "status" not in head:
        raise r.missing("Status")
    return Result(
        time=time,
        item_type=item_type,
        name=head.get("name"),
        status=head["status"],
        extra=tuple(extra),
    )


def _parse_eff(r: _Reader) -> Message:
    head: dict[str, str] = {}
    extra: list[tuple[str, str]] = []
    for s in r.raw.segments:
        k = s.key.lower()
        if k in ("time", "type", "name", "status") and k not in head:
            head[k] = s.value
        else:
            extra.append((s.key, s.value))
    return EffecterStatus(
        time=r.opt_time(),
        effecter_type=r.text("Type"),
        name=r.text("Name"),
        status=head.get("status"),
        extra=tuple(extra),
    )


_MESSAGE_PARSERS: dict[str, Callable[[_Reader], Message]] = {
    "NFO": _parse_nfo,
    "STA": _parse_sta,
    "SEN": _parse_sen,
    "GEO": _parse_geo,
    "CONF": _parse_conf,
    "MISSTA": _parse_missta,
    "ASTA": _parse_asta,
    "RES": _parse_res,
    "EFF": _parse_eff,
    "DIE": lambda r: Die(killer=r.text("Killer"), damage_type=r.text("DamageType")),
    "STEPPED": lambda r: Stepped(time=r.req_float("Time")),
    "PONG": lambda r: Pong(id=r.raw.get("Id"), time=r.opt_float("Time")),
    "ERROR": lambda r: ErrorReply(command=r.text("Command"), reason=r.text("Reason")),
}


def message_from_raw(raw: RawMessage) -> Message:
    """The message for an already split line (see :func:`parse_message`)."""
    parser = _MESSAGE_PARSERS.get(raw.type)
    if parser is None:
        return UnknownMessage(type=raw.type, segments=raw.segments)
    return parser(_Reader(raw, raw.type))


def parse_message(line: str) -> Message:
    """Parse one server line (with or without its CR LF) into a message.

    Unknown message types and sensor types give :class:`UnknownMessage`.  Raises
    :class:`~usarsim.errors.ProtocolError` when a known message lacks a key or has a bad value.
    """
    return message_from_raw(parse_line(line.rstrip("\r\n")))
