"""Holonomic steering (protocol.md 5.3c): robots whose numbered wheels each steer alone
(Lisa)."""

from __future__ import annotations

import math

from usarsim.config.robot import RobotConfig, Wheel
from usarsim.controls import SteeredWheels
from usarsim.errors import ConfigError
from usarsim.robots.base import DRIVES, DriveModel, clamp


@DRIVES.register("holonomic")
class Holonomic(DriveModel[SteeredWheels, None]):
    """``DRIVE {WheelNumber n} {WheelSpeed v} {WheelSteer a} ...``: each numbered steered
    wheel's spin speed (rad/s within MaxSpeed, percent of it when Normalized) and angle
    (rad, 0 straight ahead); either may be left out per wheel."""

    ACCEPTS = frozenset({SteeredWheels})

    def __init__(self, robot: RobotConfig) -> None:
        super().__init__(robot)
        self.wheel_steer: dict[str, float] = {}  # wheel name -> angle, rad
        self._by_number = {w.number: w for w in robot.wheels if w.number >= 0}

    @classmethod
    def check(cls, robot: RobotConfig) -> None:
        numbers = [w.number for w in robot.wheels if w.steer == "free"]
        if not numbers or -1 in numbers or len(set(numbers)) != len(numbers):
            raise ConfigError(
                "a holonomic robot's steered wheels (steer: free) need distinct numbers (number: 0, "
                "1, ...), the WheelNumber of its DRIVE",
                path=robot.path,
                key="wheels",
            )

    def command(self, part: SteeredWheels, normalized: bool) -> None:
        vmax = self.robot.max_speed_rad_s
        for sw in part.wheels:
            w = self._by_number.get(sw.number)
            if w is None:
                continue
            if sw.speed is not None and math.isfinite(sw.speed) and w.driven:
                self.wheel_speed[w.name] = clamp(sw.speed * (vmax / 100.0 if normalized else 1.0), vmax)
            if sw.steer is not None and math.isfinite(sw.steer) and w.steer == "free":
                self.wheel_steer[w.name] = math.remainder(sw.steer, 2 * math.pi)

    def steer_target(self, w: Wheel) -> float:
        return self.wheel_steer.get(w.name, 0.0) if w.steer == "free" else 0.0
