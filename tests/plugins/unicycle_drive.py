"""A drive kind that is not built in, added from the test tree: a skid-steered robot
commanded as a unicycle, by its forward speed and turn rate (DRIVE {LinearVelocity v}
{RotationalVelocity w}), as a ROS ``cmd_vel`` would.  Importing this module registers it as
``unicycle``; a robot file says ``drive: unicycle``."""

from __future__ import annotations

import math

from usarsim.controls import Velocities
from usarsim.robots import DRIVES, DriveModel


@DRIVES.register("unicycle")
class Unicycle(DriveModel):
    """Each side's wheels spin at (v +- w b / 2) / r: v forward (m/s), w the turn rate
    (rad/s, clockwise seen from above, as USARSim's yaw), b the wheel separation and r
    the wheel radius of the robot's GEO."""

    ACCEPTS = frozenset({Velocities})

    def __init__(self, robot):
        super().__init__(robot)
        self.v = 0.0
        self.w = 0.0

    def command(self, part: Velocities, normalized: bool) -> None:
        if part.linear is not None and math.isfinite(part.linear):
            self.v = part.linear
        if part.rotational is not None and math.isfinite(part.rotational):
            self.w = part.rotational

    def wheel_target(self, w) -> float:
        g = self.robot.geometry
        side = 1.0 if w.side == "left" else -1.0  # turning right: the left side runs faster
        spin = (self.v + side * self.w * g.wheel_separation_m / 2.0) / g.wheel_radius_m
        top = self.robot.max_speed_rad_s
        return max(-top, min(top, spin))
