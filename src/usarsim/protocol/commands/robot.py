"""Commands that spawn and drive the robot, with their parsers and formats: ``INIT``
(protocol.md §5.1), ``DRIVE`` in every variant (§5.3) and ``MULTIDRIVE`` (§5.3g).  The
commands of its articulated parts are in :mod:`.parts`."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from usarsim import controls as K

from ..grammar import RawMessage
from .common import Vec3
from .declare import (
    BOOL,
    COUNT,
    INTEGER,
    NUMBER,
    POSITIVE,
    TEXT,
    VEC3,
    choice,
    command,
    group,
    key,
    pairs,
)

JOINT_ORDERS = frozenset({0, 1, 2, 3, 10, 11, 12})
"""Order codes of a DRIVE joint group (§5.3f): 0 angle, 1 speed, 2 torque, 3 brake torque,
10/11/12 relative angle/speed/torque."""


_ORDER_TEXT_JOINT = "one of 0, 1, 2, 3, 10, 11, 12"
_JOINT_ORDER = choice(INTEGER, JOINT_ORDERS, _ORDER_TEXT_JOINT)


@dataclass(frozen=True, slots=True, kw_only=True)
class Init:
    """``INIT``: spawn this connection's robot (§5.1).

    ``class_name`` is kept as sent (``USARBot.P2AT`` or ``P2AT``); the session strips the
    package prefix and matches case-insensitively.  ``start`` names a start pose and wins
    over ``location``/``rotation``.  ``battery_s`` (``{Battery s}``, seen in
    re-implementations) overrides the robot's battery life.
    """

    keyword: ClassVar[str] = "INIT"
    class_name: str | None = key("ClassName", TEXT)
    name: str | None = key("Name", TEXT)
    location: Vec3 | None = key("Location", VEC3)
    rotation: Vec3 | None = key("Rotation", VEC3)
    start: str | None = key("Start", TEXT)
    battery_s: float | None = key("Battery", POSITIVE)


@dataclass(frozen=True, slots=True)
class WheelDrive:
    """One ``{WheelNumber n} {WheelSpeed v} {WheelSteer a}`` group of an omni DRIVE (§5.3c)."""

    number: int = key("WheelNumber", COUNT, hint="n", default=dataclasses.MISSING)
    speed: float | None = key("WheelSpeed", NUMBER)
    steer: float | None = key("WheelSteer", NUMBER)


@dataclass(frozen=True, slots=True)
class JointDrive:
    """One ``{Name j} {Value v} {Steer s} {Order o}`` group of a joint DRIVE (§5.3f).

    ``order`` is one of :data:`JOINT_ORDERS` (0 when not sent).
    """

    name: str = key("Name", TEXT, hint="joint", default=dataclasses.MISSING)
    value: float | None = key("Value", NUMBER)
    steer: float | None = key("Steer", NUMBER)
    order: int = key("Order", _JOINT_ORDER, default=0)


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
    left: float | None = key("Left", NUMBER)
    right: float | None = key("Right", NUMBER)
    speed: float | None = key("Speed", NUMBER)
    front_steer: float | None = key("FrontSteer", NUMBER)
    rear_steer: float | None = key("RearSteer", NUMBER)
    altitude_velocity: float | None = key("AltitudeVelocity", NUMBER)
    linear_velocity: float | None = key("LinearVelocity", NUMBER)
    lateral_velocity: float | None = key("LateralVelocity", NUMBER)
    rotational_velocity: float | None = key("RotationalVelocity", NUMBER)
    propeller: float | None = key("Propeller", NUMBER)
    rudder: float | None = key("Rudder", NUMBER)
    stern_plane: float | None = key("SternPlane", NUMBER)
    normalized: bool | None = key("Normalized", BOOL, "Normalize")  # Normalize: the AUT toolbox's spelling
    light: bool | None = key("Light", BOOL)
    flip: bool | None = key("Flip", BOOL)
    wheels: tuple[WheelDrive, ...] = group(WheelDrive, "wheel")
    joints: tuple[JointDrive, ...] = group(JointDrive, "joint")

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
    joints: tuple[tuple[str, float], ...] = pairs("{JointName angle}", "joint name")


# ---- parsing and formatting, from the declarations above

_INIT = command(Init)
_DRIVE = command(Drive)
_MULTIDRIVE = command(MultiDrive)

PARSERS: dict[str, Callable[[RawMessage], Init | Drive | MultiDrive]] = {
    "INIT": _INIT.parse,
    "DRIVE": _DRIVE.parse,
    "MULTIDRIVE": _MULTIDRIVE.parse,
}

FORMATTERS: dict[type, Callable[[Any], str]] = {
    Init: _INIT.format,
    Drive: _DRIVE.format,
    MultiDrive: _MULTIDRIVE.format,
}
