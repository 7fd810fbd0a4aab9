"""Skid steering (protocol.md 5.3a): wheeled and tracked robots that turn by driving their
sides at different speeds (P2AT, P2DX, ATRVJr, Zerg, Talon, TeleMax, Kenaf...)."""

from __future__ import annotations

import math

from usarsim.config.robot import RobotConfig, Wheel
from usarsim.controls import WheelSpeeds
from usarsim.errors import ConfigError
from usarsim.robots.base import DRIVES, DriveModel, clamp


@DRIVES.register("skid")
class Skid(DriveModel):
    """``DRIVE {Left} {Right}``: each side's wheels (tracks) spin at its speed, rad/s within
    the robot's MaxSpeed (percent of it when Normalized); a side not sent keeps its speed."""

    ACCEPTS = frozenset({WheelSpeeds})

    def __init__(self, robot: RobotConfig) -> None:
        super().__init__(robot)
        self.left = 0.0
        self.right = 0.0

    @classmethod
    def check(cls, robot: RobotConfig) -> None:
        if not (any(w.side == "left" for w in robot.wheels) and any(w.side == "right" for w in robot.wheels)):
            raise ConfigError("a skid-steered robot needs at least one left and one right wheel", path=robot.path,
                              key="wheels")

    def command(self, part: WheelSpeeds, normalized: bool) -> None:
        vmax = self.robot.max_speed_rad_s
        scale = vmax / 100.0 if normalized else 1.0
        if part.left is not None and math.isfinite(part.left):
            self.left = clamp(part.left * scale, vmax)
        if part.right is not None and math.isfinite(part.right):
            self.right = clamp(part.right * scale, vmax)
        if part.left is not None or part.right is not None:
            self.wheel_speed.clear()  # a skid DRIVE takes the wheels back from joint orders

    def wheel_target(self, w: Wheel) -> float:
        return self.left if w.side == "left" else self.right

    def on_battery_empty(self) -> None:
        self.left = self.right = 0.0
        super().on_battery_empty()
