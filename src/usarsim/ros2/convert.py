"""USARSim's axes and commands to ROS 2's, without rclpy: plain numbers in, plain numbers out.

USARSim's frames (protocol.md, section 2) are X forward, Y right, Z down, with yaw clockwise seen
from above; ROS's (REP 103) are X forward, Y left, Z up, yaw counter-clockwise.  One frame is the
other turned half a turn about X, so a vector becomes (x, -y, -z) and roll, pitch and yaw
become (roll, -pitch, -yaw), applied in the same order (yaw, then pitch, then roll).

A ``cmd_vel`` (``geometry_msgs/Twist``: m/s forward, left and up, rad/s counter-clockwise)
becomes the robot's own DRIVE, with the numbers its GETGEO and GETCONF give:

* skid-steered and tracked: each side's wheel spin speed ``(v -+ w * separation / 2) / radius``
  (rad/s; the differential-drive kinematics, e.g. Siegwart, Nourbakhsh and Scaramuzza,
  *Introduction to Autonomous Mobile Robots*, 2nd ed., section 3.2);
* Ackermann: the driven wheels' spin speed ``v / radius`` and the front axle's angle
  ``atan(wheelbase * w / v)`` (the bicycle model, ibid. section 3.3), USARSim's angle positive to
  the right; a turn asked for standing still keeps the wheels straight;
* holonomic (two steered drive wheels on one axle, as Lisa's): each wheel turned along its own
  velocity and spun at its speed;
* aerial and legged: the forward, lateral (right), altitude (up) velocities and the clockwise
  turn rate.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

Vec3 = tuple[float, float, float]


def vector(v: Vec3) -> Vec3:
    """A USARSim position or direction in ROS axes."""
    return (float(v[0]), -float(v[1]), -float(v[2]))


def angles(rpy: Vec3) -> Vec3:
    """USARSim's (roll, pitch, yaw) in ROS's convention."""
    return (float(rpy[0]), -float(rpy[1]), -float(rpy[2]))


def quaternion(roll: float, pitch: float, yaw: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of the rotation yaw about Z, then pitch about Y, then roll about X."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
        cr * cp * cy + sr * sp * sy,
    )


def yaw_of(q: tuple[float, float, float, float]) -> float:
    """The yaw of a quaternion (x, y, z, w), radians counter-clockwise."""
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def ros_pose(location: Vec3, rotation: Vec3) -> tuple[Vec3, tuple[float, float, float, float]]:
    """A USARSim pose (location, roll/pitch/yaw) as a ROS position and quaternion."""
    return vector(location), quaternion(*angles(rotation))


def scan_angles(n: int, resolution: float) -> tuple[float, float]:
    """``angle_min`` and ``angle_max`` of a LaserScan of ``n`` beams ``resolution`` apart.
    USARSim sends the rightmost beam first and the scan is symmetric about straight ahead; ROS
    counts angles counter-clockwise from the first beam, so the ranges keep their order."""
    half = (n - 1) * resolution / 2.0 if n > 1 else 0.0
    return -half, half


@dataclass(frozen=True)
class Kinematics:
    """What turning a Twist into a DRIVE needs of a robot (its GETGEO and GETCONF)."""

    kind: str  # "skid", "ackermann", "velocities" (aerial, legged) or "none"
    wheel_radius: float = 0.0
    wheel_separation: float = 0.0
    wheel_base: float = 0.0
    max_speed: float = 0.0  # rad/s of the wheels (skid, Ackermann)
    max_steer: float = 0.0  # rad (Ackermann)
    reason: str = ""  # why "none"

    @classmethod
    def of(cls, geo: Any, conf: Any) -> Kinematics:
        vehicle = getattr(geo, "vehicle_type", "") or getattr(conf, "vehicle_type", "")
        steering = getattr(conf, "steering_type", "")
        r = float(getattr(geo, "wheel_radius", 0.0) or 0.0)
        if vehicle in ("AerialVehicle", "LeggedRobot"):
            return cls("velocities")
        if steering == "SkidSteered" and r > 0:
            return cls("skid", r, float(geo.wheel_separation or 0.0), max_speed=float(conf.max_speed))
        if steering == "HolonomSteered" and r > 0:
            return cls("holonomic", r, float(geo.wheel_separation or 0.0), max_speed=float(conf.max_speed))
        if steering == "AckermanSteered" and r > 0:
            return cls(
                "ackermann",
                r,
                float(geo.wheel_separation or 0.0),
                float(geo.wheel_base or 0.0),
                float(conf.max_speed),
                float(conf.max_front_steer),
            )
        return cls(
            "none",
            reason=f"a {vehicle or 'robot'} with steering {steering or 'none'} takes no cmd_vel "
            f"(drive it with its own DRIVE)",
        )


class BadTwist(ValueError):
    """A Twist that cannot be driven: NaN or infinite."""


def drive_of(k: Kinematics, vx: float, vy: float, vz: float, wz: float, clip: bool = True) -> dict[str, Any]:
    """The DRIVE keys (for :func:`usarsim.client.core.drive_line`) of a Twist, limited to the
    robot's maxima unless ``clip`` is False (the simulator limits them too)."""
    values = (vx, vy, vz, wz)
    if not all(math.isfinite(v) for v in values):
        raise BadTwist(f"cmd_vel with a value that is not a finite number ({', '.join(f'{v:g}' for v in values)})")
    if k.kind == "skid":
        half = k.wheel_separation / 2.0
        left = (vx - wz * half) / k.wheel_radius
        right = (vx + wz * half) / k.wheel_radius
        lim = k.max_speed if k.max_speed > 0 and clip else math.inf
        return {"left": _clip(left, lim), "right": _clip(right, lim)}
    if k.kind == "ackermann":
        speed = vx / k.wheel_radius
        steer = 0.0
        if abs(vx) > 1e-6 and k.wheel_base > 0:
            steer = -math.atan(k.wheel_base * wz / vx)  # USARSim: positive to the right
        lim = k.max_steer if k.max_steer > 0 and clip else math.pi / 2
        return {
            "speed": _clip(speed, k.max_speed if k.max_speed > 0 and clip else math.inf),
            "front_steer": _clip(steer, lim),
            "rear_steer": 0.0,
        }
    if k.kind == "holonomic":
        # two steered drive wheels on the axle, numbered 0 (left) and 1 (right) (protocol.md 5.3c):
        # each turned along its own velocity (vx - w y, vy) and spun at its speed, a turn past
        # 90 degrees taken as the opposite angle driven backwards
        lim = k.max_speed if k.max_speed > 0 and clip else math.inf
        wheels = []
        for number, y in ((0, k.wheel_separation / 2.0), (1, -k.wheel_separation / 2.0)):
            wx, wy = vx - wz * y, vy
            speed, angle = math.hypot(wx, wy) / k.wheel_radius, math.atan2(wy, wx)
            if angle > math.pi / 2:
                angle, speed = angle - math.pi, -speed
            elif angle < -math.pi / 2:
                angle, speed = angle + math.pi, -speed
            wheels.append((number, _clip(speed, lim), -angle))  # USARSim: positive to the right
        return {"wheels": wheels}
    if k.kind == "velocities":
        return {"linear_velocity": vx, "lateral_velocity": -vy, "altitude_velocity": vz, "rotational_velocity": -wz}
    raise ValueError(k.reason or "this robot takes no cmd_vel")


def _clip(v: float, limit: float) -> float:
    return max(-limit, min(limit, v))
