"""Typed commands that flow from the protocol layer to the simulation.

The protocol turns a ``DRIVE`` line into a :class:`DriveCommand`: its parts by kind (wheel
speeds, Ackermann, holonomic wheels, velocities, nautical), its joint orders, and the
Light, Flip and Normalized keys that go with any of them.  A robot's drive model
(:mod:`usarsim.robots`) applies the parts its kind understands and ignores the others.

This module imports the standard library only, so that the sans-IO protocol layer and
the simulation layer may both depend on it (as on :mod:`usarsim.readings`).

Units as on the wire (protocol.md 5.3): rad/s for wheel spin, radians for steering
angles, m/s and rad/s (yaw positive clockwise seen from above) for velocities; with
``normalized`` the values are percentages (-100..100) of the robot's maxima.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class WheelSpeeds:
    """``{Left} {Right}`` (protocol.md 5.3a): each side's spin speed; None: not sent."""

    left: float | None = None
    right: float | None = None


@dataclass(frozen=True, slots=True)
class AckermannDrive:
    """``{Speed} {FrontSteer} {RearSteer}`` (5.3b); what is not sent keeps its value."""

    speed: float | None = None
    front_steer: float | None = None
    rear_steer: float | None = None


@dataclass(frozen=True, slots=True)
class SteeredWheel:
    """One ``{WheelNumber n} {WheelSpeed v} {WheelSteer a}`` group (5.3c)."""

    number: int
    speed: float | None = None
    steer: float | None = None


@dataclass(frozen=True, slots=True)
class SteeredWheels:
    """A holonomic robot's numbered steered wheels (5.3c)."""

    wheels: tuple[SteeredWheel, ...] = ()


@dataclass(frozen=True, slots=True)
class Velocities:
    """``{AltitudeVelocity} {LinearVelocity} {LateralVelocity} {RotationalVelocity}`` (5.3d):
    m/s up, forward, right and rad/s clockwise; what is not sent keeps its value."""

    altitude: float | None = None
    linear: float | None = None
    lateral: float | None = None
    rotational: float | None = None


@dataclass(frozen=True, slots=True)
class NauticalDrive:
    """``{Propeller} {Rudder} {SternPlane}`` (5.3e)."""

    propeller: float | None = None
    rudder: float | None = None
    stern_plane: float | None = None


@dataclass(frozen=True, slots=True)
class JointOrder:
    """A joint (link or wheel) order (5.3f): 0 angle, 1 speed, 2 torque, 3 brake, 10/11/12
    the same relative to the current value."""

    name: str
    value: float
    order: int = 0


DrivePart = WheelSpeeds | AckermannDrive | SteeredWheels | Velocities | NauticalDrive


@dataclass(frozen=True, slots=True)
class DriveCommand:
    """One DRIVE: the parts that were sent (at most one of each kind), then its joint
    orders; ``light`` None: not sent."""

    parts: tuple[DrivePart, ...] = ()
    joints: tuple[JointOrder, ...] = ()
    normalized: bool = False
    light: bool | None = None
    flip: bool = False

    def part(self, kind: type) -> DrivePart | None:
        """The part of ``kind`` (a class of this module), or None when it was not sent."""
        for p in self.parts:
            if type(p) is kind:
                return p
        return None


# Every kind of DRIVE part, in the order a DRIVE's parts are listed.
PART_KINDS: tuple[type, ...] = (WheelSpeeds, AckermannDrive, SteeredWheels, Velocities, NauticalDrive)
