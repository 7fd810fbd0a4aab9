"""A robot's status (STA, protocol.md 6.2) and its mission packages' state (MISSTA, 6.4)
at one instant, made from the world's state then.

They are made where the instant's sensor readings are (usarsim.sim.measuring): from the
measuring thread's copy of the physics, and from a :class:`Standing` the simulation
thread takes at the instant for what the copy does not hold (the batteries, the
headlights, the MultiView), which it takes in microseconds for hundreds of robots where
making their statuses took a millisecond.  Made on the simulation thread, from the live
state, the numbers are the same.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import mujoco
import numpy as np

from usarsim.readings import RobotStatus
from usarsim.sim import joints
from usarsim.sim.outputs import Output

if TYPE_CHECKING:
    from usarsim.sim.reports import Report
    from usarsim.sim.robot import SimRobot


@dataclass(frozen=True, slots=True)
class Standing:
    """What a status reads besides the physics, as it was at one instant: the seconds of
    battery each robot had used (a copy of the batteries' array, see
    :meth:`usarsim.sim.robot.SimRobot.battery_left`), the robots whose headlight was on,
    and the MultiView's tiles (robot id, camera) in order."""

    used: np.ndarray
    lit: frozenset[int]
    multiview: tuple[tuple[int, str], ...]

    def view_index(self, uid: int) -> int:
        """The robot's tile in the MultiView (STA ``View``), -1 when it is not shown."""
        for i, (u, _) in enumerate(self.multiview):
            if u == uid:
                return i
        return -1


def robot_status(r: SimRobot, d: mujoco.MjData, standing: Standing) -> RobotStatus:
    """STA of ``r`` from the physics state ``d`` and ``standing`` of the same instant."""
    left = r.battery_left(standing.used)
    front, rear = r.drive.steer_angles(d, r.handle)
    joint_angles = tuple((n, joints.position(d, r, n)) for n in r.config.status_joints)
    light = r.uid in standing.lit
    return RobotStatus(
        vehicle_type=r.config.vehicle_type,
        battery_s=int(math.ceil(left - 1e-6)),
        front_steer=front,
        rear_steer=rear,
        joints=joint_angles,
        light_toggle=light,
        light_intensity=100 if light else 0,
        view=standing.view_index(r.uid),
    )


def status_output(rep: Report, d: mujoco.MjData, standing: Standing, now: float) -> Output:
    """A status (STA) or mission package (MISSTA) report's output at simulated ``now``."""
    r = rep.robot
    if rep.status:
        return Output(r.uid, now, robot_status(r, d, standing), "STA")
    return Output(r.uid, now, joints.package_state(d, r, rep.package), rep.key)
