"""Client commands (protocol.md §5 and §18) as typed values.

:func:`parse_command` turns one line into one of the frozen dataclasses below;
:func:`format_command` writes a command the way a client would send it.

Parsing rules, common to every command:

* The command word and the keys are case-insensitive (MOAST sends ``Drive`` and
  ``{Classname ...}``, RDK test code ``{RIGHT 1.0}``).
* Unknown keys are ignored (the NIST Iridium UI sends extras).  An unknown command word gives
  :class:`UnknownCommand`, which is not an error: servers ignore such lines.
* A key that occurs twice counts once, the first time (the UDK server's lookup did the same);
  keys that start or continue a repeated group (DRIVE joints and wheels, MISPKG/ACT links)
  are read in order instead.
* A malformed line, or a value that a known key cannot take, raises
  :class:`~usarsim.errors.ProtocolError` naming the command, the key, the value received and
  what is allowed.  NaN and infinite numbers are never accepted.
* A field is ``None`` when its key was not sent; the session keeps the previous value.

Commands are frozen, keyword-only dataclasses; the small group records inside them
(:class:`WheelDrive`, :class:`JointDrive`, :class:`LinkCommand`) and :class:`UnknownCommand`
also accept positional arguments.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from usarsim import controls as K
from usarsim.errors import ProtocolError

from .grammar import (
    RawMessage,
    Segment,
    format_segment,
    parse_bool,
    parse_float,
    parse_int,
    parse_line,
    parse_vector,
)
from .numbers import bool_str, num

__all__ = [
    "Act",
    "Camera",
    "Command",
    "Control",
    "Drive",
    "GetClosestPathNode",
    "GetConf",
    "GetGeo",
    "GetPathNodes",
    "GetStartPoses",
    "Ping",
    "Report",
    "Goto",
    "Init",
    "JOINT_ORDERS",
    "JointDrive",
    "LINK_ORDERS",
    "LinkCommand",
    "MisPkg",
    "Move",
    "MultiDrive",
    "Set",
    "Step",
    "Test",
    "UnknownCommand",
    "Vec3",
    "WheelDrive",
    "command_from_raw",
    "format_command",
    "parse_command",
]

Vec3 = tuple[float, float, float]

JOINT_ORDERS = frozenset({0, 1, 2, 3, 10, 11, 12})
"""Order codes of a DRIVE joint group (§5.3f): 0 angle, 1 speed, 2 torque, 3 brake torque,
10/11/12 relative angle/speed/torque."""

LINK_ORDERS = frozenset({0, 1, 2})
"""Order codes of MISPKG/ACT link groups (§5.6): 0 position, 1 velocity, 2 torque."""

_ORDER_TEXT_JOINT = "one of 0, 1, 2, 3, 10, 11, 12"
_ORDER_TEXT_LINK = "one of 0 (position), 1 (velocity), 2 (torque)"

_BARE_NUMBER_RE = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)\Z")
_VIEWPORT_RE = re.compile(r"viewport([0-9]{1,3})\Z", re.IGNORECASE)


# --------------------------------------------------------------------------- commands


@dataclass(frozen=True, slots=True, kw_only=True)
class Init:
    """``INIT``: spawn this connection's robot (§5.1).

    ``class_name`` is kept as sent (``USARBot.P2AT`` or ``P2AT``); the session strips the
    package prefix and matches case-insensitively.  ``start`` names a start pose and wins
    over ``location``/``rotation``.  ``battery_s`` (``{Battery s}``, seen in
    re-implementations) overrides the robot's battery life.
    """

    keyword: ClassVar[str] = "INIT"
    class_name: str | None = None
    name: str | None = None
    location: Vec3 | None = None
    rotation: Vec3 | None = None
    start: str | None = None
    battery_s: float | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class GetStartPoses:
    """``GETSTARTPOSES`` (§5.2)."""

    keyword: ClassVar[str] = "GETSTARTPOSES"


@dataclass(frozen=True, slots=True)
class WheelDrive:
    """One ``{WheelNumber n} {WheelSpeed v} {WheelSteer a}`` group of an omni DRIVE (§5.3c)."""

    number: int
    speed: float | None = None
    steer: float | None = None


@dataclass(frozen=True, slots=True)
class JointDrive:
    """One ``{Name j} {Value v} {Steer s} {Order o}`` group of a joint DRIVE (§5.3f).

    ``order`` is one of :data:`JOINT_ORDERS` (0 when not sent).
    """

    name: str
    value: float | None = None
    steer: float | None = None
    order: int = 0


@dataclass(frozen=True, slots=True, kw_only=True)
class Drive:
    """``DRIVE`` in every variant of §5.3; only the keys that were sent are set.

    Skid steering uses ``left``/``right``; Ackermann ``speed``/``front_steer``/``rear_steer``;
    omni wheels ``wheels``; aerial ``altitude_velocity``/``linear_velocity``/
    ``lateral_velocity``/``rotational_velocity``; underwater ``propeller``/``rudder``/
    ``stern_plane``; low-level joints ``joints``.  ``normalized`` (also accepted as the
    misspelt ``Normalize``), ``light`` and ``flip`` may come with any of them, or alone.
    """

    keyword: ClassVar[str] = "DRIVE"
    left: float | None = None
    right: float | None = None
    normalized: bool | None = None
    light: bool | None = None
    flip: bool | None = None
    speed: float | None = None
    front_steer: float | None = None
    rear_steer: float | None = None
    wheels: tuple[WheelDrive, ...] = ()
    altitude_velocity: float | None = None
    linear_velocity: float | None = None
    lateral_velocity: float | None = None
    rotational_velocity: float | None = None
    propeller: float | None = None
    rudder: float | None = None
    stern_plane: float | None = None
    joints: tuple[JointDrive, ...] = ()

    def command(self) -> K.DriveCommand:
        """The typed command the simulation applies: one part per kind of key that was
        sent (a robot's drive model applies those its kind understands), the joint orders
        that carry a Value, and the Light, Flip and Normalized keys."""
        parts: list[K.DrivePart] = []
        if self.left is not None or self.right is not None:
            parts.append(K.WheelSpeeds(self.left, self.right))
        if self.speed is not None or self.front_steer is not None or self.rear_steer is not None:
            parts.append(K.AckermannDrive(self.speed, self.front_steer, self.rear_steer))
        if self.wheels:
            parts.append(K.SteeredWheels(tuple(K.SteeredWheel(w.number, w.speed, w.steer) for w in self.wheels)))
        if any(
            v is not None
            for v in (self.altitude_velocity, self.linear_velocity, self.lateral_velocity, self.rotational_velocity)
        ):
            parts.append(
                K.Velocities(
                    self.altitude_velocity, self.linear_velocity, self.lateral_velocity, self.rotational_velocity
                )
            )
        if self.propeller is not None or self.rudder is not None or self.stern_plane is not None:
            parts.append(K.NauticalDrive(self.propeller, self.rudder, self.stern_plane))
        return K.DriveCommand(
            parts=tuple(parts),
            joints=tuple(K.JointOrder(j.name, j.value, j.order) for j in self.joints if j.value is not None),
            normalized=bool(self.normalized),
            light=self.light,
            flip=bool(self.flip),
        )


@dataclass(frozen=True, slots=True, kw_only=True)
class MultiDrive:
    """``MULTIDRIVE {Joint value} ...``: absolute joint angles by joint name (§5.3g).

    Joint names are kept as written, in order.
    """

    keyword: ClassVar[str] = "MULTIDRIVE"
    joints: tuple[tuple[str, float], ...] = ()


@dataclass(frozen=True, slots=True, kw_only=True)
class Set:
    """``SET``: operate a mounted item (§5.4).

    Values are kept as sent (text), so that a command formats back as it came: their meaning
    depends on the item (``params`` is a FOV for a camera, ``<tagID> <data...>`` for an RFID
    write, ``value,steer`` for a joint).  :attr:`values` gives the numbers of ``params``.
    The Player driver sends a camera zoom as a bare segment (``{Opcode Zoom} {0.87}``); a
    bare number stands for ``params`` when no ``Params`` key is present.
    ``viewports`` holds ``{ViewportN cam}`` pairs as ``(N, cam)``.  ``segments`` holds the
    segments not turned into a field above (item-specific keys), in order.
    """

    keyword: ClassVar[str] = "SET"
    type: str | None = None
    name: str | None = None
    opcode: str | None = None
    params: str | None = None
    robot: str | None = None
    client: str | None = None
    config: str | None = None
    viewports: tuple[tuple[int, str], ...] = ()
    value: str | None = None
    segments: tuple[Segment, ...] = ()

    def get(self, key: str, default: str | None = None) -> str | None:
        """Value of the first item-specific segment with this key (case-insensitive)."""
        return _segment_value(self.segments, key, default)

    @property
    def values(self) -> tuple[float, ...] | None:
        """The numbers of ``params``, split on commas and blanks (``{Params 0.5,0}`` ->
        ``(0.5, 0.0)``); None when Params was not sent, is empty, or holds anything but
        finite numbers (an RFID write's text)."""
        words = (self.params or "").replace(",", " ").split()
        if not words:
            return None
        try:
            numbers = tuple(parse_float(w) for w in words)
        except ProtocolError:
            return None
        return numbers if all(math.isfinite(x) for x in numbers) else None


@dataclass(frozen=True, slots=True, kw_only=True)
class GetGeo:
    """``GETGEO {Type T} [{Name N}]`` (§5.5); ``Type Robot`` asks for the robot itself."""

    keyword: ClassVar[str] = "GETGEO"
    type: str | None = None
    name: str | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class GetConf:
    """``GETCONF {Type T} [{Name N}]`` (§5.5)."""

    keyword: ClassVar[str] = "GETCONF"
    type: str | None = None
    name: str | None = None


@dataclass(frozen=True, slots=True)
class LinkCommand:
    """One ``{Link n} {Value v} [{Order o}]`` group of MISPKG or ACT (§5.6, §5.8).

    ``order`` is one of :data:`LINK_ORDERS` (0 when not sent).
    """

    link: int
    value: float
    order: int = 0


@dataclass(frozen=True, slots=True, kw_only=True)
class MisPkg:
    """``MISPKG``: mission package control (§5.6).

    ``links`` holds the ``Link``/``Value``/``Order`` groups.  The older API sends
    ``{Rotation roll,tilt,pan}`` with an ``{Order 0|1}`` that is not inside a link group;
    that order is ``order``.
    """

    keyword: ClassVar[str] = "MISPKG"
    name: str | None = None
    type: str | None = None
    links: tuple[LinkCommand, ...] = ()
    rotation: Vec3 | None = None
    order: int | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Camera:
    """``CAMERA {Rotation r,p,y} {Zoom fov}``: legacy pan/tilt/zoom (§5.7)."""

    keyword: ClassVar[str] = "CAMERA"
    rotation: Vec3 | None = None
    zoom: float | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Act:
    """``ACT``: actuator control (§5.8, UDK).  ``gripper`` 1 closes, 0 opens.

    ``Seq`` is accepted for ``Sequence``.
    """

    keyword: ClassVar[str] = "ACT"
    name: str | None = None
    links: tuple[LinkCommand, ...] = ()
    gripper: int | None = None
    sequence: int | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Control:
    """``CONTROL``: world-controller request (§5.8, UDK).

    ``segments`` holds every segment other than the first ``Type`` and ``Name``, in order;
    their meaning depends on ``type`` (Create, Kill, KillAll, AbsMove, ...).
    """

    keyword: ClassVar[str] = "CONTROL"
    type: str | None = None
    name: str | None = None
    segments: tuple[Segment, ...] = ()

    def get(self, key: str, default: str | None = None) -> str | None:
        """Value of the first segment with this key (case-insensitive)."""
        return _segment_value(self.segments, key, default)


@dataclass(frozen=True, slots=True, kw_only=True)
class Move:
    """``MOVE``: avatar walking (§5.8, UDK).  ``location`` has 2 (x,y) or 3 numbers."""

    keyword: ClassVar[str] = "MOVE"
    type: str | None = None
    action: str | None = None
    location: tuple[float, ...] | None = None
    pathnode: str | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Goto:
    """``GOTO {Name pathnode}`` (§5.8, UDK)."""

    keyword: ClassVar[str] = "GOTO"
    name: str | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class GetPathNodes:
    """``GETPATHNODES`` (§5.8, UDK)."""

    keyword: ClassVar[str] = "GETPATHNODES"


@dataclass(frozen=True, slots=True, kw_only=True)
class GetClosestPathNode:
    """``GETCLOSESTPATHNODE {Location x,y,z}`` (§5.8, UDK)."""

    keyword: ClassVar[str] = "GETCLOSESTPATHNODE"
    location: Vec3 | None = None


@dataclass(frozen=True, slots=True, kw_only=True)
class Test:
    """``TEST``: UDK test mode; every segment is kept."""

    keyword: ClassVar[str] = "TEST"
    segments: tuple[Segment, ...] = ()


@dataclass(frozen=True, slots=True, kw_only=True)
class Step:
    """``STEP {Time s}``: advance the lock-step clock by ``time_s`` > 0 seconds (§18)."""

    keyword: ClassVar[str] = "STEP"
    time_s: float


@dataclass(frozen=True, slots=True)
class Ping:
    """``PING [{Id text}]``: answered ``PONG [{Id text}] {Time t}`` (an extension) once every
    request sent before it was carried out (an INIT's spawn or its ERROR) and every message
    produced so far was written to this connection: a client that waits for it has read
    everything (usarsim.client does after INIT and after each lock-step STEP)."""

    keyword: ClassVar[str] = "PING"
    id: str | None = None


@dataclass(frozen=True, slots=True)
class Report:
    """``REPORT {Type Victim} {Location x,y,z} [{Name label}]`` (an extension): the controller
    reports a victim where it believes one lies (world frame, metres), for the score
    (docs/scoring.md); answered ``RES {Time t} {Type Victim} {Name label} {Status OK}
    {Location x,y,z}``.  ``Victim`` is the only type."""

    keyword: ClassVar[str] = "REPORT"
    type: str = "Victim"
    location: Vec3 = (0.0, 0.0, 0.0)
    name: str | None = None


REPORT_TYPES = ("Victim",)


@dataclass(frozen=True, slots=True)
class UnknownCommand:
    """A line whose command word is not known; servers ignore it.  ``type`` is upper-cased."""

    type: str
    segments: tuple[Segment, ...] = ()


Command = (
    Init
    | GetStartPoses
    | Drive
    | MultiDrive
    | Set
    | GetGeo
    | GetConf
    | MisPkg
    | Camera
    | Act
    | Control
    | Move
    | Goto
    | GetPathNodes
    | GetClosestPathNode
    | Test
    | Step
    | Ping
    | Report
    | UnknownCommand
)


# --------------------------------------------------------------------------- value readers

_Reader = Callable[[str, Segment], Any]


def _segment_value(segments: tuple[Segment, ...], key: str, default: str | None) -> str | None:
    wanted = key.lower()
    for seg in segments:
        if seg.key.lower() == wanted:
            return seg.value
    return default


def _bad(cmd: str, seg: Segment, allowed: str) -> ProtocolError:
    return ProtocolError(f"{cmd}: bad value {seg.value!r} for key {seg.key}: expected {allowed}")


def _text(cmd: str, seg: Segment) -> str:
    return seg.value


def _float(cmd: str, seg: Segment) -> float:
    try:
        x = parse_float(seg.value)
    except ProtocolError as exc:
        raise _bad(cmd, seg, "a number such as 1.5") from exc
    if not math.isfinite(x):
        raise _bad(cmd, seg, "a finite number (NaN and infinity are not allowed)")
    return x


def _positive_float(cmd: str, seg: Segment) -> float:
    x = _float(cmd, seg)
    if x <= 0.0:
        raise _bad(cmd, seg, "a number greater than 0")
    return x


def _int(cmd: str, seg: Segment) -> int:
    try:
        return parse_int(seg.value)
    except ProtocolError as exc:
        raise _bad(cmd, seg, "an integer such as 1") from exc


def _non_negative_int(cmd: str, seg: Segment) -> int:
    n = _int(cmd, seg)
    if n < 0:
        raise _bad(cmd, seg, "an integer of 0 or more")
    return n


def _bool(cmd: str, seg: Segment) -> bool:
    try:
        return parse_bool(seg.value)
    except ProtocolError as exc:
        raise _bad(cmd, seg, "True, False, 1 or 0 (any letter case)") from exc


def _vec(cmd: str, seg: Segment, n: int | None) -> tuple[float, ...]:
    what = f"{n} numbers such as 1.0,2.0,3.0" if n else "numbers separated by commas"
    try:
        v = parse_vector(seg.value, n)
    except ProtocolError as exc:
        raise _bad(cmd, seg, what + " (commas and/or spaces between them)") from exc
    if not all(map(math.isfinite, v)):
        raise _bad(cmd, seg, what + ", all finite (NaN and infinity are not allowed)")
    return v


def _vec3(cmd: str, seg: Segment) -> Vec3:
    return _vec(cmd, seg, 3)  # type: ignore[return-value]


def _vec2or3(cmd: str, seg: Segment) -> tuple[float, ...]:
    v = _vec(cmd, seg, None)
    if len(v) not in (2, 3):
        raise _bad(cmd, seg, "2 or 3 numbers such as 1.0,2.0")
    return v


def _choice(reader: _Reader, allowed: frozenset[int], text: str) -> _Reader:
    def read(cmd: str, seg: Segment) -> Any:
        value = reader(cmd, seg)
        if value not in allowed:
            raise _bad(cmd, seg, text)
        return value

    return read


_joint_order = _choice(_int, JOINT_ORDERS, _ORDER_TEXT_JOINT)
_link_order = _choice(_int, LINK_ORDERS, _ORDER_TEXT_LINK)
_gripper = _choice(_int, frozenset({0, 1}), "1 (close) or 0 (open)")

_Table = dict[str, tuple[str, _Reader]]


def _read_fields(cmd: str, segments: tuple[Segment, ...], table: _Table) -> dict[str, Any]:
    """Fields of a command from ``table`` (lower-case key -> (field, reader)); first wins."""
    values: dict[str, Any] = {}
    for seg in segments:
        entry = table.get(seg.key.lower())
        if entry is not None and entry[0] not in values:
            values[entry[0]] = entry[1](cmd, seg)
    return values


# --------------------------------------------------------------------------- parsers

_INIT_KEYS: _Table = {
    "classname": ("class_name", _text),
    "name": ("name", _text),
    "location": ("location", _vec3),
    "rotation": ("rotation", _vec3),
    "start": ("start", _text),
    "battery": ("battery_s", _positive_float),
}


def _parse_init(raw: RawMessage) -> Init:
    return Init(**_read_fields(raw.type, raw.segments, _INIT_KEYS))


def _parse_get_start_poses(raw: RawMessage) -> GetStartPoses:
    return GetStartPoses()


_DRIVE_KEYS: _Table = {
    "left": ("left", _float),
    "right": ("right", _float),
    "normalized": ("normalized", _bool),
    "normalize": ("normalized", _bool),  # AUT toolbox spelling
    "light": ("light", _bool),
    "flip": ("flip", _bool),
    "speed": ("speed", _float),
    "frontsteer": ("front_steer", _float),
    "rearsteer": ("rear_steer", _float),
    "altitudevelocity": ("altitude_velocity", _float),
    "linearvelocity": ("linear_velocity", _float),
    "lateralvelocity": ("lateral_velocity", _float),
    "rotationalvelocity": ("rotational_velocity", _float),
    "propeller": ("propeller", _float),
    "rudder": ("rudder", _float),
    "sternplane": ("stern_plane", _float),
}

_WHEEL_KEYS: _Table = {"wheelspeed": ("speed", _float), "wheelsteer": ("steer", _float)}
_JOINT_KEYS: _Table = {
    "value": ("value", _float),
    "steer": ("steer", _float),
    "order": ("order", _joint_order),
}


def _parse_drive(raw: RawMessage) -> Drive:
    cmd = raw.type
    values: dict[str, Any] = {}
    wheels: list[WheelDrive] = []
    joints: list[JointDrive] = []
    wheel: dict[str, Any] | None = None
    joint: dict[str, Any] | None = None
    for seg in raw.segments:
        key = seg.key.lower()
        entry = _DRIVE_KEYS.get(key)
        if entry is not None:
            if entry[0] not in values:
                values[entry[0]] = entry[1](cmd, seg)
        elif key == "wheelnumber":
            if wheel is not None:
                wheels.append(WheelDrive(**wheel))
            wheel = {"number": _non_negative_int(cmd, seg)}
        elif key in _WHEEL_KEYS:
            if wheel is None:
                raise ProtocolError(
                    f"{cmd}: {{{seg.key} {seg.value}}} comes before any {{WheelNumber n}}: "
                    "each wheel group must start with WheelNumber"
                )
            field, reader = _WHEEL_KEYS[key]
            wheel[field] = reader(cmd, seg)
        elif key == "name":
            if joint is not None:
                joints.append(JointDrive(**joint))
            joint = {"name": seg.value}
        elif key in _JOINT_KEYS:
            if joint is None:
                raise ProtocolError(
                    f"{cmd}: {{{seg.key} {seg.value}}} comes before any {{Name joint}}: "
                    "each joint group must start with Name"
                )
            field, reader = _JOINT_KEYS[key]
            joint[field] = reader(cmd, seg)
    if wheel is not None:
        wheels.append(WheelDrive(**wheel))
    if joint is not None:
        joints.append(JointDrive(**joint))
    return Drive(wheels=tuple(wheels), joints=tuple(joints), **values)


def _parse_multidrive(raw: RawMessage) -> MultiDrive:
    cmd = raw.type
    joints = []
    for seg in raw.segments:
        if not seg.value:
            raise ProtocolError(f"{cmd}: segment {{{seg.key}}} has no value: expected {{JointName angle}}")
        joints.append((seg.key, _float(cmd, seg)))
    return MultiDrive(joints=tuple(joints))


_SET_KEYS: _Table = {
    "type": ("type", _text),
    "name": ("name", _text),
    "opcode": ("opcode", _text),
    "params": ("params", _text),
    "robot": ("robot", _text),
    "client": ("client", _text),
    "config": ("config", _text),
    "value": ("value", _text),
}


def _parse_set(raw: RawMessage) -> Set:
    values: dict[str, Any] = {}
    viewports: list[tuple[int, str]] = []
    rest: list[Segment] = []
    bare_number: Segment | None = None
    for seg in raw.segments:
        entry = _SET_KEYS.get(seg.key.lower())
        if entry is not None and entry[0] not in values:
            values[entry[0]] = seg.value
            continue
        vm = _VIEWPORT_RE.match(seg.key)
        if vm is not None:
            viewports.append((int(vm.group(1)), seg.value))
            continue
        if bare_number is None and not seg.value and _BARE_NUMBER_RE.match(seg.key):
            bare_number = seg
        rest.append(seg)
    if "params" not in values and bare_number is not None:
        values["params"] = bare_number.key
        rest.remove(bare_number)
    return Set(viewports=tuple(viewports), segments=tuple(rest), **values)


_TYPE_NAME_KEYS: _Table = {"type": ("type", _text), "name": ("name", _text)}


def _parse_getgeo(raw: RawMessage) -> GetGeo:
    return GetGeo(**_read_fields(raw.type, raw.segments, _TYPE_NAME_KEYS))


def _parse_getconf(raw: RawMessage) -> GetConf:
    return GetConf(**_read_fields(raw.type, raw.segments, _TYPE_NAME_KEYS))


def _read_links(
    cmd: str, segments: tuple[Segment, ...], table: _Table
) -> tuple[tuple[LinkCommand, ...], dict[str, Any]]:
    """Link groups plus the first-wins fields of ``table``.

    An ``Order`` inside a link group belongs to that link; one before any link goes to the
    ``order`` field of ``table`` when it has one (the legacy MISPKG Rotation form).
    """
    values: dict[str, Any] = {}
    links: list[LinkCommand] = []
    group: dict[str, Any] | None = None

    def close(group: dict[str, Any]) -> None:
        if "value" not in group:
            raise ProtocolError(
                f"{cmd}: {{Link {group['link']}}} has no {{Value v}}: "
                "each link group is {Link n} {Value v} [{Order o}]"
            )
        links.append(LinkCommand(**group))

    for seg in segments:
        key = seg.key.lower()
        if key == "link":
            if group is not None:
                close(group)
            group = {"link": _int(cmd, seg)}
        elif key == "value":
            if group is None:
                raise ProtocolError(
                    f"{cmd}: {{{seg.key} {seg.value}}} comes before any {{Link n}}: "
                    "each link group must start with Link"
                )
            group["value"] = _float(cmd, seg)
        elif key == "order" and group is not None:
            group["order"] = _link_order(cmd, seg)
        else:
            entry = table.get(key)
            if entry is not None and entry[0] not in values:
                values[entry[0]] = entry[1](cmd, seg)
    if group is not None:
        close(group)
    return tuple(links), values


_MISPKG_KEYS: _Table = {
    "name": ("name", _text),
    "type": ("type", _text),
    "rotation": ("rotation", _vec3),
    "order": ("order", _link_order),
}


def _parse_mispkg(raw: RawMessage) -> MisPkg:
    links, values = _read_links(raw.type, raw.segments, _MISPKG_KEYS)
    return MisPkg(links=links, **values)


_ACT_KEYS: _Table = {
    "name": ("name", _text),
    "gripper": ("gripper", _gripper),
    "sequence": ("sequence", _int),
    "seq": ("sequence", _int),
}


def _parse_act(raw: RawMessage) -> Act:
    links, values = _read_links(raw.type, raw.segments, _ACT_KEYS)
    return Act(links=links, **values)


_CAMERA_KEYS: _Table = {"rotation": ("rotation", _vec3), "zoom": ("zoom", _float)}


def _parse_camera(raw: RawMessage) -> Camera:
    return Camera(**_read_fields(raw.type, raw.segments, _CAMERA_KEYS))


def _parse_control(raw: RawMessage) -> Control:
    values: dict[str, Any] = {}
    rest: list[Segment] = []
    for seg in raw.segments:
        entry = _TYPE_NAME_KEYS.get(seg.key.lower())
        if entry is not None and entry[0] not in values:
            values[entry[0]] = seg.value
        else:
            rest.append(seg)
    return Control(segments=tuple(rest), **values)


_MOVE_KEYS: _Table = {
    "type": ("type", _text),
    "action": ("action", _text),
    "location": ("location", _vec2or3),
    "pathnode": ("pathnode", _text),
}


def _parse_move(raw: RawMessage) -> Move:
    return Move(**_read_fields(raw.type, raw.segments, _MOVE_KEYS))


_GOTO_KEYS: _Table = {"name": ("name", _text)}


def _parse_goto(raw: RawMessage) -> Goto:
    return Goto(**_read_fields(raw.type, raw.segments, _GOTO_KEYS))


def _parse_get_path_nodes(raw: RawMessage) -> GetPathNodes:
    return GetPathNodes()


_LOCATION_KEYS: _Table = {"location": ("location", _vec3)}


def _parse_get_closest_path_node(raw: RawMessage) -> GetClosestPathNode:
    return GetClosestPathNode(**_read_fields(raw.type, raw.segments, _LOCATION_KEYS))


def _parse_test(raw: RawMessage) -> Test:
    return Test(segments=raw.segments)


_STEP_KEYS: _Table = {"time": ("time_s", _positive_float)}


def _parse_step(raw: RawMessage) -> Step:
    values = _read_fields(raw.type, raw.segments, _STEP_KEYS)
    if "time_s" not in values:
        raise ProtocolError(f"{raw.type}: missing {{Time seconds}}: expected for example STEP {{Time 0.2}}")
    return Step(**values)


_REPORT_KEYS: _Table = {"type": ("type", _text), "location": ("location", _vec3), "name": ("name", _text)}


def _parse_report(raw: RawMessage) -> Report:
    values = _read_fields(raw.type, raw.segments, _REPORT_KEYS)
    if "type" not in values:
        raise ProtocolError(f"{raw.type}: missing {{Type Victim}}")
    kind = next((t for t in REPORT_TYPES if t.lower() == values["type"].lower()), None)
    if kind is None:
        raise ProtocolError(
            f"{raw.type}: {{Type {values.get('type', '')}}} is not a kind of report: expected {{Type Victim}}"
        )
    if "location" not in values:
        raise ProtocolError(
            f"{raw.type}: missing {{Location x,y,z}}: expected for example "
            f"REPORT {{Type Victim}} {{Location 3.1,6.0,0.1}}"
        )
    return Report(type=kind, location=values["location"], name=values.get("name"))


_PARSERS: dict[str, Callable[[RawMessage], Command]] = {
    "INIT": _parse_init,
    "GETSTARTPOSES": _parse_get_start_poses,
    "DRIVE": _parse_drive,
    "MULTIDRIVE": _parse_multidrive,
    "SET": _parse_set,
    "GETGEO": _parse_getgeo,
    "GETCONF": _parse_getconf,
    "MISPKG": _parse_mispkg,
    "CAMERA": _parse_camera,
    "ACT": _parse_act,
    "CONTROL": _parse_control,
    "MOVE": _parse_move,
    "GOTO": _parse_goto,
    "GETPATHNODES": _parse_get_path_nodes,
    "GETCLOSESTPATHNODE": _parse_get_closest_path_node,
    "TEST": _parse_test,
    "STEP": _parse_step,
    "PING": lambda raw: Ping(id=raw.get("Id")),
    "REPORT": _parse_report,
}


def command_from_raw(raw: RawMessage) -> Command:
    """The command for an already split line (see :func:`parse_command`)."""
    parser = _PARSERS.get(raw.type)
    if parser is None:
        return UnknownCommand(type=raw.type, segments=raw.segments)
    return parser(raw)


# ``STEP {Time s}`` as lock-step controllers write it, thousands of times a second: read
# without splitting the line (anything else, a STEP written otherwise included, is split).
_PLAIN_STEP = re.compile(r"STEP \{Time ((?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\}")


def parse_command(line: str) -> Command:
    """Parse one client line (without its terminator) into a command.

    Raises :class:`~usarsim.errors.ProtocolError` for a malformed line or a bad value of a
    known key, and nothing else.
    """
    m = _PLAIN_STEP.fullmatch(line)
    if m is not None:
        seconds = float(m.group(1))
        if 0.0 < seconds < math.inf:  # else the general path says what is wrong
            return Step(time_s=seconds)
    return command_from_raw(parse_line(line))


# --------------------------------------------------------------------------- formatting


def _check(text: str, what: str) -> str:
    if "{" in text or "}" in text or "\r" in text or "\n" in text:
        raise ProtocolError(f"cannot send {what} {text!r}: braces and line breaks are not allowed")
    return text


def _word(text: str, what: str) -> str:
    _check(text, what)
    if not text or text != text.strip() or len(text.split()) != 1:
        raise ProtocolError(f"cannot send {what} {text!r}: it must be one word without spaces")
    return text


class _Line:
    """Builds ``TYPE {Key Value} ...\\r\\n``, skipping fields that are None."""

    __slots__ = ("parts",)

    def __init__(self, keyword: str):
        self.parts = [keyword]

    def text(self, key: str, value: str | None) -> _Line:
        if value is not None:
            self.parts.append(format_segment(key, _check(value, key)))
        return self

    def number(self, key: str, value: float | None) -> _Line:
        if value is not None:
            self.parts.append("{%s %s}" % (key, num(value)))
        return self

    def integer(self, key: str, value: int | None) -> _Line:
        if value is not None:
            self.parts.append("{%s %d}" % (key, value))
        return self

    def boolean(self, key: str, value: bool | None) -> _Line:
        if value is not None:
            self.parts.append("{%s %s}" % (key, bool_str(value)))
        return self

    def vector(self, key: str, value: tuple[float, ...] | None) -> _Line:
        if value is not None:
            self.parts.append("{%s %s}" % (key, ",".join(map(num, value))))
        return self

    def segments(self, segments: tuple[Segment, ...]) -> _Line:
        for seg in segments:
            self.parts.append(format_segment(_word(seg.key, "key"), _check(seg.value, seg.key)))
        return self

    def links(self, links: tuple[LinkCommand, ...]) -> _Line:
        for link in links:
            self.integer("Link", link.link).number("Value", link.value)
            self.integer("Order", link.order)
        return self

    def end(self) -> str:
        return " ".join(self.parts) + "\r\n"


def _format_init(c: Init) -> str:
    return (
        _Line("INIT")
        .text("ClassName", c.class_name)
        .text("Name", c.name)
        .vector("Location", c.location)
        .vector("Rotation", c.rotation)
        .text("Start", c.start)
        .number("Battery", c.battery_s)
        .end()
    )


def _format_drive(c: Drive) -> str:
    line = (
        _Line("DRIVE")
        .number("Left", c.left)
        .number("Right", c.right)
        .number("Speed", c.speed)
        .number("FrontSteer", c.front_steer)
        .number("RearSteer", c.rear_steer)
        .number("AltitudeVelocity", c.altitude_velocity)
        .number("LinearVelocity", c.linear_velocity)
        .number("LateralVelocity", c.lateral_velocity)
        .number("RotationalVelocity", c.rotational_velocity)
        .number("Propeller", c.propeller)
        .number("Rudder", c.rudder)
        .number("SternPlane", c.stern_plane)
        .boolean("Normalized", c.normalized)
        .boolean("Light", c.light)
        .boolean("Flip", c.flip)
    )
    for w in c.wheels:
        line.integer("WheelNumber", w.number).number("WheelSpeed", w.speed)
        line.number("WheelSteer", w.steer)
    for j in c.joints:
        line.text("Name", j.name).number("Value", j.value).number("Steer", j.steer)
        line.integer("Order", j.order)
    return line.end()


def _format_multidrive(c: MultiDrive) -> str:
    line = _Line("MULTIDRIVE")
    for name, value in c.joints:
        line.number(_word(name, "joint name"), value)
    return line.end()


def _format_set(c: Set) -> str:
    line = (
        _Line("SET")
        .text("Type", c.type)
        .text("Name", c.name)
        .text("Robot", c.robot)
        .text("Client", c.client)
        .text("Opcode", c.opcode)
        .text("Params", c.params)
        .text("Value", c.value)
        .text("Config", c.config)
    )
    for index, camera in c.viewports:
        line.text("Viewport%d" % index, camera)
    return line.segments(c.segments).end()


def _format_mispkg(c: MisPkg) -> str:
    return (
        _Line("MISPKG")
        .text("Name", c.name)
        .text("Type", c.type)
        .vector("Rotation", c.rotation)
        .integer("Order", c.order)
        .links(c.links)
        .end()
    )


def _format_act(c: Act) -> str:
    return (
        _Line("ACT")
        .text("Name", c.name)
        .links(c.links)
        .integer("Gripper", c.gripper)
        .integer("Sequence", c.sequence)
        .end()
    )


def _format_control(c: Control) -> str:
    return _Line("CONTROL").text("Type", c.type).text("Name", c.name).segments(c.segments).end()


def _format_move(c: Move) -> str:
    return (
        _Line("MOVE")
        .text("Type", c.type)
        .text("Action", c.action)
        .vector("Location", c.location)
        .text("Pathnode", c.pathnode)
        .end()
    )


_FORMATTERS: dict[type, Callable[[Any], str]] = {
    Init: _format_init,
    GetStartPoses: lambda c: "GETSTARTPOSES\r\n",
    Drive: _format_drive,
    MultiDrive: _format_multidrive,
    Set: _format_set,
    GetGeo: lambda c: _Line("GETGEO").text("Type", c.type).text("Name", c.name).end(),
    GetConf: lambda c: _Line("GETCONF").text("Type", c.type).text("Name", c.name).end(),
    MisPkg: _format_mispkg,
    Camera: lambda c: _Line("CAMERA").vector("Rotation", c.rotation).number("Zoom", c.zoom).end(),
    Act: _format_act,
    Control: _format_control,
    Move: _format_move,
    Goto: lambda c: _Line("GOTO").text("Name", c.name).end(),
    GetPathNodes: lambda c: "GETPATHNODES\r\n",
    GetClosestPathNode: lambda c: _Line("GETCLOSESTPATHNODE").vector("Location", c.location).end(),
    Test: lambda c: _Line("TEST").segments(c.segments).end(),
    Step: lambda c: _Line("STEP").number("Time", c.time_s).end(),
    Ping: lambda c: _Line("PING").text("Id", c.id).end(),
    Report: lambda c: _Line("REPORT").text("Type", c.type).vector("Location", c.location).text("Name", c.name).end(),
    UnknownCommand: lambda c: _Line(_word(c.type, "command word")).segments(c.segments).end(),
}


def format_command(cmd: Command) -> str:
    """The line a client sends for ``cmd``, canonical key spelling, ending with CR LF.

    Numbers are written exactly (shortest form that reads back as the same float, no
    exponent).  Text containing braces or line breaks cannot be sent and raises
    :class:`~usarsim.errors.ProtocolError`.
    """
    try:
        formatter = _FORMATTERS[type(cmd)]
    except KeyError:
        raise TypeError(f"not a command: {cmd!r}") from None
    return formatter(cmd)
