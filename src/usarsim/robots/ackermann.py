"""Ackermann steering (protocol.md 5.3b): cars that steer with their front (or rear) axle
(Hummer, Sedan, Cooper, SnowStorm)."""

from __future__ import annotations

import math

import mujoco

from usarsim.config.robot import RobotConfig, Wheel
from usarsim.controls import AckermannDrive
from usarsim.errors import ConfigError
from usarsim.robots.base import DRIVES, DriveModel, clamp
from usarsim.sim.view import RobotHandle


@DRIVES.register("ackermann")
class Ackermann(DriveModel[AckermannDrive, None]):
    """``DRIVE {Speed} {FrontSteer} {RearSteer}``: the driven wheels' spin speed (rad/s within
    MaxSpeed) and the axles' angles (rad within MaxFrontSteer/MaxRearSteer, positive right);
    what is not sent keeps its value; percentages of the maxima when Normalized."""

    ACCEPTS = frozenset({AckermannDrive})

    def __init__(self, robot: RobotConfig) -> None:
        super().__init__(robot)
        self.speed = 0.0  # driven wheels' spin speed, rad/s
        self.front_steer = 0.0  # commanded axle angles, rad (positive: right)
        self.rear_steer = 0.0

    @classmethod
    def check(cls, robot: RobotConfig) -> None:
        wheels = robot.wheels
        if not any(w.steer in ("front", "rear") for w in wheels) or not any(w.driven for w in wheels):
            raise ConfigError(
                "an Ackermann-steered robot needs steered (steer: front or rear) and driven wheels",
                path=robot.path,
                key="wheels",
            )
        if robot.max_front_steer_rad <= 0 and robot.max_rear_steer_rad <= 0:
            raise ConfigError(
                "an Ackermann-steered robot needs max_front_steer_rad > 0 (or max_rear_steer_rad)",
                path=robot.path,
                key="max_front_steer_rad",
            )

    def command(self, part: AckermannDrive, normalized: bool) -> None:
        c = self.robot
        vmax, fmax, rmax = c.max_speed_rad_s, c.max_front_steer_rad, c.max_rear_steer_rad
        if part.speed is not None and math.isfinite(part.speed):
            self.speed = clamp(part.speed * (vmax / 100.0 if normalized else 1.0), vmax)
        if part.front_steer is not None and math.isfinite(part.front_steer):
            self.front_steer = clamp(part.front_steer * (fmax / 100.0 if normalized else 1.0), fmax)
        if part.rear_steer is not None and math.isfinite(part.rear_steer):
            self.rear_steer = clamp(part.rear_steer * (rmax / 100.0 if normalized else 1.0), rmax)
        self.wheel_speed.clear()

    def wheel_target(self, w: Wheel) -> float:
        return self.speed

    def steer_target(self, w: Wheel) -> float:
        """Ackermann axles with the Ackermann correction (each wheel on a circle about the
        same centre) when only one axle steers, else both wheels of an axle alike."""
        if w.steer not in ("front", "rear"):
            return 0.0
        delta = self.front_steer if w.steer == "front" else self.rear_steer
        other = self.rear_steer if w.steer == "front" else self.front_steer
        if delta == 0.0 or other != 0.0:
            return delta
        fixed = [x.position[0] for x in self.robot.wheels if x.steer == "none"]
        base = w.position[0] - (sum(fixed) / len(fixed) if fixed else 0.0)
        if abs(base) < 1e-6:
            return delta
        t = math.tan(delta)
        y = w.position[1]
        if base > 0:  # a front axle: the turning centre is on the rear axle's line
            return math.atan2(base * t, base - y * t)
        return math.atan2(-base * t, -base + y * t)  # a rear axle: on the front axle's line

    def steer_angles(self, data: mujoco.MjData, handle: RobotHandle) -> tuple[float, float]:
        """The current angles of the axles (mean of their wheels)."""
        q = data.qpos
        fa = [float(q[handle.steer_qpos[w.name]]) for w in self.robot.wheels if w.steer == "front"]
        ra = [float(q[handle.steer_qpos[w.name]]) for w in self.robot.wheels if w.steer == "rear"]
        return (sum(fa) / len(fa) if fa else 0.0), (sum(ra) / len(ra) if ra else 0.0)
