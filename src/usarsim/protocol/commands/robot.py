"""Commands that spawn and drive the robot, with their parsers and formats: ``INIT``
(protocol.md §5.1), ``DRIVE`` in every variant (§5.3) and ``MULTIDRIVE`` (§5.3g).  The
commands of its articulated parts are in :mod:`.parts`."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from usarsim import controls as K
from usarsim.errors import ProtocolError

from ..grammar import RawMessage
from .common import (
    Vec3,
    _bool,
    _choice,
    _float,
    _int,
    _Line,
    _non_negative_int,
    _positive_float,
    _read_fields,
    _Table,
    _text,
    _vec3,
    _word,
)

JOINT_ORDERS = frozenset({0, 1, 2, 3, 10, 11, 12})
"""Order codes of a DRIVE joint group (§5.3f): 0 angle, 1 speed, 2 torque, 3 brake torque,
10/11/12 relative angle/speed/torque."""


_ORDER_TEXT_JOINT = "one of 0, 1, 2, 3, 10, 11, 12"


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


# ---- parsing


_joint_order = _choice(_int, JOINT_ORDERS, _ORDER_TEXT_JOINT)


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


# ---- formatting


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


PARSERS: dict[str, Callable[[RawMessage], Init | Drive | MultiDrive]] = {
    "INIT": _parse_init,
    "DRIVE": _parse_drive,
    "MULTIDRIVE": _parse_multidrive,
}

FORMATTERS: dict[type, Callable[[Any], str]] = {
    Init: _format_init,
    Drive: _format_drive,
    MultiDrive: _format_multidrive,
}
